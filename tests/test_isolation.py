"""Instances are independent (spec section 8): two builds of one Python-flavour FMU in one
process each run their own code, neither runs the host's `fmu_components` or pythonfmu, and
making instances leaves the host's sys.path as it was; a copy whose Python was edited after
the build is refused, since it would share the build's module names."""

import ast
import math
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_components.export import build
from fmu_components.lab.signals import thesis_sine

from conftest import ROOT
from fmu_runner import ERROR, FmuRunner

NAME = "TrackBushTorsion"
SHIFT = 1e6  # N m: what the modified build adds to the first output

# Appended to the modified build's adapter: every output refresh adds SHIFT to the first
# output (value reference 2, after the two inputs).
SHIFTED_OUTPUT = f'''

_refresh_outputs_as_built = ComponentSlave._refresh_outputs


def _shifted_refresh_outputs(self):
    _refresh_outputs_as_built(self)
    self._values[2] += {SHIFT!r}


ComponentSlave._refresh_outputs = _shifted_refresh_outputs
'''


@pytest.fixture(scope="module")
def modified_build(tmp_path_factory):
    """The Python flavour of NAME built from a copy of the run-time code whose first output
    is SHIFT higher: a different build of the same FMU, same name, same model identifier."""
    work = tmp_path_factory.mktemp("modified")
    source = work / "fmu_components"
    shutil.copytree(ROOT / "src" / "fmu_components", source,
                    ignore=shutil.ignore_patterns("__pycache__"))
    with open(source / "runtime" / "adapter.py", "a") as adapter:
        adapter.write(SHIFTED_OUTPUT)
    patch = pytest.MonkeyPatch()
    patch.setattr(build, "SOURCE", source)
    try:
        return build.build([NAME], work / "fmus", flavours=("python",))["python"][NAME]
    finally:
        patch.undo()


def package_of(fmu):
    """The name of the run-time package an FMU carries in its resources."""
    with zipfile.ZipFile(fmu) as archive:
        return next(n.split("/")[1] for n in archive.namelist()
                    if n.startswith("resources/fmu_components_"))


def first_output(fmu):
    _, x, v = thesis_sine(NAME, 0.2, 1e-3)
    runner = FmuRunner(fmu)
    runner.initialize(x[0], v[0])
    outputs = runner.run(x, v, 1e-3)[:, 0]
    runner.free()
    return outputs


def test_two_builds_of_one_fmu_in_one_process_each_run_their_own_code(python_fmus, modified_build):
    assert package_of(python_fmus[NAME]) != package_of(modified_build)
    shipped = first_output(python_fmus[NAME])
    modified = first_output(modified_build)
    again = first_output(python_fmus[NAME])
    # Before each build had modules of its own, the second FMU loaded ran the first one's
    # code (or the host's fmu_components), and the shift never showed.
    np.testing.assert_allclose(modified - shipped, SHIFT, rtol=1e-9)
    assert np.array_equal(again, shipped)


def test_an_fmu_runs_its_own_copy_of_the_code_not_the_hosts(python_fmus):
    import pythonfmu

    import fmu_components.runtime.adapter as hosts_adapter  # the host has its own loaded

    first_output(python_fmus[NAME])
    package = package_of(python_fmus[NAME])
    adapter = sys.modules[f"{package}.runtime.adapter"]
    assert adapter is not hosts_adapter and adapter.__file__ != hosts_adapter.__file__
    assert adapter.Fmi2Slave is sys.modules[f"{package}.pythonfmu"].Fmi2Slave
    assert adapter.Fmi2Slave is not pythonfmu.Fmi2Slave


def test_making_instances_leaves_sys_path_as_it_was(python_fmus):
    path = python_fmus["RotaryDamper"]
    simulate_fmu(str(path), stop_time=0.01, output_interval=1e-3)  # the first loads the modules
    before = list(sys.path)
    for _ in range(5):  # each run extracts the FMU to a new folder: five new resource paths
        simulate_fmu(str(path), stop_time=0.01, output_interval=1e-3)
    assert sys.path == before


def test_a_copy_whose_python_was_edited_after_the_build_is_refused(python_fmus, tmp_path):
    """An edited copy keeps the build's module names: in a process that has loaded the
    unedited FMU it would run that FMU's code, not its own. The guard hashes the Python
    in the resources folder when an instance is made and refuses the copy, naming both
    hashes; the unedited FMU goes on working."""
    shipped = first_output(python_fmus[NAME])
    edited = tmp_path / f"{NAME}.fmu"
    package = package_of(python_fmus[NAME])
    with zipfile.ZipFile(python_fmus[NAME]) as source, zipfile.ZipFile(edited, "w") as target:
        for item in source.infolist():
            content = source.read(item)
            if item.filename == f"resources/{package}/runtime/adapter.py":
                content += SHIFTED_OUTPUT.encode()
            target.writestr(item, content)
    runner = FmuRunner.__new__(FmuRunner)
    with pytest.raises(Exception):
        runner.__init__(edited)
    errors = [text for status, text in runner.messages if status == ERROR]
    assert len(errors) == 1 and errors[0].startswith("fmi2Instantiate: the Python in file:")
    assert "not to " in errors[0] and "Build the FMU again" in errors[0]
    assert np.array_equal(first_output(python_fmus[NAME]), shipped)



# A host thread with a small stack makes an instance (fmpy in a thread of the given stack
# size) and prints the first output after one step.
SMALL_STACK_HOST = """
import sys, threading
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
folder, stack = sys.argv[1], int(sys.argv[2])
description = read_model_description(folder)
forces = []
def run():
    fmu = FMU2Slave(guid=description.guid, unzipDirectory=folder, instanceName="small",
                    modelIdentifier=description.coSimulation.modelIdentifier)
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)
    forces.append(fmu.getReal([2])[0])
    fmu.freeInstance()
threading.stack_size(stack)
thread = threading.Thread(target=run)
thread.start()
thread.join()
print(forces)
"""


def test_the_content_hash_runs_on_a_small_thread_stack(python_fmus, tmp_path):
    """The guard hashes the resources folder inside fmi2Instantiate, on the host's thread:
    a folder nested eight deep (no Python in it, so the hash is the build's) on a 256 KiB
    thread stack must not overflow it, as a walk that recursed with 32 KiB of buffers per
    folder did."""
    folder = tmp_path / NAME
    with zipfile.ZipFile(python_fmus[NAME]) as archive:
        archive.extractall(folder)
    (folder / "resources" / "a" / "b" / "c" / "d" / "e" / "f" / "g" / "h").mkdir(parents=True)
    run = subprocess.run([sys.executable, "-c", SMALL_STACK_HOST, str(folder), str(256 * 1024)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    forces = ast.literal_eval(run.stdout.strip())
    assert len(forces) == 1 and math.isfinite(forces[0])  # the thread made its step
