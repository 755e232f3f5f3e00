"""The tracked vehicle (examples/tracked_vehicle.py, docs/vehicle.md): its track loop's
geometry, the course's roughness class, the ISO 2631-1 weighting, the stop on bad input,
and a run of a few host steps through the command line (summary and CSV). The exudyn
parts need the `examples` extra; without it they are skipped with that reason."""

import csv
import math
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'


def test_track_loop_closes_with_every_joint_one_chord():
    """80 pins round the wheels, sprocket, roller and idler, every joint (the closing one
    included) the pitch plus the bush's static stretch apart: the loop is closed."""
    from vehicle import layout as lay

    chord = lay.LINK_PITCH + 1.6e-4
    geo = lay.Layout(3.2e-3, chord)
    joints = np.hypot(*(np.roll(geo.pins, -1, axis=0) - geo.pins).T)
    assert geo.links == len(geo.pins) == 80
    assert np.max(np.abs(joints - chord)) < 1e-9
    # the bottom run lies on the ground from under the last wheel to under the first
    bottom = geo.pins[geo.pins[:, 1] < lay.LINK_OUTER + 1e-9][:, 0]
    assert bottom.min() < geo.station_x[-1] + chord and bottom.max() > geo.station_x[0] - chord
    # sprocket at the front, idler behind the last station (section 1.1)
    assert geo.sprocket[0] > geo.station_x[0] and geo.idler[0] < geo.station_x[-1]


def test_random_road_has_the_variance_of_its_iso_8608_class():
    """The variance of the class C road over its band is the integral of
    Gd(n) = Gd(n0) (n / n0)^-2 over it: Gd(n0) n0^2 (1/n_low - 1/n_high)."""
    from vehicle.course import ISO8608_GD, ISO8608_N0, RandomRoad

    road = RandomRoad(front=0.0, roughness="C")
    x = np.arange(road.start + road.fade, 5000.0, 0.05)
    low, high = road.k[0] / (2 * math.pi), road.k[-1] / (2 * math.pi) + 0.01
    expected = ISO8608_GD["C"] * ISO8608_N0 ** 2 * (1 / (low - 0.005) - 1 / high)
    assert np.var(road.height(x)) == pytest.approx(expected, rel=0.1)


@pytest.mark.parametrize("frequency, weight", [(1.0, 0.482), (4.0, 0.967), (8.0, 1.036),
                                               (16.0, 0.768)])
def test_wk_weighting_follows_iso_2631(frequency, weight):
    """ISO 2631-1:1997 Table 3, Wk (factors x 1000: 482, 967, 1036, 768)."""
    from scipy import signal
    from vehicle.outputs import wk_weighting

    _, response = signal.freqs(*wk_weighting(), [2 * math.pi * frequency])
    assert abs(response[0]) == pytest.approx(weight, rel=0.01)


def test_a_link_through_a_wheel_stops_the_run_naming_wheel_and_time(native_fmus):
    """Road wheel 2 pushed 45 mm into the link beneath (more than its 37.5 mm of rubber):
    the check names the wheel and the time."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.model import Vehicle, VehicleError

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
    try:
        data = vehicle.mbs.systemData
        q = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Current))
        q[vehicle.mbs.GetNodeODE2Index(vehicle.arm_nodes[1]) + 1] -= 0.045
        data.SetODE2Coordinates(q, exu.ConfigurationType.Current)
        with pytest.raises(VehicleError, match=r"road wheel 2: a track link has passed "
                                               r"through its tyre .* at t = 0\.1230 s"):
            vehicle.contacts.check(0.123)
    finally:
        vehicle.coupling.free()


def _laid_out(native_fmus, settling=False, joints="kernel"):
    from vehicle.course import Bump
    from vehicle.model import Vehicle

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent, joints=joints)
    vehicle.settling = settling
    return vehicle


def test_every_wheel_starts_on_the_track_at_its_static_compression(native_fmus):
    """At the laid-out geometry each tyre is compressed by the static compression (the
    track leaves the ground run clear of the end wheels instead of wrapping a link into
    them), and gravity acts on every body."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import layout

    vehicle = _laid_out(native_fmus, settling=True)
    try:
        contacts = vehicle.contacts
        contacts.evaluate(0.0)
        static = vehicle.statics[0]
        assert np.max(np.abs(contacts.compression - static)) < 1e-4, contacts.compression
        # at rest the vertical loads on all bodies (joint reactions aside) sum to what
        # comes from outside: gravity on every body and the ground's reaction
        mbs = vehicle.mbs
        velocities = mbs.systemData.GetODE2Coordinates_t(exu.ConfigurationType.Initial)
        mbs.systemData.SetODE2Coordinates_t(0 * velocities, exu.ConfigurationType.Initial)
        settings = exu.SimulationSettings()
        settings.solution.file.write = False  # no solution file in the working directory
        solver = exu.MainSolverImplicitSecondOrder()
        solver.InitializeSolver(mbs, settings)
        solver.ComputeODE2RHS(mbs)
        loads = np.array(solver.GetSystemResidual())
        contacts.evaluate(0.0)
        vertical = [mbs.GetNodeODE2Index(node) + 1 for node in contacts.nodes]
        weight = layout.SIDE_MASS * layout.GRAVITY
        outside = contacts.ground_load.sum() - weight
        assert loads[vertical].sum() == pytest.approx(outside, rel=1e-6)
    finally:
        vehicle.coupling.free()


