"""Radial bush loads across the track, which are not tension (docs/vehicle.md, Loads
across the track).

A radial bush's load is its law's at the distance between the two links' pin seats,
whatever that distance's direction. Where the track is nearly slack (the top run, the
spans at the sprocket and the idler, the ground run), its links can turn in phase about
their centres, each joint's seats parting across the track: a mode of about 1.1 kHz
(the links' inertia against the radial bushes) that a 1 ms or 0.5 ms step does not
resolve. Its loads are the integrator's more than the model's: on a 5 m/s random-road
run the largest was 108 kN at 1 ms, 203 kN at 0.5 ms, and none over 26 kN at 1 ms with
generalized-alpha's spectral radius 0.6 instead of 0.9, while the hull's peak
acceleration stayed within 8 %. They show in the track tension read at the sprocket and
the idler (65 kN at 1 ms against 21 kN along the track with the radius at 0.6), so the
run names the largest: the joint, where it was and the time.
"""

import math
import warnings

import numpy as np

from . import layout as lay

ACROSS_LOAD = 2 * lay.TRACK_TENSION  # N: a radial load across the track worth a warning
ACROSS_SHARE = 2.0  # across: the seats this many times further apart across than along


def seat_offsets(seats, directions):
    """Each joint's seat offset (link j - 1's front seat to link j's rear seat, at pin j)
    along the track (the two links' mean direction; positive stretched) and across it
    (its size). seats: (..., links, 2 seats, 2), directions: the links' unit vectors
    (..., links, 2), as the contacts hold them (Contacts.seats, Contacts.u); leading axes
    (the steps of a run) are kept."""
    offset = seats[..., 0, :] - np.roll(seats[..., 1, :], 1, axis=-2)
    along = directions + np.roll(directions, 1, axis=-2)
    along /= np.hypot(along[..., 0], along[..., 1])[..., None]
    return (along[..., 0] * offset[..., 0] + along[..., 1] * offset[..., 1],
            np.abs(along[..., 0] * offset[..., 1] - along[..., 1] * offset[..., 0]))


def across_track(result, contacts):
    """The largest radial bush load above ACROSS_LOAD whose seats are ACROSS_SHARE times or
    more further apart across the track than along it, as a sentence naming the joint,
    where it was and the time; None where there is none. `result`: the run's histories
    (outputs.histories)."""
    load, along = result["bush_radial_force"], result["bush_seat_along"]
    across = (load > ACROSS_LOAD) & (result["bush_seat_across"] > ACROSS_SHARE * np.abs(along))
    if not across.any():
        return None
    k, j = np.unravel_index(np.argmax(np.where(across, load, 0.0)), load.shape)
    steps = int(np.count_nonzero(across.any(axis=1)))
    return (f"joint {j} ({_place(result, contacts, k, j)}): its radial bush carried "
            f"{load[k, j] / 1e3:.1f} kN across the track at t = {result['time'][k]:.4f} s "
            f"(its seats {result['bush_seat_across'][k, j] * 1e3:.2f} mm apart across it, "
            f"{along[k, j] * 1e3:.2f} mm along it): not tension, but the links there "
            f"turning in phase, a mode of about 1 kHz the host step does not resolve; "
            f"{steps} of {len(load)} steps had such loads (above {ACROSS_LOAD / 1e3:g} kN), "
            f"read the peak tensions with care (docs/vehicle.md, Loads across the track)")


def warn_across_track(result, contacts):
    message = across_track(result, contacts)
    if message is not None:
        warnings.warn(message, stacklevel=3)
    return message


def _place(result, contacts, k, j):
    """Where pin j was at step k: on the sprocket, on the idler, on the top run or the
    ground run."""
    pin = result["pins"][k, j]
    theta = result["hull_pitch"][k]
    local = contacts.sprocket_local
    sprocket = np.array([result["hull_x"][k], result["hull_y"][k]]) + [
        math.cos(theta) * local[0] - math.sin(theta) * local[1],
        math.sin(theta) * local[0] + math.cos(theta) * local[1]]
    if np.hypot(*(pin - sprocket)) < lay.SPROCKET_PITCH_RADIUS + 0.08:
        return "on the sprocket"
    if np.hypot(*(pin - result["idler"][k])) < lay.IDLER_PIN_RADIUS + 0.08:
        return "on the idler"
    wheels = result["wheels"][k]
    return "on the top run" if pin[1] > np.mean(wheels[:, 1]) else "on the ground run"
