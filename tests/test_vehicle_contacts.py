"""The tracked vehicle's contacts on their two kernels (docs/vehicle.md, Contacts): the C
kernel compiled on first use (examples/vehicle/contacts_kernel.py) against the numpy
kernel it was written from (examples/vehicle/contacts.py, the readable reference): the
same generalized forces, records and Jacobian at states that reach every contact's
branches, the same short run, and the message where no compiler is found; the linear
vehicle's (damped Kelvin tyres) Jacobian against its forces' derivatives."""

import math
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
# what the run's records, the coupling's readers and the checks read
RECORDS = ("generalized", "compression", "compression_rate", "in_contact", "tyre_force",
           "pins", "pins_v", "seats", "seats_v", "wheels", "wheels_v", "idler", "hull",
           "ground_load", "tooth_gap", "drive_torque")
FACTORS = ((1.0, 0.0), (0.25, 250.0))  # exudyn's (factor, factor_t) for K and C


def _vehicle(native_fmus):
    from vehicle.course import Bump
    from vehicle.model import Vehicle

    return Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)


@pytest.fixture(scope="module")
def linear_vehicle(native_fmus):
    """The vehicle with linear Kelvin elements in place of the FMUs (model.Linear, as
    tracked_vehicle.py --linear builds it), laid out at 3 m/s: its tyres' load moves with
    the compression's rate (c about 3.6e4 N.s/m a half-wheel)."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.model import Linear, Vehicle, static_points

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    statics = static_points(fmu_dir)
    return Vehicle(Bump(3.0), 3.0, fmu_dir, linear=Linear(statics, fmu_dir), statics=statics)


def _both_kernels(contacts, q, qd):
    """{kernel: {record: value}} at (q, qd), the Jacobian at each of FACTORS included."""
    values = {}
    for kernel in ("numpy", "compiled"):
        contacts.use(kernel)
        contacts._update(0.0, q, qd)
        got = {name: np.array(getattr(contacts, name), dtype=float) for name in RECORDS}
        got["tension_joints"] = np.array(contacts.tension_joints(), dtype=float)
        for factor, factor_t in FACTORS:
            got[f"jacobian {factor} {factor_t}"] = contacts._jacobian(0.0, q, qd, factor,
                                                                      factor_t)
            # the triplets themselves, in exudyn's order: its sums come out the same
            got[f"triplets {factor} {factor_t}"] = contacts._triplet_rows(factor,
                                                                          factor_t).copy()
        values[kernel] = got
    return values


def _coverage(contacts, seen):
    """Marks which branches of each contact the numpy kernel's last evaluation reached."""
    from vehicle import layout as lay
    from vehicle.contacts import CONTACT_ONSET
    from vehicle.model import ENGAGEMENT_RAMP

    depth = contacts.v.course.height(contacts.pins[:, 0]) - (contacts.pins[:, 1]
                                                             - lay.LINK_OUTER)
    seen["ground onset"] |= np.any((depth > 0.0) & (depth < CONTACT_ONSET))
    seen["ground full"] |= np.any(depth > CONTACT_ONSET)
    theta = contacts.hull[2]
    c, s = math.cos(theta), math.sin(theta)
    turn = np.array([[c, -s], [s, c]])
    centre = contacts.hull[:2] + turn @ contacts.sprocket_local
    relative = contacts.pins - centre
    into = (np.arctan2(relative[:, 1], relative[:, 0]) - theta - contacts.wrap_start) % (
        2 * math.pi)
    near = np.hypot(*relative.T) < lay.SPROCKET_PITCH_RADIUS + 0.08
    ramp = near & ((into < ENGAGEMENT_RAMP) | ((into > contacts.wrap_sweep - ENGAGEMENT_RAMP)
                                                & (into < contacts.wrap_sweep)))
    seen["sprocket ramp"] |= np.any(ramp)
    seen["sprocket held"] |= np.any(near & (into > ENGAGEMENT_RAMP)
                                    & (into < contacts.wrap_sweep - ENGAGEMENT_RAMP))
    roller = contacts.hull[:2] + turn @ contacts.roller_local
    seen["idler"] |= np.any(np.hypot(*(contacts.pins - contacts.idler).T)
                            < lay.IDLER_PIN_RADIUS)
    seen["roller"] |= np.any(np.hypot(*(contacts.pins - roller).T) < lay.ROLLER_PIN_RADIUS)
    seen["wheel on two links"] |= np.any(np.bincount(contacts.pair_wheel) >= 2)


