"""The validation report: the model against the thesis's measurements (``measurements``).

summary.md holds the table of every measured quantity (measured, model, difference, basis,
source, what the thesis says of its own model there) and the plots:

* per component, the difference of each compared row in % with the +-BAND band;
* per rubber component, the small loops of Measurement I with the thesis's elastic fit
  (the measured loop centres' line, grey) and the model's loop centres;
* the damper's characteristic in tests A-D with the numbers the thesis read off its own
  (laminar and general slopes, the transition and the peak), and its steady torque against
  Table A6-1.
"""

import fnmatch
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ..lab.display import DISPLAY  # noqa: E402
from ..lab.files import save_figure, write_text  # noqa: E402
from ..runtime.catalog import COMPONENTS  # noqa: E402
from .measurements import BAND, loop_centre, tally, with_unit  # noqa: E402

DPI = 200
BASIS_COLOURS = {"rig": "tab:blue", "fit": "tab:green", "supplier": "tab:purple",
                 "extrapolated": "tab:orange", "assumed": "tab:red", "design": "0.5"}
ELASTIC_STYLE = dict(color="0.6", linewidth=2.0)


def _save(fig, title, path):
    fig.axes[0].set_title(title, fontsize=10)
    fig.tight_layout()
    save_figure(fig, path, dpi=DPI, bbox_inches="tight")
    plt.close(fig)


def plot_differences(comparisons, path):
    """Horizontal bars: each compared row's difference in %, coloured by basis, the band
    shaded; an open marker where the thesis says its own model disagrees there."""
    shown = [c for c in comparisons if c.percent is not None]
    fig, ax = plt.subplots(figsize=(9, 0.28 * len(shown) + 1.6))
    y = np.arange(len(shown))[::-1]
    ax.axvspan(-BAND, BAND, color="0.92", zorder=0, label=f"+-{BAND:g} % (--strict)")
    for basis, colour in BASIS_COLOURS.items():
        k = [i for i, c in enumerate(shown) if c.measurement.basis == basis]
        if k:
            ax.barh(y[k], [shown[i].percent for i in k], color=colour, label=basis)
    disagree = [i for i, c in enumerate(shown) if c.measurement.thesis_agreement == "disagrees"]
    if disagree:
        ax.plot([shown[i].percent for i in disagree], y[disagree], "o", markerfacecolor="none",
                color="black", label="the thesis's model disagrees too")
    ax.set_yticks(y, [c.measurement.id for c in shown], fontsize=7)
    ax.axvline(0.0, color="black", linewidth=0.8)
    ax.set_xlabel("model - measured (% of the measured value, or of the row's scale)")
    ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    ax.grid(True, axis="x", alpha=0.3)
    _save(fig, f"{shown[0].measurement.component}: model against measurement", path)


def plot_small_loops(records, comparisons, path):
    """Measurement I: the model's recorded loops, the thesis's elastic fit evaluated at the
    preloads (its measured loop centres' line) and the model's loop centres."""
    fmu = records[0].case.fmu
    (x_factor, x_unit), (f_factor, f_unit), _ = DISPLAY[fmu]
    fig, ax = plt.subplots(figsize=(9, 6))
    for record in records:
        ax.plot(record.column("deflection") * x_factor, record.column("load") * f_factor,
                color="tab:blue", linewidth=0.8)
        ax.plot(np.mean(record.column("deflection")[:-1]) * x_factor,
                loop_centre(record) * f_factor, "o", color="tab:blue", markersize=5)
    fitted = [c for c in comparisons if c.measurement.metric == "loop_centre"
              and c.measurement.component == fmu]
    preloads = [np.mean(r.column("deflection")[:-1]) * x_factor for r in records]
    if len(fitted) == len(records):  # the loop-centre rows are in N or N.m, SI
        ax.plot(preloads, [c.measurement.measured * f_factor for c in fitted], **ELASTIC_STYLE,
                zorder=0, label="thesis: elastic fit through its measured loop centres")
    ax.plot([], [], "o-", color="tab:blue", label="model (FMU): loops and their centres")
    load = COMPONENTS[fmu].outputs[0].name
    ax.set_xlabel(f"{COMPONENTS[fmu].inputs[0].name} ({x_unit})")
    ax.set_ylabel(f"{load} ({f_unit})")
    ax.legend(fontsize=8)
    ax.grid(True, alpha=0.3)
    _save(fig, f"{fmu}: Measurement I (section 5.3), model against the thesis's elastic fit",
          path)


