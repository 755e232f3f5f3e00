"""The reduced vehicle (ground.py) in exudyn, its FMUs coupled by fmu_components.coupling:
the compiled path (the bank, docs/coupling.md "The bank": the tyres' compression and every
load law in exudyn's compiled symbolic functions) or the Python path; or with the linear
Kelvin elements of the full vehicle (model.Linear) in place of the FMUs.

Bodies: the hull, its surge held (the course moves under it at the set speed); six arms,
each with its wheel, on revolute joints at their pivots. Force elements: the torsion bars
(preloaded coordinate springs), the dampers (coordinate connectors, the damper's torque
at the arm's rotation in bump) and, per wheel, a Cartesian connector from the wheel's
static position that pushes the wheel up by its two tyre halves' forces.
"""

import math
import warnings

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (CoordinateConstraint, LoadForceVector, NodePointGround,
                                  NodeRigidBody2D,
                                  ObjectConnectorCartesianSpringDamper,
                                  ObjectConnectorCoordinateSpringDamper, ObjectGround,
                                  ObjectJointRevolute2D, ObjectRigidBody2D)

from fmu_components.coupling import DEFAULT_SCHEME, Coupling, FmuComponent
from fmu_components.coupling.exudyn_host import connector_state

import bank_path
from example_fmus import fmu_path

from . import ground
from . import layout as lay
from .course import Bump, Sine
from .ground import DAMPED, N, Reduced
from .model import Linear, RelaxedTable, VehicleError, markers

SIDES = ("left", "right")
TYRE_RANGE = RelaxedTable.RANGES["RoadWheelTyre"][1]  # m


class GroundLinear(Linear):
    """The full vehicle's Kelvin equivalents (model.Linear: the same sines) of the two
    components the reduced vehicle has."""
    SINES = {name: Linear.SINES[name] for name in ("RoadWheelTyre", "RotaryDamper")}


def linearisation(fmu_dir=None):
    """The Kelvin elements about the reduced vehicle's nominal tyre compression."""
    tyre = FmuComponent(fmu_path("RoadWheelTyre", fmu_dir), "tyre_nominal")
    try:
        compression = ground.nominal_compression(relaxed(tyre))
    finally:
        tyre.free()
    return GroundLinear((compression, 0.0, 0.0), fmu_dir)


def make_components(fmu_dir=None, linear=None):
    """(tyres [[left, right] per wheel], dampers [per damped station]): FmuComponents, or
    Kelvin elements from `linear`."""
    def make(fmu, name, unilateral=False):
        if linear is not None:
            return linear.element(fmu, name, unilateral)
        return FmuComponent(fmu_path(fmu, fmu_dir), name, unilateral=unilateral)

    tyres = [[make("RoadWheelTyre", f"tyre_{i + 1}_{side}", True) for side in SIDES]
             for i in range(N)]
    dampers = [make("RotaryDamper", f"damper_{i + 1}") for i in DAMPED]
    return tyres, dampers


def relaxed(component):
    """The component's load at rest at a deflection (before it starts)."""
    return lambda x: component.host_load(x, 0.0)


def symbolic_height(course, x, laws):
    """The course's height at a symbolic x (Bump and Sine, the same expressions as
    course.py's)."""
    esym = laws.esym
    if isinstance(course, Bump):
        u = (x - course.front - course.start) / course.length
        bump = 0.5 * course.bump_height * (1 - esym.cos(2 * math.pi * u))
        return laws.when(u > 0.0, laws.when(u < 1.0, bump, 0.0), 0.0)
    u = (x - course.front - course.start) / course.wavelength
    return laws.when(u > 0.0, course.amplitude * (1 - esym.cos(2 * math.pi * u)), 0.0)


