"""One side of the tracked vehicle in exudyn (2D, the pitch plane), its running-gear parts
as FMUs coupled by fmu_components.coupling (docs/coupling.md), or as linear Kelvin
elements.

Bodies: the hull (surge, bounce, pitch); six trailing arms, each carrying its road wheel
(the wheel's spin is left out: the tyre contact is frictionless); the idler on its crank;
a closed loop of links. The sprocket is part of the hull and turns with its travel.

Force elements:
* joints between links: TrackBushRadial (distance between the pin seats, along that line)
  and TrackBushTorsion (the angle between the links, zero in line, positive bent towards
  the loop's inside, as round the sprocket) FMU instances, as in examples/track_span.py:
  one object computing all their forces with their Jacobian (joints.py), or two exudyn
  connectors each;
* arms: a preloaded linear torsion bar, and a RotaryDamper at the damped stations (input
  the arm's rotation from static, positive in bump, as in examples/road_wheel_station.py);
* tyres: two RoadWheelTyre instances per wheel, one per half-wheel, both compressed by the
  wheel's overlap with the face of the link beneath it (the contact: see `Contacts`);
* contacts computed here (penalty, no FMU): pins on the ground, the sprocket's teeth, the
  idler and the support roller; the idler's tensioner a preloaded spring at its crank;
* surge: a speed-holding force on the hull (the tractive effort, not modelled in detail).
"""

import functools
import math

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (LoadMassProportional, MarkerBodyMass, MarkerBodyPosition,
                                  MarkerNodeCoordinate, NodePointGround, NodeRigidBody2D,
                                  ObjectConnectorSpringDamper,
                                  ObjectConnectorCoordinateSpringDamper, ObjectJointRevolute2D,
                                  ObjectRigidBody2D)

from fmu_components.coupling import Coupling, FmuComponent, StepRefused
from fmu_components.coupling.exudyn_host import connector_state, quiet_settings, solve
from fmu_components.coupling.kelvin import KelvinElement, harmonic_kelvin_equivalent

import bank_path
from example_fmus import fmu_path

from . import layout as lay
from .law_slopes import load_and_slopes
from .layout import GRAVITY

# Penalty contacts (assumed; docs/vehicle.md): steel on a hard road, steel teeth.
GROUND_STIFFNESS, GROUND_DAMPING = 5e6, 4e3  # N/m, N.s/m per pin
SPROCKET_STIFFNESS, SPROCKET_DAMPING = 5e6, 3e3  # per engaged pin
WHEEL_STIFFNESS, WHEEL_DAMPING = 5e6, 3e3  # idler and roller, per pin
ENGAGEMENT_RAMP = math.radians(12.0)  # a tooth takes up / lets go of its pin over this
TENSIONER_DAMPING = 3e3  # N.m.s/rad (assumed)
SURGE_FREQUENCY = 0.5  # Hz, the speed hold's (critically damped)
# Where the run stops: a wheel more than this above the link beneath has left the track
# (the track's guide horns are about this high; assumed); a compression beyond the tyre's
# rubber means the link has passed through it (section 5.1.1).
HORN_HEIGHT = 0.05
VERBOSE = 0  # exudyn's solver output while settling (1: per step)
# exudyn's Newton also stops when its residual's norm over the number of coordinates is
# below this (besides 1e-8 of its first residual). Its scale follows exudyn's formulation
# and the step, so it is not a force in newtons; 0.1 moved the histories at 1 m/s by at
# most 2e-4 % of the hull accelerations' range (docs/vehicle.md). Without it only the
# relative test decides, which asks a pass that starts from the last pass's solution
# (exudyn_host) for the same 1e-8 of its much smaller first residual.
NEWTON_TOLERANCE = 0.1
# generalized-alpha's spectral radius at infinite frequency (exudyn's default 0.9): the
# loop's links turning in phase (about 1.1 kHz, unresolved at 1 ms) are damped out instead
# of ringing into loads across the track (docs/vehicle.md, Loads across the track); 0.6 is
# HHT's alpha = -0.25, within the usual [-1/3, 0]
SPECTRAL_RADIUS = 0.6
# The coupling: `iterated`; `corrected`'s two solves leave up to 1.7 % of range in the
# hull's acceleration on the courses (docs/vehicle.md, The coupling's own error ...)
COUPLING = "iterated"
# The radial bush's force is its law's load along the line between the pin seats; that
# line is undefined where the seats meet, and the law (two-sided, with memory: spec
# section 2) can give a load of either sign there. So the force applied is faded in over
# the seats' first RADIAL_FADE of distance (radial_fade, assumed): it vanishes at zero
# distance and is Lipschitz through it (2 |load| / RADIAL_FADE), whatever the load. 5 um
# is 1/32 of the bush's deflection at the track's tension (0.159 mm at 13 kN): only a
# joint near slack (0.4 kN or less on the elastic rate) feels it. Wider fades (20, 50 um)
# made exudyn shorten more steps at 5 m/s (docs/vehicle.md). A load below zero (the
# law's unloading branch near zero deflection) is not applied (radial_pull, assumed): it
# would push the seats apart along a line whose direction is lost as they meet, a negative
# stiffness across it (-load / distance) that gave a step several solutions and Newton
# cycles (docs/vehicle.md, The radial bush never pushes).
RADIAL_FADE = 5e-6  # m
# How the track's joints are built: one object computing all their forces and their
# Jacobian (joints.py), or two exudyn connectors each (docs/vehicle.md, The joints)
JOINTS = ("kernel", "connectors")
DEFAULT_JOINTS = "kernel"