def _states(contacts, q0, qd0):
    """The states compared: the laid-out vehicle at rest and with its track running; every
    coordinate jostled (1 mm, 1 mrad) with random velocities; the track's ground run
    lifted and pressed by up to a millimetre (pins entering the ground); the hull pitched
    about the sprocket's centre (pins moved into the engagement ramps at the wrap's
    ends); a wheel over a joint bent 14 deg (a convex joint, as on a bump's crest)."""
    rng = np.random.default_rng(29)
    yield q0, np.zeros_like(q0)
    yield q0, qd0
    for _ in range(2):
        yield q0 + rng.normal(0.0, 1e-3, q0.shape), qd0 + rng.normal(0.0, 0.5, q0.shape)
    state = contacts.reference + q0.reshape(-1, 3)
    links = np.arange(contacts.link0, len(state))
    ground_run = links[state[links, 1] < 0.1]
    lifted = state.copy()
    lifted[ground_run, 1] += rng.uniform(-1e-3, 5e-4, len(ground_run))
    yield (lifted - contacts.reference).ravel(), qd0
    for pitch in (-0.15, -0.08, 0.05, 0.12):
        pitched = state.copy()
        theta = state[0, 2] + pitch

        def turned(angle, r):
            return np.array([math.cos(angle) * r[0] - math.sin(angle) * r[1],
                             math.sin(angle) * r[0] + math.cos(angle) * r[1]])

        centre = state[0, :2] + turned(state[0, 2], contacts.sprocket_local)
        pitched[0, :2], pitched[0, 2] = centre - turned(theta, contacts.sprocket_local), theta
        yield (pitched - contacts.reference).ravel(), qd0
    # a wheel over a convex joint (tests/test_vehicle.py builds the same)
    contacts.use("numpy")
    contacts._update(0.0, q0, qd0)
    wheel = 2
    on_ground = np.flatnonzero(contacts.pins[:, 1] < 0.1)
    joint = on_ground[np.argmin(np.abs(contacts.pins[on_ground, 0] - contacts.wheels[wheel, 0]))]
    bent = state.copy()
    for link, seat, turn in ((joint - 1, 1, math.radians(7.0)), (joint, 0, -math.radians(7.0))):
        body = contacts.link0 + link
        pivot = contacts.seats[link, seat].copy()
        c, s = math.cos(turn), math.sin(turn)
        r = bent[body, :2] - pivot
        bent[body] = [pivot[0] + c * r[0] - s * r[1], pivot[1] + s * r[0] + c * r[1],
                      bent[body, 2] + turn]
    bent[1 + wheel, :2] += contacts.pins[joint] + [0.0, 0.3] - contacts.wheels[wheel]
    yield (bent - contacts.reference).ravel(), qd0


def _compare(values):
    """The compiled kernel's values against the numpy kernel's, to 1e-12 of each one's
    largest magnitude; whether all were the same bits."""
    identical = True
    for name, expected in values["numpy"].items():
        got = values["compiled"][name]
        assert got.shape == expected.shape, name
        finite = np.isfinite(expected)
        assert np.array_equal(finite, np.isfinite(got)), name
        scale = np.max(np.abs(expected[finite]), initial=0.0)
        assert np.max(np.abs(got[finite] - expected[finite]), initial=0.0) <= 1e-12 * scale, \
            name
        identical &= np.array_equal(got, expected)
    return identical


