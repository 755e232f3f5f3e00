"""States of a vehicle run to evaluate the vehicle's equations at (system.py), and exudyn's
own evaluation of them there (its solver's: MainSolverImplicitSecondOrder's ComputeODE2RHS,
ComputeJacobianODE2RHS, ComputeAlgebraicEquations, ComputeJacobianAE, ComputeMassMatrix),
for tests/test_vehicle_system.py and benchmarks/vehicle_system.py."""

from dataclasses import dataclass

import numpy as np

import exudyn as exu

from fmu_components.coupling.bank import LawTable


@dataclass
class State:
    """Where exudyn's Newton converged in a host step's first solve: time, coordinates,
    velocities, multipliers, and the bank's laws of that solve."""
    step: int
    t: float
    q: np.ndarray
    v: np.ndarray
    multipliers: np.ndarray
    laws: LawTable


def run_states(vehicle, end_time, step, picks, settle_time=3.0):
    """Run `vehicle` from its static point (settled for at most `settle_time`, the
    example's default, or stored) on the compiled path to end_time at `step`, keeping the
    State of the first solve of each host step numbered in `picks` (1 the first);
    {number: State}."""
    vehicle.settle(settle_time)
    vehicle.prepare()
    path = vehicle.compiled_path
    deflections, states = path.deflections, {}

    def capture():  # the bank's reader, called where exudyn's Newton has converged
        data = vehicle.mbs.systemData
        number = round(data.GetTime() / step)
        if number in picks and number not in states:
            states[number] = State(number, data.GetTime(),
                                   np.array(data.GetODE2Coordinates()),
                                   np.array(data.GetODE2Coordinates_t()),
                                   np.array(data.GetAECoordinates()),
                                   path.bank.law_table())
        return deflections()

    path.deflections = capture
    try:
        vehicle.run(end_time, step, settle=False)
    finally:
        path.deflections = deflections
    return states


class ExudynEvaluation:
    """exudyn's own evaluation of the vehicle (after its run) at a State: its solver's
    functions, on a dense system (n ODE2 coordinates, then the algebraic equations), or
    with `dense` False on the run's sparse one (its matrices not read: for timing)."""

    def __init__(self, vehicle, dense=True):
        from .model import run_settings

        self.v = vehicle
        self.settings = run_settings()
        if dense:
            self.settings.linearSolver.solverType = exu.LinearSolverType.EXUdense
        self.solver = exu.MainSolverImplicitSecondOrder()
        self.solver.InitializeSolver(vehicle.mbs, self.settings)
        self.n = self.solver.GetODE2size()

    def at(self, state, q=None, v=None):
        """Make `state` (its q and v, or those given) current, its laws the connectors'
        (the compiled symbolic matrix) and the generic objects' (Vehicle.bank)."""
        vehicle, data = self.v, self.v.mbs.systemData
        current = exu.ConfigurationType.Current
        vehicle.bank = state.laws
        vehicle.compiled_path.laws.matrix.SetMatrix(state.laws.laws)
        data.SetTime(state.t, current)
        data.SetODE2Coordinates(state.q if q is None else q, current)
        data.SetODE2Coordinates_t(state.v if v is None else v, current)
        data.SetAECoordinates(state.multipliers, current)

    def forces(self):
        """(f, g): the ODE2 right-hand side and the algebraic equations."""
        solver, mbs = self.solver, self.v.mbs
        solver.ComputeODE2RHS(mbs)
        f = np.array(solver.GetSystemResidual()[:self.n])
        solver.ComputeAlgebraicEquations(mbs)
        return f, np.array(solver.GetSystemResidual()[self.n:])

    def jacobian(self, factor, factor_t):
        """exudyn's ComputeJacobianODE2RHS with the factors (n x n)."""
        self.solver.ComputeJacobianODE2RHS(self.v.mbs, factor, factor_t, 1.0, 1)
        return np.array(self.solver.GetSystemJacobian())[:self.n, :self.n]

    def constraint_jacobian(self):
        """exudyn's ComputeJacobianAE, its rows of the algebraic equations (m x n) and
        its columns of the multipliers (n x m)."""
        mbs = self.v.mbs
        self.solver.ComputeJacobianODE2RHS(mbs, 0.0, 0.0, 0.0, 0)  # zeroes it
        self.solver.ComputeJacobianAE(mbs, 1.0, 0.0, 1.0)
        jacobian = np.array(self.solver.GetSystemJacobian())
        return jacobian[self.n:, :self.n], jacobian[:self.n, self.n:]

    def mass(self):
        self.solver.ComputeMassMatrix(self.v.mbs)
        return np.array(self.solver.GetSystemMassMatrix())
