"""The thesis's three model structures as data for the N-branch rubber model
(runtime/catalog.py: component_definition(name, structure)).

* Values: the four-element model is Appendix 4a's (torsion bush only), the simplified Haupt
  and Sedlan model the final model's elements 1 and 3; both against the thesis tables read
  by the reference module's own route.
* Each structure builds in both flavours, and the two agree to the bit on a short run.
* The Python model of each structure matches the independent reference solve (reference.py,
  generic over branches) under the same held-rate input, within the acceptance of the
  shipped model's accuracy test (0.5 % of the output's range; the FMUs' rtol 1e-4).
* The shipped ("final") FMUs are unchanged by the structures: same variables, same states.
"""

import math

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from fmu_components.verification import reference
from fmu_components.export.build import build
from fmu_components.runtime.catalog import (COMPONENTS, STRUCTURES, component_definition,
                                             structures_of)
from fmu_components.lab.signals import THESIS_SINES, input_table, secant_rates, sine, time_grid

from conftest import peak_to_peak
from test_maxwell_closed_forms import drive

RUBBER = ["RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion"]
OTHER_STRUCTURES = [(name, s) for s in STRUCTURES if s != "final" for name in RUBBER
                    if s in structures_of(name)]
ACCEPTANCE = 0.5e-2  # of the output's peak-to-peak range, as tests/test_accuracy.py


def test_which_component_comes_in_which_structure():
    assert OTHER_STRUCTURES == [("TrackBushTorsion", "four-element"),
                                ("RoadWheelTyre", "haupt-sedlan"),
                                ("TrackBushRadial", "haupt-sedlan"),
                                ("TrackBushTorsion", "haupt-sedlan")]
    assert structures_of("RotaryDamper") == ("final",)
    with pytest.raises(KeyError, match="has no 'four-element' structure; it has: final, haupt-sedlan"):
        component_definition("TrackBushRadial", "four-element")
    for name in COMPONENTS:
        assert component_definition(name) is COMPONENTS[name]


@pytest.mark.parametrize("name, structure", OTHER_STRUCTURES)
def test_values_are_the_thesis_tables(name, structure):
    definition = component_definition(name, structure)
    values = definition.default_parameters()
    spec = reference.rubber_spec(name, structure)
    assert len(spec.elements) == len(definition.states)
    for index, (k, c, xi) in enumerate(spec.elements, start=1):
        assert values[f"k{index}"] == pytest.approx(k, rel=1e-12)
        assert values[f"c{index}"] == pytest.approx(c, rel=1e-12)
        assert values[f"xi{index}"] == pytest.approx(xi, rel=1e-12)
    shipped = COMPONENTS[name].default_parameters()
    for key in ("elastic.a0", "elastic.a1", "elastic.a2", "elastic.a3", "geometric.h",
                "geometric.x_ref"):
        assert values[key] == shipped[key]


def test_four_element_time_constants_are_appendix_4a():
    values = component_definition("TrackBushTorsion", "four-element").default_parameters()
    taus = [values[f"c{i}"] / (values[f"k{i}"] * values[f"xi{i}"]) for i in (1, 2, 3, 4)]
    # as printed: 40 / (3 * 13.3) = 1.0025
    assert taus == pytest.approx([100.0, 0.05, 1.0, 0.05], rel=0.003)


def test_parameter_and_state_names():
    four = component_definition("TrackBushTorsion", "four-element")
    assert [v.name for v in four.states] == ["state.s1", "state.s2", "state.s3", "state.s4"]
    assert [p.name for p in four.parameters][:12] == [
        f"{p}{i}" for i in (1, 2, 3, 4) for p in ("k", "c", "xi")]
    simple = component_definition("TrackBushRadial", "haupt-sedlan")
    assert [v.name for v in simple.states] == ["state.s1", "state.s2"]
    assert "k3" not in simple.default_parameters()
    assert "simplified Haupt and Sedlan" in simple.description
    final = COMPONENTS["TrackBushRadial"]
    assert [v.name for v in final.states] == ["state.s", "state.w", "state.r"]


