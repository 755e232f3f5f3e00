"""A span of Warrior track links in 2D, in the exudyn multibody host: ten links of 150 mm
pitch under 13 kN tension, every joint a TrackBushRadial and a TrackBushTorsion FMU
instance (22 instances of two FMUs in one process), coupled to the host by
fmu_components.coupling (docs/coupling.md). One end of the span is lifted sinusoidally.

    python examples/track_span.py                        # 10 links, 6 Hz, 10 mm lift, 1 s
    python examples/track_span.py --links 12 --frequency 4 --lift 0.02
    python examples/track_span.py --step 1e-3 --coupling explicit --csv
    python examples/track_span.py --coupling-study       # accuracy and cost
    python examples/track_span.py --fmi 3                # the FMI 3.0 FMUs (fmus/fmi3/)
    python examples/track_span.py --path python          # the coupling's Python path

The plots go to reports/track_span/ (or --out).

The model (x along the span, y up, angles counter-clockwise): the span runs from the
sprocket, where its first joint is held (position and link direction fixed), to a wheel
that the tensioner pulls with the track tension (horizontal force, free to move along the
span) and that lifts the last joint by lift (1 - cos 2 pi f t) / 2 without turning.
* A joint's radial deflection is the distance between the pin seats of its two links (the
  bush is round): the TrackBushRadial force acts along that line, pulling the seats
  together.
* A joint's angle is the angle between its two links, zero in line, positive when the
  span bends towards the wheels (downwards, as over the sprocket): so the straight span is
  10 deg off the bush's live angle, the -130 N.m of Eq. 5.3.1-1, which the fixed link
  directions at both ends hold (section 5.1.2).
* The static state at t = 0 is the host's static solve with every FMU relaxed at its
  deflection (its output before the first step is the relaxed component's): gravity
  sags the span against the tension.
"""

import argparse
import ctypes
import math
import time
from pathlib import Path

import numpy as np

import exudyn as exu
from exudyn.itemInterface import (CoordinateConstraint, LoadForceVector, MarkerBodyPosition,
                                  MarkerNodeCoordinate, NodePointGround, NodeRigidBody2D,
                                  ObjectConnectorCoordinateSpringDamper,
                                  ObjectConnectorSpringDamper, ObjectGround, ObjectRigidBody2D)

from fmu_components.coupling import DEFAULT_SCHEME, Coupling, FmuComponent
from fmu_components.coupling.bank_build import Library
from fmu_components.coupling.bank_exudyn import symbolic_function
from fmu_components.coupling.exudyn_host import connector_state, quiet_settings, solve

import bank_path

from coupling_study import (STUDY_GRID, STUDY_SCHEMES, STUDY_STEPS, add_arguments,
                            format_table, progress, study, write_csv, write_study)
from example_fmus import add_fmu_arguments, fmu_dir_of, fmu_path

GRAVITY = 9.81
TENSION = 13e3  # N, section 5.1.2
PITCH = 0.15  # m
LINK_MASS = 15.0  # kg (estimate for a steel link casting with its pads)
LINK_DEPTH = 0.06  # m, for the link's inertia (estimate)
LINK_INERTIA = LINK_MASS * (PITCH ** 2 + LINK_DEPTH ** 2) / 12
WHEEL_MASS = 100.0  # kg, the lifting wheel's share moving along the span (estimate)
# exudyn's Newton stops where its residual's norm per coordinate (on a scale that follows
# the step) is below this, which lets a step's second solve start from the first's
# solution (exudyn_host); not larger, as
# 1e-4 already moved the coupling's own error at 0.5 ms (benchmarks/coupling_newton.py,
# docs/coupling.md). None: exudyn's default.
NEWTON_TOLERANCE = 1e-5
DEFAULT_STEP = 5e-4  # s
# the compiled path's deflections from the coordinates (twice a host step), compiled on
# first use; numpy_deflections where it cannot be built
DEFLECTIONS = Library("track_span_deflections",
                      [Path(__file__).resolve().parent / "track_span_deflections.c"], [],
                      "the span's deflections kernel (track_span_deflections.c)",
                      "the span takes them from numpy")


