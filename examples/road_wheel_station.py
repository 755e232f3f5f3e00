"""One Warrior road-wheel station in 2D, in the exudyn multibody host, driven over a bump
and the track-link ripple: RoadWheelTyre.fmu at the wheel-track contact, RotaryDamper.fmu
at the arm pivot, coupled to the host by fmu_components.coupling (docs/coupling.md).

    python examples/road_wheel_station.py                  # speeds 3, 8 and 15 m/s
    python examples/road_wheel_station.py --speeds 8 --step 1e-3 --coupling explicit --csv
    python examples/road_wheel_station.py --speeds 8 --coupling-study  # accuracy and cost
    python examples/road_wheel_station.py --speeds 8 --fmi 3           # the FMI 3.0 FMUs (fmus/fmi3/)
    python examples/road_wheel_station.py --path python   # the coupling's Python path

Every speed is run twice: with the FMUs, and with both components replaced by their linear
Kelvin equivalents at the static point (Eqs. 10.1-2 and 10.1-3, thesis section 10.1). The
plots go to reports/road_wheel_station/ (or --out).

The model (x forward, y up, angles counter-clockwise):
* hull: the station's share of the vehicle, guided vertically (no pitch, no surge);
* trailing arm, 0.4 m (section 9.1), pivoted on the hull, trailing down at 30 deg at the
  static point, with a linear torsion bar preloaded to carry the station;
* road wheel, 613 mm diameter (section 5.1.1), free to spin at the arm's end;
* tyre: one RoadWheelTyre instance is the tyre of one half-wheel (section 5.1.1); the two
  half-wheels of a wheel run on the same track link and see the same compression in 2D,
  so the wheel gets twice its force (TYRES_PER_WHEEL);
* damper: RotaryDamper between hull and arm, input the arm's rotation from its static
  position, positive in bump (wheel up), as the damper's rotor turns with the arm (9.1);
* ground: the track link under the wheel follows the road profile, a smooth bump plus the
  ripple of the track-link pitch; the tyre touches it under the wheel centre.
"""

import argparse
import functools
import math
import time
from pathlib import Path

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.optimize import brentq

import exudyn as exu
from exudyn.itemInterface import (CoordinateConstraint, MarkerBodyPosition,
                                  LoadForceVector, MarkerNodeCoordinate, NodePointGround,
                                  NodeRigidBody2D, ObjectConnectorCartesianSpringDamper,
                                  ObjectConnectorCoordinateSpringDamper, ObjectGround,
                                  ObjectJointRevolute2D, ObjectRigidBody2D)

from fmu_components.coupling import DEFAULT_SCHEME, Coupling, FmuComponent
from fmu_components.coupling.exudyn_host import connector_state, quiet_settings
from fmu_components.coupling.kelvin import KelvinElement, harmonic_kelvin_equivalent

import bank_path
from coupling_study import (STUDY_GRID, STUDY_SCHEMES, STUDY_STEPS, add_arguments,
                            format_table, history_error, progress, study, time_progress,
                            write_csv, write_study)
from example_fmus import add_fmu_arguments, fmu_dir_of, fmu_path
from station_plots import STUDY_LABELS, plot_difference, plot_speed, plot_study

GRAVITY = 9.81
STATIONS = 12
VEHICLE_MASS = 27000.0  # kg, section 5.1.1
STATION_MASS = VEHICLE_MASS / STATIONS  # what one station's tyres carry: 2250 kg
WHEEL_MASS = 80.0  # two half-wheels: cast aluminium hubs and tyres (estimate)
WHEEL_INERTIA = 3.0  # kg.m2 about the axle (estimate; the wheel spins freely)
ARM_MASS = 40.0  # kg (estimate)
HULL_MASS = STATION_MASS - WHEEL_MASS - ARM_MASS  # the sprung share, 2130 kg
ARM_LENGTH = 0.4  # m, section 9.1
ARM_STATIC_ANGLE = math.radians(30.0)  # below horizontal, trailing (estimate)
WHEEL_RADIUS = 0.613 / 2  # m, section 5.1.1
TYRES_PER_WHEEL = 2
# Torsion bar rate: about 1.2 Hz bounce of the sprung share (section 9.0: pitch ~1 Hz).
TORSION_BAR_STIFFNESS = 15000.0  # N.m/rad
TRACK_PITCH = 0.15  # m

