"""Two more independent hosts, each on every FMU of both flavours:

- ecos (the Ecos co-simulation engine, PyPI `ecospy`) runs the thesis sine at a fixed 1 ms
  step and agrees with fmpy (FmuRunner) on the same input;
- fmu-manipulation-toolbox's `fmutool -input X.fmu -check` (XSD validation of the
  modelDescription.xml plus the FMI rules the schema cannot express) reports no error.

ecos's Python API: EcosSimulationStructure.add_model(instance, path) and
EcosSimulation(structure=..., step_size=h); set_real/get_real("instance::variable"),
init(), step() -> new time, terminate(). A set_real only stores the value: ecos applies it
with fmi2SetReal in init() (inside initialisation mode) and right before every fmi2DoStep
(fixed_step_algorithm: apply_sets, doStep(t, h), apply_gets), and reads the outputs back after
the step, so a value set before step() is the input at t, as the FMUs expect. Its time
advances as t += h in doubles, like FmuRunner's, so both hosts pass the same communication
points and the same arithmetic gives the same numbers.
"""

import re
import subprocess
import sys
import zipfile

import numpy as np
import pytest

from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import thesis_sine

from conftest import FMU_NAMES, peak_to_peak
from fmu_runner import FmuRunner

STEP = 1e-3
STOP_TIME = 2.0
TOLERANCE = 1e-9  # of each output's peak-to-peak: the same arithmetic agrees to round-off


def import_ecospy():
    """ecospy, or a skip saying what is missing (it loads libecosc.so, which needs TBB)."""
    try:
        return pytest.importorskip(
            "ecospy", reason="ecospy (the ecos co-simulation engine) is not installed: "
                             "pip install 'fmu-components[test]'")
    except OSError as failure:
        pytest.skip(f"ecospy is installed but its native library does not load ({failure}); "
                    "on Debian/Ubuntu: apt-get install libtbb12")


def run_in_ecos(path, name, deflection, rate, step):
    """Outputs after each step, and the time ecos reports after it (the last sample is not
    stepped, as in FmuRunner.run)."""
    ecospy = import_ecospy()
    ecospy.EcosLib.set_log_level("warn")
    inputs = [f"{name}::{v.name}" for v in COMPONENTS[name].inputs]
    outputs = [f"{name}::{v.name}" for v in COMPONENTS[name].outputs]
    results, times = [], []
    with ecospy.EcosSimulationStructure() as structure:
        structure.add_model(name, str(path))
        with ecospy.EcosSimulation(structure=structure, step_size=step) as simulation:
            for identifier, value in zip(inputs, (deflection[0], rate[0])):
                simulation.set_real(identifier, float(value))
            assert simulation.init(), ecospy.EcosLib.get_last_error()
            for k in range(len(deflection) - 1):
                # Inputs at t_k, applied by ecos just before doStep(t_k, h).
                simulation.set_real(inputs[0], float(deflection[k]))
                simulation.set_real(inputs[1], float(rate[k]))
                times.append(simulation.step())
                results.append([simulation.get_real(identifier) for identifier in outputs])
            simulation.terminate()
    return np.array(results), np.array(times)


def run_in_fmpy(path, deflection, rate, step):
    runner = FmuRunner(path)
    runner.initialize(deflection[0], rate[0])
    try:
        return runner.run(deflection, rate, step)
    finally:
        runner.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_ecos_agrees_with_fmpy(built_fmus, name):
    import_ecospy()
    t, x, v = thesis_sine(name, STOP_TIME, STEP)
    ecos_result, ecos_times = run_in_ecos(built_fmus[name], name, x, v, STEP)
    fmpy_result = run_in_fmpy(built_fmus[name], x, v, STEP)
    assert ecos_result.shape == fmpy_result.shape
    np.testing.assert_allclose(ecos_times, t[1:], rtol=0, atol=1e-9)
    assert np.all(np.isfinite(ecos_result))
    for column, output in enumerate(COMPONENTS[name].outputs):
        scale = peak_to_peak(fmpy_result[:, column]) or 1.0
        difference = np.max(np.abs(ecos_result[:, column] - fmpy_result[:, column])) / scale
        assert difference <= TOLERANCE, (built_fmus.flavour, output.name, difference)


# ------------------------------------------------------------------ fmutool -check

ANSI = re.compile(r"\x1b\[[0-9;]*m")


def fmutool_check(path):
    """(exit code, output lines) of `fmutool -input path -check`. fmutool logs to stdout
    as 'LEVEL    | message'; each violation is an ERROR line and makes it exit with 7
    (ExitCode.CHECK_FAILED) after '-check: N error(s) found.'; an unreadable input is a
    CRITICAL line and exit code 3 or 4."""
    pytest.importorskip("fmu_manipulation_toolbox",
                        reason="fmu-manipulation-toolbox is not installed: "
                               "pip install 'fmu-components[test]'")
    # `python -m fmu_manipulation_toolbox <arguments>` is the fmutool command line (with no
    # arguments it would start the GUI); run in this interpreter, whatever its PATH.
    completed = subprocess.run(
        [sys.executable, "-m", "fmu_manipulation_toolbox", "-input", str(path), "-check"],
        capture_output=True, text=True, timeout=120)
    lines = ANSI.sub("", completed.stdout + completed.stderr).splitlines()
    return completed.returncode, lines


def problems(lines):
    return [line for line in lines if line.split("|")[0].strip() in ("WARNING", "ERROR", "CRITICAL")
            or "Traceback" in line]


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmutool_check_reports_no_error(built_fmus, name):
    returncode, lines = fmutool_check(built_fmus[name])
    output = "\n".join(lines)
    assert returncode == 0, output
    assert not problems(lines), output
    # Both checkers ran and passed.
    assert "This FMU seems to be compliant with FMI-2.0." in output, output
    assert "No semantic error against the FMI-2 standard." in output, output


def test_fmutool_check_catches_a_broken_description(native_fmus, tmp_path):
    """The check is not vacuous: a copy whose inputs carry initial="exact" (not allowed
    for a continuous input in FMI 2.0) and whose root has an unknown attribute fails it."""
    source = native_fmus[FMU_NAMES[0]]
    broken = tmp_path / "broken.fmu"
    with zipfile.ZipFile(source) as original, zipfile.ZipFile(broken, "w",
                                                              zipfile.ZIP_DEFLATED) as copy:
        for item in original.infolist():
            data = original.read(item.filename)
            if item.filename == "modelDescription.xml":
                text = data.decode("utf-8")
                text = text.replace('causality="input"', 'causality="input" initial="exact"')
                text = text.replace("<fmiModelDescription", '<fmiModelDescription bogus="1"', 1)
                data = text.encode("utf-8")
            copy.writestr(item, data)
    returncode, lines = fmutool_check(broken)
    output = "\n".join(lines)
    assert returncode == 7, output
    errors = [line for line in lines if line.startswith("ERROR")]
    assert any("initial must not be set with causality='input'" in line for line in errors), output
    assert any("'bogus' attribute not allowed" in line for line in errors), output
    assert "This FMU does not validate with FMI standard." in output, output
