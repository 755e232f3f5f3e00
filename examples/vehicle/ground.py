"""The reduced vehicle: the tracked vehicle's hull and six road-wheel stations with the
track replaced by ground-laid contact, and its equations of motion written out here.

The hull (bounce y and pitch theta about its centre of gravity; its surge held at the set
speed, so the course moves under it) carries six trailing arms, each with its road wheel
(one rigid body: the wheel's spin is left out, the contact is frictionless), a preloaded
linear torsion bar, and a RotaryDamper at the damped stations; the values are the full
vehicle's (layout.py; docs/vehicle.md). The track is laid on the ground as a rigid layer
of the links' thickness: each wheel's two RoadWheelTyre halves are compressed by the
course's height under the wheel centre, as in examples/road_wheel_station.py, and push it
up.

Coordinates q = [y, theta, psi_1 .. psi_6]: the hull's rise and pitch (nose up) from the
layout's static point, and each arm's rotation from its static angle relative to the hull
(counter-clockwise, so the wheel drops for psi > 0; the damper's input, the rotation in
bump, is -psi). Lagrange's equations of the rigid bodies, in the form

    M(q) q'' = Q(q, q', loads) - sum_bodies m J^T (dJ/dt q'),

J the Jacobian of a body's centre of mass (examples/vehicle/ground_reference.py integrates
them with the Model Exchange FMUs; the exudyn model, ground_exudyn.py, is built from
bodies and joints and starts from the static point found here).
"""

import math

import numpy as np
from scipy.optimize import brentq, fsolve

from . import layout as lay
from .layout import GRAVITY

ARM_BODY_MASS = lay.ARM_MASS + lay.WHEEL_MASS
# the arm with its wheel as one body: its centre of mass from the pivot and its inertia
ARM_COM = (0.5 * lay.ARM_MASS + lay.WHEEL_MASS) * lay.ARM_LENGTH / ARM_BODY_MASS
ARM_BODY_INERTIA = (lay.ARM_MASS * lay.ARM_LENGTH ** 2 / 12
                    + lay.ARM_MASS * (0.5 * lay.ARM_LENGTH - ARM_COM) ** 2
                    + lay.WHEEL_MASS * (lay.ARM_LENGTH - ARM_COM) ** 2)
TRACK_THICKNESS = lay.LINK_OUTER + lay.LINK_INNER  # the links laid under the wheels
TRACK_LINKS = 80  # the full vehicle's loop (model.TRACK_LINKS): the hull is its hull
DAMPED = tuple(i - 1 for i in lay.DAMPED_STATIONS)  # station indices with a damper
N = lay.STATIONS
COORDINATES = 2 + N
SLOPE_STEP = 1e-5  # m: the course's slope by central difference


def perp(v):
    """v turned by +90 degrees (the derivative of a rotating vector by its angle)."""
    return np.stack([-v[..., 1], v[..., 0]], axis=-1)


def nominal_wheel_load():
    """What each wheel carries with the hull level: the hull and the arms over six (N)."""
    return (lay.side_masses(TRACK_LINKS)[0] + N * ARM_BODY_MASS) * GRAVITY / N


def nominal_compression(tyre_relaxed):
    """The compression at which a wheel's two relaxed tyre halves carry the nominal load."""
    load = nominal_wheel_load()
    return brentq(lambda x: lay.TYRES_PER_WHEEL * tyre_relaxed(x) - load, 1e-5, 9e-3,
                  xtol=1e-13)


def course_height_and_slope(course, x):
    height = course.height(x)
    slope = (course.height(x + SLOPE_STEP) - course.height(x - SLOPE_STEP)) / (2 * SLOPE_STEP)
    return height, slope


