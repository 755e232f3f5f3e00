"""The shared stiff integrator: order, stability, error control, valid region, failures."""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from fmu_components.runtime.catalog import COMPONENTS, ROTARY_DAMPER
from fmu_components.runtime.cosim import CoSimulation
from fmu_components.runtime.damper import Z_LIMIT
from fmu_components.runtime.expressions import Assign, Number, Symbol, total
from fmu_components.runtime.integrator import ROS34PW2, Rosenbrock
from fmu_components.runtime.model import Equations, Model
from fmu_components.runtime.rubber import Branch, MaxwellElement, rubber_equations
from fmu_components.lab.signals import thesis_sine


def system(n, stage, jacobian, scale=1.0, region=None):
    """An n-state integrator system: f_i and j_i_k as expressions of Y."""
    Y = [Symbol(f"Y{i}") for i in range(n)]
    return Model(Equations(
        integrated=n, state_size=n, region=None if region is None else region(Y),
        stage=[Assign(Symbol(f"f{i}"), f) for i, f in enumerate(stage(Y))],
        jacobian=[Assign(Symbol(f"j{i}_{k}"), value) for i, row in enumerate(jacobian(Y))
                  for k, value in enumerate(row)],
        initial_state=[0.0] * n, outputs=[], state_scale=[scale] * n))


def linear_system(matrix, scale=1.0):
    """y' = A y: known solution expm(A t) y0."""
    matrix = [[float(a) for a in row] for row in matrix]
    model = system(len(matrix), lambda Y: [total([a * Y[j] for j, a in enumerate(row)]) for row in matrix],
                   lambda Y: matrix, scale)
    model.matrix = matrix
    return model


