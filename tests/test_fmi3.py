"""The FMI 3.0 FMUs: the FMI 2.0 FMUs' core and model code behind the FMI 3.0 face. fmpy
validates them and runs them in both interfaces with the same bits as FMI 2.0; their
states, derivatives (directional, adjoint, the outputs' time derivatives) and refusals."""

import math
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi1 import FMICallException
from fmpy.fmi3 import FMU3Slave
from fmpy import extract
from fmpy.validation import validate_fmu

from fmu_components.lab.build_command import sine_input
from fmu_components.lab.signals import thesis_sine
from fmu_components.runtime.integrator import DEFAULT_RTOL

from conftest import FMU_NAMES

STEP = 1e-3


@pytest.fixture(scope="module")
def fmi3(all_fmus):
    return all_fmus["fmi3"]


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmpy_validates_the_fmu_and_it_carries_both_platforms_and_its_build_description(fmi3, name):
    assert validate_fmu(str(fmi3[name])) == []
    names = zipfile.ZipFile(fmi3[name]).namelist()
    assert f"binaries/x86_64-linux/{name}.so" in names
    assert f"binaries/x86_64-windows/{name}.dll" in names
    assert "sources/buildDescription.xml" in names and "sources/fmi3_face.c" in names
    description = read_model_description(str(fmi3[name]))
    assert description.fmiVersion == "3.0"
    assert description.coSimulation.maxOutputDerivativeOrder == 1
    assert description.coSimulation.canHandleVariableCommunicationStepSize
    assert description.modelExchange.providesAdjointDerivatives


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("interface", ["CoSimulation", "ModelExchange"])
def test_fmi3_gives_the_bits_of_fmi2(all_fmus, name, interface):
    """fmpy's own loops in both interfaces, on the thesis sine: the same outputs to the bit."""
    output = read_model_description(str(all_fmus["native"][name])).modelVariables[2].name
    stop = 0.5
    signal = sine_input(name, stop, STEP)
    results = [simulate_fmu(str(all_fmus[flavour][name]), stop_time=stop, output_interval=STEP,
                            input=signal, output=[output], fmi_type=interface)
               for flavour in ("native", "fmi3")]
    assert np.isfinite(results[0][output]).all()
    assert np.array_equal(results[0][output], results[1][output])


class Instance:
    """One FMI 3.0 Co-Simulation instance through fmpy, its messages kept."""

    def __init__(self, path, **options):
        self.description = read_model_description(str(path))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.inputs = [v.valueReference for v in self.description.modelVariables
                       if v.causality == "input"]
        self.outputs = [v.valueReference for v in self.description.modelVariables
                        if v.causality == "output"]
        self.messages = []
        self.fmu = FMU3Slave(guid=self.description.guid, unzipDirectory=extract(str(path)),
                             modelIdentifier=self.description.coSimulation.modelIdentifier,
                             instanceName="fmi3")
        self.fmu.instantiate(logMessage=self._log, **options)
        self.time = 0.0

    def _log(self, environment, status, category, message):
        self.messages.append((status, message.decode()))

    def start(self, x, v):
        self.fmu.enterInitializationMode(startTime=0.0)
        self.fmu.setFloat64(self.inputs, [x, v])
        self.fmu.exitInitializationMode()

    def step(self, x, v, h=STEP):
        self.fmu.setFloat64(self.inputs, [x, v])
        self.fmu.doStep(self.time, h)
        self.time += h
        return self.fmu.getFloat64(self.outputs)

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_a_serialized_state_continues_identically(fmi3, name):
    t, x, v = thesis_sine(name, 0.2, STEP)
    first = Instance(fmi3[name])
    first.start(x[0], v[0])
    for k in range(100):
        first.step(x[k], v[k])
    blob = first.fmu.serializeFMUState(first.fmu.getFMUState())
    expected = [first.step(x[k], v[k]) for k in range(100, 200)]
    second = Instance(fmi3[name])
    second.start(x[0], v[0])
    second.fmu.setFMUState(second.fmu.deserializeFMUState(blob))
    second.time = first.time - 100 * STEP
    assert [second.step(x[k], v[k]) for k in range(100, 200)] == expected
    broken = bytearray(blob)
    broken[-10] ^= 1
    with pytest.raises(FMICallException):
        second.fmu.deserializeFMUState(bytes(broken))
    assert "checksum" in second.messages[-1][1]
    first.free()
    second.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_adjoint_derivatives_are_the_directional_ones_transposed(fmi3, name):
    t, x, v = thesis_sine(name, 0.1, STEP)
    instance = Instance(fmi3[name])
    instance.start(x[0], v[0])
    for k in range(50):
        instance.step(x[k], v[k])
    knowns, unknowns = instance.inputs, instance.outputs
    jacobian = np.array([instance.fmu.getDirectionalDerivative(unknowns, [known], [1.0])
                         for known in knowns]).T  # rows: unknowns
    assert np.isfinite(jacobian).all() and np.abs(jacobian).max() > 0
    seed = [0.5 + i for i in range(len(unknowns))]
    adjoint = instance.fmu.getAdjointDerivative(unknowns, knowns, seed, nSensitivity=len(knowns))
    assert np.allclose(adjoint, np.array(seed) @ jacobian, rtol=1e-14, atol=0.0)
    instance.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_the_outputs_time_derivative_is_their_slope_over_a_short_step(fmi3, name):
    t, x, v = thesis_sine(name, 0.3, STEP)
    instance = Instance(fmi3[name])
    instance.start(x[0], v[0])
    for k in range(250):
        before = instance.step(x[k], v[k])
    slope = instance.fmu.getOutputDerivatives(instance.outputs, [1] * len(instance.outputs))
    h = 1e-7  # the deflection moves on at the held rate over a step
    after = instance.step(x[249] + v[249] * STEP, v[249], h)
    numeric = (np.array(after) - np.array(before)) / h
    assert np.allclose(slope, numeric, rtol=1e-3, atol=1e-6 * np.abs(numeric).max()), \
        (slope, numeric)
    instance.free()


