"""Bad input never crashes and never corrupts: each is answered with fmi2Error (fmi2Discard
for a step the integrator cannot complete) and a message naming the variable and the value,
the instance keeps the state it had, and the run can go on, or restart from a saved state."""

import json
import math
import struct
import zlib

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2LastSuccessfulTime

from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import THESIS_SINES, thesis_sine

from conftest import FMU_NAMES
from fmu_runner import DISCARD, ERROR, OK, WARNING, FmuRunner

STEP = 1e-3
STARTED = 200  # steps into the 0.4 s sine history where `started` hands over


def started(path, name):
    """An instance run STARTED steps into a sine, and the rest of the history."""
    t, x, v = thesis_sine(name, 0.4, STEP)
    runner = FmuRunner(path)
    runner.initialize(x[0], v[0])
    runner.run(x[:STARTED + 1], v[:STARTED + 1], STEP)
    return runner, x[STARTED:], v[STARTED:]


def uninterrupted(path, name):
    runner, x, v = started(path, name)
    result = runner.run(x, v, STEP)
    runner.free()
    return result


def last_error(runner):
    errors = [text for status, text in runner.messages if status == ERROR]
    assert errors, runner.messages
    return errors[-1]


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf], ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("which", [0, 1], ids=["deflection", "rate"])
def test_non_finite_input_is_refused_and_changes_nothing(built_fmus, name, bad, which):
    expected = uninterrupted(built_fmus[name], name)
    runner, x, v = started(built_fmus[name], name)
    before = runner.read()
    input_name = runner.inputs[which]
    assert runner.status(runner.fmu.setReal, [runner.vr[input_name]], [bad]) == ERROR
    message = last_error(runner)
    assert input_name in message and repr(bad) in message
    assert runner.read() == before
    assert np.array_equal(runner.run(x, v, STEP), expected)
    runner.free()


def test_an_input_that_would_drive_an_output_to_infinity_is_refused_and_changes_nothing(
        built_fmus):
    """Compression 1e300 m overflows the tyre's exponential force: refused with the values
    and the output named, not answered with OK and an infinite force."""
    name = "RoadWheelTyre"
    expected = uninterrupted(built_fmus[name], name)
    runner, x, v = started(built_fmus[name], name)
    before = runner.read()
    rate = runner.fmu.getReal([runner.vr["compression_rate"]])[0]
    assert runner.status(runner.fmu.setReal, [runner.vr["compression"]], [1e300]) == ERROR
    assert last_error(runner) == ("fmi2SetReal: compression = 1e+300 m with compression_rate "
                                  f"= {rate!r} m/s would drive force to inf; nothing set")
    assert runner.read() == before
    assert np.array_equal(runner.run(x, v, STEP), expected)
    runner.free()


def test_a_step_that_would_drive_an_output_to_infinity_is_discarded_and_changes_nothing(
        built_fmus):
    """A step of 1e300 s at a pressing rate leaves the tyre 1e297 m compressed: discarded,
    the instance where it was, and a saved state carries on as if it had never been tried."""
    name = "RoadWheelTyre"
    expected = uninterrupted(built_fmus[name], name)
    runner, x, v = started(built_fmus[name], name)
    saved = runner.fmu.getFMUstate()
    before = runner.read()
    runner.set_inputs(x[0], 1e-3)
    assert runner.status(runner.fmu.doStep, runner.time, 1e300) == DISCARD
    message = [text for status, text in runner.messages if status == DISCARD][-1]
    assert message.startswith(f"fmi2DoStep: step from t = {runner.time:.9g} s by 1e+300 s "
                              "failed: it would drive force to inf (compression = ")
    assert message.endswith("m at its end); nothing changed: take a smaller step")
    runner.fmu.setFMUstate(saved)
    assert runner.read() == before
    assert np.array_equal(runner.run(x, v, STEP), expected)
    runner.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_every_output_is_finite_at_the_corners_of_the_finite_bounds(built_fmus, name):
    """Inside ComponentDefinition.finite_bounds the guard does not look: at their corners,
    from a state inside a sine's loop, a set of inputs and a 1 ms step give finite outputs
    (or a refusal that is the model's own, as the damper's gas-spring limit)."""
    (x_low, x_high), (v_low, v_high) = COMPONENTS[name].finite_bounds
    for deflection in (x_low, x_high):
        for rate in (v_low, v_high):
            runner, _, _ = started(built_fmus[name], name)
            if runner.status(runner.fmu.setReal, [runner.vr[n] for n in runner.inputs],
                             [deflection, rate]) == OK:
                assert np.all(np.isfinite(runner.read())), (deflection, rate)
                runner.status(runner.fmu.doStep, runner.time, STEP)
                assert np.all(np.isfinite(runner.read())), (deflection, rate)
            runner.free()


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("time_offset, step", [(0.0, 0.0), (0.0, -STEP), (0.0, math.nan),
                                               (0.5, STEP), (-STEP, STEP)],
                         ids=["zero-step", "negative-step", "nan-step", "time-jump", "time-back"])
