"""The vehicle's contacts, all computed at once from the host's current state, with their
Jacobian, as one exudyn object over the bodies they touch (one evaluation per state):

* tyres: a road wheel overlaps the inner face of each link beneath it (the face
  LINK_INNER inside the pin line) by R - d, d the wheel centre's distance from that face;
  the tyre's compression is a smooth maximum of these overlaps (TYRE_BLEND wide, each
  link's term faded in and out over HANDOVER about its ends). Both half-wheels'
  RoadWheelTyre instances get this compression and its rate; their load pushes the
  compression back (minus the load times its gradient), each link beneath taking its
  weight's share along its own normal.
* pins on the ground: a vertical penalty contact of the link's ground face (smooth onset,
  frictionless: the sprocket, turning with the hull's travel, holds the ground run still);
* the sprocket's teeth: each pin within the sprocket's wrap is pulled to the tooth space
  nearest it, the pull taken up and let go over ENGAGEMENT_RAMP at the wrap's ends;
* idler and support roller: pins on a circle, radial penalty contact.
"""

import math

import numpy as np

import exudyn as exu
from exudyn.itemInterface import ObjectGenericODE2

from . import layout as lay
from .contact_math import cross, rotate, smoothstep, smoothstep_derivatives
from .contacts_kernel import (CompiledContacts, KernelResults, as_vector, index_or_slice,
                              library)
from .model import (ENGAGEMENT_RAMP, GROUND_DAMPING, GROUND_STIFFNESS, HORN_HEIGHT,
                    SPROCKET_DAMPING, SPROCKET_STIFFNESS, VehicleError, WHEEL_DAMPING,
                    WHEEL_STIFFNESS)
from .settle_damping import settle_damping

TOOTH_SPACING = 2 * math.pi / lay.SPROCKET_TEETH
# The tyre's compression blends the overlaps of the links beneath a wheel: a smooth maximum
# TYRE_BLEND wide (2 mm), each link's term faded in and out over HANDOVER (30 mm) about
# its ends, so that the contact passes from link to link without a jump (assumed;
# docs/vehicle.md, Contacts).
TYRE_BLEND = 2e-3
HANDOVER = 0.03
CONTACT_ONSET = 5e-4  # m: the penalty contacts' force grows smoothly over this depth


def _penalty(depth, closing, stiffness, damping):
    """A penalty contact with a smooth onset: the spring's force k d^2 / (2 e) over the
    first CONTACT_ONSET e of depth d, then k (d - e / 2), and the damper's taken up over the
    same depth, never pulling. Returns (force, its slope by depth, by closing rate)."""
    d = np.maximum(depth, 0.0)
    ramp = np.minimum(d / CONTACT_ONSET, 1.0)
    spring = stiffness * np.where(d < CONTACT_ONSET, 0.5 * d * ramp, d - 0.5 * CONTACT_ONSET)
    force = spring + damping * ramp * closing
    touching = force > 0.0
    return (np.where(touching, force, 0.0), np.where(touching, stiffness * ramp, 0.0),
            np.where(touching, damping * ramp, 0.0))


