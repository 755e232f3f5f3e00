"""A step's first law with the reversal's kink at the accepted point (fmu.py's
`kinked_first_law`, Bank.kink_first_laws; docs/vehicle.md, "A kink in the first law"):
its shape, and the bank's numbers to the bit against the Python path's, on test_bank.py's
prescribed host (bank_runs.py)."""

import math
import warnings

import numpy as np
import pytest

from bank_runs import bank_run, python_run


@pytest.mark.parametrize("scheme", ["iterated", "corrected"])
def test_the_bank_gives_the_python_paths_numbers_with_kinked_first_laws(native_fmus, scheme):
    """Every accepted load and every law at the probes, and each step's first laws, to the
    bit (the first laws' points, tangents and kinks)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        python_first, bank_first = [], []
        expected, _ = python_run(native_fmus, scheme, 120, kinked=True, first=python_first)
        got, _ = bank_run(native_fmus, scheme, 120, kinked=True, first=bank_first)
    assert np.array_equal(got, expected)
    straight = bank_run(native_fmus, scheme, 120)[0]  # the host's motion is set:
    assert np.array_equal(got, straight)  # the first laws change no FMU's answer here
    fields = ("deflection", "load", "stiffness", "curvature", "kink", "kink_load", "beyond",
              "side")
    for laws, step in zip(bank_first, python_first):
        for row, (law, *_) in zip(laws, step):
            assert list(row[[0, 1, 2, 3, 8, 9, 10, 11]]) == [getattr(law, f) for f in fields]


def test_the_first_law_has_the_last_directions_tangent_on_its_side_the_others_beyond(
        native_fmus):
    """About the accepted point (x*, F*): on the side the last step moved to, the
    `stiffness` output's tangent; beyond x*, the tangent for motion the other way (the
    output at the mirrored rate); continuous at x*. Where the last rate was zero, no kink."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        first = []
        python_run(native_fmus, "iterated", 60, kinked=True, first=first)
    kinked = 0
    for step in first[1:]:
        for law, x, rate, stiffness, reverse, unilateral in step:
            if reverse is None or (unilateral and law.load <= 0.0):  # not reversible (the
                continue  # damper's linearised law), or a contact's touch law
            d = 1e-6 * max(abs(x), 1e-3)
            side = math.copysign(1.0, rate) if rate else 0.0
            assert law.side == side
            if not side:
                continue
            step = side * d
            ahead, behind = law(x + step) - law(x), law(x) - law(x - step)
            assert law(x) == law.load
            assert ahead / step == pytest.approx(stiffness, rel=1e-6)
            assert behind / step == pytest.approx(reverse, rel=1e-6)
            kinked += reverse != pytest.approx(stiffness, rel=1e-3)
    assert kinked > 0
