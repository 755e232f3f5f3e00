"""Parameter sets as SSP 1.0 parameter-value files (ssv.py, export/parameters.py): written as
SSP's schema says, read back bit for bit, other units of the same kind converted to SI, and
every mistake refused naming the file, the parameter and the value."""

import pytest
from fmpy.ssp.ssd import read_ssv as fmpy_read_ssv

from fmu_components.export.parameters import (ParameterError, parameter_set,
                                               write_parameter_set)
from fmu_components.runtime.catalog import COMPONENTS, component_definition
from fmu_components.ssv import SsvError, read_ssv

BUSH = "TrackBushRadial"


def write_text(path, parameters, units=""):
    path.write_text(
        '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"'
        ' xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="t">'
        f"<ssv:Parameters>{parameters}</ssv:Parameters>"
        + (f"<ssv:Units>{units}</ssv:Units>" if units else "") + "</ssv:ParameterSet>")
    return path


@pytest.mark.parametrize("component", COMPONENTS)
def test_a_written_set_passes_ssp_schema_and_reads_back_bit_for_bit(tmp_path, component):
    definition = component_definition(component)
    values = definition.default_parameters()
    values = {name: value * (1.0 + 1e-15) for name, value in values.items()}  # all 17 digits
    path = tmp_path / "set.ssv"
    write_parameter_set(path, definition, values, f"{component} thesis")
    parameter_set_read = fmpy_read_ssv(str(path), validate=True)  # SSP 1.0's own schema
    assert [p.name for p in parameter_set_read.parameters] == list(values)
    assert [p.unit for p in parameter_set_read.parameters] == [
        p.unit for p in definition.parameters]
    assert parameter_set(component, "final", path) == values


def test_a_value_in_another_unit_of_the_same_kind_is_taken_in_si(tmp_path):
    path = write_text(tmp_path / "mm.ssv",
                      '<ssv:Parameter name="k1"><ssv:Real value="60000" unit="N/mm"/>'
                      "</ssv:Parameter>",
                      '<ssc:Unit name="N/mm"><ssc:BaseUnit kg="1" s="-2" factor="1000"/>'
                      "</ssc:Unit>")
    assert parameter_set(BUSH, "final", path)["k1"] == 6e7


def test_a_value_without_a_unit_is_in_the_variables_own(tmp_path):
    path = write_text(tmp_path / "bare.ssv",
                      '<ssv:Parameter name="k1"><ssv:Real value="5e7"/></ssv:Parameter>')
    assert parameter_set(BUSH, "final", path)["k1"] == 5e7


@pytest.mark.parametrize("parameter, units, said", [
    ('<ssv:Parameter name="k9"><ssv:Real value="1"/></ssv:Parameter>', "",
     "parameter 'k9' = 1.0"),
    ('<ssv:Parameter name="k1"><ssv:Real value="2" unit="N"/></ssv:Parameter>',
     '<ssc:Unit name="N"><ssc:BaseUnit kg="1" m="1" s="-2"/></ssc:Unit>',
     "k1 = 2.0 N is not in a unit of N/m's kind"),
    ('<ssv:Parameter name="k1"><ssv:Real value="2" unit="N/mm"/></ssv:Parameter>', "",
     "k1 = 2.0 N/mm: the file defines no unit 'N/mm'"),
    ('<ssv:Parameter name="k1"><ssv:Real value="-6e7"/></ssv:Parameter>', "",
     "k1 = -60000000.0 N/m must be positive"),
    ('<ssv:Parameter name="k1"><ssv:Real value="INF"/></ssv:Parameter>', "",
     "k1 = inf is not a finite number"),
    ('<ssv:Parameter name="k1"><ssv:Integer value="3"/></ssv:Parameter>', "",
     "'k1' is Integer"),
])
def test_a_mistake_is_refused_naming_the_file_the_parameter_and_the_value(tmp_path, parameter,
                                                                          units, said):
    path = write_text(tmp_path / "wrong.ssv", parameter, units)
    with pytest.raises(ParameterError) as refused:
        parameter_set(BUSH, "final", path)
    message = str(refused.value)
    assert said in message and str(path) in message


def test_a_file_that_is_no_parameter_set_is_refused(tmp_path):
    path = tmp_path / "other.ssv"
    path.write_text("<ParameterSet/>")
    with pytest.raises(SsvError, match="not an SSP 1.0"):
        read_ssv(path)
    path.write_text("<ssv:ParameterSet")
    with pytest.raises(SsvError, match="is not XML"):
        read_ssv(path)
