"""A second, independent importer: libcosim (the Open Simulation Platform's engine, through
libcosimpy) runs every FMU and agrees with fmpy on the same input."""

import math

import numpy as np
import pytest

from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import thesis_sine

from conftest import FMU_NAMES, default_parameters, peak_to_peak
from fmu_runner import FmuRunner

libcosimpy = pytest.importorskip("libcosimpy")
from libcosimpy.CosimExecution import CosimExecution  # noqa: E402
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level  # noqa: E402
from libcosimpy.CosimManipulator import CosimManipulator  # noqa: E402
from libcosimpy.CosimObserver import CosimObserver  # noqa: E402
from libcosimpy.CosimSlave import CosimLocalSlave  # noqa: E402

NANOSECONDS = 1_000_000_000  # libcosim counts time in integer nanoseconds


def run_in_libcosim(path, name, deflection, rate, step):
    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_step_size(step_size=round(step * NANOSECONDS))
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(path), instance_name=name))
    references = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
    inputs = [references[v.name] for v in COMPONENTS[name].inputs]
    outputs = [references[v.name] for v in COMPONENTS[name].outputs]
    override = CosimManipulator.create_override()
    execution.add_manipulator(override)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    for reference, value in zip(inputs, (deflection[0], rate[0])):
        execution.real_initial_value(index, reference, value)
    results = []
    for k in range(len(deflection) - 1):
        override.slave_real_values(index, inputs, [deflection[k], rate[k]])
        assert execution.step(), f"libcosim step {k} failed"
        results.append(observer.last_real_values(index, outputs))
    return np.array(results)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_libcosim_agrees_with_fmpy(built_fmus, name):
    step = 1e-3
    t, x, v = thesis_sine(name, 2.0, step)
    cosim = run_in_libcosim(built_fmus[name], name, x, v, step)
    runner = FmuRunner(built_fmus[name])
    runner.initialize(x[0], v[0])
    fmpy_result = runner.run(x, v, step)
    runner.free()
    # The geometric multiplier f = 1 + h|x - x_ref| has a kink, so dF/dx jumps there. A
    # sample that lands on it (the torsion sine crosses its 10 deg mean exactly) falls on
    # either side by round-off: libcosim derives the step size from integer nanoseconds,
    # one ulp away from fmpy's. Away from the kink everything must agree.
    x_ref = default_parameters(name).get("geometric.x_ref", math.inf)
    away_from_kink = np.abs(x[1:] - x_ref) > 1e-9
    for column, output in enumerate(COMPONENTS[name].outputs):
        rows = away_from_kink if output.name == "stiffness" else slice(None)
        scale = peak_to_peak(fmpy_result[:, column]) or 1.0
        difference = np.max(np.abs(cosim[rows, column] - fmpy_result[rows, column])) / scale
        # The requirement is 0.1 %; the same arithmetic on the same input agrees to
        # round-off, and a difference at the tolerance level means a host's step sizes
        # (integer nanoseconds) changed the integrator's decisions.
        assert difference <= 1e-9, (output.name, difference)
    assert away_from_kink.sum() >= len(away_from_kink) - 4