def test_a_refused_value_is_named_and_changes_nothing(fmi3):
    instance = Instance(fmi3["TrackBushRadial"])
    instance.start(1e-3, 0.0)
    before = instance.step(1e-3, 0.0)
    with pytest.raises(FMICallException):
        instance.fmu.setFloat64(instance.inputs, [math.nan, 0.0])
    assert "nan" in instance.messages[-1][1] and "fmi3SetFloat64" in instance.messages[-1][1]
    with pytest.raises(FMICallException):
        instance.fmu.doStep(instance.time, -1e-3)
    assert "-0.001" in instance.messages[-1][1] and "fmi3DoStep" in instance.messages[-1][1]
    assert instance.fmu.getFloat64(instance.outputs) == before
    instance.free()


def test_the_tyres_contact_event_is_a_variable_and_its_indicator(fmi3):
    description = read_model_description(str(fmi3["RoadWheelTyre"]))
    indicator, = description.eventIndicators
    assert indicator.variable.name == "contact_indicator"
    instance = Instance(fmi3["RoadWheelTyre"])
    instance.start(-2e-3, 0.0)
    instance.step(-2e-3, 0.0)
    assert instance.fmu.getFloat64([indicator.variable.valueReference]) == [pytest.approx(-2.0)]
    instance.free()


def contact_sine(t):
    """A tyre that lifts off and lands twice a second: (compression, its rate)."""
    return (0.5e-3 + 1.5e-3 * math.sin(2 * math.pi * t),
            1.5e-3 * 2 * math.pi * math.cos(2 * math.pi * t))


def run_tyre(path, early_return, event_mode, steps=2000):
    """1 ms host steps on contact_sine; a step that returns early is finished from where it
    returned (after event mode, if asked for). Forces at the grid, and the early returns as
    (time, eventHandlingNeeded)."""
    tyre = Instance(path, earlyReturnAllowed=early_return, eventModeUsed=event_mode)
    tyre.start(*contact_sine(0.0))
    if event_mode:  # initialization ends in Event Mode
        tyre.fmu.updateDiscreteStates()
        tyre.fmu.enterStepMode()
    forces, returns = [], []
    for k in range(steps):
        t, end = k * STEP, (k + 1) * STEP
        tyre.fmu.setFloat64(tyre.inputs, list(contact_sine(t)))
        while True:
            event, _, early, last = tyre.fmu.doStep(t, end - t)
            if not early:
                break
            returns.append((last, event))
            if event:
                tyre.fmu.enterEventMode()
                tyre.fmu.updateDiscreteStates()
                tyre.fmu.enterStepMode()
            t = last
        forces.append(tyre.fmu.getFloat64([tyre.vr["force"]])[0])
    assert not [m for m in tyre.messages if m[0] >= 2], tyre.messages
    tyre.free()
    return np.array(forces), returns


