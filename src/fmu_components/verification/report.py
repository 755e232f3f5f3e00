"""The verification report (the FMUs against the independent solve): PNG plots in the
style of the thesis figures (FMU and reference overlaid, the elastic force as a grey line as
in section 7.2) and a summary page.

One figure per test of each component (spec section 5), plus one plot per case of its
output against time with the FMU's error.
"""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.interpolate import PchipInterpolator  # noqa: E402

from . import cases as programme  # noqa: E402
from . import reference  # noqa: E402
from ..runtime.catalog import COMPONENTS  # noqa: E402
from ..lab.display import DISPLAY  # noqa: E402
from ..lab.files import save_figure, write_text, written_whole  # noqa: E402
from .outcome import STRICT_LIMIT, rows  # noqa: E402

DPI = 200  # print quality
REFERENCE_STYLE = dict(color="black", linewidth=1.0)
# Dashed with open markers, so that the FMU shows where it lies exactly on the reference.
FMU_STYLE = dict(linestyle="--", linewidth=1.2, marker="o", markersize=3.5, markerfacecolor="none")
FMU_MARKERS = 40  # markers per curve
ELASTIC_STYLE = dict(color="0.6", linewidth=2.0)


class Axes:
    """Names and display scaling of one FMU's signals."""

    def __init__(self, fmu):
        self.deflection, self.rate = (v.name for v in COMPONENTS[fmu].inputs)
        self.load = COMPONENTS[fmu].outputs[0].name
        (self.x_factor, self.x_unit), (self.f_factor, self.f_unit), (self.v_factor, self.v_unit) = \
            DISPLAY[fmu]

    def x(self, inputs):
        return inputs[self.deflection] * self.x_factor

    def v(self, inputs):
        return inputs[self.rate] * self.v_factor

    def f(self, table, name=None):
        return table[name or self.load] * self.f_factor

    @property
    def x_label(self):
        return f"{self.deflection.replace('_', ' ')} ({self.x_unit})"

    @property
    def f_label(self):
        return f"{self.load} ({self.f_unit})"


# Tests whose input is not one sine: their titles name the shape instead.
NOT_ONE_SINE = {"IV", "dual sine", "sweep"}


