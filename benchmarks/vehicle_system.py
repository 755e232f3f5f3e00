"""The cost of the vehicle's equations in C (examples/vehicle/system.py; docs/vehicle.md,
The vehicle's equations in C): microseconds of one residual (f and g) and of one Jacobian
(K and D as factor K + factor_t D, the kernels evaluated again there, and G) of the whole
vehicle, beside exudyn's own evaluation of the same model at the same state (its solver's
ComputeODE2RHS, and ComputeJacobianODE2RHS with ComputeJacobianAE, on the run's sparse
system), the two measured in alternating rounds.

    python benchmarks/vehicle_system.py --rounds 5

The state: host step 30 of a 30 ms run on the bump at 3 m/s, from the stored static point
(the first run solves it: about a minute), with the bank's laws of that step.
"""

import argparse
import ctypes
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]


def _timed(function, repeat):
    """CPU microseconds per call of `function`, over `repeat` calls."""
    began = time.process_time()
    for _ in range(repeat):
        function()
    return (time.process_time() - began) / repeat * 1e6


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--repeat", type=int, default=2000, help="C calls a round")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore", UserWarning)  # the FMUs' range notes
    from vehicle.course import Bump
    from vehicle.model import Vehicle
    from vehicle.system import VehicleSystem
    from vehicle.system_states import ExudynEvaluation, run_states

    vehicle = Vehicle(Bump(3.0), 3.0)
    state = run_states(vehicle, 0.03, 1e-3, {30})[30]
    system = VehicleSystem(vehicle, state.laws)
    exudyn = ExudynEvaluation(vehicle, dense=False)
    exudyn.at(state)
    lib, handle = system.lib, system.handle
    q, v = np.ascontiguousarray(state.q), np.ascontiguousarray(state.v)
    at = [a.ctypes.data for a in (q, v, system.f, system.g, system.triplets_out,
                                  system._scratch)]
    G = np.zeros((6 * system.m, 3))
    t, capacity = ctypes.c_double(state.t), len(system.triplets_out)
    one, zero, step = ctypes.c_double(1.0), ctypes.c_double(0.0), ctypes.c_double(1e-3)

    def residual():
        lib.vsystem_residual(handle, t, at[0], at[1], at[2], at[3])

    def jacobian():  # the generalized-alpha matrix's K and D parts at once, then G
        lib.vsystem_jacobian(handle, t, at[0], at[1], one, step, at[4], capacity, at[5])
        lib.vsystem_constraint_jacobian(handle, at[0], None, G.ctypes.data, None)

    mbs, solver = vehicle.mbs, exudyn.solver

    def exudyn_forces():
        solver.ComputeODE2RHS(mbs)

    def exudyn_jacobian():
        solver.ComputeJacobianODE2RHS(mbs, 1.0, 1e-3, 1.0, 1)
        solver.ComputeJacobianAE(mbs, 1.0, 0.0, 1.0)

    rounds = {"C residual": [], "C Jacobian": [], "exudyn forces": [], "exudyn Jacobian": []}
    for _ in range(args.rounds):
        rounds["C residual"].append(_timed(residual, args.repeat))
        rounds["exudyn forces"].append(_timed(exudyn_forces, max(args.repeat // 20, 10)))
        rounds["C Jacobian"].append(_timed(jacobian, args.repeat // 4))
        rounds["exudyn Jacobian"].append(_timed(exudyn_jacobian, max(args.repeat // 40, 10)))
    count = len(system.jacobian(state.t, q, v, 1.0, 1e-3))
    print(f"load average {os.getloadavg()[0]:.2f}; {system.n} coordinates, {system.m} "
          f"constraint equations, {count} triplets; CPU microseconds per call, median (min "
          f"to max) of {args.rounds} rounds:")
    for name, values in rounds.items():
        print(f"  {name:16s} {np.median(values):9.1f} ({min(values):.1f} to {max(values):.1f})")


if __name__ == "__main__":
    main()
