"""What limits Newton's contraction on the vehicle's own solver (docs/vehicle.md, Newton's
convergence): at states of a run on the bump (exudyn's, vehicle.system_states.run_states:
where its Newton converged in a host step's first solve, with that step's laws), one step
of the solver core (alpha_solver.c, full Newton, tolerance 1e-5) from each state with the
Newton matrix from the system's Jacobian (system.c) and with one from central
differences of its residual, their residual norms per iteration; the linear rate the
Jacobian's error alone gives near the solution, the spectral radius of S^-1 (S_cd - S)
(S the Newton matrix, S_cd the same with K by central differences), with that error kept
to a few blocks; and per iteration of the exact matrix's Newton, the part of the next
residual its linearization did not predict, the contacts' apart from the rest, where it
is largest and the radial bushes' seat distances there; with --radial-linear also the
same step with the radial bushes' laws made linear through zero load at zero distance
(F = k d along the seats' line, k the law's slope: an experiment, not the model). With
--host: the own host's run (examples/tracked_vehicle.py --solver own) with the system's
Jacobian or with central differences as the Newton matrix (both through
alpha_solver.PythonSystem, slow), its Newton iterations per solve and matrices per step.

    python benchmarks/vehicle_newton.py [--speed 5] [--steps 100 200 300 350 400]
                                        [--radial-linear]
    python benchmarks/vehicle_newton.py --host [--end-time 0.4] [--newton full reuse]
"""

import argparse
import os
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from tracked_vehicle import DEFAULT_STEP, simulate  # noqa: E402
from vehicle import alpha_solver as alpha  # noqa: E402
from vehicle import own_host  # noqa: E402
from vehicle.course import Bump  # noqa: E402
from vehicle.model import Vehicle  # noqa: E402
from vehicle.system import VehicleSystem, dense, ordering, outside_band  # noqa: E402
from vehicle.system_states import State, run_states  # noqa: E402

from fmu_components.coupling.bank import LawTable  # noqa: E402

STEP_Q = 1e-8  # m or rad: the central differences' step (the tests' for K)
MATRICES = ("system", "differences")


def contacts_force(system):
    """The contacts' generalized forces in the system's coordinates, at its last
    evaluation."""
    force = np.zeros(system.n)
    np.add.at(force, system.body_index, system.contacts.views["generalized"].reshape(-1))
    return force


def differences(system, t, q, v):
    """K = -df/dq by central differences of the residual, and the contacts' part of it."""
    n = system.n
    K, contacts = np.zeros((n, n)), np.zeros((n, n))
    for j in range(n):
        sides = []
        for sign in (1.0, -1.0):
            moved = q.copy()
            moved[j] += sign * STEP_Q
            sides.append((system.residual(t, moved, v)[0].copy(), contacts_force(system)))
        (f_plus, c_plus), (f_minus, c_minus) = sides
        K[:, j] = -(f_plus - f_minus) / (2 * STEP_Q)
        contacts[:, j] = -(c_plus - c_minus) / (2 * STEP_Q)
    system.residual(t, q, v)
    return K, contacts


class Probe:
    """The vehicle's system as the solver core's Python callbacks, its Newton matrix's K
    from the system (`matrix` "system") or from central differences ("differences"), D
    and the multipliers' term from the system; each evaluation's state, residual parts
    and radial seat distances kept in `iterates` (where `record`), each matrix's K."""

    def __init__(self, system, matrix, record=False):
        self.system, self.matrix, self.record = system, matrix, record
        self.order, self.half, self.border = ordering(system)
        system.keep_band(self.order, self.half, self.border)
        self.iterates, self.matrices, self.solver = [], [], None
        self.calls = np.zeros(2, dtype=np.int64)  # evaluations, Jacobians
        python = alpha.PythonSystem(system.n, system.m, self._evaluate, self._jacobian)
        self.evaluate, self.jacobian, self.context = (python.evaluate, python.jacobian,
                                                      python.context)
        self._python = python

    def bind(self, solver):
        self.solver = solver

    def times(self):  # as own_host.OwnSystem's (calls counted, not timed)
        return np.zeros(2), self.calls.copy()

    def _evaluate(self, t, q, v):
        system = self.system
        self.calls[0] += 1
        f, g = (part.copy() for part in system.residual(t, q, v))
        G, _ = system.constraint_jacobian(q)
        if self.record:
            lam = self.solver.state()[3]
            self.iterates.append(dict(q=q, v=v, lam=lam, f=f, contacts=contacts_force(system),
                                      G=dense(G, system.m, system.n),
                                      seats=system.joints.arrays["joint"][:, 2].copy(),
                                      radial=system.joints.arrays["loads"][
                                          system.joints.arrays["radial_rows"]].copy()))
        return f, g, (G[:, 0], G[:, 1], G[:, 2])

    def _jacobian(self, t, q, v):
        system, n = self.system, self.system.n
        self.calls[1] += 1
        _, H = system.constraint_jacobian(q, self.solver.state()[3])
        D = system.jacobian(t, q, v, 0.0, 1.0).copy()
        if self.matrix == "system":
            K = system.jacobian(t, q, v, 1.0, 0.0).copy()
            rows, columns, values = K.T
        else:
            K, contacts = differences(system, t, q, v)
            rows, columns = np.nonzero(K)
            kept = np.ones(len(rows), dtype=bool)
            kept[outside_band(self.order, self.half, self.border, rows, columns)] = False
            rows, columns = rows[kept], columns[kept]
            values = K[rows, columns]
            if self.record:
                self.matrices.append(dict(K=K, contacts=contacts, D=dense(D, n),
                                          H=dense(H, n)))
        return ((np.concatenate([rows, H[:, 0]]).astype(int),
                 np.concatenate([columns, H[:, 1]]).astype(int),
                 np.concatenate([values, H[:, 2]])),
                (D[:, 0].astype(int), D[:, 1].astype(int), D[:, 2]))

    def solver_for(self, vehicle, relative_tolerance, **settings):
        """The solver core over this probe, the vehicle's spectral radius."""
        system = self.system
        solver = alpha.AlphaSolver(
            self, system.mass_diagonal(), system.m, self.order, len(self.order) - self.border,
            self.half, alpha.Settings(spectral_radius=vehicle.spectral_radius,
                                      relative_tolerance=relative_tolerance,
                                      use_modified_newton=0, **settings),
            system.n ** 2 + 8 * system.n)
        self.bind(solver)
        return solver


