"""fmu-components fit: a small synthetic round trip through the command line (data from the
independent reference solver with 0.5 % noise, a held-back test predicted), and one clear
line for each kind of bad data file."""

import json
import math

import numpy as np
import pytest

from fmu_components import cli
from fmu_components.export.parameters import read_parameters

from fmu_components.verification import synthetic
from fmu_components.lab.history import simulate
from fmu_components.runtime.catalog import component_definition

COMPONENT = "TrackBushRadial"
MM = 1e-3
TRUTH = synthetic.scaled(COMPONENT, {"k": 1.5, "c": 0.7})
FIXED = ["xi1", "xi2", "xi3", "elastic.a0", "elastic.a2", "elastic.a3", "geometric.h"]


def sine_path(mean, amplitude, frequency):
    return lambda t: mean + amplitude * np.sin(2 * math.pi * frequency * t)


def sine_times(frequency, cycles, per_cycle=100):
    return np.arange(cycles * per_cycle + 1) / (frequency * per_cycle)


def measured(label, mean, amplitude, frequency, cycles, seed):
    return synthetic.measure_path(COMPONENT, label, sine_times(frequency, cycles),
                                  sine_path(mean, amplitude, frequency), TRUTH, 0.005, seed)


def run_fit(*argv):
    return cli.main(["fit", "--component", COMPONENT, *map(str, argv)])


def test_round_trip_recovers_the_parameters_and_predicts_a_held_back_test(tmp_path):
    files = []
    for seed, (mean, amplitude, frequency, cycles) in enumerate(
            [(0.2 * MM, 0.1 * MM, 0.2, 2), (0.3 * MM, 0.05 * MM, 1.0, 3),
             (0.1 * MM, 0.2 * MM, 5.0, 3)]):
        history, _ = measured(f"sine{seed}.csv", mean, amplitude, frequency, cycles, seed)
        files.append(synthetic.write_history(tmp_path / history.label, history))
    out = tmp_path / "fitted" / "bush.json"
    assert run_fit("--fix", *FIXED, "--starts", "2", "--out", out, *files) == 0

    fitted = json.loads(out.read_text())
    assert set(fitted) == set(TRUTH)
    # the same set beside it as SSP, bit for bit
    assert read_parameters(out.with_suffix(".ssv"), component_definition(COMPONENT)) == fitted
    for name in FIXED + ["geometric.x_ref"]:
        assert fitted[name] == TRUTH[name]
    for name in ("k1", "k3", "c3", "elastic.a1"):
        assert fitted[name] == pytest.approx(TRUTH[name], rel=0.1), name
    held_back, truth = measured("held.csv", 0.25 * MM, 0.15 * MM, 2.0, 3, 9)
    predicted = simulate(COMPONENT, fitted, held_back.times, held_back.deflection)
    assert synthetic.peak_to_peak_error(predicted, truth) < 2.0

    report = (out.parent / "bush_report.md").read_text()
    for figure in ("responses", "residuals", "correlation"):
        assert (out.parent / f"bush_{figure}.png").stat().st_size > 10_000
        assert f"bush_{figure}.png" in report
    assert "95 % interval" in report


# --- bad data files -----------------------------------------------------------------------

def one_line_error(capsys, tmp_path, text, *argv):
    path = tmp_path / "data.csv"
    path.write_text(text)
    with pytest.raises(SystemExit) as exit_:
        run_fit("--out", tmp_path / "p.json", path, *argv)
    assert exit_.value.code == 2
    message = capsys.readouterr().err.strip()
    assert "\n" not in message and "Traceback" not in message
    return message


def csv_text(t, x, f, header="time,deflection,force"):
    return header + "\n" + "\n".join(f"{float(a)!r},{float(b)!r},{float(c)!r}"
                                   for a, b, c in zip(t, x, f)) + "\n"


def good_sine(cycles=2.0, n=400):
    t = np.linspace(0.0, cycles, n)
    x = 0.2 * MM + 0.1 * MM * np.sin(2 * math.pi * t)
    return t, x, 81.8e6 * x


