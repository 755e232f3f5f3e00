"""The vehicle's own solver core (examples/vehicle/alpha_solver.py, docs/vehicle.md "An own
solver"; its bordered band LU in test_vehicle_bordered_band.py): its generalized-alpha
step against exudyn's on the same small model (a chain of rigid bodies on springs, the first
pinned to the ground, a border body sprung to all) and against an independent scipy
solution, at second order; a step that does not converge says so and keeps its start."""

import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
alpha = pytest.importorskip("vehicle.alpha_solver")


# --- a small constrained system: a chain of rigid bodies ------------------------------------

class Chain:
    """`links` 2D rigid bodies (x, y, angle; reference point at the centre of mass) in a
    row, neighbours joined by distance springs between their ends, the first pinned to the
    ground at its left end (a revolute joint: 2 multipliers), and a border body above
    sprung to every link's centre; gravity. Coordinates: each body's displacement from
    its reference, the links first."""

    def __init__(self, links=4):
        self.links = links
        self.bodies = links + 1
        self.nq, self.nm = 3 * self.bodies, 2
        self.half = 0.25  # a link's half length
        self.reference = np.array([[0.5 * (2 * i + 1) * self.half * 2.2, 0.0, 0.0]
                                   for i in range(links)] + [[0.6, 0.8, 0.0]])
        mass = [1.0 + 0.5 * i for i in range(links)] + [6.0]
        inertia = [m * (2 * self.half) ** 2 / 12 for m in mass[:-1]] + [0.4]
        self.masses = np.repeat(mass, 3)
        self.masses[2::3] = inertia
        self.gravity = -9.81
        # springs: (body a, local point a, body b, local point b, stiffness, damping)
        self.springs = [(i, (self.half, 0.0), i + 1, (-self.half, 0.0), 4e4, 40.0)
                        for i in range(links - 1)]
        self.springs += [(links, (0.1 * (i - links / 2), -0.1), i, (0.0, 0.0), 3e3 + 500 * i,
                          8.0) for i in range(links)]
        self.pin = (0, (-self.half, 0.0))  # body, local point; pinned where it starts
        self.lengths = [self._distance(self.reference, s) for s in self.springs]
        self.lengths = [0.95 * L for L in self.lengths]  # pretension
        self.ground = self._point(self.reference, *self.pin)

    # kinematics of a body's local point
    @staticmethod
    def _rotation(angle):
        c, s = np.cos(angle), np.sin(angle)
        return np.array([[c, -s], [s, c]])

    def _point(self, x, body, local):
        return x[body, :2] + self._rotation(x[body, 2]) @ local

    def _distance(self, x, spring):
        a, la, b, lb = spring[:4]
        return np.linalg.norm(self._point(x, b, lb) - self._point(x, a, la))

    def _arm(self, x, body, local):
        """d(point)/d(angle): the rotated local vector turned by 90 degrees."""
        r = self._rotation(x[body, 2]) @ local
        return np.array([-r[1], r[0]])

    def forces(self, t, q, v):
        """f at (t, q, v); q, v of shape (..., nq): the springs' forces on their bodies and
        gravity, every spring at once."""
        q, v = np.broadcast_arrays(q, v)
        x = self.reference + q.reshape(*q.shape[:-1], self.bodies, 3)
        xd = v.reshape(x.shape)
        a, local_a, b, local_b, k, d = (np.array(c) for c in zip(*self.springs))

        def end(body, local):
            angle = x[..., body, 2]
            c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
            r = np.stack([c[..., 0] * local[:, 0] - s[..., 0] * local[:, 1],
                          s[..., 0] * local[:, 0] + c[..., 0] * local[:, 1]], axis=-1)
            arm = np.stack([-r[..., 1], r[..., 0]], axis=-1)  # d(point)/d(angle)
            velocity = xd[..., body, :2] + xd[..., body, 2:3] * arm
            return x[..., body, :2] + r, arm, velocity

        point_a, arm_a, velocity_a = end(a, local_a)
        point_b, arm_b, velocity_b = end(b, local_b)
        delta = point_b - point_a
        distance = np.linalg.norm(delta, axis=-1)
        n = delta / distance[..., None]
        rate = (n * (velocity_b - velocity_a)).sum(axis=-1)
        force = k * (distance - self.lengths) + d * rate  # tension pulls the ends together
        on_a = np.concatenate([n, (n * arm_a).sum(axis=-1, keepdims=True)], axis=-1)
        on_b = np.concatenate([n, (n * arm_b).sum(axis=-1, keepdims=True)], axis=-1)
        f = np.zeros(x.shape)
        f[..., 1] = self.masses[0::3] * self.gravity
        ends_a, ends_b = np.eye(self.bodies)[a], np.eye(self.bodies)[b]
        f += np.einsum("...sk,sj->...jk", force[..., None] * on_a, ends_a)
        f -= np.einsum("...sk,sj->...jk", force[..., None] * on_b, ends_b)
        return f.reshape(q.shape)

    def constraint(self, q):
        """g (the pin's point minus where it is pinned) and G = dg/dq as triplets."""
        x = self.reference + q.reshape(-1, 3)
        body, local = self.pin
        g = self._point(x, body, local) - self.ground
        arm = self._arm(x, body, local)
        rows = np.array([0, 1, 0, 1])
        cols = 3 * body + np.array([0, 1, 2, 2])
        return g, (rows, cols, np.array([1.0, 1.0, arm[0], arm[1]]))

    def constraint_curvature(self, q, v):
        """(G v)_q v: the pin point's acceleration at zero body acceleration."""
        x = self.reference + q.reshape(-1, 3)
        body, local = self.pin
        return -v[3 * body + 2] ** 2 * (self._rotation(x[body, 2]) @ np.asarray(local))

    def evaluate(self, t, q, v):
        g, G = self.constraint(q)
        return self.forces(t, q, v), g, G

    def jacobian(self, t, q, v, epsilon=1e-6):
        """K = -df/dq, D = -df/dv by central differences (only Newton's convergence rate
        depends on them), every perturbed state at once, as triplets."""
        e = epsilon * np.eye(self.nq)
        K = -(self.forces(t, q + e, v) - self.forces(t, q - e, v)).T / (2 * epsilon)
        D = -(self.forces(t, q, v + e) - self.forces(t, q, v - e)).T / (2 * epsilon)
        rows, cols = np.nonzero((K != 0) | (D != 0))
        return (rows, cols, K[rows, cols]), (rows, cols, D[rows, cols])

    def initial(self):
        """(q, v): displaced and moving, the pinned link turning about its pin (so that the
        initial accelerations need the constraint's curvature)."""
        q = np.zeros(self.nq)
        v = np.zeros(self.nq)
        q[3::3][:self.links - 1] = 0.01
        q[4::3][:self.links - 1] = -0.02 * np.arange(1, self.links)
        v[3:3 * self.links] = 0.3
        v[-2] = -0.5
        body, local = self.pin
        spin = 2.0
        v[3 * body + 2] = spin
        v[3 * body:3 * body + 2] = -spin * self._arm(self.reference + q.reshape(-1, 3), body,
                                                     local)
        return q, v

    def order(self):
        """The links' coordinates in the band (half bandwidth 5: neighbours' 6), the border
        body and the multipliers the border."""
        return np.arange(self.nq + self.nm), 3 * self.links, 5


