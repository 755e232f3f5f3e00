"""The virtual rig's plots, and the thesis's three model structures of the torsion bush
compared on its dual sine and step-and-hold tests (sections 6.1-6.4).

Both draw with matplotlib, imported when a plot is made.
"""

import math
from multiprocessing import get_context

import numpy as np

from ..runtime.catalog import COMPONENTS, STRUCTURES, structures_of
from ..runtime.units import RAD_PER_DEG
from .harmonics import secondary_loop_areas
from .rig import HOLD_TIME, RISE_TIME, _cores, drive, make_setup, relaxation_record, units
from .signals import DUAL_SINE, DUAL_SINE_SHOWN, DUAL_SINE_STEP, DUAL_SINE_STOP, dual_sine


def plot_rows(rows, out, component, relaxation=None, dpi=200):
    """|K*| and loss angle against frequency (a curve per amplitude) and against amplitude
    (a curve per frequency), per preload; for the damper its equivalent stiffness and
    damping likewise; the relaxation record on a log time axis. Returns the files."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    length, load, stiffness = units(component)
    quantities = [("dynamic_stiffness", f"|K*| ({stiffness})"),
                  ("loss_angle_deg", "loss angle (deg)")]
    if component == "RotaryDamper":
        quantities += [("equivalent_stiffness", f"equivalent stiffness K' ({stiffness})"),
                       ("equivalent_damping", f"equivalent damping c_eq ({load}.s/{length})")]
    preloads = sorted({r.preload for r in rows})
    files = []
    for against, by, label, log in (("frequency", "amplitude", "frequency (Hz)", True),
                                    ("amplitude", "frequency", f"amplitude ({length})", False)):
        figure, axes = plt.subplots(len(quantities), 1, figsize=(6.5, 2.6 * len(quantities)),
                                    sharex=True, squeeze=False)
        for preload in preloads:
            for level in sorted({getattr(r, by) for r in rows}):
                curve = sorted((r for r in rows if r.preload == preload and getattr(r, by) == level),
                               key=lambda r: getattr(r, against))
                if not curve:
                    continue
                unit = "Hz" if by == "frequency" else length
                name = f"{by} {level:g} {unit}" + (
                    f", preload {preload:g} {length}" if len(preloads) > 1 else "")
                style = "o-" if len(curve) > 1 else "o"
                for axis, (quantity, _) in zip(axes[:, 0], quantities):
                    axis.plot([getattr(r, against) for r in curve],
                              [getattr(r, quantity) for r in curve], style, ms=3, label=name)
        for axis, (_, title) in zip(axes[:, 0], quantities):
            axis.set_ylabel(title)
            axis.grid(True, which="both", alpha=0.3)
            if log:
                axis.set_xscale("log")
        axes[-1, 0].set_xlabel(label)
        axes[0, 0].legend(fontsize=7, ncol=2)
        axes[0, 0].set_title(f"{component}: first harmonic at periodic steady state")
        figure.tight_layout()
        path = out / f"rig_{against}.png"
        figure.savefig(path, dpi=dpi)
        plt.close(figure)
        files.append(path)
    if relaxation is not None:
        files.append(plot_relaxation(relaxation, out / "rig_relaxation.png", component, dpi))
    return files


def plot_relaxation(records, path, component, dpi=200, title=None):
    """records: {label: (times, deflection, force, rise)}; the force over the hold against
    the time since the ramp ended, log axis (as the thesis plots relaxation, Fig. 5.6-1)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    _, load, _ = units(component)
    figure, axis = plt.subplots(figsize=(6.5, 3.6))
    for label, (times, _, force, rise) in records.items():
        shown = times > rise
        axis.semilogx(times[shown] - rise, force[shown], label=label)
    axis.set_xlabel("time since the ramp ended (s)")
    axis.set_ylabel(f"{COMPONENTS[component].outputs[0].name} ({load})")
    axis.grid(True, which="both", alpha=0.3)
    axis.legend(fontsize=8)
    axis.set_title(title or f"{component}: step and hold")
    figure.tight_layout()
    figure.savefig(path, dpi=dpi)
    plt.close(figure)
    return path


# --- structure comparison (thesis Figs. 6.1-1/6.3-2, 6.3-4, 6.3-5, 6.4-2, 6.4-3) ------------

RELAXATION_FROM, RELAXATION_TO = 10.0 * RAD_PER_DEG, 25.0 * RAD_PER_DEG  # section 5.6, Fig. 5.6-1
RELAXATION_TIMES = (0.1, 1.0, 10.0, 100.0)  # s after the ramp, the table's columns


