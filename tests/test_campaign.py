"""Campaigns on Dask (src/fmu_components/campaign/, docs/campaigns.md): a real scheduler and
two workers, each a process of its own in its own empty folder, run small rig, verify and
station campaigns; the results equal the serial run's bit for bit, with a worker killed
mid-campaign too; an interrupted campaign resumes without computing anything twice; a
scheduler that cannot be reached, a worker of another version and a failing run are
reported."""

import csv
import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fmu_components.campaign.engine import Engine, EngineError, Failure
from fmu_components.campaign.grid import read_grid
from fmu_components.campaign.run import run_grid
from fmu_components.campaign.table import FILE, ResultsTable, read, without_timings

ROOT = Path(__file__).resolve().parents[1]
ENVIRONMENT = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
# rig points of about half a second each: long enough to be caught running
RIG = {"run": "rig", "component": "TrackBushRadial", "preloads": [2e-4, 3e-4],
       "amplitudes": [5e-5, 1e-4], "frequencies": [1.0, 3.0], "samples_per_cycle": 1000,
       "steady": 1e-6}


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_for(condition, timeout, what):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return
        time.sleep(0.1)
    raise AssertionError(f"not within {timeout} s: {what}")


class Cluster:
    """A scheduler and workers started as processes (`dask scheduler`, `dask worker`), each
    worker in an empty folder of its own; every process ended by its PID."""

    def __init__(self, folder):
        self.folder = folder
        self.address = f"tcp://127.0.0.1:{_free_port()}"
        self.processes = []
        self.scheduler = self._start("scheduler", [
            "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1",
            "--port", self.address.rsplit(":", 1)[1], "--no-dashboard"], folder)
        self.workers = [self.start_worker() for _ in range(2)]

    def _start(self, name, arguments, cwd, environment=ENVIRONMENT):
        log = open(self.folder / f"{name}.log", "w")
        process = subprocess.Popen([sys.executable, *arguments], cwd=cwd, env=environment,
                                   stdout=log, stderr=subprocess.STDOUT)
        self.processes.append(process)
        return process

    def start_worker(self, environment=ENVIRONMENT, nanny=True):
        """`dask worker` as an engineer starts one: with its nanny, which restarts the
        worker process if it dies."""
        index = len(self.processes)
        folder = self.folder / f"worker{index}"
        folder.mkdir()  # empty: the worker finds none of the client's files there
        return self._start(f"worker{index}", [
            "-m", "distributed.cli.dask_worker", self.address, "--nthreads", "1",
            "--no-dashboard", "--local-directory", str(folder),
            *([] if nanny else ["--no-nanny"])], folder, environment)

    def client(self):
        from distributed import Client

        return Client(self.address, timeout=30, set_as_default=False)

    def stop(self):
        """Each process ended by its PID: asked first (a nanny ends its worker), then
        killed."""
        for process in reversed(self.processes):
            if process.poll() is None:
                os.kill(process.pid, signal.SIGTERM)
                try:
                    process.wait(timeout=15)
                except subprocess.TimeoutExpired:
                    os.kill(process.pid, signal.SIGKILL)
                    process.wait()


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    started = Cluster(tmp_path_factory.mktemp("cluster"))
    try:
        with started.client() as client:
            client.wait_for_workers(2, timeout=60)
        yield started
    finally:
        started.stop()


def write_grid(folder, spec, name="grid.json"):
    path = folder / name
    path.write_text(json.dumps(spec))
    return path


def serial(grid_path, folder):
    """The grid's rows run one after another in this process."""
    with Engine(jobs=1) as engine:
        run_grid(read_grid(grid_path), folder, engine)
    return by_run(read(folder / FILE))


def by_run(rows):
    return {row["run"]: row for row in rows}


def assert_bitwise_equal(rows, expected):
    """The same runs with the same values, every number the same float (timings aside)."""
    assert sorted(rows) == sorted(expected)
    for key in expected:
        got, want = without_timings([rows[key]])[0], without_timings([expected[key]])[0]
        assert got.keys() == want.keys(), key
        for column in want:
            assert type(got[column]) is type(want[column]) and got[column] == want[column], \
                f"{key}: {column} is {got[column]!r}, serially {want[column]!r}"