def chain_solver(chain, half_bandwidth=None, masses=None, **settings):
    """The solver core over the chain (its order; another half bandwidth or masses where
    given)."""
    system = alpha.PythonSystem(chain.nq, chain.nm, chain.evaluate, chain.jacobian)
    order, n_band, w = chain.order()
    return alpha.AlphaSolver(system, chain.masses if masses is None else masses, chain.nm,
                             order, n_band, w if half_bandwidth is None else half_bandwidth,
                             alpha.Settings(**settings))


def own_history(chain, step, end_time, spectral_radius, **settings):
    """The solver core's coordinates at every step, (steps + 1, nq), and its iterations."""
    solver = chain_solver(chain, spectral_radius=spectral_radius, **settings)
    q, v = chain.initial()
    assert solver.initialize(0.0, q, v) == 0
    steps = round(end_time / step)
    history, iterations = [solver.state()[0]], []
    for k in range(1, steps + 1):
        status = solver.step(step, k * step)  # exudyn's time: step index times step
        assert status == 0, alpha.STATUS[status]
        history.append(solver.state()[0])
        iterations.append(solver.report()["iterations"])
    return np.array(history), iterations


def exudyn_history(chain, step, end_time, spectral_radius, modified_newton=False,
                   relative_tolerance=1e-8):
    """exudyn's generalized-alpha on the same model (its own bodies, springs and revolute
    joint): the coordinates at every step."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from exudyn.itemInterface import (LoadMassProportional, MarkerBodyMass,
                                      MarkerBodyPosition, NodeRigidBody2D,
                                      ObjectConnectorSpringDamper, ObjectGround,
                                      ObjectRigidBody2D, RevoluteJoint2D)
    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    q0, v0 = chain.initial()
    bodies = []
    for i in range(chain.bodies):
        node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=list(chain.reference[i]),
                                           initialCoordinates=list(q0[3 * i:3 * i + 3]),
                                           initialVelocities=list(v0[3 * i:3 * i + 3])))
        body = mbs.AddObject(ObjectRigidBody2D(nodeNumber=node, mass=chain.masses[3 * i],
                                               inertia=chain.masses[3 * i + 2]))
        mass = mbs.AddMarker(MarkerBodyMass(bodyNumber=body))
        mbs.AddLoad(LoadMassProportional(markerNumber=mass, loadVector=[0, chain.gravity, 0]))
        bodies.append(body)

    def marker(body, local):
        return mbs.AddMarker(MarkerBodyPosition(bodyNumber=bodies[body],
                                                localPosition=[*local, 0.0]))

    for (a, la, b, lb, k, d), length in zip(chain.springs, chain.lengths):
        mbs.AddObject(ObjectConnectorSpringDamper(markerNumbers=[marker(a, la), marker(b, lb)],
                                                  referenceLength=length, stiffness=k,
                                                  damping=d))
    ground = mbs.AddObject(ObjectGround())
    pinned = mbs.AddMarker(MarkerBodyPosition(bodyNumber=ground,
                                              localPosition=[*chain.ground, 0.0]))
    mbs.AddObject(RevoluteJoint2D(markerNumbers=[pinned, marker(*chain.pin)]))
    history = []

    def record(mbs, t):
        history.append(np.array(mbs.systemData.GetODE2Coordinates()))
        return True

    mbs.SetPostStepUserFunction(record)
    mbs.Assemble()
    settings = exu.SimulationSettings()
    ti = settings.timeIntegration
    ti.numberOfSteps = round(end_time / step)
    ti.endTime = end_time
    ti.generalizedAlpha.spectralRadius = spectral_radius
    ti.newton.useModifiedNewton = modified_newton
    ti.newton.relativeTolerance = relative_tolerance
    ti.verboseMode = 0
    settings.solution.file.write = False
    exu.SolveDynamic(mbs, settings)
    return np.array(history)  # the post-step function sees the initial state too


def reference_solution(chain, times):
    """An independent solution: the accelerations from [M G^T; G 0] [a; lambda] =
    [f; -(G v)_q v] (the constraint differentiated twice), integrated by scipy's DOP853 at
    tolerances far below the steps' errors; q at `times`."""
    integrate = pytest.importorskip("scipy.integrate")
    nq, nm = chain.nq, chain.nm
    mass = np.diag(chain.masses)

    def rates(t, y):
        q, v = y[:nq], y[nq:]
        _, (rows, cols, values) = chain.constraint(q)
        G = np.zeros((nm, nq))
        np.add.at(G, (rows, cols), values)
        system = np.block([[mass, G.T], [G, np.zeros((nm, nm))]])
        rhs = np.r_[chain.forces(t, q, v), -chain.constraint_curvature(q, v)]
        return np.r_[v, np.linalg.solve(system, rhs)[:nq]]

    q, v = chain.initial()
    solution = integrate.solve_ivp(rates, (0.0, times[-1]), np.r_[q, v], method="DOP853",
                                   t_eval=times, rtol=1e-12, atol=1e-13)
    assert solution.success
    return solution.y[:nq].T