def test_bad_do_step_is_refused_and_changes_nothing(built_fmus, name, time_offset, step):
    expected = uninterrupted(built_fmus[name], name)
    runner, x, v = started(built_fmus[name], name)
    runner.set_inputs(x[0], v[0])
    assert runner.status(runner.fmu.doStep, runner.time + time_offset, step) == ERROR
    assert "step" in last_error(runner) or "time" in last_error(runner)
    assert runner.fmu.getRealStatus(fmi2LastSuccessfulTime) == pytest.approx(runner.time)
    assert np.array_equal(runner.run(x, v, STEP), expected)
    runner.free()


NONSENSE = {
    "RoadWheelTyre": [("k1", 0.0), ("c2", -1000.0), ("xi3", 0.0), ("geometric.h", -1.0)],
    "TrackBushRadial": [("k3", -1.7e7), ("c1", 0.0), ("xi2", -6.3e-4)],
    "TrackBushTorsion": [("k2", 0.0), ("c3", -40.0), ("xi1", 0.0)],
    "RotaryDamper": [("C1", 0.0), ("C2", -0.03), ("I", 0.0), ("dashpot.rate[3]", math.nan)],
}


@pytest.mark.parametrize("name, parameter, value",
                         [(n, p, v) for n in FMU_NAMES for p, v in NONSENSE[n]])
def test_nonsense_parameter_is_refused_when_set(built_fmus, name, parameter, value):
    t, x, v = thesis_sine(name, 0.4, STEP)
    runner = FmuRunner(built_fmus[name])
    runner.fmu.setupExperiment(startTime=0.0)
    runner.fmu.enterInitializationMode()
    assert runner.status(runner.fmu.setReal, [runner.vr[parameter]], [value]) == ERROR
    message = last_error(runner)
    assert parameter in message and repr(value) in message
    # The value was not taken: initialization completes with the thesis value.
    runner.set_inputs(x[0], v[0])
    assert runner.status(runner.fmu.exitInitializationMode) == OK
    assert np.all(np.isfinite(runner.run(x[:50], v[:50], STEP)))
    runner.free()


OVERFLOWING = [("TrackBushRadial", "k3", 1e-310), ("TrackBushTorsion", "c3", 1e300),
               ("RoadWheelTyre", "geometric.h", 1e300), ("RoadWheelTyre", "geometric.x_ref", 1e300),
               ("RoadWheelTyre", "geometric.x_ref", -1e300)]


@pytest.mark.parametrize("name, parameter, value", OVERFLOWING)
def test_a_parameter_that_overflows_the_arithmetic_is_refused_at_initialization(
        built_fmus, name, parameter, value):
    """Finite and of the right sign, but 1/k3 or h*|x - x_ref| would be Inf on every step."""
    t, x, v = thesis_sine(name, 0.4, STEP)
    runner = FmuRunner(built_fmus[name])
    runner.fmu.setupExperiment(startTime=0.0)
    runner.fmu.enterInitializationMode()
    runner.set_inputs(x[0], v[0])
    runner.status(runner.fmu.setReal, [runner.vr[parameter]], [value])
    assert runner.status(runner.fmu.exitInitializationMode) == ERROR
    message = last_error(runner)
    assert parameter in message and repr(value) in message and "magnitudes" in message
    # Still in initialization mode: the thesis value restores it.
    default = COMPONENTS[name].default_parameters()[parameter]
    assert runner.status(runner.fmu.setReal, [runner.vr[parameter]], [default]) == OK
    assert runner.status(runner.fmu.exitInitializationMode) == OK
    assert np.all(np.isfinite(runner.run(x[:50], v[:50], STEP)))
    runner.free()