def campaign(arguments):
    return subprocess.Popen([sys.executable, "-m", "fmu_components", "campaign",
                             *map(str, arguments)], cwd=ROOT, env=ENVIRONMENT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def rows_written(path):
    """Rows in the table now (0 before it exists)."""
    try:
        with open(path, newline="") as f:
            return len(list(csv.DictReader(f)))
    except FileNotFoundError:
        return 0


# --- the table ------------------------------------------------------------------------------

def test_the_table_reads_back_every_number_bit_for_bit_and_resumes_from_ok_rows(tmp_path):
    table = ResultsTable(tmp_path)
    values = [0.1 + 0.2, 1e-300 / 3, -2.0 ** 0.5, 6.02214076e23]
    table.add({"run": "a", "x": values[0], "y": values[1], "steady": True, "cycles": 3,
               "status": "ok", "wall_s": 0.25})
    table.add({"run": "b", "x": values[2], "y": values[3], "status": "failed",
               "message": "RigError: no"})
    rows = by_run(read(tmp_path / FILE))
    assert [rows["a"]["x"], rows["a"]["y"], rows["b"]["x"], rows["b"]["y"]] == values
    assert rows["a"]["steady"] is True and rows["a"]["cycles"] == 3
    assert list(rows["a"])[-3:] == ["status", "message", "wall_s"]  # timings last
    assert not list(tmp_path.glob(".*part*"))  # written whole, nothing left beside it
    resumed = ResultsTable(tmp_path, resume=True)
    assert "a" in resumed and "b" not in resumed  # a failed run is tried again


# --- the grid file ---------------------------------------------------------------------------

SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
                  version="1.0" name="stiff">
  <ssv:Parameters>
    <ssv:Parameter name="k1"><ssv:Real value="9e7"/></ssv:Parameter>
    <ssv:Parameter name="elastic.a1"><ssv:Real value="3.1e6"/></ssv:Parameter>
  </ssv:Parameters>
</ssv:ParameterSet>
"""


def test_a_parameter_set_in_ssv_or_json_gives_the_same_runs(tmp_path):
    (tmp_path / "stiff.ssv").write_text(SSV)
    (tmp_path / "stiff.json").write_text(json.dumps({"k1": 9e7, "elastic.a1": 3.1e6}))
    small = dict(RIG, preloads=[3e-4], amplitudes=[1e-4], frequencies=[1.0],
                 samples_per_cycle=40, steady=1e-3)
    tables = {}
    for name in ("stiff.ssv", "stiff.json"):
        grid = write_grid(tmp_path, dict(small, parameter_sets={"thesis": {}, "stiff": name}),
                          f"{name}.grid.json")
        tables[name] = serial(grid, tmp_path / f"results_{name}")
    assert_bitwise_equal(tables["stiff.ssv"], tables["stiff.json"])
    rows = {row["parameter_set"]: row for row in tables["stiff.ssv"].values()}
    change = rows["stiff"]["dynamic_stiffness"] / rows["thesis"]["dynamic_stiffness"] - 1
    assert abs(change) > 0.1  # the set's values reached the runs


# --- the engine's errors ----------------------------------------------------------------------

def test_a_scheduler_that_cannot_be_reached_is_named_within_10_s():
    address = f"tcp://127.0.0.1:{_free_port()}"  # nothing listens there
    started = time.monotonic()
    with pytest.raises(EngineError, match=f"cannot reach the Dask scheduler at {address}"):
        Engine(address).start()
    assert time.monotonic() - started < 10


def test_the_command_says_so_in_one_line(tmp_path):
    address = f"tcp://127.0.0.1:{_free_port()}"
    grid = write_grid(tmp_path, RIG)
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-m", "fmu_components", "campaign", grid,
                             "--scheduler", address, "--report", tmp_path / "r"],
                            cwd=ROOT, env=ENVIRONMENT, capture_output=True, text=True,
                            timeout=60)
    assert time.monotonic() - started < 10  # the command's start included
    assert result.returncode == 2
    assert "Traceback" not in result.stderr
    assert f"cannot reach the Dask scheduler at {address}" in result.stderr


def test_a_worker_of_another_version_is_refused_naming_both(cluster, tmp_path):
    from fmu_components.campaign.engine import package_version

    # a worker whose installed fmu-components says 0.0.1 (its metadata found first)
    metadata = tmp_path / "site" / "fmu_components-0.0.1.dist-info"
    metadata.mkdir(parents=True)
    (metadata / "METADATA").write_text("Metadata-Version: 2.1\nName: fmu-components\n"
                                       "Version: 0.0.1\n")
    environment = {**ENVIRONMENT, "PYTHONPATH": f"{tmp_path / 'site'}{os.pathsep}"
                                                f"{ENVIRONMENT['PYTHONPATH']}"}
    stranger = cluster.start_worker(environment, nanny=False)
    try:
        with cluster.client() as client:
            client.wait_for_workers(3, timeout=60)
        with pytest.raises(EngineError) as refused:
            Engine(cluster.address).start()
        assert "fmu-components 0.0.1" in str(refused.value)
        assert f"this client {package_version()}" in str(refused.value)
    finally:
        os.kill(stranger.pid, signal.SIGKILL)
        stranger.wait()
    with cluster.client() as client:
        _wait_for(lambda: len(client.scheduler_info(n_workers=-1)["workers"]) == 2, 30,
                  "the scheduler forgets the refused worker")


# --- campaigns through the cluster ------------------------------------------------------------

def test_a_verify_campaign_equals_the_serial_run(cluster, tmp_path, native_fmus):
    spec = {"run": "verify", "fmus": str(native_fmus["TrackBushRadial"].parent),
            "fmu": ["TrackBushRadial"], "cases": ["II_amplitude_0.1mm", "II_amplitude_0.2mm",
                                                  "III_frequency_10Hz"]}
    grid = write_grid(tmp_path, spec)
    expected = serial(grid, tmp_path / "serial")
    with Engine(cluster.address) as engine:
        assert engine.workers == 2
        outcome = run_grid(read_grid(grid), tmp_path / "cluster", engine)
    assert outcome.ran == 3 and not outcome.failures
    rows = by_run(read(tmp_path / "cluster" / FILE))
    assert all(row["passed"] is True for row in rows.values())
    assert_bitwise_equal(rows, expected)


def test_verify_draws_each_cases_plot_in_its_task_and_the_client_only_assembles(
        cluster, tmp_path, native_fmus, monkeypatch):
    """verify on a cluster: each case's plot is drawn by the task that ran the case (the
    client's plot_case is never called), and the report is the serial run's, every PNG
    byte for byte and every number of its table bit for bit."""
    from fmu_components import cli
    from fmu_components.verification import report

    selection = ["verify", "--fmus", str(native_fmus["TrackBushRadial"].parent),
                 "--fmu=TrackBushRadial", "--case=II_amplitude_0.1mm", "--case=II_amplitude_0.2mm",
                 "--case=III_frequency_10Hz"]
    assert cli.main([*selection, "--report", str(tmp_path / "serial"), "--jobs", "1"]) == 0

    def not_here(*arguments):
        raise AssertionError("a case's plot drawn on the client")
    monkeypatch.setattr(report, "plot_case", not_here)
    assert cli.main([*selection, "--report", str(tmp_path / "cluster"),
                     "--scheduler", cluster.address]) == 0
    drawn = sorted(p.name for p in (tmp_path / "serial").glob("*.png"))
    assert len([n for n in drawn if n.startswith("case_")]) == 3 and len(drawn) == 3 + 2
    for name in drawn:
        assert (tmp_path / "cluster" / name).read_bytes() == \
            (tmp_path / "serial" / name).read_bytes(), name
    assert_bitwise_equal(by_run(read(tmp_path / "cluster" / FILE)),
                         by_run(read(tmp_path / "serial" / FILE)))


def test_validate_streams_a_results_table_equal_to_the_serial_run(cluster, tmp_path,
                                                                   native_fmus, capsys):
    """validate, as verify, leaves REPORT/results.csv, a row per case; on the cluster its
    numbers and the printed comparison are the serial run's."""
    from fmu_components import cli

    selection = ["validate", "--fmus", str(native_fmus["RotaryDamper"].parent),
                 "--fmu=RotaryDamper", "--case=damper-largest-torque-A-D"]
    printed = {}
    for name, where in (("serial", ["--jobs", "1"]), ("cluster", ["--scheduler", cluster.address])):
        assert cli.main([*selection, "--report", str(tmp_path / name), *where]) == 0
        printed[name] = capsys.readouterr().out.split("report:")[0]
    rows = by_run(read(tmp_path / "cluster" / FILE))
    assert len(rows) == 4 and all(r["status"] == "ok" and r["fmu"] == "RotaryDamper"
                                  for r in rows.values())
    assert all(r["samples"] > 100 and r["torque_max"] > 0 and r["wall_s"] > 0
               for r in rows.values()), rows
    assert_bitwise_equal(rows, by_run(read(tmp_path / "serial" / FILE)))
    assert printed["cluster"] == printed["serial"]


def test_rig_compares_the_structures_on_the_cluster_as_in_one_process(cluster, tmp_path,
                                                                      capsys):
    """rig --compare-structures: each structure a task on the cluster, the table the one
    a single process computes, every number to the last bit."""
    from fmu_components import cli
    from fmu_components.lab.rig_plots import compare_structures

    assert cli.main(["rig", "--component", "TrackBushTorsion", "--compare-structures",
                     "--out", str(tmp_path / "cluster"), "--scheduler", cluster.address]) == 0
    assert f"running on 2 workers of {cluster.address}" in capsys.readouterr().err
    from fmu_components.campaign.tasks import structures_runner

    serial_table = compare_structures(tmp_path / "serial", processes=1)
    assert len(serial_table) == 3
    assert (tmp_path / "cluster" / "structures.md").read_text() == \
        (tmp_path / "serial" / "structures.md").read_text()
    with Engine(cluster.address) as engine:
        assert compare_structures(tmp_path / "again", runner=structures_runner(engine)) == \
            serial_table


def test_a_failing_run_is_reported_with_its_values_and_the_fmus_message(cluster, tmp_path,
                                                                        native_fmus):
    pytest.importorskip("exudyn")
    spec = {"run": "station", "fmus": str(native_fmus["RoadWheelTyre"].parent), "speeds": [8],
            "parameter_sets": {"thesis": {}, "negative": {"RoadWheelTyre": {"k1": -1.0}}},
            "end_time": 0.02, "step": 1e-3}
    grid = write_grid(tmp_path, spec)
    with Engine(cluster.address) as engine:
        outcome = run_grid(read_grid(grid), tmp_path / "cluster", engine)
    rows = by_run(read(tmp_path / "cluster" / FILE))
    failed = "speed=8 course=bump parameter_set=negative"
    assert [run.key for run, _ in outcome.failures] == [failed]
    assert rows[failed]["status"] == "failed" and "k1 = -1.0 N/m must be positive" in rows[failed]["message"]
    done = rows["speed=8 course=bump parameter_set=thesis"]
    assert done["status"] == "ok" and done["max_tyre_force"] > 0


def test_a_worker_killed_mid_campaign_costs_nothing_but_time(cluster, tmp_path):
    grid = write_grid(tmp_path, RIG)
    expected = serial(grid, tmp_path / "serial")
    report = tmp_path / "cluster"
    process = campaign([grid, "--scheduler", cluster.address, "--report", report])
    try:
        _wait_for(lambda: rows_written(report / FILE) >= 1, 120, "a first row")
        with cluster.client() as client:
            pids = client.run(os.getpid)  # the worker processes (their nannies' children)
            busy = [address for address, keys in client.processing().items() if keys]
        assert busy, "no worker was running a task"
        os.kill(pids[busy[0]], signal.SIGKILL)  # its nanny starts a new worker
        out, err = process.communicate(timeout=180)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 0, err
    assert "8 of 8 runs done" in out
    assert_bitwise_equal(by_run(read(report / FILE)), expected)


@pytest.mark.parametrize("stop", [signal.SIGINT, signal.SIGKILL], ids=["ctrl-c", "killed"])
def test_an_interrupted_campaign_resumes_without_computing_anything_twice(cluster, tmp_path,
                                                                          stop):
    grid = write_grid(tmp_path, RIG)
    expected = serial(grid, tmp_path / "serial")
    report = tmp_path / "cluster"
    with cluster.client() as client:
        client.wait_for_workers(2, timeout=60)
    process = campaign([grid, "--scheduler", cluster.address, "--report", report])
    try:
        _wait_for(lambda: rows_written(report / FILE) >= 2, 120, "two rows")
        process.send_signal(stop)
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
    if stop == signal.SIGINT:
        assert process.returncode == 130 and err.strip().splitlines()[-1] == \
            "fmu-components: interrupted", err
    before = by_run(read(report / FILE))  # whole: every row parses, none half written
    done = len(before)
    assert 2 <= done < 8, "the campaign was not stopped in the middle"
    assert not list(report.glob(".*part*"))
    resumed = subprocess.run([sys.executable, "-m", "fmu_components", "campaign", grid,
                              "--scheduler", cluster.address, "--report", report, "--resume"],
                             cwd=ROOT, env=ENVIRONMENT, capture_output=True, text=True,
                             timeout=180)
    assert resumed.returncode == 0, resumed.stderr
    assert f"({8 - done} run now, {done} before)" in resumed.stdout
    after = by_run(read(report / FILE))
    for key, row in before.items():
        assert after[key] == row  # kept as it was, its wall_s too: not run again
    assert_bitwise_equal(after, expected)


def test_a_failure_is_a_value_of_the_stream_not_an_exception():
    def task(x):
        if x == 2:
            raise ValueError("two")
        return x * 10

    with Engine(jobs=1) as engine:
        assert engine.map(task, [(1,), (2,), (3,)]) == [10, Failure("ValueError: two"), 30]


def fit_data(tmp_path):
    import numpy as np

    t = np.arange(1001) * 2e-3
    x = 2e-4 + 1e-4 * np.sin(2 * np.pi * t)
    data = tmp_path / "sine.csv"
    np.savetxt(data, np.column_stack([t, x, 81.8e6 * x]), delimiter=",", fmt="%.17g",
               header="time,deflection,force", comments="")
    return data


FIT_FIXED = ["xi1", "k2", "c2", "xi2", "k3", "c3", "xi3", "elastic.a2", "elastic.a3",
             "geometric.h"]


@pytest.mark.parametrize("starts", [2, 1])
def test_a_fits_starts_on_the_cluster_give_the_serial_fit(cluster, tmp_path, starts):
    """Each start's whole fit a task (a 1,001-sample fit's evaluations are far too short to
    go to the workers one Jacobian at a time): the parameters of the serial fit to the
    last bit."""
    data = fit_data(tmp_path)
    fitted = {}
    for where in (["--jobs", "1"], ["--scheduler", cluster.address]):
        out = tmp_path / f"{where[0][2:]}.json"
        result = subprocess.run([sys.executable, "-m", "fmu_components", "fit", "--component",
                                 "TrackBushRadial", "--starts", str(starts), "--fix",
                                 *FIT_FIXED, "--out", out, data, *where], cwd=ROOT,
                                env=ENVIRONMENT, capture_output=True, text=True, timeout=300)
        assert result.returncode == 0, result.stderr
        fitted[where[0]] = json.loads(out.read_text())
    assert "columns" not in result.stderr
    assert fitted["--scheduler"] == fitted["--jobs"]  # json keeps every float's 17 digits


def test_a_fits_jacobian_columns_on_the_cluster_give_the_serial_fit(cluster, tmp_path):
    """One start, two workers, the columns sent whatever they cost (pays=0): the starts
    run here, each Jacobian's 4 columns in 2 tasks on the workers, and the fit, its
    Jacobian and its evaluations are the serial fit's to the last bit."""
    import numpy as np

    from fmu_components.campaign.tasks import fit_runner
    from fmu_components.lab.fit import fit
    from fmu_components.lab.history import component_definition
    from fmu_components.lab.measured import read_data

    tests = [read_data(fit_data(tmp_path), component_definition("TrackBushRadial", "final"))]
    results, said = {}, []
    for name, engine in (("serial", Engine(jobs=1)), ("cluster", Engine(cluster.address))):
        with engine:
            results[name] = fit("TrackBushRadial", tests, FIT_FIXED, starts=1,
                                runner=fit_runner(engine, said.append, pays=0))
    assert said == ["each Jacobian's 4 columns in 2 tasks per start"]
    serial, distributed = results["serial"], results["cluster"]
    assert distributed.values == serial.values and distributed.starts == serial.starts
    assert np.array_equal(distributed.jacobian, serial.jacobian)


def test_ctrl_c_at_a_terminal_ends_a_local_cluster_in_one_line(tmp_path):
    """Ctrl-C reaches the whole process group, the local cluster's workers too: only the
    command answers, with its one line, and no process of the group stays behind."""
    grid = write_grid(tmp_path, RIG)
    report = tmp_path / "report"
    process = subprocess.Popen([sys.executable, "-m", "fmu_components", "campaign", grid,
                                "--jobs", "2", "--report", report], cwd=ROOT, env=ENVIRONMENT,
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        _wait_for(lambda: rows_written(report / FILE) >= 1, 120, "a first row")
        os.killpg(process.pid, signal.SIGINT)
        _, err = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    assert process.returncode == 130
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert err.strip().splitlines()[-1] == "fmu-components: interrupted"
    _wait_for(lambda: not _group_alive(process.pid), 30, "the workers end")


def _group_alive(group):
    try:
        os.killpg(group, 0)
    except ProcessLookupError:
        return False
    return True


def _distributed_log_level():
    import logging

    return logging.getLogger("distributed.worker").getEffectiveLevel()


def test_a_local_clusters_workers_log_only_what_is_critical():
    """A worker's heartbeat that meets the scheduler closed at a Ctrl-C's shutdown is
    logged by distributed as an ERROR with a traceback: the local workers log only what is
    critical (a task's error reaches the client through its future), and this process's
    environment is left as it was."""
    import logging

    kept = os.environ.get("DASK_LOGGING__DISTRIBUTED")
    with Engine(jobs=2) as engine:
        levels = engine.client.run(_distributed_log_level)
    assert len(levels) == 2
    assert set(levels.values()) == {logging.CRITICAL}
    assert os.environ.get("DASK_LOGGING__DISTRIBUTED") == kept