def _fmu_style(n):
    return dict(FMU_STYLE, markevery=max(1, n // FMU_MARKERS))


def conditions(outcome):
    """Preload (mean), amplitude and frequency of a periodic case's shown window, in display
    units, e.g. {"preload": "3.5 mm", "amplitude": "+-1 mm", "frequency": "1 Hz"}; {} for a
    ramp or a sweep."""
    if outcome.case.test in NOT_ONE_SINE:
        return {}
    axes = Axes(outcome.case.fmu)
    # The shown window is whole cycles with both ends sampled: one end dropped, mean, rms and
    # the spectrum's bins are exact for a sine.
    x = axes.x(outcome.inputs)[_shown(outcome)][:-1]
    spectrum = np.abs(np.fft.rfft(x - x.mean()))
    frequency = np.argmax(spectrum[1:]) + 1 if len(spectrum) > 1 else 0
    mean_name = "preload" if outcome.case.fmu != "RotaryDamper" else "mean"
    amplitude = math.sqrt(2) * float(np.std(x))
    # a mean within 1 % of the amplitude is a zero mean (the grid's sampling of a sine)
    mean = x.mean() if abs(x.mean()) > 1e-2 * amplitude else 0.0
    return {mean_name: f"{_round(mean)} {axes.x_unit}",
            "amplitude": f"+-{_round(amplitude)} {axes.x_unit}",
            "frequency": f"{_round(frequency / (len(x) * outcome.case.step))} Hz"}


def _round(value):
    return f"{float(f'{value:.3g}'):g}"


def describe(outcomes):
    """The conditions every outcome shares, for a title: "preload 3.5 mm, 1 Hz"."""
    shared = None
    for outcome in outcomes:
        these = conditions(outcome)
        shared = these if shared is None else {k: v for k, v in shared.items()
                                               if these.get(k) == v}
    return ", ".join(v if k == "frequency" else f"{k} {v}" for k, v in (shared or {}).items())


def _shown(outcome):
    return outcome.reference["time"] >= outcome.case.shown_from - outcome.case.step / 2


def _overlay(ax, outcome, x_of, y_of, color, label):
    """Reference (black) and FMU (dashed, colour) of one case over its shown window."""
    k = _shown(outcome)
    ax.plot(x_of(outcome.inputs)[k], y_of(outcome.reference)[k], **REFERENCE_STYLE)
    if outcome.errors:  # the FMU ran the whole case
        ax.plot(x_of(outcome.inputs)[k], y_of(outcome.result)[k], color=color, label=label,
                **_fmu_style(int(np.count_nonzero(k))))


def _legend_note(ax, elastic=False):
    ax.plot([], [], label="reference (independent solve)", **REFERENCE_STYLE)
    if elastic:
        ax.plot([], [], label="elastic force Fe (section 5.3.1)", **ELASTIC_STYLE)
    _legend_outside(ax)


def _legend_outside(ax):
    """Legend to the right of the axes, never over the data."""
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.grid(True, alpha=0.3)


def _colors(n):
    return plt.get_cmap("viridis")(np.linspace(0.0, 0.85, max(n, 1)))


def plot_loops(ax, outcomes):
    """Load against deflection (Figs. 5.4-x, 7.2-x): one loop per case, elastic line grey."""
    axes = Axes(outcomes[0].case.fmu)
    elastic = f"{axes.load}_elastic"
    xs = np.concatenate([axes.x(o.inputs)[_shown(o)] for o in outcomes])
    fe = np.concatenate([axes.f(o.reference, elastic)[_shown(o)] for o in outcomes])
    order = np.argsort(xs)
    ax.plot(xs[order], fe[order], **ELASTIC_STYLE, zorder=0)
    for outcome, color in zip(outcomes, _colors(len(outcomes))):
        _overlay(ax, outcome, axes.x, axes.f, color, f"FMU, {outcome.case.label}")
    ax.set_xlabel(axes.x_label)
    ax.set_ylabel(axes.f_label)
    _legend_note(ax, elastic=True)


def plot_relaxation(fig, outcomes):
    """Load against time after a step (Figs. 5.6-x, 7.2-6, 7.2-7): the whole record, and
    the hold against log time, where fast-then-slow relaxation shows."""
    axes = Axes(outcomes[0].case.fmu)
    linear, logarithmic = fig.subplots(1, 2)
    for ax, log in ((linear, False), (logarithmic, True)):
        for outcome, color in zip(outcomes, _colors(len(outcomes))):
            t = outcome.reference["time"]
            hold = outcome.case.shown_from
            k = t > hold + outcome.case.step / 2 if log else slice(None)
            t = t - hold if log else t
            ax.plot(t[k], axes.f(outcome.reference, f"{axes.load}_elastic")[k], **ELASTIC_STYLE)
            ax.plot(t[k], axes.f(outcome.reference)[k], **REFERENCE_STYLE)
            if outcome.errors:
                ax.plot(t[k], axes.f(outcome.result)[k], color=color,
                        label=f"FMU, {outcome.case.label}",
                        **_fmu_style(int(np.count_nonzero(np.ones_like(t)[k]))))
        ax.set_xlabel("time since the hold began (s), log scale" if log else "time (s)")
        ax.set_ylabel(axes.f_label)
        if log:
            ax.set_xscale("log")
        _legend_note(ax, elastic=True)


def plot_damper(fig, outcomes):
    """Work diagram and characteristic (Figs. 13.1-1, 13.1-2, 13.2-1, 13.2-2)."""
    axes = Axes("RotaryDamper")
    work, characteristic = fig.subplots(1, 2)
    for ax, x_of, label in ((work, axes.x, axes.x_label),
                            (characteristic, axes.v, f"angular velocity ({axes.v_unit})")):
        for outcome, color in zip(outcomes, _colors(len(outcomes))):
            _overlay(ax, outcome, x_of, axes.f, color, f"FMU, {outcome.case.label}")
        ax.set_xlabel(label)
        ax.set_ylabel(axes.f_label)
        _legend_note(ax)
    work.set_title("work diagram", fontsize=10)
    characteristic.set_title("characteristic", fontsize=10)


def plot_sweep(fig, outcomes):
    """Steady torque of the constant-velocity sweep against Table A6-1 (Fig. A6-1)."""
    (outcome,) = outcomes
    case = outcome.case
    grid = fig.add_gridspec(2, 2)
    table = fig.add_subplot(grid[:, 0])
    # The plateaus shorten as the rate rises (the travel is fixed): the fast end gets a panel
    # of its own so that each plateau can be read.
    early = fig.add_subplot(grid[0, 1])
    late = fig.add_subplot(grid[1, 1])
    spec = reference.damper_spec()
    rates, smoothed = spec.rates, spec.torques
    measured = np.array([float(r["measured_N_m"]) for r in reference.thesis_rows("table_A6-1.csv")])
    fine = np.linspace(rates[0], rates[-1], 1401)
    table.plot(fine, PchipInterpolator(rates, smoothed)(fine), color="0.6", linewidth=2.0,
               label="Table A6-1 smoothed, monotone spline (the model)")
    table.plot(rates, smoothed, "s", color="0.4", markersize=4, label="Table A6-1 smoothed")
    table.plot(rates, measured, "x", color="tab:red", label="Table A6-1 measured")
    sweep_rates, steady = programme.steady_torques(case, outcome.reference["time"],
                                                   outcome.reference["torque"])
    table.plot(sweep_rates, steady, "o", markerfacecolor="none", color="black",
               label="reference, steady torque")
    if outcome.errors:
        _, fmu_steady = programme.steady_torques(case, outcome.result["time"],
                                                 outcome.result["torque"])
        table.plot(sweep_rates, fmu_steady, "+", color="tab:blue", markersize=9,
                   label="FMU, steady torque")
    table.set_xlabel("angular velocity (rad/s)")
    table.set_ylabel("torque (N.m)")
    table.legend(fontsize=7, loc="upper left")  # the curve runs from lower left to upper right
    table.grid(True, alpha=0.3)
    t = outcome.reference["time"]
    for panel, k in ((early, t <= SWEEP_SPLIT), (late, t >= SWEEP_SPLIT)):
        panel.plot(t[k], outcome.reference["torque"][k], **REFERENCE_STYLE)
        if outcome.errors:
            panel.plot(t[k], outcome.result["torque"][k], color="tab:blue", label="FMU",
                       **_fmu_style(int(np.count_nonzero(k))))
        panel.set_xlim(t[k][0], t[k][-1])
        panel.set_ylabel("torque (N.m)")
        _legend_note(panel)
    early.set_title(f"up to {SWEEP_SPLIT:g} s: |omega| up to 1.6 rad/s", fontsize=9)
    late.set_title(f"after {SWEEP_SPLIT:g} s: |omega| 1.6 to 14 rad/s", fontsize=9)
    late.set_xlabel("time (s)")


SWEEP_SPLIT = 20.0  # s


def plot_test(outcomes, path):
    """The figure of one test of one component."""
    case = outcomes[0].case
    wide_plot = WIDE_PLOTS.get(case.test)
    fig = plt.figure(figsize=(15, 6.5) if wide_plot else (10, 6.5))
    if wide_plot:
        wide_plot(fig, outcomes)
    else:
        plot_loops(fig.subplots(), outcomes)
    shared = describe(outcomes)
    _save(fig, f"{outcomes[0].name}: {programme.TESTS[case.test].title}{', ' + shared if shared else ''}"
               f"\nthesis {case.figure}; FMU dashed with markers over the reference (black)", path)


# Tests drawn on a wide figure of two panels; every other test is a set of loops.
WIDE_PLOTS = {"IV": plot_relaxation, "A-D": plot_damper, "high frequency": plot_damper,
              "sweep": plot_sweep}


def plot_case(outcome, path):
    """The case's outputs against time, FMU over reference, and the FMU's error."""
    names = outcome.reference.dtype.names[1:]
    fig, panels = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    t = outcome.reference["time"]
    axes = Axes(outcome.case.fmu)
    panels[0].plot(t, axes.f(outcome.reference), **REFERENCE_STYLE, label="reference")
    if outcome.errors:
        panels[0].plot(t, axes.f(outcome.result), color="tab:blue", label="FMU",
                       **_fmu_style(len(t)))
        for name in names:
            error = 100 * (outcome.result[name] - outcome.reference[name]) / \
                programme.column_scale(outcome.reference[name])
            panels[1].plot(t, error, linewidth=0.8, label=name)
    panels[0].set_ylabel(axes.f_label)
    panels[1].set_ylabel(f"FMU - reference\n(% of peak-to-peak;\nlimit {STRICT_LIMIT:g} %)")
    panels[1].set_xlabel("time (s)")
    for panel in panels:
        _legend_outside(panel)
    shared = describe([outcome])
    _save(fig, f"{outcome.case.key}{': ' + shared if shared else ''}\nstrict error "
               f"{outcome.strict_error:.4f} % ({'pass' if outcome.passed else 'FAIL'})", path)


# The fastest zlib level: the same pixels, a PNG about a fifth larger, its encoding about
# a tenth of a plot's time less (measured on the report's plots).
PNG_OPTIONS = {"compress_level": 1}


def _save(fig, title, path):
    """One layout pass (tight_layout keeps the legends outside the axes on the figure):
    bbox_inches="tight" would draw the whole figure a second time to crop it."""
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=DPI, pil_kwargs=PNG_OPTIONS)
    plt.close(fig)


def plot_count(outcomes, pngs=()):
    """How many PNGs write_report draws for these outcomes (for a progress bar), those
    of `pngs` (drawn already) aside."""
    ran = [o for o in outcomes if o.reference is not None]
    return len([o for o in ran if case_plot_name(o) not in pngs]) + \
        len({(o.name, o.case.test) for o in ran})


def case_plot_name(outcome):
    return f"case_{outcome.name}_{outcome.case.name}.png"


def case_png(outcome):
    """The PNG bytes of the case's own plot (``plot_case``), drawn where the case ran (a
    campaign's worker); None for a case that did not run."""
    return plot_png(plot_case, (outcome,)) if outcome.reference is not None else None


def plot_png(draw, arguments):
    """The PNG bytes of ``draw(*arguments, path)``, drawn wherever this runs (a campaign's
    worker, which has none of the report's folder)."""
    import tempfile

    with tempfile.TemporaryDirectory() as scratch:
        path = Path(scratch) / "plot.png"
        draw(*arguments, path)
        return path.read_bytes()


def write_report(outcomes, folder, progress=None, drawn=None, pngs=None):
    """Plots and summary.md in folder; returns the summary's path. progress (a tqdm bar, or
    None) advances by one per plot drawn. pngs: {file name: PNG bytes} of plots drawn
    already (each case's, ``case_png``, in the case's own task), written as they are.
    drawn(jobs), if given, draws the others elsewhere: it yields (index, PNG bytes) of
    each ``plot_png`` job (draw, arguments) as it is done (a campaign's engine); else they
    are drawn here, one after another."""
    pngs = pngs or {}
    advance = progress.update if progress is not None else (lambda n: None)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    groups = {}
    for outcome in (o for o in outcomes if o.reference is not None):  # those that ran
        groups.setdefault((outcome.name, outcome.case.test), []).append(outcome)
    lines = ["# Verification: the FMUs against an independent solve of the test programme", "",
             f"{sum(o.passed for o in outcomes)} of {len(outcomes)} cases pass. Each case is "
             f"simulated with `fmpy.simulate_fmu` and compared with the independent reference "
             f"(`reference_data/<FMU>/<case>_ref.csv`): the strict error is the largest "
             f"|FMU - reference| of any output in % of that output's peak-to-peak range "
             f"(limit {STRICT_LIMIT:g} %); the cross-check column is the share of samples "
             f"inside the band of `fmpy.util.validate_result` for the worst output (the FMI "
             f"cross-check rule fails a case with more than 10 % outside).", "",
             "## Figures", ""]
    plots = []  # (file name, draw, arguments)
    for (fmu, test), members in groups.items():
        name = f"test_{fmu}_{test.replace(' ', '_')}.png"
        plots.append((name, plot_test, (members,)))
        lines += [f"### {fmu}: {programme.TESTS[test].title}", "",
                  f"Thesis {members[0].case.figure}.", "", f"![{fmu} {test}]({name})", ""]
    header, *table = rows(outcomes)
    lines += ["## Cases", "",
              "| " + " | ".join(header) + " | plot |",
              "|---" * (len(header) + 1) + "|"]
    for outcome, row in zip(outcomes, table):
        name = case_plot_name(outcome)
        if name in pngs:
            with written_whole(folder / name) as whole:
                whole.write_bytes(pngs[name])
        elif outcome.reference is not None:
            plots.append((name, plot_case, (outcome,)))
        lines.append("| " + " | ".join(row) + (f" | [plot]({name}) |" if outcome.reference
                                               is not None else " |  |"))
    if drawn is None:
        for name, draw, arguments in plots:
            draw(*arguments, folder / name)
            advance(1)
    else:
        for index, png in drawn([(draw, arguments) for _, draw, arguments in plots]):
            with written_whole(folder / plots[index][0]) as whole:
                whole.write_bytes(png)
            advance(1)
    summary = folder / "summary.md"
    write_text(summary, "\n".join(lines) + "\n")
    return summary
