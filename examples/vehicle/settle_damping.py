"""The damping that brings the vehicle to rest while it settles to its static point
(static.py; not in the run): on the hull's translation and pitch, on each arm at its
wheel's centre, on each link at its two seats. Applied by the contacts' object (numpy
kernel here, contacts_forces.c's settle_damping in C, the same operations), each damper's
force and its Jacobian from the same points: a force at a point loads its body with the
force's moment about the body's node too (an arm's did not: its Jacobian had the moment,
its force not)."""

import numpy as np

# About critical for the hull's bounce and pitch on its suspension (its surge has the
# speed hold's own); the track's and the arms' light.
SETTLE_DAMPING = {"seat": 300.0, "arm": 5e3, "hull": (0.0, 1.8e5), "hull_pitch": 4e5}
# the hull's pitch damper in the Jacobian: a "point" whose first coordinate is the angle
PITCH_G = np.array([[[0.0, 0.0, 1.0], [0.0, 0.0, 0.0]]])


def settle_damping(contacts, bodies, seat):
    """Adds the settling's damping forces to the bodies' generalized forces `bodies` and
    the links' seats' forces `seat`, and its dampers to the contacts' springs (their
    Jacobian)."""
    c = SETTLE_DAMPING
    seat -= c["seat"] * contacts.seats_v
    bodies[0, :2] -= np.array(c["hull"]) * contacts.hull_v[:2]
    bodies[0, 2] -= c["hull_pitch"] * contacts.hull_v[2]

    def dampers(body, points, damping):
        g = contacts._point_g(body, points)
        count = len(points)
        contacts._add_springs(np.zeros((count, 2, 2)), np.broadcast_to(damping, (count, 2, 2)),
                              [(body, g, g, 1.0)])

    hull = np.zeros(1, dtype=int)
    dampers(hull, contacts.body_pos[:1], np.diag(c["hull"]))
    contacts._add_springs(np.zeros((1, 2, 2)), np.diag([c["hull_pitch"], 0.0])[None],
                          [(hull, PITCH_G, PITCH_G, 1.0)])
    # each arm damped at its wheel's centre: the force there and its moment on the arm
    arms = 1 + np.arange(len(contacts.wheels))
    force = -c["arm"] * contacts.wheels_v
    r = contacts.wheels - contacts.body_pos[arms]
    bodies[arms, :2] += force
    bodies[arms, 2] += r[:, 0] * force[:, 1] - r[:, 1] * force[:, 0]
    dampers(arms, contacts.wheels, c["arm"] * np.eye(2))
    links = contacts.link0 + np.repeat(np.arange(len(contacts.seats)), 2)
    dampers(links, contacts.seats.reshape(-1, 2), c["seat"] * np.eye(2))