# --- the step against exudyn's and against the reference --------------------------------------

@pytest.mark.parametrize("spectral_radius, relative_tolerance, modified_newton",
                         [(0.8, 1e-8, False), (0.8, 1e-10, False), (0.5, 1e-10, True)])
def test_the_step_is_exudyns_generalized_alpha(spectral_radius, relative_tolerance,
                                                modified_newton):
    """The same model stepped by exudyn and by the core at 2 ms: the same histories to
    Newton's tolerance (the difference follows the tolerance: another spectral radius or
    scheme differs by the method's error, 1e-3 here)."""
    chain = Chain()
    step, end_time = 2e-3, 0.2
    expected = exudyn_history(chain, step, end_time, spectral_radius, modified_newton,
                              relative_tolerance)
    own, _ = own_history(chain, step, end_time, spectral_radius,
                         relative_tolerance=relative_tolerance,
                         use_modified_newton=int(modified_newton))
    assert own.shape == expected.shape
    scale = np.ptp(expected, axis=0).max()
    assert np.abs(own - expected).max() <= 10 * relative_tolerance * scale


def test_the_step_converges_at_second_order_to_the_reference():
    """Against scipy's solution: the error falls at second order as the step halves."""
    chain = Chain()
    times = np.array([0.02, 0.04, 0.06, 0.08, 0.1])
    reference = reference_solution(chain, times)
    errors = []
    for step in (1e-3, 5e-4, 2.5e-4):
        history, _ = own_history(chain, step, times[-1], 0.8, relative_tolerance=1e-10)
        errors.append(np.abs(history[np.round(times / step).astype(int)] - reference).max())
    orders = np.log2(np.array(errors[:-1]) / errors[1:])
    assert np.all((orders > 1.8) & (orders < 2.3)), (errors, orders)


