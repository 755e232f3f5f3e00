"""Model Exchange and directional derivatives of the native FMUs (spec section 7).

* On fmpy's CVode (rtol 1e-6, nominals used) with continuous inputs (tests/me_host.py), every
  validation case agrees with the independent continuous-input solve
  (reference.solve_smooth) within 0.5 % of each output's peak-to-peak range; the damper
  runs through its 8 Hz blow-off.
* Directional derivatives, in both interfaces, agree with central finite differences of
  the FMU's own outputs and derivatives at random points, on both sides of every kink.
* A host that sets continuous states straight after Event Mode is served, with one
  warning.
"""

import math
import random
from ctypes import c_double

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy import calloc, free
from fmpy.fmi2 import (FMU2Model, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

from fmu_components import cases, reference
from fmu_components.runtime.catalog import COMPONENTS

from conftest import FMU_NAMES
from me_host import (Instance, ModelExchangeRun, central_differences, continuous_input,
                     evaluate, random_points)

LIMIT = 0.5  # % of the output's peak-to-peak range


@pytest.mark.parametrize("case", [c for c in cases.CASES if c.test not in ("IV", "sweep")],
                         ids=lambda c: c.key)
def test_model_exchange_on_cvode_matches_the_continuous_input_solve(native_fmus, case):
    x_of, v_of = continuous_input(case)
    times = case.times()
    run = ModelExchangeRun(native_fmus[case.fmu], x_of, v_of, rtol=1e-6)
    outputs = run.run(times)
    expected = reference.solve_smooth(case.fmu, times, x_of, v_of)
    names = [o.name for o in COMPONENTS[case.fmu].outputs]
    for output, values in expected.items():
        scale = np.ptp(values) or 1.0
        error = np.max(np.abs(outputs[:, names.index(output)] - values)) / scale * 100
        assert error <= LIMIT, (output, error)


def test_the_tyre_leaves_and_regains_contact_through_events(native_fmus):
    times = np.arange(0.0, 2.0 + 1e-9, 2e-3)
    x_of = lambda t: 0.5e-3 + 1.5e-3 * math.sin(2 * math.pi * t)  # noqa: E731
    v_of = lambda t: 1.5e-3 * 2 * math.pi * math.cos(2 * math.pi * t)  # noqa: E731
    run = ModelExchangeRun(native_fmus["RoadWheelTyre"], x_of, v_of, rtol=1e-6)
    force = run.run(times)[:, 0]
    expected = reference.solve_smooth("RoadWheelTyre", times, x_of, v_of)["force"]
    assert run.events >= 4  # two lift-offs and two touch-downs
    assert np.all(force >= 0.0) and np.all(force[np.array([x_of(t) for t in times]) <= 0] == 0.0)
    assert np.max(np.abs(force - expected)) <= LIMIT / 100 * np.ptp(expected)


@pytest.mark.parametrize("interface", ["ModelExchange", "CoSimulation"])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_directional_derivatives_match_central_differences(native_fmus, name, interface):
    rng = random.Random(11)
    instance = Instance(native_fmus[name], interface)
    fmu = instance.fmu
    knowns, unknowns = instance.knowns(), instance.unknowns()
    x, v, _ = next(random_points(name, 1, rng))
    if interface == "CoSimulation":
        runner = instance.runner
        runner.initialize(x, v)
        for k in range(300):  # a state inside the hysteresis loop
            runner.step(x + 0.5 * (v * 1e-3) * math.sin(k / 30), v * math.cos(k / 30), 1e-3)
    else:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal(knowns[:2], [x, v])
        fmu.exitInitializationMode()
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()
    checked = 0
    nominals = COMPONENTS[name].build_model(COMPONENTS[name].default_parameters()).nominals
    for x, v, states in random_points(name, 40, rng):
        if interface == "CoSimulation" and name == "RotaryDamper":
            x = runner.read()[1] * 0.0 + runner.fmu.getReal([knowns[0]])[0] + rng.uniform(-5e-3, 5e-3)
        point = {knowns[0]: x, knowns[1]: v}
        if interface == "ModelExchange":
            point.update(zip(knowns[2:], states))
        scale = {knowns[0]: abs(x) + 1e-3, knowns[1]: abs(v)}
        scale.update({vr: abs(point[vr]) + nominal for vr, nominal in zip(knowns[2:], nominals)})
        instance.steps = {vr: 1e-6 * scale[vr] for vr in knowns}
        for known in knowns:
            base = evaluate(instance, point, knowns, unknowns)
            analytic = np.array(fmu.getDirectionalDerivative(unknowns, [known], [1.0]))
            up, down = central_differences(instance, point, knowns, unknowns, {known: 1.0})
            numeric = (up - down) / (2 * instance.steps[known])
            # away from kinks: both one-sided differences agree with the central one
            forward = (up - base) / instance.steps[known]
            backward = (base - down) / instance.steps[known]
            smooth = np.abs(forward - backward) <= 1e-4 * (np.abs(numeric) + 1e-300) + 1e-9 * (
                np.max(np.abs(numeric)) + 1e-300)
            for i in np.flatnonzero(smooth):
                assert analytic[i] == pytest.approx(numeric[i], rel=1e-6,
                                                    abs=1e-6 * np.max(np.abs(numeric)) + 1e-12), (
                    known, unknowns[i], x, v)
                checked += 1
    assert checked > 40 * len(knowns)


def test_a_host_setting_states_straight_after_event_mode_is_served_with_one_warning(native_fmus):
    """The call pattern of importers that skip fmi2EnterContinuousTimeMode before setting
    the states (spec section 7)."""
    path = native_fmus["TrackBushTorsion"]
    description = read_model_description(str(path))
    messages = []
    fmu = FMU2Model(guid=description.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=description.modelExchange.modelIdentifier,
                    instanceName="importer")
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(
        lambda env, name, status, category, message: messages.append((status, message.decode())))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    fmu.instantiate(callbacks=callbacks)
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([0, 1], [math.radians(10), 0.1])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    states = (c_double * 3)(1e-3, 2e-4, 3e-3)
    fmu.setContinuousStates(states, 3)  # in Event Mode: a warning, taken
    fmu.setContinuousStates(states, 3)  # again: no second warning
    fmu.enterContinuousTimeMode()
    derivatives = (c_double * 3)()
    fmu.getDerivatives(derivatives, 3)
    back = (c_double * 3)()
    fmu.getContinuousStates(back, 3)
    assert list(back) == list(states) and all(math.isfinite(d) for d in derivatives)
    warnings = [text for status, text in messages if status == 1]
    assert len(warnings) == 1 and "fmi2SetContinuousStates in EventMode" in warnings[0]
    model = COMPONENTS["TrackBushTorsion"].build_model(
        COMPONENTS["TrackBushTorsion"].default_parameters())
    assert list(derivatives) == list(model.rates(list(states), math.radians(10), 0.1, 1.0))
    fmu.terminate()
    fmu.freeInstance()


def test_the_damper_refuses_states_past_its_region_with_discard(native_fmus):
    path = native_fmus["RotaryDamper"]
    description = read_model_description(str(path))
    fmu = FMU2Model(guid=description.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=description.modelExchange.modelIdentifier,
                    instanceName="damper")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.setContinuousStates((c_double * 2)(25.0, 0.0), 2)  # z = 25: xd is C2 to the last bit
    with pytest.raises(FMICallException) as refused:
        fmu.getDerivatives((c_double * 2)(), 2)
    assert refused.value.status == 2  # fmi2Discard: the host retries a smaller step
    fmu.setContinuousStates((c_double * 2)(0.5, 0.0), 2)
    derivatives = (c_double * 2)()
    fmu.getDerivatives(derivatives, 2)
    assert all(math.isfinite(d) for d in derivatives)
    fmu.terminate()
    fmu.freeInstance()
