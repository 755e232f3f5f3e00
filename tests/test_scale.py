"""Many instances in one process, and long runs, at a size CI can afford; the full size
(400 instances for 1 s, 10^6 steps) is the same script: `python benchmarks/scale.py ...`."""

import json
import subprocess
import sys

from conftest import ROOT


def scale(built_fmus, *args):
    fmu_dir = next(iter(built_fmus.values())).parent
    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "scale.py"), *args,
                          "--fmus", str(fmu_dir), "--json"],
                         capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stdout + run.stderr  # includes a clean exit
    return json.loads(run.stdout.strip().splitlines()[-1])


def test_mixed_instances_reproduce_single_instance_runs(built_fmus):
    figures = scale(built_fmus, "instances", "--count", "40", "--duration", "0.1")
    assert figures["instances"] == 40 and figures["steps"] == 100
    assert set(figures["mix"]) == set(built_fmus) and min(figures["mix"].values()) >= 1
    assert figures["mismatches"] == 0


def test_long_run_stays_on_its_periodic_steady_state_without_memory_growth(built_fmus):
    figures = scale(built_fmus, "long-run", "--steps", "30000")
    assert figures["steps"] == 30000
    assert figures["last_cycle_change_of_peak_to_peak"] <= 1e-9
    assert figures["rss_growth_mib"] < 4.0
