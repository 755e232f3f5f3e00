"""The vehicle's step check in C (examples/vehicle/step_check.c) against its numpy reference
(step_check.py's links_verdict and contacts_verdict): on solutions that pass, that move or
turn a link, jump a tyre's compression or skip a tooth, with wheels out of contact, pins
disengaged, ties and NaNs, the same verdict, index and values to the bit."""

import math
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
LINKS, WHEELS, N = 12, 5, 60


@pytest.fixture(scope="module")
def check():
    """(the module, its compiled check over LINKS links whose coordinates lie apart in a
    system of N, their index)"""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle import joints, step_check

    lib = joints.library()
    if lib is None:
        pytest.skip("no C compiler: the step check runs its numpy reference")
    index = (np.arange(LINKS)[:, None] * 4 + 9 + np.array([0, 1, 2])).astype(int)
    return step_check, step_check._CompiledCheck(lib, index, WHEELS), index


def _step(rng):
    """A step's start (q0, v0), its length and a solution its motion reaches (a little
    beyond h v0)."""
    q0, v0, h = rng.normal(size=N), rng.normal(size=N) * 5.0, 1e-3 * rng.uniform(0.1, 1.0)
    return q0, v0, h, q0 + h * v0 + rng.normal(size=N) * 1e-4


def _same(a, b):
    """The same verdicts, indices and values to the bit."""
    return a[0] == b[0] and a[1] == b[1] and len(a[2]) == len(b[2]) and all(
        np.array(x).tobytes() == np.array(y).tobytes() for x, y in zip(a[2], b[2]))


def test_the_links_verdict_in_c_is_the_references(check):
    module, compiled, index = check
    rng = np.random.default_rng(7)
    kinds = set()
    for case in range(400):
        q0, v0, h, q1 = _step(rng)
        k = int(rng.integers(LINKS))
        at = index[k]
        if case % 4 == 1:  # moved beyond LINK_JUMP
            q1[at[:2]] += rng.uniform(0.5, 2.0) * module.LINK_JUMP * np.array([0.6, 0.8])
        elif case % 4 == 2:  # turned beyond LINK_TURN, another link moved as far by ratio
            q1[at[2]] -= rng.uniform(0.9, 2.0) * module.LINK_TURN
            other = index[(k + 3) % LINKS]
            q1[other[0]] += module.LINK_JUMP * abs(q1[at[2]] - q0[at[2]] - h * v0[at[2]]) \
                / module.LINK_TURN
        elif case % 4 == 3:  # a NaN: numpy's argmax takes the first
            q1[index[k, int(rng.integers(3))]] = math.nan
            if case % 8 == 3:
                q1[index[(k + 1) % LINKS, 0]] += 2.0 * module.LINK_JUMP
        expected = module.links_verdict(h, q1, q0, v0, index.ravel(), LINKS)
        got = compiled.links(h, q1.ctypes.data, q0.ctypes.data, v0.ctypes.data)
        assert _same(got, expected), (case, got, expected)
        kinds.add(expected[0])
    assert kinds == {module.PASSED, module.LINK}


def test_the_contacts_verdict_in_c_is_the_references(check):
    module, compiled, _ = check
    rng = np.random.default_rng(11)
    kinds = set()
    for case in range(400):
        h = 1e-3 * rng.uniform(0.1, 1.0)
        compression0 = rng.uniform(-0.01, 0.01, WHEELS)
        rate0 = rng.normal(size=WHEELS) * 0.5
        compression1 = compression0 + h * rate0 + rng.normal(size=WHEELS) * 1e-4
        gap0 = rng.uniform(-0.02, 0.02, LINKS)
        gap1 = gap0 + rng.normal(size=LINKS) * 1e-3
        out = rng.random(WHEELS) < 0.3  # wheels out of contact at one end or the other
        (compression0 if case % 2 else compression1)[out] = -np.inf
        w, j = int(rng.integers(WHEELS)), int(rng.integers(LINKS))
        if case % 5 == 1:
            compression1[w] += rng.uniform(0.5, 3.0) * module.TYRE_JUMP
        elif case % 5 == 2:
            gap0[j], gap1[j] = 0.004, 0.004 + rng.uniform(0.5, 3.0) * module.TOOTH_JUMP
        elif case % 5 == 3:  # a tie: the first of two equal jumps
            compression0[:2] = compression1[:2] = 0.0
            rate0[:2] = -module.TYRE_JUMP * 2.0 / h
        elif case % 5 == 4:
            gap1[j] = math.nan
            gap0[j] = 0.001
            rate0[w] = math.nan  # numpy's argmax takes it: the tyres pass
        arrays = [np.ascontiguousarray(a) for a in (compression1, gap1, compression0, rate0,
                                                    gap0)]
        expected = module.contacts_verdict(h, *arrays)
        got = compiled.contacts(h, *(a.ctypes.data for a in arrays))
        assert _same(got, expected), (case, got, expected)
        kinds.add(expected[0])
    assert kinds == {module.PASSED, module.TYRE, module.TOOTH}