def test_non_monotone_damper_table_is_refused_at_initialization(built_fmus):
    runner = FmuRunner(built_fmus["RotaryDamper"])
    runner.fmu.setupExperiment(startTime=0.0)
    runner.fmu.enterInitializationMode()
    # Each point on its own is a finite number; together they make a non-monotone curve.
    assert runner.status(runner.fmu.setReal, [runner.vr["dashpot.torque[30]"]], [0.0]) == OK
    assert runner.status(runner.fmu.exitInitializationMode) == ERROR
    message = last_error(runner)
    assert "dashpot table" in message and "point 30" in message
    # Still in initialization mode: the host can correct the point and carry on.
    assert runner.status(runner.fmu.setReal, [runner.vr["dashpot.torque[30]"]], [3250.0]) == OK
    assert runner.status(runner.fmu.exitInitializationMode) == OK
    assert runner.status(runner.fmu.doStep, 0.0, STEP) == OK
    runner.free()


def test_feeding_torque_into_the_dashpot_is_refused(built_fmus):
    runner = FmuRunner(built_fmus["RotaryDamper"])
    runner.fmu.setupExperiment(startTime=0.0)
    runner.fmu.enterInitializationMode()
    # Monotone, but negative torque at a positive rate would feed energy in.
    rates_at_or_below = [runner.vr[f"dashpot.torque[{i}]"] for i in range(1, 26)]
    runner.fmu.setReal(rates_at_or_below, [-9000.0] * 25)
    assert runner.status(runner.fmu.exitInitializationMode) == ERROR
    assert "feed energy in" in last_error(runner)
    runner.fmu.freeInstance()  # still in initialization mode, where terminate is not allowed


@pytest.mark.parametrize("name", FMU_NAMES)
def test_calls_out_of_sequence_are_refused(built_fmus, name):
    runner = FmuRunner(built_fmus[name])
    fmu, vr = runner.fmu, runner.vr
    parameter, output = COMPONENTS[name].parameters[0].name, runner.outputs[0]
    assert runner.status(fmu.doStep, 0.0, STEP) == ERROR
    assert "fmi2DoStep is not allowed in state Instantiated" in last_error(runner)
    assert runner.status(fmu.exitInitializationMode) == ERROR
    runner.initialize(THESIS_SINES[name][0], 0.0)
    assert runner.status(fmu.setupExperiment, None, 0.0) == ERROR
    assert runner.status(fmu.enterInitializationMode) == ERROR
    assert runner.status(fmu.setReal, [vr[parameter]], [1.0]) == ERROR
    assert parameter in last_error(runner) and "fixed parameter" in last_error(runner)
    assert runner.status(fmu.setReal, [vr[output]], [1.0]) == ERROR
    assert runner.status(fmu.getReal, [10_000]) == ERROR
    assert runner.status(fmu.getInteger, [0]) == ERROR
    assert runner.status(fmu.setBoolean, [0], [True]) == ERROR
    assert runner.status(fmu.getString, [0]) == ERROR
    # None of it disturbed the instance.
    assert runner.status(fmu.doStep, 0.0, STEP) == OK
    assert np.all(np.isfinite(runner.read()))
    fmu.terminate()
    assert runner.status(fmu.doStep, STEP, STEP) == ERROR
    fmu.freeInstance()


@pytest.mark.parametrize("name, value", [("RoadWheelTyre", 12e-3), ("TrackBushRadial", 0.8e-3),
                                         ("TrackBushTorsion", math.radians(60)),
                                         ("RotaryDamper", math.radians(50))])
def test_input_outside_the_measured_range_simulates_with_one_warning(built_fmus, name, value):
    runner = FmuRunner(built_fmus[name])
    runner.initialize(THESIS_SINES[name][0], 0.0)
    # Get there by a ramp, as a host would.
    start = THESIS_SINES[name][0]
    ramp = np.linspace(start, value, 101)
    statuses = []
    for k in range(100):
        rate = (ramp[k + 1] - ramp[k]) / STEP
        statuses.append(runner.set_real_status(runner.inputs, [ramp[k], rate]))
        assert runner.status(runner.fmu.doStep, runner.time, STEP) == OK
        runner.time += STEP
        assert np.all(np.isfinite(runner.read()))
    warnings = [text for status, text in runner.messages if status == WARNING]
    assert statuses.count(WARNING) == 1 and len(warnings) == 1
    assert runner.inputs[0] in warnings[0] and "outside the range the thesis measured" in warnings[0]
    runner.free()


