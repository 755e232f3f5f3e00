"""The coupling's bank (fmu_components.coupling.bank: the per-step work of many FMU
instances in C) against the Python path it follows: the same numbers to the bit, on a
prescribed host and in the track span in exudyn; the faults as the Python path has them;
memory over many steps; one thread; the build."""

import math
import shutil
import subprocess
import sys
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

from fmu_components.coupling import CouplingError, LoadLaw
from fmu_components.coupling import bank_build, linearised
from fmu_components.coupling.bank import Bank

from bank_runs import bank_run, mix, motion, python_run

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


@pytest.fixture
def python_exponential(monkeypatch):
    """The Python path's linearised steps with linearised.py's own exponential, not the
    bank library's C twin it takes where built."""
    monkeypatch.setattr(linearised, "USE_COMPILED", False)


def test_the_c_exponential_is_linearised_pys_to_the_bit():
    """bank_linearised.c's expm of augmented matrices, as the damper's step makes them
    (1 to 3 states, stable A, 0.5 to 4 ms), against linearised.py's: the same bits, in
    every entry."""
    assert linearised.compiled_expm() is not None
    rng = np.random.default_rng(7)
    for _ in range(500):
        n = int(rng.integers(1, 4))
        d = 2 * n + 2
        a = -np.diag(rng.uniform(1.0, 5e3, n)) + rng.uniform(-1e3, 1e3, (n, n))
        a[-1, 0] = -rng.uniform(1e4, 5e5)
        m = np.zeros((d, d))
        m[:n, :n] = m[n:2 * n, n:2 * n] = a
        m[:2 * n, 2 * n:] = rng.uniform(-1e4, 1e4, (2 * n, 2))
        m[2 * n, 2 * n + 1] = 1.0
        m = (m * rng.choice([4e-3, 1e-3, 5e-4])).tolist()
        python = linearised.expm(m, linearised.augmented_pattern(d))
        assert all(math.isfinite(x) for row in python for x in row)
        assert [list(row) for row in linearised.augmented_expm(m)] == python


def test_the_compact_exponential_takes_every_state_count_to_the_bit():
    """bank_linearised.c keeps the augmented matrix on its pattern (the diagonal block
    once): 4 to 8 states, entries exactly zero, norms that need no squaring, against
    linearised.py's full-matrix expm, to the bit; a matrix off the pattern (the two
    blocks differing) is refused."""
    rng = np.random.default_rng(11)
    for trial in range(60):
        n = int(rng.integers(4, 9))
        d = 2 * n + 2
        a = rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-3, 4)
        a[rng.random((n, n)) < 0.3] = 0.0
        m = np.zeros((d, d))
        m[:n, :n] = m[n:2 * n, n:2 * n] = a
        m[:2 * n, 2 * n:] = rng.uniform(-1e4, 1e4, (2 * n, 2)) * (rng.random((2 * n, 2)) > 0.2)
        m[2 * n, 2 * n + 1] = 1.0
        m = (m * (1e-6 if trial % 3 == 0 else 1e-3)).tolist()
        python = linearised.expm(m, linearised.augmented_pattern(d))
        assert [list(row) for row in linearised.augmented_expm(m)] == python
    m[n][n] += 1.0  # the second block no longer the first
    flat = np.array(m)
    assert linearised.compiled_expm()(d, flat.ctypes.data) == -1


