"""`fmu-components simulate`: an FMU on an input CSV. It refuses what fmpy would run
without a word (a missing rate column, misspelt columns, mm or deg values, a stop time past
the input), and its result holds the inputs and every output, matching the independent
solve."""

import csv
import math
import subprocess
import sys

import numpy as np
import pytest

from fmu_components import cli

from fmu_components.verification import reference
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import input_table, sine, time_grid, write_csv

from conftest import ROOT, peak_to_peak

ACCEPTANCE = 0.5e-2  # of the output's peak-to-peak range, as tests/test_accuracy.py


def write_input(path, name, columns=None, scale=1.0, frequency=1.0, duration=1.0, step=1e-3):
    """A sine in the thesis range (times `scale`), with the named columns of the input
    table (all by default); returns the table."""
    mean, amplitude = {"RoadWheelTyre": (3.5e-3, 1e-3), "TrackBushRadial": (0.3e-3, 0.1e-3),
                       "TrackBushTorsion": (math.radians(10), math.radians(5)),
                       "RotaryDamper": (0.0, 0.21)}[name]
    t = time_grid(duration, step)
    table = input_table(name, t, sine(t, mean, amplitude, frequency))
    for field in table.dtype.names[1:]:
        table[field] *= scale
    if columns is not None:
        table = table[list(columns)]
    with open(path, "w", newline="") as file:
        write_csv(table, file)
    return table


def run(capsys, *args):
    """(exit status, stdout, stderr) of `fmu-components simulate ...` in this process."""
    try:
        status = cli.main(["simulate", *map(str, args)])
    except SystemExit as exit:
        status = exit.code
    captured = capsys.readouterr()
    return status, captured.out, captured.err


def read_result(path):
    with open(path, newline="") as file:
        rows = list(csv.reader(file))
    return rows[0], np.array(rows[1:], dtype=float)


def test_a_missing_rate_column_is_refused_with_the_inputs_named(native_fmus, tmp_path):
    """Through the console entry point, as a user runs it."""
    source = tmp_path / "in.csv"
    write_input(source, "RoadWheelTyre", ["time", "compression"])
    out = tmp_path / "out.csv"
    completed = subprocess.run(
        [sys.executable, "-m", "fmu_components", "simulate", str(native_fmus["RoadWheelTyre"]),
         str(source), "--out", str(out)], capture_output=True, text=True, cwd=ROOT)
    assert completed.returncode == 2 and not out.exists()
    lines = completed.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in completed.stderr
    assert ("has no compression_rate column: RoadWheelTyre's inputs are compression, "
            "compression_rate; the CSV's columns are time, compression") in lines[0]
    assert "--derive-rate" in lines[0]


@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_the_result_has_the_inputs_and_every_output_and_matches_the_reference(
        built_fmus, name, tmp_path, capsys):
    source, out, plot = tmp_path / "in.csv", tmp_path / "out.csv", tmp_path / "loop.png"
    table = write_input(source, name)
    status, said, errors = run(capsys, built_fmus[name], source, "--out", out, "--plot", plot)
    assert status == 0 and errors == ""
    header, values = read_result(out)
    definition = COMPONENTS[name]
    assert header == ["time"] + [v.name for v in definition.inputs] + [v.name for v in definition.outputs]
    assert len(values) == len(table)
    deflection, rate = (v.name for v in definition.inputs)
    assert np.allclose(values[:, 0], table["time"], rtol=0, atol=1e-12)
    assert np.array_equal(values[:, 1], table[deflection])
    assert np.array_equal(values[:, 2], table[rate])
    expected = reference.solve_held_rate(name, table["time"], table[deflection], table[rate])
    for output, reference_values in expected.items():
        column = values[:, header.index(output)]
        assert np.max(np.abs(column - reference_values)) <= ACCEPTANCE * peak_to_peak(
            reference_values), output
    import matplotlib.image
    # the loop beside the time histories: 12.8 x 5.6 in at 200 dpi
    assert matplotlib.image.imread(plot).shape[:2] == (1120, 2560)
    assert str(out) in said and str(plot) in said


def test_derive_rate_runs_without_a_rate_column(built_fmus, tmp_path, capsys):
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    table = write_input(source, "TrackBushRadial", ["time", "deflection"])
    status, _, errors = run(capsys, built_fmus["TrackBushRadial"], source, "--out", out,
                            "--derive-rate")
    assert status == 0 and errors == ""  # no fmpy note about the rate left out on purpose
    header, values = read_result(out)
    # The rate column is the one the FMU derived: the backward difference, held.
    x = table["deflection"]
    assert values[0, 2] == 0.0
    assert np.allclose(values[1:, 2], np.diff(x) / np.diff(table["time"]), rtol=1e-9)
    # With the rate derived the viscoelastic force is there (rate 0 would make it vanish).
    viscoelastic = values[:, header.index("force_viscoelastic")]
    assert peak_to_peak(viscoelastic) > 0.05 * peak_to_peak(values[:, header.index("force")])