def test_wrong_columns_are_listed_against_the_expected(capsys, tmp_path):
    t, x, f = good_sine()
    message = one_line_error(capsys, tmp_path, csv_text(t, x, f, "t,x,F"))
    assert "columns t,x,F" in message and "expected time,deflection,force" in message
    assert "preload,amplitude,frequency,dynamic_stiffness,loss_angle_deg" in message


def test_deflection_in_mm_is_caught(capsys, tmp_path):
    t, x, f = good_sine()
    message = one_line_error(capsys, tmp_path, csv_text(t, x / MM, f))
    assert "looks like mm" in message and "give m" in message


def test_force_in_kn_is_caught(capsys, tmp_path):
    t, x, f = good_sine()
    message = one_line_error(capsys, tmp_path, csv_text(t, x, f / 1e3))
    assert "looks like kN" in message and "give N" in message


def test_too_few_cycles_is_caught(capsys, tmp_path):
    t, x, f = good_sine(cycles=0.4)
    message = one_line_error(capsys, tmp_path, csv_text(t, x, f))
    assert "too few cycles" in message


def test_too_few_samples_is_caught(capsys, tmp_path):
    t, x, f = good_sine(n=20)
    assert "20 samples" in one_line_error(capsys, tmp_path, csv_text(t, x, f))


def test_nan_is_caught(capsys, tmp_path):
    t, x, f = good_sine()
    f[17] = np.nan
    message = one_line_error(capsys, tmp_path, csv_text(t, x, f))
    assert "line 19" in message and "force" in message and "not finite" in message


def test_time_going_back_is_caught(capsys, tmp_path):
    t, x, f = good_sine()
    t[100] = t[98]
    message = one_line_error(capsys, tmp_path, csv_text(t, x, f))
    assert "time does not increase at line 102" in message


def test_the_damper_is_refused(capsys, tmp_path):
    t, x, f = good_sine()
    path = tmp_path / "data.csv"
    path.write_text(csv_text(t, x, f))
    with pytest.raises(SystemExit):
        cli.main(["fit", "--component", "RotaryDamper", "--out", str(tmp_path / "p.json"),
                  str(path)])
    assert "rubber component" in capsys.readouterr().err


def test_rig_table_in_n_per_mm_is_caught(capsys, tmp_path):
    rows = "\n".join(f"0.0003,0.0001,{f},{60000.0},{10.0}" for f in (0.1, 1.0, 10.0))
    message = one_line_error(capsys, tmp_path, "preload,amplitude,frequency,dynamic_stiffness,"
                             f"loss_angle_deg\n{rows}\n")
    assert "dynamic_stiffness" in message and "give N/m" in message


# --- the rig-table format ---------------------------------------------------------------

def test_a_rig_table_point_is_the_reference_steady_state():
    """The fit's simulation of a table row against the reference solver's steady sine."""
    from fmu_components.lab.fit import rig_point
    from fmu_components.lab.history import native_history

    for preload, amplitude, frequency in ((0.3 * MM, 0.05 * MM, 0.5), (0.1 * MM, 0.2 * MM, 10.0)):
        *_, stiffness, loss = steady_reference_row(preload, amplitude, frequency)
        ours = rig_point(native_history(COMPONENT), TRUTH, preload, amplitude, frequency)
        assert ours[0] == pytest.approx(stiffness, rel=2e-4)
        assert ours[1] == pytest.approx(loss, abs=0.01)


def steady_reference_row(preload, amplitude, frequency, cycles=10, per_cycle=200):
    """|K*| and loss angle of the reference solution's last cycle (independent of the FMUs)."""
    from fmu_components.lab.harmonics import first_harmonic

    times = sine_times(frequency, cycles, per_cycle)
    history, force = synthetic.measure_path(COMPONENT, "row", times,
                                            sine_path(preload, amplitude, frequency), TRUTH, 0.0)
    result = first_harmonic(times, history.deflection, force, frequency, cycles=1)
    return preload, amplitude, frequency, result.dynamic_stiffness, result.loss_angle_deg