def _central_differences(contacts, q, qd, h, by_velocity=False):
    """Minus the contacts' generalized forces' central differences by q (or qd): the
    Jacobian exudyn takes from them."""
    numeric = np.zeros((len(q), len(q)))
    for i in range(len(q)):
        d = np.zeros_like(q)
        d[i] = h
        plus, minus = ((q, qd + d), (q, qd - d)) if by_velocity else ((q + d, qd), (q - d, qd))
        numeric[:, i] = -(contacts._generalized(0.0, *plus)
                          - contacts._generalized(0.0, *minus)) / (2 * h)
    return numeric


@pytest.mark.parametrize("settling", [True, False])
def test_the_contacts_jacobian_is_the_derivative_of_their_forces(native_fmus, settling):
    """The Jacobian the contacts give exudyn's Newton (tyres with the tangent of their load
    law and the blend over the links beneath, the sprocket turning with the hull's travel,
    the penalty contacts) against central differences of their generalized forces, at the
    laid-out state: within 1 % of the largest entry."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    vehicle = _laid_out(native_fmus, settling)
    try:
        contacts = vehicle.contacts
        if not settling:
            vehicle.coupling.start(0.0)  # the FMUs' load laws
        data = vehicle.mbs.systemData
        q = np.asarray(data.GetODE2Coordinates(exu.ConfigurationType.Current))
        q = q[contacts.system_index]
        qd = np.zeros_like(q)
        analytic = contacts._jacobian(0.0, q, qd, 1.0, 0.0)
        numeric = _central_differences(contacts, q, qd, 1e-8)
        assert np.max(np.abs(analytic - numeric)) < 0.01 * np.max(np.abs(numeric))
    finally:
        vehicle.coupling.free()


def test_the_settling_dampings_jacobian_is_the_derivative_of_its_forces(native_fmus):
    """While settling, the contacts' damping part of the Jacobian (factor_t) against
    central differences of their generalized forces by the velocities, on both kernels:
    linear in the velocities, so to rounding. Each arm is damped at its wheel's centre (its
    force's moment on the arm in the force as in the Jacobian), the hull's pitch damper in
    the Jacobian as in the force."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    vehicle = _laid_out(native_fmus, settling=True)
    try:
        contacts = vehicle.contacts
        data = vehicle.mbs.systemData
        q = np.asarray(data.GetODE2Coordinates(exu.ConfigurationType.Current))
        q = q[contacts.system_index]
        qd = np.random.default_rng(1).normal(0.0, 0.1, q.shape)
        for kernel in ("numpy", "compiled"):
            contacts.use(kernel)
            analytic = contacts._jacobian(0.0, q, qd, 0.0, 1.0)
            numeric = _central_differences(contacts, q, qd, 1e-6, by_velocity=True)
            # the arms' rows (the wheel 0.067 m from the arm's node: moments of 22 to
            # 290 N.m.s) are 1e-3 of the largest entry (the hull's pitch damper)
            assert np.max(np.abs(analytic - numeric)) < 1e-8 * np.max(np.abs(numeric)), kernel
    finally:
        vehicle.coupling.free()