def plot_damper_tests(records, comparisons, path):
    """Tests A-D: the model's torque against angular velocity, with the numbers the thesis
    states of its measured characteristic (Fig. 12.0-2, sections 12.0-12.2)."""
    fig, ax = plt.subplots(figsize=(9, 6))
    colours = plt.get_cmap("viridis")(np.linspace(0.0, 0.85, len(records)))
    for record, colour in zip(records, colours):
        ax.plot(record.column("rate"), record.column("load"), color=colour, linewidth=1.0,
                label=f"model (FMU), {record.case.label}")
    said = {c.measurement.id: c.measurement for c in comparisons}
    rate = np.linspace(-1.0, 1.0, 3)
    for key, limit, style in (("damper-laminar-slope", 0.25, dict(color="tab:green")),
                              ("damper-general-slope", 1.0, dict(color="tab:red"))):
        if key in said:
            r = rate * limit
            ax.plot(r, said[key].measured * r, linestyle="--", **style,
                    label=f"thesis: {said[key].measured_text} ({said[key].source.split(',')[0]})")
    # the transition at its rate; the peak at the peak rate of its test
    points = [(said[key].at, said[key].measured) for key in ("damper-transition-torque",)
              if key in said]
    points += [(float(np.max(r.column("rate"))), said[key].measured)
               for key in ("damper-peak-torque-A",) if key in said
               for r in records if r.case.key == said[key].case]
    for w, torque in points:
        ax.plot([w, -w], [torque, -torque], "s", color="black", markerfacecolor="none")
    if "damper-largest-torque-A-D" in said:
        bound = said["damper-largest-torque-A-D"].measured
        ax.axhline(bound, color="0.5", linestyle=":", label="thesis: up to 4 kN.m (section 12.0)")
        ax.axhline(-bound, color="0.5", linestyle=":")
    ax.plot([], [], "s", color="black", markerfacecolor="none",
            label="thesis: 250 N.m at 0.25 rad/s, 3250 N.m at 1 rad/s (section 12.2)")
    ax.set_xlabel("angular velocity (rad/s)")
    ax.set_ylabel("torque (N.m)")
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, alpha=0.3)
    _save(fig, "RotaryDamper: tests A-D (Table 11.2-1), model against the thesis's "
               "characteristic (Fig. 12.0-2)", path)


def plot_table_a6_1(comparisons, path):
    """Steady torque against angular velocity: Table A6-1's measured column by basis, its
    smoothed column (the thesis's model) and the model's steady torques."""
    rows = sorted((c for c in comparisons if c.measurement.id.startswith("damper-A6-1-")),
                  key=lambda c: c.measurement.at)
    fig, ax = plt.subplots(figsize=(9, 6))
    rates = [c.measurement.at for c in rows]
    ax.plot(rates, [c.measurement.thesis_model for c in rows], color="0.6", linewidth=2.0,
            label="thesis's model: smoothed column")
    for basis, colour in BASIS_COLOURS.items():
        k = [c for c in rows if c.measurement.basis == basis]
        if k:
            ax.plot([c.measurement.at for c in k], [c.measurement.measured for c in k], "x",
                    color=colour, label=f"measured column: {basis}")
    ran = [c for c in rows if c.ran]
    ax.plot([c.measurement.at for c in ran], [c.model for c in ran], "o", color="black",
            markerfacecolor="none", label="model (FMU): steady torque")
    ax.set_xlabel("angular velocity (rad/s)")
    ax.set_ylabel("torque (N.m)")
    ax.legend(fontsize=7, loc="upper left")
    ax.grid(True, alpha=0.3)
    _save(fig, "RotaryDamper: steady torque against Table A6-1 (Appendix 6)", path)


def _cell(text):
    return str(text).replace("|", "\\|").replace("\n", " ")


def _records(runs, pattern):
    return [r for key, r in runs.records.items() if fnmatch.fnmatchcase(key, pattern)]


def write_report(comparisons, runs, folder):
    """summary.md and the PNGs in folder; returns the summary's path."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    lines = ["# Validation: the model against the thesis's measurements", "",
             "Every number the thesis states from its own rig tests "
             "(`reference_data/thesis/measurements.csv`), run through the FMUs under the "
             "test's conditions. The model's value is taken from the run the way the thesis "
             "took the measured one. `basis` says what the measured value is: the rig's "
             "measurement, a fit the thesis made to it, the manufacturer's data, or a value "
             "with no measurement behind it (extrapolated, assumed, design). Statements "
             "without a number are shown with the model's value and not compared. With "
             f"`--strict`, measurements (rig, fit, supplier) must lie within +-{BAND:g} % or "
             "their bound: a convention for flagging, not a measurement uncertainty (the "
             "thesis gives none).", "", tally(comparisons), "", "## Figures", ""]
    components = list(dict.fromkeys(c.measurement.component for c in comparisons))
    figures = []
    for fmu in components:
        mine = [c for c in comparisons if c.measurement.component == fmu]
        if any(c.percent is not None for c in mine):
            figures.append((f"differences_{fmu}.png", plot_differences, (mine,)))
        small = _records(runs, f"{fmu}/I_*")
        if small:
            figures.append((f"measurement_I_{fmu}.png", plot_small_loops, (small, mine)))
    tests = sorted(_records(runs, "RotaryDamper/[A-D]_*"), key=lambda r: r.case.name)
    if tests:
        figures.append(("damper_tests_A-D.png", plot_damper_tests, (tests, comparisons)))
    if any(c.ran and c.measurement.id.startswith("damper-A6-1-") for c in comparisons):
        figures.append(("damper_table_A6-1.png", plot_table_a6_1, (comparisons,)))
    for name, plot, arguments in figures:
        plot(*arguments, folder / name)
        lines += [f"![{name}]({name})", ""]
    lines += ["## Measured quantities", "",
              "| id | quantity | conditions | measured | model | difference | % | basis | "
              "source | the thesis on its model | result |",
              "|---" * 11 + "|"]
    for c in comparisons:
        m = c.measurement
        said = f"{m.thesis_agreement}: {m.thesis_says}" if m.thesis_agreement else m.thesis_says
        lines.append("| " + " | ".join(_cell(v) for v in (
            m.id, m.quantity, m.conditions, m.measured_text,
            with_unit(c.model, m.unit) if c.ran else "-",
            with_unit(c.difference, m.unit, "+.4g") if c.difference is not None else "-",
            f"{c.percent:+.1f}" if c.percent is not None else "-",
            m.basis, f"{m.source}: \"{m.quote}\"", said or "-",
            c.problem or c.verdict)) + " |")
    summary = folder / "summary.md"
    write_text(summary, "\n".join(lines) + "\n")
    return summary