@pytest.mark.parametrize("degrees, warned", [(40.0, True), (-20.0, True), (30.0, False),
                                             (-10.0, False)])
def test_torsion_warns_outside_the_live_angle_plus_or_minus_the_largest_torsion(
        built_fmus, degrees, warned):
    """The message, the threshold and the spec agree: 10 +- 23 deg (section 5.1.2)."""
    runner = FmuRunner(built_fmus["TrackBushTorsion"])
    runner.initialize(math.radians(10.0), 0.0)
    runner.set_real_status(runner.inputs, [math.radians(degrees), 0.0])
    warnings = [text for status, text in runner.messages if status == WARNING]
    if warned:
        assert len(warnings) == 1 and "-13 to 33 deg" in warnings[0], warnings
    else:
        assert warnings == []
    runner.free()


def test_damper_refuses_an_angle_jump_beyond_the_gas_spring_limit(built_fmus):
    runner = FmuRunner(built_fmus["RotaryDamper"])
    runner.initialize(0.0, 0.0)
    runner.step(0.0, 0.0, STEP)
    before = runner.read()
    assert runner.status(runner.fmu.setReal, [runner.vr["angle"]], [0.05]) == ERROR
    assert "outside its limit" in last_error(runner) and "0.05" in last_error(runner)
    assert runner.read() == before
    runner.free()


def test_a_step_the_integrator_cannot_complete_is_discarded_and_recoverable(built_fmus):
    """An arm rate jumping from rest to 150 rad/s in one step asks the gas spring for a
    torque spike no step size can follow. The step is discarded, the instance is where it
    was, and a saved state restarts it."""
    runner = FmuRunner(built_fmus["RotaryDamper"])
    runner.initialize(0.0, 0.0)
    runner.step(0.0, 0.0, STEP)
    saved = runner.fmu.getFMUstate()
    before = runner.read()
    runner.set_inputs(0.0, 150.0)
    assert runner.status(runner.fmu.doStep, runner.time, STEP) == DISCARD
    assert "ramp the rate" in [text for s, text in runner.messages if s == DISCARD][-1]
    assert runner.fmu.getRealStatus(fmi2LastSuccessfulTime) == pytest.approx(runner.time)
    assert runner.read() == before  # the state did not move
    # FMI: after a discarded step the host restores a state before stepping again.
    assert runner.status(runner.fmu.doStep, runner.time, STEP) == ERROR
    runner.fmu.setFMUstate(saved)
    angle, outputs = 0.0, []
    for k in range(40):  # the same rate, reached by a ramp
        rate = 150.0 * k / 39
        outputs.append(runner.step(angle, rate, STEP))
        angle += rate * STEP
    assert np.all(np.isfinite(outputs))
    runner.free()


ENVELOPE_HEAD = 8 + 4 + 4 + 64 + 64  # "FMUSTATE", version, length, name, GUID


def reseal(blob, payload=None, version=None):
    """A serialized state with its payload or format version replaced and its length and
    checksum made right again: what a careful forger (or another build) would send."""
    head, body = bytearray(blob[:ENVELOPE_HEAD]), blob[ENVELOPE_HEAD:-4]
    payload = body if payload is None else payload
    if version is not None:
        head[8:12] = struct.pack("<I", version)
    head[12:16] = struct.pack("<I", len(payload))
    content = bytes(head) + payload
    return content + struct.pack("<I", zlib.crc32(content))


def serialized(runner):
    return bytes(runner.fmu.serializeFMUstate(runner.fmu.getFMUstate()))


def refused_state(runner, blob):
    """The status and message of deserializing and setting `blob`: refused either way."""
    try:
        state = runner.fmu.deSerializeFMUstate(blob)
    except FMICallException as failure:
        return failure.status, last_error(runner)
    return runner.status(runner.fmu.setFMUstate, state), last_error(runner)


def with_first_input(flavour, payload, value):
    """The payload with the deflection input replaced: in the native Snapshot the values
    follow the FMI state (an int, padded to 8 bytes); in the Python one it is JSON."""
    if flavour == "native":
        return payload[:8] + struct.pack("<d", value) + payload[16:]
    state = json.loads(payload)
    state["values"][0] = value
    return json.dumps(state).encode()


@pytest.mark.parametrize("kind, expected", [
    ("not a state", "cannot be read"), ("truncated", "cannot be read"),
    ("corrupted", "checksum"), ("other version", "format version"),
    ("non-finite input", "is not a finite number")])
