"""Validation against the thesis's measurements: the data file holds the thesis's numbers
with their sources, every row with a metric runs through the FMUs of both flavours and gives
a finite value, the metrics give on an independent solve what they give on the FMU, and the
`validate` command reports and exits as documented."""

import math
import re

import numpy as np
import pytest
from scipy.interpolate import PchipInterpolator

from fmu_components import cli
from fmu_components.verification import cases, measurements, reference
from fmu_components.verification.measurements import (Comparison, Measurement, Record, Runs,
                                                       compare_all, from_si, read_measurements)

ROWS = read_measurements()
BY_ID = {m.id: m for m in ROWS}
DEG = math.pi / 180


# --- the data file -----------------------------------------------------------------------

def test_every_row_has_a_source_a_quote_and_a_known_basis():
    assert len(ROWS) >= 90
    for m in ROWS:
        assert m.source and m.quote and m.obtained, m.id
        assert re.search(r"(section|Section|Table|Appendix|Fig|Eq)", m.source), m.id
        assert m.basis in measurements.BASES


def test_every_metric_names_cases_that_exist():
    runs = Runs("unused")
    for m in ROWS:
        if m.metric and m.metric != "parameter":
            assert runs.select(m), m.id


def test_rows_without_a_metric_say_why_they_are_not_run():
    for m in ROWS:
        if not m.metric:
            assert m.thesis_says or "not stated" in m.conditions, m.id


@pytest.mark.parametrize("change, message", [
    (lambda r: r.update(source=""), "no source"),
    (lambda r: r.update(basis="guess"), "basis 'guess'"),
    (lambda r: r.update(measured="12 kN"), "measured '12 kN' is not a number"),
    (lambda r: r.update(metric="no_such_metric"), "metric 'no_such_metric'"),
    (lambda r: r.update(relation=""), "a measured value needs a relation"),
])
def test_the_reader_names_the_row_and_what_is_wrong(tmp_path, change, message):
    import csv

    with open(measurements.MEASUREMENTS, newline="") as f:
        rows = list(csv.DictReader(f))
    change(rows[3])
    path = tmp_path / "measurements.csv"
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, measurements.COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    with pytest.raises(ValueError, match=re.escape(message)) as raised:
        read_measurements(path)
    assert f"line 5 ({rows[3]['id']})" in str(raised.value)


def test_table_a6_1_rows_are_the_tables_columns():
    table = reference.thesis_rows("table_A6-1.csv")
    rows = [m for m in ROWS if m.id.startswith("damper-A6-1-")]
    assert len(rows) == len(table) - 1  # every rate but 0
    for r in table:
        rate = float(r["rate_rad_per_s"])
        if rate == 0.0:
            continue
        (m,) = [m for m in rows if m.at == rate]
        assert m.measured == float(r["measured_N_m"])
        assert m.thesis_model == float(r["smoothed_N_m"])
        assert (m.thesis_agreement == "disagrees") == (m.measured != m.thesis_model)


def _case(key):
    (case,) = [c for c in measurements.CASES if c.key == key]
    return case


def _preload(case):
    t = case.times()
    x = case.path(t)[t >= case.shown_from - case.step / 2]
    return float(np.mean(x[:-1]))


def test_elastic_rows_are_the_thesis_equations_at_the_cases_preloads():
    """The measured value of each loop-centre row is Eqs. 5.3.1-1 to 5.3.1-3 (read from
    reference_data/thesis by the independent solver) at the preload of the case it runs."""
    rows = [m for m in ROWS if m.metric == "loop_centre"]
    assert len(rows) == 15
    for m in rows:
        a = reference.rubber_spec(m.component).elastic
        x = _preload(_case(m.case))
        assert m.measured == pytest.approx(a[0] + a[1] * x + a[2] * x ** 2 + a[3] * x ** 3,
                                           rel=1e-9, abs=1e-9), m.id


# --- units and the comparison --------------------------------------------------------------

def test_si_values_are_given_in_the_rows_units():
    assert from_si(1.0, "N.m/deg") == pytest.approx(DEG)
    assert from_si(1.0, "1/deg") == pytest.approx(DEG)
    assert from_si(DEG, "deg") == pytest.approx(1.0)
    assert from_si(0.25, "%") == 25.0
    assert from_si(3.0, "N.m.s/rad") == 3.0 and from_si(2.0, "N") == 2.0
    with pytest.raises(ValueError):
        from_si(1.0, "furlong")


