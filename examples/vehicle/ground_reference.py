"""The reduced vehicle's independent reference: its equations of motion (ground.Reduced,
Lagrange's equations in the hull's rise and pitch and the arms' rotations, not exudyn's
bodies and joints) and the tyres' and dampers' Model Exchange FMUs in one ODE, integrated
by scipy's Radau at tight tolerance (fmu_components.verification.monolithic), as
examples/station_reference.py does for one station.

The two tyre halves of a wheel see the same compression and rate, so one Model Exchange
instance per wheel stands for both (its force counted twice): the same equations as two
instances, at half the cost. With `linear` (model.Linear) the components are its Kelvin
elements instead, as the co-simulation's `--linear` has them: that run checks the
equations of motion of the two models against each other with no coupling in between.
"""

import numpy as np

from fmu_components.verification.monolithic import ModelExchangeComponent, MonolithicSystem

from example_fmus import fmu_path

from . import layout as lay
from .ground import COORDINATES, DAMPED, N, Reduced


class KelvinModel:
    """A Kelvin element (coupling.kelvin) in ModelExchangeComponent's interface: no
    states, its load at the inputs set."""

    events = ()
    n = 0
    nominals = np.zeros(0)

    def __init__(self, element):
        self.element = element
        self.output_names = [element.load_name]
        self._inputs = (0.0, 0.0)

    def start(self, deflection, rate):
        self._inputs = deflection, rate
        return np.zeros(0)

    def set(self, time, states, deflection, rate):
        self._inputs = deflection, rate

    def derivatives(self):
        return []

    def outputs(self):
        return {self.output_names[0]: self.element.host_load(*self._inputs)}

    def free(self):
        pass


def solve_reference(course, speed, end_time, t_eval, fmu_dir=None, linear=None, rtol=1e-10,
                    reached=None):
    """Histories of the reduced vehicle over `course` at `speed` (m/s), at t_eval: the
    names of ground_exudyn.histories. reached(t), if given, hears the times the solver
    evaluates."""
    if linear is not None:
        tyres = [KelvinModel(linear.element("RoadWheelTyre", f"tyre_{i + 1}", True))
                 for i in range(N)]
        dampers = [KelvinModel(linear.element("RotaryDamper", f"damper_{i + 1}"))
                   for i in DAMPED]
        relaxed = [lambda x, e=m.element: e.host_load(x, 0.0) for m in (tyres[0], dampers[0])]
    else:
        tyres = [ModelExchangeComponent(fmu_path("RoadWheelTyre", fmu_dir), f"tyre_{i + 1}_me")
                 for i in range(N)]
        dampers = [ModelExchangeComponent(fmu_path("RotaryDamper", fmu_dir),
                                          f"damper_{i + 1}_me") for i in DAMPED]
        relaxed = [RelaxedProbe("RoadWheelTyre", fmu_dir), RelaxedProbe("RotaryDamper",
                                                                             fmu_dir)]
    try:
        reduced = Reduced(course, speed, *relaxed)
    finally:
        for probe in relaxed:
            getattr(probe, "free", lambda: None)()

    def tyre_kinematics(w):
        return lambda t, q, qdot: tuple(a[w] for a in reduced.tyre_compressions(t, q, qdot))

    def damper_kinematics(i):
        return lambda t, q, qdot: (-q[2 + i], -qdot[2 + i])

    def accelerations(t, q, qdot, loads):
        if reached is not None:
            reached(t)
        return reduced.accelerations(q, qdot, lay.TYRES_PER_WHEEL * np.asarray(loads[:N]),
                                     loads[N:])

    components = ([(tyre, tyre_kinematics(w)) for w, tyre in enumerate(tyres)]
                  + [(damper, damper_kinematics(i)) for damper, i in zip(dampers, DAMPED)])
    system = MonolithicSystem(COORDINATES, accelerations, components)
    try:
        times, states, outputs = system.solve(end_time, reduced.q0, np.zeros(COORDINATES),
                                              t_eval, rtol=rtol)
    finally:
        system.free()
    loads = np.array([[out[c.output_names[0]] for out, (c, _) in zip(row, components)]
                      for row in outputs])
    q, qdot = states[:, :COORDINATES], states[:, COORDINATES:2 * COORDINATES]
    qddot = np.array([reduced.accelerations(a, b, lay.TYRES_PER_WHEEL * f[:N], f[N:])
                      for a, b, f in zip(q, qdot, loads)])
    found = {"time": times, "hull_vertical_acceleration": qddot[:, 0],
             "hull_pitch_acceleration": qddot[:, 1], "hull_pitch": q[:, 1],
             "hull_pitch_rate": qdot[:, 1], "tyre_force": lay.TYRES_PER_WHEEL * loads[:, :N],
             "damper_torque": loads[:, N:],
             "damper_rotation": -q[:, [2 + i for i in DAMPED]],
             "tyre_compression": np.array([reduced.tyre_compressions(t, a, b)[0]
                                           for t, a, b in zip(times, q, qdot)]),
             "evaluations": system.evaluations, "events": system.events}
    found["seat_acceleration"] = reduced.seat_acceleration(
        found["hull_pitch"], found["hull_pitch_rate"], found["hull_vertical_acceleration"],
        found["hull_pitch_acceleration"])
    return found


class RelaxedProbe:
    """The relaxed load of a co-simulation instance of the FMU (for the static point)."""

    def __init__(self, name, fmu_dir):
        from fmu_components.coupling import FmuComponent
        self.component = FmuComponent(fmu_path(name, fmu_dir), f"{name}_static")

    def __call__(self, x):
        return self.component.relaxed_outputs(x)[self.component.load_name]

    def free(self):
        self.component.free()