# How the coupling predicts the damper's answer to a step: None, the library's choice (its
# Model Exchange linearisation); "tangent", its `stiffness` output (for a host without a
# second instance: benchmarks/coupling_study.py --damper-tangent measures what it costs).
DAMPER_STEP_MODEL = None
# exudyn's Newton's absolute tolerance (its residual's norm per coordinate, on a scale
# that follows the step); one lets a step's second
# solve start from the first's solution (exudyn_host). None, exudyn's default: the
# tolerance that keeps the coupling's own error (1e-4) saves the second solve one
# iteration of six and costs more in the state's copies than it saves
# (benchmarks/coupling_newton.py, docs/coupling.md).
NEWTON_TOLERANCE = None
DEFAULT_STEP = 1e-4  # s, host step: exudyn's own error small for the plots (0.3 % at 8 m/s)

# The linear equivalents are fitted to each FMU's steady response to a sine about the
# static point, at the amplitudes the station shows over the default bump (tyre
# compression 1 to 3 mm either side of 3.25 mm, the arm 2 to 4 deg either side of static)
# and at frequencies between its bounce (about 1.2 Hz) and wheel hop (50 to 70 Hz).
TYRE_SINE = (1e-3, 10.0)  # amplitude (m), frequency (Hz)
DAMPER_SINE = (0.06, 2.0)  # amplitude (rad), frequency (Hz)


class RoadProfile:
    """Height of the track link under the wheel against distance s along the road: a
    (1 - cos) bump, and a dip of `ripple_depth` at every track-link joint (the wheel
    rides on the link pitch). Starts flat on a link's middle: no slope at s = 0."""

    def __init__(self, bump_height=0.03, bump_length=1.0, bump_start=1.0, ripple_depth=1e-3,
                 pitch=TRACK_PITCH):
        self.bump_height = bump_height
        self.bump_length = bump_length
        self.bump_start = bump_start
        self.ripple_depth = ripple_depth
        self.pitch = pitch

    def height(self, s, cos=math.cos):
        """height_and_slope's height alone (its operations, its bits)."""
        ripple_k = 2 * math.pi / self.pitch
        height = -0.5 * self.ripple_depth * (1 - cos(ripple_k * s))
        u = (s - self.bump_start) / self.bump_length
        if 0.0 < u < 1.0:
            height += 0.5 * self.bump_height * (1 - cos(2 * math.pi * u))
        return height

    def height_and_slope(self, s):
        ripple_k = 2 * math.pi / self.pitch
        height = -0.5 * self.ripple_depth * (1 - math.cos(ripple_k * s))
        slope = -0.5 * self.ripple_depth * ripple_k * math.sin(ripple_k * s)
        u = (s - self.bump_start) / self.bump_length
        if 0.0 < u < 1.0:
            bump_k = 2 * math.pi / self.bump_length
            height += 0.5 * self.bump_height * (1 - math.cos(2 * math.pi * u))
            slope += 0.5 * self.bump_height * bump_k * math.sin(2 * math.pi * u)
        return height, slope

    @property
    def end(self):
        return self.bump_start + self.bump_length


def static_tyre_compression(tyre):
    """Compression at which the relaxed tyre carries its share of the station's weight
    (the thesis: about 11 kN at 3.24 mm), from the FMU's own output."""
    share = STATION_MASS * GRAVITY / TYRES_PER_WHEEL
    return brentq(lambda x: tyre.relaxed_outputs(x)[tyre.load_name] - share, 1e-4, 6e-3,
                  xtol=1e-12)


def static_tyre_point(fmu_dir=None, parameters=None):
    """(compression, load) of one half-wheel's relaxed tyre at the static point, from an
    instance of its own (with `parameters`, its own values); computed once per FMU file,
    values and process."""
    return _static_tyre_point(fmu_path("RoadWheelTyre", fmu_dir).resolve(),
                              tuple(sorted((parameters or {}).items())))