def one_step(vehicle, state, matrix, record=False):
    """Full Newton on one host step from `state` (its accelerations computed there):
    (its residual norms, the probe)."""
    probe = Probe(VehicleSystem(vehicle, state.laws), matrix, record)
    solver = probe.solver_for(vehicle, 1e-14, absolute_tolerance=1e-5, max_iterations=12)
    solver.initialize(state.t, state.q, state.v)
    probe.iterates.clear()
    solver.step(DEFAULT_STEP, state.t + DEFAULT_STEP)
    return solver.trace()[0], probe


def rates(vehicle, state):
    """The spectral radius of S^-1 (S_cd - S) with the error in every entry, and kept to
    the entries of the arms' rows or columns, of the links' angles, of the links' y."""
    system = VehicleSystem(vehicle, state.laws)
    n, m = system.n, system.m
    solver = Probe(system, "system").solver_for(vehicle, 1e-8)
    c = solver.coefficients()
    h = DEFAULT_STEP
    beta_prime = (1 - c["alpha_m"]) / (h * h * c["beta"] * (1 - c["alpha_f"]))
    K = dense(system.jacobian(state.t, state.q, state.v, 1.0, 0.0), n)
    error = differences(system, state.t, state.q, state.v)[0] - K
    gamma_prime = c["gamma"] / (h * c["beta"])
    G, H = system.constraint_jacobian(state.q, state.multipliers)
    S = np.zeros((n + m, n + m))
    S[:n, :n] = (np.diag(beta_prime * system.mass_diagonal()) + K + dense(H, n)
                 + gamma_prime * dense(system.jacobian(state.t, state.q, state.v, 0.0, 1.0), n))
    S[n:, :n] = dense(G, m, n)
    S[:n, n:] = S[n:, :n].T
    names = [system.coordinate_name(i) for i in range(n)]
    arm = np.array(["arm" in name for name in names])
    link = np.array([name.startswith("link") for name in names])
    angle, y = link & np.array([name.endswith("angle") for name in names]), \
        link & np.array([name.endswith("'s y") for name in names])
    blocks = {"every entry": np.ones((n, n), dtype=bool),
              "the arms' rows and columns": arm[:, None] | arm[None, :],
              "the links' angles (rows or columns)": angle[:, None] | angle[None, :],
              "the links' y (both)": y[:, None] & y[None, :]}
    out = {}
    for name, mask in blocks.items():
        dS = np.zeros_like(S)
        dS[:n, :n] = np.where(mask, error, 0.0)
        out[name] = float(np.abs(np.linalg.eigvals(np.linalg.solve(S, dS))).max())
    return out