def test_rig_table_round_trip(tmp_path):
    """|K*| and loss angle of four steady sines of the reference solution: k1, k3 and c3
    recovered from the thesis's values as the start, the others held at the truth."""
    from fmu_components.lab.fit import fit
    from fmu_components.lab.measured import RigTable, read_data
    from fmu_components.lab.history import component_definition

    rows = [steady_reference_row(0.3 * MM, amplitude, frequency)
            for amplitude in (0.05 * MM, 0.2 * MM) for frequency in (0.5, 5.0)]
    path = tmp_path / "table.csv"
    path.write_text("preload,amplitude,frequency,dynamic_stiffness,loss_angle_deg\n" + "".join(
        ",".join(repr(float(v)) for v in row) + "\n" for row in rows))
    table = read_data(path, component_definition(COMPONENT))
    assert isinstance(table, RigTable)
    free = ("k1", "k3", "c3")
    thesis = synthetic.scaled(COMPONENT, {})
    start = dict(TRUTH, **{name: thesis[name] for name in free})
    result = fit(COMPONENT, [table], fix=[n for n in TRUTH if n not in free], starts=2,
                 start_values=start)
    for name in free:
        assert result.values[name] == pytest.approx(TRUTH[name], rel=0.03), name


def test_fit_reads_what_simulate_writes_and_says_which_columns(native_fmus, tmp_path, capsys):
    """simulate names its columns as the FMU does (angle, torque); the fit takes them."""
    from fmu_components.lab.measured import read_data
    from fmu_components.lab.signals import input_table, sine, time_grid, write_csv

    t = time_grid(2.0, 2e-3)
    with open(tmp_path / "in.csv", "w") as f:
        write_csv(input_table("TrackBushTorsion", t, sine(t, 0.17, 0.08, 1.0)), f)
    assert cli.main(["simulate", str(native_fmus["TrackBushTorsion"]), str(tmp_path / "in.csv"),
                     "--out", str(tmp_path / "torsion.csv")]) == 0
    history = read_data(tmp_path / "torsion.csv", component_definition("TrackBushTorsion"))
    assert history.columns == ("time", "angle", "torque")
    assert history.deflection == pytest.approx(sine(t, 0.17, 0.08, 1.0), abs=1e-12)
    capsys.readouterr()
    fixed = [n for n in component_definition("TrackBushTorsion").default_parameters()
             if n not in ("k1", "geometric.x_ref")]
    assert cli.main(["fit", "--component", "TrackBushTorsion", "--fix", *fixed, "--starts", "1",
                     "--jobs", "1", "--out", str(tmp_path / "p.json"),
                     str(tmp_path / "torsion.csv")]) == 0
    assert (f"{tmp_path / 'torsion.csv'}: deflection from column 'angle', load from column "
            f"'torque'") in capsys.readouterr().err
    fitted = json.loads((tmp_path / "p.json").read_text())
    assert fitted["k1"] == pytest.approx(component_definition("TrackBushTorsion")
                                         .default_parameters()["k1"], rel=1e-3)


def test_a_rig_table_is_read_with_the_old_header_and_the_new(tmp_path):
    """rig.csv's header says the units since ("preload [m]", ...); a table written before,
    with the bare names, reads the same."""
    from fmu_components.lab import rig
    from fmu_components.lab.measured import read_data

    definition = component_definition(COMPONENT)
    rows = [rig.RigRow(3e-4, a, f, k, d, 0.0, k, 0.0, 0.0, 5, True, 0.0)
            for a, f, k, d in ((2e-5, 1.0, 1.2e8, 8.0), (1e-4, 1.0, 1.0e8, 9.0),
                               (1e-4, 10.0, 1.1e8, 10.0))]
    new = rig.write_rows(rows, tmp_path / "new", COMPONENT)[0]
    assert new.read_text().startswith("preload [m],amplitude [m],frequency [Hz],"
                                      "dynamic_stiffness [N/m],loss_angle_deg,")
    old = tmp_path / "old.csv"
    old.write_text("\n".join([",".join(rig.CSV_COLUMNS)] + [
        ",".join(repr(float(getattr(r, c))) for c in rig.CSV_COLUMNS) for r in rows]) + "\n")
    tables = [read_data(path, definition) for path in (new, old)]
    assert np.array_equal(tables[0].rows, tables[1].rows)
    assert tables[0].rows[:, 3].tolist() == [1.2e8, 1.0e8, 1.1e8]