def test_misspelt_columns_are_listed_against_the_inputs(native_fmus, tmp_path, capsys):
    source = tmp_path / "in.csv"
    write_input(source, "TrackBushTorsion")
    text = source.read_text().replace('"angle_rate"', '"angle_speed"', 1)
    source.write_text(text)
    status, _, errors = run(capsys, native_fmus["TrackBushTorsion"], source, "--out",
                            tmp_path / "out.csv")
    assert status == 2 and len(errors.strip().splitlines()) == 1
    assert ("columns angle, angle_speed do not match the inputs of TrackBushTorsion "
            "(angle, angle_rate)") in errors


@pytest.mark.parametrize("name, scale, unit, factor", [
    ("RoadWheelTyre", 1e3, "mm", "1000"), ("TrackBushRadial", 1e3, "mm", "1000"),
    ("TrackBushTorsion", 180 / math.pi, "deg", "57.2958"), ("RotaryDamper", 180 / math.pi, "deg", "57.2958")])
def test_values_in_mm_or_deg_are_refused_with_what_to_do(native_fmus, tmp_path, capsys, name,
                                                         scale, unit, factor):
    source = tmp_path / "in.csv"
    write_input(source, name, scale=scale)
    status, _, errors = run(capsys, native_fmus[name], source, "--out", tmp_path / "out.csv")
    assert status == 2 and len(errors.strip().splitlines()) == 1
    assert f"it looks like {unit}" in errors and f"Convert to SI" in errors
    assert f"divide by {factor}" in errors


def test_a_stop_time_past_the_input_is_refused(native_fmus, tmp_path, capsys):
    source = tmp_path / "in.csv"
    write_input(source, "RoadWheelTyre", duration=0.5)
    status, _, errors = run(capsys, native_fmus["RoadWheelTyre"], source, "--out",
                            tmp_path / "out.csv", "--stop-time", "0.8")
    assert status == 2
    assert "--stop-time 0.8 s is past the input's end at 0.5 s" in errors


def test_step_and_stop_time_are_taken_and_a_wrong_rate_is_reported(native_fmus, tmp_path,
                                                                    capsys):
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    table = write_input(source, "RoadWheelTyre", step=2e-3)
    text = source.read_text().splitlines()
    # the rate in mm/s: the FMU's rate check warns, and simulate passes it on
    rows = [text[0]] + [",".join([*r.split(",")[:2], repr(float(r.split(",")[2]) * 1e3)])
                        for r in text[1:]]
    source.write_text("\n".join(rows) + "\n")
    status, _, errors = run(capsys, native_fmus["RoadWheelTyre"], source, "--out", out,
                            "--stop-time", "0.5", "--tolerance", "1e-6")
    assert status == 0
    assert "RoadWheelTyre: fmi2DoStep: compression_rate = " in errors
    assert "does not fit the movement of compression" in errors
    _, values = read_result(out)
    assert len(values) == 251 and values[-1, 0] == pytest.approx(0.5)
    assert np.allclose(np.diff(values[:, 0]), 2e-3)
    assert len(table) == 501


def test_a_step_finer_than_the_samples_feeds_the_path_between_them(native_fmus, tmp_path,
                                                                   capsys):
    """fmpy interpolates the deflection straight between samples; simulate feeds that
    line's slope as the rate, so the pair fits and the rate check stays quiet."""
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    table = write_input(source, "TrackBushTorsion", step=1e-2)
    status, _, errors = run(capsys, native_fmus["TrackBushTorsion"], source, "--out", out,
                            "--step", "1e-3")
    assert status == 0 and errors == ""
    header, values = read_result(out)
    assert len(values) == 1001
    samples = values[::10]
    assert np.allclose(samples[:, 1], table["angle"], rtol=0, atol=1e-15)
    # between samples: on the straight line, with its slope as the rate
    slopes = np.diff(table["angle"]) / 1e-2
    assert np.allclose(values[:-1, 2], np.repeat(slopes, 10), rtol=1e-9)
    expected = reference.solve_held_rate("TrackBushTorsion", values[:, 0], values[:, 1],
                                         values[:, 2])["torque"]
    torque = values[:, header.index("torque")]
    assert np.max(np.abs(torque - expected)) <= ACCEPTANCE * peak_to_peak(expected)