def _row(**values):
    fields = {name: "" for name in measurements.COLUMNS}
    fields.update(id="x", component="RoadWheelTyre", quantity="q", basis="rig",
                  metric="peak_torque", case="c", measured=None, thesis_model=None, at=None,
                  scale=None)
    fields.update(values)
    return Measurement(**fields)


def test_differences_in_percent_of_the_measured_value_or_the_rows_scale():
    c = Comparison(_row(measured=200.0, relation="="), model=230.0)
    assert c.difference == 30.0 and c.percent == pytest.approx(15.0)
    assert c.inside is False and "OUTSIDE" in c.verdict
    c = Comparison(_row(measured=-6.4, relation="=", scale=254.4), model=-7.4)
    assert c.percent == pytest.approx(-100 / 254.4) and c.inside
    c = Comparison(_row(measured=200.0, relation="~"), model=181.0)
    assert c.inside and c.verdict == "inside +-10 %"


def test_bounds_and_rows_that_are_not_measurements():
    assert Comparison(_row(measured=50.0, relation="<"), model=49.0).verdict == "bound holds"
    assert Comparison(_row(measured=4000.0, relation="<="), model=4100.0).verdict == "BOUND BROKEN"
    assert Comparison(_row(measured=1.0, relation=">"), model=0.9).inside is False
    for basis in ("extrapolated", "assumed", "design", "statement", "none"):
        c = Comparison(_row(measured=200.0, relation="=", basis=basis), model=400.0)
        assert c.inside is None and c.verdict == "shown"
    # a measured 0 without a scale has no % to judge by
    assert Comparison(_row(measured=0.0, relation="="), model=0.6).inside is None
    assert Comparison(_row(), model=None).verdict == "not run"
    assert Comparison(_row(), problem="RotaryDamper/A: failed").verdict == "FMU FAILED"


# --- through the FMUs ----------------------------------------------------------------------

@pytest.fixture(scope="module")
def compared(all_fmus):
    """Every row through both flavours: {flavour: [Comparison]}."""
    return {flavour: compare_all(ROWS, Runs(next(iter(paths.values())).parent))
            for flavour, paths in all_fmus.items()}


@pytest.mark.parametrize("flavour", ["native", "python", "fmi3"])
def test_every_row_with_a_metric_runs_and_gives_a_finite_value(compared, flavour):
    for c in compared[flavour]:
        assert not c.problem, c.problem
        assert c.ran == bool(c.measurement.metric), c.measurement.id
        if c.ran:
            assert math.isfinite(c.model), c.measurement.id


def test_both_flavours_give_the_same_values(compared):
    for native, python, fmi3 in zip(compared["native"], compared["python"], compared["fmi3"]):
        if native.ran:
            assert python.model == pytest.approx(native.model, rel=1e-9, abs=1e-9), \
                native.measurement.id
            assert fmi3.model == native.model, native.measurement.id  # one core, same bits


class ReferenceRuns(Runs):
    """The cases' records from the independent solve (reference_data/<FMU>/, or a fresh
    solve for a case that has no committed files) instead of an FMU."""

    def run(self, case):
        if case.key not in self.records:
            if case in cases.CASES:
                inputs, result, _ = cases.read(case)
            else:
                inputs = case.inputs()
                result = cases.reference_table(case, inputs)
            self.records[case.key] = Record(case, inputs, result)
        return self.records[case.key]


INDEPENDENT = ["tyre-elastic-3mm", "tyre-geometric-h", "radial-elastic-stiffness",
               "torsion-elastic-stiffness", "torsion-elastic-offset", "torsion-relaxation",
               "torsion-dual-sine-loops", "tyre-frequency-loss-angle", "damper-peak-torque-A",
               "damper-laminar-slope", "damper-energy-rises-with-frequency",
               "damper-transition-torque"]