@pytest.mark.parametrize("name, structure", [(n, "final") for n in RUBBER] + OTHER_STRUCTURES)
def test_python_model_matches_the_reference(name, structure):
    mean, amplitude, frequency = THESIS_SINES[name]
    t = time_grid(1.0 / frequency, 1e-3)
    x = sine(t, mean, amplitude, frequency)
    rates = secant_rates(t, x)
    definition = component_definition(name, structure)
    loads = drive(definition.build_model(definition.default_parameters()), t, x,
                  rtol=definition.default_experiment["tolerance"])
    expected = reference.solve_held_rate(name, t, x, rates, structure=structure)
    load = reference.LOAD_NAMES[name]
    error = np.max(np.abs(loads - expected[load])) / peak_to_peak(expected[load])
    assert error <= ACCEPTANCE


def test_structures_differ_where_the_thesis_says():
    """Section 6.3: the nested elements give the rapid initial relaxation the simplified
    Haupt and Sedlan model lacks. After a 0.1 s ramp 10 -> 25 deg, the four-element torque
    falls faster over the first 0.1 s of the hold than the final one's, and the Haupt and
    Sedlan one's slowest."""
    from fmu_components.lab import rig

    drops = {}
    for structure in structures_of("TrackBushTorsion"):
        setup = rig.make_setup("TrackBushTorsion", structure)
        times, _, torque = rig.relaxation_record(setup, math.radians(10), math.radians(15),
                                                 hold=1.0)
        peak = np.interp(rig.RISE_TIME, times, torque)
        drops[structure] = peak - np.interp(rig.RISE_TIME + 0.1, times, torque)
    assert drops["four-element"] > drops["final"] > drops["haupt-sedlan"] > 0.0


@pytest.fixture(scope="module")
def structure_fmus(tmp_path_factory):
    """{structure: {flavour: {name: path}}} of every structure but the shipped one."""
    built = {}
    for structure in STRUCTURES:
        if structure == "final":
            continue
        names = [n for n in RUBBER if structure in structures_of(n)]
        built[structure] = build(names, tmp_path_factory.mktemp(structure), structure=structure)
    return built


@pytest.mark.parametrize("name, structure", OTHER_STRUCTURES)
def test_both_flavours_build_and_agree_to_the_bit(structure_fmus, name, structure):
    native = structure_fmus[structure]["native"][name]
    python = structure_fmus[structure]["python"][name]
    definition = component_definition(name, structure)
    descriptions = [read_model_description(str(p)) for p in (native, python)]
    for description in descriptions:
        assert [v.name for v in description.modelVariables] == [
            v.name for v in (*definition.variables, *definition.switches)]
    assert descriptions[0].guid != descriptions[1].guid
    mean, amplitude, frequency = THESIS_SINES[name]
    t = time_grid(2.0 / frequency, 1e-3)
    inputs = input_table(name, t, sine(t, mean, amplitude, frequency))
    results = [simulate_fmu(str(p), stop_time=t[-1], output_interval=1e-3, input=inputs)
               for p in (native, python)]
    for output in results[0].dtype.names:
        assert np.array_equal(results[0][output], results[1][output]), output
    load = definition.outputs[0].name
    assert peak_to_peak(results[0][load]) > 0.0


def test_another_structure_has_another_guid_than_the_shipped_fmu(structure_fmus, all_fmus):
    for flavour in ("native", "python"):
        shipped = read_model_description(str(all_fmus[flavour]["TrackBushTorsion"])).guid
        for structure in structure_fmus:
            other = read_model_description(
                str(structure_fmus[structure][flavour]["TrackBushTorsion"])).guid
            assert other != shipped, (flavour, structure)


@pytest.mark.parametrize("name, structure", [(name, "final") for name in sorted(COMPONENTS)]
                         + OTHER_STRUCTURES)
def test_the_state_nominals_are_read_from_the_definition(name, structure):
    """What the modelDescription declares, from the nominals' expressions alone: the
    compiled model's own figures, to the bit, for the thesis's values and a part's own."""
    definition = component_definition(name, structure)
    for values in (None, {p.name: 2.5 * p.start for p in definition.parameters}):
        model = definition.build_model(values or definition.default_parameters())
        assert definition.state_nominals(values) == model.nominals
        assert len(model.nominals) == len(definition.states)

