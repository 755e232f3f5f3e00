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

    def __init__(self, path):
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
        self.fmu.instantiate(logMessage=self._log)
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