def _start_state(vehicle):
    """The object's coordinates at the vehicle's current state and its initial rates."""
    import exudyn as exu

    data, index = vehicle.mbs.systemData, vehicle.contacts.system_index
    return (np.array(data.GetODE2Coordinates(exu.ConfigurationType.Current))[index],
            np.array(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))[index])


@pytest.mark.parametrize("model, settling", [("FMUs", True), ("FMUs", False),
                                             ("linear", False)])
def test_the_c_kernel_gives_the_numpy_kernels_numbers(native_fmus, request, model, settling):
    """At each state of _states, settling (its damping springs) and running (the tyres'
    FMU laws, or the linear vehicle's damped Kelvin tyres): the C kernel's generalized
    forces, the records the run and the checks read and the Jacobian (at two of exudyn's
    factor pairs) equal the numpy kernel's to 1e-12 of each one's largest magnitude (they
    are the same bits on this machine; other builds of numpy or libm may differ in the
    last bits); and the states reach every contact's branches."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    vehicle = (_vehicle(native_fmus) if model == "FMUs"
               else request.getfixturevalue("linear_vehicle"))
    try:
        contacts = vehicle.contacts
        assert contacts.kernel == "compiled"  # the default where gcc is found
        vehicle.settling = settling
        if not settling:
            vehicle.coupling.start(0.0)  # the FMUs' load laws
        data = vehicle.mbs.systemData
        index = contacts.system_index
        q0 = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Current))[index]
        qd0 = np.array(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))[index]
        seen = dict.fromkeys(("ground onset", "ground full", "sprocket ramp", "sprocket held",
                              "idler", "roller", "wheel on two links"), False)
        identical = True
        for q, qd in list(_states(contacts, q0, qd0)):
            values = _both_kernels(contacts, q, qd)
            contacts.use("numpy")
            contacts._update(0.0, q, qd)
            _coverage(contacts, seen)
            identical &= _compare(values)
        assert all(seen.values()), seen
        print(f"bit-identical: {identical}")
        assert np.any(values["numpy"]["generalized"] != 0.0)
    finally:
        vehicle.coupling.free()


def test_the_linear_vehicles_tyre_damping_is_in_the_contacts_jacobian(linear_vehicle):
    """The linear vehicle's contacts on both kernels, at the laid-out state with the
    track running and with every coordinate jostled (0.1 mm, 0.1 mrad; 0.1 m/s, rad/s),
    the tyres in contact (five or six loaded) and their compressions changing: the
    Jacobian's velocity part (factor_t: the damped Kelvin tyres', the penalty contacts')
    equals minus the central differences of the generalized forces by the velocities to
    1e-8 of its largest entry (the forces are linear in them); at rest its position part
    (factor) to 1 %, as the FMU vehicle's (tests/test_vehicle.py). In motion the position
    part leaves out the rate's derivative by the coordinates (as it leaves out each
    link's term's second derivatives)."""
    from test_vehicle import _central_differences

    contacts = linear_vehicle.contacts
    q0, qd0 = _start_state(linear_vehicle)
    rng = np.random.default_rng(11)
    jostled = (q0 + rng.normal(0.0, 1e-4, q0.shape), qd0 + rng.normal(0.0, 0.1, q0.shape))
    for kernel in ("numpy", "compiled"):
        contacts.use(kernel)
        for q, qd in ((q0, qd0), jostled):
            contacts._update(0.0, q, qd)
            assert np.all(contacts.in_contact) and np.sum(contacts.tyre_force > 0.0) >= 5
            assert np.any(contacts.compression_rate != 0.0)
            analytic = contacts._jacobian(0.0, q, qd, 0.0, 1.0)
            numeric = _central_differences(contacts, q, qd, 1e-6, by_velocity=True)
            assert np.max(np.abs(analytic - numeric)) < 1e-8 * np.max(np.abs(numeric)), kernel
            rest = np.zeros_like(qd)
            analytic = contacts._jacobian(0.0, q, rest, 1.0, 0.0)
            numeric = _central_differences(contacts, q, rest, 1e-8)
            assert np.max(np.abs(analytic - numeric)) < 0.01 * np.max(np.abs(numeric)), kernel


def test_the_c_kernel_calls_the_banks_laws_as_the_vehicle_does(native_fmus):
    """On the compiled path the C kernel evaluates the tyres' loads itself, calling the
    bank's laws in its one call per evaluation: at each state of _states its forces,
    records and Jacobian equal the numpy kernel's, which takes the loads from
    Vehicle.tyre_loads (Bank.law_loads), to 1e-12 (the same bits on this machine); the
    tyres carry load."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    vehicle = _vehicle(native_fmus)
    vehicle.prepare()
    bank = vehicle.compiled_path.bank
    try:
        bank.start(0.0, *vehicle.compiled_path.initial_state())
        bank.begin_step(1e-3)  # the tyres' first laws
        vehicle.bank = bank
        contacts = vehicle.contacts
        q0, qd0 = _start_state(vehicle)
        identical, loaded = True, False
        for q, qd in list(_states(contacts, q0, qd0)):
            values = _both_kernels(contacts, q, qd)
            identical &= _compare(values)
            loaded |= bool(np.any(values["compiled"]["tyre_force"] > 1e3))
        assert contacts._compiled._bank is bank  # the one call took the bank's laws
        assert loaded
        print(f"bit-identical: {identical}")
    finally:
        vehicle.bank = None
        bank.free()