@pytest.mark.parametrize("event_mode", [True, False], ids=["event-mode", "early-return-only"])
def test_the_tyre_returns_early_where_its_contact_begins_and_ends(fmi3, event_mode):
    """Two lift-offs and two landings in 2 s: each step that crosses x = 0 returns at the
    crossing of the held-rate path, asking for event handling when the host uses event
    mode; the forces at the grid are those of whole steps."""
    whole, none = run_tyre(fmi3["RoadWheelTyre"], False, False)
    forces, returns = run_tyre(fmi3["RoadWheelTyre"], True, event_mode)
    assert none == [] and len(returns) == 4
    for last, event in returns:
        k = math.floor(last / STEP)
        x, v = contact_sine(k * STEP)
        assert last == pytest.approx(k * STEP - x / v, abs=1e-15)  # where x + v (t - tk) = 0
        assert event == event_mode
    assert np.max(np.abs(forces - whole)) <= 1e-12 * np.ptp(whole)


def test_an_early_return_at_the_contact_is_not_met_again_by_inputs_set_there(fmi3):
    """A host that sets the inputs again at lastSuccessfulTime, the compression a hair to
    the side the contact was on (interpolation's round-off), steps on from there: the
    crossing just reported is no reason to return again, nor is one a round-off after the
    step's start."""
    tyre = Instance(fmi3["RoadWheelTyre"], earlyReturnAllowed=True)
    tyre.start(5e-6, -0.01)
    _, _, early, last = tyre.fmu.doStep(0.0, STEP)
    assert early and last == pytest.approx(5e-4, rel=1e-12)
    for hair in (4.5e-20, 1e-22):  # still in contact by a hair, lifting off
        tyre.fmu.setFloat64(tyre.inputs, [hair, -0.01])
        _, _, early, end = tyre.fmu.doStep(last, STEP)
        assert not early and end == last + STEP
        last = end
        tyre.fmu.setFloat64(tyre.inputs, [-5e-6, 0.01])  # landing: reported...
        _, _, early, at = tyre.fmu.doStep(last, STEP)
        assert early and at == pytest.approx(last + 5e-4, rel=1e-9)
        tyre.fmu.setFloat64(tyre.inputs, [-hair, 0.01])  # ...and met again from below
        _, _, early, end = tyre.fmu.doStep(at, STEP)
        assert not early and end == at + STEP
        tyre.fmu.setFloat64(tyre.inputs, [5e-6, -0.01])  # a lift-off of its own
        _, _, early, last = tyre.fmu.doStep(end, STEP)
        assert early and last == pytest.approx(end + 5e-4, rel=1e-9)
    assert tyre.fmu.getFloat64([tyre.vr["force"]])[0] == 0.0
    assert not [m for m in tyre.messages if m[0] >= 2], tyre.messages
    tyre.free()


@pytest.mark.parametrize("event_mode", [True, False], ids=["event-mode", "step-mode"])
def test_initialization_ends_in_event_mode_when_the_host_uses_it(fmi3, event_mode):
    """FMI 3.0 section 3.2.3: fmi3ExitInitializationMode leads a Co-Simulation instance to
    Event Mode when it was made with eventModeUsed, else to Step Mode; fmi3EnterStepMode
    leads from Event Mode only."""
    tyre = Instance(fmi3["RoadWheelTyre"], earlyReturnAllowed=True, eventModeUsed=event_mode)
    tyre.start(1e-3, 0.0)

    def refused(call):
        try:
            call()
        except FMICallException:
            return True
        return False

    assert refused(tyre.fmu.updateDiscreteStates) != event_mode
    assert refused(tyre.fmu.enterStepMode) != event_mode
    assert refused(tyre.fmu.enterStepMode)  # now in Step Mode either way
    assert "fmi3EnterStepMode is not allowed in state StepMode" in tyre.messages[-1][1]
    tyre.fmu.doStep(0.0, STEP)
    assert refused(tyre.fmu.enterEventMode) != event_mode
    if event_mode:
        assert refused(lambda: tyre.fmu.doStep(STEP, STEP))  # not in Event Mode
        tyre.fmu.updateDiscreteStates()
        tyre.fmu.enterStepMode()
    tyre.fmu.doStep(STEP, STEP)
    tyre.free()


def damper_run(path, callback=None, early_return=False, steps=100, h=0.02):
    """The damper on a 0.75 Hz sine at 20 ms steps (several internal steps each)."""
    damper = Instance(path, intermediateUpdate=callback, earlyReturnAllowed=early_return)
    damper.start(0.0, 0.0)
    rate = lambda t: 0.2 * 1.5 * math.pi * math.cos(1.5 * math.pi * t)  # noqa: E731
    angle = lambda t: 0.2 * math.sin(1.5 * math.pi * t)  # noqa: E731
    return damper, angle, rate, h, steps