def markers(mbs):
    """(coordinate(node, index), at(body, local)): markers in `mbs` on a node's coordinate
    and at a point of a body (local x, y), the two kinds the vehicles' elements attach to."""
    def coordinate(node, index):
        return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=index))

    def at(body, local):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=body,
                                                localPosition=[local[0], local[1], 0.0]))
    return coordinate, at


def radial_fade(distance, smaller=min):
    """The share of the radial bush's load applied at its seats' `distance`: s (2 - s),
    s = min(distance / RADIAL_FADE, 1), rising from 0 with slope 2 / RADIAL_FADE to 1 at
    RADIAL_FADE with zero slope (no kink). `smaller` is min for numbers and exudyn's
    symbolic min for the compiled path's expression (compiled.py): one definition, the
    same operations on both paths."""
    s = smaller(distance / RADIAL_FADE, 1.0)
    return s * (2.0 - s)


def radial_pull(load, larger=max):
    """The radial bush's load as the vehicle applies it along its seats' line: never
    pushing them apart, a load below zero cut to zero (NaN passes). `larger` is max for
    numbers and exudyn's symbolic max (b > a ? b : a, as max) for the compiled path's
    expression; the joints' kernels cut it the same way (joints.py, joints.c)."""
    return larger(load, 0.0)


class VehicleError(RuntimeError):
    """The run left what the model can represent: names the part and the time."""


def static_points(fmu_dir=None):
    """(tyre compression at the static wheel load, radial bush deflection at the track
    tension, torsion bush torque in line) from the relaxed FMUs' own outputs."""
    from scipy.optimize import brentq

    tyre = FmuComponent(fmu_path("RoadWheelTyre", fmu_dir), "tyre_static")
    radial = FmuComponent(fmu_path("TrackBushRadial", fmu_dir), "radial_static")
    torsion = FmuComponent(fmu_path("TrackBushTorsion", fmu_dir), "torsion_static")
    try:
        load = wheel_load() / lay.TYRES_PER_WHEEL
        compression = brentq(lambda x: tyre.relaxed_outputs(x)[tyre.load_name] - load,
                             1e-4, 8e-3, xtol=1e-12)
        probe = 1e-4
        stretch = probe * lay.TRACK_TENSION / radial.relaxed_outputs(probe)[radial.load_name]
        return compression, stretch, torsion.relaxed_outputs(0.0)[torsion.load_name]
    finally:
        for component in (tyre, radial, torsion):
            component.free()