def test_the_c_kernels_records_are_its_last_evaluations(native_fmus):
    """The C kernel's results are read from its memory where they are first asked for
    after an evaluation: after one that was read and one that was not, the records are
    the second's (the numpy kernel's at that state); the generalized forces handed out
    are each evaluation's own arrays (a caller may keep them)."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    vehicle = _vehicle(native_fmus)
    try:
        vehicle.settling = True
        contacts = vehicle.contacts
        q0, qd0 = _start_state(vehicle)
        q1 = q0 + np.random.default_rng(5).normal(0.0, 1e-3, q0.shape)
        contacts.use("numpy")
        contacts._update(0.0, q1, qd0)
        expected = {name: np.array(getattr(contacts, name), dtype=float) for name in RECORDS}
        contacts.use("compiled")
        first = contacts._generalized(0.0, list(q0), list(qd0))  # lists, as exudyn's
        read = contacts.compression.copy()
        second = contacts._generalized(0.0, list(q1), list(qd0))
        assert not np.array_equal(read, contacts.compression)
        for name in RECORDS:
            assert np.array_equal(np.array(getattr(contacts, name), dtype=float),
                                  expected[name]), name
        assert np.array_equal(second, expected["generalized"])
        assert not np.array_equal(first, second)  # the first kept its values
    finally:
        vehicle.coupling.free()


def test_the_c_kernel_evaluates_the_courses_as_course_py_does(native_fmus):
    """The C kernel's course heights (contacts_course.c) under links on the ground equal
    course.py's heights to 1e-12 of their largest (the same bits on this machine) for the
    flat ground, the bump, the sine course and random roads, over the flat start and the
    course, and again after a course's attribute is set anew; a course of another class
    gives its heights from Python."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump, Course, RandomRoad, Sine

    class Ramp(Course):
        def height(self, x):
            return 0.01 * np.asarray(x, dtype=float)

    vehicle = _vehicle(native_fmus)
    try:
        kernel = vehicle.contacts._compiled
        rng = np.random.default_rng(8)
        moved = Bump(3.0, 0.2, 0.5)
        courses = [Course(3.0), Bump(3.0), Sine(3.0), RandomRoad(3.0), RandomRoad(3.0, "E"),
                   moved, moved, Ramp(3.0)]
        identical = True
        for i, course in enumerate(courses):
            if i == 6:
                moved.start = 2.5  # set anew after the kernel took the course
            for trial in range(20):
                # random points, and some over every course's features (4 to 6.1 m)
                x = np.sort(np.concatenate([rng.uniform(0.0, 12.0, len(kernel.views["pins"])
                                                        - 20), np.linspace(3.9, 6.1, 20)]))
                kernel.views["pins"][:, 0] = x
                kernel.views["pins"][:, 1] = 0.0  # the links' faces below every ceiling
                given = kernel._set_course(course)
                assert given == isinstance(course, Ramp)
                if not given:
                    kernel.lib.contacts_course_heights(kernel.handle)
                    got, expected = kernel.views["ground"].copy(), course.height(x)
                    assert np.any(expected != 0.0) or type(course) is Course
                    scale = np.max(np.abs(expected))
                    assert np.max(np.abs(got - expected)) <= 1e-12 * scale, type(course)
                    identical &= np.array_equal(got, expected)
        print(f"bit-identical: {identical}")
    finally:
        vehicle.coupling.free()