def test_the_stored_static_point_is_keyed_by_the_models_values(native_fmus, monkeypatch):
    """Same model, same key; a changed value (the torsion-bar rate) or FMU set, a new one."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import layout, settle_damping, static

    vehicle = _laid_out(native_fmus)
    try:
        key = static.static_key(vehicle, 2e-3)
        assert static.static_key(vehicle, 2e-3) == key
        assert static.static_key(vehicle, 1e-3) != key
        monkeypatch.setattr(layout, "TORSION_BAR_STIFFNESS", 16000.0)
        changed = static.static_key(vehicle, 2e-3)
        assert changed != key
        # the settling's damping decides where it stops (its rest is a velocity)
        monkeypatch.setitem(settle_damping.SETTLE_DAMPING, "arm", 6e3)
        assert static.static_key(vehicle, 2e-3) != changed
    finally:
        vehicle.coupling.free()


def test_a_short_run_prints_its_summary_and_writes_the_csv(native_fmus, tmp_path):
    """Four host steps of 1 ms from the laid-out geometry, the default run: on the own
    solver, and the summary says so; it counts the 175 FMU instances, the cost and the
    own solver's iterations, the CSV has SI columns, the track stays closed and every
    wheel stays on it."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    run = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "tracked_vehicle.py"), "--end-time", "0.004",
         "--settle-time", "0", "--csv", "--out", str(tmp_path), "--newton-tolerance", "2.5",
         "--fmu-dir", str(native_fmus["RoadWheelTyre"].parent)],
        capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr[-2000:]
    assert "175 FMU instances" in run.stdout and "compiled path" in run.stdout
    assert "solver own (no exudyn in the time loop)" in run.stdout
    assert re.search(r"s wall and [0-9.]+ s CPU per simulated second", run.stdout)
    assert re.search(r"^own: [0-9.]+ Newton iterations per solve", run.stdout, re.M)
    assert "Newton tolerance 2.5" in run.stdout
    assert f"wrote {tmp_path}" in run.stdout
    with open(tmp_path / "bump_3mps.csv") as stream:
        rows = list(csv.DictReader(stream))
    # each column headed by its name and SI unit, "time (s)"
    units = dict(re.fullmatch(r"(\S+) \((\S+)\)", h).groups() for h in rows[0])
    assert units["time"] == "s" and units["hull_vertical_acceleration"] == "m/s2"
    assert units["hull_pitch_acceleration"] == "rad/s2" and units["bush_angle_79"] == "rad"
    rows = [{h.split(" (")[0]: v for h, v in row.items()} for row in rows]
    for column in ("time", "hull_vertical_acceleration", "hull_pitch_acceleration",
                   "seat_vertical_acceleration", "track_tension_sprocket",
                   "track_tension_idler", "tyre_force_1", "tyre_force_6", "damper_torque_1",
                   "damper_torque_6", "bush_radial_deflection_0", "bush_angle_79"):
        assert column in rows[0]
    assert float(rows[-1]["time"]) >= 0.004 - 1e-9
    # the joints stay within 1 mm of the pitch (closed) and every wheel on its tyre
    stretch = [float(rows[-1][f"bush_radial_deflection_{j}"]) for j in range(80)]
    assert max(stretch) < 1e-3
    for w in range(1, 7):
        assert 0.0 < float(rows[-1][f"tyre_compression_{w}"]) < 0.0375


def test_the_newton_tolerance_reaches_exudyn_and_a_bad_one_is_refused_naming_it():
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.model import NEWTON_TOLERANCE, run_settings
    assert run_settings().timeIntegration.newton.absoluteTolerance == NEWTON_TOLERANCE
    assert run_settings(0.6, 2.5).timeIntegration.newton.absoluteTolerance == 2.5
    run = subprocess.run(
        [sys.executable, str(ROOT / "examples" / "tracked_vehicle.py"),
         "--newton-tolerance", "-1"], capture_output=True, text=True, timeout=300)
    assert run.returncode == 2
    assert "--newton-tolerance -1: give a value above 0" in run.stderr


