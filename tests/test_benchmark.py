"""The benchmark runs (at its quick size) and its figures are finite; no timing is judged."""

import json
import math
import subprocess
import sys

from conftest import ROOT


def test_quick_benchmark_runs_and_reports_finite_figures(built_fmus, tmp_path):
    fmu_dir = next(iter(built_fmus.values())).parent
    report, figures = tmp_path / "results.md", tmp_path / "results.json"
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "run.py"), "--quick",
                          "--fmus", str(fmu_dir), "--output", str(report), "--json", str(figures)],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    data = json.loads(figures.read_text())
    assert set(data["costs"]) == {"Floor", *built_fmus}
    for result in data["costs"].values():
        assert all(math.isfinite(v) and v > 0 for v in result["do_step"] + result["cycle"])
    assert all(math.isfinite(v) and v > 0 for samples in data["model_alone"].values() for v in samples)
    assert {row["fmu"] for row in data["accuracy"]} == set(built_fmus)
    for row in data["accuracy"]:
        assert all(math.isfinite(row[key]) and row[key] >= 0 for key in
                   ("error_held_pct", "error_smooth_pct", "cost_s_per_s"))
    assert data["vehicle_scale"]["instances"] == 4 and data["vehicle_scale"]["real_time_factor"] > 0
    text = report.read_text()
    assert "## Cost at h = 1 ms" in text and "## Profile of one doStep" in text