class Contacts(KernelResults):
    def __init__(self, vehicle):
        self.v = vehicle
        geo = vehicle.layout
        self.cg = geo.cg
        self.sprocket_local = geo.sprocket - geo.cg
        self.roller_local = geo.roller - geo.cg
        arc = geo.arc(2)
        self.wrap_start, self.wrap_sweep = arc.start, arc.sweep
        # the tooth spaces line up with the pin nearest the middle of the wrap
        middle = arc.start + 0.5 * arc.sweep
        angles = np.arctan2(*(geo.pins - geo.sprocket).T[::-1])
        near = np.argmin(np.abs(np.angle(np.exp(1j * (angles - middle)))))
        self.tooth_phase = angles[near]
        self.hull_x0 = geo.cg[0]
        self.wheel_offset = np.array(vehicle.wheel_offset)
        # fixed points where the tensions are read (hull frame): where the front span meets
        # the sprocket (the tight side driving forward) and the top run meets the idler
        self.tension_points = (geo.arc(2).point(0.0) - geo.cg,
                               geo.arc(4).point(0.0) - geo.cg)
        self._key, self._adopted, self._adoption = None, False, None
        self.audit = None  # an energy.Audit: the power of each class of contact
        # "compiled" (contacts_kernel.py, C) where it builds, else "numpy" (this file's)
        self.kernel, self._compiled, self._by_compiled = "numpy", None, False

    def add_object(self):
        """One exudyn object carries every contact force: a generic ODE2 object over the
        hull, the arms, the idler's crank and the links, with the force as its user
        function and its Jacobian (each contact's stiffness and damping mapped onto the
        bodies' coordinates) as another, so that exudyn's Newton sees the contacts."""
        v = self.v
        self.nodes = [v.hull_node, *v.arm_nodes, v.crank_node, *v.link_nodes]
        self.link0 = 2 + len(v.arm_nodes)  # body index of the first link
        self.reference = np.array([v.mbs.GetNodeParameter(n, "referenceCoordinates")
                                   for n in self.nodes], dtype=float)
        if library() is not None:
            self.kernel, self._compiled = "compiled", CompiledContacts(self, library())
        size = 3 * len(self.nodes)
        # sparse (triplets): a dense matrix of this size made exudyn's sparse solver factor
        # a dense block at every Newton iteration
        massless = exu.MatrixContainer()
        massless.SetWithSparseMatrix(np.zeros((0, 3)), size, size)
        v.mbs.AddObject(ObjectGenericODE2(
            nodeNumbers=self.nodes, massMatrix=massless,
            forceUserFunction=lambda mbs, t, item, q, qd: self._generalized(t, q, qd),
            jacobianUserFunction=lambda mbs, t, item, q, qd, f, f_t:
                self._sparse_jacobian(t, q, qd, f, f_t)))

    def use(self, kernel):
        """Evaluate with `kernel`: "compiled" (C, where it builds) or "numpy"."""
        if kernel not in ("compiled", "numpy") or (kernel == "compiled" and not self._compiled):
            raise ValueError(f"contacts kernel {kernel!r}: 'numpy', or 'compiled' where gcc is")
        self.kernel, self._key = kernel, None

    def index(self):
        """After Assemble: where the object's coordinates sit in the system's vectors."""
        mbs = self.v.mbs
        self.system_index = np.concatenate([mbs.GetNodeODE2Index(n) + np.arange(3)
                                            for n in self.nodes])
        self._coordinates = index_or_slice(self.system_index)  # evaluate's

    def rebase(self, settled):
        """The settled state becomes the start: the sprocket's tooth spaces stay where the
        settling left them while the hull's travel is counted from there."""
        hull_x = self.reference[0, 0] + settled[self.system_index[0]]
        self.tooth_phase -= (hull_x - self.hull_x0) / lay.SPROCKET_PITCH_RADIUS
        self.hull_x0 = hull_x
        self._key = None
        if self._compiled is not None:
            self._compiled.set_parameters()

    # --- one evaluation per state ---------------------------------------------------------

    def evaluate(self, t, q=None, qd=None, laws=True):
        """The contacts at the host's current state (for the coupling's readers and the
        records), or at the system's coordinates q and velocities qd where given. laws
        False: for a reader of nothing the tyres' load laws decide (the kinematics, the
        tyres' compressions, the ground's and the sprocket's forces: the records), whom the
        last evaluation at the same state serves, whatever laws it had."""
        if q is None:
            q = np.asarray(self.v.mbs.systemData.GetODE2Coordinates(
                exu.ConfigurationType.Current))
        if qd is None:
            qd = np.asarray(self.v.mbs.systemData.GetODE2Coordinates_t(
                exu.ConfigurationType.Current))
        index = self._coordinates
        self._update(t, q[index], qd[index], laws)

    def _update(self, t, q, qd, laws=True):
        q, qd = as_vector(q), as_vector(qd)
        # the tyres' load laws change between the coupling's passes at the same state
        state, key = self._state(t, q, qd), self._key
        if key is not None and state == key[0] and not laws:
            return
        tyre_laws = self.v.tyre_laws_key()
        if key is not None and state == key[0] and tyre_laws == key[1]:
            return
        self._key, self._adopted = (state, tyre_laws), False
        self._by_compiled = self.kernel == "compiled" and self.audit is None
        if self._by_compiled:  # the audit reads the numpy kernel's steps
            return self._compiled.update(q, qd)
        self.qd = qd = qd.copy()  # kept: evaluate may give a view of the caller's
        self._kinematics(self.reference + q.reshape(-1, 3), qd.reshape(-1, 3))
        self._forces(t)

    def _generalized(self, t, q, qd):
        self._update(t, q, qd)
        return self._compiled.generalized() if self._by_compiled else self.generalized

    def _sparse_jacobian(self, t, q, qd, factor, factor_t):
        """The Jacobian as exudyn takes it from this object: (row, column, value)
        triplets, repeated entries summed."""
        self._evaluated(t, q, qd)
        size = 3 * len(self.nodes)
        matrix = exu.MatrixContainer()
        matrix.SetWithSparseMatrix(self._triplet_rows(factor, factor_t), size, size)
        return matrix

    def _jacobian(self, t, q, qd, factor, factor_t):
        """The Jacobian as a dense matrix (for checks)."""
        self._evaluated(t, q, qd)
        size = 3 * len(self.nodes)
        rows, columns, values = self._triplet_rows(factor, factor_t).T
        return np.bincount((rows * size + columns).astype(int), values,
                           minlength=size * size).reshape(size, size)

    def _triplet_rows(self, factor, factor_t):
        """The triplets as rows (row, column, value), from the kernel that evaluated."""
        if self._by_compiled:
            return self._compiled.triplets(factor, factor_t)
        return np.stack(self._triplets(factor, factor_t), axis=1)

    def _triplets(self, factor, factor_t):
        """Every spring's block (its members a, b: w_a G_a^T (factor K + factor_t C) w_b H_b,
        G how a force at the member's point loads its body, H how the point moves with
        it) at once, then the tyres'."""
        stiffness, damping, bodies, force_g, motion_g, weights = (
            np.concatenate(part) for part in zip(*self.springs))
        block = factor * stiffness + factor_t * damping
        left = weights[:, :, None, None] * force_g
        right = weights[:, :, None, None] * motion_g
        blocks = np.einsum("saji,sjk,sbkl->sabil", left, block, right)
        first = 3 * bodies[:, :, None] + np.arange(3)  # (spring, member, coordinate)
        member = weights != 0  # the blocks of members that exist, in the C kernel's order
        pair = (member[:, :, None] & member[:, None, :])[..., None, None]
        kept = np.broadcast_to(pair, blocks.shape)
        parts = [(np.broadcast_to(first[:, :, None, :, None], blocks.shape)[kept],
                  np.broadcast_to(first[:, None, :, None, :], blocks.shape)[kept],
                  blocks[kept])]
        parts += self._tyre_triplets(factor, factor_t)
        return tuple(np.concatenate(part).astype(float) for part in zip(*parts))

    def _tyre_triplets(self, factor, factor_t):
        """The tyres' factor K + factor_t C of each wheel in contact, from the blend's
        gradient D (a row per link beneath) and weights p: K = F' (p.D)^T (p.D) +
        F/b D^T (diag(p) - p p^T) D (b TYRE_BLEND; the second derivatives of each link's
        own term left out, and the rate's derivative by q), C = F_rate (p.D)^T (p.D) (the
        rate is p.D times the velocities: a Kelvin tyre's damping), on the few coordinates
        D touches (the arm's, the links')."""
        count = len(self.wheels)
        force, slope, rate_slope = np.zeros(count), np.zeros(count), np.zeros(count)
        for w, f, k, c in self.tyre_terms:
            force[w], slope[w], rate_slope[w] = f, k, c
        pairs = np.flatnonzero(force[self.pair_wheel] > 0.0)
        wheel, weights = self.pair_wheel[pairs], self.pair_weight[pairs]
        gradient = self.pair_gradient[pairs]
        coordinates = self.pair_coordinates[pairs]
        size = coordinates.shape[1]
        # F/b sum_k p_k D_k^T D_k, a block per pair
        scale = factor * force[wheel] / TYRE_BLEND * weights
        own = (np.broadcast_to(coordinates[:, :, None], (len(pairs), size, size)).ravel(),
               np.broadcast_to(coordinates[:, None, :], (len(pairs), size, size)).ravel(),
               (scale[:, None, None] * gradient[:, :, None] * gradient[:, None, :]).ravel())
        # (factor (F' - F/b) + factor_t F_rate) (p.D)^T (p.D): p.D's entries, the wheel's
        # summed over its links
        wheels = np.flatnonzero(force > 0.0)
        by_wheel = np.stack([np.bincount(wheel, weights * gradient[:, j], minlength=count)
                             for j in range(3)], axis=1)[wheels]
        entry_wheel = np.concatenate([np.repeat(wheels, 3), np.repeat(wheel, size - 3)])
        entry_coordinate = np.concatenate([(3 * (1 + wheels)[:, None] + np.arange(3)).ravel(),
                                           coordinates[:, 3:].ravel()])
        entry_value = np.concatenate([by_wheel.ravel(),
                                      (weights[:, None] * gradient[:, 3:]).ravel()])
        first, second = np.nonzero(entry_wheel[:, None] == entry_wheel[None, :])
        w = entry_wheel[first]
        mean = (entry_coordinate[first], entry_coordinate[second],
                (factor * (slope[w] - force[w] / TYRE_BLEND) + factor_t * rate_slope[w])
                * entry_value[first] * entry_value[second])
        return [own, mean]

    def _point_g(self, bodies, points):
        """d(point)/d(body's x, y, angle), one 2 x 3 matrix per point fixed on its body:
        how a force there loads the body, and how the point moves with it."""
        r = points - self.body_pos[bodies]
        g = np.zeros((len(r), 2, 3))
        g[:, 0, 0] = g[:, 1, 1] = 1.0
        g[:, 0, 2], g[:, 1, 2] = -r[:, 1], r[:, 0]
        return g

    def _add_springs(self, stiffness, damping, members):
        """Springs (their 2 x 2 stiffness and damping, one per row) for the Jacobian, each
        between up to three members, given as (bodies, force_g, motion_g, weights) per
        member slot (a weight 0: no member)."""
        count = len(stiffness)
        if not count:
            return
        bodies = np.zeros((count, 3), dtype=int)
        force_g, motion_g = np.zeros((count, 3, 2, 3)), np.zeros((count, 3, 2, 3))
        weights = np.zeros((count, 3))
        for slot, (body, g_force, g_motion, weight) in enumerate(members):
            bodies[:, slot], weights[:, slot] = body, weight
            force_g[:, slot], motion_g[:, slot] = g_force, g_motion
        self.springs.append((stiffness, damping, bodies, force_g, motion_g, weights))

    def _pin_springs(self, pins, stiffness, damping, third=None):
        """Springs on pins (indices): each pin the two seats that make it, half each; and
        a third member (bodies, force_g, motion_g, weights) if given."""
        behind = (pins - 1) % len(self.pins)
        members = []
        for links, seats in ((behind, self.seats[behind, 1]), (pins, self.seats[pins, 0])):
            g = self._point_g(self.link0 + links, seats)
            members.append((self.link0 + links, g, g, 0.5))
        self._add_springs(stiffness, damping, members + ([third] if third else []))

    def _kinematics(self, state, rates):
        half = 0.5 * lay.LINK_PITCH
        self.body_pos, self.rates = state[:, :2], rates
        self.hull, self.hull_v = state[0], rates[0]
        links, links_v = state[self.link0:], rates[self.link0:]
        self.link_pos, self.link_angle, self.link_omega = links[:, :2], links[:, 2], links_v[:, 2]
        self.link_v = links_v[:, :2]
        u = np.stack([np.cos(links[:, 2]), np.sin(links[:, 2])], axis=1)
        self.u, self.n = u, np.stack([-u[:, 1], u[:, 0]], axis=1)
        seat_v = cross(links_v[:, 2], half * u)
        self.seats = np.stack([links[:, :2] - half * u, links[:, :2] + half * u], axis=1)
        self.seats_v = np.stack([links_v[:, :2] - seat_v, links_v[:, :2] + seat_v], axis=1)
        # pin j: between link j - 1's front seat and link j's rear seat
        self.pins = 0.5 * (np.roll(self.seats[:, 1], 1, axis=0) + self.seats[:, 0])
        self.pins_v = 0.5 * (np.roll(self.seats_v[:, 1], 1, axis=0) + self.seats_v[:, 0])
        arms, arms_v = state[1:self.link0 - 1], rates[1:self.link0 - 1]
        offsets = np.array([rotate(a, o) for a, o in zip(arms[:, 2], self.wheel_offset)])
        self.wheels = arms[:, :2] + offsets
        self.wheels_v = arms_v[:, :2] + cross(arms_v[:, 2], offsets)
        self.idler, self.idler_v = state[self.link0 - 1][:2], rates[self.link0 - 1][:2]
        self._tyre_kinematics()

    def _tyre_kinematics(self):
        """Per wheel: the tyre's compression, a smooth maximum (TYRE_BLEND wide) of the
        overlaps of the links beneath it, each faded in and out over HANDOVER about its
        joints, and its rate; per (wheel, link) pair: the link's weight in the blend and
        the gradient of its term by the coordinates of the arm and of the links behind,
        beneath and ahead. All wheels at once. A window is bounded at each joint by the
        bisector of the links' angle there (through the pin, normal m the mean of their
        directions): over a convex joint, as on a bump's crest, a wheel still has a link
        beneath it, and the two windows at a joint sum to one (docs/vehicle.md)."""
        count, links = len(self.wheels), len(self.u)
        r = self.wheels[:, None, :] - self.link_pos[None, :, :]
        along = r[..., 0] * self.u[:, 0] + r[..., 1] * self.u[:, 1]
        height = r[..., 0] * self.n[:, 0] + r[..., 1] * self.n[:, 1]
        wheel, link = np.nonzero((np.abs(along) < lay.LINK_PITCH) & (height > 0.0)
                                 & (height < 2 * lay.WHEEL_RADIUS))
        behind, ahead = (link - 1) % links, (link + 1) % links
        w = self.wheels[wheel]
        # each end: its joint's pin, the bisector's normal m = (u_a + u_b) / |u_a + u_b|,
        # the wheel's distance from it into the link, the smoothstep's argument
        ends = []
        for a, b, sign, pin in ((behind, link, 1.0, link), (link, ahead, -1.0, ahead)):
            mean = self.u[a] + self.u[b]
            size = np.hypot(mean[:, 0], mean[:, 1])
            m = mean / size[:, None]
            offset = w - self.pins[pin]
            x = sign * np.einsum("ij,ij->i", offset, m) / HANDOVER + 0.5
            ends.append((a, b, sign, m, size, offset, x))
        window = smoothstep(ends[0][6]) * smoothstep(ends[1][6])
        overlap = lay.WHEEL_RADIUS - (height[wheel, link] - lay.LINK_INNER)
        top = np.full(count, -np.inf)
        np.maximum.at(top, wheel, np.where(window > 0.0, overlap, -np.inf))
        # a link whose overlap is 40 blend widths below the largest weighs e^-40 in the
        # blend: left out (links of the top run above the wheel)
        keep = (window > 0.0) & (overlap > top[wheel] - 40 * TYRE_BLEND)
        wheel, link, behind, ahead = wheel[keep], link[keep], behind[keep], ahead[keep]
        along, height, window, w = along[wheel, link], height[wheel, link], window[keep], w[keep]
        overlap = overlap[keep]
        terms = window * np.exp((overlap - top[wheel]) / TYRE_BLEND)
        total = np.bincount(wheel, terms, minlength=count)
        self.in_contact = total > 0.0
        with np.errstate(divide="ignore"):
            self.compression = np.where(self.in_contact,
                                        top + TYRE_BLEND * np.log(total), -np.inf)
        weights = terms / np.where(self.in_contact, total, 1.0)[wheel]
        # the gradient of each term, its overlap (R + inner - (wheel - link) . n) plus
        # TYRE_BLEND ln(its window), by (x, y, angle) of the arm and of the links behind,
        # beneath and ahead; each end's ln(smoothstep) changes with the wheel, the pin (half
        # each of the two links' seats) and m (turning with the two links)
        n = self.n[link]
        gradient = np.zeros((len(wheel), 4, 3))
        by_wheel = -n
        gradient[:, 2, :2] = n
        gradient[:, 2, 2] = along
        half = 0.5 * lay.LINK_PITCH
        for (a, b, sign, m, size, offset, x), slots in zip(ends, ((1, 2), (2, 3))):
            m, size, offset, x = m[keep], size[keep], offset[keep], x[keep]
            a, b = a[keep], b[keep]
            value, slope, _ = smoothstep_derivatives(x)
            scale = sign * TYRE_BLEND * slope / np.maximum(value, 1e-300) / HANDOVER
            by_wheel = by_wheel + scale[:, None] * m
            across = offset - np.einsum("ij,ij->i", offset, m)[:, None] * m
            for slot, body, seat in ((slots[0], a, half), (slots[1], b, -half)):
                # the pin: half of link a's front seat and of link b's rear seat
                gradient[:, slot, :2] -= 0.5 * scale[:, None] * m
                turn = (-0.5 * seat * np.einsum("ij,ij->i", m, self.n[body])
                        + np.einsum("ij,ij->i", across, self.n[body]) / size)
                gradient[:, slot, 2] += scale * turn
        arm = w - self.body_pos[1 + wheel]
        gradient[:, 0, :2] = by_wheel
        gradient[:, 0, 2] = -by_wheel[:, 0] * arm[:, 1] + by_wheel[:, 1] * arm[:, 0]
        bodies = np.stack([1 + wheel, self.link0 + behind, self.link0 + link,
                           self.link0 + ahead], axis=1)
        self.pair_wheel, self.pair_weight = wheel, weights
        self.pair_coordinates = (3 * bodies[:, :, None] + np.arange(3)).reshape(-1, 12)
        self.pair_gradient = gradient.reshape(-1, 12)
        # the compression's rate is its gradient times the velocities, the windows' fading
        # included (the tyre's damping sees the rate its force does work against)
        velocities = self.rates[bodies].reshape(-1, 12)
        self.compression_rate = np.bincount(
            wheel, weights * np.sum(self.pair_gradient * velocities, axis=1), minlength=count)

    def tyre_state(self, w):
        self.evaluate(self.v.mbs.systemData.GetTime())
        if not self.in_contact[w]:
            return -HORN_HEIGHT, 0.0
        return float(self.compression[w]), float(self.compression_rate[w])

    def _forces(self, t):
        v = self.v
        count = len(self.pins)
        pin = np.zeros((count, 2))  # forces on the pins
        bodies = np.zeros((len(self.nodes), 3))
        self.springs = [(np.zeros((0, 2, 2)), np.zeros((0, 2, 2)), np.zeros((0, 3), dtype=int),
                         np.zeros((0, 3, 2, 3)), np.zeros((0, 3, 2, 3)), np.zeros((0, 3)))]
        hull_pos, hull_theta = self.hull[:2], self.hull[2]
        hull_vel, hull_omega = self.hull_v[:2], self.hull_v[2]
        if self.audit is not None:
            self.audit.begin()

        def on_body(body, points, forces):
            bodies[body, :2] += forces.sum(axis=0)
            r = points - self.body_pos[body]
            bodies[body, 2] += np.sum(r[:, 0] * forces[:, 1] - r[:, 1] * forces[:, 0])

        def normal_springs(k, c, normals):
            outer = normals[:, :, None] * normals[:, None, :]
            return k[:, None, None] * outer, c[:, None, None] * outer

        # ground (frictionless, vertical)
        face = self.pins[:, 1] - lay.LINK_OUTER  # the links' ground faces' heights
        depth = v.course.under(self.pins[:, 0], face) - face
        load, stiffness, damping = _penalty(depth, -self.pins_v[:, 1], GROUND_STIFFNESS,
                                            GROUND_DAMPING)
        pin[:, 1] += load
        self.ground_load = load
        if self.audit is not None:
            self.audit.mark("ground", self, pin, bodies)
        on = np.flatnonzero(load > 0.0)
        self._pin_springs(on, *normal_springs(stiffness[on], damping[on],
                                              np.tile([0.0, 1.0], (len(on), 1))))

        # sprocket teeth
        centre = hull_pos + rotate(hull_theta, self.sprocket_local)
        centre_v = hull_vel + cross(hull_omega, centre - hull_pos)
        turned = (hull_theta + self.tooth_phase
                  - (hull_pos[0] - self.hull_x0) / lay.SPROCKET_PITCH_RADIUS)
        rate = hull_omega - hull_vel[0] / lay.SPROCKET_PITCH_RADIUS
        rel = self.pins - centre
        angle = np.arctan2(rel[:, 1], rel[:, 0])
        into = (angle - hull_theta - self.wrap_start) % (2 * math.pi)
        weight, weight_slope, weight_curvature = self._engagement(into)
        distance = np.hypot(rel[:, 0], rel[:, 1])
        off = distance > lay.SPROCKET_PITCH_RADIUS + 0.08
        weight[off], weight_slope[off], weight_curvature[off] = 0.0, 0.0, 0.0
        tooth = np.round((angle - turned) / TOOTH_SPACING)
        slot_angle = turned + tooth * TOOTH_SPACING
        radial = np.stack([np.cos(slot_angle), np.sin(slot_angle)], axis=1)
        slot = centre + lay.SPROCKET_PITCH_RADIUS * radial
        slot_v = centre_v + cross(rate, lay.SPROCKET_PITCH_RADIUS * radial)
        gap = slot - self.pins
        tooth_force = weight[:, None] * (SPROCKET_STIFFNESS * gap
                                         + SPROCKET_DAMPING * (slot_v - self.pins_v))
        # the engagement is the potential w(pin's angle) k |gap|^2 / 2: besides the pull,
        # minus its gradient by the angle (d angle / d pin = z x rel / |rel|^2); a pull
        # scaled by the ramp alone did net work at each passage (docs/vehicle.md)
        stored = 0.5 * SPROCKET_STIFFNESS * np.sum(gap * gap, axis=1)
        by_angle = cross(1.0, rel) / (distance * distance)[:, None]
        ramp_force = -(stored * weight_slope)[:, None] * by_angle
        pin += tooth_force + ramp_force
        self.tooth_gap = np.where(weight > 0, np.hypot(*gap.T), 0.0)
        on = np.flatnonzero(weight > 0.0)
        on_body(0, slot[on], -tooth_force[on])
        on_body(0, self.pins[on], -ramp_force[on])  # w turns with the hull, not the teeth
        r = slot[on] - centre
        self.drive_torque = -np.sum(r[:, 0] * tooth_force[on, 1] - r[:, 1] * tooth_force[on, 0])
        def slot_motion(pins):  # the tooth space turns back as the hull travels forward
            slot_g = self._point_g(np.zeros(len(pins), dtype=int), slot[pins])
            motion_g = slot_g.copy()
            motion_g[:, 0, 0] += np.sin(slot_angle[pins])
            motion_g[:, 1, 0] -= np.cos(slot_angle[pins])
            return slot_g, motion_g

        slot_g, motion_g = slot_motion(on)
        identity = weight[on, None, None] * np.eye(2)
        self._pin_springs(on, SPROCKET_STIFFNESS * identity, SPROCKET_DAMPING * identity,
                          (0, slot_g, motion_g, -1.0))
        # the ramp force's change with the gap, -k w' m gap^T (m = d angle / d pin; hull
        # member the tooth space), with the angle, stored (w'' m m^T + w' dm/d pin; hull
        # member its point at the pin: w turns with the hull)
        ramp = np.flatnonzero(weight_slope != 0.0)
        hull = np.zeros(len(ramp), dtype=int)
        pin_g = self._point_g(hull, self.pins[ramp])
        ramp_slot, ramp_motion = slot_motion(ramp)
        m, r = by_angle[ramp], rel[ramp]
        slope = weight_slope[ramp, None, None]
        by_gap = -SPROCKET_STIFFNESS * slope * m[:, :, None] * gap[ramp, None, :]
        self._pin_springs(ramp, by_gap, np.zeros_like(by_gap), (0, pin_g, ramp_motion, -1.0))
        # the pull's (spring's and damper's) change with w: -w' (k gap + c gap') m^T
        pull = SPROCKET_STIFFNESS * gap[ramp] + SPROCKET_DAMPING * (slot_v - self.pins_v)[ramp]
        by_weight = -slope * pull[:, :, None] * m[:, None, :]
        self._pin_springs(ramp, by_weight, np.zeros_like(by_weight),
                          (0, ramp_slot, pin_g, -1.0))
        turn = np.array([[0.0, -1.0], [1.0, 0.0]])
        squared = (distance[ramp] ** 2)[:, None, None]
        m_slope = turn / squared - 2.0 * np.einsum("ij,nj,nk->nik", turn, r, r) / squared ** 2
        by_turn = stored[ramp, None, None] * (
            weight_curvature[ramp, None, None] * m[:, :, None] * m[:, None, :]
            + weight_slope[ramp, None, None] * m_slope)
        self._pin_springs(ramp, by_turn, np.zeros_like(by_turn), (0, pin_g, pin_g, -1.0))
        if self.audit is not None:
            self.audit.mark("sprocket", self, pin, bodies)
            damped = weight * SPROCKET_DAMPING * np.sum((slot_v - self.pins_v) ** 2, axis=1)
            self.audit.sprocket(tooth_force, weight * stored, damped,
                                -hull_vel[0] * cross(1.0, radial))

        # idler (on its crank) and support roller (on the hull)
        roller = hull_pos + rotate(hull_theta, self.roller_local)
        roller_v = hull_vel + cross(hull_omega, roller - hull_pos)
        for centre, centre_v, radius, body in (
                (self.idler, self.idler_v, lay.IDLER_PIN_RADIUS, self.link0 - 1),
                (roller, roller_v, lay.ROLLER_PIN_RADIUS, 0)):
            rel = self.pins - centre
            distance = np.hypot(rel[:, 0], rel[:, 1])
            normal = rel / distance[:, None]
            closing = -np.einsum("ij,ij->i", self.pins_v - centre_v, normal)
            force, stiffness, damping = _penalty(radius - distance, closing, WHEEL_STIFFNESS,
                                                 WHEEL_DAMPING)
            on = np.flatnonzero(force > 0.0)
            pushed = force[on, None] * normal[on]
            pin[on] += pushed
            on_body(body, np.tile(centre, (len(on), 1)), -pushed)
            centre_g = self._point_g(np.full(len(on), body), np.tile(centre, (len(on), 1)))
            self._pin_springs(on, *normal_springs(stiffness[on], damping[on], normal[on]),
                              (body, centre_g, centre_g, -1.0))
            if self.audit is not None:
                self.audit.mark("idler" if body else "roller", self, pin, bodies)

        # tyres: both half-wheels at the wheel's compression, the generalized force minus
        # the load times the compression's gradient (shared among the links beneath by
        # their weights in the blend, each along its own normal)
        loads, slopes, rate_slopes = v.tyre_loads(self.compression, self.compression_rate)
        self.tyre_force = np.where(self.in_contact, loads, 0.0)
        self.tyre_terms = [(w, self.tyre_force[w], slopes[w], rate_slopes[w])
                           for w in np.flatnonzero(self.tyre_force > 0.0)]
        # pushes the compression back: minus the load times the gradient, by weight
        share = -(self.tyre_force[self.pair_wheel] * self.pair_weight)[:, None] * self.pair_gradient
        tyres = np.bincount(self.pair_coordinates.ravel(), share.ravel(),
                            minlength=3 * len(self.nodes))
        if self.audit is not None:
            self.audit.power["tyres"] = float(tyres @ self.qd)

        seat = self.onto_seats(pin)
        if v.settling:  # to rest: damping of every body's velocity
            settle_damping(self, bodies, seat)
        self.onto_links(bodies, seat)
        self.generalized = bodies.reshape(-1) + tyres

    @staticmethod
    def onto_seats(pin):
        """Forces on the pins as forces on the seats of the links either side, half each."""
        return np.stack([0.5 * pin, 0.5 * np.roll(pin, -1, axis=0)], axis=1)

    def onto_links(self, bodies, seat):
        """Adds forces on the links' seats to the links' generalized forces in `bodies`."""
        links = slice(self.link0, None)
        r0, r1 = self.seats[:, 0] - self.link_pos, self.seats[:, 1] - self.link_pos
        bodies[links, :2] += seat[:, 0] + seat[:, 1]
        bodies[links, 2] += (r0[:, 0] * seat[:, 0, 1] - r0[:, 1] * seat[:, 0, 0]
                             + r1[:, 0] * seat[:, 1, 1] - r1[:, 1] * seat[:, 1, 0])

    def _engagement(self, into):
        """The teeth's hold w on a pin by its angle into the wrap, taken up and let go over
        ENGAGEMENT_RAMP at the wrap's ends (smoothsteps: the ramp force has no jump), and
        its first and second derivatives by that angle."""
        rise = into / ENGAGEMENT_RAMP
        fall = (self.wrap_sweep - into) / ENGAGEMENT_RAMP
        (a, da, dda), (b, db, ddb) = smoothstep_derivatives(rise), smoothstep_derivatives(fall)
        return (a * b, (da * b - a * db) / ENGAGEMENT_RAMP,
                (dda * b - 2.0 * da * db + a * ddb) / ENGAGEMENT_RAMP ** 2)

    # --- checks and records ---------------------------------------------------------------

    def check(self, t, q=None, qd=None):
        """Stop with the part and the time where the model no longer holds (at the
        host's current state, or at q, qd: evaluate's; the kinematics alone are read)."""
        self.evaluate(t, q, qd, laws=False)
        (compression, _), (gap, _) = self.last("compression"), self.last("tooth_gap")
        # the wheels one by one only where one is out of bounds (the first named)
        if compression.max() > lay.TYRE_RUBBER or compression.min() < -HORN_HEIGHT:
            w = np.flatnonzero((compression > lay.TYRE_RUBBER)
                               | (compression < -HORN_HEIGHT))[0]
            compression = compression[w]
            if compression > lay.TYRE_RUBBER:
                raise VehicleError(
                    f"road wheel {w + 1}: a track link has passed through its tyre (compressed "
                    f"{compression * 1e3:.1f} mm, more than the {lay.TYRE_RUBBER * 1e3:.1f} mm "
                    f"of rubber, section 5.1.1) at t = {t:.4f} s; lower --speed or choose a "
                    f"gentler course")
            if compression < -HORN_HEIGHT:
                raise VehicleError(
                    f"road wheel {w + 1} has left the track (more than {HORN_HEIGHT * 1e3:g} mm "
                    f"above the link beneath, the guide horns' height) at t = {t:.4f} s; "
                    f"lower --speed or choose a gentler course")
        if gap.max() > 0.3 * lay.LINK_PITCH:
            j = int(np.argmax(gap))
            raise VehicleError(f"the track jumped a sprocket tooth at joint {j} at "
                               f"t = {t:.4f} s; lower --speed or choose a gentler course")

    def tension_joints(self, hulls=None, pins=None):
        """The joints nearest the points where the tensions are read, at the last
        evaluation, or (n x 2) at each state whose hulls (n x 3) and pins are given."""
        if hulls is None:
            return [int(j) for j in self.tension_joints(self.hull[None], self.pins[None])[0]]
        points = np.array([[hull[:2] + rotate(hull[2], local) for local in self.tension_points]
                           for hull in hulls])  # n x 2 x 2
        return np.argmin(np.hypot(*(pins[:, None] - points[:, :, None]).transpose(3, 0, 1, 2)),
                         axis=2)
