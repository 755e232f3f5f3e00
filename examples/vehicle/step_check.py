"""The vehicle's check of each solve's solution against its step's start
(exudyn_host's `step_check`): a solution that jumps is refused and the step retried
shorter (docs/vehicle.md, The bush's fade and the step check).

exudyn's Newton can converge, within one step, on a solution no motion in that step gives:
a link on the ground turning 21 deg and moving 47 mm through a wheel in 1 ms (the radial
bushes and the contacts give a step several solutions). Such a solution moves a body
further than its velocity at the step's start and any physical acceleration carry it in
the step. What is compared, beyond the motion at the start's velocity (generalized-alpha
moves a coordinate by h v0 plus h^2 times a mean of the step's accelerations):

* each link's centre and angle: more than LINK_JUMP or LINK_TURN (at 1 ms, 20 000 m/s2:
  300 kN on a 15 kg link, several times the largest wheel load; and 1.7e5 rad/s2);
* each tyre's compression (both ends of the step in contact): more than TYRE_JUMP (its
  static compression, 3.2 mm, in one step);
* each pin's gap to its sprocket tooth space (engaged at both ends): more than TOOTH_JUMP
  (50 kN of tooth load at the teeth's 5 MN/m): a tooth skipped.

The thresholds do not shrink with a shortened step: a jump stays a jump. The steps of a
run at 5 m/s measured 2.5 to 18 times below them (docs/vehicle.md).
"""

import math

import numpy as np

import exudyn as exu

from . import layout as lay
from .contacts_kernel import index_or_slice

LINK_JUMP = 0.01  # m
LINK_TURN = math.radians(5.0)
TYRE_JUMP = 3.2e-3  # m
TOOTH_JUMP = 0.01  # m


class StepCheck:
    def __init__(self, vehicle):
        self.v = vehicle
        mbs = vehicle.mbs
        links = np.array([mbs.GetNodeODE2Index(n) for n in vehicle.link_nodes])[:, None] \
            + [0, 1, 2]
        # the links' coordinates: a slice (a view) where they are one run, as exudyn has them
        self.links = index_or_slice(links)
        self.link_count = len(links)
        self.reference = np.array([mbs.GetNodeParameter(n, "referenceCoordinates")
                                   for n in vehicle.link_nodes], dtype=float)
        self.start = None  # the contacts' values at the last accepted step

    def accepted(self):
        """Keep the contacts' values at the accepted state (the records evaluated them;
        the contacts' arrays are new at each evaluation: kept as they are)."""
        c = self.v.contacts
        self.start = (c.compression, c.compression_rate, c.in_contact, c.tooth_gap)

    def __call__(self, mbs, t):
        """None where the solution in exudyn's data (the exudyn run's, at t) is one the
        step can reach, else what jumped (judge)."""
        data = mbs.systemData
        start = exu.ConfigurationType.StartOfStep
        return self.judge(t, t - data.GetTime(start), np.asarray(data.GetODE2Coordinates()),
                          None, np.asarray(data.GetODE2Coordinates(start)),
                          np.asarray(data.GetODE2Coordinates_t(start)))

    def judge(self, t, h, q1, v1, q0, v0):
        """None where the solution q1, v1 at t (v1 None: exudyn's current velocities) is
        one the step of length h from q0, v0 can reach, else what jumped. Each part tests
        its largest value first (the common case, nothing jumped, in a few array
        operations); only a value beyond a threshold takes the part's full comparison."""
        links = self.links
        beyond = (q1[links] - q0[links] - h * v0[links]).reshape(self.link_count, 3)
        moved = np.hypot(beyond[:, 0], beyond[:, 1])
        turned = np.abs(beyond[:, 2])
        # not all within (rather than the largest above): a NaN (the largest too) takes the
        # full comparison
        if not (moved.max() <= LINK_JUMP and turned.max() <= LINK_TURN):
            k = int(np.argmax(np.maximum(moved / LINK_JUMP, turned / LINK_TURN)))
            if moved[k] > LINK_JUMP or turned[k] > LINK_TURN:
                return (f"link {k}{self._where(k, q1[links][3 * k:3 * k + 3])} moved "
                        f"{moved[k] * 1e3:.1f} mm and turned {math.degrees(turned[k]):.1f} deg "
                        f"in one step beyond its motion at the step's start")
        if self.start is None:
            return None
        compression0, rate0, contact0, gap0 = self.start
        contacts = self.v.contacts
        contacts.evaluate(t, q1, v1)  # the coupling's deflections use this evaluation
        jump = np.abs(contacts.compression - compression0 - h * rate0)
        # a wheel out of contact has compression -inf at both ends: NaN here
        if not jump.max() <= TYRE_JUMP:
            jump = np.where(contact0 & contacts.in_contact, jump, 0.0)
            w = int(np.argmax(jump))
            if jump[w] > TYRE_JUMP:
                return (f"road wheel {w + 1}: its tyre's compression jumped by "
                        f"{jump[w] * 1e3:.1f} mm in one step (to "
                        f"{contacts.compression[w] * 1e3:.1f} mm)")
        gap = contacts.tooth_gap
        skip = np.abs(gap - gap0)
        if not skip.max() <= TOOTH_JUMP:
            skip = np.where((gap0 > 0.0) & (gap > 0.0), skip, 0.0)
            j = int(np.argmax(skip))
            if skip[j] > TOOTH_JUMP:
                return (f"joint {j}: its pin's gap to its sprocket tooth space jumped by "
                        f"{skip[j] * 1e3:.1f} mm in one step (a tooth skipped)")
        return None

    def _where(self, k, moved):
        """Which road wheel link k is beneath, where one is within a link's pitch."""
        centre = self.reference[k, :2] + moved[:2]
        wheels = self.v.contacts.wheels  # at the contacts' last evaluation
        distance = np.hypot(*(wheels - centre).T)
        w = int(np.argmin(distance))
        if distance[w] > lay.WHEEL_RADIUS + lay.LINK_PITCH:
            return ""
        return f" (beneath road wheel {w + 1})"