TRACK_LINKS = 80  # the loop Layout closes (checked by tests/test_vehicle.py)
GROUND_SHARE = 0.4  # of the track's weight, carried by the ground directly (about its bottom run)


def wheel_load():
    """Static load of one wheel (both half-wheels): the side's mass less what of the track
    lies on the ground, over the stations. The static solve refines it."""
    track = TRACK_LINKS * lay.LINK_MASS
    return (lay.SIDE_MASS - GROUND_SHARE * track) * GRAVITY / lay.STATIONS


class RelaxedTable:
    """The relaxed component's load against its deflection, tabulated from an FMU's own
    output before start (a Kelvin element: its static law): the vehicle settles to its
    static point on these instead of calling 160 FMUs at every iterate."""

    # within what the thesis measured, where the FMUs do not warn (they clamp beyond)
    RANGES = {"RoadWheelTyre": (-0.005, 0.0099), "TrackBushRadial": (0.0, 3e-3),
              "TrackBushTorsion": (-0.22, 0.575), "RotaryDamper": (-0.78, 0.78)}

    def __init__(self, component, fmu):
        low, high = self.RANGES[fmu]
        self.x = np.linspace(low, high, 1201)
        self.load = np.array([component.host_load(x) for x in self.x])

    def __call__(self, deflection, rate=0.0):
        return float(np.interp(deflection, self.x, self.load))


class Linear:
    """Kelvin equivalents (Eqs. 10.1-2, 10.1-3) of the four components about their static
    points, fitted to each FMU's steady response to a sine (examples/road_wheel_station.py
    does the same for the tyre and the damper)."""

    SINES = {"RoadWheelTyre": (1e-3, 10.0), "RotaryDamper": (0.06, 2.0),
             "TrackBushRadial": (1e-4, 10.0), "TrackBushTorsion": (0.1, 2.0)}

    def __init__(self, statics, fmu_dir=None):
        compression, stretch, _ = statics
        means = {"RoadWheelTyre": compression, "RotaryDamper": 0.0,
                 "TrackBushRadial": stretch, "TrackBushTorsion": 0.0}
        self.coefficients = {}
        for name, (amplitude, frequency) in self.SINES.items():
            path = fmu_path(name, fmu_dir)
            k, c, _ = harmonic_kelvin_equivalent(path, means[name], amplitude, frequency)
            probe = FmuComponent(path, f"{name}_static_load")
            try:
                load = probe.relaxed_outputs(means[name])[probe.load_name]
                load_name = probe.load_name
            finally:
                probe.free()
            self.coefficients[name] = (k, c, means[name], load, load_name)

    def element(self, fmu, name, unilateral=False):
        k, c, x0, load, load_name = self.coefficients[fmu]
        return KelvinElement(name, load_name, k, c, x0, load, unilateral=unilateral)

    def describe(self):
        units = {"RoadWheelTyre": ("N/m", "N.s/m"), "RotaryDamper": ("N.m/rad", "N.m.s/rad"),
                 "TrackBushRadial": ("N/m", "N.s/m"), "TrackBushTorsion": ("N.m/rad",
                                                                            "N.m.s/rad")}
        return "; ".join(f"{name}: k = {k:.4g} {units[name][0]}, c = {c:.4g} {units[name][1]}"
                         for name, (k, c, *_rest) in self.coefficients.items())