def test_a_step_solved_again_from_its_start_is_the_same_step():
    """restart: the state at the step's start again (a host's retry); repeat: the step
    solved again from its start, cold (the predictor: the same solution to the bit) or
    warm (Newton from the present solution: converged at once, within the tolerance)."""
    chain = Chain()
    solver = chain_solver(chain, relative_tolerance=1e-10)
    q, v = chain.initial()
    assert solver.initialize(0.0, q, v) == 0
    start = solver.state()
    assert solver.step(2e-3, 2e-3) == 0
    solved, iterations = solver.state(), solver.report()["iterations"]
    assert not np.array_equal(solved[0], start[0])
    solver.restart()
    for before, after in zip(start, solver.state()):
        np.testing.assert_array_equal(after, before)
    assert solver.step(2e-3, 2e-3) == 0
    assert solver.repeat(2e-3, 2e-3) == 0
    for first, again in zip(solved, solver.state()):
        np.testing.assert_array_equal(again, first)
    assert solver.repeat(2e-3, 2e-3, warm=True) == 0
    assert solver.report()["iterations"] < iterations
    for first, again in zip(solved, solver.state()):
        np.testing.assert_allclose(again, first, rtol=1e-7, atol=1e-9 * np.abs(first).max())


# --- what the step refuses ---------------------------------------------------------------------

def test_a_step_that_does_not_converge_returns_its_status_and_keeps_its_start():
    chain = Chain()
    solver = chain_solver(chain, max_iterations=1, relative_tolerance=1e-14)
    q, v = chain.initial()
    assert solver.initialize(0.0, q, v) == 0
    start = solver.state()
    assert alpha.STATUS[solver.step(2e-3, 2e-3)] == "not converged"
    assert solver.report()["iterations"] == 1
    for before, after in zip(start, solver.state()):
        np.testing.assert_array_equal(after, before)
    # the same step with Newton's iterations converges
    solver = chain_solver(chain)
    solver.initialize(0.0, q, v)
    assert solver.step(2e-3, 2e-3) == 0


def test_a_step_into_non_numbers_returns_its_status_never_a_nan_state():
    chain = Chain()
    evaluate = chain.evaluate

    def spoiled(t, q, v):
        f, g, G = evaluate(t, q, v)
        return f * (np.nan if t > 0.003 else 1.0), g, G

    chain.evaluate = spoiled
    solver = chain_solver(chain)
    q, v = chain.initial()
    solver.initialize(0.0, q, v)
    assert solver.step(2e-3, 2e-3) == 0
    assert alpha.STATUS[solver.step(2e-3, 4e-3)] == "not converged"
    assert all(np.isfinite(x).all() for x in solver.state())