def test_the_compiled_path_gives_the_python_paths_numbers(native_fmus):
    """Three host steps of 1 ms from the laid-out geometry (5 m/s, `corrected`): the bank
    with every instance's law in exudyn's compiled symbolic functions and the tyres' laws
    read from its arrays gives the same histories as a Python force function per
    connector and a Python call per tyre, to the bit; and the bank is what ran."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from tracked_vehicle import simulate
    from vehicle.model import static_points

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    statics = static_points(fmu_dir)
    runs, steps = {}, {}
    for path in ("python", "compiled"):
        vehicle, runs[path], _, _ = simulate("bump", 5.0, 0.003, 1e-3, "corrected", None,
                                             statics, 0.0, fmu_dir, path, solver="exudyn")
        assert vehicle.compiled == (path == "compiled")
        assert type(vehicle.coupling).__name__ == ("Bank" if vehicle.compiled else "Coupling")
        # every step (3 asked; exudyn may halve one in this start from the laid-out
        # geometry) solved twice, the same steps on both paths
        steps[path] = vehicle.coupling.steps
        assert steps[path] >= 3 and vehicle.coupling.total_passes == 2 * steps[path]
    assert steps["python"] == steps["compiled"]
    keys = [key for key, value in runs["python"].items() if isinstance(value, np.ndarray)]
    assert {"hull_vertical_acceleration", "tyre_force", "bush_radial_force", "bush_angle",
            "damper_torque", "track_tension_sprocket"} <= set(keys)
    for key in keys:
        assert runs["python"][key].shape == runs["compiled"][key].shape, key
        assert np.array_equal(runs["python"][key], runs["compiled"][key]), key
    # the run did something: every wheel on its tyres, the bushes carrying the tension
    assert np.all(runs["compiled"]["tyre_force"][-1] > 0.0)
    assert np.max(runs["compiled"]["bush_radial_force"][-1]) > 5e3


def test_the_components_start_at_the_runs_initial_state(native_fmus):
    """The run's initial state (a stored static point, here the laid-out geometry with one
    link turned by 0.01 rad) is where the components start relaxed, not exudyn's current
    configuration before the solve (the laid-out geometry): the torsion bushes either side
    of the turned link start at their joints' angles in the initial state."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.model import Vehicle

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
    data = vehicle.mbs.systemData
    k = 40
    turned = vehicle.mbs.GetNodeODE2Index(vehicle.link_nodes[k]) + 2
    q = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Initial))
    assert q[turned] == 0.0  # the laid-out geometry is the nodes' reference
    q[turned] = 0.01
    data.SetODE2Coordinates(q, exu.ConfigurationType.Initial)
    result = vehicle.run(1e-3, 1e-3, settle=False)
    offsets = vehicle.torsion_offsets
    assert result["time"][0] == 0.0
    assert result["bush_angle"][0][k] == pytest.approx(0.01 + offsets[k], abs=1e-12)
    assert result["bush_angle"][0][k + 1] == pytest.approx(-0.01 + offsets[k + 1], abs=1e-12)


def _carried_round(contacts, state, link, edges, points=200):
    """The work the contacts' forces do on one link carried round a closed loop of its
    coordinates (edges: functions of s in [0, 1] giving the link's (x, y, angle), each
    edge starting where the last ended), everything else still: trapezoids on each edge."""
    q = state.copy()
    qd = np.zeros_like(q)
    rows = 3 * (contacts.link0 + link) + np.arange(3)
    work = travelled = 0.0
    for edge in edges:
        path = np.array([edge(s) for s in np.linspace(0.0, 1.0, points + 1)])
        forces = []
        for coordinates in path:
            q[rows] = coordinates - contacts.reference[contacts.link0 + link]
            forces.append(contacts._generalized(0.0, q, qd)[rows].copy())
        forces, steps = np.array(forces), np.diff(path, axis=0)
        pieces = 0.5 * np.einsum("ij,ij->i", forces[1:] + forces[:-1], steps)
        work += pieces.sum()
        travelled += np.abs(pieces).sum()
    return work, travelled


