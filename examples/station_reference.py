"""The road-wheel station's independent reference: its equations of motion written out
here (Lagrange's equations in two coordinates, not exudyn's formulation) and integrated
monolithically with the tyre's and the damper's Model Exchange FMUs by scipy's Radau at
tight tolerance (fmu_components.verification.monolithic).

Coordinates: y, the hull's rise from the static point, and psi, the arm's rotation from
it (counter-clockwise, so the wheel drops for psi > 0). With beta = ARM_STATIC_ANGLE + psi
the wheel centre is at (-L cos beta, y - L sin beta) from the static pivot, the arm's
centre of mass halfway. The wheel spins freely on the arm and carries no moment: its spin
is left out. Generalized forces on psi: gravity, the torsion bar's preload - k psi, the
damper's torque T(-psi, -psi') (its input is the rotation in bump, -psi) and the tyre's
2 F at the wheel centre, upward.

    M = [[M_h + m_a + m_w,   -c cos beta],        c = m_a L/2 + m_w L
         [-c cos beta,        m_a L^2/4 + I_a + m_w L^2]]
    M [y'', psi'']^T = Q - [c sin beta psi'^2, 0]^T
"""

import math

import numpy as np

from fmu_components.verification.monolithic import ModelExchangeComponent, MonolithicSystem

import road_wheel_station as station
from example_fmus import fmu_path

L = station.ARM_LENGTH
ALPHA = station.ARM_STATIC_ANGLE
C = station.ARM_MASS * L / 2 + station.WHEEL_MASS * L
ARM_INERTIA = station.ARM_MASS * L ** 2 / 12  # about its centre, as the exudyn model has it


def solve_reference(speed, profile, end_time, t_eval, fmu_dir=None, rtol=1e-10, reached=None):
    """Histories of the station at `speed` (m/s) over `profile`, at t_eval: the same
    names as Station.run. reached(t), if given, hears the times the solver evaluates (a
    progress bar)."""
    static_compression, static_load = station.static_tyre_point(fmu_dir)
    preload = station.torsion_bar_preload(station.TYRES_PER_WHEEL * static_load)
    masses = station.HULL_MASS + station.ARM_MASS + station.WHEEL_MASS
    g = station.GRAVITY

    def tyre_kinematics(t, q, qdot):
        y, psi = q
        ydot, psidot = qdot
        beta = ALPHA + psi
        dx, dy = L * (math.cos(ALPHA) - math.cos(beta)), y - L * (math.sin(beta) - math.sin(ALPHA))
        vx, vy = L * math.sin(beta) * psidot, ydot - L * math.cos(beta) * psidot
        height, slope = profile.height_and_slope(speed * t + dx)
        return static_compression - dy + height, -vy + slope * (speed + vx)

    def damper_kinematics(t, q, qdot):
        return -q[1], -qdot[1]

    def accelerations(t, q, qdot, loads):
        if reached is not None:
            reached(t)
        tyre_force, damper_torque = loads
        y, psi = q
        psidot = qdot[1]
        beta = ALPHA + psi
        wheel_force = station.TYRES_PER_WHEEL * tyre_force
        mass = np.array([[masses, -C * math.cos(beta)],
                         [-C * math.cos(beta), station.ARM_MASS * L ** 2 / 4 + ARM_INERTIA
                          + station.WHEEL_MASS * L ** 2]])
        forces = np.array([
            -masses * g + wheel_force - C * math.sin(beta) * psidot ** 2,
            g * C * math.cos(beta) + preload - station.TORSION_BAR_STIFFNESS * psi
            + damper_torque - wheel_force * L * math.cos(beta)])
        return np.linalg.solve(mass, forces)

    tyre = ModelExchangeComponent(fmu_path("RoadWheelTyre", fmu_dir), "tyre_me")
    damper = ModelExchangeComponent(fmu_path("RotaryDamper", fmu_dir), "damper_me")
    system = MonolithicSystem(2, accelerations, [(tyre, tyre_kinematics),
                                                 (damper, damper_kinematics)])
    try:
        times, states, outputs = system.solve(end_time, [0.0, 0.0], [0.0, 0.0], t_eval,
                                              rtol=rtol)
    finally:
        system.free()
    tyre_out = np.array([o[0]["force"] for o in outputs])
    torque = np.array([o[1]["torque"] for o in outputs])
    accelerations_ = np.array([accelerations(t, y[:2], y[2:4], [f, m])
                               for t, y, f, m in zip(times, states, tyre_out, torque)])
    hull_acceleration = accelerations_[:, 0]
    return {"time": times, "hull_acceleration": hull_acceleration,
            "hull_force": station.HULL_MASS * (hull_acceleration + g),
            "arm_angle": -states[:, 1], "damper_torque": torque,
            "tyre_compression": np.array([tyre_kinematics(t, y[:2], y[2:4])[0]
                                          for t, y in zip(times, states)]),
            "tyre_force": station.TYRES_PER_WHEEL * tyre_out,
            "evaluations": system.evaluations, "events": system.events}
