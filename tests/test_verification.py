"""Verification on the thesis test programme (spec section 5): the case definitions cover
the programme, the committed reference data are what the independent solver gives, every
case runs through the `fmpy simulate` command line and matches its reference, and the
verification command passes, reports and fails when it should."""

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.util import read_csv

from fmu_components import cli
from fmu_components.commands import cases as case_command
from fmu_components.verification import cases, reference, verify
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import piecewise_linear_rate, write_csv

from conftest import FMU_NAMES

MM, DEG = 1e-3, math.pi / 180
BY_KEY = {c.key: c for c in cases.CASES}

# Spec section 5, written out here independently of cases.py: the recorded part of each
# sinusoidal test as (mean, amplitude, frequency in Hz), SI units.
SPEC_SINES = {
    ("RoadWheelTyre", "I"): [(p * MM, 0.2 * MM, 1.0) for p in (1, 2, 3, 4, 5)],
    ("RoadWheelTyre", "II"): [(3.5 * MM, a * MM, 1.0) for a in (0.5, 1, 1.5, 2)],
    ("RoadWheelTyre", "III"): [(3.5 * MM, 1 * MM, f) for f in (0.1, 1, 10, 20)],
    ("TrackBushRadial", "I"): [(p * MM, 0.02 * MM, 1.0) for p in (0.05, 0.15, 0.25, 0.35, 0.45)],
    ("TrackBushRadial", "II"): [(0.3 * MM, a * MM, 1.0) for a in (0.05, 0.1, 0.15, 0.2)],
    ("TrackBushRadial", "III"): [(0.3 * MM, 0.1 * MM, f) for f in (0.1, 1, 10, 20)],
    ("TrackBushTorsion", "I"): [(p * DEG, 1 * DEG, 1.0) for p in (-10, 0, 10, 20, 30)],
    ("TrackBushTorsion", "II"): [(10 * DEG, a * DEG, 1.0) for a in (2.5, 5, 10, 15, 20)],
    ("TrackBushTorsion", "III"): [(10 * DEG, 5 * DEG, f) for f in (0.1, 1, 5)],
    ("RotaryDamper", "A-D"): [(0.0, 0.21, f) for f in (0.75, 0.5, 0.25, 0.1)],
    ("RotaryDamper", "high frequency"): [(0.0, 0.21, f) for f in (3, 8)],
}
SPEC_RELAXATION = {"RoadWheelTyre": (0.0, 4 * MM), "TrackBushRadial": (0.0, 0.3 * MM),
                   "TrackBushTorsion": (10 * DEG, 25 * DEG)}


def sine_fit(t, x, frequency):
    """(mean, amplitude, rms residual) of the least-squares sine at this frequency."""
    w = 2 * math.pi * frequency
    basis = np.column_stack([np.ones_like(t), np.sin(w * t), np.cos(w * t)])
    coefficients, *_ = np.linalg.lstsq(basis, x, rcond=None)
    residual = x - basis @ coefficients
    return coefficients[0], math.hypot(*coefficients[1:]), float(np.sqrt(np.mean(residual ** 2)))


def recorded(case):
    t = case.times()
    k = t >= case.shown_from - case.step / 2
    return t[k], case.path(t)[k]


# --- the programme -----------------------------------------------------------------------

