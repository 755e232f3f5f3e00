"""An independent FMI 3.0 importer: fmusim, the Reference-FMUs' command-line host (tag
v0.0.39, the last with fmusim; docs/fmi3.md says how it is built here). It runs the FMI 3.0
FMUs from the command line in Co-Simulation and in Model Exchange on its own CVode.

fmusim is not on any package registry, so these tests run where it is on PATH (or named by
$FMUSIM) and are skipped elsewhere.

* Co-Simulation: on a verification case's input file, fmusim gives fmpy's outputs within
  1e-12 of each output's range (the inputs it sets are the same samples).
* Model Exchange: fmusim runs the tyre through lift-off and touch-down with no force out of
  contact. Its accuracy is not judged here: fmusim applies inputs at communication points and in its
  root function, not in its right-hand side, so its CVode runs on held inputs between
  them and its errors on a time-varying input are that host's (docs/fmi3.md gives the
  figures). tests/test_model_exchange.py judges Model Exchange on a host that sets the
  inputs at every evaluation.
"""

import math
import os
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.verification import cases

FMUSIM = os.environ.get("FMUSIM") or shutil.which("fmusim")
pytestmark = pytest.mark.skipif(FMUSIM is None, reason="fmusim is not on PATH (docs/fmi3.md)")


@pytest.fixture(scope="module")
def fmi3(all_fmus):
    return all_fmus["fmi3"]


def sinusoidal_case(name):
    """The component's first verification case with a smooth input (no step, no sweep)."""
    smooth = [c for c in cases.CASES if c.fmu == name and c.test not in ("IV", "sweep")]
    return next((c for c in smooth if c.test == "II"), smooth[0])


def fmusim(path, interface, stop, interval, input_file, output_file, *extra):
    completed = subprocess.run(
        [FMUSIM, "--interface-type", interface, "--stop-time", repr(stop),
         "--output-interval", repr(interval), "--input-file", str(input_file),
         "--output-file", str(output_file), *extra, str(path)],
        capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stdout + completed.stderr
    result = np.genfromtxt(output_file, delimiter=",", names=True)
    _, first = np.unique(result["time"], return_index=True)  # rows repeated at events
    return result[first]


def write_input(path, times, x, v, name):
    inputs = [variable.name for variable in COMPONENTS[name].inputs]
    header = ",".join(f'"{column}"' for column in ["time", *inputs])
    np.savetxt(path, np.c_[times, x, v], delimiter=",", header=header, comments="",
               fmt="%.17g")


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