@pytest.mark.parametrize("step", [3e-4, 3e-3])
def test_a_step_that_does_not_divide_the_span_ends_on_the_stop_time(native_fmus, tmp_path,
                                                                    capsys, step):
    """fmpy ends with a shorter step to the stop time: the last row is that time's, its
    times strictly increase, and every row's inputs are the input's at that row's time."""
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    table = write_input(source, "RoadWheelTyre", duration=2.0)
    status, _, _ = run(capsys, native_fmus["RoadWheelTyre"], source, "--out", out,
                       "--step", step)
    assert status == 0
    _, values = read_result(out)
    assert np.all(np.diff(values[:, 0]) > 0.0)
    assert values[-1, 0] == 2.0
    assert np.allclose(values[:, 1], np.interp(values[:, 0], table["time"], table["compression"]),
                       rtol=0, atol=1e-12)
    # the last row's force is the force at 2.0 s: the same as a run that stops there on
    # a dividing step
    status, _, _ = run(capsys, native_fmus["RoadWheelTyre"], source, "--out",
                       tmp_path / "whole.csv", "--step", "1e-3")
    _, whole = read_result(tmp_path / "whole.csv")
    assert values[-1, 3] == pytest.approx(whole[-1, 3], rel=2e-3)


@pytest.mark.parametrize("shape, expected", [
    ("step", "step and hold: 0 mm to 4 mm in 0.1 s, held 200 s"),
    ("bump", "single bump: 3 mm to 4 mm and back to 3 mm over 2 s"),
    ("sine", "sine: 0.75 Hz, 3.5 mm +- 1 mm"),
    ("ramp", "ramp: 0 mm to 2 mm over 2 s"),
    ("constant", "constant at 1 mm"),
])
def test_a_plot_is_titled_with_what_the_signal_really_is(shape, expected):
    """Not 'main frequency 0.005 Hz' for a step and hold, nor '0.999 Hz' for one bump."""
    from fmu_components.lab.signals import describe, ramp_and_hold

    t = np.arange(0, 200.0 + 1e-9, 0.01) if shape == "step" else time_grid(2.0, 1e-3)
    x = {"step": lambda: ramp_and_hold(t, 0.0, 4e-3, 0.1),
         "bump": lambda: 3e-3 + 1e-3 * (1 - np.cos(math.pi * t)) / 2,
         "sine": lambda: sine(t, 3.5e-3, 1e-3, 0.75),
         "ramp": lambda: 1e-3 * t,
         "constant": lambda: np.full_like(t, 1e-3)}[shape]()
    assert describe(t, x, 1e3, "mm") == expected


@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_an_fmi3_fmu_gives_the_fmi2_fmus_result_to_the_bit(all_fmus, name, tmp_path, capsys):
    """`simulate fmus/fmi3/X.fmu` runs the FMI 3.0 FMU (it looked for an FMI 2.0 binary)
    and writes the FMI 2.0 FMU's CSV byte for byte: fmpy's loop is the same for both
    versions, and so are the FMUs' core and model code. With a parameter set and the rate
    derived too."""
    source = tmp_path / "in.csv"
    write_input(source, name, duration=0.5)
    parameter = COMPONENTS[name].parameters[0].name
    value = COMPONENTS[name].default_parameters()[parameter] * 1.1
    written = {}
    for flavour in ("native", "fmi3"):
        for options in ([], ["--derive-rate", "--param", f"{parameter}={value!r}"]):
            out = tmp_path / f"{flavour}{len(options)}.csv"
            status, _, errors = run(capsys, all_fmus[flavour][name], source, "--out", out,
                                    *options)
            assert status == 0, errors
            written[flavour, len(options)] = out.read_bytes()
    assert written["native", 0] == written["fmi3", 0]
    assert written["native", 3] == written["fmi3", 3]
    assert written["native", 0] != written["native", 3]


# --- arguments and inputs that must not pass ----------------------------------------------

def run_apart(*args, timeout=120):
    """`fmu-components simulate ...` in a process of its own (a hang or a runaway memory
    stays there): (exit status, stderr)."""
    completed = subprocess.run([sys.executable, "-m", "fmu_components", "simulate",
                                *map(str, args)], capture_output=True, text=True, cwd=ROOT,
                               timeout=timeout)
    return completed.returncode, completed.stderr