def prothero_robinson(lam):
    """y' = lam (y - s) + c, s' = c, c' = -s: from y(0) = s(0) = 0, c(0) = 1 the solution
    is y = s = sin t, c = cos t, with stiffness lam in y (the Prothero-Robinson problem,
    autonomous and linear)."""
    return linear_system([[lam, -lam, 1.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


# A stiff, non-normal 2x2 system: eigenvalues -1 and -1e4.
P = np.array([[1.0, 1.0], [1.0, 2.0]])
STIFF = P @ np.diag([-1.0, -1e4]) @ np.linalg.inv(P)


def fixed_step_error(model, y0, t_end, n):
    integrator = Rosenbrock(rtol=1.0)
    y = list(y0)
    h = t_end / n
    for _ in range(n):
        y, _ = integrator.step(model, y, 0.0, h)
    exact = expm(np.array(model.matrix) * t_end) @ np.array(y0)
    return float(np.max(np.abs(np.array(y) - exact)))


def standard_form(tab):
    """(alpha, Gamma, b, bhat) recovered from the transformed coefficients the integrator
    runs on: Gamma^-1 = diag(1/gamma) - C, alpha = A Gamma, b = m Gamma, bhat = b - e Gamma."""
    stages = len(tab.m)
    a = np.zeros((stages, stages))
    c = np.zeros((stages, stages))
    for i in range(stages):
        a[i, :i] = tab.a[i]
        c[i, :i] = tab.c[i]
    gamma = np.linalg.inv(np.eye(stages) / tab.gamma - c)
    b = np.array(tab.m) @ gamma
    return a @ gamma, gamma, b, b - np.array(tab.e) @ gamma


def test_transformed_coefficients_reproduce_the_published_tableau():
    alpha, gamma, b, bhat = standard_form(ROS34PW2)
    published = [np.array(part) for part in ROS34PW2.standard_form]
    for ours, theirs in zip((alpha, gamma, b, bhat), published):
        assert np.max(np.abs(ours - theirs)) < 1e-13


def test_tableau_satisfies_order_conditions_and_is_l_stable():
    tab = ROS34PW2
    alpha, gamma, b, bhat = standard_form(tab)
    g = tab.gamma
    beta = alpha + np.tril(gamma, -1)
    a_sum, b_sum = alpha.sum(axis=1), beta.sum(axis=1)
    for weights, order in ((b, 3), (bhat, 2)):
        assert weights.sum() == pytest.approx(1.0, abs=1e-14)
        assert weights @ b_sum == pytest.approx(0.5 - g, abs=1e-14)
        conditions_3 = (weights @ a_sum ** 2 - 1 / 3, weights @ beta @ b_sum - (1 / 6 - g + g * g))
        if order == 3:
            assert max(map(abs, conditions_3)) < 1e-14
        else:
            assert max(map(abs, conditions_3)) > 1e-3  # genuinely one order lower
    # L-stable: the solution of y' = lambda y vanishes as h*lambda -> -infinity.
    very_stiff = linear_system([[-1e12]])
    y1, _ = Rosenbrock().step(very_stiff, [1.0], 0.0, 1.0)
    assert abs(y1[0]) < 1e-9


def test_observed_order_is_three_on_a_stiff_problem():
    errors = [fixed_step_error(linear_system(STIFF), [1.0, 0.5], 1.0, n) for n in (20, 40, 80, 160)]
    orders = [math.log2(e0 / e1) for e0, e1 in zip(errors, errors[1:])]
    assert all(2.7 < p < 3.3 for p in orders), orders


@pytest.mark.parametrize("rtol", [1e-3, 1e-5, 1e-7])
def test_error_control_meets_the_tolerance_on_prothero_robinson(rtol):
    model = prothero_robinson(lam=-1e5)
    integrator = Rosenbrock(rtol)
    y = [0.0, 0.0, 1.0]
    for k in range(10):  # ten communication steps of 0.2 s
        assert integrator.integrate(model, y, 0.0, 0.2) is None
        assert abs(y[0] - math.sin(0.2 * (k + 1))) < 10 * rtol


def test_tighter_tolerance_costs_more_steps_and_gives_smaller_error():
    results = []
    for rtol in (1e-3, 1e-6):
        integrator = Rosenbrock(rtol)
        y = [1.0, 0.5]
        assert integrator.integrate(linear_system(STIFF), y, 0.0, 1.0) is None
        exact = expm(STIFF) @ np.array([1.0, 0.5])
        results.append((integrator.accepted_steps, float(np.max(np.abs(np.array(y) - exact)))))
    (steps_loose, error_loose), (steps_tight, error_tight) = results
    assert steps_tight > steps_loose
    assert error_tight < error_loose / 50


def asymptote():
    """y' = 1 - y approaches 1 from below; the model is defined only for y < 1. An
    L-stable, stiffly accurate step of any size lands exactly on 1 and must be rejected."""
    return system(1, lambda Y: [1.0 - Y[0]], lambda Y: [[-1.0]], region=lambda Y: Y[0] < 1.0)


def test_steps_leaving_the_valid_region_are_rejected_not_clipped():
    integrator = Rosenbrock(1e-4)
    integrator.h_next = 1e3  # a first guess far too large
    y = [0.0]
    assert integrator.integrate(asymptote(), y, 0.0, 30.0) is None
    assert y[0] < 1.0
    assert y[0] == pytest.approx(1.0 - math.exp(-30.0), abs=1e-6)
    assert integrator.rejected_steps > 0


def broken():
    """A right-hand side that is never finite: inf * 0."""
    return system(1, lambda Y: [(Number(1e308) * 10.0) * (Y[0] * 0.0)], lambda Y: [[-1.0]])


def test_failure_comes_back_as_a_message_with_the_state_untouched():
    integrator = Rosenbrock()
    y = [0.25]
    message = integrator.integrate(broken(), y, 0.0, 1e-3)
    assert message and "step size" in message
    assert y == [0.25]


@pytest.mark.parametrize("duration", [1e-6, 1e-3, 1.0])
def test_damper_system_integrates_any_step_from_1e_6_to_1_s(duration):
    """The stiffest system here (rotor mode ~20 us) over one held-rate interval."""
    damper = ROTARY_DAMPER.build_model(ROTARY_DAMPER.default_parameters())
    integrator = Rosenbrock(1e-4)
    y = [0.0, 0.0]  # gas-spring coordinate z, rotor rate; the arm turns at 1 rad/s
    assert integrator.integrate(damper, y, 1.0, duration) is None
    assert abs(y[0]) < Z_LIMIT
    if duration == 1.0:  # long enough to settle: rotor follows the arm, gas holds Td(1)
        assert y[1] == pytest.approx(1.0, abs=1e-4)
        assert 800.0 * math.sinh(2.0 * y[0]) == pytest.approx(3250.0, rel=1e-3)


# --- the components' right-hand sides, compiled into the stages -----------------------

def _model(name):
    definition = COMPONENTS[name]
    return definition.build_model(definition.default_parameters())


# States and held inputs on both sides of every |.| in the equations, for each system.
SYSTEM_POINTS = {
    "RoadWheelTyre": [([2e-4, 5e-5], 0.05), ([-1e-4, 3e-4], -0.02), ([3e-4, -2e-4], 0.0)],
    "TrackBushRadial": [([1e-4, 2e-5], 0.01), ([-2e-4, 1e-4], -0.003)],
    "TrackBushTorsion": [([1e-3, -2e-4], 0.3), ([-5e-4, 1e-3], -0.1)],
    "RotaryDamper": [([0.3, 0.5], 1.0), ([-1.2, -3.0], -2.0), ([2.5, 20.0], 0.0)],
}


@pytest.mark.parametrize("name", sorted(SYSTEM_POINTS))
def test_analytic_jacobian_matches_finite_differences_of_the_compiled_rhs(name):
    model = _model(name)
    rhs = model.rhs
    for y, u in SYSTEM_POINTS[name]:
        analytic = np.array(model.jacobian(y, u), dtype=float)
        numeric = np.empty_like(analytic)
        for j in range(len(y)):
            step = 1e-7 * max(abs(y[j]), model.state_scale[j] * 1e-3)
            up, down = list(y), list(y)
            up[j] += step
            down[j] -= step
            numeric[:, j] = (np.array(rhs(up, u)) - np.array(rhs(down, u))) / (2 * step)
        assert np.allclose(analytic, numeric, rtol=1e-6, atol=1e-9 * np.abs(analytic).max())


def test_rubber_rhs_is_the_nested_maxwell_branch():
    """The compiled equations against the branch equations written out here (rubber.py)."""
    model = _model("RoadWheelTyre")
    values = COMPONENTS["RoadWheelTyre"].default_parameters()
    k1, c1, xi1, k2, c2, xi2 = (values[n] for n in ("k1", "c1", "xi1", "k2", "c2", "xi2"))
    for (s, w), v in SYSTEM_POINTS["RoadWheelTyre"]:
        ds = v - (k1 * s + k2 * w) * (abs(v) + xi1) / c1
        dw = ds - k2 / c2 * w * (abs(ds) + xi2)
        assert model.rhs([s, w], v) == pytest.approx((ds, dw), rel=1e-14, abs=1e-300)


def test_step_sizes_differing_in_the_last_bits_take_the_same_steps():
    """A host that counts time in integer nanoseconds, or adds up step sizes, hands over
    communication steps a few ulps apart: the integrator must not make different
    decisions (a fresh W every step) from those of a host with exact steps."""
    model = _model("RotaryDamper")
    exact, jittered = Rosenbrock(1e-4), Rosenbrock(1e-4)
    y_exact, y_jittered = [0.0, 0.0], [0.0, 0.0]
    for k in range(200):
        u = 0.21 * 2 * math.pi * 0.75 * math.cos(2 * math.pi * 0.75 * k * 1e-3)
        assert exact.integrate(model, y_exact, u, 1e-3) is None
        h = (k + 1) * 1e-3 - k * 1e-3  # what a host computing t_k = k*h hands over
        assert jittered.integrate(model, y_jittered, u, h) is None
    assert (exact.accepted_steps, exact.rejected_steps) == (
        jittered.accepted_steps, jittered.rejected_steps)
    assert y_jittered == pytest.approx(y_exact, rel=1e-12, abs=1e-15)


# --- the single-step path: one generated function per communication step -------------

def _run(model, inputs, single_step=True):
    """Outputs and state after each step of a CoSimulation fed (x, v, h) per step."""
    x0, v0, _ = inputs[0]
    cosim = CoSimulation(model, 1e-4, 0.0, x0, v0)
    if not single_step:
        cosim._single_step = None  # every step through model.advance and integrate
    rows = []
    for x, v, h in inputs:
        assert cosim.set_inputs(x, v) is None
        assert cosim.do_step(cosim.time, h) is None
        rows.append((tuple(cosim.outputs()), tuple(cosim.state), cosim.integrator.h_next,
                     cosim.integrator.w))
    return rows


def _inputs(name, amplitude, frequency, jittered):
    """A sine sampled at its step points (secant rates) or, jittered, with steps from
    0.3 to 1.8 ms and the angle resampled off the path the rate predicts."""
    rows, t = [], 0.0
    for k in range(1500):
        h = 1e-3 * (0.3 + 0.25 * (k % 7)) if jittered else 1e-3
        x = amplitude * math.sin(2 * math.pi * frequency * t)
        x_next = amplitude * math.sin(2 * math.pi * frequency * (t + h))
        rows.append((x, (x_next - x) / h, h))
        t += h
    return rows


# Amplitudes that take the tyre off the ground and the damper into blow-off.
SINGLE_STEP_CASES = {"RoadWheelTyre": (4e-3, 3.0), "TrackBushRadial": (3e-4, 5.0),
                     "TrackBushTorsion": (0.3, 2.0), "RotaryDamper": (0.2, 3.0)}


@pytest.mark.parametrize("jittered", [False, True])
@pytest.mark.parametrize("name", sorted(SINGLE_STEP_CASES))
def test_single_step_path_is_bit_identical_to_the_general_path(name, jittered):
    """The fused path only saves calls: every output, state entry and integrator memory
    the same to the last bit as model.advance + integrate, including the steps it hands
    back (tyre crossings, rejections, steps the controller splits)."""
    inputs = _inputs(name, *SINGLE_STEP_CASES[name], jittered)
    assert _run(_model(name), inputs) == _run(_model(name), inputs, single_step=False)


@pytest.mark.parametrize("name", sorted(SINGLE_STEP_CASES))
def test_single_step_path_takes_the_thesis_sine_at_1_ms(name):
    """The benchmark's standard input: the fused path takes (almost) every step, so the
    cost it measures is that path's."""
    model = _model(name)
    cosim = CoSimulation(model, 1e-4)
    single_step = cosim._single_step
    taken = []
    cosim._single_step = lambda *args: taken.append(single_step(*args)) or taken[-1]
    _, x, v = thesis_sine(name, 2.0, 1e-3)
    for k in range(len(x) - 1):
        cosim.set_inputs(x[k], v[k])
        assert cosim.do_step(cosim.time, 1e-3) is None
    assert sum(taken) >= 0.99 * len(taken)


def test_rubber_with_two_nested_branches_takes_the_general_n_state_path():
    """Four integrated states (the factorisation by inversion, a block Jacobian): the
    compiled Jacobian matches finite differences and both step paths agree."""
    values = COMPONENTS["TrackBushRadial"].default_parameters()
    k1, c1, xi1, k2, c2, xi2, k3, c3, xi3 = (values[f"{p}{i}"] for i in (1, 2, 3)
                                             for p in ("k", "c", "xi"))
    branch = Branch(MaxwellElement(k1, c1, xi1), nested=MaxwellElement(k2, c2, xi2))
    slower = Branch(MaxwellElement(0.5 * k1, 4.0 * c1, xi1),
                    nested=MaxwellElement(0.3 * k2, 0.3 * c2, xi2))
    plain = Branch(MaxwellElement(k3, c3, xi3))
    model = Model(rubber_equations([branch, slower, plain], [values[f"elastic.a{p}"] for p in range(4)],
                                   0.0, 0.0))
    rhs = model.rhs
    y, u = [1e-4, 2e-5, -5e-5, 1e-5], 0.01
    analytic = np.array(model.jacobian(y, u))
    assert analytic[0, 2] == analytic[2, 0] == 0.0  # the branches do not interact
    for j in range(4):
        step = 1e-7 * max(abs(y[j]), model.state_scale[j] * 1e-3)
        up, down = list(y), list(y)
        up[j] += step
        down[j] -= step
        numeric = (np.array(rhs(up, u)) - np.array(rhs(down, u))) / (2 * step)
        assert np.allclose(analytic[:, j], numeric, rtol=1e-6, atol=1e-9 * np.abs(analytic).max())
    inputs = _inputs("TrackBushRadial", 3e-4, 5.0, jittered=True)[:400]
    assert _run(model, inputs) == _run(model, inputs, single_step=False)