class Vehicle:
    def __init__(self, course, speed, fmu_dir=None, linear=None, coupling=COUPLING,
                 statics=None, path=bank_path.DEFAULT_PATH, joints=DEFAULT_JOINTS):
        """path: "compiled", the coupling's bank (examples/bank_path.py: the FMUs' per-step
        work in C, the load laws in exudyn's compiled symbolic functions; compiled.py), or
        "python", the readable reference (a Python force function per connector); the
        linear vehicle (no FMUs) takes the Python path. joints: "kernel", the track's
        joints as one object with their analytic Jacobian (joints.py: `self.joints`), or
        "connectors", two exudyn connectors per joint that exudyn differentiates."""
        if joints not in JOINTS:
            raise ValueError(f"joints {joints!r}: one of {', '.join(JOINTS)}")
        self.joint_elements = joints
        self.spectral_radius = SPECTRAL_RADIUS
        self.newton_tolerance = NEWTON_TOLERANCE
        self.solver = "exudyn"  # or "own": no exudyn in the time loop (own_host.py)
        self.own_newton = None  # the own solver's Newton policy (own_host.NEWTON)
        self.course, self.speed = course, speed
        self.compiled = linear is None and bank_path.compiled(path, coupling)
        self.bank = None  # the compiled path's, while it runs
        self.compiled_path = None  # compiled.CompiledPath, made by prepare()
        self.fmu_dir, self.linear = fmu_dir, linear
        self.statics = statics or static_points(fmu_dir)
        compression, stretch, _ = self.statics
        self.layout = geo = lay.Layout(compression, lay.LINK_PITCH + stretch)
        self.links = geo.links
        self.hull_mass, self.hull_inertia = lay.side_masses(self.links)
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        self.SC, self.mbs = SC, mbs
        self.coupling = Coupling(coupling, record=self._record)
        self.records = None  # the run's (outputs.Records), made at its first record
        self.settling = False
        self.step_check = None  # the run's (step_check.py), while it runs
        self.given_state = None  # (q, v, a) a host of its own records (own_host.py)
        # every instance in one list (the bank's order); rows of it by kind
        self.components = []
        self.rows = {"tyre": [], "damper": [], "radial": [], "torsion": []}

        tables = {}

        def make(fmu, name, unilateral=False):
            if linear is not None:
                component = linear.element(fmu, name, unilateral)
            else:
                component = FmuComponent(fmu_path(fmu, fmu_dir), name, unilateral=unilateral)
            if fmu not in tables:
                tables[fmu] = RelaxedTable(component, fmu)
            component.relaxed = tables[fmu]
            self.components.append(component)
            return component

        ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))

        coordinate, at = markers(mbs)

        # --- hull and its speed hold -------------------------------------------------------
        cg = geo.cg
        self.hull_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[*cg, 0.0],
                                                     initialVelocities=[speed, 0.0, 0.0]))
        hull = mbs.AddObject(ObjectRigidBody2D(mass=self.hull_mass, inertia=self.hull_inertia,
                                               nodeNumber=self.hull_node))
        self.hull_marker = at(hull, [0.0, 0.0])
        stiffness = self.hull_mass * (2 * math.pi * SURGE_FREQUENCY) ** 2
        damping = 2 * math.sqrt(stiffness * self.hull_mass)

        def surge(mbs, t, item, displacement, velocity, *_):
            if self.settling:  # held where it stands (the ground is frictionless)
                return stiffness * displacement + damping * velocity
            return stiffness * (displacement - speed * t) + damping * (velocity - speed)

        self.surge = (stiffness, damping)
        self.surge_connector = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
            markerNumbers=[coordinate(ground, 0), coordinate(self.hull_node, 0)],
            springForceUserFunction=surge))
        hull_rotation = coordinate(self.hull_node, 2)

        # --- stations: arm with its wheel, torsion bar, damper, two tyres --------------------
        self.arm_nodes, self.arm_bodies, self.tyres, self.dampers = [], [], [], {}
        self.damper_connectors = []
        arm_com = (lay.ARM_MASS * 0.5 + lay.WHEEL_MASS) * lay.ARM_LENGTH / (
            lay.ARM_MASS + lay.WHEEL_MASS)
        arm_inertia = (lay.ARM_MASS * lay.ARM_LENGTH ** 2 / 12
                       + lay.ARM_MASS * (0.5 * lay.ARM_LENGTH - arm_com) ** 2
                       + lay.WHEEL_MASS * (lay.ARM_LENGTH - arm_com) ** 2)
        direction = -np.array([math.cos(lay.ARM_STATIC_ANGLE), math.sin(lay.ARM_STATIC_ANGLE)])
        lever = lay.ARM_LENGTH * math.cos(lay.ARM_STATIC_ANGLE)
        preload = ((wheel_load() - lay.WHEEL_MASS * GRAVITY) * lever
                   - lay.ARM_MASS * GRAVITY * 0.5 * lever)
        self.wheel_offset = []  # wheel centre from the arm body's node, in its frame
        for i, (pivot, wheel) in enumerate(zip(geo.pivots, geo.wheel_centres), start=1):
            com = pivot + arm_com * direction
            node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[*com, 0.0],
                                               initialVelocities=[speed, 0.0, 0.0]))
            arm = mbs.AddObject(ObjectRigidBody2D(mass=lay.ARM_MASS + lay.WHEEL_MASS,
                                                  inertia=arm_inertia, nodeNumber=node))
            mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[at(hull, pivot - cg),
                                                               at(arm, pivot - com)]))
            arm_rotation = coordinate(node, 2)
            # bump rotation = q_hull - q_arm; +f turns the arm counter-clockwise (wheel down)
            mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
                markerNumbers=[arm_rotation, hull_rotation],
                stiffness=lay.TORSION_BAR_STIFFNESS,
                offset=-preload / lay.TORSION_BAR_STIFFNESS))
            if i in lay.DAMPED_STATIONS:
                damper = make("RotaryDamper", f"damper_{i}")
                connector = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
                    markerNumbers=[arm_rotation, hull_rotation],
                    springForceUserFunction=lambda mbs, t, item, x, v, *_, d=damper:
                        self.load(d, x, v)))
                self.dampers[i] = damper
                self.damper_connectors.append(connector)
                self.rows["damper"].append(len(self.components) - 1)
                self.coupling.add(damper, self._connector_reader(connector))
            pair = [make("RoadWheelTyre", f"tyre_{i}_{side}", unilateral=True)
                    for side in ("left", "right")]
            self.tyres.append(pair)
            self.rows["tyre"].append([len(self.components) - 2, len(self.components) - 1])
            for tyre in pair:
                self.coupling.add(tyre, lambda w=i - 1: self.contacts.tyre_state(w))
            self.arm_nodes.append(node)
            self.arm_bodies.append(arm)
            self.wheel_offset.append(wheel - com)

        # --- idler on its crank, with the tensioner ---------------------------------------
        crank_com = geo.idler  # the idler wheel's mass dominates: the node at its centre
        self.crank_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[*crank_com, 0.0],
                                                      initialVelocities=[speed, 0.0, 0.0]))
        crank = mbs.AddObject(ObjectRigidBody2D(mass=lay.CRANK_MASS, inertia=2.0,
                                                nodeNumber=self.crank_node))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            at(hull, geo.crank_pivot - cg), at(crank, geo.crank_pivot - crank_com)]))
        # preload: the moment of the two spans' pull on the idler about the crank's pivot
        before, after = geo.idler_pull()
        pull = lay.TRACK_TENSION * (before + after)
        arm = geo.idler - geo.crank_pivot
        moment = arm[0] * pull[1] - arm[1] * pull[0]
        mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
            markerNumbers=[coordinate(self.crank_node, 2), hull_rotation],
            stiffness=lay.TENSIONER_STIFFNESS, damping=TENSIONER_DAMPING,
            offset=moment / lay.TENSIONER_STIFFNESS))

        # --- the track loop ----------------------------------------------------------------
        pins = geo.pins
        n = self.links
        self.link_nodes, self.link_bodies, self.radial, self.torsion = [], [], [], []
        self.link_markers = []
        self.link_angle0 = []
        ahead = np.roll(pins, -1, axis=0)
        centres, angles = 0.5 * (pins + ahead), np.arctan2(*(ahead - pins).T[::-1])
        # track speed relative to the hull: clockwise round the loop (the path runs
        # counter-clockwise), so the ground run stands still
        tangents = (ahead - pins) / np.hypot(*(ahead - pins).T)[:, None]
        turn = np.angle(np.exp(1j * (np.roll(angles, -1) - np.roll(angles, 1))))
        for k in range(n):
            velocity = [speed - speed * tangents[k][0], -speed * tangents[k][1],
                        -speed * turn[k] / (2 * geo.chord)]
            node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[*centres[k], angles[k]],
                                               initialVelocities=velocity))
            body = mbs.AddObject(ObjectRigidBody2D(mass=lay.LINK_MASS,
                                                   inertia=lay.LINK_INERTIA, nodeNumber=node))
            self.link_nodes.append(node)
            self.link_bodies.append(body)
            self.link_markers.append((at(body, [-0.5 * lay.LINK_PITCH, 0.0]),
                                      at(body, [0.5 * lay.LINK_PITCH, 0.0])))
            self.link_angle0.append(angles[k])
        self.link_angle0 = np.array(self.link_angle0)
        # joint j: between link j - 1 (behind) and link j; its torsion bush's angle is the
        # links' relative rotation plus its offset, the angle between them as laid out
        self.torsion_offsets = [float(np.angle(np.exp(1j * (angles[j] - angles[j - 1]))))
                                for j in range(n)]
        self.radial_connectors, self.torsion_connectors = [], []
        for j, offset in enumerate(self.torsion_offsets):
            radial = make("TrackBushRadial", f"radial_{j}")
            torsion = make("TrackBushTorsion", f"torsion_{j}")
            self.radial.append(radial)
            self.torsion.append(torsion)
            self.rows["radial"].append(len(self.components) - 2)
            self.rows["torsion"].append(len(self.components) - 1)
            if joints == "kernel":  # one object for all joints (joints.py), added below
                self.coupling.add(radial, lambda j=j: self.joints.state(j, "radial"))
                self.coupling.add(torsion, lambda j=j: self.joints.state(j, "torsion"))
                continue
            # a scalar force along the line between the seats (exudyn's own geometry, as
            # the track-span example): a tension pulls them together (its Cartesian
            # spring-damper with the force as a vector cost a fifth more CPU); faded in
            # over the seats' first RADIAL_FADE of distance, where that line turns
            behind, ahead_ = (j - 1) % n, j
            rc = mbs.AddObject(ObjectConnectorSpringDamper(
                markerNumbers=[self.link_markers[behind][1], self.link_markers[ahead_][0]],
                springForceUserFunction=lambda mbs, t, item, length, rate, *_, b=radial:
                    radial_pull(self.load(b, length, rate)) * radial_fade(length)))
            tc = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
                markerNumbers=[coordinate(self.link_nodes[behind], 2),
                               coordinate(self.link_nodes[ahead_], 2)],
                springForceUserFunction=lambda mbs, t, item, x, v, *_, b=torsion, o=offset:
                    self.load(b, x + o, v)))
            self.radial_connectors.append(rc)
            self.torsion_connectors.append((tc, offset))
            self.coupling.add(radial, lambda c=rc: _seat_deflection(*connector_state(mbs, c)))
            self.coupling.add(torsion, self._connector_reader(tc, offset))

        # gravity on every body
        for body in [hull, *self.arm_bodies, crank, *self.link_bodies]:
            mbs.AddLoad(LoadMassProportional(
                markerNumber=mbs.AddMarker(MarkerBodyMass(bodyNumber=body)),
                loadVector=[0.0, -GRAVITY, 0.0]))

        from .contacts import Contacts
        from .joints import Joints
        self.joints = Joints(self) if joints == "kernel" else None
        if self.joints is not None:
            self.joints.add_object()
        self.contacts = Contacts(self)
        self.contacts.add_object()
        mbs.Assemble()
        self.contacts.index()
        if self.joints is not None:
            self.joints.index()

    def load(self, component, deflection, rate):
        """What a force element applies: the component's load law, or while the vehicle
        settles its relaxed load."""
        if self.settling:
            return component.relaxed(deflection)
        return component.host_load(deflection, rate)

    def tyre_loads(self, compression, rate):
        """Each wheel's tyre load (both half-wheels) at its compression and rate, and its
        slopes by the compression and by the rate, for the contacts' Jacobian (the load
        law's tangent, not its secant; a Kelvin tyre's damping: law_slopes.py). On the
        compiled path the bank's laws, rate-free, in one call for every tyre (the
        contacts' C kernel makes that call itself, the same operations:
        contacts_kernel.py)."""
        compression = np.where(np.isfinite(compression), compression, -HORN_HEIGHT)
        rows = self.tyre_rows
        if self.bank is not None:
            deflection = np.zeros(len(self.components))
            deflection[rows] = compression[:, None]
            loads, slopes = self.bank.law_loads(deflection, slopes=True)
            return loads[rows].sum(axis=1), slopes[rows].sum(axis=1), np.zeros(len(rows))
        laws = np.zeros((len(rows), 3))  # load, slope by compression, by rate
        for w, pair in enumerate(self.tyres):
            for tyre in pair:
                laws[w] += load_and_slopes(self, tyre, float(compression[w]), float(rate[w]))
        return tuple(laws.T)

    @functools.cached_property
    def tyre_rows(self):
        """The tyres' rows in `components`, a row (both half-wheels) per wheel."""
        return np.array(self.rows["tyre"])

    @functools.cached_property
    def _tyre_rows_end(self):
        return int(self.tyre_rows.max()) + 1

    def tyre_laws_key(self):
        """What decides the tyres' present load laws (they change between the coupling's
        passes at the same state). On the compiled path the bank's rows of laws up to the
        last tyre's: a slice costs less than picking the tyres' rows (a change of a
        damper's law among them costs at most an evaluation more)."""
        if self.bank is not None:
            return self.bank.laws[:self._tyre_rows_end].tobytes()
        return tuple(_law_key(tyre) for pair in self.tyres for tyre in pair)

    def accepted(self):
        """(load, deflection) of every instance at the last accepted step, in the order
        of `components`."""
        if self.bank is not None:
            return self.bank.loads.copy(), self.bank.accepted[:, 1].copy()
        return (np.array([c.load for c in self.components]),
                np.array([c.deflection for c in self.components]))

    def _connector_reader(self, connector, offset=0.0):
        def read():
            x, v = connector_state(self.mbs, connector)
            return float(x) + offset, float(v)
        return read

    @property
    def instances(self):
        return len(self.components)

    # --- static state, run, records ---------------------------------------------------------

    def settle(self, longest=2.0, step=2e-3, store=True):
        """To the static point, solved once and stored (static.py); returns the settling
        time it took (0.0 from the store)."""
        from .static import settle
        return settle(self, longest, step, store)

    def _record(self, t):
        from .outputs import record
        record(self, t)

    def prepare(self):
        """What the run sets up before its first step (after the settling, which runs on
        the Python functions): on the compiled path the bank and the compiled functions
        (compiled.py); the outputs' modules."""
        from . import outputs  # noqa: F401 (scipy's import: a few seconds)
        if self.compiled and self.compiled_path is None:
            from .compiled import CompiledPath
            self.compiled_path = CompiledPath(self)

    def run(self, end_time, step, settle=True):
        if settle:
            self.settle()
        self.prepare()
        # the components start relaxed at the host's current state (their readers read
        # it before exudyn's solve makes the initial state current): the initial one, not
        # the laid-out geometry nor the settling's last state at rest
        data = self.mbs.systemData
        for get, put in ((data.GetODE2Coordinates, data.SetODE2Coordinates),
                         (data.GetODE2Coordinates_t, data.SetODE2Coordinates_t)):
            put(get(exu.ConfigurationType.Initial), exu.ConfigurationType.Current)
        self.host_steps = math.ceil(end_time / step - 1e-9)
        from .step_check import StepCheck
        self.step_check = check = StepCheck(self)
        settings = run_settings(self.spectral_radius, self.newton_tolerance)
        try:
            if self.solver == "own":
                from .own_host import OwnHost
                self.host = OwnHost(self).run(end_time, step, check=check)
            elif self.compiled:
                from .compiled import solve_compiled
                self.host = solve_compiled(self, end_time, step, settings, check)
            else:
                self.host = solve(self.mbs, self.coupling, end_time, step, settings=settings,
                                  step_check=check)
        except exu.SolverError:
            raise VehicleError(f"exudyn's solver gave up at t = {self.coupling.time:.4f} s "
                               f"(its Newton did not converge even on shortened steps; "
                               f"docs/vehicle.md, What remains)") from None
        except StepRefused as refused:
            raise VehicleError(f"the solution jumped: {refused.what} at "
                               f"t = {refused.time:.4f} s, on steps down to "
                               f"{refused.step * 1e6:.3g} us; lower --speed or choose a "
                               f"gentler course") from None
        finally:
            self.step_check = None
        from .outputs import histories
        return histories(self)

    def solver_statistics(self):
        """exudyn's Newton iterations per solve of a step, solves (coupling passes) per
        accepted step, the steps accepted against the host steps asked for (more where
        steps were shortened), and the solves the step check refused (step_check.py); on
        the own solver its own (OwnHost.statistics)."""
        if self.solver == "own":
            return self.host.statistics()
        it = self.mbs.sys["dynamicSolver"].it
        passes = max(self.coupling.total_passes, 1)
        return {"newton_per_pass": it.newtonStepsCount / passes,
                "passes_per_step": passes / max(self.coupling.steps, 1),
                "steps": self.coupling.steps, "host_steps": self.host_steps,
                "refused": self.host.refused}


