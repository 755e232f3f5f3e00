"""A host written in C (tests/c_host/fmu_host.c, built against the FMI 2.0 headers fmpy
ships) loads each FMU's linux64 binary without LD_PRELOAD and without a Python of its own,
runs a sine, and gets fmpy's results; bad calls come back as fmi2Error."""

import math
import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest

from fmu_components.runtime.catalog import COMPONENTS

from conftest import FMU_NAMES, ROOT, peak_to_peak
from fmu_components.lab.signals import THESIS_SINES
from fmu_runner import FmuRunner

pytestmark = pytest.mark.skipif(shutil.which("gcc") is None, reason="needs gcc")


@pytest.fixture(scope="module")
def c_host(tmp_path_factory):
    executable = tmp_path_factory.mktemp("c_host") / "fmu_host"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror",
                    f"-I{Path(fmpy.__file__).parent / 'c-code'}",
                    str(ROOT / "tests" / "c_host" / "fmu_host.c"), "-o", str(executable),
                    "-ldl", "-lm"], check=True)
    return executable


def clean_environment():
    """No preloaded libraries and no Python settings leaking in from the test process."""
    return {k: v for k, v in os.environ.items()
            if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}


def host_command(c_host, fmu, unzipped, name, binary=None, stop=0.5, step=1e-3, extra=()):
    description = fmpy.read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in description.modelVariables}
    definition = COMPONENTS[name]
    mean, amplitude, frequency = THESIS_SINES[name]
    binary = binary or unzipped / "binaries" / "linux64" / f"{name}.so"
    return [str(c_host), str(binary), (unzipped / "resources").as_uri(), description.guid,
            str(vr[definition.inputs[0].name]), str(vr[definition.inputs[1].name]),
            str(vr[definition.outputs[0].name]), repr(mean), repr(amplitude), repr(frequency),
            repr(step), repr(stop), *extra]


def unzip(fmu, directory):
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(directory)
    return directory


@pytest.mark.parametrize("name", FMU_NAMES)
def test_c_host_runs_the_fmu_and_matches_fmpy(built_fmus, c_host, tmp_path, name):
    unzipped = unzip(built_fmus[name], tmp_path)
    run = subprocess.run(host_command(c_host, built_fmus[name], unzipped, name),
                         capture_output=True, text=True, env=clean_environment(), timeout=120)
    assert run.returncode == 0, run.stderr
    rows = np.array([[float(v) for v in line.split(",")] for line in run.stdout.splitlines()])
    # The same input through fmpy: x = sine, rate = its derivative at the step start.
    mean, amplitude, frequency = THESIS_SINES[name]
    omega = 2 * math.pi * frequency
    runner = FmuRunner(built_fmus[name])
    runner.initialize(mean, amplitude * omega)
    expected = [runner.step(mean + amplitude * math.sin(omega * t), amplitude * omega * math.cos(omega * t),
                            1e-3)[0] for t in rows[:, 0] - 1e-3]
    runner.free()
    assert len(rows) == 500
    assert np.max(np.abs(rows[:, 1] - expected)) <= 1e-9 * peak_to_peak(expected)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_c_host_gets_fmi2error_for_bad_calls_and_continues(built_fmus, c_host, tmp_path, name):
    unzipped = unzip(built_fmus[name], tmp_path)
    good = subprocess.run(host_command(c_host, built_fmus[name], unzipped, name),
                          capture_output=True, text=True, env=clean_environment(), timeout=120)
    bad = subprocess.run(host_command(c_host, built_fmus[name], unzipped, name, extra=["bad-input"]),
                         capture_output=True, text=True, env=clean_environment(), timeout=120)
    assert bad.returncode == 0, bad.stderr  # the harness checks each status itself
    assert "is not a finite number" in bad.stderr and "must be positive" in bad.stderr
    assert bad.stdout == good.stdout  # the refused calls changed nothing


def test_pythonfmu_library_alone_does_not_load_in_a_c_host(python_fmus, c_host, tmp_path):
    """Why the Python FMUs carry the guard: pythonfmu's library leaves the Python C API
    undefined."""
    name = "TrackBushTorsion"
    unzipped = unzip(python_fmus[name], tmp_path)
    engine = unzipped / "binaries" / "linux64" / "libpythonfmu-export.so"
    run = subprocess.run(host_command(c_host, python_fmus[name], unzipped, name, binary=engine),
                         capture_output=True, text=True, env=clean_environment(), timeout=60)
    assert run.returncode != 0 and "undefined symbol" in run.stderr