@pytest.mark.parametrize("scheme", ["corrected", "iterated", "explicit", "converged"])
def test_the_bank_gives_the_python_paths_numbers(native_fmus, scheme, python_exponential):
    """A tyre, both bushes and the damper, every pass's law and every accepted load: to
    the bit, the damper's linearised law too (its matrix exponential in C, operation for
    operation as linearised.py's)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # converged's pass limit, on both paths
        expected, coupling = python_run(native_fmus, scheme, 200)
        got, bank = bank_run(native_fmus, scheme, 200)
    assert np.array_equal(got, expected)
    assert bank.costs() == pytest.approx(coupling.costs())


@pytest.mark.parametrize("step", [4e-3, 1e-3, 5e-4])
def test_the_track_span_compiled_path_gives_the_python_paths_numbers(native_fmus, step):
    """exudyn with the laws in compiled symbolic functions against exudyn with a Python
    force function per connector: the same histories, to the bit."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import track_span
    finally:
        sys.path.remove(str(EXAMPLES))
    fmu_dir = Path(native_fmus["TrackBushRadial"]).parent
    runs = {path: track_span.simulate(step, links=3, fmu_dir=fmu_dir, end_time=0.04,
                                      path=path) for path in ("python", "compiled")}
    for key in ("joint_torque", "radial_force", "link_height", "link_acceleration"):
        python, compiled = runs["python"][key], runs["compiled"][key]
        assert python.shape == compiled.shape
        assert np.array_equal(compiled, python), key
    assert runs["compiled"]["costs"]["passes"] == runs["python"]["costs"]["passes"] == 2
    # the dynamic solve's own CPU time, which benchmarks/coupling_exudyn.py reads
    assert all(0.0 < run["solve_cpu"] < 60.0 for run in runs.values())