@functools.lru_cache(maxsize=None)
def _static_tyre_point(path, parameters):
    tyre = FmuComponent(path, "tyre_static", dict(parameters) or None)
    try:
        compression = static_tyre_compression(tyre)
        return compression, tyre.relaxed_outputs(compression)[tyre.load_name]
    finally:
        tyre.free()


def torsion_bar_preload(tyre_load_per_wheel):
    """Bar torque at the static point: moment balance of arm and wheel about the pivot."""
    lever = ARM_LENGTH * math.cos(ARM_STATIC_ANGLE)
    return (tyre_load_per_wheel - WHEEL_MASS * GRAVITY - 0.5 * ARM_MASS * GRAVITY) * lever


class Linearisation:
    """Kelvin equivalents of the tyre and damper about the station's static point."""

    def __init__(self, fmu_dir, static_compression, tyre_sine=TYRE_SINE,
                 damper_sine=DAMPER_SINE):
        self.static_compression = static_compression
        self.tyre_sine, self.damper_sine = tyre_sine, damper_sine
        self.tyre = harmonic_kelvin_equivalent(fmu_path("RoadWheelTyre", fmu_dir),
                                               static_compression, *tyre_sine)
        self.damper = harmonic_kelvin_equivalent(fmu_path("RotaryDamper", fmu_dir), 0.0,
                                                 *damper_sine)

    def describe(self):
        (kt, ct, _), (kd, cd, _) = self.tyre, self.damper
        (tyre_amplitude, tyre_f), (damper_amplitude, damper_f) = self.tyre_sine, self.damper_sine
        return (f"tyre (one half-wheel) about {self.static_compression * 1e3:.3f} mm, "
                f"+-{tyre_amplitude * 1e3:g} mm at {tyre_f:g} Hz: k_eq = {kt / 1e3:.0f} "
                f"N/mm, c_eq = {ct:.0f} N.s/m; damper +-{damper_amplitude:g} rad at "
                f"{damper_f:g} Hz: k_eq = {kd:.0f} N.m/rad, c_eq = {cd:.0f} N.m.s/rad")


