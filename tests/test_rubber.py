"""Rubber components: parameter provenance, tangent stiffness, the tyre's contact."""

import math

import numpy as np
import pytest

from fmu_components.verification import reference
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.runtime.cosim import CoSimulation
from fmu_components.lab.signals import THESIS_SINES, secant_rates, sine, thesis_sine, time_grid

from conftest import default_parameters, peak_to_peak

RUBBER = ["RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion"]


@pytest.mark.parametrize("name", RUBBER)
def test_catalog_values_are_the_spec_values(name):
    """The FMUs' SI start values against the thesis tables converted by the reference
    module's own route (reference_data/thesis, spec section 1 rules)."""
    values = default_parameters(name)
    spec = reference.rubber_spec(name)
    for index, (k, c, xi) in enumerate(spec.elements, start=1):
        assert values[f"k{index}"] == pytest.approx(k, rel=1e-12)
        assert values[f"c{index}"] == pytest.approx(c, rel=1e-12)
        assert values[f"xi{index}"] == pytest.approx(xi, rel=1e-12)
    for power in range(4):
        assert values[f"elastic.a{power}"] == pytest.approx(spec.elastic[power], rel=1e-12)
    assert values["geometric.h"] == pytest.approx(spec.h, rel=1e-12)
    assert values["geometric.x_ref"] == pytest.approx(spec.x_ref, rel=1e-12)


def test_damper_constants_are_the_spec_values():
    values = default_parameters("RotaryDamper")
    spec = reference.damper_spec()
    assert (values["C1"], values["C2"], values["I"]) == (spec.C1, spec.C2, spec.I)


@pytest.mark.parametrize("name", RUBBER)
def test_time_constants_are_those_of_section_6_4(name):
    values = default_parameters(name)
    taus = [values[f"c{i}"] / (values[f"k{i}"] * values[f"xi{i}"]) for i in (1, 2, 3)]
    assert taus == pytest.approx([100.0, 0.1, 1.0], rel=0.01)


def test_torsion_torque_is_near_zero_at_the_live_angle():
    model = COMPONENTS["TrackBushTorsion"].build_model(default_parameters("TrackBushTorsion"))
    live = math.radians(10.0)
    torque = model.outputs(model.initial_state(live, 0.0), live, 0.0)[0]
    assert abs(torque) < 10.0  # N.m, against +-250 N.m over the measured range


@pytest.mark.parametrize("name", RUBBER)
@pytest.mark.parametrize("direction", [1.0, -1.0])
def test_tangent_stiffness_is_the_slope_under_fast_motion(name, direction):
    """From a state inside a hysteresis loop, a small fast move changes the force by
    stiffness * dx (the dashpots act rate-independently at |v| >> xi)."""
    amplitude = THESIS_SINES[name][1]
    model = COMPONENTS[name].build_model(default_parameters(name))
    t, x, v = thesis_sine(name, 1.3, 1e-3)
    cosim = CoSimulation(model, 1e-10, 0.0, x[0], v[0])
    for k in range(len(t) - 1):
        cosim.set_inputs(x[k], v[k])
        cosim.do_step(t[k], 1e-3)
    speed = 1e4 * amplitude  # 10^4 amplitudes per second: far above every xi
    dx = direction * 1e-5 * amplitude
    cosim.set_inputs(cosim.deflection, direction * speed)
    force, _, _, stiffness = cosim.outputs()
    cosim.do_step(cosim.time, abs(dx) / speed)
    slope = (cosim.outputs()[0] - force) / dx
    assert slope == pytest.approx(stiffness, rel=2e-3)


def test_tyre_pushes_and_never_pulls():
    model = COMPONENTS["RoadWheelTyre"].build_model(default_parameters("RoadWheelTyre"))
    t = time_grid(3.0, 1e-3)
    x = sine(t, 0.5e-3, 2e-3, 1.0)  # in and out of contact every cycle
    v = secant_rates(t, x)
    cosim = CoSimulation(model, 1e-6, 0.0, x[0], v[0])
    forces = []
    for k in range(len(t) - 1):
        cosim.set_inputs(x[k], v[k])
        assert cosim.do_step(t[k], 1e-3) is None
        forces.append(cosim.outputs())
    forces = np.array(forces)
    assert np.all(forces[:, 0] >= 0.0)
    out_of_contact = x[1:] <= 0.0
    assert out_of_contact.any()
    assert np.all(forces[out_of_contact] == 0.0)
    assert forces[:, 0].max() > 5e3


def test_tyre_leaving_and_regaining_contact_matches_the_reference():
    """Steps that cross x = 0 are split at the crossing; the reference does the same by
    its own route."""
    name = "RoadWheelTyre"
    model = COMPONENTS[name].build_model(default_parameters(name))
    step = 7e-3  # coarse, so that many steps straddle the contact point
    t = time_grid(2.1, step)
    x = sine(t, 0.5e-3, 1.5e-3, 1.0)
    v = secant_rates(t, x)
    expected = reference.solve_held_rate(name, t, x, v)["force"]
    cosim = CoSimulation(model, 1e-8, 0.0, x[0], v[0])
    forces = [cosim.outputs()[0]]
    for k in range(len(t) - 1):
        cosim.set_inputs(x[k], v[k])
        assert cosim.do_step(t[k], step) is None
        forces.append(cosim.outputs()[0])
    assert np.max(np.abs(np.array(forces) - expected)) < 1e-5 * peak_to_peak(expected)
