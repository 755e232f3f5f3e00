"""An independent FMI 3.0 importer: fmusim, the Reference-FMUs' command-line host (tag
v0.0.39, the last with fmusim; docs/fmi3.md says how it is built here). It runs the FMI 3.0
FMUs from the command line in Co-Simulation and in Model Exchange on its own CVode.

fmusim is not on any package registry, so the tests that run it run where it is on PATH (or
named by $FMUSIM) and are skipped elsewhere.

* Co-Simulation: on a verification case's input file, fmusim gives fmpy's outputs within
  1e-12 of each output's range (the inputs it sets are the same samples).
* Model Exchange: fmusim runs the tyre through lift-off and touch-down with no force out of
  contact. Its accuracy is not judged here: fmusim applies inputs at communication points and in its
  root function, not in its right-hand side, so its CVode runs on held inputs between
  them and its errors on a time-varying input are that host's (docs/fmi3.md gives the
  figures). tests/test_model_exchange.py judges Model Exchange on a host that sets the
  inputs at every evaluation.
* Early return and event mode: the tyre's lift-off sine through fmusim's
  --early-return-allowed and --event-mode-used, and through tests/fmusim_host.py, a host
  that does what fmusim does there (it runs everywhere).
"""

import math
import os
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_components.lab.signals import input_table, sine, time_grid, write_csv
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.verification import cases

import fmusim_host

FMUSIM = os.environ.get("FMUSIM") or shutil.which("fmusim")
needs_fmusim = pytest.mark.skipif(FMUSIM is None, reason="fmusim is not on PATH (docs/fmi3.md)")


@pytest.fixture(scope="module")
def fmi3(all_fmus):
    return all_fmus["fmi3"]


def sinusoidal_case(name):
    """The component's first verification case with a smooth input (no step, no sweep)."""
    smooth = [c for c in cases.CASES if c.fmu == name and c.test not in ("IV", "sweep")]
    return next((c for c in smooth if c.test == "II"), smooth[0])