class Station:
    """The station in exudyn with its two components; `run` drives it at one speed."""

    def __init__(self, speed, profile, fmu_dir=None, linear=None, coupling=DEFAULT_SCHEME,
                 path=bank_path.DEFAULT_PATH, reached=None, parameters=None):
        """linear: a Linearisation, whose Kelvin elements replace both components; without
        it both components are the FMUs. path: "compiled", the coupling's bank (the FMUs'
        per-step work in C, the load laws in exudyn's compiled symbolic functions), or
        "python", its Python path (the Kelvin elements always take it). reached(t), if
        given, hears every accepted host step's time (a progress bar). parameters: FMU
        name -> {parameter: SI value} of the FMUs' own values to change (a part)."""
        parameters = parameters or {}
        self.reached = reached
        self.speed = speed
        self.profile = profile
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        self.SC, self.mbs = SC, mbs

        self.static_compression, static_tyre_load = static_tyre_point(
            fmu_dir, parameters.get("RoadWheelTyre"))
        if linear:
            stiffness, damping, _ = linear.tyre
            tyre = KelvinElement("tyre", "force", stiffness, damping, self.static_compression,
                                 static_tyre_load, unilateral=True)
            stiffness, damping, _ = linear.damper
            damper = KelvinElement("damper", "torque", stiffness, damping, 0.0, 0.0)
        else:
            tyre = FmuComponent(fmu_path("RoadWheelTyre", fmu_dir), "tyre",
                                parameters.get("RoadWheelTyre"), unilateral=True)
            damper = FmuComponent(fmu_path("RotaryDamper", fmu_dir), "damper",
                                  parameters.get("RotaryDamper"), step_model=DAMPER_STEP_MODEL)
        self.tyre, self.damper = tyre, damper
        self.bar_preload = torsion_bar_preload(TYRES_PER_WHEEL * static_tyre_load)

        # Geometry at the static point: pivot at the origin, arm trailing down to the wheel.
        arm_direction = np.array([-math.cos(ARM_STATIC_ANGLE), -math.sin(ARM_STATIC_ANGLE)])
        arm_centre = 0.5 * ARM_LENGTH * arm_direction
        wheel_centre = ARM_LENGTH * arm_direction
        self.ground_level = wheel_centre[1] - WHEEL_RADIUS + self.static_compression
        arm_angle = math.pi + ARM_STATIC_ANGLE

        ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
        hull_node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, 0.0]))
        arm_node = mbs.AddNode(NodeRigidBody2D(
            referenceCoordinates=[arm_centre[0], arm_centre[1], arm_angle]))
        wheel_node = mbs.AddNode(NodeRigidBody2D(
            referenceCoordinates=[wheel_centre[0], wheel_centre[1], 0.0]))
        # The hull's share is guided vertically: its rotation and surge belong to the rest
        # of the vehicle.
        hull = mbs.AddObject(ObjectRigidBody2D(mass=HULL_MASS, inertia=1.0,
                                               nodeNumber=hull_node))
        arm = mbs.AddObject(ObjectRigidBody2D(mass=ARM_MASS,
                                              inertia=ARM_MASS * ARM_LENGTH ** 2 / 12,
                                              nodeNumber=arm_node))
        wheel = mbs.AddObject(ObjectRigidBody2D(mass=WHEEL_MASS, inertia=WHEEL_INERTIA,
                                                nodeNumber=wheel_node))

        def coordinate(node, index):
            return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=index))

        for index in (0, 2):
            mbs.AddObject(CoordinateConstraint(markerNumbers=[coordinate(ground, index),
                                                              coordinate(hull_node, index)]))
        self.pivot = mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=hull, localPosition=[0.0, 0.0, 0.0])),
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=arm,
                                             localPosition=[-0.5 * ARM_LENGTH, 0.0, 0.0]))]))
        mbs.AddObject(ObjectJointRevolute2D(markerNumbers=[
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=arm,
                                             localPosition=[0.5 * ARM_LENGTH, 0.0, 0.0])),
            mbs.AddMarker(MarkerBodyPosition(bodyNumber=wheel, localPosition=[0.0, 0.0, 0.0]))]))
        for body, mass in ((hull, HULL_MASS), (arm, ARM_MASS), (wheel, WHEEL_MASS)):
            mbs.AddLoad(LoadForceVector(
                markerNumber=mbs.AddMarker(MarkerBodyPosition(bodyNumber=body)),
                loadVector=[0.0, -mass * GRAVITY, 0.0]))

        # Arm rotation relative to the hull, from the static point, positive in bump
        # (the wheel moving up turns the trailing arm clockwise): q_hull - q_arm.
        # A coordinate spring-damper applies +f to its first marker (the arm) and -f to
        # the second (the hull), f its force: so f is the component's torque.
        arm_rotation, hull_rotation = coordinate(arm_node, 2), coordinate(hull_node, 2)
        mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
            markerNumbers=[arm_rotation, hull_rotation], stiffness=TORSION_BAR_STIFFNESS,
            offset=-self.bar_preload / TORSION_BAR_STIFFNESS))
        self.damper_connector = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
            markerNumbers=[arm_rotation, hull_rotation],
            springForceUserFunction=lambda mbs, t, item, rotation, rate, *_:
                damper.host_load(rotation, rate)))

        # Tyre: a Cartesian spring-damper from the wheel centre's static position (on
        # ground) to the wheel centre; it pushes the wheel up by the wheels' tyre force.
        wheel_static = mbs.AddObject(ObjectGround(
            referencePosition=[wheel_centre[0], wheel_centre[1], 0.0]))
        self.tyre_connector = mbs.AddObject(ObjectConnectorCartesianSpringDamper(
            markerNumbers=[mbs.AddMarker(MarkerBodyPosition(bodyNumber=wheel_static)),
                           mbs.AddMarker(MarkerBodyPosition(bodyNumber=wheel))],
            springForceUserFunction=self._tyre_force))

        self.hull_node = hull_node
        self.coupling = Coupling(coupling, record=self._record)
        self.coupling.add(tyre, self._tyre_state)
        self.coupling.add(damper, self._damper_state)
        mbs.Assemble()
        # where _deflections reads the connectors' displacements in the system's coordinates
        self._tyre_reference = (float(wheel_centre[0]), float(wheel_centre[1]))
        self._wheel_index = mbs.GetNodeODE2Index(wheel_node)
        self._rotation_indices = (mbs.GetNodeODE2Index(arm_node) + 2,
                                  mbs.GetNodeODE2Index(hull_node) + 2)
        self.records = []
        self.compiled = not linear and bank_path.compiled(path, coupling)
        if self.compiled:
            self._compile_forces(coupling)

    def _compile_forces(self, scheme):
        """The compiled path: the tyre's and the damper's forces the symbolic laws of their
        instances in one bank, the tyre's compression the same expression as
        _compression's (the road profile's too)."""
        self.bank = bank_path.Bank([self.tyre, self.damper], scheme, record=self._record)
        laws = self.laws = bank_path.SymbolicLaws(self.bank, name="station_laws")
        esym, profile, speed = laws.esym, self.profile, self.speed
        ripple_k = 2 * math.pi / profile.pitch

        def tyre_force(mbs, t, itemNumber, displacement, velocity, stiffness, damping, offset):
            s = speed * t + displacement[0]
            height = -0.5 * profile.ripple_depth * (1 - esym.cos(ripple_k * s))
            u = (s - profile.bump_start) / profile.bump_length
            bump = height + 0.5 * profile.bump_height * (1 - esym.cos(2 * math.pi * u))
            height = laws.when(u > 0.0, laws.when(u < 1.0, bump, height), height)
            compression = self.static_compression - displacement[1] + height
            return [0.0 * height, -TYRES_PER_WHEEL * laws.load(0, compression), 0.0 * height]

        def damper_torque(mbs, t, itemNumber, displacement, velocity, stiffness, damping,
                          offset):
            return laws.load(1, displacement)

        self._symbolic = [
            bank_path.symbolic_function(self.mbs, self.tyre_connector, tyre_force),
            bank_path.symbolic_function(self.mbs, self.damper_connector, damper_torque)]

    def _deflections(self):
        """Both instances' deflections now (the post-Newton hook's, each pass), into the
        bank's own array: from one read of the system's coordinates, each displacement as
        exudyn's connectors form it (the wheel's position, its reference plus its
        coordinates, less the ground point's; the hull's rotation coordinate less the
        arm's), the same bits as their GetObjectOutput at a third of the cost (exudyn's
        GetObjectOutput is a call per connector; tests/test_road_wheel_station.py)."""
        mbs = self.mbs
        q = mbs.systemData.GetODE2Coordinates().tolist()
        x0, y0 = self._tyre_reference
        w = self._wheel_index
        dx, dy = (x0 + q[w]) - x0, (y0 + q[w + 1]) - y0
        arm, hull = self._rotation_indices
        deflection = self.bank.deflection
        deflection[0] = (self.static_compression - dy
                         + self.profile.height(self.speed * mbs.systemData.GetTime() + dx))
        deflection[1] = q[hull] - q[arm]
        return deflection

    def _connector_deflections(self):
        """_deflections by exudyn's connector outputs (what it must equal)."""
        mbs, displacement = self.mbs, exu.OutputVariableType.Displacement
        return np.array([
            self._compression(mbs.systemData.GetTime(),
                              mbs.GetObjectOutput(self.tyre_connector, displacement)),
            float(mbs.GetObjectOutput(self.damper_connector, displacement))])

    # --- kinematics shared by the force functions and the post-step hook ------------------

    def _compression(self, t, displacement, velocity=None):
        """Tyre compression and its rate from the wheel centre's displacement from static
        (without its velocity: the compression alone)."""
        dx, dy = displacement[0], displacement[1]
        height, slope = self.profile.height_and_slope(self.speed * t + dx)
        compression = self.static_compression - dy + height
        if velocity is None:
            return compression
        rate = -velocity[1] + slope * (self.speed + velocity[0])
        return compression, rate

    def _tyre_force(self, mbs, t, item, displacement, velocity, *_):
        compression, rate = self._compression(t, displacement, velocity)
        return [0.0, -TYRES_PER_WHEEL * self.tyre.host_load(compression, rate), 0.0]

    def _tyre_state(self):
        return self._compression(self.mbs.systemData.GetTime(),
                                 *connector_state(self.mbs, self.tyre_connector))

    def _damper_state(self):
        rotation, rate = connector_state(self.mbs, self.damper_connector)
        return float(rotation), float(rate)

    def _record(self, t):
        mbs = self.mbs
        hull_acceleration = mbs.GetNodeOutput(self.hull_node, exu.OutputVariableType.Acceleration)[1]
        pivot_force = mbs.GetObjectOutput(self.pivot, exu.OutputVariableType.Force)[1]
        if self.compiled:  # the bank's arrays: row 0 the tyre, row 1 the damper
            bank = self.bank
            damper = dict(zip(self.damper.output_names, bank.outputs[1]))
            tyre_deflection, damper_deflection = bank.accepted[:, 1]
            tyre_load = bank.loads[0]
        else:
            damper = self.damper.outputs
            tyre_deflection, damper_deflection = self.tyre.deflection, self.damper.deflection
            tyre_load = self.tyre.load
        if self.reached is not None:
            self.reached(t)
        self.records.append((
            t, hull_acceleration, pivot_force, damper_deflection, damper["torque"],
            damper.get("dashpot_torque", math.nan), damper.get("rotor_rate", math.nan),
            tyre_deflection, TYRES_PER_WHEEL * tyre_load))

    def run(self, end_time, step):
        """Integrate to end_time with a fixed host step; returns the recorded histories."""
        bank_path.run(self, end_time, step, quiet_settings(NEWTON_TOLERANCE))
        names = ("time", "hull_acceleration", "hull_force", "arm_angle", "damper_torque",
                 "dashpot_torque", "rotor_rate", "tyre_compression", "tyre_force")
        data = np.array(self.records)
        return {name: data[:, i] for i, name in enumerate(names)}