def test_a_broken_serialized_state_is_refused(built_fmus, kind, expected):
    runner = FmuRunner(built_fmus["TrackBushTorsion"])
    runner.initialize(math.radians(10), 0.0)
    before = runner.step(math.radians(10), 0.1, STEP)
    blob = serialized(runner)
    broken = {"not a state": lambda: b"{not json",
              "truncated": lambda: blob[:-9],
              "corrupted": lambda: blob[:ENVELOPE_HEAD + 20] + bytes([blob[ENVELOPE_HEAD + 20] ^ 1])
              + blob[ENVELOPE_HEAD + 21:],
              "other version": lambda: reseal(blob, version=99),
              "non-finite input": lambda: reseal(blob, with_first_input(
                  built_fmus.flavour, blob[ENVELOPE_HEAD:-4], math.nan))}[kind]()
    status, message = refused_state(runner, broken)
    assert status == ERROR and expected in message, message
    assert runner.read() == before
    runner.free()


def forged(flavour, payload, craft, n_variables):
    """The payload of a TrackBushTorsion state with one value forged. The Python state is
    JSON; the native one is its Snapshot (runtime.h): the FMI state (an int padded to 8
    bytes), the values by reference, start time, tolerance, the initialized flag (padded),
    time, deflection, rate, then the model state."""
    k1 = 6  # TrackBushTorsion's first stiffness (catalog order)
    if flavour == "native":
        model_state = 8 + 8 * n_variables + 8 + 8 + 8 + 3 * 8
        offset, value = {"a bogus FMI state": (0, struct.pack("<i", 12345)),
                         "a negative stiffness": (8 + 8 * k1, struct.pack("<d", -1.0)),
                         "a NaN model state": (model_state, struct.pack("<d", math.nan))}[craft]
        return payload[:offset] + value + payload[offset + len(value):]
    state = json.loads(payload)
    if craft == "a bogus FMI state":
        state["mode"] = "Bogus"
    elif craft == "a negative stiffness":
        state["values"][k1] = -1.0
    elif craft == "a NaN model state":
        state["cosim"]["state"][0] = math.nan
    elif craft == "an empty model state":
        state["cosim"]["state"] = []
    elif craft == "a parameter given as text":
        state["values"][k1] = str(state["values"][k1])
    return json.dumps(state).encode()


# The native state is a fixed binary layout: it has no list to empty and no text.
CRAFTS = {"native": ["a bogus FMI state", "a negative stiffness", "a NaN model state"],
          "python": ["a bogus FMI state", "a negative stiffness", "a NaN model state",
                     "an empty model state", "a parameter given as text"]}


def test_a_forged_state_with_a_valid_checksum_is_refused_and_changes_nothing(built_fmus):
    """A state whose envelope and checksum are right but whose content no run could reach:
    every value passes the checks fmi2SetReal makes before any of it is used."""
    runner = FmuRunner(built_fmus["TrackBushTorsion"])
    runner.initialize(math.radians(10), 0.0)
    before = runner.step(math.radians(10), 0.1, STEP)
    blob = serialized(runner)
    n_variables = sum(1 for v in runner.description.modelVariables if v.type == "Real")
    for craft in CRAFTS[built_fmus.flavour]:
        payload = forged(built_fmus.flavour, blob[ENVELOPE_HEAD:-4], craft, n_variables)
        assert payload != blob[ENVELOPE_HEAD:-4]
        status, message = refused_state(runner, reseal(blob, payload))
        assert status == ERROR and "state" in message, (craft, message)
        if craft == "a NaN model state":  # the refusal names the field and its value
            assert "the state's internal state[0] = nan is not valid" in message, message
        assert runner.read() == before, craft
    assert np.all(np.isfinite(runner.step(math.radians(10), 0.1, STEP)))
    runner.free()


def test_a_state_of_another_component_is_refused(built_fmus):
    damper = FmuRunner(built_fmus["RotaryDamper"])
    damper.initialize(0.0, 0.0)
    foreign = serialized(damper)
    bush = FmuRunner(built_fmus["TrackBushTorsion"])
    bush.initialize(math.radians(10), 0.0)
    status, message = refused_state(bush, foreign)
    assert status == ERROR and "RotaryDamper" in message
    damper.free()
    bush.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_after_an_error_a_saved_state_continues_identically(built_fmus, name):
    expected = uninterrupted(built_fmus[name], name)
    runner, x, v = started(built_fmus[name], name)
    saved = runner.fmu.getFMUstate()
    assert runner.status(runner.fmu.doStep, runner.time + 1.0, STEP) == ERROR
    runner.fmu.setFMUstate(saved)
    assert np.array_equal(runner.run(x, v, STEP), expected)
    runner.free()


