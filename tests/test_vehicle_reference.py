"""The reduced vehicle (examples/ground_vehicle.py: the hull and six stations on
ground-laid contact) against its independent monolithic reference
(examples/vehicle/ground_reference.py), over the first tenths of a second of a bump: the
equations of motion (exudyn's bodies and joints against the reference's Lagrange
equations, with Kelvin elements: no coupling in either), the co-simulation against the
reference, the coupling's own error, and the monolithic solve's step through states a
model does not take. The longer studies: benchmarks/vehicle_reference.py."""

import math
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))

pytest.importorskip("exudyn", reason='exudyn is not installed: pip install -e ".[examples]"')

SPEED = 5.0
END = 0.15  # s: the front wheel climbs three quarters of the bump's rise
START = -0.25  # m: the bump begins just ahead of the front wheel


def bump():
    from ground_vehicle import make_course
    return make_course("bump", START)


def error(result, reference, key):
    from coupling_study import history_error
    return history_error(result, reference, key)


@pytest.fixture(scope="module")
def linear():
    from vehicle.ground_exudyn import linearisation
    return linearisation()


@pytest.fixture(scope="module")
def reference():
    from vehicle.ground_reference import solve_reference
    return solve_reference(bump(), SPEED, END, np.arange(0.0, END + 1e-12, 5e-4), rtol=1e-8)


def test_static_point_is_at_rest_in_exudyn():
    """The static point the reduced vehicle's own equations give (ground.Reduced) holds
    in exudyn's model of it: on flat ground nothing moves."""
    from ground_vehicle import make_course, simulate

    _, result, _ = simulate(make_course("bump", 10.0), SPEED, 0.02, 1e-3)
    assert np.max(np.abs(result["hull_vertical_acceleration"])) < 1e-6
    assert np.max(np.abs(result["hull_pitch_acceleration"])) < 1e-6
    assert np.ptp(result["tyre_force"], axis=0).max() < 1e-3  # N, of about 20 kN


def test_exudyn_model_has_the_reference_equations_of_motion(linear):
    """With Kelvin elements in both (no FMU, no coupling lag: exudyn applies them at
    every iterate), exudyn's bodies and joints at 0.5 ms against the reference's ODE:
    what differs is exudyn's own step error."""
    from ground_vehicle import simulate
    from vehicle.ground_reference import solve_reference

    ode = solve_reference(bump(), SPEED, END, np.arange(0.0, END + 1e-12, 5e-4), linear=linear,
                          rtol=1e-9)
    _, result, _ = simulate(bump(), SPEED, END, 5e-4, linear=linear)
    assert np.ptp(ode["hull_vertical_acceleration"]) > 1.0  # m/s2: the bump is felt
    # measured: 0.0039, 0.014, 0.048 % (at 1 ms 0.021, 0.10, 0.38 %: exudyn's step error)
    assert error(result, ode, "hull_vertical_acceleration") < 0.01
    assert error(result, ode, "hull_pitch_acceleration") < 0.03
    assert error(result, ode, "tyre_force") < 0.1


def test_cosimulation_agrees_with_the_monolithic_reference(reference):
    """The co-simulation (compiled path, default coupling, 0.5 ms) against the reference:
    within the host's own step error, which halves by four with the step
    (benchmarks/vehicle_reference.py); a coupling that lags or loses a load is off by
    far more."""
    from ground_vehicle import simulate

    _, result, _ = simulate(bump(), SPEED, END, 5e-4)
    assert np.ptp(reference["tyre_force"][:, 0]) > 5e3  # N: the front wheel climbs
    # measured: 0.047, 0.11, 2.4, 0.12 % (at 1 ms 0.21, 0.42, 9.6, 0.48 %)
    assert error(result, reference, "hull_vertical_acceleration") < 0.1
    assert error(result, reference, "hull_pitch_acceleration") < 0.25
    assert error(result, reference, "tyre_force") < 5.0
    assert error(result, reference, "damper_torque") < 0.25


def test_coupling_own_error_is_below_the_target_at_1_ms():
    """The default coupling against `converged` at 1 ms: at most 0.1 % of the hull
    vertical acceleration's range (the target), on the compiled and the Python path,
    which give the same numbers."""
    from ground_vehicle import simulate

    runs = {(scheme, path): simulate(bump(), SPEED, END, 1e-3, scheme, path)[1]
            for scheme in ("corrected", "converged") for path in ("compiled", "python")}
    for path in ("compiled", "python"):
        own = error(runs["corrected", path], runs["converged", path],
                    "hull_vertical_acceleration")
        assert own < 0.1
    assert error(runs["corrected", "python"], runs["corrected", "compiled"],
                 "hull_vertical_acceleration") < 1e-6


def test_a_course_too_rough_for_the_speed_stops_naming_the_wheel_and_the_time():
    """A bump that compresses the front wheel's tyre beyond the range its model was
    measured to ends the run with the wheel, the time and what to do, not with nonsense
    past it (the FMU clamps there)."""
    from ground_vehicle import FRONT, simulate
    from vehicle.course import Bump
    from vehicle.model import VehicleError

    course = Bump(FRONT, height=0.3, length=0.5)
    course.start = START
    with pytest.raises(VehicleError, match=r"wheel 1's tyre .* at t = 0\.0\d+ s.*--speed"):
        simulate(course, 10.0, 0.1, 1e-3)


def test_monolithic_solve_takes_a_discarded_trial_state_as_a_failed_iteration():
    """A Model Exchange damper at a trial state outside its region (the FMU discards the
    call) answers NaN derivatives and outputs, which Radau takes as a failed Newton
    iteration, instead of ending the solve."""
    from example_fmus import fmu_path
    from fmu_components.verification.monolithic import ModelExchangeComponent

    damper = ModelExchangeComponent(fmu_path("RotaryDamper"), "damper_me")
    try:
        states = damper.start(0.0, 0.0)
        wild = np.full_like(states, 1e6)
        damper.set(0.0, wild, 0.0, 0.0)
        assert all(math.isnan(v) for v in damper.derivatives())
        assert all(math.isnan(v) for v in damper.outputs().values())
        damper.set(0.0, states, 0.0, 0.0)  # back in the region: finite again
        assert all(math.isfinite(v) for v in damper.derivatives())
    finally:
        damper.free()
