"""The tracked vehicle's joints as one object (examples/vehicle/joints.py, docs/vehicle.md
The joints): at states that bend, slacken and compress joints, the kernel's generalized
forces are what exudyn's two connectors per joint apply, its Jacobian is the derivative of
those forces, its C kernel gives its numpy kernel's bits, and the coupling's readers read
the connectors' deflections."""

import math
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
FACTORS = ((1.0, 0.0), (0.0, 1.0), (0.25, 250.0))  # exudyn's (factor, factor_t)


@pytest.fixture(scope="module")
def vehicle(native_fmus):
    """The vehicle with its joints as connectors, the FMUs' laws started (5 m/s, laid out
    at the static point's design: every joint at the track's tension), and a joints
    kernel over the same links."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.joints import Joints
    from vehicle.model import Vehicle

    built = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent, joints="connectors")
    built.coupling.start(0.0)
    built.kernel = Joints(built)
    built.kernel.index()
    built.fmu_laws = {c: c.law for c in built.radial + built.torsion}
    yield built
    built.coupling.free()


def _laws(vehicle, joint):
    """Load laws that reach each branch: rate-dependent (a damper term: the Kelvin
    elements'), a clipped secant (LoadLaw's curvature beyond [K/2, 2K]) carrying a
    compression, and the FMUs' own (the relaxed start's) on the rest."""
    from fmu_components.coupling.law import LoadLaw

    for j, component in enumerate(vehicle.radial):
        x = float(joint[j, 2])
        if j % 3 == 0:
            component.law = lambda d, r, x0=x: 13e3 + 8e7 * (d - x0) + 2e4 * r
        elif j % 3 == 1:
            component.law = LoadLaw(x + 2e-5, -2e3, 8e7, 3 * 8e7 / 2e-5)
    for j, component in enumerate(vehicle.torsion):
        if j % 2:
            x = float(joint[j, 6])
            component.law = lambda d, r, x0=x: 10.0 + 300.0 * (d - x0) + 5.0 * r


def _states(vehicle):
    """(name, q, qd) of the whole system: the laid-out loop running at 5 m/s (its joints
    bent 33 deg round the sprocket and the idler); every coordinate jostled (0.1 mm,
    0.1 mrad) with random velocities; a joint on the top run pulled to 3 um, inside the
    radial bush's fade (5 um); the sprocket's joints bent 5 deg more."""
    import exudyn as exu

    data = vehicle.mbs.systemData
    q0 = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Initial))
    qd0 = np.array(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))
    rng = np.random.default_rng(29)
    yield "running", q0, qd0
    jostled = q0 + rng.normal(0.0, 1e-4, q0.shape), qd0 + rng.normal(0.0, 0.3, q0.shape)
    yield "jostled", *jostled
    kernel, index = vehicle.kernel, vehicle.kernel.system_index
    joint = kernel.kinematics(q0[index], qd0[index])[1]
    j = 40  # top run: link 40 moved onto link 39's front seat, 3 um short of it
    slack = jostled[0].copy()
    separation = kernel.kinematics(slack[index], qd0[index])[1][j, :2]
    x = index[3 * j:3 * j + 2]
    slack[x] -= separation * (1.0 - 3e-6 / np.hypot(*separation))
    yield "near slack", slack, jostled[1]
    bent = jostled[0].copy()
    sprocket = np.flatnonzero(joint[:, 6] > math.radians(20.0))
    assert len(sprocket) >= 4  # the wrap round the sprocket and the idler
    bent[index[3 * sprocket + 2]] += math.radians(5.0)
    yield "bent", bent, jostled[1]


def _connector_forces(vehicle, q, qd):
    """What the 160 connectors apply at (q, qd): the system's ODE2 right-hand side with
    them less without them, on the links' coordinates."""
    import exudyn as exu

    mbs, data = vehicle.mbs, vehicle.mbs.systemData
    settings = exu.SimulationSettings()
    settings.solution.file.write = False
    solver = exu.MainSolverImplicitSecondOrder()
    solver.InitializeSolver(mbs, settings)
    connectors = vehicle.radial_connectors + [c for c, _ in vehicle.torsion_connectors]
    sides = []
    for active in (True, False):
        for connector in connectors:
            mbs.SetObjectParameter(connector, "activeConnector", active)
        data.SetODE2Coordinates(q, exu.ConfigurationType.Current)
        data.SetODE2Coordinates_t(qd, exu.ConfigurationType.Current)
        solver.ComputeODE2RHS(mbs)
        sides.append(np.array(solver.GetSystemResidual()))
    for connector in connectors:
        mbs.SetObjectParameter(connector, "activeConnector", True)
    return (sides[0] - sides[1])[vehicle.kernel.system_index]


def _dense(triplets, size):
    matrix = np.zeros((size, size))
    np.add.at(matrix, (triplets[:, 0].astype(int), triplets[:, 1].astype(int)), triplets[:, 2])
    return matrix