def test_a_state_restored_into_an_instance_with_other_parameters_runs_on_them(built_fmus):
    """fmi2SetFMUstate keeps the instance's constants and curves only where the state's
    parameters are the instance's own; a state made with others brings them along."""
    t, x, v = thesis_sine("TrackBushRadial", 0.05, STEP)
    softer = FmuRunner(built_fmus["TrackBushRadial"], "softer")
    softer.fmu.setupExperiment(startTime=0.0)
    softer.fmu.enterInitializationMode()
    softer.fmu.setReal([softer.vr["k1"]], [0.5 * softer.fmu.getReal([softer.vr["k1"]])[0]])
    softer.set_inputs(x[0], v[0])
    softer.fmu.exitInitializationMode()
    softer.run(x[:21], v[:21], STEP)
    thesis = FmuRunner(built_fmus["TrackBushRadial"], "thesis")
    thesis.initialize(x[0], v[0])
    thesis.run(x[:21], v[:21], STEP)
    thesis.fmu.setFMUstate(softer.fmu.getFMUstate())
    thesis.time = softer.time
    assert thesis.run(x[20:], v[20:], STEP).tolist() == softer.run(x[20:], v[20:], STEP).tolist()
    thesis.fmu.setFMUstate(thesis.fmu.getFMUstate())  # its own parameters: nothing rebuilt
    softer.free()
    thesis.free()


def test_a_state_of_another_fmu_is_refused(built_fmus):
    bush = FmuRunner(built_fmus["TrackBushRadial"], "bush")
    bush.initialize(1e-3, 0.0)
    tyre = FmuRunner(built_fmus["RoadWheelTyre"], "tyre")
    tyre.initialize(1e-3, 0.0)
    before = tyre.step(1e-3, 0.0, STEP)
    assert tyre.status(tyre.fmu.setFMUstate, bush.fmu.getFMUstate()) == ERROR
    assert "RoadWheelTyre" in last_error(tyre) and "state unchanged" in last_error(tyre)
    assert tyre.read() == before
    bush.free()
    tyre.free()


def declared(description, *types):
    return {v.valueReference for v in description.modelVariables if v.type in types}


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("flavour", ["native", "python", "fmi3"])
def test_a_value_reference_the_model_description_does_not_declare_is_refused_by_number(
        all_fmus, flavour, name):
    """Every reference the modelDescription declares is answered; every other one (the
    gaps, the next few, FMI 3.0's event indicator and time in FMI 2.0, the largest) gets
    Error naming it, in getReal/getFloat64, setReal/setFloat64 and getBoolean."""
    path = all_fmus[flavour][name]
    if flavour == "fmi3":
        from test_fmi3 import Instance
        instance = Instance(path)
        instance.start(*[0.0] * 2)
        fmu, get_real, set_real = instance.fmu, instance.fmu.getFloat64, instance.fmu.setFloat64
        get_boolean = fmu.getBoolean
        messages = instance.messages
    else:
        runner = FmuRunner(path)
        runner.initialize(0.0, 0.0)
        fmu, get_real, set_real = runner.fmu, runner.fmu.getReal, runner.fmu.setReal
        get_boolean = fmu.getBoolean
        messages = runner.messages
    description = read_model_description(str(path))
    reals = declared(description, "Real", "Float64")
    booleans = declared(description, "Boolean")
    probes = set(range(max(reals | booleans) + 5)) | {2 ** 31, 2 ** 32 - 1}
    assert all(math.isfinite(value) for value in get_real(sorted(reals)))
    assert get_boolean(sorted(booleans))
    for vr in sorted(probes - reals):
        for call in (lambda: get_real([vr]), lambda: set_real([vr], [0.0])):
            with pytest.raises(FMICallException):
                call()
            assert str(vr) in messages[-1][1], (vr, messages[-1])
    for vr in sorted(probes - booleans):
        with pytest.raises(FMICallException):
            get_boolean([vr])
        assert str(vr) in messages[-1][1], (vr, messages[-1])
    fmu.terminate()
    fmu.freeInstance()