def test_the_sprocket_engagement_does_no_net_work_round_a_closed_motion(native_fmus):
    """The teeth take up and let go of a pin over ENGAGEMENT_RAMP at the wrap's ends. A link
    whose front pin lies just past the wrap's end, turned about the sprocket's centre until
    that pin is inside the ramp, pushed out from the centre, turned back and let back in
    (everything else still, at rest): the contacts' forces on it do no net work round the
    loop, as a passive contact must (the engagement is the potential w k |gap|^2 / 2; a
    pull k (tooth space - pin) scaled by w alone pumped energy into the track at every
    passage)."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.model import ENGAGEMENT_RAMP

    vehicle = _laid_out(native_fmus, settling=True)  # the tyres' relaxed tables: no FMU calls
    try:
        contacts = vehicle.contacts
        data = vehicle.mbs.systemData
        state = np.asarray(data.GetODE2Coordinates(exu.ConfigurationType.Current))[
            contacts.system_index]
        contacts.evaluate(0.0)
        centre = contacts.hull[:2] + contacts.sprocket_local
        relative = contacts.pins - centre
        into = (np.arctan2(relative[:, 1], relative[:, 0]) - contacts.wrap_start) % (2 * math.pi)
        past = into - contacts.wrap_sweep
        pin = int(np.argmin(np.where(past > 0.0, past, np.inf)))
        assert 0.0 < past[pin] < 0.5 * ENGAGEMENT_RAMP  # just past the wrap's end
        link = pin - 1  # its front seat is that pin
        start = contacts.reference[contacts.link0 + link] + state[
            3 * (contacts.link0 + link) + np.arange(3)]
        # the pin moves by half its link's motion: turn the link by twice the angle that
        # takes the pin a fifth of the ramp inside the wrap
        turn = -2.0 * (past[pin] + 0.2 * ENGAGEMENT_RAMP)
        push = 0.02

        def placed(angle, out):
            c, s = math.cos(angle), math.sin(angle)
            r = start[:2] - centre
            moved = centre + np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])
            moved += out * (moved - centre) / np.hypot(*(moved - centre))
            return np.array([*moved, start[2] + angle])

        edges = [lambda s: placed(turn * s, 0.0), lambda s: placed(turn, push * s),
                 lambda s: placed(turn * (1 - s), push), lambda s: placed(0.0, push * (1 - s))]
        work, travelled = _carried_round(contacts, state, link, edges)
        assert travelled > 10.0  # the teeth did work on the way (J)
        assert abs(work) < 1e-4 * travelled, (work, travelled)
    finally:
        vehicle.coupling.free()


def test_the_tyres_compression_rate_is_the_rate_of_their_compression(native_fmus):
    """The rate each wheel's tyres are given (their damping acts on it) is the time
    derivative of the blended compression their force works against, the links' windows
    fading in and out included: against central differences along the run's initial
    velocities (the track running at 5 m/s under the wheels), the links jostled by 1 mm so
    that the overlaps beneath a wheel differ."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    vehicle = _laid_out(native_fmus, settling=True)
    try:
        contacts = vehicle.contacts
        data = vehicle.mbs.systemData
        index = contacts.system_index
        q = np.asarray(data.GetODE2Coordinates(exu.ConfigurationType.Current))[index]
        qd = np.asarray(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))[index]
        q = q + np.random.default_rng(3).normal(0.0, 1e-3, q.shape)
        h = 1e-7
        compression = []
        for sign in (1.0, -1.0):
            contacts._update(0.0, q + sign * h * qd, qd)
            compression.append(contacts.compression.copy())
        contacts._update(0.0, q, qd)
        assert np.all(contacts.in_contact)
        rate = (compression[0] - compression[1]) / (2 * h)
        assert np.max(np.abs(rate)) > 0.01  # the wheels' compressions change (m/s)
        assert np.max(np.abs(contacts.compression_rate - rate)) < 1e-3 * np.max(np.abs(rate))
    finally:
        vehicle.coupling.free()