def run_settings(spectral_radius=SPECTRAL_RADIUS, newton_tolerance=NEWTON_TOLERANCE):
    """The settings of the coupled run (exudyn_host.solve adds what the coupling needs)."""
    settings = quiet_settings(newton_tolerance)
    settings.timeIntegration.generalizedAlpha.spectralRadius = spectral_radius
    settings.timeIntegration.verboseMode = VERBOSE
    # a Jacobian per iteration: the contacts change from step to step (the modified
    # Newton's kept Jacobian took 14 iterations a pass against 8)
    settings.timeIntegration.newton.useModifiedNewton = False
    configure(settings)
    return settings


def configure(settings):
    """Solver settings every run of the vehicle needs: the contacts are loads computed from
    the whole state (contacts.py); a sparse linear solver for the loop's banded system."""
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse


def _law_key(component):
    """What decides the component's present load law (its values; None for none)."""
    law = getattr(component, "law", None)
    if law is None or not hasattr(law, "__slots__"):
        return id(law)  # none, or a law that never changes (a Kelvin element)
    return tuple(getattr(law, name) for name in law.__slots__)


def _seat_deflection(displacement, velocity):
    # the distance as the compiled path's deflections (compiled.py) have it
    distance = math.sqrt(displacement[0] * displacement[0] + displacement[1] * displacement[1])
    if distance == 0.0:
        return 0.0, 0.0
    return distance, (displacement[0] * velocity[0] + displacement[1] * velocity[1]) / distance