def remainders(probe):
    """Per iteration: |next residual's unpredicted part| (the contacts', the rest's, the
    multipliers' term's), the largest link move, the radial bushes whose law's load
    changed sign (the load cut at zero, model.radial_pull: slack or not), the row where
    the part is largest and the radial seat distances of that link's two joints before
    and after."""
    system, rows = probe.system, []
    links = len(system.link_index) // 3
    for k, mats in enumerate(probe.matrices[:len(probe.iterates) - 1]):
        a, b = probe.iterates[k], probe.iterates[k + 1]
        dq, dv = b["q"] - a["q"], b["v"] - a["v"]
        f = b["f"] - a["f"] + mats["K"] @ dq + mats["D"] @ dv
        contacts = b["contacts"] - a["contacts"] + mats["contacts"] @ dq
        multipliers = (b["G"].T @ b["lam"] - a["G"].T @ a["lam"]
                       - a["G"].T @ (b["lam"] - a["lam"]) - mats["H"] @ dq)
        top = int(np.argmax(np.abs(f)))
        slot = np.flatnonzero(system.link_index == top)
        seats = ""
        if len(slot):
            joints = (slot[0] // 3, (slot[0] // 3 + 1) % links)
            seats = ", ".join(f"{a['seats'][j] * 1e6:.0f} -> {b['seats'][j] * 1e6:.0f} um"
                              for j in joints)
        crossed = int(np.sum((a["radial"] > 0.0) != (b["radial"] > 0.0)))
        rows.append((np.linalg.norm(f), np.linalg.norm(contacts), np.linalg.norm(f - contacts),
                     np.linalg.norm(multipliers), np.abs(dq[system.link_index]).max(),
                     crossed, system.coordinate_name(top), seats))
    return rows


def radial_linear(vehicle, state):
    """`state` with its radial bushes' laws (bank.c's law_load) linear through zero: the
    load at the operating point k x* (F* = k x*, k the law's slope there), a constant
    secant, no kink branch."""
    rows = VehicleSystem(vehicle, state.laws).joints.arrays["radial_rows"]
    laws = state.laws.laws.copy()
    laws[rows, 1] = laws[rows, 2] * laws[rows, 0]
    laws[rows, 3] = laws[rows, 11] = 0.0
    return State(state.step, state.t, state.q, state.v, state.multipliers,
                 LawTable(laws, state.laws.unilateral))


def host_run(speed, end_time, policy, matrix):
    """The own host's run with the probe's Newton matrix: its statistics."""
    original = own_host.solver_for

    def solver_for(vehicle, laws, relative_tolerance=1e-8):
        probe = Probe(VehicleSystem(vehicle, laws), matrix)
        return probe, probe.solver_for(
            vehicle, relative_tolerance, absolute_tolerance=vehicle.newton_tolerance,
            **own_host.NEWTON[vehicle.own_newton or own_host.DEFAULT_NEWTON])

    own_host.solver_for = solver_for
    try:
        vehicle, _, _, cpu = simulate("bump", speed, end_time, DEFAULT_STEP, solver="own",
                                      own_newton=policy)
    finally:
        own_host.solver_for = original
    statistics = vehicle.solver_statistics()
    return statistics, statistics["jacobians"] / max(statistics["steps"], 1), cpu


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", type=float, default=5.0)
    parser.add_argument("--steps", type=int, nargs="+", default=[100, 200, 300, 350, 400],
                        help="host steps of the exudyn run whose states are taken")
    parser.add_argument("--radial-linear", action="store_true")
    parser.add_argument("--host", action="store_true")
    parser.add_argument("--end-time", type=float, default=0.4)
    parser.add_argument("--newton", nargs="+", default=["full", own_host.DEFAULT_NEWTON],
                        choices=sorted(own_host.NEWTON))
    args = parser.parse_args(argv)
    print("load before:", os.getloadavg())
    if args.host:
        for policy in args.newton:
            for matrix in MATRICES:
                statistics, matrices, cpu = host_run(args.speed, args.end_time, policy, matrix)
                print(f"{args.speed:g} m/s, {args.end_time:g} s, {policy}, K from the {matrix}: "
                      f"{statistics['newton_per_pass']:.3f} Newton iterations per solve, "
                      f"{statistics['passes_per_step']:.2f} solves per step, {matrices:.2f} "
                      f"matrices per step, {statistics['steps']} steps ({cpu:.0f} s CPU)",
                      flush=True)
        print("load after:", os.getloadavg())
        return
    vehicle = Vehicle(Bump(args.speed), args.speed)
    states = run_states(vehicle, (max(args.steps) + 1) * DEFAULT_STEP, DEFAULT_STEP,
                        set(args.steps))
    for number in args.steps:
        state = states[number]
        print(f"\nhost step {number} (t = {state.t:.3f} s)")
        for matrix in MATRICES:
            norms, probe = one_step(vehicle, state, matrix, record=matrix == "differences")
            print(f"  K from the {matrix:11s}: " + " ".join(f"{x:.3g}" for x in norms))
        if args.radial_linear:
            norms, _ = one_step(vehicle, radial_linear(vehicle, state), "differences")
            print("  radial laws linear, K from the differences: "
                  + " ".join(f"{x:.3g}" for x in norms))
        print("  linear rate from the Jacobian's error: " + "; ".join(
            f"{name} {rate:.3g}" for name, rate in rates(vehicle, state).items()))
        print("  the exact matrix's iterations: the next residual's unpredicted part "
              "(contacts, rest, multipliers' term), largest link move, radial bushes "
              "turned slack or loaded, where")
        for k, (total, contacts, rest, multipliers, move, crossed, row, seats) in enumerate(
                remainders(probe)):
            print(f"    {k + 1}: {total:.3g} ({contacts:.3g}, {rest:.3g}, {multipliers:.2g}), "
                  f"{move * 1e3:.3f} mm, {crossed}, {row}"
                  f"{'; seat distances ' + seats if seats else ''}")
    print("load after:", os.getloadavg())


if __name__ == "__main__":
    main()
