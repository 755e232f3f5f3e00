"""The command-line tool's mistakes come out as one line that says what to do, no traceback."""

import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import ROOT


def run(arguments, env=None, python_options=()):
    environment = {**os.environ, "PYTHONPATH": str(ROOT / "src"), **(env or {})}
    return subprocess.run([sys.executable, *python_options, *arguments], cwd=ROOT, env=environment,
                          capture_output=True, text=True, timeout=120)


def one_line_error(result, *words):
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1, result.stderr
    for word in words:
        assert word in lines[0], lines[0]
    return lines[0]


def test_build_script_outside_the_environment_says_how_to_create_it():
    # -S: no site-packages, so neither the project nor pythonfmu can be imported
    result = run(["build_fmus.py"], env={"PYTHONPATH": ""}, python_options=["-S"])
    one_line_error(result, "venv", "pip install -e", "build_fmus.py")


def test_build_without_gcc_says_to_install_it(tmp_path):
    result = run(["-m", "fmu_components", "build", "--no-run", "--dest", str(tmp_path)],
                 env={"PATH": str(tmp_path)})
    one_line_error(result, "gcc", "apt-get install gcc")
    assert not list(tmp_path.glob("*.fmu"))


@pytest.mark.parametrize("fmu, mean, amplitude, meant", [
    ("RoadWheelTyre", "3.5", "1", "mm"),         # mm typed where m are expected
    ("TrackBushRadial", "0.3", "0.1", "mm"),
    ("TrackBushTorsion", "10", "5", "deg"),      # deg typed where rad are expected
    ("RotaryDamper", "0", "12", "deg"),
])
def test_signal_in_the_wrong_unit_is_refused(fmu, mean, amplitude, meant):
    result = run(["-m", "fmu_components", "signal", fmu, "sine", "--mean", mean,
                  "--amplitude", amplitude])
    one_line_error(result, f"looks like {meant}")
    assert result.stdout == ""


@pytest.mark.parametrize("fmu, mean, amplitude", [
    ("RoadWheelTyre", "3.5e-3", "1e-3"), ("TrackBushRadial", "0.3e-3", "0.1e-3"),
    ("TrackBushTorsion", "0.1745", "0.0873"), ("RotaryDamper", "0", "0.21")])
def test_signal_in_si_units_is_written(fmu, mean, amplitude):
    result = run(["-m", "fmu_components", "signal", fmu, "sine", "--mean", mean,
                  "--amplitude", amplitude, "--stop-time", "0.01"])
    assert result.returncode == 0, result.stderr
    assert len(result.stdout.splitlines()) == 12  # header and 11 samples


@pytest.mark.parametrize("options, words", [
    (["--step", "0"], ["--step"]),
    (["--frequency", "-1"], ["--frequency"]),
])
def test_signal_timing_mistakes_are_one_line(options, words):
    result = run(["-m", "fmu_components", "signal", "RoadWheelTyre", "sine", "--mean", "3.5e-3",
                  "--amplitude", "1e-3", *options])
    one_line_error(result, *words)


def test_verify_before_building_says_to_build(tmp_path):
    result = run(["-m", "fmu_components", "verify", "--fmu", "RotaryDamper", "--fmus",
                  str(tmp_path), "--report", str(tmp_path / "report")])
    one_line_error(result, "fmu-components build")


def test_verify_with_no_matching_case_says_where_the_names_are(tmp_path):
    result = run(["-m", "fmu_components", "verify", "--case", "no_such_case", "--fmus",
                  str(tmp_path), "--report", str(tmp_path / "report")])
    one_line_error(result, "reference_data")


@pytest.mark.parametrize("fmu, mean, amplitude", [
    ("RotaryDamper", "0", "2"),        # +-2 deg typed as rad: under 10 times the range
    ("TrackBushTorsion", "0", "0.8"),  # 0.8 deg typed as rad: past the 33 deg measured
])
def test_a_small_angle_that_may_be_in_deg_is_warned_about(fmu, mean, amplitude):
    result = run(["-m", "fmu_components", "signal", fmu, "sine", "--mean", mean,
                  "--amplitude", amplitude, "--stop-time", "1"])
    assert result.returncode == 0
    assert "warning:" in result.stderr and "if the values are in deg" in result.stderr
    assert "divide by 57.2958" in result.stderr


# --- Ctrl-C: "interrupted", exit status 130, nothing half written -------------------------

def interrupt(arguments, after, tmp_path):
    """Run `fmu-components ARGUMENTS`, send SIGINT (Ctrl-C) `after` seconds in, and return the
    CompletedProcess-like (returncode, stdout, stderr). The process must end within 60 s
    of the signal (worker processes included)."""
    environment = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    process = subprocess.Popen([sys.executable, "-m", "fmu_components", *map(str, arguments)],
                               cwd=ROOT, env=environment, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)
    time.sleep(after)
    assert process.poll() is None, "it ended before it could be interrupted"
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=60)
    return process.returncode, out, err


def assert_interrupted(status, err):
    assert status == 130, err
    assert "Traceback" not in err, err
    assert err.strip().splitlines()[-1] == "fmu-components: interrupted"


def test_ctrl_c_during_simulate(tmp_path, all_fmus):
    from fmu_components.lab.signals import input_table, sine, time_grid, write_csv

    t = time_grid(60.0, 1e-3)
    with open(tmp_path / "in.csv", "w") as f:
        write_csv(input_table("RoadWheelTyre", t, sine(t, 3.5e-3, 1e-3, 1.0)), f)
    out = tmp_path / "out.csv"
    status, _, err = interrupt(["simulate", all_fmus["native"]["RoadWheelTyre"],
                                tmp_path / "in.csv", "--out", out, "--step", "1e-4"], 8, tmp_path)
    assert_interrupted(status, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.csv"]  # no partial result


def test_ctrl_c_during_verify(tmp_path, all_fmus):
    report = tmp_path / "report"
    # every component's cases, on the local cluster: 24 s on this machine when idle (the
    # tyre's alone less), so the signal comes at 8 s, within them on a machine three
    # times as fast, past the cluster's start
    status, _, err = interrupt(["verify", "--fmus", all_fmus["native"]["RoadWheelTyre"].parent,
                                "--report", report], 8, tmp_path)
    assert_interrupted(status, err)
    assert not (report / "summary.md").exists()


def test_ctrl_c_during_fit_ends_its_workers_too(tmp_path):
    # 200 cycles sampled every 1 ms: each simulation of the fit reads 200,000 samples, and a
    # fit from four starts takes minutes
    t = np.arange(200_001) * 1e-3
    x = 2e-4 + 1e-4 * np.sin(2 * np.pi * t)
    data = tmp_path / "sine.csv"
    np.savetxt(data, np.column_stack([t, x, 81.8e6 * x]), delimiter=",", fmt="%.17g",
               header="time,deflection,force", comments="")
    out = tmp_path / "fitted.json"
    started = time.perf_counter()
    status, _, err = interrupt(["fit", "--component", "TrackBushRadial", "--starts", "4",
                                "--jobs", "2", "--out", out, data], 10, tmp_path)
    assert_interrupted(status, err)
    assert not out.exists() and not list(tmp_path.glob("*.part*"))
    # the workers were stopped, not waited for
    assert time.perf_counter() - started < 40