def test_a_jacobian_entry_outside_the_pattern_is_named():
    """With half bandwidth 4, neighbouring links' angles (5 apart) do not fit."""
    chain = Chain()
    solver = chain_solver(chain, half_bandwidth=4)
    q, v = chain.initial()
    assert solver.initialize(0.0, q, v) == 0  # M and G alone fit
    assert alpha.STATUS[solver.step(2e-3, 2e-3)] == "entry outside the band and the border"
    report = solver.report()
    assert abs(report["bad_row"] - report["bad_col"]) == 5
    assert max(report["bad_row"], report["bad_col"]) < 3 * chain.links


def test_a_mass_that_is_not_positive_is_a_band_pivot_named():
    chain = Chain()
    masses = chain.masses.copy()
    masses[4] = -masses[4]
    solver = chain_solver(chain, masses=masses)
    q, v = chain.initial()
    assert alpha.STATUS[solver.initialize(0.0, q, v)] == "band pivot not positive"
    assert solver.report()["bad_row"] == 4


def test_a_failing_callback_returns_its_status_and_keeps_the_start():
    chain = Chain()
    evaluate = chain.evaluate

    def failing(t, q, v):
        if t > 0.003:
            raise ArithmeticError("the model cannot evaluate here")
        return evaluate(t, q, v)

    chain.evaluate = failing
    solver = chain_solver(chain)
    q, v = chain.initial()
    solver.initialize(0.0, q, v)
    assert solver.step(2e-3, 2e-3) == 0
    start = solver.state()
    assert alpha.STATUS[solver.step(2e-3, 4e-3)] == "callback failed"
    for before, after in zip(start, solver.state()):
        np.testing.assert_array_equal(after, before)


# --- the reuse policy: the Newton matrix kept -------------------------------------------------

REUSE = dict(reuse_jacobian=2, reuse_contractivity=0.1)


def exact_jacobian(chain, coefficients, h, t, q, v, lam, epsilon=1e-6):
    """d(scaled residual)/d(Newton's unknowns) at a step's solution, by central differences
    of the model's own functions (all its terms, the multipliers' d(G^T lambda)/dq among
    them): v and a move with q as Newton moves them (gamma', beta'), the multipliers'
    unknown is lambda beta h^2, the coordinate rows scaled by beta h^2."""
    c = coefficients
    scale = c["beta"] * h * h
    beta_prime = (1 - c["alpha_m"]) / (scale * (1 - c["alpha_f"]))
    gamma_prime = c["gamma"] / (h * c["beta"])

    def coordinate_rows(dq):
        g, (rows, cols, values) = chain.constraint(q + dq)
        G = np.zeros((chain.nm, chain.nq))
        np.add.at(G, (rows, cols), values)
        return (chain.masses * beta_prime * dq - chain.forces(t, q + dq, v + gamma_prime * dq)
                + G.T @ lam), G

    e = epsilon * np.eye(chain.nq)
    dR = np.array([coordinate_rows(e[i])[0] - coordinate_rows(-e[i])[0]
                   for i in range(chain.nq)]).T / (2 * epsilon)
    G = coordinate_rows(np.zeros(chain.nq))[1]
    J = np.block([[scale * dR, G.T], [G, np.zeros((chain.nm, chain.nm))]])
    return J, np.r_[np.full(chain.nq, scale), np.ones(chain.nm)]