def test_the_kernels_forces_are_what_the_connectors_apply(vehicle):
    """At each state, with the FMUs' laws and with laws that reach every branch, the
    kernel's generalized forces equal the connectors' (exudyn's own geometry and force
    functions) within 1e-9 of their largest; the near-slack joint is inside the fade."""
    kernel, index = vehicle.kernel, vehicle.kernel.system_index
    for laws in ("fmus", "branches"):
        for name, q, qd in _states(vehicle):
            if laws == "branches":
                _laws(vehicle, kernel.kinematics(q[index], qd[index])[1])
            else:
                for component, law in vehicle.fmu_laws.items():
                    component.law = law
            expected = _connector_forces(vehicle, q, qd)
            for which in ("numpy", "compiled"):
                kernel.use(which)
                _, joint, _, _, got = kernel.evaluate(q[index], qd[index])
                scale = np.max(np.abs(expected))
                assert scale > 5e3, name  # the tension's resultant round the wheels
                assert np.max(np.abs(got.ravel() - expected)) <= 1e-9 * scale, (laws, name, which)
            if name == "near slack":
                assert 0.0 < joint[40, 2] < 5e-6 and abs(joint[40, 2] - 3e-6) < 1e-9


def test_the_kernels_jacobian_is_the_derivative_of_its_forces(vehicle):
    """The analytic stiffness and damping (the laws' slopes, the fade's, the seats' line
    turning with the links, the damper terms) against central differences of the
    kernel's forces by the coordinates and the velocities: within 1e-6 of the largest
    entry, at each state."""
    kernel, index = vehicle.kernel, vehicle.kernel.system_index
    kernel.use("numpy")
    for name, q, qd in _states(vehicle):
        q, qd = q[index], qd[index]
        _laws(vehicle, kernel.kinematics(q, qd)[1])
        size = len(q)
        for factor, factor_t, h in ((1.0, 0.0, 1e-8), (0.0, 1.0, 1e-4)):
            analytic = _dense(kernel.triplets(q, qd, factor, factor_t), size)
            numeric = np.zeros((size, size))
            for i in range(size):
                step = np.zeros(size)
                step[i] = h
                if factor:
                    plus, minus = kernel.generalized(q + step, qd), kernel.generalized(q - step, qd)
                else:
                    plus, minus = kernel.generalized(q, qd + step), kernel.generalized(q, qd - step)
                numeric[:, i] = -(plus - minus) / (2 * h)
            worst = np.max(np.abs(analytic - numeric))
            assert worst <= 1e-6 * np.max(np.abs(numeric)), (name, factor, worst)


def test_the_c_kernel_gives_the_numpy_kernels_bits(vehicle):
    """joints.c against the numpy kernel it follows operation for operation: kinematics,
    the forces applied, the generalized forces and the triplets at each state (1e-13 of
    each quantity's largest: another libm may round cos or sin differently; on this
    machine they are the same bits)."""
    kernel, index = vehicle.kernel, vehicle.kernel.system_index
    for name, q, qd in _states(vehicle):
        q, qd = q[index], qd[index]
        _laws(vehicle, kernel.kinematics(q, qd)[1])
        got = {}
        for which in ("numpy", "compiled"):
            kernel.use(which)
            got[which] = list(kernel.evaluate(q, qd))
            got[which] += [kernel.triplets(q, qd, *factors) for factors in FACTORS]
        for numpy_value, c_value in zip(got["numpy"], got["compiled"]):
            scale = max(np.max(np.abs(numpy_value)), 1e-300)
            assert np.max(np.abs(numpy_value - c_value)) <= 1e-13 * scale, name


def test_a_radial_bush_never_pushes_its_seats_apart(vehicle):
    """A radial law's load below zero is not applied (model.radial_pull), its slopes with
    it, by either kernel; at or above zero the law's load is applied as it was."""
    from vehicle.joints import forces
    from vehicle.model import radial_fade, radial_pull

    kernel, index = vehicle.kernel, vehicle.kernel.system_index
    name, q, qd = next(_states(vehicle))
    link, joint = kernel.kinematics(q[index], qd[index])
    law = np.zeros((len(joint), 6))
    law[:, 0] = np.where(np.arange(len(joint)) % 2, -2e3, 2e3)  # pushing, pulling
    law[:, 1], law[:, 2], law[:, 3] = 8e7, 2e4, 10.0
    kernel.use("compiled")
    kernel._compiled.kinematics(q[index].reshape(-1, 3), qd[index].reshape(-1, 3))
    for effort in (forces(link, joint, law)[0], kernel._compiled.forces(law)[0]):
        pushing = law[:, 0] < 0.0
        assert np.all(effort[pushing] == 0.0)
        share = np.array([radial_fade(d) for d in joint[~pushing, 2]])
        assert np.array_equal(effort[~pushing, 0], 2e3 * share)
        assert np.all(effort[~pushing, 1] > 0.0) and np.all(effort[~pushing, 2] > 0.0)
    assert radial_pull(-2e3) == 0.0 and radial_pull(2e3) == 2e3
    assert math.isnan(radial_pull(math.nan))


