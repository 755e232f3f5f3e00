"""Radial bush loads across the track (examples/vehicle/bush_shear.py; docs/vehicle.md,
Loads across the track): the seats' offset along and across the track at each joint, and
the run's sentence naming the joint, where it is and the time where a large radial load
is across the track, not tension."""

import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
TURN = 4e-3  # rad: the top run's links 30 to 40 turned in phase about their centres


def _record(contacts, t):
    from vehicle.bush_shear import seat_offsets

    along, across = seat_offsets(contacts.seats, contacts.u)
    hull = contacts.hull
    return {"time": t, "bush_seat_along": along, "bush_seat_across": across,
            "pins": contacts.pins.copy(), "wheels": contacts.wheels.copy(),
            "idler": contacts.idler.copy(), "hull_x": hull[0], "hull_y": hull[1],
            "hull_pitch": hull[2]}


def test_links_turning_in_phase_part_their_seats_across_the_track_and_the_run_says_so(
        native_fmus):
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import layout as lay
    from vehicle.bush_shear import ACROSS_LOAD, across_track
    from vehicle.course import Bump
    from vehicle.model import Vehicle

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
    try:
        contacts, data = vehicle.contacts, vehicle.mbs.systemData
        contacts.evaluate(0.0)
        laid = _record(contacts, 0.1)
        # laid out: the top run's joints stretched along the track by the bush's static
        # stretch (0.159 mm), none parted across it
        stretch = vehicle.layout.chord - lay.LINK_PITCH
        assert laid["bush_seat_along"][31:41] == pytest.approx(stretch, rel=1e-3)
        assert np.max(laid["bush_seat_across"]) < 1e-6
        q = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Current))
        for link in range(30, 41):
            q[vehicle.mbs.GetNodeODE2Index(vehicle.link_nodes[link]) + 2] += TURN
        data.SetODE2Coordinates(q, exu.ConfigurationType.Current)
        contacts.evaluate(0.2)
        turned = _record(contacts, 0.2)
        # each joint between two turned links: its seats part across by the pitch times
        # the turn, one side's half where only one link turned (joints 30 and 41)
        inside = slice(31, 41)
        assert turned["bush_seat_across"][inside] == pytest.approx(0.15 * TURN, rel=0.01)
        assert turned["bush_seat_across"][[30, 41]] == pytest.approx(0.075 * TURN, rel=0.01)
        # and along it they come closer by the seats' second-order shortening
        closer = lay.LINK_PITCH * (1.0 - np.cos(TURN))
        assert turned["bush_seat_along"][inside] == pytest.approx(
            laid["bush_seat_along"][inside] - closer, abs=1e-8)
    finally:
        vehicle.coupling.free()
    result = {key: np.array([laid[key], turned[key]]) for key in laid}
    load = np.zeros((2, 80))
    load[0, 5] = 3 * ACROSS_LOAD  # along the track: tension, not named
    load[1, 35] = 50e3  # across the track
    load[1, 20] = 0.5 * ACROSS_LOAD  # across, but small
    result["bush_radial_force"] = load
    message = across_track(result, contacts)
    assert message.startswith("joint 35 (on the top run): its radial bush carried 50.0 kN "
                              "across the track at t = 0.2000 s (its seats 0.60 mm apart "
                              "across it, 0.16 mm along it)"), message
    assert "1 of 2 steps" in message
    load[1, 35] = 0.0
    assert across_track(result, contacts) is None


def test_seat_offsets_of_a_run_stacked_are_each_steps_to_the_bit():
    """The histories take the seats' offsets after the run, over all steps at once
    (outputs.histories): the same bits as each step's alone."""
    from vehicle.bush_shear import seat_offsets

    rng = np.random.default_rng(7)
    steps, links = 5, 12
    angle = rng.uniform(-np.pi, np.pi, (steps, links))
    directions = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    centres = rng.normal(0.0, 1.0, (steps, links, 2))
    seats = np.stack([centres - 0.1 * directions, centres + 0.1 * directions], axis=-2)
    seats += rng.normal(0.0, 1e-3, seats.shape)  # the seats off the links' line
    along, across = seat_offsets(seats, directions)
    assert along.shape == across.shape == (steps, links)
    for k in range(steps):
        along_k, across_k = seat_offsets(seats[k], directions[k])
        assert np.array_equal(along[k], along_k) and np.array_equal(across[k], across_k)
    assert np.all(across > 0.0) and np.any(np.abs(along) > 0.0)