@pytest.mark.parametrize("broyden", [0, 1])
def test_the_kept_matrix_converges_to_full_newtons_solution_within_the_tolerance(broyden):
    """The same step from the same start, on a matrix kept from the step before and with
    full Newton: each stops with a residual r, |r| <= tol = max(absolute, relative x first
    residual); linearized, J du = S (r_kept - r_full) (J the exact derivative of the scaled
    residual S r in Newton's unknowns u), so each coordinate's difference is at most
    |row_i of J^-1 S| (|r_kept| + |r_full|) <= |row_i of J^-1 S| (tol_kept + tol_full)
    (the rows' constraint part, about 3 here, makes the tolerance's bound loose: the
    constraints' residual is a length)."""
    chain = Chain()
    h, tolerance = 2e-3, 1e-8
    solver = chain_solver(chain, relative_tolerance=tolerance, reuse_broyden=broyden,
                          **REUSE)
    q, v = chain.initial()
    solver.initialize(0.0, q, v)
    for k in range(1, 21):
        assert solver.step(h, k * h) == 0
    assert solver.step(h, 21 * h) == 0
    kept, made = solver.state(), solver.trace()[1]
    assert made[0] == 0  # the step began on the last step's matrix
    report = solver.report()
    residuals = [report["residual"]]
    assert residuals[0] <= max(solver.settings.absolute_tolerance,
                               tolerance * report["initial_residual"])
    solver.restart()
    solver.configure(reuse_jacobian=0)
    assert solver.step(h, 21 * h) == 0
    full, report = solver.state(), solver.report()
    assert np.all(solver.trace()[1] == 1)  # full Newton: a new matrix every iteration
    residuals.append(report["residual"])
    J, S = exact_jacobian(chain, solver.coefficients(), h, 21 * h, *full[:2], full[3])
    rows = np.linalg.norm((np.linalg.inv(J) * S)[:chain.nq], axis=1)
    bound = rows * sum(residuals)
    difference = np.abs(kept[0] - full[0])
    assert 0.0 < difference.max() and np.all(difference <= bound), difference / bound
    solver.restart()  # the bound is far below the step's motion
    assert bound.max() < 1e-2 * np.abs(full[0] - solver.state()[0]).max()


@pytest.mark.parametrize("broyden", [0, 1])
def test_an_iteration_that_contracts_slowly_makes_a_new_matrix(broyden):
    """Over 40 steps on a kept matrix (the contractivity set so that both happen): after
    every iteration whose residual fell by a ratio worse than the contractivity (or rose:
    that iterate undone), the next iteration makes a new matrix; after one that fell
    faster, it keeps the matrix unless that pace would not converge within the
    iterations left."""
    chain = Chain()
    h = 2e-3
    solver = chain_solver(chain, relative_tolerance=1e-10, reuse_broyden=broyden, **REUSE)
    q, v = chain.initial()
    solver.initialize(0.0, q, v)
    slow = kept = 0
    for k in range(1, 41):
        assert solver.step(h, k * h) == 0
        norms, made = solver.trace()
        report = solver.report()
        target = max(solver.settings.absolute_tolerance, 1e-10 * report["initial_residual"])
        last = report["initial_residual"]
        for i in range(len(norms) - 1):
            ratio = norms[i] / last
            if ratio > 1.0 and not made[i]:  # undone: the next from the iterate before
                assert made[i + 1]
                slow += 1
                continue
            if ratio > REUSE["reuse_contractivity"]:
                assert made[i + 1], (k, i, ratio)
                slow += 1
            else:
                needed = np.log(target / norms[i]) / np.log(ratio)
                left = solver.settings.max_iterations - (i + 1)
                assert made[i + 1] == (needed > left), (k, i, ratio)
                kept += not made[i + 1]
            last = norms[i]
    assert slow > 0 and kept > 0


def test_another_step_or_a_restart_makes_a_new_matrix():
    """A kept matrix serves the steps of its own h only; a restart (a retry) or a step
    of another h makes a new one at its first iteration, as does every step's first pass
    when the matrix is kept over a step's passes alone (reuse_jacobian 1)."""
    chain = Chain()
    h = 2e-3
    solver = chain_solver(chain, **REUSE)
    q, v = chain.initial()
    solver.initialize(0.0, q, v)
    first = []
    for t, step in ((h, h), (2 * h, h), (2.5 * h, h / 2), (3 * h, h / 2), (4 * h, h)):
        assert solver.step(step, t) == 0
        first.append(solver.trace()[1][0])
    assert first == [1, 0, 1, 0, 1]
    assert solver.repeat(h, 4 * h, warm=True) == 0
    assert solver.trace()[1][0] == 0
    solver.restart()
    assert solver.step(h, 4 * h) == 0
    assert solver.trace()[1][0] == 1
    solver.configure(reuse_jacobian=1, reuse_contractivity=REUSE["reuse_contractivity"])
    for k in (5, 6):
        assert solver.step(h, k * h) == 0
        assert solver.trace()[1][0] == 1
        assert solver.repeat(h, k * h, warm=True) == 0
        assert solver.trace()[1][0] == 0