class Reduced:
    """The reduced vehicle's geometry, masses and equations of motion over `course` at
    `speed` (m/s). tyre_relaxed(x), damper_relaxed(x): the relaxed load of one tyre half
    and of a damper at a deflection (the FMUs' own, or a Kelvin element's), for the
    static point."""

    def __init__(self, course, speed, tyre_relaxed, damper_relaxed):
        self.course, self.speed = course, speed
        self.hull_mass, self.hull_inertia = lay.side_masses(TRACK_LINKS)
        self.wheel_load = nominal_wheel_load()
        self.nominal_compression = nominal_compression(tyre_relaxed)
        geometry = lay.Layout(self.nominal_compression, lay.LINK_PITCH)
        self.cg = geometry.cg
        self.pivot_offsets = geometry.pivots - geometry.cg  # in the hull's frame
        self.wheel_centres = geometry.wheel_centres  # at q = 0
        self.station_x = geometry.station_x
        # Torsion-bar preload: the arm's moment balance about its pivot at the nominal load.
        lever = lay.ARM_LENGTH * math.cos(lay.ARM_STATIC_ANGLE)
        self.preload = ((self.wheel_load - lay.WHEEL_MASS * GRAVITY) * lever
                        - lay.ARM_MASS * GRAVITY * 0.5 * lever)
        self.q0 = self.static_point(tyre_relaxed, damper_relaxed)

    # --- kinematics -------------------------------------------------------------------------

    def frames(self, q):
        """(hull centre, pivot offsets u_i, arm directions e_i (pivot to wheel, unit)) at q."""
        y, theta, psi = q[0], q[1], np.asarray(q[2:])
        c, s = math.cos(theta), math.sin(theta)
        p = self.pivot_offsets
        u = np.stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]], axis=-1)
        phi = lay.ARM_STATIC_ANGLE + psi + theta
        e = -np.stack([np.cos(phi), np.sin(phi)], axis=-1)
        return np.array([0.0, self.cg[1] + y]), u, e

    def point_jacobians(self, u, r):
        """Jacobians (N x 2 x COORDINATES) of the points at u_i + r_i from the hull's centre,
        r_i turning with arm i."""
        jac = np.zeros((N, 2, COORDINATES))
        jac[:, 1, 0] = 1.0
        jac[:, :, 1] = perp(u + r)
        jac[np.arange(N), :, 2 + np.arange(N)] = perp(r)
        return jac

    def wheels(self, q, qdot):
        """Wheel centres and their velocities (N x 2 each)."""
        centre, u, e = self.frames(q)
        r = lay.ARM_LENGTH * e
        velocity = self.point_jacobians(u, r) @ np.asarray(qdot)
        return centre + u + r, velocity

    def tyre_compressions(self, t, q, qdot):
        """Each wheel's tyre compression and its rate: the course's height under the wheel
        centre (the hull travels at `speed`), the track's thickness on it, less the wheel's
        underside's height."""
        position, velocity = self.wheels(q, qdot)
        x = position[:, 0] + self.speed * t
        height, slope = course_height_and_slope(self.course, x)
        compression = height + TRACK_THICKNESS - (position[:, 1] - lay.WHEEL_RADIUS)
        rate = slope * (self.speed + velocity[:, 0]) - velocity[:, 1]
        return compression, rate

    # --- equations of motion ----------------------------------------------------------------

    def accelerations(self, q, qdot, wheel_forces, damper_torques):
        """q'' for each wheel's vertical tyre force (both halves) and each damper's torque
        (in DAMPED's order; positive turns the arm in +psi, as the damper's torque does at
        its input -psi)."""
        q, qdot = np.asarray(q, float), np.asarray(qdot, float)
        _, u, e = self.frames(q)
        m, inertia, g = ARM_BODY_MASS, ARM_BODY_INERTIA, GRAVITY
        mass = np.zeros((COORDINATES, COORDINATES))
        mass[0, 0], mass[1, 1] = self.hull_mass, self.hull_inertia
        forces = np.zeros(COORDINATES)
        forces[0] = -self.hull_mass * g
        arm = ARM_COM * e
        jac = self.point_jacobians(u, arm)
        omega = np.zeros((N, COORDINATES))  # each arm's angular velocity: theta' + psi_i'
        omega[:, 1] = 1.0
        omega[np.arange(N), 2 + np.arange(N)] = 1.0
        mass += m * np.einsum("nki,nkj->ij", jac, jac) + inertia * omega.T @ omega
        # dJ/dt q' of each arm's centre: the centripetal terms of its two turning vectors
        theta_rate, psi_rate = qdot[1], qdot[2:]
        bias = -u * theta_rate ** 2 - arm * ((theta_rate + psi_rate) ** 2)[:, None]
        forces -= m * np.einsum("nki,nk->i", jac, bias)
        forces += np.einsum("nki,k->i", jac, np.array([0.0, -m * g]))
        wheel_jac = self.point_jacobians(u, lay.ARM_LENGTH * e)
        forces += wheel_jac[:, 1, :].T @ np.asarray(wheel_forces, float)
        psi = q[2:]
        forces[2:] += self.preload - lay.TORSION_BAR_STIFFNESS * psi
        forces[[2 + i for i in DAMPED]] += damper_torques
        return np.linalg.solve(mass, forces)

    def static_point(self, tyre_relaxed, damper_relaxed):
        """q where the relaxed vehicle stands still on the flat start of the course."""
        zero = np.zeros(COORDINATES)

        def residual(q):
            compression, _ = self.tyre_compressions(0.0, q, zero)
            forces = [lay.TYRES_PER_WHEEL * tyre_relaxed(x) for x in compression]
            torques = [damper_relaxed(-q[2 + i]) for i in DAMPED]
            return self.accelerations(q, zero, forces, torques)

        q0, info, found, message = fsolve(residual, zero, xtol=1e-13, full_output=True)
        if found != 1 or np.max(np.abs(residual(q0))) > 1e-8:
            raise RuntimeError(f"the reduced vehicle's static point: {message}")
        return q0

    # --- what the hull feels ----------------------------------------------------------------

    def seat_acceleration(self, theta, theta_rate, y_acceleration, theta_acceleration):
        """Vertical acceleration at the driver's seat (layout.SEAT from the centre of
        gravity, in the hull's frame)."""
        sx, sy = lay.SEAT
        c, s = np.cos(theta), np.sin(theta)
        along, up = c * sx - s * sy, s * sx + c * sy  # the seat from the CG, turned
        return y_acceleration + theta_acceleration * along - theta_rate ** 2 * up