def fmusim(path, interface, stop, interval, input_file, output_file, *extra, timeout=300,
           every_row=False):
    try:
        completed = subprocess.run(
            [FMUSIM, "--interface-type", interface, "--stop-time", repr(stop),
             "--output-interval", repr(interval), "--input-file", str(input_file),
             "--output-file", str(output_file), *extra, str(path)],
            capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        pytest.fail(f"fmusim {' '.join(extra)} did not finish within {timeout} s")
    assert completed.returncode == 0, completed.stdout + completed.stderr
    result = np.genfromtxt(output_file, delimiter=",", names=True)
    if every_row:
        return result
    _, first = np.unique(result["time"], return_index=True)  # rows repeated at events
    return result[first]


def write_input(path, times, x, v, name):
    inputs = [variable.name for variable in COMPONENTS[name].inputs]
    header = ",".join(f'"{column}"' for column in ["time", *inputs])
    np.savetxt(path, np.c_[times, x, v], delimiter=",", header=header, comments="",
               fmt="%.17g")


@needs_fmusim
@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_fmusim_co_simulation_gives_fmpys_outputs(fmi3, tmp_path, name):
    case = sinusoidal_case(name)
    stop, step = 1.0, case.step
    signal = case.inputs()
    signal = signal[signal["time"] <= stop + 1e-12]
    input_file = tmp_path / "in.csv"
    write_input(input_file, signal["time"], *(signal[v.name] for v in COMPONENTS[name].inputs),
                name)
    theirs = fmusim(fmi3[name], "cs", stop, step, input_file, tmp_path / "out.csv")
    ours = simulate_fmu(str(fmi3[name]), stop_time=stop, output_interval=step, input=signal)
    assert len(theirs) == len(ours)
    for output in COMPONENTS[name].outputs:
        scale = np.ptp(ours[output.name]) or 1.0
        assert np.isfinite(theirs[output.name]).all()
        assert np.max(np.abs(theirs[output.name] - ours[output.name])) <= 1e-12 * scale, output


@needs_fmusim
def test_fmusim_model_exchange_runs_the_tyre_through_its_contact_events(fmi3, tmp_path):
    """Lift-off and touch-down through fmusim's event handling: no failed call, and no force
    out of contact."""
    stop, sampling = 2.0, 1e-4
    fine = np.arange(0.0, stop + sampling / 2, sampling)
    x = 0.5e-3 + 1.5e-3 * np.sin(2 * math.pi * fine)
    v = 1.5e-3 * 2 * math.pi * np.cos(2 * math.pi * fine)
    input_file = tmp_path / "in.csv"
    write_input(input_file, fine, x, v, "RoadWheelTyre")
    theirs = fmusim(fmi3["RoadWheelTyre"], "me", stop, 2e-3, input_file, tmp_path / "out.csv",
                    "--solver", "cvode", "--tolerance", "1e-6")
    out_of_contact = np.interp(theirs["time"], fine, x) < 0
    assert out_of_contact.sum() > 100 and (~out_of_contact).sum() > 100
    assert np.all(theirs["force"][out_of_contact] == 0.0)
    assert np.isfinite(theirs["force"]).all() and theirs["force"].max() > 0


# --- early return and event mode: the tyre lifts off and lands twice -------------------------

STOP = 2.0
OPTIONS = {"early-return": (True, False), "event-mode": (False, True), "both": (True, True)}
FLAGS = {"early-return": ["--early-return-allowed"], "event-mode": ["--event-mode-used"],
         "both": ["--early-return-allowed", "--event-mode-used"]}


def lift_off_sine(step):
    """Mean 0.5 mm, amplitude 1.5 mm, 1 Hz, sampled at the host's step with the secant rates
    (as `fmu-components signal` writes it): the held-rate path of each step is the
    straight line between its samples."""
    t = time_grid(STOP, step)
    return input_table("RoadWheelTyre", t, sine(t, 0.5e-3, 1.5e-3, 1.0))


def crossings(table):
    """Where the held-rate path of a step crosses x = 0: the early returns expected."""
    x, v, t = table["compression"], table["compression_rate"], table["time"]
    k = np.flatnonzero(np.sign(x[:-1]) != np.sign(x[1:]))
    return t[k] - x[k] / v[k]


def off_grid(rows, step):
    return rows[np.abs(rows["time"] / step - np.round(rows["time"] / step)) > 1e-6]


def on_grid(rows, step):
    rows = rows[np.abs(rows["time"] / step - np.round(rows["time"] / step)) <= 1e-6]
    _, first = np.unique(rows["time"], return_index=True)
    return rows[first]


def check_lift_off_run(rows, table, step, path, early_return, event_mode):
    """Events at the four crossings (a row each, repeated after Event Mode) and the forces
    of a run without early return or events: the plain run, or where the host sets the
    inputs again at an early return (early return without event mode), a plain host that
    ends its step at the crossing itself."""
    expected = crossings(table)
    assert len(expected) == 4
    returned = off_grid(rows, step)["time"]
    if early_return:
        repeats = 2 if event_mode else 1
        assert np.allclose(returned, np.repeat(expected, repeats), rtol=0, atol=1e-12), returned
    else:
        assert len(returned) == 0
    stops = expected if early_return and not event_mode else ()
    reference, _ = fmusim_host.run(path, table, STOP, step, stops=stops)
    force, plain = on_grid(rows, step)["force"], on_grid(reference, step)["force"]
    assert len(force) == len(plain) == round(STOP / step) + 1
    assert np.max(np.abs(force - plain)) <= 1e-9 * np.ptp(plain)
    out_of_contact = np.interp(on_grid(rows, step)["time"], table["time"],
                               table["compression"]) < 0
    assert out_of_contact.sum() > 0 and np.all(force[out_of_contact] == 0.0)


@pytest.mark.parametrize("step", [1e-3, 5e-3], ids=["1ms", "5ms"])
@pytest.mark.parametrize("option", sorted(OPTIONS))
def test_a_host_like_fmusim_finishes_the_lift_off_sine_with_events_at_the_crossings(
        fmi3, step, option):
    """tests/fmusim_host.py: the inputs set again (interpolated) at every early return's
    lastSuccessfulTime, Event Mode after initialization and at every early return; the
    doStep calls bounded, so that a run that makes no progress fails."""
    early_return, event_mode = OPTIONS[option]
    table = lift_off_sine(step)
    rows, returns = fmusim_host.run(fmi3["RoadWheelTyre"], table, STOP, step, early_return,
                                    event_mode)
    assert [event for _, event in returns] == [event_mode] * (4 if early_return else 0)
    check_lift_off_run(rows, table, step, fmi3["RoadWheelTyre"], early_return, event_mode)


@needs_fmusim
@pytest.mark.parametrize("step", [1e-3, 5e-3], ids=["1ms", "5ms"])
@pytest.mark.parametrize("option", sorted(OPTIONS))
def test_fmusim_finishes_the_lift_off_sine_with_events_at_the_crossings(fmi3, tmp_path, step,
                                                                        option):
    table = lift_off_sine(step)
    input_file = tmp_path / "in.csv"
    with open(input_file, "w") as file:
        write_csv(table, file)
    rows = fmusim(fmi3["RoadWheelTyre"], "cs", STOP, step, input_file, tmp_path / "out.csv",
                  *FLAGS[option], timeout=120, every_row=True)
    check_lift_off_run(rows, table, step, fmi3["RoadWheelTyre"], *OPTIONS[option])