SETTLE_TIME = 1.0  # s after the bump: the body's bounce dies out


def simulate(speed, profile, step, fmu_dir=None, linear=None, end_time=None,
             coupling=DEFAULT_SCHEME, path=bank_path.DEFAULT_PATH, reached=None,
             parameters=None):
    """One drive at `speed` (m/s); histories plus the damper's energy balance.
    parameters: as Station's."""
    if end_time is None:
        end_time = profile.end / speed + SETTLE_TIME
    station = Station(speed, profile, fmu_dir, linear, coupling, path, reached, parameters)
    result = station.run(end_time, step)
    result["costs"] = station.coupling.costs()
    result["solve_cpu"] = station.host.solve_cpu  # s, the dynamic solve's CPU time
    # Work done on the damper, and what its dashpot dissipated (FMU only): J.
    result["damper_work"] = cumulative_trapezoid(result["damper_torque"], result["arm_angle"],
                                                 initial=0)
    result["dashpot_dissipation"] = cumulative_trapezoid(
        result["dashpot_torque"] * result["rotor_rate"], result["time"], initial=0)
    return result


def peaks(result, ripple_from=None):
    """Figures of what the hull feels: peak |acceleration|, the force range and, from
    `ripple_from` (s) on, the rms hull acceleration and damper torque on the ripple."""
    found = {"peak_hull_acceleration": float(np.max(np.abs(result["hull_acceleration"]))),
             "max_hull_force": float(np.max(result["hull_force"])),
             "min_hull_force": float(np.min(result["hull_force"])),
             "max_tyre_force": float(np.max(result["tyre_force"])),
             "peak_damper_torque": float(np.max(np.abs(result["damper_torque"]))),
             "damper_work": float(result["damper_work"][-1])}
    ripple = result["time"] >= (ripple_from if ripple_from is not None else np.inf)
    if ripple.any():
        for key in ("hull_acceleration", "damper_torque"):
            found[f"ripple_rms_{key}"] = float(np.sqrt(np.mean(result[key][ripple] ** 2)))
    return found