def test_the_readers_read_the_connectors_deflections(vehicle):
    """The coupling's readers with the kernel (seat distance and its rate, relative angle
    plus offset and its rate) read what the connectors' readers read, at each state."""
    import exudyn as exu

    kernel, data = vehicle.kernel, vehicle.mbs.systemData
    readers = dict(vehicle.coupling.entries)
    for name, q, qd in _states(vehicle):
        data.SetODE2Coordinates(q, exu.ConfigurationType.Current)
        data.SetODE2Coordinates_t(qd, exu.ConfigurationType.Current)
        for j in range(vehicle.links):
            for kind, component in (("radial", vehicle.radial[j]),
                                    ("torsion", vehicle.torsion[j])):
                expected = readers[component]()
                assert kernel.state(j, kind) == pytest.approx(expected, rel=1e-12, abs=1e-12), (
                    name, j, kind)


def test_a_short_run_takes_the_same_steps_on_both_kernels(native_fmus):
    """Three host steps of 1 ms from the laid-out loop at 5 m/s on the compiled path, the
    joints' object on its C kernel and on its numpy kernel: the same histories (the same
    bits on this machine; 1e-9 of each history's range asked: another libm may round
    cos or sin differently)."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.model import Vehicle

    runs, steps = {}, {}
    for which in ("numpy", "compiled"):
        vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
        vehicle.joints.use(which)
        runs[which] = vehicle.run(0.003, 1e-3, settle=False)
        # 3 asked; exudyn may halve one in this start from the laid-out loop
        steps[which] = vehicle.coupling.steps
        assert vehicle.compiled and steps[which] >= 3
    assert steps["numpy"] == steps["compiled"]
    for key, value in runs["numpy"].items():
        if isinstance(value, np.ndarray) and value.dtype.kind == "f":
            span = max(np.ptp(value), 1e-300)
            assert np.max(np.abs(runs["compiled"][key] - value)) <= 1e-9 * span, key
    assert np.max(runs["compiled"]["bush_radial_force"][-1]) > 5e3  # the track's tension


def test_the_one_call_path_gives_the_three_call_paths_bits(native_fmus):
    """On the compiled path (the bank's laws, the C kernel) exudyn's force and Jacobian
    functions take one C call each (kinematics, the bank's laws called from C, forces):
    at each state, with the bank's relaxed laws and with laws set on a few rows (a
    clipped secant, a compression), their forces and triplets are the three-call path's
    (Joints.evaluate and Joints.triplets: kinematics, Bank.law_loads, forces) to the bit,
    in either order of the calls."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    import exudyn as exu
    from vehicle.course import Bump
    from vehicle.model import Vehicle

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
    joints = vehicle.joints
    if joints.kernel != "compiled":
        pytest.skip("the joints' C kernel does not build here")
    vehicle.prepare()
    compiled = vehicle.compiled_path
    try:
        compiled.bank.start(0.0, *compiled.initial_state())
        vehicle.bank = compiled.bank
        data = vehicle.mbs.systemData
        q0 = np.array(data.GetODE2Coordinates(exu.ConfigurationType.Initial))
        qd0 = np.array(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))
        index, rng = joints.system_index, np.random.default_rng(31)
        states = [(q0, qd0)] + [(q0 + rng.normal(0.0, 1e-4, q0.shape),
                                 qd0 + rng.normal(0.0, 0.3, q0.shape)) for _ in range(3)]
        for laws in ("relaxed", "set"):
            if laws == "set":
                joint = joints.kinematics(q0[index], qd0[index])[1]
                for j in (3, 40, 41):
                    row = compiled.radial_rows[j]
                    compiled.bank._set_law(row, joint[j, 2] + 2e-5, -2e3, 8e7, 1e13)
                compiled.bank._set_law(compiled.torsion_rows[5], joint[5, 6], 10.0, 300.0, 0.0)
            for q, qd in states:
                q, qd = list(q[index]), list(qd[index])  # as exudyn hands them
                three = joints.evaluate(np.array(q), np.array(qd))[-1].reshape(-1)
                expected = [joints.triplets(np.array(q), np.array(qd), *f) for f in FACTORS]
                assert joints.one_call() is not None
                for order in ("forces first", "jacobian first"):
                    if order == "forces first":
                        forces = joints.generalized(q, qd).copy()
                    got = [joints.jacobian(q, qd, *f).copy() for f in FACTORS]
                    if order == "jacobian first":
                        forces = joints.generalized(q, qd).copy()
                    assert np.array_equal(forces, three), (laws, order)
                    for e, g in zip(expected, got):
                        assert np.array_equal(e, g), (laws, order)
        assert np.max(np.abs(three)) > 5e3  # the track's tension
    finally:
        vehicle.bank = None
        compiled.bank.free()