def test_intermediate_updates_come_at_internal_steps_with_outputs_to_read(fmi3):
    """The host is called back inside each step that takes more than one internal step,
    reads the outputs there, and the step ends where a step without call-backs ends (to
    the integrator's relative tolerance of the range)."""
    results, seen = {}, []
    for with_callback in (False, True):
        holder = {}

        def callback(environment, t, set_requested, get_allowed, finished, can_return_early,
                     early_requested, early_time):
            damper = holder["damper"]
            seen.append((t, damper.time, damper.fmu.getFloat64([damper.vr["torque"]])[0],
                         bool(set_requested and get_allowed and finished)))

        damper, angle, rate, h, steps = damper_run(fmi3["RotaryDamper"],
                                                   callback if with_callback else None)
        holder["damper"] = damper
        torques = [damper.step(angle(k * h), rate(k * h), h)[0] for k in range(steps)]
        assert not [m for m in damper.messages if m[0] >= 1], damper.messages
        damper.free()
        results[with_callback] = np.array(torques)
    assert len(seen) >= steps // 2
    assert all(start < t < start + h and math.isfinite(torque) and flags
               for t, start, torque, flags in seen)
    difference = np.max(np.abs(results[True] - results[False]))
    assert 0 < difference <= DEFAULT_RTOL * np.ptp(results[False])


def test_an_intermediate_update_sets_inputs_and_asks_to_return_early(fmi3):
    """In the first call-back the host sets the rate to 0 and asks the step to return: the
    step ends there, early, without event handling; the rate set holds from there on."""
    holder, calls = {"armed": False}, []

    def callback(environment, t, set_requested, get_allowed, finished, can_return_early,
                 early_requested, early_time):
        damper = holder["damper"]
        if holder["armed"] and not calls:
            calls.append((t, can_return_early))
            damper.fmu.setFloat64([damper.vr["angle_rate"]], [0.0])
            early_requested[0] = True

    damper, angle, rate, h, _ = damper_run(fmi3["RotaryDamper"], callback, early_return=True)
    holder["damper"] = damper
    for k in range(10):  # into the sine: the integrator takes several steps per host step
        damper.step(angle(k * h), rate(k * h), h)
    start = damper.time
    holder["armed"] = True
    damper.fmu.setFloat64(damper.inputs, [angle(start), rate(start)])
    event, _, early, last = damper.fmu.doStep(start, h)
    assert calls and calls[0][1]  # the host was told it can ask for an early return
    assert early and not event and last == calls[0][0] and start < last < start + h
    assert damper.fmu.getFloat64([damper.vr["angle_rate"]]) == [0.0]
    event, _, early, last = damper.fmu.doStep(last, start + h - last)
    assert last == pytest.approx(start + h, abs=1e-15)
    assert all(math.isfinite(value) for value in damper.fmu.getFloat64(damper.outputs))
    assert not [m for m in damper.messages if m[0] >= 2], damper.messages
    damper.free()


def test_a_host_cannot_step_or_save_the_state_inside_an_intermediate_update(fmi3):
    holder, statuses = {}, []

    def callback(environment, t, set_requested, get_allowed, finished, can_return_early,
                 early_requested, early_time):
        damper = holder["damper"]
        for call in (lambda: damper.fmu.doStep(t, 1e-3), damper.fmu.getFMUState,
                     lambda: damper.fmu.setFloat64([damper.vr["C1"]], [900.0])):
            try:
                call()
                statuses.append("accepted")
            except FMICallException:
                statuses.append("refused")

    damper, angle, rate, h, _ = damper_run(fmi3["RotaryDamper"], callback)
    holder["damper"] = damper
    for k in range(10):
        damper.step(angle(k * h), rate(k * h), h)
    assert statuses and set(statuses) == {"refused"}
    assert any("IntermediateUpdateMode" in m[1] for m in damper.messages)
    damper.free()


# --- the project's tools on FMI 3.0 FMUs: FMI 2.0's numbers ---------------------------------