def test_at_least_five_cases_per_rubber_fmu_and_six_for_the_damper():
    counts = {name: sum(c.fmu == name for c in cases.CASES) for name in FMU_NAMES}
    assert all(counts[n] >= 5 for n in ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion"))
    assert counts["RotaryDamper"] >= 6
    assert len(BY_KEY) == len(cases.CASES)  # names are unique per FMU


@pytest.mark.parametrize("fmu, test", sorted(SPEC_SINES))
def test_sinusoidal_cases_record_the_spec_preloads_amplitudes_and_frequencies(fmu, test):
    group = [c for c in cases.CASES if c.fmu == fmu and c.test == test]
    found = []
    for case in group:
        t, x = recorded(case)
        for mean, amplitude, frequency in SPEC_SINES[fmu, test]:
            fit_mean, fit_amplitude, residual = sine_fit(t, x, frequency)
            if (abs(fit_mean - mean) <= 1e-3 * amplitude and residual <= 1e-3 * amplitude
                    and abs(fit_amplitude - amplitude) <= 1e-3 * amplitude):
                found.append((mean, amplitude, frequency))
                # at least one whole recorded cycle (five for Measurement I), to a sample
                assert t[-1] - t[0] >= (5 if test == "I" else 1) / frequency - case.step
    assert sorted(found) == sorted(SPEC_SINES[fmu, test])


@pytest.mark.parametrize("case", [c for c in cases.CASES if c.test == "I"], ids=lambda c: c.key)
def test_measurement_i_cycles_large_before_recording_small(case):
    """Section 5.3: each preload first cycled at large amplitude, then reduced."""
    t = case.times()
    x = case.path(t)
    before = t < case.shown_from - case.step / 2
    _, recorded_amplitude, _ = sine_fit(*recorded(case), 1.0)
    preload = np.mean(recorded(case)[1])
    assert np.max(np.abs(x[before] - preload)) >= 3 * recorded_amplitude


@pytest.mark.parametrize("fmu", sorted(SPEC_RELAXATION))
def test_relaxation_steps_to_the_spec_deflection_and_holds_200_s(fmu):
    (case,) = [c for c in cases.CASES if c.fmu == fmu and c.test == "IV"]
    t = case.times()
    x = case.path(t)
    start, end = SPEC_RELAXATION[fmu]
    assert x[0] == pytest.approx(start, abs=1e-12)
    held = np.isclose(x, end, rtol=0, atol=1e-12 * abs(end))
    first = np.argmax(held)
    assert np.all(held[first:]) and t[-1] - t[first] >= 200.0 - 1e-9
    assert t[first] <= 0.1 + 1e-9  # a fast ramp, then the hold


def test_dual_sine_is_the_spec_history():
    (case,) = [c for c in cases.CASES if c.test == "dual sine"]
    t = case.times()
    expected = (10 + 7.5 * np.sin(2 * np.pi * 0.1 * t) + 0.75 * np.sin(2 * np.pi * 1.5 * t)) * DEG
    assert np.allclose(case.path(t), expected, rtol=0, atol=1e-12)
    assert t[-1] >= 2 / 0.1 - 1e-9  # two primary cycles


def test_sweep_holds_every_table_rate_of_either_sign():
    (case,) = [c for c in cases.CASES if c.test == "sweep"]
    table_rates = {float(r) for r in reference.damper_spec().rates if r != 0}
    assert {rate for rate, _, _ in case.plateaus} == table_rates
    inputs = case.inputs()
    for rate, start, end in case.plateaus:
        k = (inputs["time"] >= start - 1e-9) & (inputs["time"] < end - 1e-9)
        assert np.allclose(inputs["angle_rate"][k], rate, rtol=1e-9, atol=0)
    assert np.max(np.abs(inputs["angle"])) <= math.pi / 4  # the damper's travel, section 9.1


def test_piecewise_linear_rate_integrates_its_rate_exactly():
    knot_times, knot_rates = [0.0, 0.1, 0.3, 0.35, 0.6], [0.0, 2.0, 2.0, -1.0, -1.0]
    t = np.linspace(0.0, 0.6, 6001)
    x = piecewise_linear_rate(t, knot_times, knot_rates, start=0.5)
    midpoints = (t[1:] + t[:-1]) / 2
    # a quadratic between knots: the secant rate is the rate at the midpoint
    assert np.allclose(np.diff(x) / np.diff(t), np.interp(midpoints, knot_times, knot_rates),
                       rtol=0, atol=1e-9)
    expected_end = 0.5 + 0.1 + 0.4 + 0.025 - 0.25  # areas under the rate
    assert x[0] == 0.5 and x[-1] == pytest.approx(expected_end, abs=1e-12)


# --- the committed files -----------------------------------------------------------------

@pytest.mark.parametrize("case", cases.CASES, ids=lambda c: c.key)
def test_committed_files_are_those_of_the_case_definition(case):
    paths = cases.case_paths(case)
    header = paths["in.csv"].read_text().split("\n", 1)[0]
    names = [v.name for v in COMPONENTS[case.fmu].inputs]
    assert header == ",".join(f'"{n}"' for n in ["time", *names])
    committed_in, committed_ref, options = cases.read(case)
    assert cases.differences(case.inputs(), committed_in, 0.0) == []
    assert list(committed_ref.dtype.names) == ["time"] + [
        v.name for v in COMPONENTS[case.fmu].outputs if v.name != "stiffness"]
    assert np.array_equal(committed_ref["time"], committed_in["time"])
    assert paths["ref.opt"].read_text() == cases.options_text(case.options())
    assert options["StopTime"] == committed_in["time"][-1]
    assert options["StepSize"] == case.step


def test_regeneration_reproduces_the_committed_references():
    """A fresh independent solve of the cheap subset gives the committed files."""
    assert case_command.main(["--check", *[f"--case={key}" for key in cases.QUICK_CHECK]]) == 0


def test_regenerate_writes_what_check_then_reproduces(tmp_path):
    key = "TrackBushRadial/IV_relaxation_0.3mm"
    assert case_command.main(["--regenerate", f"--case={key}",
                              f"--reference-data={tmp_path}"]) == 0
    case = BY_KEY[key]
    fresh, committed = cases.read(case, tmp_path), cases.read(case)
    for fresh_table, committed_table in zip(fresh[:2], committed[:2]):
        assert cases.differences(committed_table, fresh_table, cases.REPRODUCE_TOLERANCE) == []


def test_check_finds_a_changed_reference(tmp_path):
    case = BY_KEY["TrackBushTorsion/IV_relaxation_25deg"]
    for path in cases.case_paths(case).values():
        (tmp_path / case.fmu).mkdir(exist_ok=True)
        shutil.copy(path, tmp_path / case.fmu / path.name)
    reference_csv = cases.case_paths(case, tmp_path)["ref.csv"]
    lines = reference_csv.read_text().splitlines()
    row = lines[500].split(",")
    row[1] = repr(float(row[1]) * (1 + 1e-6))
    lines[500] = ",".join(row)
    reference_csv.write_text("\n".join(lines) + "\n")
    problems = cases.check(case, tmp_path)
    assert problems and "torque" in problems[0]


def test_sweep_steady_torques_reproduce_table_a6_1(built_fmus):
    (case,) = [c for c in cases.CASES if c.test == "sweep"]
    inputs, committed, options = cases.read(case)
    table = dict(zip(reference.damper_spec().rates, reference.damper_spec().torques))
    result = simulate_fmu(str(built_fmus["RotaryDamper"]), stop_time=options["StopTime"],
                          output_interval=options["StepSize"],
                          relative_tolerance=options["RelTol"], input=inputs, output=["torque"])
    for source in (committed, result):
        rates, steady = cases.steady_torques(case, source["time"], source["torque"])
        expected = np.array([table[r] for r in rates])
        assert np.max(np.abs(steady - expected) / np.abs(expected)) <= 0.5e-2


# --- the comparison ----------------------------------------------------------------------

def _tables(values, time_step=1e-3):
    t = np.arange(len(values)) * time_step
    table = np.zeros(len(t), dtype=[("time", float), ("force", float)])
    table["time"], table["force"] = t, values
    return table


def test_strict_error_is_the_largest_deviation_in_percent_of_the_range():
    rising = np.linspace(50.0, 150.0, 501)
    expected = _tables(np.concatenate([rising, rising[::-1][1:]]))  # range exactly 100
    result = expected.copy()
    result["force"][300] += 0.4
    errors, outliers, problem = verify.compare(result, expected, expected["time"][-1])
    assert errors["force"] == pytest.approx(0.4) and outliers == 0 and not problem
    result["force"][300] += 0.2
    errors, _, _ = verify.compare(result, expected, expected["time"][-1])
    assert errors["force"] == pytest.approx(0.6) and errors["force"] > verify.STRICT_LIMIT


def test_cross_check_counts_samples_outside_the_band():
    expected = _tables(np.sin(np.linspace(0, 6, 1001)))
    result = expected.copy()
    result["force"][:200] += 0.5  # a quarter of the range, for a fifth of the record
    _, outliers, _ = verify.compare(result, expected, expected["time"][-1])
    assert outliers == pytest.approx(0.2, abs=0.01) and outliers > verify.CROSS_CHECK_LIMIT


def test_a_non_finite_output_fails():
    expected = _tables(np.sin(np.linspace(0, 6, 1001)))
    result = expected.copy()
    result["force"][10] = np.nan
    errors, _, _ = verify.compare(result, expected, expected["time"][-1])
    assert errors["force"] == math.inf


def test_a_result_of_the_wrong_length_is_not_compared():
    expected = _tables(np.sin(np.linspace(0, 6, 1001)))
    errors, outliers, problem = verify.compare(expected[:500], expected, expected["time"][-1])
    assert not errors and outliers == 1.0 and "samples" in problem


# --- the fmpy command line ---------------------------------------------------------------

FMPY = Path(sys.executable).parent / "fmpy"


@pytest.mark.parametrize("case", cases.CASES, ids=lambda c: c.key)
def test_case_runs_through_fmpy_simulate_and_matches_its_reference(built_fmus, tmp_path, case):
    """The README's command, in a fresh interpreter, on every case."""
    paths = cases.case_paths(case)
    _, expected, options = cases.read(case)
    output = tmp_path / "out.csv"
    command = [str(FMPY), "simulate", str(built_fmus[case.fmu]),
               "--input-file", str(paths["in.csv"]),
               "--output-interval", repr(options["StepSize"]),
               "--stop-time", repr(options["StopTime"]),
               "--relative-tolerance", repr(options["RelTol"]),
               "--output-file", str(output)]
    completed = subprocess.run(command, capture_output=True, text=True, timeout=300)
    assert completed.returncode == 0, completed.stderr
    result = read_csv(output)
    errors, outliers, problem = verify.compare(result, expected, options["StopTime"])
    assert not problem
    assert max(errors.values()) <= verify.STRICT_LIMIT, errors
    assert outliers <= verify.CROSS_CHECK_LIMIT


# --- the verification command ------------------------------------------------------------

SMALL_SELECTION = ["RoadWheelTyre/II_amplitude_1mm", "RoadWheelTyre/II_amplitude_2mm",
                   "TrackBushTorsion/IV*", "RotaryDamper/A_*"]


def verify_command(arguments):
    return cli.main(["verify", *arguments])


def _verify(built_fmus, report, *extra):
    arguments = [f"--fmus={built_fmus['RoadWheelTyre'].parent}", f"--report={report}"]
    return verify_command(arguments + [f"--case={c}" for c in SMALL_SELECTION] + list(extra))


def test_verification_command_passes_prints_the_table_and_writes_the_report(built_fmus,
                                                                            tmp_path, capsys):
    assert _verify(built_fmus, tmp_path) == 0
    printed = capsys.readouterr().out
    for key in ("II_amplitude_1mm", "II_amplitude_2mm", "IV_relaxation_25deg", "A_0.75Hz"):
        assert re.search(rf"{key}\s+\d+\.\d+\s+\w+\s+[\d.]+ %\s+pass", printed), key
    assert "4 of 4 cases pass" in printed
    summary = (tmp_path / "summary.md").read_text()
    images = re.findall(r"\]\(([^)]+\.png)\)", summary)
    # one figure per test (tyre II, torsion IV, damper A-D) and one plot per case
    assert len(images) == 3 + 4
    for image in images:
        assert (tmp_path / image).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_verification_command_fails_on_a_case_off_its_reference(built_fmus, tmp_path, capsys):
    data = tmp_path / "reference_data"
    for case in cases.select(patterns=SMALL_SELECTION):
        (data / case.fmu).mkdir(parents=True, exist_ok=True)
        for path in cases.case_paths(case).values():
            shutil.copy(path, data / case.fmu / path.name)
    # 1 % more force than the reference: at the peak (the record starts unloaded, so the
    # peak is the range) that is 1 % of the range, twice the limit
    case = BY_KEY["RoadWheelTyre/II_amplitude_1mm"]
    table = read_csv(cases.case_paths(case, data)["ref.csv"])
    table["force"] *= 1.01
    with open(cases.case_paths(case, data)["ref.csv"], "w") as f:
        write_csv(table, f)
    assert _verify(built_fmus, tmp_path / "report", f"--reference-data={data}") == 1
    printed = capsys.readouterr().out
    assert re.search(r"II_amplitude_1mm\s+0\.9\d+\s+force\s+[\d.]+ %\s+FAIL", printed)
    assert "3 of 4 cases pass" in printed


def test_verification_command_refuses_missing_fmus(tmp_path):
    with pytest.raises(SystemExit) as stop:
        verify_command([f"--fmus={tmp_path}", "--case=RotaryDamper/A_*"])
    assert stop.value.code == 2


# --- the report's titles and plots --------------------------------------------------------

class _Shown:
    """What report.conditions reads of an outcome: the case, its inputs and its time."""

    def __init__(self, case):
        self.case, self.inputs = case, case.inputs()
        self.reference = {"time": self.inputs["time"]}


@pytest.mark.parametrize("case", [c for c in cases.CASES if (c.fmu, c.test) in SPEC_SINES],
                         ids=lambda c: c.key)
def test_plot_titles_name_the_spec_preload_amplitude_and_frequency(case):
    from fmu_components.lab.display import DISPLAY
    from fmu_components.verification.report import conditions

    factor = DISPLAY[case.fmu][0][0]
    said = conditions(_Shown(case))
    mean, amplitude, frequency = (float(re.match(r"(\+-)?(-?[\d.e-]+)", said[k]).group(2))
                                  for k in (list(said)[0], "amplitude", "frequency"))
    assert any(math.isclose(mean, m * factor, rel_tol=2e-3, abs_tol=1e-3 * amplitude)
               and math.isclose(amplitude, a * factor, rel_tol=2e-3)
               and math.isclose(frequency, f, rel_tol=1e-3)
               for m, a, f in SPEC_SINES[case.fmu, case.test]), said


def test_report_plots_are_200_dpi(built_fmus, tmp_path):
    from PIL import Image

    assert verify_command([f"--fmus={built_fmus['RotaryDamper'].parent}",
                          f"--report={tmp_path}", "--case=RotaryDamper/A_*"]) == 0
    for image in tmp_path.glob("*.png"):
        assert Image.open(image).info["dpi"] == pytest.approx((200, 200), abs=0.5)


def test_an_fmu_warning_names_its_case(native_fmus, tmp_path, capsys):
    """The torsion bush's Measurement I at 30 deg reaches 34 deg, past the 33 deg the thesis
    measured: the FMU's warning says so, and verify says which case it came from."""
    assert cli.main(["verify", "--fmus", str(native_fmus["TrackBushTorsion"].parent), "--fmu",
                     "TrackBushTorsion", "--case", "I_preload_30deg", "--report",
                     str(tmp_path)]) == 0
    said = capsys.readouterr()
    warnings = [line for line in (said.out + said.err).splitlines() if "[WARNING]" in line]
    assert warnings and all(line.startswith("TrackBushTorsion/I_preload_30deg: [WARNING] angle = ")
                            for line in warnings), warnings

