"""First-harmonic analysis (fmu_components.lab.harmonics) against linear closed forms.

* Kelvin element F = k x + c dx/dt under x = x0 + A sin(wt): |K*| = sqrt(k^2 + (c w)^2),
  tan(delta) = c w / k, energy per cycle pi c w A^2, secant stiffness k.
* Maxwell element (spring k in series with dashpot c, tau = c/k), from rest:
  K* = k i w tau / (1 + i w tau), so |K*| = k w tau / sqrt(1 + (w tau)^2),
  tan(delta) = 1/(w tau), energy pi A^2 K'' = pi A^2 k w tau / (1 + (w tau)^2), secant
  stiffness K' = |K*| cos(delta). Its exact response carries the start-up transient
  -A |K*| sin(delta) exp(-t/tau), which the analysis of the last cycles must not see.
"""

import math

import numpy as np
import pytest

from fmu_components.lab.harmonics import HarmonicError, first_harmonic

K, C, A, X0, FREQUENCY = 2.0e6, 3.0e3, 1.0e-4, 3.0e-4, 1.7
OMEGA = 2.0 * math.pi * FREQUENCY


def kelvin_record(times, third_harmonic=0.0):
    x = X0 + A * np.sin(OMEGA * times)
    force = K * x + C * A * OMEGA * np.cos(OMEGA * times)
    return x, force + third_harmonic * np.sin(3.0 * OMEGA * times)


def assert_kelvin_element(result, rel):
    """|K*|, loss angle and energy per cycle of the Kelvin element."""
    assert result.dynamic_stiffness == pytest.approx(math.hypot(K, C * OMEGA), rel=rel)
    assert math.tan(math.radians(result.loss_angle_deg)) == pytest.approx(C * OMEGA / K, rel=rel)
    assert result.energy_per_cycle == pytest.approx(math.pi * C * OMEGA * A ** 2, rel=rel)


def uniform_times(cycles, per_cycle):
    return np.arange(cycles * per_cycle + 1) / (per_cycle * FREQUENCY)


@pytest.mark.parametrize("per_cycle", [64, 400, 401])
def test_kelvin_element_on_uniform_cycles(per_cycle):
    times = uniform_times(3, per_cycle)
    result = first_harmonic(times, *kelvin_record(times), FREQUENCY)
    assert result.cycles == 3
    assert_kelvin_element(result, rel=1e-12)
    assert result.mean_deflection == pytest.approx(X0, rel=1e-12)
    assert result.mean_force == pytest.approx(K * X0, rel=1e-12)
    # equivalent spring and dashpot of the damper's report: the element itself
    assert result.equivalent_stiffness == pytest.approx(K, rel=1e-12)
    assert result.equivalent_damping == pytest.approx(C, rel=1e-12)
    if per_cycle % 4 == 0:  # a sample at each tip: the secant is exact
        assert result.secant_stiffness == pytest.approx(K, rel=1e-12)


def test_higher_harmonics_change_neither_stiffness_nor_energy_but_the_secant():
    times = uniform_times(2, 400)
    distortion = 0.05 * K * A
    result = first_harmonic(times, *kelvin_record(times, distortion), FREQUENCY)
    assert_kelvin_element(result, rel=1e-12)
    # sin(3wt) is -1 at the top tip and +1 at the bottom one
    assert result.secant_stiffness == pytest.approx(K - distortion / A, rel=1e-12)


def test_kelvin_element_on_scattered_samples():
    """Not uniformly sampled: the trapezoidal path, accurate to its sampling."""
    times = np.sort(np.random.default_rng(12).uniform(0.0, 3.0 / FREQUENCY, 20000))
    result = first_harmonic(times, *kelvin_record(times), FREQUENCY)
    assert result.cycles == 2
    assert_kelvin_element(result, rel=1e-4)
    assert result.secant_stiffness == pytest.approx(K, rel=1e-3)


@pytest.mark.parametrize("omega_tau", [0.1, 1.0, 10.0])
def test_maxwell_element_after_its_transient(omega_tau):
    k = K
    tau = omega_tau / OMEGA
    modulus = k * omega_tau / math.sqrt(1.0 + omega_tau ** 2)
    delta = math.atan2(1.0, omega_tau)
    cycles = int(math.ceil(40.0 * tau * FREQUENCY)) + 2  # the transient decays by e^-40
    times = uniform_times(cycles, 256)
    x = A * np.sin(OMEGA * times)
    force = A * modulus * (np.sin(OMEGA * times + delta) - math.sin(delta) * np.exp(-times / tau))
    # the same force from the element's equation dF/dt = k dx/dt - F/tau, as a check of the
    # closed form itself
    rate = A * modulus * (OMEGA * np.cos(OMEGA * times + delta)
                          + math.sin(delta) / tau * np.exp(-times / tau))
    np.testing.assert_allclose(rate, k * A * OMEGA * np.cos(OMEGA * times) - force / tau,
                               rtol=0.0, atol=1e-9 * k * A * OMEGA)
    assert force[0] == pytest.approx(0.0, abs=1e-12 * k * A)  # from rest
    result = first_harmonic(times, x, force, FREQUENCY, cycles=2)
    assert result.dynamic_stiffness == pytest.approx(modulus, rel=1e-12)
    assert result.loss_angle_deg == pytest.approx(math.degrees(delta), rel=1e-12)
    assert result.energy_per_cycle == pytest.approx(
        math.pi * A ** 2 * k * omega_tau / (1.0 + omega_tau ** 2), rel=1e-12)
    assert result.secant_stiffness == pytest.approx(modulus * math.cos(delta), rel=1e-12)
    assert result.storage_stiffness == pytest.approx(k * omega_tau ** 2 / (1 + omega_tau ** 2),
                                                     rel=1e-12)


def test_a_record_with_the_start_transient_in_it_differs():
    """The analysis window matters: the Maxwell start-up left in shifts the result."""
    tau = 1.0 / OMEGA
    times = uniform_times(30, 256)
    force = A * K / math.sqrt(2.0) * (np.sin(OMEGA * times + math.pi / 4)
                                       - math.sin(math.pi / 4) * np.exp(-times / tau))
    x = A * np.sin(OMEGA * times)
    first = first_harmonic(times[:257], x[:257], force[:257], FREQUENCY)
    last = first_harmonic(times, x, force, FREQUENCY, cycles=1)
    assert last.change_from(first) > 1e-3
    assert last.change_from(first_harmonic(times, x, force, FREQUENCY, cycles=2)) < 1e-12


@pytest.mark.parametrize("times, deflection, force, frequency, message", [
    ([0.0, 0.1, 0.2], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0], 1.0, "less than one cycle"),
    ([0.0, 0.5, 1.0, 1.5], [0.0, 1.0, math.nan, 0.0], [0.0] * 4, 1.0, "finite"),
    ([0.0, 0.5, 0.5, 1.5], [0.0] * 4, [0.0] * 4, 1.0, "increase"),
    ([0.0, 0.5, 1.0, 1.5], [0.0] * 4, [0.0] * 3, 1.0, "one length"),
    ([0.0, 0.5, 1.0, 1.5], [0.0] * 4, [0.0] * 4, 0.0, "positive"),
    ([0.0, 0.25, 0.5, 0.75, 1.0], [1.0] * 5, [0.0] * 5, 1.0, "no first harmonic"),
])
def test_records_that_cannot_be_analysed(times, deflection, force, frequency, message):
    with pytest.raises(HarmonicError, match=message):
        first_harmonic(times, deflection, force, frequency)