RIPPLE_DELAY = 0.5  # s after the bump: the ripple figures start there


# --- coupling accuracy --------------------------------------------------------------------

STUDY_KEYS = ("hull_acceleration", "tyre_force", "damper_torque")
FINE_STEP = 3.125e-5  # s: the co-simulation the independent reference is checked against
REFERENCE_OUTPUT = 5e-4  # s: where the reference is sampled


def coupling_study(speed, profile, fmu_dir=None, steps=STUDY_STEPS, schemes=STUDY_SCHEMES,
                   end_time=None, progress=None):
    """The study at one speed (examples/coupling_study.py), against the independent
    reference (station_reference.py: Radau on the station's own equations with the Model
    Exchange FMUs). Returns (reference, agreement of the reference with the converged
    co-simulation at FINE_STEP in % per history, study table)."""
    from station_reference import solve_reference

    if end_time is None:
        end_time = profile.end / speed + SETTLE_TIME
    t_eval = np.arange(0.0, end_time + 1e-12, REFERENCE_OUTPUT)
    show = progress is not None  # the study's own runs report through it
    started = time.perf_counter()
    with time_progress("reference (Radau)", end_time, show) as reached:
        reference = solve_reference(speed, profile, end_time, t_eval, fmu_dir,
                                    reached=reached)
    reference["wall"] = time.perf_counter() - started
    with time_progress(f"converged at {FINE_STEP * 1e3:g} ms", end_time, show) as reached:
        fine = simulate(speed, profile, FINE_STEP, fmu_dir, end_time=end_time,
                        coupling="converged", reached=reached)
    agreement = {key: history_error(fine, reference, key) for key in STUDY_KEYS}
    table = study(lambda scheme, step: simulate(speed, profile, step, fmu_dir,
                                                end_time=end_time, coupling=scheme),
                  reference, STUDY_KEYS, steps, schemes, progress)
    return reference, agreement, table


