"""The fit report: PARAMS_report.md beside PARAMS.json, with 200-dpi plots of the measured
against the fitted responses, the residuals and the parameters' correlations."""

import math
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .display import DISPLAY  # noqa: E402
from .files import save_figure, write_text  # noqa: E402
from .measured import History  # noqa: E402

DPI = 200


def _grid(count):
    columns = min(count, 3)
    return math.ceil(count / columns), columns


def plot_responses(result, responses, path):
    (xf, xu), (ff, fu), _ = DISPLAY[result.component]
    rows, columns = _grid(len(result.tests))
    fig, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 3.4 * rows), squeeze=False)
    for ax, test, response in zip(axes.flat, result.tests, responses):
        if isinstance(test, History):
            ax.plot(test.deflection * xf, test.force * ff, ".", color="0.6", markersize=1.5,
                    label="measured")
            ax.plot(test.deflection * xf, response * ff, color="C0", linewidth=1.0,
                    label="fitted")
            ax.set_xlabel(f"deflection ({xu})")
            ax.set_ylabel(f"force ({fu})")
        else:
            frequency = test.rows[:, 2]
            ax.semilogx(frequency, test.rows[:, 3] * ff / xf, "o", color="0.5", label="|K*| measured")
            ax.semilogx(frequency, response[:, 0] * ff / xf, "x", color="C0", label="|K*| fitted")
            ax.set_xlabel("frequency (Hz)")
            ax.set_ylabel(f"|K*| ({fu}/{xu})")
            twin = ax.twinx()
            twin.semilogx(frequency, test.rows[:, 4], "s", color="0.8", label="loss angle measured")
            twin.semilogx(frequency, response[:, 1], "+", color="C1", label="loss angle fitted")
            twin.set_ylabel("loss angle (deg)")
        ax.set_title(test.label, fontsize=9)
        ax.legend(fontsize=7)
    for ax in list(axes.flat)[len(result.tests):]:
        ax.axis("off")
    fig.tight_layout()
    save_figure(fig, path, dpi=DPI)
    plt.close(fig)


def plot_residuals(result, responses, path):
    rows, columns = _grid(len(result.tests))
    fig, axes = plt.subplots(rows, columns, figsize=(4.2 * columns, 2.8 * rows), squeeze=False)
    for ax, test, response in zip(axes.flat, result.tests, responses):
        if isinstance(test, History):
            ax.plot(test.times, (response - test.force) / test.scale * 100, linewidth=0.6)
            ax.set_xlabel("time (s)")
            ax.set_ylabel("fitted - measured (% p-p)")
        else:
            frequency = test.rows[:, 2]
            ax.semilogx(frequency, (response[:, 0] / test.rows[:, 3] - 1) * 100, "o",
                        label="|K*| (%)")
            ax.semilogx(frequency, response[:, 1] - test.rows[:, 4], "s", label="loss angle (deg)")
            ax.set_xlabel("frequency (Hz)")
            ax.legend(fontsize=7)
        ax.axhline(0.0, color="0.5", linewidth=0.5)
        ax.set_title(test.label, fontsize=9)
    for ax in list(axes.flat)[len(result.tests):]:
        ax.axis("off")
    fig.tight_layout()
    save_figure(fig, path, dpi=DPI)
    plt.close(fig)


def plot_correlation(result, path):
    names = [s.name for s in result.free]
    fig, ax = plt.subplots(figsize=(1.0 + 0.45 * len(names), 0.6 + 0.45 * len(names)))
    image = ax.imshow(result.correlation(), vmin=-1, vmax=1, cmap="RdBu_r")
    ax.set_xticks(range(len(names)), names, rotation=90, fontsize=7)
    ax.set_yticks(range(len(names)), names, fontsize=7)
    fig.colorbar(image, ax=ax, shrink=0.8, label="correlation")
    ax.set_title("parameter correlation at the solution", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, dpi=DPI)
    plt.close(fig)


def test_errors(test, response):
    """RMS and max error of a test in % of its measured peak-to-peak force (a History), or
    of |K*| in % and of the loss angle in deg (a RigTable)."""
    if isinstance(test, History):
        error = (response - test.force) / test.scale * 100
        return f"{np.sqrt(np.mean(error ** 2)):.2f} % rms, {np.max(np.abs(error)):.2f} % max of p-p"
    k = (response[:, 0] / test.rows[:, 3] - 1) * 100
    d = response[:, 1] - test.rows[:, 4]
    return (f"dynamic stiffness {np.sqrt(np.mean(k ** 2)):.2f} % rms; loss angle "
            f"{np.sqrt(np.mean(d ** 2)):.2f} deg rms")


def write_report(result, out):
    """Markdown and plots beside `out` (PARAMS.json); returns the Markdown's path."""
    out = Path(out)
    stem = out.with_suffix("")
    responses = result.responses()
    figures = {"responses": f"{stem.name}_responses.png",
               "residuals": f"{stem.name}_residuals.png",
               "correlation": f"{stem.name}_correlation.png"}
    plot_responses(result, responses, out.parent / figures["responses"])
    plot_residuals(result, responses, out.parent / figures["residuals"])
    plot_correlation(result, out.parent / figures["correlation"])

    confidence = result.confidence()
    lines = [f"# Fit of {result.component} ({result.structure} structure)", "",
             f"Parameters: `{out.name}`. {len(result.tests)} test(s), {result.samples} "
             f"residuals, {len(result.free)} free parameters, {len(result.starts)} starting "
             f"point(s), {result.wall_time:.1f} s.", "",
             "## Tests", "", "| test | kind | error of the fitted model |", "|---|---|---|"]
    for test, response in zip(result.tests, responses):
        kind = "history" if isinstance(test, History) else f"rig table, {len(test.rows)} rows"
        lines.append(f"| {test.label} | {kind} | {test_errors(test, response)} |")
    lines += ["", f"![measured and fitted]({figures['responses']})", "",
              f"![residuals]({figures['residuals']})", "",
              "## Parameters", "",
              "95 % intervals from the Jacobian at the solution (s^2 (J'J)^-1 in the scaled "
              "parameters); an end beyond the floats is inf, the interval unbounded.", "",
              "| parameter | thesis | fitted | 95 % interval | +- % |", "|---|---|---|---|---|"]
    for name, value in result.values.items():
        if name in confidence:
            low, high, relative = confidence[name]
            flag = " **not identifiable**" if result.too_wide(relative) else ""
            width = "unbounded" if math.isinf(relative) else f"{relative * 100:.1f}"
            lines.append(f"| `{name}` | {result.thesis[name]:.5g} | {value:.5g} | "
                         f"{low:.4g} .. {high:.4g} | {width}{flag} |")
        else:
            lines.append(f"| `{name}` | {result.thesis[name]:.5g} | {value:.5g} (fixed) | | |")
    lines += ["", f"Condition number of the Jacobian: {result.condition():.3g}.", "",
              f"![correlation]({figures['correlation']})", "", "## Starting points", "",
              "| start | cost | evaluations | stopped because |", "|---|---|---|---|"]
    for i, (cost, evaluations, message) in enumerate(result.starts):
        lines.append(f"| {i + 1} | {cost:.4g} | {evaluations} | {message} |")
    notes = result.warnings()
    lines += ["", "## Warnings", ""] + ([f"* {n}" for n in notes] or ["None."]) + [""]
    path = out.parent / f"{stem.name}_report.md"
    write_text(path, "\n".join(lines))
    return path