class GroundVehicle:
    """The reduced vehicle in exudyn over `course` at `speed`; `run` drives it."""

    def __init__(self, course, speed, fmu_dir=None, linear=None, coupling=DEFAULT_SCHEME,
                 path=bank_path.DEFAULT_PATH, reached=None):
        self.course, self.speed, self.reached = course, speed, reached
        self.tyres, self.dampers = make_components(fmu_dir, linear)
        self.reduced = red = Reduced(course, speed, relaxed(self.tyres[0][0]),
                                     relaxed(self.dampers[0]))
        self.instances = 2 * N + len(DAMPED)
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        self.SC, self.mbs = SC, mbs

        coordinate, at = markers(mbs)

        q0 = red.q0
        ground_node = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
        self.hull_node = mbs.AddNode(NodeRigidBody2D(
            referenceCoordinates=[*red.cg, 0.0], initialCoordinates=[0.0, q0[0], q0[1]]))
        hull = mbs.AddObject(ObjectRigidBody2D(mass=red.hull_mass, inertia=red.hull_inertia,
                                               nodeNumber=self.hull_node))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[coordinate(ground_node, 0),
                                                          coordinate(self.hull_node, 0)]))
        hull_rotation = coordinate(self.hull_node, 2)
        bodies = [(hull, red.hull_mass)]

        _, _, e_ref = red.frames(np.zeros(ground.COORDINATES))
        centre0, u0, e0 = red.frames(q0)
        self.tyre_connectors, self.damper_connectors = [], []
        for i in range(N):
            pivot = red.cg + red.pivot_offsets[i]
            com = pivot + ground.ARM_COM * e_ref[i]
            com0 = centre0 + u0[i] + ground.ARM_COM * e0[i]
            node = mbs.AddNode(NodeRigidBody2D(
                referenceCoordinates=[*com, 0.0],
                initialCoordinates=[*(com0 - com), q0[1] + q0[2 + i]]))
            arm = mbs.AddObject(ObjectRigidBody2D(mass=ground.ARM_BODY_MASS,
                                                  inertia=ground.ARM_BODY_INERTIA,
                                                  nodeNumber=node))
            bodies.append((arm, ground.ARM_BODY_MASS))
            mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[at(hull, red.pivot_offsets[i]),
                                                               at(arm, pivot - com)]))
            arm_rotation = coordinate(node, 2)
            # the rotation in bump, q_hull - q_arm; +f turns the arm in +psi (model.py's)
            mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
                markerNumbers=[arm_rotation, hull_rotation], stiffness=lay.TORSION_BAR_STIFFNESS,
                offset=-red.preload / lay.TORSION_BAR_STIFFNESS))
            if i in DAMPED:
                damper = self.dampers[DAMPED.index(i)]
                self.damper_connectors.append(mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
                    markerNumbers=[arm_rotation, hull_rotation],
                    springForceUserFunction=lambda mbs, t, item, x, v, *_, d=damper:
                        d.host_load(x, v))))
            wheel = red.wheel_centres[i]
            static = mbs.AddObject(ObjectGround(referencePosition=[*wheel, 0.0]))
            self.tyre_connectors.append(mbs.AddObject(ObjectConnectorCartesianSpringDamper(
                markerNumbers=[at(static, [0.0, 0.0]), at(arm, wheel - com)],
                springForceUserFunction=lambda mbs, t, item, d, v, *_, w=i:
                    self._tyre_force(w, t, d, v))))
        for body, mass in bodies:
            mbs.AddLoad(LoadForceVector(markerNumber=at(body, [0.0, 0.0]),
                                        loadVector=[0.0, -mass * lay.GRAVITY, 0.0]))

        self.components = [t for pair in self.tyres for t in pair] + self.dampers
        self.compiled = linear is None and bank_path.compiled(path, coupling)
        if self.compiled and not isinstance(course, (Bump, Sine)):
            warnings.warn(f"the {course.name} course has no compiled height; taking the "
                          f"Python path", stacklevel=2)
            self.compiled = False
        self.coupling = Coupling(coupling, record=self._record)
        for i, pair in enumerate(self.tyres):
            for tyre in pair:
                self.coupling.add(tyre, lambda w=i: self._tyre_state(w))
        for damper, connector in zip(self.dampers, self.damper_connectors):
            self.coupling.add(damper, lambda c=connector: tuple(
                map(float, connector_state(self.mbs, c))))
        mbs.Assemble()
        self.records = []
        if self.compiled:
            self._compile_forces(coupling)

    # --- the tyres' compression, shared by the force functions and the coupling -----------

    def _compression(self, w, t, displacement, velocity):
        """Wheel w's tyre compression and its rate from its centre's displacement from the
        layout's static point (ground.Reduced.tyre_compressions' expression)."""
        x0, y0 = self.reduced.wheel_centres[w]
        x = x0 + displacement[0] + self.speed * t
        height, slope = ground.course_height_and_slope(self.course, x)
        compression = float(height) + ground.TRACK_THICKNESS + lay.WHEEL_RADIUS \
            - (y0 + displacement[1])
        return compression, float(slope) * (self.speed + velocity[0]) - velocity[1]

    def _tyre_force(self, w, t, displacement, velocity):
        compression, rate = self._compression(w, t, displacement, velocity)
        return [0.0, -sum(tyre.host_load(compression, rate) for tyre in self.tyres[w]), 0.0]

    def _tyre_state(self, w):
        return self._compression(w, self.mbs.systemData.GetTime(),
                                 *connector_state(self.mbs, self.tyre_connectors[w]))

    def _deflections(self):
        tyres = [self._tyre_state(w)[0] for w in range(N)]
        dampers = [float(connector_state(self.mbs, c)[0]) for c in self.damper_connectors]
        return np.array([x for x in tyres for _ in range(2)] + dampers)

    def _compile_forces(self, scheme):
        """The compiled path: each connector's force the symbolic laws of its instances in
        one bank, the compression the same expression as _compression's."""
        self.bank = bank_path.Bank(self.components, scheme, record=self._record)
        laws = self.laws = bank_path.SymbolicLaws(self.bank, name="ground_vehicle_laws")
        speed, course = self.speed, self.course

        def tyre(w):
            x0, y0 = self.reduced.wheel_centres[w]

            def force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
                height = symbolic_height(course, x0 + displacement[0] + speed * t, laws)
                compression = height + (ground.TRACK_THICKNESS + lay.WHEEL_RADIUS - y0) \
                    - displacement[1]
                load = laws.load(2 * w, compression) + laws.load(2 * w + 1, compression)
                return [0.0 * height, -load, 0.0 * height]
            return force

        def damper(k):
            def torque(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
                return laws.load(2 * N + k, displacement)
            return torque

        self._symbolic = (
            [bank_path.symbolic_function(self.mbs, c, tyre(w))
             for w, c in enumerate(self.tyre_connectors)]
            + [bank_path.symbolic_function(self.mbs, c, damper(k))
               for k, c in enumerate(self.damper_connectors)])

    # --- records and the run ----------------------------------------------------------------

    def _record(self, t):
        node = self.mbs.GetNodeOutput
        acceleration = node(self.hull_node, exu.OutputVariableType.Coordinates_tt)
        position = node(self.hull_node, exu.OutputVariableType.Coordinates)
        velocity = node(self.hull_node, exu.OutputVariableType.Coordinates_t)
        if self.compiled:
            loads, deflections = self.bank.loads, self.bank.accepted[:, 1]
        else:
            loads = np.array([c.load for c in self.components])
            deflections = np.array([c.deflection for c in self.components])
        compression = deflections[:2 * N:2]
        if np.max(compression) > TYRE_RANGE:
            w = int(np.argmax(compression))
            raise VehicleError(f"wheel {w + 1}'s tyre is compressed {compression[w] * 1e3:.1f} "
                               f"mm at t = {t:.4f} s, beyond the {TYRE_RANGE * 1e3:g} mm its "
                               f"model was measured to (the FMU clamps there): the course is "
                               f"too rough for {self.speed:g} m/s; lower --speed or choose "
                               f"another --course")
        if self.reached is not None:
            self.reached(t)
        self.records.append((t, acceleration[1], acceleration[2], position[2], velocity[2],
                             loads[:2 * N].reshape(N, 2).sum(axis=1), loads[2 * N:].copy(),
                             deflections[2 * N:].copy(), deflections[:2 * N:2].copy()))

    def run(self, end_time, step):
        """Integrate to end_time at a fixed host step; the recorded histories."""
        bank_path.run(self, end_time, step)
        return histories(self.records, self.reduced)


HISTORY_NAMES = ("time", "hull_vertical_acceleration", "hull_pitch_acceleration",
                 "hull_pitch", "hull_pitch_rate", "tyre_force", "damper_torque",
                 "damper_rotation", "tyre_compression")


def histories(records, reduced):
    """Records (one tuple per accepted step, in HISTORY_NAMES' order) as arrays, with the
    seat's vertical acceleration."""
    found = {name: np.array([r[i] for r in records]) for i, name in enumerate(HISTORY_NAMES)}
    found["seat_acceleration"] = reduced.seat_acceleration(
        found["hull_pitch"], found["hull_pitch_rate"], found["hull_vertical_acceleration"],
        found["hull_pitch_acceleration"])
    return found
