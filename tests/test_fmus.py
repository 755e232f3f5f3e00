"""The built FMUs through fmpy: conformance, simulation, step-size consistency, state,
passivity."""

import ast
import math
import sys
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.validation import validate_fmu

from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import THESIS_SINES, input_table, thesis_sine, time_grid

from conftest import FMU_NAMES, peak_to_peak
from fmu_runner import FmuRunner


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmu_passes_fmpy_validation(built_fmus, name):
    assert validate_fmu(str(built_fmus[name])) == []


@pytest.mark.parametrize("name", FMU_NAMES)
def test_every_variable_has_unit_description_and_thesis_start_value(built_fmus, name):
    description = read_model_description(str(built_fmus[name]))
    units = {u.name: [d.name for d in u.displayUnits] for u in description.unitDefinitions}
    definition = COMPONENTS[name]
    catalog = {v.name: v for v in definition.variables}
    reals = [v for v in description.modelVariables if v.type == "Real"]
    assert [v.name for v in reals] == list(catalog)
    # The Boolean parameters come after every Real variable, their value references too.
    switches = [v for v in description.modelVariables if v.type == "Boolean"]
    assert [(v.name, v.valueReference, v.causality, v.variability, v.start) for v in switches] == [
        (s.name, len(catalog) + i, "parameter", "fixed", "false")
        for i, s in enumerate(definition.switches)]
    assert len(reals) + len(switches) == len(description.modelVariables)
    assert all(v.description for v in switches)
    for variable in reals:
        expected = catalog[variable.name]
        assert variable.unit == expected.unit and variable.unit in units
        assert variable.description
        if expected.display_unit:
            assert variable.displayUnit in units[variable.unit]
        if variable.causality == "parameter":
            assert variable.variability == "fixed"
            assert float(variable.start) == expected.start
    assert description.defaultExperiment.tolerance is not None
    assert description.coSimulation.canGetAndSetFMUstate
    assert description.coSimulation.canSerializeFMUstate
    assert not description.coSimulation.canInterpolateInputs


# What each output and derivative reads, by the physics of spec sections 2 and 3, written
# out here independently of the equations the ModelStructure is read off.
RUBBER_STRUCTURE = {0: {"x", "s", "w", "r"}, 1: {"x"}, 2: {"x", "s", "w", "r"},
                    3: {"x", "v", "s", "w", "r"},  # the tangent takes the rate's direction
                    "der(state.s)": {"v", "s", "w"}, "der(state.w)": {"v", "s", "w"},
                    "der(state.r)": {"v", "r"}}
DAMPER_STRUCTURE = {0: {"x", "z"}, 1: {"x", "z"}, 2: {"omega_r"}, 3: {"omega_r"}, 4: {"x", "z"},
                    "der(state.z)": {"v", "z", "omega_r"}, "der(state.omega_r)": {"z", "omega_r"}}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_model_structure_declares_what_each_output_and_derivative_reads(built_fmus, name):
    description = read_model_description(str(built_fmus[name]))
    definition = COMPONENTS[name]
    short = {definition.inputs[0].name: "x", definition.inputs[1].name: "v",
             **{v.name: v.name.split(".")[1] for v in definition.states}}
    expected = DAMPER_STRUCTURE if name == "RotaryDamper" else RUBBER_STRUCTURE
    for unknown in list(description.outputs) + list(description.derivatives):
        variable = unknown.variable
        key = (variable.name if variable.name.startswith("der(")
               else [o.name for o in definition.outputs].index(variable.name))
        assert {short[d.name] for d in unknown.dependencies} == expected[key], variable.name
    assert [d.variable.name for d in description.derivatives] == [
        v.name for v in definition.derivatives]
    assert {u.variable.name for u in description.initialUnknowns} == {
        v.name for v in list(definition.outputs) + list(definition.states)
        + list(definition.derivatives)}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmu_resources_import_only_the_standard_library(python_fmus, name):
    with zipfile.ZipFile(python_fmus[name]) as archive:
        sources = [n for n in archive.namelist() if n.startswith("resources/") and n.endswith(".py")]
        # The FMU's own modules (its entry module and its package, which carries pythonfmu;
        # the adapter names the top-level pythonfmu only for the development tree, and
        # tests/test_isolation.py shows the FMU's own copy is the one used).
        own = {n.split("/")[1].removesuffix(".py") for n in sources}
        allowed = set(sys.stdlib_module_names) | own | {"pythonfmu"}
        assert any(n.endswith("runtime/integrator.py") for n in sources)
        for source in sources:
            tree = ast.parse(archive.read(source))
            for node in ast.walk(tree):
                if isinstance(node, ast.Import):
                    modules = [alias.name for alias in node.names]
                elif isinstance(node, ast.ImportFrom) and node.level == 0:
                    modules = [node.module]
                else:
                    continue
                for module in modules:
                    assert module.split(".")[0] in allowed, f"{source} imports {module}"