@pytest.mark.parametrize("option, value, words", [
    ("--stop-time", "nan", ["--stop-time nan"]),
    ("--stop-time", "-1", ["--stop-time -1", "after the input's start at 0 s"]),
    ("--stop-time", "0", ["--stop-time 0", "after the input's start at 0 s"]),
    ("--tolerance", "5", ["--tolerance 5", "between 0 and 1"]),
    ("--tolerance", "nan", ["--tolerance nan"]),
    ("--step", "1e-9", ["--step 1e-09", "1e+09 communication steps"]),
])
def test_a_stop_time_tolerance_or_step_that_cannot_be_meant_is_one_line(native_fmus, tmp_path,
                                                                        option, value, words):
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    write_input(source, "RoadWheelTyre")
    status, errors = run_apart(native_fmus["RoadWheelTyre"], source, "--out", out, option,
                               value, timeout=60)
    assert status == 2 and not out.exists()
    lines = errors.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in errors, errors
    for word in words:
        assert word in lines[0], lines[0]


@pytest.mark.parametrize("step", ["0.5", "0.01"])
def test_a_step_coarser_than_the_samples_is_warned_about(native_fmus, tmp_path, capsys, step):
    """The FMU holds each communication point's rate over the whole step: samples between
    steps are skipped and the force is wrong. The user is told which step and which
    spacing."""
    source, out = tmp_path / "in.csv", tmp_path / "out.csv"
    write_input(source, "RoadWheelTyre")
    status, _, errors = run(capsys, native_fmus["RoadWheelTyre"], source, "--out", out,
                            "--step", step)
    assert status == 0
    assert f"--step {step} s is coarser than the input's sampling (0.001 s)" in errors
    # the input's own step says nothing
    status, _, errors = run(capsys, native_fmus["RoadWheelTyre"], source, "--out", out)
    assert status == 0 and errors == ""


def test_the_result_folder_is_made_before_the_run(native_fmus, tmp_path, capsys):
    source = tmp_path / "in.csv"
    write_input(source, "TrackBushRadial")
    out, plot = tmp_path / "nodir" / "sub" / "o.csv", tmp_path / "plots" / "loop.png"
    status, said, errors = run(capsys, native_fmus["TrackBushRadial"], source, "--out", out,
                               "--plot", plot)
    assert status == 0 and errors == "", errors
    assert len(read_result(out)[1]) == 1001 and plot.stat().st_size > 10_000


@pytest.mark.parametrize("cell, words", [
    ("nan", ["row 6", "time 0.004 s", "compression", "nan"]),
    ("abc", ["row 6", "time 0.004 s", "'abc'"]),
    ("", ["row 6", "time 0.004 s", "''"]),
])
def test_a_bad_cell_is_named_by_its_row_and_time(native_fmus, tmp_path, capsys, cell, words):
    source = tmp_path / "in.csv"
    write_input(source, "RoadWheelTyre")
    lines = source.read_text().splitlines()
    time, _, rate = lines[5].split(",")  # row 6 of the file, the 5th sample
    lines[5] = ",".join([time, cell, rate])
    source.write_text("\n".join(lines) + "\n")
    status, _, errors = run(capsys, native_fmus["RoadWheelTyre"], source, "--out",
                            tmp_path / "out.csv")
    assert status == 2 and len(errors.strip().splitlines()) == 1, errors
    for word in words:
        assert word in errors, errors


def test_a_semicolon_separated_file_gets_a_hint(native_fmus, tmp_path, capsys):
    source = tmp_path / "in.csv"
    write_input(source, "RoadWheelTyre")
    source.write_text(source.read_text().replace(",", ";"))
    status, _, errors = run(capsys, native_fmus["RoadWheelTyre"], source, "--out",
                            tmp_path / "out.csv")
    assert status == 2 and len(errors.strip().splitlines()) == 1, errors
    assert "separated by ';'" in errors and "commas" in errors


def test_the_damper_plot_shows_its_torque_and_its_parts(native_fmus, tmp_path):
    """The torque is drawn wide and light under its parts, so that a part equal to it
    (the dashpot's torque, most of the time) does not hide it."""
    from fmu_components.lab.simulate import Component, loop_figure

    component = Component(str(native_fmus["RotaryDamper"]))
    table = write_input(tmp_path / "in.csv", "RotaryDamper")
    columns = {"time": table["time"], "angle": table["angle"], "angle_rate": table["angle_rate"]}
    for output in component.outputs:
        columns[output] = np.sin(table["time"])  # every part equal to the torque
    figure = loop_figure(component, columns)
    histories = figure.axes[3]
    lines = {line.get_label(): line for line in histories.get_lines()}
    torque = lines["torque"]
    parts = [lines[n] for n in lines if n != "torque"]
    assert parts and all(torque.get_linewidth() > 2 * p.get_linewidth() for p in parts)
    assert all(torque.get_zorder() < p.get_zorder() for p in parts)
    assert figure.axes[0].get_xlabel() == "angle (rad)"  # as the thesis gives its tests