class TrackSpan:
    def __init__(self, links=10, lift=0.01, frequency=6.0, fmu_dir=None,
                 coupling=DEFAULT_SCHEME, path=bank_path.DEFAULT_PATH):
        """path: "compiled", the coupling's bank (its per-step work in C, the load laws
        in exudyn's compiled symbolic functions), where the scheme has one; "python", the
        coupling's Python path (Coupling, a Python force function per connector)."""
        self.links, self.lift, self.frequency = links, lift, frequency
        self.compiled = bank_path.compiled(path, coupling)
        self._symbolic = []  # the compiled user functions live as long as the system
        SC = exu.SystemContainer()
        mbs = SC.AddSystem()
        self.SC, self.mbs = SC, mbs
        joints = links + 1
        self.coupling = Coupling(coupling, record=self._record)
        self.radial = [FmuComponent(fmu_path("TrackBushRadial", fmu_dir), f"radial_{j}")
                       for j in range(joints)]
        self.torsion = [FmuComponent(fmu_path("TrackBushTorsion", fmu_dir), f"torsion_{j}")
                        for j in range(joints)]
        if self.compiled:
            self.bank = bank_path.Bank([c for pair in zip(self.radial, self.torsion)
                                        for c in pair], coupling, record=self._record_bank)
            self.laws = bank_path.SymbolicLaws(self.bank)
        # The straight span under tension, before gravity: each bush deflected to carry it.
        seat_gap = self._deflection_for(self.radial[0], TENSION)

        ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
        sprocket = mbs.AddObject(ObjectGround(referencePosition=[0.0, 0.0, 0.0]))

        def coordinate(node, index):
            return mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=index))

        def seat(body, x):
            return mbs.AddMarker(MarkerBodyPosition(bodyNumber=body, localPosition=[x, 0, 0]))

        # Bodies along the span: (right pin seat marker, rotation marker) of the body left
        # of each joint, and (left seat, rotation) of the body right of it.
        left = (seat(sprocket, 0.0), coordinate(ground, 2))
        self.link_nodes = []
        for j in range(joints):
            if j < links:
                x_centre = j * PITCH + (j + 1) * seat_gap + 0.5 * PITCH
                node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x_centre, 0.0, 0.0]))
                body = mbs.AddObject(ObjectRigidBody2D(mass=LINK_MASS, inertia=LINK_INERTIA,
                                                       nodeNumber=node))
                mbs.AddLoad(LoadForceVector(markerNumber=seat(body, 0.0),
                                            loadVector=[0.0, -LINK_MASS * GRAVITY, 0.0]))
                self.link_nodes.append(node)
                right = (seat(body, -0.5 * PITCH), coordinate(node, 2))
                next_left = (seat(body, 0.5 * PITCH), coordinate(node, 2))
            else:
                right = self._lifting_wheel(ground, coordinate, seat,
                                            links * PITCH + joints * seat_gap)
                self.wheel_node = mbs.GetObject(mbs.GetMarker(right[0])["bodyNumber"])["nodeNumber"]
            self._add_joint(j, left, right)
            if j < links:
                left = next_left
        mbs.Assemble()
        self.records = []

    @staticmethod
    def _deflection_for(bush, force):
        """Deflection at which the relaxed bush carries `force` (its elastic force is
        linear: one secant from the FMU's own output)."""
        probe = 1e-4
        return probe * force / bush.relaxed_outputs(probe)[bush.load_name]

    def _lifting_wheel(self, ground, coordinate, seat, x):
        """The wheel at the span's far end: pulled along the span by the tension, lifted
        by the prescribed motion, not turning."""
        mbs = self.mbs
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[x, 0.0, 0.0]))
        body = mbs.AddObject(ObjectRigidBody2D(mass=WHEEL_MASS, inertia=1.0, nodeNumber=node))
        mbs.AddLoad(LoadForceVector(markerNumber=seat(body, 0.0), loadVector=[TENSION, 0, 0]))
        lifting = mbs.AddObject(CoordinateConstraint(
            markerNumbers=[coordinate(ground, 1), coordinate(node, 1)]))
        # the lift as a compiled symbolic function (exudyn evaluates it at every Newton
        # iterate): the same operations as lift_at's, in C++
        esym = exu.symbolic
        self._symbolic.append(symbolic_function(
            mbs, lifting, lambda mbs, t, itemNumber, lOffset: self.lift_at(t, esym.cos),
            "offsetUserFunction"))
        mbs.AddObject(CoordinateConstraint(markerNumbers=[coordinate(ground, 2),
                                                          coordinate(node, 2)]))
        return seat(body, 0.0), coordinate(node, 2)

    def lift_at(self, t, cos=math.cos):
        return 0.5 * self.lift * (1.0 - cos(2 * math.pi * self.frequency * t))

    def _add_joint(self, j, left, right):
        """Radial and torsion bush between the body left of joint j and the one right of
        it. Connector convention: the force f of a spring-damper acts as -f on its second
        marker (the right body) and +f on its first."""
        mbs = self.mbs
        radial, torsion = self.radial[j], self.torsion[j]

        def radial_force(mbs, t, item, distance, rate, *_):
            # the spring's length less its reference length, 0: the seats' distance
            return radial.host_load(distance, rate)

        def torsion_torque(mbs, t, item, rotation, rate, *_):
            # Joint angle = left link's rotation - right link's = -rotation.
            return -torsion.host_load(-rotation, -rate)

        # a scalar force along the line between the seats, exudyn's own geometry: a
        # tension pulls them together
        radial_connector = mbs.AddObject(ObjectConnectorSpringDamper(
            markerNumbers=[left[0], right[0]], springForceUserFunction=radial_force))
        torsion_connector = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
            markerNumbers=[left[1], right[1]], springForceUserFunction=torsion_torque))

        def radial_state():
            return seat_deflection(*connector_state(mbs, radial_connector))

        def torsion_state():
            rotation, rate = connector_state(mbs, torsion_connector)
            return -float(rotation), -float(rate)

        self.coupling.add(radial, radial_state)
        self.coupling.add(torsion, torsion_state)
        self.connectors = getattr(self, "connectors", []) + [(j, radial_connector,
                                                              torsion_connector)]

    def _compile_forces(self):
        """The compiled path: each connector's force the symbolic law of its instance
        (after the static solve, which the relaxed bushes' Python functions make)."""
        laws = self.laws

        def radial(i):
            def radial_force(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
                return laws.load(i, deltaL)
            return radial_force

        def torsion(i):
            def torsion_torque(mbs, t, itemNumber, displacement, velocity, stiffness, damping,
                               offset):
                return -laws.load(i, -displacement)
            return torsion_torque

        for j, radial_connector, torsion_connector in self.connectors:
            self._symbolic += [
                bank_path.symbolic_function(self.mbs, radial_connector, radial(2 * j)),
                bank_path.symbolic_function(self.mbs, torsion_connector, torsion(2 * j + 1))]
        nodes = self.link_nodes + [self.wheel_node]
        self._index = np.array([self.mbs.GetNodeODE2Index(n) for n in nodes])[:, None] + [0, 1, 2]
        self._reference = np.array([self.mbs.GetNodeParameter(n, "referenceCoordinates")
                                    for n in nodes])
        joints = self.links + 1
        # _deflections' arrays, rows x and y: the links' half-pitch vectors; the joints'
        # left seats (the sprocket's (0, 0) first) and right seats
        self._seats = (np.empty((2, joints - 1)), np.zeros((2, joints)),
                       np.empty((2, joints)))
        self._index_rows = np.ascontiguousarray(self._index.T)  # rows x, y, angle
        self._reference_rows = np.ascontiguousarray(self._reference.T)
        self._deflections = self.compiled_deflections() or self.numpy_deflections

    def compiled_deflections(self):
        """numpy_deflections in C (track_span_deflections.c: the same operations, the same
        bits, a quarter of the time), its arrays' addresses taken once; None where the
        kernel cannot be built (DEFLECTIONS.load warns)."""
        lib = DEFLECTIONS.load("the span takes its deflections from numpy")
        if lib is None:
            return None
        function = lib.span_deflections
        function.argtypes = [ctypes.c_int, ctypes.c_double] + [ctypes.c_void_p] * 4
        function.restype = None
        index = self._index_rows.astype(np.int64)
        nodes, half = index.shape[1], 0.5 * PITCH
        deflections = np.empty(2 * nodes)
        self._kernel_arrays = (index, deflections)  # alive as long as the span
        arrays = (index.ctypes.data, self._reference_rows.ctypes.data, deflections.ctypes.data)
        coordinates = self.mbs.systemData.GetODE2Coordinates

        def compiled():
            now = coordinates()  # held while the kernel reads it
            function(nodes, half, now.ctypes.data, *arrays)
            return deflections
        return compiled

    def numpy_deflections(self):
        """Every instance's deflection from the system's coordinates, in one pass: radial,
        the distance between the pin seats of a joint; torsion, the left link's rotation
        minus the right one's (the Python path's connector_state, vectorised, its
        operations). x and y as the rows of one array, so that each operation takes both,
        into arrays made once, each cosine and sine taken once: it runs twice per host
        step."""
        x_y_angle = self._reference_rows + self.mbs.systemData.GetODE2Coordinates()[
            self._index_rows]
        x_y, angle = x_y_angle[:2], x_y_angle[2]
        half, left, right = self._seats
        np.cos(angle[:-1], out=half[0])
        np.sin(angle[:-1], out=half[1])
        half *= 0.5 * PITCH
        # left seats: the sprocket's (0, 0), then each link's right end; right seats: each
        # link's left end, then the wheel's centre
        np.add(x_y[:, :-1], half, out=left[:, 1:])
        np.subtract(x_y[:, :-1], half, out=right[:, :-1])
        right[:, -1] = x_y[:, -1]
        apart = right - left
        apart *= apart
        deflections = np.empty(2 * len(angle))
        np.sqrt(np.add(apart[0], apart[1], out=apart[0]), out=deflections[0::2])
        deflections[1] = 0.0 - angle[0]
        np.subtract(angle[:-1], angle[1:], out=deflections[3::2])
        return deflections

    # --- static state and run -----------------------------------------------------------

    def solve_static(self):
        """The host's static equilibrium with the relaxed bushes; becomes the initial state."""
        settings = exu.SimulationSettings()
        settings.staticSolver.verboseMode = 0
        settings.solution.file.write = False
        settings.solution.sensors.active = False
        if not self.mbs.SolveStatic(settings, updateInitialValues=True):
            raise RuntimeError("exudyn's static solver failed")

    def _record(self, t):
        mbs = self.mbs
        heights = [mbs.GetNodeOutput(n, exu.OutputVariableType.Position)[1]
                   for n in self.link_nodes]
        accelerations = [mbs.GetNodeOutput(n, exu.OutputVariableType.Acceleration)[1]
                         for n in self.link_nodes]
        self.records.append((t, [c.load for c in self.torsion],
                             [c.deflection for c in self.torsion],
                             [c.load for c in self.radial], heights, accelerations))

    def _record_bank(self, t):
        """The bank's loads and the system's vectors as they are (the links' heights and
        accelerations are picked out after the run: _bank_histories)."""
        data, bank = self.mbs.systemData, self.bank
        self.records.append((t, bank.loads, bank.accepted[1::2, 1].copy(),
                             data.GetODE2Coordinates(), data.GetODE2Coordinates_tt()))

    def _bank_histories(self):
        """_record's histories from _record_bank's: the links' heights (reference plus
        coordinate, as exudyn's node output has it) and accelerations."""
        t, loads, angles, coordinates, accelerations = (np.array(a) for a in zip(*self.records))
        y = self._index[:-1, 1]
        return (t, loads[:, 1::2], angles, loads[:, 0::2],
                self._reference[:-1, 1] + coordinates[:, y], accelerations[:, y])

    def run(self, end_time, step):
        self.solve_static()
        if self.compiled:
            self._compile_forces()
            self.host = bank_path.solve(self.mbs, self.bank, self.laws, self._deflections,
                                        end_time, step, settings=solver_settings())
            self.coupling = self.bank
            t, torques, angles, forces, heights, accelerations = self._bank_histories()
        else:
            self.host = solve(self.mbs, self.coupling, end_time, step,
                              settings=solver_settings())
            t, torques, angles, forces, heights, accelerations = zip(*self.records)
        return {"time": np.array(t), "joint_torque": np.array(torques),
                "joint_angle": np.array(angles), "radial_force": np.array(forces),
                "link_height": np.array(heights), "link_acceleration": np.array(accelerations),
                "lift": np.array([self.lift_at(ti) for ti in t])}


def solver_settings():
    """exudyn's settings for the dynamic solve: quiet, no files, its sparse linear solver,
    as a long span's Jacobian is a band (40 links: a fifth less CPU than dense), and
    Newton to NEWTON_TOLERANCE."""
    settings = quiet_settings(NEWTON_TOLERANCE)
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    return settings


def seat_deflection(displacement, velocity):
    """Radial deflection of a round bush (distance between the pin seats) and its rate."""
    # the distance as the compiled path's symbolic function and _deflections have it
    distance = math.sqrt(displacement[0] * displacement[0] + displacement[1] * displacement[1])
    if distance == 0.0:
        return 0.0, 0.0
    return distance, (displacement[0] * velocity[0] + displacement[1] * velocity[1]) / distance


# --- plots --------------------------------------------------------------------------------

def plot_span(path, result, span):
    from plotting import plt, save_figure

    t = result["time"]
    figure, axes = plt.subplots(4, 1, figsize=(9, 12), sharex=True)
    joints = result["joint_torque"].shape[1]
    colours = plt.cm.viridis(np.linspace(0, 1, joints))
    for j in range(joints):
        axes[0].plot(t, result["joint_torque"][:, j], color=colours[j], lw=0.8,
                     label=f"joint {j}" if j in (0, joints // 2, joints - 1) else None)
        axes[1].plot(t, np.degrees(result["joint_angle"][:, j]), color=colours[j], lw=0.8)
        axes[2].plot(t, result["radial_force"][:, j] / 1e3, color=colours[j], lw=0.8)
    axes[0].set_ylabel("joint torque,\nTrackBushTorsion (N.m)")
    # legends beside the axes: the curves fill each panel
    axes[0].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axes[1].set_ylabel("joint angle (deg)\n(live angle 10 deg)")
    axes[2].set_ylabel("pin radial force,\nTrackBushRadial (kN)")
    heights = (result["link_height"] - result["link_height"][0]) * 1e3
    for i in range(heights.shape[1]):
        axes[3].plot(t, heights[:, i], color=colours[i], lw=0.8,
                     label=f"link {i}" if i in (0, heights.shape[1] // 2) else None)
    axes[3].plot(t, result["lift"] * 1e3, "k--", lw=1.0, label="end lift")
    axes[3].set_ylabel("link height from\nstatic (mm)")
    axes[3].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    axes[-1].set_xlabel("time (s)")
    for axis in axes:
        axis.grid(alpha=0.3)
    axes[0].set_title(f"Track span: {span.links} links, {TENSION / 1e3:g} kN, end lifted "
                      f"{span.lift * 1e3:g} mm at {span.frequency:g} Hz (colour: joint/link "
                      f"from sprocket to wheel)")
    save_figure(figure, path)


def plot_shapes(path, result, span):
    """Vertical position of every link centre along the span at a few instants."""
    from plotting import plt, save_figure

    figure, axis = plt.subplots(figsize=(9, 4))
    # The held joint at the sprocket, the link centres, the lifted joint at the wheel.
    x = np.concatenate(([0.0], (np.arange(span.links) + 0.5) * PITCH, [span.links * PITCH]))
    t = result["time"]
    for instant in np.linspace(0.0, t[-1], 9):
        i = min(int(np.searchsorted(t, instant)), len(t) - 1)
        heights = np.concatenate(([0.0], result["link_height"][i], [result["lift"][i]]))
        axis.plot(x, heights * 1e3, "o-", ms=3, lw=1.0, label=f"t = {t[i]:.3f} s")
    axis.set_xlabel("position along the span (m)")
    axis.set_ylabel("height (mm): end joints\nand link centres")
    axis.set_title("Span shape (static sag at t = 0)")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0)
    save_figure(figure, path)


# --- coupling accuracy --------------------------------------------------------------------

STUDY_KEYS = ("link_acceleration", "joint_torque", "radial_force")
STUDY_LABELS = {"link_acceleration": "link acceleration", "joint_torque": "joint torque",
                "radial_force": "pin force"}
FINE_STEP = 3.125e-5  # s: the reference run, `converged` at this host step


def simulate(step, links=10, lift=0.01, frequency=6.0, fmu_dir=None, end_time=1.0,
             coupling=DEFAULT_SCHEME, path=bank_path.DEFAULT_PATH):
    span = TrackSpan(links, lift, frequency, fmu_dir, coupling, path)
    result = span.run(end_time, step)
    result["costs"] = span.coupling.costs()
    result["solve_cpu"] = span.host.solve_cpu  # s, the dynamic solve's CPU time
    return result


def coupling_study(links=10, lift=0.01, frequency=6.0, fmu_dir=None, end_time=1.0,
                   steps=STUDY_STEPS, schemes=STUDY_SCHEMES, progress=None):
    """The study (examples/coupling_study.py) against `converged` at FINE_STEP; errors of
    each history are the worst over the links (joints)."""
    def run(scheme, step):
        return simulate(step, links, lift, frequency, fmu_dir, end_time, scheme)

    started = time.perf_counter()
    reference = run("converged", FINE_STEP)
    reference["wall"] = time.perf_counter() - started
    return reference, study(run, reference, STUDY_KEYS, steps, schemes, progress)


CSV_UNITS = {"time": "s", "lift": "m", "link_height": "m", "link_acceleration": "m/s2",
             "joint_angle": "rad", "joint_torque": "N.m", "radial_force": "N"}


def csv_columns(result):
    joints = result["joint_torque"].shape[1]
    links = result["link_height"].shape[1]
    return {"time": result["time"], "lift": result["lift"],
            "link_height": [(f"link_height_{i}", result["link_height"][:, i])
                            for i in range(links)],
            "link_acceleration": [(f"link_acceleration_{i}", result["link_acceleration"][:, i])
                                  for i in range(links)],
            "joint_angle": [(f"joint_angle_{j}", result["joint_angle"][:, j])
                            for j in range(joints)],
            "joint_torque": [(f"joint_torque_{j}", result["joint_torque"][:, j])
                             for j in range(joints)],
            "radial_force": [(f"radial_force_{j}", result["radial_force"][:, j])
                             for j in range(joints)]}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--links", type=int, default=10)
    parser.add_argument("--lift", type=float, default=0.01, help="end lift, m")
    parser.add_argument("--frequency", type=float, default=6.0, help="end lift, Hz")
    parser.add_argument("--end-time", type=float, default=1.0, help="s")
    parser.add_argument("--step", type=float, default=DEFAULT_STEP, help="host step, s")
    add_fmu_arguments(parser)
    parser.add_argument("--out", type=Path, default=Path("reports") / "track_span")
    add_arguments(parser, "every scheme at host steps of 4 to 0.25 ms against a fine "
                          "reference, instead of the run")
    bank_path.add_argument(parser)
    args = parser.parse_args(argv)
    args.fmu_dir = fmu_dir_of(args)
    args.out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    if args.coupling_study:
        reference, table = coupling_study(args.links, args.lift, args.frequency,
                                          args.fmu_dir, args.end_time, progress=progress)
        text = (f"Track span, {args.links} links, end lifted {args.lift * 1e3:g} mm at "
                f"{args.frequency:g} Hz: every coupling scheme against `converged` at "
                f"{FINE_STEP * 1e3:g} ms (total; {reference['wall']:.0f} s) and against "
                f"`converged` at the same host step (own); history errors are max over "
                f"the links (joints) and on a {STUDY_GRID * 1e3:g} ms grid, in % of the "
                f"reference's range; costs per host step and FMU.\n\n"
                f"{format_table(table, STUDY_KEYS, STUDY_LABELS)}\n")
        write_study(args.out, text)
        print(f"wrote {args.out / 'coupling_study.md'}; wall time "
              f"{time.perf_counter() - started:.1f} s")
        return
    span = TrackSpan(args.links, args.lift, args.frequency, args.fmu_dir, args.coupling,
                     args.path)
    result = span.run(args.end_time, args.step)
    wall = time.perf_counter() - started
    torque, force = result["joint_torque"], result["radial_force"]
    print(f"{args.links} links, {2 * (args.links + 1)} FMU instances, "
          f"{len(result['time']) - 1} host steps of {args.step * 1e3:g} ms, "
          f"coupling {args.coupling}, {'compiled' if span.compiled else 'Python'} path")
    print(f"static: pin forces {force[0].min() / 1e3:.2f} to {force[0].max() / 1e3:.2f} kN, "
          f"joint torques {torque[0].min():.1f} to {torque[0].max():.1f} N.m, mid-span sag "
          f"{-result['link_height'][0][args.links // 2] * 1e3:.2f} mm")
    rise = result["link_height"] - result["link_height"][0]
    print(f"run: joint torques {torque.min():.1f} to {torque.max():.1f} N.m, pin forces "
          f"{force.min() / 1e3:.2f} to {force.max() / 1e3:.2f} kN, link heights from static "
          f"{rise.min() * 1e3:.1f} to {rise.max() * 1e3:.1f} mm (as plotted)")
    plot_span(args.out / "track_span.png", result, span)
    plot_shapes(args.out / "track_span_shapes.png", result, span)
    if args.csv:
        write_csv(args.out / "track_span.csv", csv_columns(result), CSV_UNITS)
    print(f"wrote plots{' and CSV' if args.csv else ''} to {args.out}/; "
          f"wall time {wall:.1f} s")


if __name__ == "__main__":
    main()
