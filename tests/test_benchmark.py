"""The benchmark runs (at its quick size) and its figures are finite; no timing is judged."""

import json
import math
import subprocess
import sys

from conftest import ROOT


def test_quick_benchmark_runs_and_reports_finite_figures(all_fmus, tmp_path):
    fmu_dir = next(iter(all_fmus["native"].values())).parent
    report, figures = tmp_path / "results.md", tmp_path / "results.json"
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "run.py"), "--quick",
                          "--fmus", str(fmu_dir), "--output", str(report), "--json", str(figures)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    data = json.loads(figures.read_text())
    flavoured = {f"{f}/{n}" for f in ("native", "python") for n in all_fmus["native"]}
    assert set(data["costs"]["fmpy"]) == {"Floor", "Floor (pythonfmu)", *flavoured}
    assert set(data["costs"]["c_host"]) == {"Floor", *flavoured}
    for host in data["costs"].values():
        for name, result in host.items():
            assert all(math.isfinite(v) for v in result["do_step"])
            assert all(math.isfinite(v) and v > 0 for v in result["cycle"])
            # a floor's doStep is a few ns, the size of the clock's own cost taken off it
            assert name.startswith("Floor") or all(v > 0 for v in result["do_step"])
    for flavour in ("native", "python"):
        assert set(data["model_alone"][flavour]) == set(all_fmus["native"])
        assert all(math.isfinite(v) and v > 0
                   for samples in data["model_alone"][flavour].values() for v in samples)
    assert {row["fmu"] for row in data["accuracy"]} == set(all_fmus["native"])
    for row in data["accuracy"]:
        assert all(math.isfinite(row[key]) and row[key] >= 0 for key in
                   ("error_held_pct", "error_smooth_pct", "cost_s_per_s"))
    assert set(data["vehicle_scale"]) == {"c_host/native", "c_host/python", "fmpy/native",
                                          "fmpy/python"}
    for figures in data["vehicle_scale"].values():
        assert figures["instances"] == 4 and figures["real_time_factor"] > 0
    text = report.read_text()
    assert "## Cost at h = 1 ms" in text and "## Vehicle scale" in text


def test_the_python_flavours_c_host_benchmark_runs_and_reports_every_fmu(all_fmus):
    python_dir = str(next(iter(all_fmus["python"].values())).parent)
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "python_c_host.py"), "--quick",
                          "--fmus", python_dir, "--before", python_dir],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    rows = [line.split("|")[1:-1] for line in run.stdout.splitlines()
            if line.startswith("| ") and not line.startswith("| FMU")]
    assert {row[0].strip() for row in rows} == set(all_fmus["python"])
    for row in rows:
        medians = [float(cell.split()[0]) for cell in row[1:]]
        assert len(medians) == 5 and all(math.isfinite(v) and v > 0 for v in medians)


def benchmark_rows(script, all_fmus):
    """The table rows a benchmark script prints for the native FMUs' folder (--quick)."""
    native_dir = str(next(iter(all_fmus["native"].values())).parent)
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), "--quick",
                          "--fmus", native_dir], capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    rows = [line.split("|")[1:-1] for line in run.stdout.splitlines()
            if line.startswith("| ") and not line.startswith("| FMU")]
    assert {row[0].strip() for row in rows} == set(all_fmus["native"])
    return [[float(cell.split()[0]) for cell in row[1:]] for row in rows]


def test_the_rollback_cost_benchmark_reports_every_native_fmu(all_fmus):
    for plain, corrected, ratio, get, set_ in benchmark_rows("rollback_cost.py", all_fmus):
        assert all(math.isfinite(v) and v > 0 for v in (plain, corrected, get, set_))
        assert ratio > 1.0  # two cycles and a state round trip cost more than one cycle


def test_the_fmi3_cost_benchmark_reports_every_component(all_fmus):
    for medians in benchmark_rows("fmi3_cost.py", all_fmus):
        assert len(medians) == 3 and all(math.isfinite(v) and v > 0 for v in medians)
