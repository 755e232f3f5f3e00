"""The damper's torque-velocity curve (Table A6-1) and its steady response."""

import csv

import numpy as np
import pytest
from fmpy import simulate_fmu
from scipy.interpolate import PchipInterpolator

from fmu_components.runtime.catalog import ROTARY_DAMPER
from fmu_components.runtime.damper_part import DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES
from fmu_components.runtime.cosim import CoSimulation
from fmu_components.runtime.hermite import MonotoneCubic
from fmu_components.lab.signals import input_table

from conftest import ROOT, default_parameters

CURVE = MonotoneCubic(DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES)


def test_catalog_table_is_the_smoothed_column_of_table_a6_1():
    with open(ROOT / "reference_data" / "thesis" / "table_A6-1.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [float(r["rate_rad_per_s"]) for r in rows] == list(DAMPER_TABLE_RATES)
    assert [float(r["smoothed_N_m"]) for r in rows] == list(DAMPER_TABLE_TORQUES)


def test_curve_passes_through_every_table_point():
    for rate, torque in zip(DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES):
        assert CURVE(rate) == pytest.approx(torque, abs=1e-9)


def test_curve_is_monotone():
    rates = np.linspace(-16.0, 16.0, 64001)
    values = np.array([CURVE(r) for r in rates])
    slopes = np.array([CURVE.value_and_slope(r)[1] for r in rates])
    assert np.all(np.diff(values) >= -1e-9)
    assert np.all(slopes >= -1e-9)


def test_curve_is_c1_at_every_knot():
    for knot in DAMPER_TABLE_RATES:
        eps = 1e-9
        (left, left_slope), (right, right_slope) = (CURVE.value_and_slope(knot - eps),
                                                    CURVE.value_and_slope(knot + eps))
        assert right - left == pytest.approx(0.0, abs=1e-4)
        assert right_slope == pytest.approx(left_slope, rel=1e-5, abs=1e-3)


def test_curve_agrees_with_scipy_pchip_inside_the_table():
    reference = PchipInterpolator(DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES)
    rates = np.linspace(-14.0, 14.0, 10007)
    ours = np.array([CURVE(r) for r in rates])
    assert np.max(np.abs(ours - reference(rates))) < 1e-8


def test_curve_extends_with_the_end_slope():
    # Table A6-1 ends flat on both sides: blow-off torque holds beyond +-14 rad/s.
    assert CURVE(20.0) == pytest.approx(13650.0)
    assert CURVE(-30.0) == pytest.approx(-8050.0)
    tilted = MonotoneCubic([0.0, 1.0, 2.0], [0.0, 1.0, 3.0])
    value, slope = tilted.value_and_slope(2.0)
    assert tilted(5.0) == pytest.approx(value + 3.0 * slope)


@pytest.mark.parametrize("rate", [0.1, 0.5, 1.0, 1.5, 3.0, 10.0, -0.3, -1.7, -6.0])
def test_steady_torque_at_constant_rate_equals_the_curve(rate):
    """At constant arm rate the rotor follows the arm, and the gas spring carries Td."""
    model = ROTARY_DAMPER.build_model(default_parameters("RotaryDamper"))
    cosim = CoSimulation(model, 1e-6, 0.0, 0.0, rate)
    step = 1e-3
    for k in range(2000):
        assert cosim.set_inputs(rate * k * step, rate) is None
        assert cosim.do_step(k * step, step) is None
    torque, deflection, rotor_rate, dashpot, _ = cosim.outputs()
    assert rotor_rate == pytest.approx(rate, rel=1e-6)
    assert torque == pytest.approx(CURVE(rate), rel=1e-5)
    assert dashpot == pytest.approx(torque, rel=1e-5)


def test_steady_torque_through_the_fmu_reproduces_table_points(built_fmus):
    step, stop = 1e-3, 2.0
    times = np.arange(int(round(stop / step)) + 1) * step
    for rate, torque in [(1.0, 3250.0), (-1.2, -4471.0), (5.0, 12100.0)]:
        result = simulate_fmu(str(built_fmus["RotaryDamper"]), stop_time=stop,
                              output_interval=step, output=["torque"],
                              input=input_table("RotaryDamper", times, rate * times))
        assert result["torque"][-1] == pytest.approx(torque, rel=1e-4)