def test_verify_and_validate_take_fmi3_fmus_with_the_fmi2_numbers(all_fmus, tmp_path):
    """verify and validate (fmpy's own loop) on the FMI 3.0 FMUs: the same identity, the
    same results to the bit as the FMI 2.0 FMUs, for a case of each component and the bush
    radial's measured quantities."""
    from fmu_components.export.identity import read_identity
    from fmu_components.verification import cases, measurements, verify

    for name in FMU_NAMES:
        identities = [read_identity(all_fmus[f][name]) for f in ("native", "fmi3")]
        assert [(i.component, i.structure, i.values, i.native) for i in identities] == \
            [(name, "final", identities[0].values, True)] * 2
        case = cases.select([name])[0]
        native, fmi3 = (verify.run_case(case, all_fmus[f][name]) for f in ("native", "fmi3"))
        assert native.errors and all(math.isfinite(e) for e in native.errors.values())
        assert np.array_equal(native.result, fmi3.result) and native.errors == fmi3.errors
    chosen = measurements.select(measurements.read_measurements(), ["TrackBushRadial"])
    compared = {}
    for flavour in ("native", "fmi3"):
        folder = tmp_path / flavour
        folder.mkdir()
        (folder / "TrackBushRadial.fmu").write_bytes(all_fmus[flavour]["TrackBushRadial"].read_bytes())
        compared[flavour] = [(c.measurement.id, c.model, c.problem)
                             for c in measurements.compare_all(chosen, measurements.Runs(folder))]
    assert compared["native"] == compared["fmi3"]
    assert sum(model is not None for _, model, _ in compared["fmi3"]) >= 5


def test_the_monolithic_reference_takes_fmi3_fmus_with_the_fmi2_numbers(all_fmus):
    """A mass dropped onto the tyre and swung on the damper, each Model Exchange FMU in one
    Radau solve with the bodies (verification/monolithic.py, the coupled examples'
    reference): the tyre's contact events and every output are FMI 2.0's to the bit."""
    from fmu_components.verification.monolithic import ModelExchangeComponent, MonolithicSystem

    def tyre_kinematics(t, q, qdot):
        return 1e-3 - q[0], -qdot[0]

    def damper_kinematics(t, q, qdot):
        return q[1], qdot[1]

    def accelerations(t, q, qdot, loads):
        return [loads[0] / 500.0 - 9.81, (200.0 * math.sin(30 * t) - loads[1]) / 2.0]

    runs = {}
    for flavour in ("native", "fmi3"):
        system = MonolithicSystem(2, accelerations, [
            (ModelExchangeComponent(all_fmus[flavour]["RoadWheelTyre"], "tyre"),
             tyre_kinematics),
            (ModelExchangeComponent(all_fmus[flavour]["RotaryDamper"], "damper"),
             damper_kinematics)])
        try:
            times, states, outputs = system.solve(0.3, [0.0, 0.0], [0.5, 0.0],
                                                  np.linspace(0.0, 0.3, 61), rtol=1e-8)
        finally:
            system.free()
        runs[flavour] = (times, states, [[o["force"], p["torque"]] for o, p in outputs],
                         system.events)
    (t2, y2, out2, events2), (t3, y3, out3, events3) = runs["native"], runs["fmi3"]
    assert events2 == events3 >= 1  # the mass leaves the tyre and lands again
    assert np.array_equal(t2, t3) and np.array_equal(y2, y3) and out2 == out3


@pytest.mark.parametrize("version", ["fmi3", "native"], ids=["fmi3", "fmi2"])
def test_model_exchange_enters_event_mode_where_its_fmi_version_allows(all_fmus, version):
    """fmiXEnterEventMode in Event Mode: FMI 3.0 refuses it (sections 3.2 and 3.2.1: from
    Continuous-Time Mode only, as the Reference FMUs' fmi3Functions.c); FMI 2.0 allows it
    (table 3.2.3). From Continuous-Time Mode both accept it."""
    from fmpy.fmi2 import FMU2Model
    from fmpy.fmi3 import FMU3Model

    path = all_fmus[version]["RoadWheelTyre"]
    description = read_model_description(path)
    messages = []
    if version == "fmi3":
        fmu = FMU3Model(guid=description.guid, unzipDirectory=extract(str(path)),
                        modelIdentifier=description.modelExchange.modelIdentifier)
        fmu.instantiate(logMessage=lambda env, status, category, message:
                        messages.append(message.decode()))
    else:
        fmu = FMU2Model(guid=description.guid, unzipDirectory=extract(str(path)),
                        modelIdentifier=description.modelExchange.modelIdentifier)
        fmu.instantiate(loggingOn=True)
        fmu.fmi2SetDebugLogging(fmu.component, True, 0, None)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    if version == "fmi3":  # Event Mode after initialization
        with pytest.raises(FMICallException):
            fmu.enterEventMode()
        assert "fmi3EnterEventMode is not allowed in state EventMode" in messages[-1]
        fmu.updateDiscreteStates()
    else:
        fmu.enterEventMode()  # FMI 2.0: allowed here, nothing changes
        fmu.newDiscreteStates()
    fmu.enterContinuousTimeMode()
    fmu.enterEventMode()  # from Continuous-Time Mode: both
    fmu.terminate()
    fmu.freeInstance()