def dual_sine_record(setup):
    """The torsion dual sine of section 5.8 (10 deg + 7.5 deg at 0.1 Hz + 0.75 deg at
    1.5 Hz), exact rates at each sample, from rest at its start."""
    mean, components = DUAL_SINE
    times = np.arange(int(round(DUAL_SINE_STOP / DUAL_SINE_STEP)) + 1) * DUAL_SINE_STEP
    deflection = dual_sine(times, mean, components)
    rates = sum(a * 2 * math.pi * f * np.cos(2 * math.pi * f * times) for a, f in components)
    return times, deflection, drive(setup, times, deflection, rates)


def structure_records(structure):
    """(structure, the dual sine's (t, x, f), the step and hold's (t, x, f)) of one of the
    torsion bush's structures: one task of the comparison."""
    setup = make_setup("TrackBushTorsion", structure)
    dual = dual_sine_record(setup)
    relax = relaxation_record(setup, RELAXATION_FROM, RELAXATION_TO - RELAXATION_FROM,
                              RISE_TIME, HOLD_TIME)
    return structure, dual, relax


def compare_structures(out, processes=None, dpi=200, runner=None):
    """The three structures of the torsion bush on the dual sine and the step-and-hold test:
    a figure (DIR/structures.png) and a Markdown table (DIR/structures.md). Returns the
    table's rows as dicts. runner(structures), if given, runs ``structure_records`` of
    each elsewhere (a campaign's engine) and returns them in order; else they run on
    `processes` local processes."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out.mkdir(parents=True, exist_ok=True)
    structures = [s for s in STRUCTURES if s in structures_of("TrackBushTorsion")]
    processes = min(processes or _cores(), len(structures))
    if runner is not None:
        results = runner(structures)
    elif processes > 1:
        with get_context("fork").Pool(processes) as pool:
            results = pool.map(structure_records, structures, chunksize=1)
    else:
        results = [structure_records(s) for s in structures]
    figure, (loops, relaxation) = plt.subplots(1, 2, figsize=(11, 4.2))
    table = []
    figures = {"final": "Fig. 6.4-2, 6.4-3", "four-element": "Figs. 6.3-4, 6.3-5",
               "haupt-sedlan": "Fig. 6.3-2"}
    for structure, (t, x, f), (tr, xr, fr) in results:
        shown = t >= DUAL_SINE_SHOWN
        loops.plot(np.degrees(x[shown]), f[shown], lw=0.8, label=structure)
        held = tr > RISE_TIME
        relaxation.semilogx(tr[held] - RISE_TIME, fr[held], label=structure)
        areas = secondary_loop_areas(t, f)
        peak = fr[np.argmin(np.abs(tr - RISE_TIME))]
        final = fr[-1]
        row = {"structure": structure, "thesis": figures[structure],
               "dual_sine_range": float(np.ptp(f[shown])),
               "small_loop_area_mean": float(np.mean(areas)),
               "small_loop_area_min": float(np.min(areas)),
               "relaxation_peak": float(peak)}
        for after in RELAXATION_TIMES:
            value = float(np.interp(RISE_TIME + after, tr, fr))
            row[f"relaxed_{after:g}s"] = (peak - value) / (peak - final) if peak != final else 0.0
            row[f"torque_{after:g}s"] = value
        table.append(row)
    loops.set_xlabel("angle (deg)")
    loops.set_ylabel("torque (N.m)")
    loops.set_title("dual sine, 10 + 7.5 sin(0.1 Hz) + 0.75 sin(1.5 Hz) deg")
    relaxation.set_xlabel("time since the ramp ended (s)")
    relaxation.set_ylabel("torque (N.m)")
    relaxation.set_title("step 10 to 25 deg in 0.1 s, hold")
    for axis in (loops, relaxation):
        axis.grid(True, which="both", alpha=0.3)
        axis.legend(fontsize=8)
    figure.suptitle("TrackBushTorsion: the thesis's three model structures")
    figure.tight_layout()
    figure.savefig(out / "structures.png", dpi=dpi)
    plt.close(figure)
    (out / "structures.md").write_text(structures_table(table))
    return table


def structures_table(table):
    head = ("| structure | thesis | dual sine range (N.m) | 1.5 Hz loops: energy per cycle, mean / "
            "min (J) "
            "| torque at the end of the ramp (N.m) | "
            + " | ".join(f"{t:g} s" for t in RELAXATION_TIMES) + " |")
    lines = [head, "|" + "---|" * (5 + len(RELAXATION_TIMES))]
    for row in table:
        relaxed = " | ".join(f"{row[f'torque_{t:g}s']:.1f} ({100 * row[f'relaxed_{t:g}s']:.0f} %)"
                             for t in RELAXATION_TIMES)
        lines.append(f"| {row['structure']} | {row['thesis']} | {row['dual_sine_range']:.1f} | "
                     f"{row['small_loop_area_mean']:.3g} / {row['small_loop_area_min']:.3g} | "
                     f"{row['relaxation_peak']:.1f} | {relaxed} |")
    return ("Torque after the step (in brackets: the share of the relaxation over the whole "
            "hold that has happened by then)\n\n" + "\n".join(lines) + "\n")
