"""The vehicle on its own solver (examples/vehicle/own_host.py, own_system.c; docs/vehicle.md,
The vehicle on its own solver) against the same vehicle in exudyn: the same scheme
(corrected), step (1 ms), spectral radius, Newton tolerances and full Newton, from the
stored static point over 0.02 s at 3 m/s on the bump. The two take the same Newton
iterations, and their histories agree far below Newton's tolerance (the same iterates, to
round-off)."""

import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
END, STEP, SPEED = 0.02, 1e-3, 3.0
KEYS = ("hull_vertical_acceleration", "hull_pitch_acceleration",
        "seat_vertical_acceleration", "hull_y", "tyre_force", "damper_torque",
        "bush_radial_force", "bush_torque")


@pytest.fixture(scope="module")
def runs(native_fmus):
    """{solver: (histories, solver statistics)}"""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from tracked_vehicle import simulate
    from vehicle.model import static_points

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    statics = static_points(fmu_dir)
    result = {}
    for solver in ("exudyn", "own"):
        vehicle, histories, _, _ = simulate("bump", SPEED, END, STEP, statics=statics,
                                            fmu_dir=fmu_dir, solver=solver)
        result[solver] = histories, vehicle.solver_statistics()
    return result


def test_the_own_solver_takes_exudyns_steps_and_iterations(runs):
    (_, exudyn), (histories, own) = runs["exudyn"], runs["own"]
    assert len(histories["time"]) == round(END / STEP) + 1
    for statistics in (exudyn, own):
        assert statistics["steps"] == statistics["host_steps"] == round(END / STEP)
        assert statistics["refused"] == 0
    assert own["passes_per_step"] == exudyn["passes_per_step"] >= 1.0
    assert own["newton_per_pass"] == exudyn["newton_per_pass"]


def test_the_own_solver_agrees_with_exudyn_below_newtons_tolerance(runs):
    """Every history compared to 1e-5 % of its range (measured 1.2e-7 %, the hull's
    accelerations: the same iterates, apart by the two LUs' round-off)."""
    from vehicle.outputs import largest_difference

    difference, _ = largest_difference(runs["exudyn"][0], runs["own"][0], KEYS)
    assert 0.0 < difference <= 1e-5  # not the same run twice
