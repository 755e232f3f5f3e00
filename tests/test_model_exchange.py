"""Model Exchange and directional derivatives of the native FMUs (spec section 7).

* On fmpy's CVode (rtol 1e-6, nominals used) with continuous inputs (tests/me_host.py), every
  verification case agrees with the independent continuous-input solve
  (reference.solve_smooth) within 0.5 % of each output's peak-to-peak range; the damper
  runs through its 8 Hz blow-off.
* Directional derivatives, in both interfaces, agree with central finite differences of
  the FMU's own outputs and derivatives at random points, on both sides of every kink.
* A host that sets continuous states straight after Event Mode is served, with one
  warning.
"""

import math
from ctypes import c_double

import numpy as np
import pytest
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Model, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

from fmu_components.verification import cases, reference
from fmu_components.runtime.catalog import COMPONENTS

from conftest import FMU_NAMES
from me_host import ModelExchangeRun, compare_directional_derivatives, continuous_input

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
    compared, kinks, worst = compare_directional_derivatives(native_fmus[name], interface, 40,
                                                             seed=11)
    knowns = 2 + (len(COMPONENTS[name].states) if interface == "ModelExchange" else 0)
    assert worst <= 1e-6 and compared > 40 * knowns, (compared, kinks, worst)


def logged_instance(path, name):
    """A Model Exchange instance through fmpy, and the list its messages land in as
    (status, text)."""
    description = read_model_description(str(path))
    messages = []
    fmu = FMU2Model(guid=description.guid, unzipDirectory=extract(str(path)),
                    modelIdentifier=description.modelExchange.modelIdentifier, instanceName=name)
    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(
        lambda env, name, status, category, message: messages.append((status, message.decode())))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    fmu.instantiate(callbacks=callbacks)
    fmu.callbacks_kept = callbacks  # alive as long as the instance
    return fmu, messages


def test_a_host_setting_states_straight_after_event_mode_is_served_with_one_warning(native_fmus):
    """The call pattern of importers that skip fmi2EnterContinuousTimeMode before setting
    the states (spec section 7)."""
    fmu, messages = logged_instance(native_fmus["TrackBushTorsion"], "importer")
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
    fmu, messages = logged_instance(native_fmus["RotaryDamper"], "damper")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.setContinuousStates((c_double * 2)(25.0, 0.0), 2)  # z = 25: xd is C2 to the last bit
    with pytest.raises(FMICallException) as refused:
        fmu.getDerivatives((c_double * 2)(), 2)
    assert refused.value.status == 2  # fmi2Discard: the host retries a smaller step
    assert messages[-1] == (2, "fmi2GetDerivatives: at t = 0 s the states (state.z = 25.0, "
                               "state.omega_r = 0.0) are outside the region the model is "
                               "defined in; retry with a smaller step")
    fmu.setContinuousStates((c_double * 2)(0.5, 0.0), 2)
    derivatives = (c_double * 2)()
    fmu.getDerivatives(derivatives, 2)
    assert all(math.isfinite(d) for d in derivatives)
    fmu.terminate()
    fmu.freeInstance()


def test_an_output_driven_to_infinity_is_answered_with_discard_and_the_value(native_fmus):
    """In Model Exchange the host's inputs and states go in unchecked until it reads: an
    overflowing output is a Discard that names it, never an infinite value with OK."""
    fmu, messages = logged_instance(native_fmus["RoadWheelTyre"], "overflow")
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setReal([0, 1], [2e-3, 0.0])
    fmu.exitInitializationMode()
    fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    assert all(math.isfinite(value) for value in fmu.getReal([2, 3, 4, 5]))
    fmu.setReal([0, 1], [1e300, 0.0])
    with pytest.raises(FMICallException):
        fmu.getReal([2])
    assert messages[-1] == (2, "fmi2GetReal: force would be inf at compression = 1e+300 m, "
                               "compression_rate = 0.0 m/s: beyond what the model can give; "
                               "retry with a smaller step or smaller inputs")
    fmu.setReal([0, 1], [2e-3, 0.0])
    assert all(math.isfinite(value) for value in fmu.getReal([2, 3, 4, 5]))
    fmu.terminate()
    fmu.freeInstance()
