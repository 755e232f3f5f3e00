"""The vehicle's own solver's bordered band LU (examples/vehicle/bordered_band.c,
docs/vehicle.md "An own solver", "The vehicle on its own solver"): its solves against
numpy's, its refusals, and its assembly with the places of the last assembly's entries
kept against matrices assembled fresh."""

import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

alpha = pytest.importorskip("vehicle.alpha_solver")

# --- the bordered band LU --------------------------------------------------------------------

def bordered_matrix(rng, n, n_band, w, saddle, isolated=False):
    """A random matrix of the structure, in a random order of its unknowns: a diagonally
    dominant band, a dense border whose last `saddle` rows and columns have a zero
    corner (the multipliers), `isolated`: those touch only the border; (order, matrix)."""
    order = rng.permutation(n)
    position = np.empty(n, dtype=int)
    position[order] = np.arange(n)
    pi, pj = np.meshgrid(position, position, indexing="ij")
    band = (pi < n_band) & (pj < n_band)
    keep = np.where(band, np.abs(pi - pj) <= w, ~((pi >= n - saddle) & (pj >= n - saddle)))
    if isolated:
        keep &= ~(((pi >= n - saddle) & (pj < n_band)) | ((pj >= n - saddle) & (pi < n_band)))
    matrix = np.where(keep, rng.normal(size=(n, n)), 0.0)
    rows = np.flatnonzero(position < n_band)
    matrix[rows, rows] = 1.0 + np.abs(matrix[rows]).sum(axis=1)
    return order, matrix


@pytest.mark.parametrize("n, n_band, w, saddle, isolated",
                         [(30, 22, 3, 3, False), (278, 237, 5, 14, False),
                          (278, 237, 5, 14, True), (12, 12, 2, 0, False), (9, 0, 0, 4, False)])
def test_the_bordered_band_lu_solves_as_numpy(n, n_band, w, saddle, isolated):
    rng = np.random.default_rng(n + w)
    order, matrix = bordered_matrix(rng, n, n_band, w, saddle, isolated)
    lu = alpha.BorderedBand(n, order, n_band, w)
    rows, cols = np.nonzero(matrix)
    # each entry given in two parts: repeated entries add
    values = matrix[rows, cols]
    lu.set(np.r_[rows, rows], np.r_[cols, cols], np.r_[0.25 * values, 0.75 * values])
    lu.factorize()
    for _ in range(3):
        rhs = rng.normal(size=n)
        expected = np.linalg.solve(matrix, rhs)
        assert np.abs(lu.solve(rhs) - expected).max() <= 1e-11 * np.abs(expected).max()


def test_an_entry_outside_the_structure_is_named():
    rng = np.random.default_rng(5)
    order, matrix = bordered_matrix(rng, 30, 22, 3, 3)
    lu = alpha.BorderedBand(30, order, 22, 3)
    row, col = order[2], order[6]  # band positions 2 and 6: 4 apart, half bandwidth 3
    rows, cols = np.nonzero(matrix)
    with pytest.raises(alpha.StructureError, match=f"entry \\({row}, {col}\\) outside") as e:
        lu.set(np.r_[rows, row], np.r_[cols, col], np.r_[matrix[rows, cols], 1.0])
    assert (e.value.row, e.value.col) == (row, col)
    lu.set(rows, cols, matrix[rows, cols])  # the same pattern without it is taken
    lu.factorize()


def test_an_assembly_that_repeats_or_changes_the_last_ones_entries_gives_the_same_matrix():
    """The places of the last assembly's entries reused (bordered_band.c): assemblies with
    the same sequence of (row, col), one whose middle, tail or length changed, an entry
    outside the structure where the last one had an entry inside, each factorized and
    solved with the same bits as a matrix assembled once, fresh."""
    rng = np.random.default_rng(11)
    n, n_band, w, saddle = 278, 237, 5, 14
    order, matrix = bordered_matrix(rng, n, n_band, w, saddle)
    rows, cols = np.nonzero(matrix)
    kept = alpha.BorderedBand(n, order, n_band, w)
    rhs = rng.normal(size=n)
    third = len(rows) // 3
    middle = np.r_[np.arange(third), third + rng.permutation(len(rows) - third)]
    sequences = [np.arange(len(rows)), np.arange(len(rows)), middle,
                 np.r_[np.arange(len(rows)), np.arange(len(rows) // 2)],  # longer: repeated
                 np.arange(len(rows))[::-1], np.arange(len(rows)),
                 np.insert(np.arange(len(rows)), [5, 300, 301, 900], [7, 7, 200, 900]),  # in
                 np.arange(len(rows))]  # and out again
    for sequence in sequences:
        scale = rng.uniform(0.5, 2.0)
        r, c = rows[sequence], cols[sequence]
        values = scale * matrix[r, c] / np.bincount(sequence)[sequence]  # repeats add
        kept.set(r, c, values)
        kept.factorize()
        fresh = alpha.BorderedBand(n, order, n_band, w)
        fresh.set(r, c, values)
        fresh.factorize()
        x = kept.solve(rhs)
        assert np.array_equal(x, fresh.solve(rhs))
        expected = np.linalg.solve(np.bincount(r * n + c, values, n * n).reshape(n, n), rhs)
        assert np.abs(x - expected).max() <= 1e-11 * np.abs(expected).max()
    row, col = order[2], order[9]  # band positions 2 and 9: outside half bandwidth 5
    r, c = rows.copy(), cols.copy()
    r[len(r) // 2], c[len(c) // 2] = row, col  # where the last assembly had an entry inside
    with pytest.raises(alpha.StructureError, match=f"entry \\({row}, {col}\\) outside") as e:
        kept.set(r, c, matrix[rows, cols])
    assert (e.value.row, e.value.col) == (row, col)


def test_a_band_pivot_that_is_not_positive_is_named():
    rng = np.random.default_rng(6)
    order, matrix = bordered_matrix(rng, 30, 22, 3, 3)
    unknown = order[7]
    matrix[unknown, unknown] = -matrix[unknown, unknown]
    lu = alpha.BorderedBand(30, order, 22, 3)
    rows, cols = np.nonzero(matrix)
    lu.set(rows, cols, matrix[rows, cols])
    with pytest.raises(alpha.StructureError, match=f"band pivot not positive at unknown "
                       f"{unknown}$"):
        lu.factorize()
