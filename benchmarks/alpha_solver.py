"""The cost of one factorization and solve of the solver core's bordered band LU
(examples/vehicle/alpha_solver.py, docs/vehicle.md "An own solver") on a Newton matrix of
the vehicle's size and structure, beside SciPy's SuperLU on the same matrix.

    python benchmarks/alpha_solver.py [--repeats 2000]

The matrix: 80 links (3 coordinates each), the hull, 6 arms (each with its wheel), the
idler's crank: 264 coordinates; 14 multipliers (the arms' and the crank's pivots on the
hull). Its pattern is the vehicle's couplings: each link with itself and its neighbours
(the joints, round the loop), each wheel with the 3 links beneath it, the hull with 4 links
on the sprocket and 2 on the roller, the crank with 4 on the idler, the hull with every arm
and the crank, each pivot's 2 rows with its body and the hull. Values random, the band's
rows diagonally dominant (mass plus stiffness at a 1 ms step), the multipliers' corner
zero. The order: links 1 to 79 in the band (237 coordinates, half bandwidth 5), the border
link 0 (it breaks the loop), the hull, the arms, the crank and the multipliers (41).
A second matrix has every border row and column full against the band (the dense bound).
Prints microseconds per call (the mean over `repeats`, old and new alternated in rounds)
and the load.
"""

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from scipy.sparse import csc_matrix
from scipy.sparse.linalg import splu

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "examples"), str(ROOT / "src")]

from vehicle.alpha_solver import BorderedBand  # noqa: E402

LINKS, ARMS = 80, 6
HULL, ARM0, CRANK = 3 * LINKS, 3 * LINKS + 3, 3 * LINKS + 3 + 3 * ARMS
NQ = CRANK + 3
NM = 2 * (ARMS + 1)
N = NQ + NM


def body(start):
    return list(range(start, start + 3))


def vehicle_pattern():
    """The pairs of coupled unknowns (symmetric), as a boolean matrix."""
    pattern = np.zeros((N, N), dtype=bool)

    def couple(a, b):
        pattern[np.ix_(a, b)] = True
        pattern[np.ix_(b, a)] = True

    link = [body(3 * k) for k in range(LINKS)]
    for k in range(LINKS):
        couple(link[k], link[k])
        couple(link[k], link[k - 1])  # the joint behind, round the loop
    for i in range(ARMS):
        arm = body(ARM0 + 3 * i)
        couple(arm, arm)
        couple(arm, body(HULL))
        beneath = 45 + round(i * 0.72 / 0.15)  # the bottom run, a wheel every 4.8 links
        for k in range(beneath - 1, beneath + 2):
            couple(arm, link[k])
        for j in range(2):  # its pivot's two rows
            couple([NQ + 2 * i + j], arm + body(HULL))
    couple(body(HULL), body(HULL))
    couple(body(CRANK), body(CRANK))
    couple(body(CRANK), body(HULL))
    for j in range(2):
        couple([NQ + 2 * ARMS + j], body(CRANK) + body(HULL))
    for k in (0, 1, 2, 3, 20, 21):  # the sprocket's teeth, the roller
        couple(body(HULL), link[k])
    for k in (38, 39, 40, 41):  # the idler
        couple(body(CRANK), link[k])
    pattern[NQ:, NQ:] = False
    return pattern


def order():
    band = list(range(3, 3 * LINKS))
    return np.array(band + [0, 1, 2] + list(range(HULL, N))), len(band)


def matrix_of(pattern, seed=1):
    rng = np.random.default_rng(seed)
    matrix = np.where(pattern, rng.normal(size=(N, N)), 0.0)
    rows = np.arange(NQ)
    matrix[rows, rows] = 1.0 + np.abs(matrix[rows]).sum(axis=1)
    return matrix


def timed(call, repeats):
    start = time.perf_counter()
    for _ in range(repeats):
        call()
    return (time.perf_counter() - start) / repeats * 1e6


def measure(matrix, repeats, rounds=5):
    """{what: microseconds per call}, the best round of each (alternated)."""
    permutation, n_band = order()
    lu = BorderedBand(N, permutation, n_band, 5)
    rows, cols = np.nonzero(matrix)
    values = matrix[rows, cols]
    sparse = csc_matrix(matrix)
    rhs = np.random.default_rng(2).normal(size=N)
    expected = np.linalg.solve(matrix, rhs)

    def own():
        lu.set(rows, cols, values)
        lu.factorize()
        return lu.solve(rhs)

    def superlu():
        return splu(sparse).solve(rhs)

    for solve in (own, superlu):
        error = np.abs(solve() - expected).max() / np.abs(expected).max()
        assert error < 1e-10, (solve.__name__, error)
    best = {"own: set": [], "own: set, factorize, solve": [], "SuperLU: factorize, solve": []}
    for _ in range(rounds):
        best["own: set"].append(timed(lambda: lu.set(rows, cols, values), repeats))
        best["own: set, factorize, solve"].append(timed(own, repeats))
        best["SuperLU: factorize, solve"].append(timed(superlu, repeats))
    result = {key: min(times) for key, times in best.items()}
    result["own: factorize, solve"] = (result["own: set, factorize, solve"]
                                       - result["own: set"])
    return result, len(values)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=2000)
    args = parser.parse_args(argv)
    pattern = vehicle_pattern()
    dense = pattern.copy()
    permutation, n_band = order()
    border = permutation[n_band:]
    band = permutation[:n_band]
    dense[np.ix_(border, band)] = dense[np.ix_(band, border)] = True
    print(f"load before: {os.getloadavg()[0]:.2f}")
    for name, p in (("the vehicle's pattern", pattern), ("border full against the band", dense)):
        result, nonzeros = measure(matrix_of(p), args.repeats)
        print(f"{name}: {N} x {N}, {nonzeros} nonzeros, band {n_band} (half bandwidth 5), "
              f"border {N - n_band}")
        for key, value in result.items():
            print(f"  {key}: {value:.1f} us")
    print(f"load after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