@pytest.mark.parametrize("row", INDEPENDENT)
def test_the_fmus_value_is_the_independent_solves(compared, row):
    m = BY_ID[row]
    (fmu,) = [c for c in compared["native"] if c.measurement.id == row]
    independent = from_si(measurements.METRICS[m.metric](m, ReferenceRuns("unused")), m.unit)
    scale = abs(m.measured) if m.measured else abs(independent)
    assert fmu.model == pytest.approx(independent, abs=5e-3 * scale), (fmu.model, independent)


def test_steady_torques_are_table_a6_1s_smoothed_curve(compared):
    """The model's value of each Table A6-1 row is the thesis's model value (the smoothed
    column, which the spec's dashpot interpolates), and at 0.25 rad/s the independent
    solver's monotone spline through it."""
    for c in compared["native"]:
        if c.measurement.id.startswith("damper-A6-1-"):
            assert c.model == pytest.approx(c.measurement.thesis_model, rel=5e-3), \
                c.measurement.id
    spec = reference.damper_spec()
    (transition,) = [c for c in compared["native"]
                     if c.measurement.id == "damper-transition-torque"]
    spline = PchipInterpolator(spec.rates, spec.torques)
    assert transition.model == pytest.approx(float(spline(0.25)), rel=1e-3)


def test_the_rotor_inertia_is_read_from_the_fmu(compared):
    for flavour in ("native", "python"):
        (c,) = [c for c in compared[flavour] if c.measurement.id == "damper-rotor-inertia"]
        assert c.model == 0.118 and c.inside


# --- the command ---------------------------------------------------------------------------

def validate(*arguments):
    return cli.main(["validate", *arguments])


def test_validate_prints_the_table_writes_the_report_and_exits_0(native_fmus, tmp_path, capsys):
    folder = next(iter(native_fmus.values())).parent
    assert validate(f"--fmus={folder}", f"--report={tmp_path}", "--fmu=RotaryDamper",
                    "--case=damper-A6-1-compression-1*", "--case=damper-friction") == 0
    printed = capsys.readouterr().out
    assert re.search(r"damper-A6-1-compression-1\s+3250 N\.m\s+3250 N\.m .* fit .* inside", printed)
    assert re.search(r"damper-A6-1-compression-1\.8\s+9091 N\.m\s+8000 N\.m .* extrapolated\s+"
                     r"disagrees\s+shown", printed)
    assert re.search(r"damper-friction\s+< 50 N\.m\s+-.*not run", printed)
    summary = (tmp_path / "summary.md").read_text()
    assert "Appendix 6, Table A6-1" in summary and "smoothed curve 8000 Nm" in summary
    images = re.findall(r"\]\(([^)]+\.png)\)", summary)
    assert "damper_table_A6-1.png" in images
    for image in images:
        assert (tmp_path / image).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_strict_fails_on_a_row_outside_the_band(python_fmus, tmp_path, capsys):
    folder = next(iter(python_fmus.values())).parent
    selection = ["--fmu=RotaryDamper", "--case=damper-general-slope", f"--fmus={folder}",
                 f"--report={tmp_path}"]
    assert validate(*selection) == 0
    assert "OUTSIDE +-10 %" in capsys.readouterr().out
    assert validate(*selection, "--strict") == 1


def test_an_fmu_that_fails_exits_1(tmp_path, capsys):
    (tmp_path / "RotaryDamper.fmu").write_bytes(b"not a zip file")
    assert validate(f"--fmus={tmp_path}", f"--report={tmp_path / 'report'}",
                    "--case=damper-peak-torque-A") == 1
    assert "FMU FAILED" in capsys.readouterr().out


@pytest.mark.parametrize("arguments, words", [
    (["--case=II_amplitude_1mm"], "fmu-components verify"),
    (["--case=damper-peak-torque-A"], "fmu-components build"),
])
def test_usage_mistakes_are_one_line(tmp_path, capsys, arguments, words):
    with pytest.raises(SystemExit) as stop:
        validate(f"--fmus={tmp_path}", f"--report={tmp_path / 'report'}", *arguments)
    assert stop.value.code == 2
    assert words in capsys.readouterr().err


def test_the_printed_table_gives_the_difference_its_unit():
    header, row = measurements.rows([Comparison(_row(measured=200.0, relation="=",
                                                     unit="N.m"), model=230.0)])
    assert header[3] == "difference"
    assert row[2] == "230 N.m" and row[3] == "+30 N.m"
