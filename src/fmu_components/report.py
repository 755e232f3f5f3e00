"""The validation report: PNG plots in the style of the thesis figures (FMU and reference
overlaid, the elastic force as a grey line as in section 7.2) and a summary page.

One figure per test of each component (spec section 5), plus one plot per case of its
output against time with the FMU's error.
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from scipy.interpolate import PchipInterpolator  # noqa: E402

from . import cases as programme  # noqa: E402
from . import reference  # noqa: E402
from .runtime.catalog import COMPONENTS  # noqa: E402
from .runtime.units import DEG  # noqa: E402  (display degrees per radian)
from .validate import STRICT_LIMIT, rows  # noqa: E402

# Display units engineers read: (factor from SI, unit) of the deflection, load and rate.
DISPLAY = {
    "RoadWheelTyre": ((1e3, "mm"), (1e-3, "kN"), (1e3, "mm/s")),
    "TrackBushRadial": ((1e3, "mm"), (1e-3, "kN"), (1e3, "mm/s")),
    "TrackBushTorsion": ((DEG, "deg"), (1.0, "N.m"), (DEG, "deg/s")),
    # The damper as the thesis reports it: Table 11.2-1 in rad, Table A6-1 in rad/s.
    "RotaryDamper": ((1.0, "rad"), (1.0, "N.m"), (1.0, "rad/s")),
}
REFERENCE_STYLE = dict(color="black", linewidth=1.0)
FMU_STYLE = dict(linestyle="--", linewidth=1.4)
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


def _shown(outcome):
    return outcome.reference["time"] >= outcome.case.shown_from - outcome.case.step / 2


def _overlay(ax, outcome, x_of, y_of, color, label):
    """Reference (black) and FMU (dashed, colour) of one case over its shown window."""
    k = _shown(outcome)
    ax.plot(x_of(outcome.inputs)[k], y_of(outcome.reference)[k], **REFERENCE_STYLE)
    if outcome.errors:  # the FMU ran the whole case
        ax.plot(x_of(outcome.inputs)[k], y_of(outcome.result)[k], color=color, label=label,
                **FMU_STYLE)


def _legend_note(ax, elastic=False):
    ax.plot([], [], label="reference (independent solve)", **REFERENCE_STYLE)
    if elastic:
        ax.plot([], [], label="elastic force Fe (section 5.3.1)", **ELASTIC_STYLE)
    ax.legend(fontsize=8, loc="best")
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
                        label=f"FMU, {outcome.case.label}", **FMU_STYLE)
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
    table, time_history = fig.subplots(1, 2)
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
    table.legend(fontsize=8)
    table.grid(True, alpha=0.3)
    t = outcome.reference["time"]
    time_history.plot(t, outcome.reference["torque"], **REFERENCE_STYLE)
    if outcome.errors:
        time_history.plot(t, outcome.result["torque"], color="tab:blue", label="FMU", **FMU_STYLE)
    time_history.set_xlabel("time (s)")
    time_history.set_ylabel("torque (N.m)")
    _legend_note(time_history)


def plot_test(outcomes, path):
    """The figure of one test of one component."""
    case = outcomes[0].case
    wide_plot = WIDE_PLOTS.get(case.test)
    fig = plt.figure(figsize=(13, 5.5) if wide_plot else (8, 6))
    if wide_plot:
        wide_plot(fig, outcomes)
    else:
        plot_loops(fig.subplots(), outcomes)
    _save(fig, f"{case.fmu}: {programme.TESTS[case.test].title}\nthesis {case.figure}; FMU "
               f"dashed over the reference", path, dpi=100)


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
        panels[0].plot(t, axes.f(outcome.result), color="tab:blue", label="FMU", **FMU_STYLE)
        for name in names:
            error = 100 * (outcome.result[name] - outcome.reference[name]) / \
                programme.column_scale(outcome.reference[name])
            panels[1].plot(t, error, linewidth=0.8, label=name)
    panels[0].set_ylabel(axes.f_label)
    panels[1].set_ylabel(f"FMU - reference\n(% of peak-to-peak;\nlimit {STRICT_LIMIT:g} %)")
    panels[1].set_xlabel("time (s)")
    for panel in panels:
        panel.legend(fontsize=8)
        panel.grid(True, alpha=0.3)
    _save(fig, f"{outcome.case.key}: strict error {outcome.strict_error:.4f} % "
               f"({'pass' if outcome.passed else 'FAIL'})", path, dpi=80)


def _save(fig, title, path, dpi):
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)


def write_report(outcomes, folder):
    """Plots and summary.md in folder; returns the summary's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    groups = {}
    for outcome in (o for o in outcomes if o.reference is not None):  # those that ran
        groups.setdefault((outcome.case.fmu, outcome.case.test), []).append(outcome)
    lines = ["# Validation against the thesis test programme", "",
             f"{sum(o.passed for o in outcomes)} of {len(outcomes)} cases pass. Each case is "
             f"simulated with `fmpy.simulate_fmu` and compared with the independent reference "
             f"(`reference_data/<FMU>/<case>_ref.csv`): the strict error is the largest "
             f"|FMU - reference| of any output in % of that output's peak-to-peak range "
             f"(limit {STRICT_LIMIT:g} %); the cross-check column is the share of samples "
             f"inside the band of `fmpy.util.validate_result` for the worst output (the FMI "
             f"cross-check rule fails a case with more than 10 % outside).", "",
             "## Figures", ""]
    for (fmu, test), members in groups.items():
        name = f"test_{fmu}_{test.replace(' ', '_')}.png"
        plot_test(members, folder / name)
        lines += [f"### {fmu}: {programme.TESTS[test].title}", "",
                  f"Thesis {members[0].case.figure}.", "", f"![{fmu} {test}]({name})", ""]
    header, *table = rows(outcomes)
    lines += ["## Cases", "",
              "| " + " | ".join(header) + " | plot |",
              "|---" * (len(header) + 1) + "|"]
    for outcome, row in zip(outcomes, table):
        name = f"case_{outcome.case.fmu}_{outcome.case.name}.png"
        if outcome.reference is not None:
            plot_case(outcome, folder / name)
        lines.append("| " + " | ".join(row) + (f" | [plot]({name}) |" if outcome.reference
                                               is not None else " |  |"))
    summary = folder / "summary.md"
    summary.write_text("\n".join(lines) + "\n")
    return summary