def test_a_rough_first_solve_stops_at_its_own_tolerance_and_the_repeat_at_the_full():
    """first_pass_tolerance: a step's first solve (alpha_step) stops once its residual is
    within that tolerance, in fewer iterations than the full tolerance takes; the step's
    warm repeat (alpha_repeat, as a coupled host's next pass) goes on to the full
    tolerance, and ends where the full solve does, to the bound the tolerance leaves
    (J du = S (r_rough - r_full), as the kept matrix's test)."""
    chain = Chain()
    h, absolute = 2e-3, 1e-9
    full = chain_solver(chain, relative_tolerance=1e-14, absolute_tolerance=absolute)
    q, v = chain.initial()
    full.initialize(0.0, q, v)
    assert full.step(h, h) == 0
    report = full.report()
    rough_tolerance = 1e-3 * report["initial_residual"]
    rough = chain_solver(chain, relative_tolerance=1e-14, absolute_tolerance=absolute,
                         first_pass_tolerance=rough_tolerance)
    rough.initialize(0.0, q, v)
    assert rough.step(h, h) == 0
    first = rough.report()
    assert absolute < first["residual"] <= rough_tolerance
    assert first["iterations"] < report["iterations"]
    assert rough.repeat(h, h, warm=True) == 0
    again = rough.report()
    assert again["residual"] <= absolute
    solved, reference = rough.state(), full.state()
    J, S = exact_jacobian(chain, full.coefficients(), h, h, *reference[:2], reference[3])
    bound = np.linalg.norm((np.linalg.inv(J) * S)[:chain.nq], axis=1) * (
        again["residual"] + report["residual"])
    assert np.all(np.abs(solved[0] - reference[0]) <= bound)
    assert rough.step(h, 2 * h) == 0  # each step's first solve rough again
    assert absolute < rough.report()["residual"] <= rough_tolerance


def test_an_update_that_grew_the_residual_on_a_new_matrix_is_halved():
    """reuse_damping: a body on a saturating force, F atan(q / eps), whose step crosses the
    knee. Newton cycles there between iterates on new matrices (each one's tangent sends
    it past the knee again) and does not converge; with each update that grew the residual
    on a new matrix halved, the same step converges (the residual is monotone in q, so
    its one root is the step's solution)."""
    force, eps = 1e3, 1e-3

    def evaluate(t, q, v):
        return (-force * np.arctan(q / eps), np.zeros(0),
                (np.zeros(0, int), np.zeros(0, int), np.zeros(0)))

    def jacobian(t, q, v):
        one = np.zeros(1, int)
        return ((one, one, force / eps / (1.0 + (q / eps) ** 2)), (one, one, np.zeros(1)))

    statuses = {}
    for damping in (0, 3):
        solver = alpha.AlphaSolver(
            alpha.PythonSystem(1, 0, evaluate, jacobian), np.ones(1), 0, np.zeros(1, int), 1,
            0, alpha.Settings(reuse_damping=damping, absolute_tolerance=1e-8,
                              relative_tolerance=1e-12, reuse_broyden=1, **REUSE), 16)
        assert solver.initialize(0.0, np.array([0.05]), np.zeros(1)) == 0
        statuses[damping] = solver.step(1e-2, 1e-2)
        norms, made = solver.trace()
        if damping == 0:  # a cycle of two on new matrices to the iteration limit
            assert len(norms) == solver.settings.max_iterations and made.all()
            assert norms[-1] == pytest.approx(norms[-3], rel=1e-6) and norms[-1] > 1e3
        else:
            assert solver.report()["residual"] <= 1e-8
    assert [alpha.STATUS[statuses[d]] for d in (0, 3)] == ["not converged", "converged"]