@pytest.mark.parametrize("name", FMU_NAMES)
def test_sine_simulation_gives_finite_outputs(built_fmus, name):
    t, x, _ = thesis_sine(name, 2.0, 1e-3)
    result = simulate_fmu(str(built_fmus[name]), stop_time=t[-1], output_interval=1e-3,
                          input=input_table(name, t, x))
    for output in COMPONENTS[name].outputs:
        assert np.all(np.isfinite(result[output.name])), output.name
    assert peak_to_peak(result[COMPONENTS[name].outputs[0].name]) > 0


@pytest.mark.parametrize("name", FMU_NAMES)
def test_results_at_steps_1e_4_1e_3_1e_2_agree_at_common_times(built_fmus, name):
    """Spec section 4: for the same input path, doStep(t, H) and n doSteps of H/n agree to
    the integrator's tolerance. The path is a sine sampled every 10 ms and straight between
    samples, so every step size sees the same deflection history."""
    coarse = 1e-2
    t_coarse, x_coarse, v_coarse = thesis_sine(name, 2.0, coarse)
    results = {}
    for h in (1e-4, 1e-3, 1e-2):
        t = time_grid(2.0, h)
        segment = np.minimum((t / coarse + 1e-9).astype(int), len(t_coarse) - 1)
        x = x_coarse[segment] + v_coarse[segment] * (t - t_coarse[segment])
        runner = FmuRunner(built_fmus[name], instance_name=f"h{h}")
        runner.initialize(x[0], v_coarse[0])
        out = runner.run(x, v_coarse[segment], h)[:, 0]
        runner.free()
        stride = int(round(coarse / h))
        results[h] = out[stride - 1::stride]
    scale = peak_to_peak(results[1e-4])
    rtol = COMPONENTS[name].default_experiment["tolerance"]
    for h in (1e-3, 1e-2):
        assert np.max(np.abs(results[h] - results[1e-4])) < 10 * rtol * scale, h


@pytest.mark.parametrize("name", FMU_NAMES)
def test_state_save_and_restore_continue_identically(built_fmus, name):
    t, x, v = thesis_sine(name, 1.0, 1e-3)
    first = FmuRunner(built_fmus[name], instance_name="first")
    first.initialize(x[0], v[0])
    first.run(x[:401], v[:401], 1e-3)
    saved_time = first.time
    state = first.fmu.getFMUstate()
    serialized = first.fmu.serializeFMUstate(state)
    uninterrupted = first.run(x[400:], v[400:], 1e-3)

    # Same instance, rewound.
    first.fmu.setFMUstate(state)
    first.time = saved_time
    assert np.array_equal(first.run(x[400:], v[400:], 1e-3), uninterrupted)
    first.fmu.freeFMUstate(state)
    first.free()

    # A fresh instance, from the serialized bytes.
    second = FmuRunner(built_fmus[name], instance_name="second")
    second.fmu.setupExperiment(startTime=0.0)
    second.fmu.enterInitializationMode()
    second.fmu.exitInitializationMode()
    restored = second.fmu.deSerializeFMUstate(serialized)
    second.fmu.setFMUstate(restored)
    second.time = saved_time
    assert np.array_equal(second.run(x[400:], v[400:], 1e-3), uninterrupted)
    second.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_each_closed_cycle_dissipates_energy(built_fmus, name):
    """Passivity: the work done on the component over every closed cycle is >= 0."""
    frequency = THESIS_SINES[name][2]
    step = 1e-3
    cycles = 3
    t, x, v = thesis_sine(name, cycles / frequency, step)
    runner = FmuRunner(built_fmus[name])
    runner.initialize(x[0], v[0])
    force = np.concatenate([[runner.read()[0]], runner.run(x, v, step)[:, 0]])
    runner.free()
    per_cycle = int(round(1 / frequency / step))
    for c in range(cycles):
        k = slice(c * per_cycle, (c + 1) * per_cycle + 1)
        work = np.trapezoid(force[k], x[k])
        loop_scale = peak_to_peak(force[k]) * peak_to_peak(x[k])
        assert work > 1e-3 * loop_scale, (c, work)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_reset_returns_to_the_initial_state(built_fmus, name):
    t, x, v = thesis_sine(name, 0.2, 1e-3)
    runner = FmuRunner(built_fmus[name])
    runner.initialize(x[0], v[0])
    before = runner.run(x, v, 1e-3)
    runner.fmu.reset()
    runner.initialize(x[0], v[0])
    assert np.array_equal(runner.run(x, v, 1e-3), before)
    runner.free()


def test_many_instances_of_one_fmu_in_one_process(built_fmus):
    """pythonfmu 0.7.0 frees the entry module's namespace after the first instance unless
    the adapter compensates (see adapter.hold_module_namespace)."""
    runners = [FmuRunner(built_fmus["TrackBushTorsion"], instance_name=f"joint{i}")
               for i in range(12)]
    outputs = []
    for i, runner in enumerate(runners):
        runner.initialize(math.radians(10 + i), 0.0)
        outputs.append(runner.step(math.radians(10 + i), 0.1, 1e-3)[0])
    assert len(set(outputs)) == 12 and all(np.isfinite(outputs))
    for runner in runners:
        runner.free()
    for _ in range(2):
        result = simulate_fmu(str(built_fmus["TrackBushTorsion"]), stop_time=0.01)
        assert np.all(np.isfinite(result["torque"]))