def test_fit_shows_its_progress_on_a_terminal(tmp_path):
    """A fit runs for a minute or more: on a terminal, stderr carries a progress bar of the
    simulations run (tqdm, as verify's); in a log (no terminal) it stays quiet."""
    import fcntl
    import os
    import pty
    import struct
    import subprocess
    import sys
    import termios

    from conftest import ROOT

    history, _ = measured("sine.csv", 0.3 * MM, 0.1 * MM, 1.0, 2, 0)
    data = synthetic.write_history(tmp_path / "sine.csv", history)
    command = [sys.executable, "-m", "fmu_components", "fit", "--component", COMPONENT,
               "--fix", *FIXED, "--starts", "2", "--jobs", "2", "--out", tmp_path / "p.json",
               data]
    environment = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    terminal, other_end = pty.openpty()
    # a terminal 100 columns wide (a new pseudo-terminal has none, and tqdm fits its width)
    fcntl.ioctl(other_end, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))
    process = subprocess.Popen(list(map(str, command)), cwd=ROOT, env=environment,
                               stdout=subprocess.PIPE, stderr=other_end)
    os.close(other_end)
    shown = b""
    while True:
        try:
            chunk = os.read(terminal, 4096)
        except OSError:  # the other end closed
            break
        if not chunk:
            break
        shown += chunk
    process.wait(timeout=600)
    os.close(terminal)
    assert process.returncode == 0, shown
    # the bar, its description and its count of the starts done (each start a task)
    assert b"fitting from 2 starts" in shown and b"2/2" in shown
    quiet = subprocess.run(list(map(str, command)), cwd=ROOT, env=environment,
                           capture_output=True, text=True, timeout=600)
    # in a log (no terminal) no bar is drawn: a plain line at every tenth done
    assert quiet.returncode == 0 and "\r" not in quiet.stderr
    assert "fitting from 2 starts: 2/2 done" in quiet.stderr


def test_an_unidentifiable_parameters_interval_is_unbounded_not_an_overflow():
    """A parameter the data barely touch has a standard deviation of thousands in its
    scaled form: the ends of its 95 % interval lie beyond the floats, and the interval is
    reported as unbounded (inf), where math.exp and math.sinh raised OverflowError."""
    from fmu_components.lab.fit import FitResult, Scaling

    free = [Scaling("k1", "log", 1e6, -4.6, 4.6), Scaling("k2", "log", 2e6, -4.6, 4.6),
            Scaling("elastic.a1", "symlog", 10.0, -11.0, 11.0)]
    rows = 20
    alternating = np.resize([1.0, -1.0], rows)
    # k1 well determined; k2 and a1 moved 1e-6 as far by the data: s.d. about 2e4 in u
    jacobian = np.column_stack([np.ones(rows), 1e-6 * alternating,
                                1e-6 * alternating * np.resize([1.0, 1.0, -1.0, -1.0], rows)])
    result = FitResult("TrackBushRadial", "final", {}, free, np.array([0.0, 0.1, 0.2]),
                       jacobian, np.full(rows, 0.1), [], [], 0.0,
                       {"k1": 1e6, "k2": 2e6, "elastic.a1": 1.0})
    confidence = result.confidence()
    low, high, relative = confidence["k1"]
    assert 0 < low < 1e6 < high < math.inf and relative < 0.5
    assert confidence["k2"] == (0.0, math.inf, math.inf)
    assert confidence["elastic.a1"] == (-math.inf, math.inf, math.inf)
    notes = result.warnings()
    assert any(n.startswith("k2 is not identifiable") and "interval is unbounded" in n
               for n in notes), notes
    assert any(n.startswith("elastic.a1 is not told apart from 0") and "-inf .. inf" in n
               for n in notes), notes
    assert not any(n.startswith("k1 ") for n in notes), notes