def test_the_track_spans_c_deflections_are_its_numpy_deflections_to_the_bit(native_fmus):
    """The compiled path's deflections from the coordinates (track_span_deflections.c)
    against the numpy function it replaces, at the laid-out span and at states moved by
    up to a millimetre and half a radian per coordinate."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import track_span
    finally:
        sys.path.remove(str(EXAMPLES))
    span = track_span.TrackSpan(links=6, fmu_dir=Path(native_fmus["TrackBushRadial"]).parent,
                                path="compiled")
    try:
        span._compile_forces()
        compiled = span._deflections
        assert compiled != span.numpy_deflections  # the compiled path's, where gcc is
        data, generator = span.mbs.systemData, np.random.default_rng(7)
        laid_out = data.GetODE2Coordinates()
        for position, angle in ((0.0, 0.0), (1e-6, 1e-6), (1e-3, 0.5), (0.1, 0.5)):
            scale = np.tile([position, position, angle], len(laid_out) // 3)
            data.SetODE2Coordinates(laid_out + scale * generator.uniform(-1.0, 1.0,
                                                                         laid_out.shape))
            expected = span.numpy_deflections()
            assert compiled().tobytes() == expected.tobytes()
        assert np.ptp(expected[0::2]) > 1e-3 and np.ptp(expected[1::2]) > 0.1
    finally:
        span.bank.free()


def announced_run(fmus, announce, steps=120):
    """A corrected bank of the four FMUs over `steps` host steps of 1 ms, the damper turned
    0.1 rad within step 60 (a Discard: the host retries it shorter), the host announcing each next
    step's end at accept where `announce`. Per step the laws after begin_step and after the
    last pass, the accepted loads, the passes and the mismatch; the number of C
    begin_step calls; the costs."""
    bank = Bank(mix(fmus), "corrected")
    calls = []
    begin = bank._begin
    bank._begin = lambda handle: calls.append(1) or begin(handle)
    bank.start(0.0, motion(0.0))
    rows, t = [], 0.0
    try:
        for k in range(1, steps + 1):
            end = t + 1e-3
            bank.begin_step(end)
            first_laws = list(bank.law_loads(1.01 * motion(end)))
            while True:
                x = motion(end)
                x[3] += 0.1 * min(max((end - 0.059) / 1e-3, 0.0), 1.0)  # 0.1 rad in step 60
                verdict = bank.end_pass(end, x)
                if verdict.retry_step:
                    end = t + verdict.retry_step
                    bank.begin_step(end)
                    first_laws = list(bank.law_loads(1.01 * motion(end)))
                elif not verdict.repeat:
                    break
            t = end
            last_laws = list(bank.law_loads(1.01 * motion(t)))
            bank.accept(t, t + 1e-3 if announce and k < steps else None)
            rows.append(first_laws + last_laws + list(bank.loads)
                        + [bank.passes, bank.total_passes, bank.last_mismatch])
        costs = bank.costs()
    finally:
        bank.free()
    return np.array(rows), len(calls), costs


def test_a_host_that_announces_its_next_step_saves_a_call_and_changes_no_number(native_fmus):
    """accept(t, next_time) begins the next step in the same C call: the same loads,
    laws, passes and costs to the bit as begin_step's own, a C begin_step only for the
    first step and where the host begins another step than it announced (a retry)."""
    expected, calls, costs = announced_run(native_fmus, announce=False)
    got, announced_calls, announced_costs = announced_run(native_fmus, announce=True)
    assert np.array_equal(got, expected)
    assert announced_costs == costs
    assert calls >= 121 and announced_calls == calls - 119


def test_a_step_begun_again_saves_no_state_again(native_fmus):
    """A step begun again (the retry after step 60's Discard in announced_run) has every
    instance restored to the state saved at the step's start, and saves none again: one
    save per instance per accepted step, the retry's restores on top."""
    _, _, costs = announced_run(native_fmus, announce=False)
    assert costs["saves"] == 1.0 and costs["restores"] > 1.0


def test_the_law_loads_entry_called_from_c_gives_law_loads(native_fmus):
    """law_loads_entry's function (bank.c's bank_law_loads, as the vehicle's contacts
    kernel calls it) at the bank's handle gives law_loads' loads and slopes to the bit,
    at a step's laws, and so do the laws kept as a LawTable."""
    import ctypes

    bank = Bank(mix(native_fmus), "corrected")
    bank.start(0.0, motion(0.0))
    try:
        bank.begin_step(1e-3)
        address, handle = bank.law_loads_entry()
        double = ctypes.POINTER(ctypes.c_double)
        law_loads = ctypes.CFUNCTYPE(None, ctypes.c_void_p, double, double, double)(address)
        for scale in (0.5, 1.01, 2.0):
            deflection = scale * motion(1e-3)
            loads, slopes = np.empty(bank.n), np.empty(bank.n)
            law_loads(handle, *(a.ctypes.data_as(double) for a in (deflection, loads, slopes)))
            expected_loads, expected_slopes = bank.law_loads(deflection, slopes=True)
            assert np.any(expected_loads != 0.0)
            assert np.array_equal(loads, expected_loads)
            assert np.array_equal(slopes, expected_slopes)
            # the laws kept apart (a LawTable: law_table_loads) give the same bits, from C too
            table = bank.law_table()
            kept, table_handle = table.law_loads_entry()
            function = ctypes.CFUNCTYPE(None, ctypes.c_void_p, double, double, double)(kept)
            function(table_handle, *(a.ctypes.data_as(double)
                                     for a in (deflection, loads, slopes)))
            for got in ((loads, slopes), table.law_loads(deflection, slopes=True)):
                assert np.array_equal(got[0], expected_loads)
                assert np.array_equal(got[1], expected_slopes)
    finally:
        bank.free()


def serialized(bank):
    return [c.serialized_state() for c in bank.components]


def test_a_discard_restores_the_whole_bank_and_the_host_retries(native_fmus):
    """The damper driven at 100 rad/s from rest cannot finish a 1 ms step: every
    instance of the bank goes back to the step's start, and the host retries shorter."""
    bank = Bank(mix(native_fmus, ("tyre", "radial", "damper")), "corrected")
    bank.start(0.0, [3e-3, 2e-4, 0.0])
    try:
        before = serialized(bank)
        bank.begin_step(1e-3)
        verdict = bank.end_pass(1e-3, [3.1e-3, 2.1e-4, 0.1])
        assert verdict.retry_step == pytest.approx(5e-4)
        assert serialized(bank) == before
        assert bank.retries == 1
        step = verdict.retry_step
        while True:
            bank.begin_step(step)
            verdict = bank.end_pass(step, [3.1e-3, 2.1e-4, 100.0 * step])
            while verdict.repeat:
                verdict = bank.end_pass(step, [3.1e-3, 2.1e-4, 100.0 * step])
            if verdict.retry_step is None:
                break
            step = verdict.retry_step
        bank.accept(step)
        assert step <= 5e-4 and np.all(np.isfinite(bank.loads)) and bank.loads[2] > 0.0
    finally:
        bank.free()


def test_a_host_that_cannot_retry_gets_the_fmu_step_cut(native_fmus):
    bank = Bank(mix(native_fmus, ("damper",)), "explicit", host_can_retry=False)
    bank.start(0.0, [0.0])
    try:
        bank.begin_step(1e-3)
        assert not bank.end_pass(1e-3, [0.1]).repeat
        bank.accept(1e-3)
        assert bank.costs()["do_steps"] > 2 and bank.retries >= 1
        assert math.isfinite(bank.loads[0])
    finally:
        bank.free()


def test_an_error_names_the_instance_and_the_time(native_fmus):
    components = mix(native_fmus, ("radial", "tyre"))
    components[1].name = "front_tyre"
    bank = Bank(components, "corrected")
    bank.start(0.0, [2e-4, 3e-3])
    try:
        bank.begin_step(1e-3)
        with pytest.raises(CouplingError, match=r"front_tyre at t = 0 s: fmi2SetReal "
                                                r"returned fmi2Error.*compression"):
            bank.end_pass(1e-3, [2.1e-4, math.nan])
    finally:
        bank.free()


def test_a_hundred_thousand_bank_steps_keep_memory_flat(native_fmus):
    """One saved state per instance, reused, and no allocation per call: the process does
    not grow between 10,000 and 100,000 corrected steps of the rubber instances
    (benchmarks/coupling_scale.py --long measures 10^6)."""
    def resident_kib():
        return int(Path("/proc/self/statm").read_text().split()[1]) * 4

    bank = Bank(mix(native_fmus, ("tyre", "radial", "torsion")), "corrected")
    bank.start(0.0, motion(0.0)[:3])
    try:
        for k in range(1, 100_001):
            t = k * 1e-4
            bank.begin_step(t)
            x = motion(t)[:3]
            while bank.end_pass(t, x).repeat:
                pass
            bank.accept(t)
            if k == 10_000:
                early = resident_kib()
        grown = resident_kib() - early
        assert bank.costs()["do_steps"] == 2.0 and bank.costs()["saves"] == 1.0
    finally:
        bank.free()
    assert grown < 512, f"{grown} KiB more after 90,000 further steps"


def test_a_bank_used_from_a_second_thread_is_refused(native_fmus):
    bank = Bank(mix(native_fmus, ("radial",)), "corrected")
    bank.start(0.0, [2e-4])
    refused = []

    def other():
        try:
            bank.begin_step(1e-3)
        except RuntimeError as error:
            refused.append(str(error))

    try:
        thread = threading.Thread(target=other)
        thread.start()
        thread.join()
        assert refused and "belongs to thread" in refused[0] and "called from thread" in refused[0]
        bank.begin_step(1e-3)  # its own thread still can
        assert not bank.end_pass(1e-3, [2.1e-4]).retry_step
    finally:
        bank.free()


def test_the_symbolic_laws_are_the_load_laws_to_the_bit():
    """exudyn's compiled expression of the law against LoadLaw, on random laws (curved,
    straight, contacts in and out of touch, with and without a reversal's kink)."""
    exudyn = pytest.importorskip("exudyn")
    from fmu_components.coupling.bank_exudyn import SymbolicLaws

    class Laws:
        laws = np.zeros((6, 12))
        unilateral = np.array([False, True, False, True, False, True])
        reversible = np.array([False, False, True, True, True, True])

    laws = SymbolicLaws(Laws, name="test_laws")
    x = exudyn.symbolic.Real("test_x", 0.0)
    expressions = [laws.load(i, x) for i in range(6)]
    rng = np.random.default_rng(1)
    for _ in range(2000):
        Laws.laws[:, :5] = rng.normal(size=(6, 5)) * [1e-3, 1e4, 1e7, 1e10, 1e7]
        Laws.laws[rng.random(6) < 0.3, 3] = 0.0
        kinks = [(Laws.laws[i, 0] + rng.normal() * 1e-3 * rng.integers(0, 2),
                  rng.normal() * 1e7, float(rng.integers(-1, 2)) * Laws.reversible[i])
                 for i in range(6)]
        for i, (where, beyond, side) in enumerate(kinks):  # as the bank writes them
            row = Laws.laws[i]
            k, q = row[2], row[3]
            law = LoadLaw(*row[:4], kink=where, beyond=beyond, side=side)
            row[5:] = (0.5 * q, 0.5 * k if k >= 0 else 2 * k, 2 * k if k >= 0 else 0.5 * k,
                       where, law.kink_load, beyond, side)
        laws.update()
        value = rng.normal() * 2e-3
        x.SetValue(value)
        for i, expression in enumerate(expressions):
            law = LoadLaw(*Laws.laws[i, :4], unilateral=bool(Laws.unilateral[i]),
                          touch_stiffness=Laws.laws[i, 4], kink=kinks[i][0],
                          beyond=kinks[i][1], side=kinks[i][2])
            assert expression.Evaluate() == law(value)
    # a contact's law about a point with no number (x* NaN) out of touch: max(x*, 0) is
    # NaN in Python, so the touch gives no load; so in exudyn
    Laws.laws[1] = [math.nan, -1.0, 1e7, 0.0, 1e7, 0.0, 5e6, 2e7, math.nan, math.nan, 1e7, 0.0]
    laws.update()
    x.SetValue(1e-3)
    law = LoadLaw(math.nan, -1.0, 1e7, 0.0, unilateral=True, touch_stiffness=1e7)
    assert expressions[1].Evaluate() == law(1e-3) == 0.0


def test_without_a_compiler_the_bank_says_so(monkeypatch, tmp_path):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(bank_build.NoCompiler, match="gcc not found.*Python path"):
        bank_build.compile_bank("linux64", tmp_path)


@pytest.mark.skipif(shutil.which("x86_64-w64-mingw32-gcc") is None, reason="no mingw-w64")
def test_the_bank_builds_for_win64(tmp_path):
    """Built only: loading it needs Windows (or wine with a Windows Python)."""
    library = bank_build.compile_bank("win64", tmp_path)
    exports = subprocess.run(["x86_64-w64-mingw32-objdump", "-p", str(library)],
                             capture_output=True, text=True, check=True).stdout
    assert "bank_end_pass" in exports and "bank_begin_step" in exports
    assert "python" not in exports.lower()


FMI3 = Path(__file__).resolve().parents[1] / "fmus" / "fmi3"


def fmi3_fmus():
    if not (FMI3 / "RotaryDamper.fmu").exists():
        pytest.skip("no FMI 3.0 FMUs in fmus/fmi3: python build_fmus.py")
    return {name: FMI3 / f"{name}.fmu" for name in
            ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion", "RotaryDamper")}


def corrected_rows(parts, columns):
    """Every accepted load and every law (at 1.01 times the motion) of a corrected bank
    over 200 steps of motion()'s `columns`."""
    bank = Bank(parts, "corrected")
    bank.start(0.0, motion(0.0)[columns])
    rows = []
    try:
        for k in range(1, 201):
            t, passes = k * 1e-3, 0
            bank.begin_step(t)
            while bank.end_pass(t, motion(t, passes)[columns]).repeat:
                passes += 1
            bank.accept(t)
            rows.append(list(bank.loads) + list(bank.law_loads(1.01 * motion(t)[columns])))
    finally:
        bank.free()
    return np.array(rows)


def test_fmi3_instances_in_a_bank_give_the_fmi2_numbers(native_fmus):
    """The bank drives FMI 3.0 instances through their fmi3* functions (save, set, step,
    get, restore, the stiffness's directional derivative): the bushes' loads and laws are
    those of their FMI 2.0 versions, to the bit."""
    fmi3 = fmi3_fmus()
    names = ("radial", "torsion")
    assert np.array_equal(corrected_rows(mix(fmi3, names), [1, 2]),
                          corrected_rows(mix(native_fmus, names), [1, 2]))


def test_fmi3_dampers_and_tyres_are_linearised_in_c_with_the_fmi2_numbers(native_fmus,
                                                                          monkeypatch):
    """The linearised step of FMI 3.0 instances in C too (their Model Exchange instances
    through fmi3*: states, directional derivatives, the contact's event iteration): the
    damper's and the tyre's loads and laws are the FMI 2.0 instances', to the bit, and
    no instance is linearised in Python."""
    names, columns = ("tyre", "damper"), [0, 3]
    fmi2 = corrected_rows(mix(native_fmus, names), columns)

    def in_python(*_):
        raise AssertionError("an instance linearised in Python")

    monkeypatch.setattr(Bank, "_linearised", in_python)
    assert np.array_equal(corrected_rows(mix(fmi3_fmus(), names), columns), fmi2)


@pytest.mark.parametrize("step", [4e-3, 1e-3, 5e-4])
def test_the_station_compiled_path_gives_the_python_paths_numbers(native_fmus, monkeypatch,
                                                                   step, python_exponential):
    """The road-wheel station at 8 m/s: the compiled path gives the Python path's
    histories to the bit, with the damper linearised in C (the default) as with it
    linearised by linearised.py."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import bank_path
        import road_wheel_station as station
    finally:
        sys.path.remove(str(EXAMPLES))
    fmu_dir = Path(native_fmus["RoadWheelTyre"]).parent
    profile = station.RoadProfile(bump_start=0.2)

    def run(path):
        return station.simulate(8.0, profile, step, fmu_dir, end_time=0.15, path=path)

    python = run("python")
    compiled = run("compiled")
    real_bank = bank_path.Bank
    monkeypatch.setattr(bank_path, "Bank", lambda *a, **k: real_bank(*a, linearise="python", **k))
    exact = run("compiled")
    for key in ("hull_acceleration", "tyre_force", "damper_torque"):
        assert np.array_equal(exact[key], python[key]), key
        assert np.array_equal(compiled[key], python[key]), key


def test_the_stations_deflections_from_its_coordinates_are_its_connectors(native_fmus,
                                                                         monkeypatch):
    """The station's compiled path reads both deflections from one read of the system's
    coordinates: at every pass of a run over the bump, the bits of the tyre's compression
    and the arm's rotation from its connectors' outputs (exudyn's GetObjectOutput)."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import road_wheel_station as station
    finally:
        sys.path.remove(str(EXAMPLES))
    read, compared = station.Station._deflections, []

    def compare(self):
        deflections = read(self)
        compared.append((deflections.copy(), self._connector_deflections()))
        return deflections

    monkeypatch.setattr(station.Station, "_deflections", compare)
    profile = station.RoadProfile(bump_start=0.1)
    station.simulate(8.0, profile, 1e-3, Path(native_fmus["RoadWheelTyre"]).parent,
                     end_time=0.05)
    assert len(compared) > 50
    coordinates, connectors = map(np.array, zip(*compared))
    assert np.ptp(connectors[:, 0]) > 1e-4  # the tyre went over the bump
    assert np.array_equal(coordinates, connectors)


def test_exudyn_announces_each_next_step_to_the_bank(native_fmus, monkeypatch):
    """In exudyn the bank's accept begins the next step (exudyn's time plus its step, as
    exudyn adds them, the last cut to the end time): a C begin_step of its own only for
    the first step, and no step begun twice or begun past the end (one save per step)."""
    sys.path.insert(0, str(EXAMPLES))
    try:
        import road_wheel_station as station
    finally:
        sys.path.remove(str(EXAMPLES))
    begun = []
    real_bank = Bank.__init__

    def counting(self, *args, **kwargs):
        real_bank(self, *args, **kwargs)
        begin = self._begin
        self._begin = lambda handle: begun.append(self._call.time) or begin(handle)

    monkeypatch.setattr(Bank, "__init__", counting)
    result = station.simulate(8.0, station.RoadProfile(), 1e-3,
                              Path(native_fmus["RoadWheelTyre"]).parent, end_time=0.05)
    assert len(result["time"]) > 50
    assert begun == [pytest.approx(1e-3)]
    assert result["costs"]["saves"] == 1.0


def test_the_exudyn_cost_benchmark_runs_both_paths(native_fmus):
    """benchmarks/coupling_exudyn.py --quick: a row per run and path, each a finite CPU
    time per simulated second (its figures are the benchmark's, not a test's)."""
    script = EXAMPLES.parent / "benchmarks" / "coupling_exudyn.py"
    run = subprocess.run([sys.executable, str(script), "--quick",
                          "--fmus", str(Path(native_fmus["RotaryDamper"]).parent)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    rows = [line.split("|")[1:-1] for line in run.stdout.splitlines()
            if line.startswith("| ") and not line.startswith("| run")]
    assert [row[1].strip() for row in rows] == ["python", "compiled"] * 3
    assert all(math.isfinite(float(row[2])) for row in rows)