def test_a_wheel_above_a_convex_joint_stays_on_the_track(native_fmus):
    """Over a bump's crest the track bends convexly under a wheel (the 80 mm bump's crest:
    about 14 deg a joint). Two links beneath road wheel 3 turned 7 deg each way about their
    joint, the wheel moved onto the bisector above it: the wheel is still on the track,
    its compression its overlap with either link's face (the two windows half each), not
    lost because the wheel's centre lies beyond both links' ends along their own lines."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import layout as lay

    vehicle = _laid_out(native_fmus, settling=True)
    try:
        contacts = vehicle.contacts
        data = vehicle.mbs.systemData
        q = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Current))[contacts.system_index]
        contacts.evaluate(0.0)
        wheel = 2
        on_ground = np.flatnonzero(contacts.pins[:, 1] < 0.1)
        joint = on_ground[np.argmin(np.abs(contacts.pins[on_ground, 0]
                                           - contacts.wheels[wheel, 0]))]
        state = contacts.reference + q.reshape(-1, 3)
        half = math.radians(7.0)
        for link, seat, turn in ((joint - 1, 1, half), (joint, 0, -half)):
            body = contacts.link0 + link
            pivot = contacts.seats[link, seat]
            c, s = math.cos(turn), math.sin(turn)
            r = state[body, :2] - pivot
            state[body] = [pivot[0] + c * r[0] - s * r[1], pivot[1] + s * r[0] + c * r[1],
                           state[body, 2] + turn]
        pin = contacts.pins[joint]
        above = 0.3  # m from the joint to the wheel's centre
        state[1 + wheel, :2] += pin + [0.0, above] - contacts.wheels[wheel]
        q = (state - contacts.reference).ravel()
        contacts._update(0.0, q, np.zeros_like(q))
        assert contacts.in_contact[wheel]
        expected = lay.WHEEL_RADIUS + lay.LINK_INNER - above * math.cos(half)
        assert contacts.compression[wheel] == pytest.approx(expected, abs=1e-4)
    finally:
        vehicle.coupling.free()


@pytest.mark.parametrize("joints", ["kernel", "connectors"])
@pytest.mark.parametrize("path", ["python", "compiled"])
@pytest.mark.parametrize("load", [-3000.0, 3000.0])
def test_the_radial_bushs_force_is_lipschitz_through_zero_distance(native_fmus, path, load,
                                                                   joints):
    """A radial bush's law carries a load at zero distance (its memory: here -3 or +3 kN
    at 0.01 mm, 1e8 N/m): the force applied at its seats (by the joints' object or by the
    joint's connector), along the line between them, must still vanish there
    continuously, not flip with the line's direction. With the seats displaced by +e and
    -e along one direction, e from 1 um to 0.1 nm, the force goes to zero and its change
    over the 2 e stays bounded (a Lipschitz constant) on both paths."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from fmu_components.coupling.law import LoadLaw
    from vehicle import layout as lay
    from vehicle.model import RADIAL_FADE

    vehicle = _laid_out(native_fmus, joints=joints)
    mbs, j = vehicle.mbs, 40  # joint 40: between links 39 and 40, on the top run
    try:
        if path == "compiled":
            vehicle.prepare()
            compiled = vehicle.compiled_path
            compiled.bank.start(0.0, *compiled.initial_state())
            compiled.bank._set_law(compiled.radial_rows[j], 1e-5, load, 1e8, 0.0)
            compiled.laws.update()
            vehicle.bank = compiled.bank  # where the joints' object reads the laws
        else:
            vehicle.coupling.start(0.0)
            vehicle.radial[j].law = LoadLaw(1e-5, load, 1e8)
        data, current = mbs.systemData, exu.ConfigurationType.Current
        q = np.array(data.GetODE2Coordinates(current))
        behind, ahead = (mbs.GetNodeODE2Index(vehicle.link_nodes[k]) for k in (j - 1, j))
        reference = [np.array(mbs.GetNodeParameter(vehicle.link_nodes[k],
                                                   "referenceCoordinates")) for k in (j - 1, j)]
        x0, y0, angle0 = reference[0] + q[behind:behind + 3]
        angle1 = reference[1][2] + q[ahead + 2]
        half = 0.5 * lay.LINK_PITCH
        front = np.array([x0 + half * math.cos(angle0), y0 + half * math.sin(angle0)])
        direction = np.array([math.cos(0.3), math.sin(0.3)])

        def force(offset):
            rear = front + offset  # link 40's rear seat
            centre = rear + half * np.array([math.cos(angle1), math.sin(angle1)])
            q[ahead:ahead + 2] = centre - reference[1][:2]
            data.SetODE2Coordinates(q, current)
            if joints == "kernel":  # the force on link 39's front seat, along the line
                index = vehicle.joints.system_index
                _, joint, _, effort, _ = vehicle.joints.evaluate(q[index], 0.0 * q[index])
                assert joint[j, 2] == pytest.approx(np.hypot(*offset), rel=1e-3)
                return effort[j, 0] * joint[j, :2] / joint[j, 2]
            assert mbs.GetObjectOutput(vehicle.radial_connectors[j], exu.OutputVariableType
                                       .Distance) == pytest.approx(np.hypot(*offset), rel=1e-3)
            return np.array(mbs.GetObjectOutput(vehicle.radial_connectors[j],
                                                exu.OutputVariableType.Force))[:2]

        slopes = []
        for e in (1e-6, 1e-8, 1e-10):
            plus, minus = force(e * direction), force(-e * direction)
            # the law's load there is at most |load| + 1 kN; the fade s (2 - s) <= 2 s
            assert np.hypot(*plus) <= 2.0 * (abs(load) + 1e3) * e / RADIAL_FADE
            slopes.append(np.hypot(*(plus - minus)) / (2 * e))
        # no steeper as the seats meet: the fade's Lipschitz constant, 2 |load| / RADIAL_FADE
        assert max(slopes) <= 2.0 * (abs(load) + 1e3) / RADIAL_FADE, slopes
    finally:  # the bank frees the same instances
        (vehicle.compiled_path.bank if path == "compiled" else vehicle.coupling).free()


def _checked_step(vehicle):
    """A step of 1 ms from the vehicle's present state at t = 0.1 s, its start's
    velocities the initial ones, and the run's step check on it: (q0, v0, judged), judged(q)
    the check's verdict on the solution q."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.step_check import StepCheck

    mbs = vehicle.mbs
    data = mbs.systemData
    current, start = exu.ConfigurationType.Current, exu.ConfigurationType.StartOfStep
    q0 = np.array(data.GetODE2Coordinates(current))
    v0 = np.array(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))
    data.SetODE2Coordinates(q0, start)
    data.SetODE2Coordinates_t(v0, start)
    data.SetODE2Coordinates_t(v0, current)
    data.SetTime(0.1, start)
    check = StepCheck(vehicle)
    vehicle.contacts.evaluate(0.1)
    check.accepted()

    def judged(q):
        data.SetODE2Coordinates(q, current)
        return check(mbs, 0.101)

    return q0, v0, judged


def test_a_step_whose_solution_jumps_is_refused_naming_the_part(native_fmus):
    """The run's step check (vehicle/step_check.py) against a step of 1 ms from the
    laid-out state, the track running at 5 m/s: the state its start's velocities carry it
    to passes; the link beneath road wheel 1 turned by 21 deg and moved 47 mm (a stop at
    5 m/s replayed showed that) is refused, naming the link and the wheel; so is road
    wheel 2 pressed 5 mm further into its tyre."""
    vehicle = _laid_out(native_fmus, settling=True)
    try:
        mbs, contacts = vehicle.mbs, vehicle.contacts
        q0, v0, judged = _checked_step(vehicle)
        assert judged(q0 + 1e-3 * v0) is None
        wheel = contacts.wheels[0]
        ground = np.flatnonzero(contacts.link_pos[:, 1] < 0.1)
        k = int(ground[np.argmin(np.abs(contacts.link_pos[ground, 0] - wheel[0]))])
        jumped = q0 + 1e-3 * v0
        index = mbs.GetNodeODE2Index(vehicle.link_nodes[k])
        jumped[index:index + 3] += [0.04, 0.025, math.radians(21.0)]
        assert re.fullmatch(rf"link {k} \(beneath road wheel 1\) moved 47\.2 mm and turned "
                            r"21\.0 deg in one step beyond its motion at the step's start",
                            judged(jumped))
        pressed = q0 + 1e-3 * v0
        pressed[mbs.GetNodeODE2Index(vehicle.arm_nodes[1]) + 1] -= 5e-3
        assert re.match(r"road wheel 2: its tyre's compression jumped by 5\.\d mm",
                        judged(pressed))
    finally:
        vehicle.coupling.free()


def test_a_pin_whose_tooth_space_jumps_is_refused_naming_the_joint(native_fmus):
    """The step check's teeth (each part tests its largest value first; beyond a
    threshold, the full comparison and the message): from the laid-out state, the track
    at 5 m/s, the hull moved 20 mm further in a step of 1 ms (the sprocket's tooth spaces
    with it, past the engaged pins) is refused as a tooth skipped at an engaged joint."""
    from vehicle.step_check import TOOTH_JUMP

    vehicle = _laid_out(native_fmus, settling=True)
    try:
        q0, v0, judged = _checked_step(vehicle)
        engaged = np.flatnonzero(vehicle.contacts.tooth_gap > 0.0)
        assert len(engaged) > 0
        q = q0 + 1e-3 * v0
        q[vehicle.mbs.GetNodeODE2Index(vehicle.hull_node)] += 0.02
        message = judged(q)
        found = re.fullmatch(r"joint (\d+): its pin's gap to its sprocket tooth space jumped "
                             r"by ([\d.]+) mm in one step \(a tooth skipped\)", message)
        assert found, message
        assert int(found.group(1)) in engaged and float(found.group(2)) > TOOTH_JUMP * 1e3
    finally:
        vehicle.coupling.free()