def describe_reference(reference, agreement):
    return (f"Independent reference: the station's equations of motion with the Model "
            f"Exchange FMUs, Radau at rtol 1e-10 ({reference['evaluations']} evaluations, "
            f"{reference['events']} contact events, {reference['wall']:.0f} s); against "
            f"the converged co-simulation at {FINE_STEP * 1e3:g} ms it differs by "
            + ", ".join(f"{agreement[k]:.2g} % ({STUDY_LABELS[k]})" for k in STUDY_KEYS)
            + " of each history's range")


# The CSV's columns and their SI units. The linear station's damper is a Kelvin element,
# with no dashpot or rotor of its own: its CSV leaves the last two out.
CSV_COLUMNS = {"time": "s", "hull_acceleration": "m/s2", "hull_force": "N", "tyre_force": "N",
               "damper_torque": "N.m", "arm_angle": "rad", "tyre_compression": "m",
               "dashpot_torque": "N.m", "rotor_rate": "rad/s"}
DAMPER_INSIDE = ("dashpot_torque", "rotor_rate")


def csv_columns(result, linear):
    return {name: result[name] for name in CSV_COLUMNS
            if not (linear and name in DAMPER_INSIDE)}


# --- command line -------------------------------------------------------------------------

def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs="+", default=[3.0, 8.0, 15.0],
                        help="forward speeds, m/s")
    parser.add_argument("--step", type=float, default=DEFAULT_STEP, help="host step, s")
    parser.add_argument("--bump-height", type=float, default=0.03, help="m")
    parser.add_argument("--bump-length", type=float, default=1.0, help="m")
    parser.add_argument("--ripple-depth", type=float, default=1e-3,
                        help="dip at each track-link joint, m")
    parser.add_argument("--damper-sine", type=float, nargs=2, default=DAMPER_SINE,
                        metavar=("AMPLITUDE", "FREQUENCY"),
                        help="sine (rad, Hz) the damper's Kelvin equivalent is fitted to")
    parser.add_argument("--tyre-sine", type=float, nargs=2, default=TYRE_SINE,
                        metavar=("AMPLITUDE", "FREQUENCY"),
                        help="sine (m, Hz) the tyre's Kelvin equivalent is fitted to")
    parser.add_argument("--end-time", type=float, help="s; default: bump passed + 1 s")
    add_fmu_arguments(parser)
    parser.add_argument("--out", type=Path, default=Path("reports") / "road_wheel_station")
    add_arguments(parser, "every scheme at host steps of 4 to 0.25 ms against the "
                          "independent reference, at the first speed, instead of the runs")
    bank_path.add_argument(parser)
    args = parser.parse_args(argv)
    args.fmu_dir = fmu_dir_of(args)
    profile = RoadProfile(args.bump_height, args.bump_length, ripple_depth=args.ripple_depth)
    args.out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()

    if args.coupling_study:
        speed = args.speeds[0]
        reference, agreement, table = coupling_study(speed, profile, args.fmu_dir,
                                                     end_time=args.end_time,
                                                     progress=progress)
        text = (f"Road-wheel station at {speed:g} m/s: every coupling scheme against the "
                f"independent reference (total) and against `converged` at the same host "
                f"step (own); history errors are max on a {STUDY_GRID * 1e3:g} ms grid in % "
                f"of the reference's range; costs per host step and FMU.\n\n"
                f"{describe_reference(reference, agreement)}.\n\n"
                f"{format_table(table, STUDY_KEYS, STUDY_LABELS)}\n")
        write_study(args.out, text)
        plot_study(args.out / "coupling_accuracy.png", table)
        print(f"wrote {args.out / 'coupling_study.md'} and coupling_accuracy.png; "
              f"wall time {time.perf_counter() - started:.1f} s")
        return

    linear = Linearisation(args.fmu_dir, static_tyre_point(args.fmu_dir)[0], args.tyre_sine,
                           args.damper_sine)
    print(f"Linear Kelvin equivalents (Eqs. 10.1-2, 10.1-3): {linear.describe()}")
    print(f"Coupling: {args.coupling} ({args.path} path), host step {args.step * 1e3:g} ms")
    runs = {}
    print(f"\n{'speed':>6s} {'model':>7s} {'peak |a| hull':>14s} {'hull force max':>15s} "
          f"{'min':>8s} {'tyre max':>9s} {'damper |T|':>10s} {'damper work':>11s} "
          f"{'ripple: rms a':>14s} {'rms T':>11s}")
    for speed in args.speeds:
        nonlinear = simulate(speed, profile, args.step, args.fmu_dir, end_time=args.end_time,
                             coupling=args.coupling, path=args.path)
        linearised = simulate(speed, profile, args.step, args.fmu_dir, linear,
                              end_time=args.end_time, coupling=args.coupling)
        runs[speed] = nonlinear, linearised
        for model, result in (("FMUs", nonlinear), ("linear", linearised)):
            p = peaks(result, ripple_from=profile.end / speed + RIPPLE_DELAY)
            print(f"{speed:5g}  {model:>7s} {p['peak_hull_acceleration']:10.2f} m/s2 "
                  f"{p['max_hull_force'] / 1e3:11.1f} kN {p['min_hull_force'] / 1e3:6.1f} kN "
                  f"{p['max_tyre_force'] / 1e3:6.1f} kN {p['peak_damper_torque'] / 1e3:6.2f} kNm "
                  f"{p['damper_work'] / 1e3:8.2f} kJ "
                  f"{p.get('ripple_rms_hull_acceleration', math.nan):9.2f} m/s2 "
                  f"{p.get('ripple_rms_damper_torque', math.nan):7.0f} N.m")
            if args.csv:
                suffix = "" if model == "FMUs" else "_linear"
                write_csv(args.out / f"station_{speed:g}mps{suffix}.csv",
                          csv_columns(result, linear=model == "linear"), CSV_COLUMNS)
        plot_speed(args.out / f"station_{speed:g}mps.png", speed, profile, nonlinear, linearised)
    plot_difference(args.out / "station_difference.png", runs)
    print(f"\nstatic hull force {HULL_MASS * GRAVITY / 1e3:.2f} kN; wrote plots"
          f"{' and CSV files' if args.csv else ''} to {args.out}/; "
          f"wall time {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main()