def test_a_short_run_gives_the_same_hull_accelerations_on_both_kernels(native_fmus):
    """20 host steps of 1 ms (3 m/s, bump course, the default coupling and path, in
    exudyn, whose Newton evaluates the vehicle's contacts' kernel) from the laid-out
    geometry on each kernel: the hull's vertical and pitch accelerations agree to 1e-9 of
    their range, and each run used its kernel."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from tracked_vehicle import simulate
    from vehicle.model import static_points

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    start = dict(statics=static_points(fmu_dir), settle_time=0.0, fmu_dir=fmu_dir)
    runs = {}
    for kernel in ("numpy", "compiled"):
        vehicle, runs[kernel], _, _ = simulate("bump", 3.0, 0.02, 1e-3, contacts=kernel,
                                               solver="exudyn", **start)
        assert vehicle.contacts.kernel == kernel
        assert vehicle.coupling.steps >= 20
    for key in ("hull_vertical_acceleration", "hull_pitch_acceleration"):
        numpy_run, compiled_run = runs["numpy"][key], runs["compiled"][key]
        assert numpy_run.shape == compiled_run.shape
        spread = np.ptp(numpy_run)
        assert spread > 0.0
        assert np.max(np.abs(compiled_run - numpy_run)) <= 1e-9 * spread, key


def test_without_a_compiler_the_contacts_say_so_and_use_numpy(native_fmus, monkeypatch,
                                                              tmp_path):
    """Compiling with no compiler found names the numpy kernel; the loader then warns
    once with that message and the vehicle's contacts take the numpy kernel."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from fmu_components.coupling import bank_build
    from vehicle import contacts_kernel

    platform = bank_build.platform_name()
    _, suffix, flags = bank_build.COMPILERS[platform]
    monkeypatch.setitem(bank_build.COMPILERS, platform, ("no-such-gcc", suffix, flags))
    with pytest.raises(bank_build.NoCompiler,
                       match=r"^no-such-gcc not found: the vehicle's contacts kernel .* "
                             r"numpy kernel \(--contacts numpy, "
                             r"or vehicle\.contacts\.use\('numpy'\)\)$"):
        contacts_kernel.LIBRARY.compile(platform, tmp_path)
    monkeypatch.setattr(contacts_kernel.LIBRARY, "built", lambda beside=None: None)
    # the loader's cache (bank_build.Library.load) emptied for this test
    monkeypatch.setattr(contacts_kernel.LIBRARY, "_loaded", None, raising=False)
    monkeypatch.delattr(contacts_kernel.LIBRARY, "_loaded")
    with pytest.warns(UserWarning, match="no-such-gcc not found.*use their numpy kernel"):
        assert contacts_kernel.library() is None
    assert contacts_kernel.library() is None  # once: no second warning, no second try
    vehicle = _vehicle(native_fmus)
    try:
        assert vehicle.contacts.kernel == "numpy"
        vehicle.contacts.evaluate(0.0)
        assert np.all(vehicle.contacts.in_contact)
        with pytest.raises(ValueError, match="'compiled' where gcc is"):
            vehicle.contacts.use("compiled")
    finally:
        vehicle.coupling.free()


