"""The single nonlinear Maxwell element against the thesis's closed forms.

* Appendix 1 / Eq. 4.2.7-2: for |v| >> xi the element is rate independent, and from a
  turning point (x0, F0) the force follows F = c*s - (c*s - F0)*exp(-k*s*(x - x0)/c),
  s = sgn(v).
* Appendix 2 / Eq. 4.2.7-3: with the deflection held, F = F0*exp(-xi*k*t/c).

The element is exercised through both code paths of the rubber model: a branch without
nesting (exact exponential update) and a branch whose nested element is made inert
(k2 -> 0), which goes through the stiff integrator. One more case runs through the built
TrackBushTorsion FMU, re-parameterised to a single element.
"""

import math

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_components.runtime.cosim import CoSimulation
from fmu_components.runtime.model import Model
from fmu_components.runtime.rubber import Branch, MaxwellElement, rubber_equations
from fmu_components.lab.signals import input_table, ramp_and_hold

K, C = 1.5e5, 500.0  # the tyre's branch B (Appendix 4b, SI)


def single_element_model(xi, integrated):
    element = MaxwellElement(K, C, xi)
    if integrated:
        branch = Branch(element, nested=MaxwellElement(K * 1e-12, C, xi))
    else:
        branch = Branch(element)
    return Model(rubber_equations([branch], elastic=(0.0, 0.0, 0.0, 0.0), geometric_slope=0.0,
                                  geometric_reference=0.0))


def drive(model, times, deflection, rtol=1e-9):
    """Force after each step, the rate held as the secant of the deflection samples."""
    rates = np.diff(deflection) / np.diff(times)
    cosim = CoSimulation(model, rtol, times[0], deflection[0], rates[0])
    forces = [cosim.outputs()[0]]
    for k in range(len(times) - 1):
        assert cosim.set_inputs(deflection[k], rates[k]) is None
        assert cosim.do_step(times[k], times[k + 1] - times[k]) is None
        forces.append(cosim.outputs()[0])
    return np.array(forces)


def triangle(amplitude, speed, step):
    """0 -> +A -> -A -> +A at constant speed: three monotone segments."""
    legs = [(0.0, amplitude), (amplitude, -amplitude), (-amplitude, amplitude)]
    times, deflection, t = [0.0], [0.0], 0.0
    for start, end in legs:
        n = int(round(abs(end - start) / speed / step))
        for i in range(1, n + 1):
            t += step
            times.append(t)
            deflection.append(start + (end - start) * i / n)
    return np.array(times), np.array(deflection)


def closed_form_loop(deflection):
    """Eq. 4.2.7-2 applied segment by segment, starting relaxed at x = 0."""
    forces = [0.0]
    x0, f0 = deflection[0], 0.0
    sign = 1.0
    for k in range(1, len(deflection)):
        s = math.copysign(1.0, deflection[k] - deflection[k - 1])
        if s != sign:  # turning point at the previous sample
            x0, f0, sign = deflection[k - 1], forces[-1], s
        forces.append(C * s - (C * s - f0) * math.exp(-K * s * (deflection[k] - x0) / C))
    return np.array(forces)


@pytest.mark.parametrize("integrated", [False, True], ids=["exact-update", "integrator"])
def test_time_independent_loop_matches_eq_4_2_7_2(integrated):
    speed = 0.01  # m/s, so xi/|v| = 1e-7: the small-xi limit of Appendix 1
    amplitude = 3 * C / K
    times, deflection = triangle(amplitude, speed, step=1e-3)
    forces = drive(single_element_model(xi=1e-9, integrated=integrated), times, deflection)
    expected = closed_form_loop(deflection)
    # The loop spans +-C; the closed form neglects xi/|v| = 1e-7.
    assert np.max(np.abs(forces - expected)) < 1e-5 * C
    # The loop is the asymmetric exponential one: it nearly saturates at +-c.
    assert forces.max() > 0.99 * C and forces.min() < -0.99 * C


@pytest.mark.parametrize("integrated", [False, True], ids=["exact-update", "integrator"])
def test_stress_relaxation_matches_eq_4_2_7_3(integrated):
    xi = 1e-4  # tau = c/(k xi) = 33 s
    tau = C / (K * xi)
    step = 0.01
    times = np.arange(0, int(round(100.0 / step)) + 1) * step
    ramp_time = 0.05
    deflection = ramp_and_hold(times, 0.0, 5e-3, ramp_time)
    forces = drive(single_element_model(xi, integrated), times, deflection)
    hold = times >= ramp_time
    f0 = forces[hold][0]
    expected = f0 * np.exp(-(times[hold] - times[hold][0]) / tau)
    assert f0 > 0.5 * C  # the ramp loaded the element well into its nonlinear range
    assert np.max(np.abs(forces[hold] - expected)) < 1e-6 * f0
    assert forces[-1] < f0 * math.exp(-2.9)  # three time constants of decay happened


def test_relaxation_through_the_fmu_reparameterised_to_one_element(built_fmus):
    """The torsion FMU with branch A made negligible and no elastic torque is a single
    Maxwell element (k3, c3, xi3); its relaxation follows Eq. 4.2.7-3."""
    k3, c3, xi3 = 171.88733853924697, 40.0, 0.23212879051524585 / 10  # tau = 10 s
    start_values = {"k1": 1e-9, "k2": 1e-9, "elastic.a0": 0.0, "elastic.a1": 0.0,
                    "geometric.h": 0.0, "xi3": xi3}
    step = 1e-2
    times = np.arange(int(round(30.0 / step)) + 1) * step
    angle = ramp_and_hold(times, 0.0, math.radians(20.0), 0.1)
    result = simulate_fmu(str(built_fmus["TrackBushTorsion"]), stop_time=times[-1],
                          output_interval=step, start_values=start_values,
                          input=input_table("TrackBushTorsion", times, angle),
                          output=["torque"], relative_tolerance=1e-8)
    torque = result["torque"]
    hold = result["time"] >= 0.1 - 1e-12
    t_hold = result["time"][hold] - result["time"][hold][0]
    expected = torque[hold][0] * np.exp(-xi3 * k3 * t_hold / c3)
    assert torque[hold][0] > 0.5 * c3
    assert np.max(np.abs(torque[hold] - expected)) < 1e-4 * torque[hold][0]
