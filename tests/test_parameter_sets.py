"""Parameter sets at run time: `fit` writes an .ssv beside its JSON, and the coupling's
components (coupling/instance.py, fmu.py) take an .ssv as their parameters, applied to the
FMU as built, its units checked against the FMU's modelDescription and every refusal
naming the file, the parameter and the value."""

import json

import pytest

from fmu_components.coupling import CouplingError, FmuComponent
from fmu_components.coupling.instance import FmuInstance
from fmu_components.export.parameters import read_parameters
from fmu_components.lab.fit import write_parameters
from fmu_components.runtime.catalog import component_definition
from fmu_components.ssv import write_ssv

BUSH = "TrackBushRadial"
STIFFNESS = {"N/m": {"kg": 1, "s": -2}, "N": {"kg": 1, "m": 1, "s": -2}}


@pytest.fixture(scope="module")
def bush_fmus(all_fmus):
    """The bush's native FMI 2.0 and FMI 3.0 FMUs, {flavour: path}, of the session's build."""
    return {flavour: all_fmus[flavour][BUSH] for flavour in ("native", "fmi3")}


def n_per_mm_file(path, name, value):
    """An .ssv giving `name` in N/mm (defined in the file as 1000 N/m)."""
    write_ssv(path, "bush", [(name, value, "N/mm", None)], {"N/mm": STIFFNESS["N/m"]})
    path.write_text(path.read_text().replace('<ssc:BaseUnit kg="1" s="-2"',
                                             '<ssc:BaseUnit kg="1" s="-2" factor="1000.0"'))
    return path


def test_fit_writes_an_ssv_beside_its_json_with_the_same_values(tmp_path):
    definition = component_definition(BUSH)
    values = {name: value * (1.0 + 3e-16) for name, value in
              definition.default_parameters().items()}
    ssv = write_parameters(tmp_path / "bush.json", values, definition)
    assert ssv == tmp_path / "bush.ssv"
    from_json = json.loads((tmp_path / "bush.json").read_text())
    assert read_parameters(ssv, definition) == from_json == values  # bit for bit


def trace(path, parameters, steps=20):
    """Forces of a component driven along a ramp, with `parameters` as given."""
    component = FmuComponent(path, "bush", parameters=parameters)
    try:
        component.start(0.0, 0.0)
        forces = []
        for k in range(1, steps + 1):
            component.begin_step()
            forces.append(component.trial(k * 1e-3, k * 2e-6)[component.load_name])
            component.accept()
        return forces
    finally:
        component.free()


@pytest.mark.parametrize("flavour", ["native", "fmi3"])
def test_a_component_takes_an_ssv_at_run_time_as_the_same_values_in_si(bush_fmus, tmp_path,
                                                                        flavour):
    ssv = n_per_mm_file(tmp_path / "soft.ssv", "k3", 8500.0)  # half the thesis's k3
    from_file = trace(bush_fmus[flavour], ssv)
    assert from_file == trace(bush_fmus[flavour], {"k3": 8.5e6})
    assert from_file != trace(bush_fmus[flavour], None)  # the file changed the FMU


def refusal(path, parameters):
    instance = FmuInstance(path, "bush")
    try:
        with pytest.raises(CouplingError) as raised:
            instance.setup(parameters)
    finally:
        instance.close()
    return str(raised.value)


def test_an_unknown_parameter_is_refused_naming_file_parameter_and_value(bush_fmus, tmp_path):
    path = tmp_path / "typo.ssv"
    write_ssv(path, "bush", [("k9", 1.5e7, "N/m", None)], STIFFNESS)
    message = refusal(bush_fmus["native"], path)
    assert str(path) in message and "'k9' = 15000000.0" in message and "no such" in message


def test_a_unit_of_another_kind_is_refused_naming_file_parameter_and_value(bush_fmus,
                                                                           tmp_path):
    path = tmp_path / "newton.ssv"
    write_ssv(path, "bush", [("k1", 6e7, "N", None)], STIFFNESS)
    message = refusal(bush_fmus["fmi3"], path)
    assert str(path) in message and "k1 = 60000000.0 N" in message and "N/m" in message


def test_a_value_the_fmu_refuses_is_said_with_the_file(bush_fmus, tmp_path):
    path = n_per_mm_file(tmp_path / "negative.ssv", "k1", -6e4)
    message = refusal(bush_fmus["native"], path)
    assert str(path) in message and "k1 = -60000000.0" in message and "positive" in message


def test_a_value_outside_the_declared_range_is_refused(bush_fmus, tmp_path):
    """A min/max the modelDescription declares is checked before the FMU is asked."""
    instance = FmuInstance(bush_fmus["native"], "bush")
    try:
        k1 = next(v for v in instance.fmu.description.modelVariables if v.name == "k1")
        k1.max = "1e8"  # as an FMU declaring max="1e8" N/m reads
        path = tmp_path / "stiff.ssv"
        write_ssv(path, "bush", [("k1", 2e8, "N/m", None)], STIFFNESS)
        with pytest.raises(CouplingError) as raised:
            instance.setup(path)
    finally:
        k1.max = None
        instance.close()
    message = str(raised.value)
    assert str(path) in message and "k1 = 200000000.0" in message
    assert "outside the range" in message and "100000000.0" in message