def _moved_to_reach(contacts, q, body, centre, reach, beyond):
    """q with `body` (the hull, or the idler's crank) shifted straight away from the pin
    nearest `centre(contacts)` (evaluated at q by the numpy kernel), so that this pin
    lies `beyond` past `reach` of the centre (inside it where negative); the pin, and its
    distance from the centre there."""
    contacts.use("numpy")
    contacts._update(0.0, q, np.zeros_like(q))
    rel = contacts.pins - centre(contacts)
    j = np.argmin(np.hypot(*rel.T))
    distance = math.hypot(*rel[j])
    moved = q.reshape(-1, 3).copy()
    moved[body, :2] -= rel[j] / distance * (reach + beyond - distance)
    moved = moved.ravel()
    contacts._update(0.0, moved, np.zeros_like(q))
    return moved, j, math.hypot(*(contacts.pins[j] - centre(contacts)))


def test_the_c_kernels_reach_bounds_skip_no_pin_in_reach(native_fmus):
    """The C kernel leaves out the sprocket's teeth, the idler's and the roller's contact
    for pins surely beyond their reach (a cheap bound on the squared distance, 1e-9 of
    it to spare): with a pin put just inside a reach (1e-6 m), just beyond it within the
    bound's margin (1e-11 m: the full computation) and past it (1e-9 m: left out), its
    forces, records and Jacobian equal the numpy kernel's (which computes every pin) to
    1e-12 of their largest magnitude, and the pin's distance is where it was put; just
    inside the sprocket's reach the teeth hold the pin (the wrap's middle)."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import layout as lay

    vehicle = _vehicle(native_fmus)
    try:
        contacts = vehicle.contacts
        vehicle.coupling.start(0.0)
        q0 = np.array(vehicle.mbs.systemData.GetODE2Coordinates(
            exu.ConfigurationType.Current))[contacts.system_index]

        def turned(r):
            theta = contacts.hull[2]
            return np.array([math.cos(theta) * r[0] - math.sin(theta) * r[1],
                             math.sin(theta) * r[0] + math.cos(theta) * r[1]])

        reaches = {  # body moved, centre, reach
            "sprocket": (0, lambda k: k.hull[:2] + turned(k.sprocket_local),
                         lay.SPROCKET_PITCH_RADIUS + 0.08),
            "idler": (contacts.link0 - 1, lambda k: k.idler, lay.IDLER_PIN_RADIUS),
            "roller": (0, lambda k: k.hull[:2] + turned(k.roller_local),
                       lay.ROLLER_PIN_RADIUS)}
        for name, (body, centre, reach) in reaches.items():
            for beyond in (-1e-6, 1e-11, 1e-9):
                q, j, distance = _moved_to_reach(contacts, q0, body, centre, reach, beyond)
                assert abs(distance - (reach + beyond)) < 1e-12, (name, beyond)
                held = contacts.tooth_gap[j]
                _compare(_both_kernels(contacts, q, np.zeros_like(q)))
                if name == "sprocket":
                    assert (held > 0.0) == (beyond < 0.0), beyond
    finally:
        vehicle.coupling.free()


def _faces_at(ceiling, outer):
    """Pin heights y whose ground face y - outer (as both kernels compute it) is the last
    at or below `ceiling` and the first above it."""
    y = ceiling + outer
    while y - outer > ceiling:
        y = np.nextafter(y, -np.inf)
    while np.nextafter(y, np.inf) - outer <= ceiling:
        y = np.nextafter(y, np.inf)
    return y, np.nextafter(y, np.inf)


def test_the_courses_heights_are_left_out_only_above_their_ceiling(native_fmus):
    """A course's ceiling (course.py's Course.ceiling) is above every height of it, sampled
    every 2 mm over 100 m (the bump, the sine, random roads of class C and E); under a
    link whose ground face is at the last height at or below the ceiling both kernels give
    the course's height there (course.py's height), under one whose face is the next
    float up they give the ceiling, not the height, where the height differs from it;
    and on a random road under the whole vehicle (its ground run in it, its top run above
    the ceiling) the C kernel's forces, records and Jacobian equal the numpy kernel's."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import layout as lay
    from vehicle.course import Bump, RandomRoad, Sine

    vehicle = _vehicle(native_fmus)
    try:
        kernel = vehicle.contacts._compiled
        x = np.linspace(3.5, 103.5, 50_001)
        pins = kernel.views["pins"]
        for course in (Bump(3.0), Sine(3.0), RandomRoad(3.0), RandomRoad(3.0, "E")):
            heights, ceiling = course.height(x), course.ceiling()
            assert np.max(heights) < ceiling, type(course)
            at, above = _faces_at(ceiling, lay.LINK_OUTER)
            assert at - lay.LINK_OUTER <= ceiling < above - lay.LINK_OUTER
            # the pins in pairs over the course's features, one at, one above the ceiling
            spots = np.linspace(4.1, 4.9, len(pins) // 2)
            pins[:, 0], pins[:, 1] = np.repeat(spots, 2), np.tile([at, above], len(spots))
            kernel._set_course(course)
            kernel.lib.contacts_course_heights(kernel.handle)
            got = kernel.views["ground"].copy()
            expected = course.under(pins[:, 0], pins[:, 1] - lay.LINK_OUTER)
            assert np.array_equal(got, expected), type(course)
            assert np.array_equal(expected[0::2], course.height(spots)), type(course)
            assert np.all(expected[1::2] == ceiling)
            assert np.all(course.height(spots) < ceiling)
        # the whole vehicle on a random road from 10 m behind it
        vehicle.course = RandomRoad(-10.0)
        vehicle.coupling.start(0.0)
        q0 = np.array(vehicle.mbs.systemData.GetODE2Coordinates(
            exu.ConfigurationType.Current))[vehicle.contacts.system_index]
        contacts = vehicle.contacts
        values = _both_kernels(contacts, q0, np.zeros_like(q0))
        face = contacts.pins[:, 1] - lay.LINK_OUTER
        above = face > vehicle.course.ceiling()
        assert 0 < np.sum(above) < len(face)
        assert np.any(values["numpy"]["ground_load"] > 0.0)
        _compare(values)
    finally:
        vehicle.coupling.free()


def test_the_random_roads_recurrence_gives_its_sum_of_cosines():
    """RandomRoad.height turns e^(i u k) from term to term instead of evaluating each
    cosine: over 200 m of road (every 5 mm, the flat start and the fade-in included, class
    C and E) its heights equal the sum of the amplitudes times cos(u k + phase), each
    cosine evaluated and the terms summed exactly (math.fsum), less that sum at the start,
    to 1e-12 of the largest height."""
    from vehicle.course import RandomRoad

    for roughness in "CE":
        road = RandomRoad(3.0, roughness)
        x = np.linspace(3.5, 203.5, 40_001)
        u = x - road.front - road.start
        start = math.fsum(road.amplitude * np.cos(road.phase))
        expected = np.array([
            (math.fsum(road.amplitude * np.cos(p * road.k + road.phase)) - start)
            * min(p / road.fade, 1.0) if p > 0.0 else 0.0 for p in u])
        got = road.height(x)
        assert np.all(got[u <= 0.0] == 0.0)
        worst = np.max(np.abs(got - expected))
        print(f"class {roughness}: {worst:.2g} m, {worst / np.max(np.abs(expected)):.2g} of "
              f"the largest height")
        assert worst <= 1e-12 * np.max(np.abs(expected)), roughness
