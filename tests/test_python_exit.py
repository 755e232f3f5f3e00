"""The Python flavour leaves a process cleanly: a host that loads, steps and frees the Python
tyre and exits gets no invalid read or write in the FMU's libraries under valgrind's memcheck.

pythonfmu 0.7.0's library destroys its interpreter keeper among the exit handlers and then,
from its unload hook, assigns to the destroyed pointer; the guard orders the two
(guard/python_engine.c, finalize_engine_first). Both kinds of host are run: fmpy, which
unloads the guard in fmi2FreeInstance, and a C host, which does not and whose interpreter
the engine started."""

import shutil
import subprocess
import sys

import fmpy
import pytest

from test_c_host import c_host, clean_environment, host_command, unzip  # noqa: F401

pytestmark = pytest.mark.skipif(shutil.which("valgrind") is None, reason="needs valgrind")

NAME = "RoadWheelTyre"
# Python under valgrind is slow: the host does the least that makes an instance, steps it
# and frees it.
PYTHON_HOST = """
import sys
from fmpy.fmi2 import FMU2Slave
folder, guid, name, deflection, rate, force = sys.argv[1:7]
fmu = FMU2Slave(guid=guid, unzipDirectory=folder, modelIdentifier=name, instanceName="exit")
inputs = [int(deflection), int(rate)]
fmu.instantiate()
fmu.setupExperiment(startTime=0.0)
fmu.enterInitializationMode()
fmu.setReal(inputs, [0.002, 0.0])
fmu.exitInitializationMode()
for i in range(3):
    fmu.setReal(inputs, [0.002 + 1e-4 * i, 0.1])
    fmu.doStep(i * 1e-3, 1e-3)
print(fmu.getReal([int(force)])[0])
fmu.terminate()
fmu.freeInstance()
"""


def invalid_accesses(log, folder):
    """valgrind's reports of an invalid read or write with a frame in the FMU's binaries."""
    binaries = str(folder / "binaries")
    reports, current = [], []
    for line in log.splitlines():
        text = line.split("== ", 1)[-1] if line.startswith("==") else line
        if text.startswith(("Invalid read", "Invalid write")):
            current = [text]
            reports.append(current)
        elif current and text.strip():
            current.append(text)
        else:
            current = []
    return ["\n".join(report) for report in reports if any(binaries in l for l in report)]


def memcheck(command, tmp_path, env=None):
    log = tmp_path / "memcheck.txt"
    run = subprocess.run(["valgrind", "--tool=memcheck", "--undef-value-errors=no",
                          f"--log-file={log}", *command],
                         capture_output=True, text=True, env=env, timeout=900)
    return run, log.read_text()


def test_a_python_host_exits_without_touching_freed_memory(python_fmus, tmp_path):
    folder = unzip(python_fmus[NAME], tmp_path / "fmu")
    description = fmpy.read_model_description(str(python_fmus[NAME]))
    vr = {v.name: str(v.valueReference) for v in description.modelVariables}
    run, log = memcheck([sys.executable, "-c", PYTHON_HOST, str(folder), description.guid,
                         NAME, vr["compression"], vr["compression_rate"], vr["force"]],
                        tmp_path)
    assert run.returncode == 0, run.stderr[-2000:]
    assert float(run.stdout.split()[-1]) > 0  # the tyre was compressed: it pushes back
    assert "ERROR SUMMARY" in log
    assert invalid_accesses(log, folder) == []


def test_a_c_host_exits_without_touching_freed_memory(python_fmus, c_host, tmp_path):
    folder = unzip(python_fmus[NAME], tmp_path / "fmu")
    command = host_command(c_host, python_fmus[NAME], folder, NAME, stop=0.003)
    run, log = memcheck(command, tmp_path, clean_environment())
    assert run.returncode == 0, run.stderr[-2000:]
    assert len(run.stdout.splitlines()) == 3
    assert "ERROR SUMMARY" in log
    assert invalid_accesses(log, folder) == []
