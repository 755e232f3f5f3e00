"""The vehicle on its own solver (examples/vehicle/own_host.py, own_system.c; docs/vehicle.md,
The vehicle on its own solver) against the same vehicle in exudyn: the same scheme
(the vehicle's default, iterated), step (1 ms), spectral radius, Newton tolerances and full Newton, from the
stored static point over 0.02 s at 3 m/s on the bump. The two take the same Newton
iterations, and their histories agree far below Newton's tolerance (the same iterates, to
round-off). The reuse policy (the Newton matrix kept) against full Newton: their
difference falls with Newton's tolerance. The host's halving of a step whose Newton
fails, on stand-ins. The own solver is the default run, and settings it cannot run are
refused naming --solver exudyn."""

import sys

import numpy as np
import pytest

from conftest import ROOT, load_benchmark

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'
END, STEP, SPEED = 0.02, 1e-3, 3.0
TIGHT = 1e-3  # a Newton absolute tolerance 100 times the runs' (model.NEWTON_TOLERANCE)
KEYS = ("hull_vertical_acceleration", "hull_pitch_acceleration",
        "seat_vertical_acceleration", "hull_y", "tyre_force", "damper_torque",
        "bush_radial_force", "bush_torque")


@pytest.fixture(scope="module")
def runs(native_fmus):
    """{run: (histories, solver statistics)}: exudyn's, the own solver's with full Newton
    ("own") and with the reuse policy ("reuse"), at the runs' Newton tolerance and at TIGHT
    ("full tight", "reuse tight"), the reuse runs with full Newton's first laws (without
    the kink: own_host.kinked_first_laws) so that only Newton differs; and the default
    run ("kinked": the reuse policy with its kinked first laws)"""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from tracked_vehicle import simulate
    from vehicle.model import NEWTON_TOLERANCE, static_points

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    statics = static_points(fmu_dir)
    result = {}
    for name, solver, newton, tolerance in (
            ("exudyn", "exudyn", None, NEWTON_TOLERANCE), ("own", "own", "full", NEWTON_TOLERANCE),
            ("reuse", "own", "reuse", NEWTON_TOLERANCE), ("full tight", "own", "full", TIGHT),
            ("reuse tight", "own", "reuse", TIGHT), ("kinked", "own", None, NEWTON_TOLERANCE)):
        with pytest.MonkeyPatch.context() as patch:
            if name == "own":  # the adoptions of one run (test_every_pass_takes_...)
                result["adopted"] = _watch_adoptions(patch)
            if name.startswith("reuse"):
                patch.setattr("vehicle.own_host.kinked_first_laws", lambda settings: False)
            vehicle, histories, _, _ = simulate("bump", SPEED, END, STEP, statics=statics,
                                                fmu_dir=fmu_dir, solver=solver,
                                                own_newton=newton, newton_tolerance=tolerance)
        result[name] = histories, vehicle.solver_statistics()
        if name == "own":
            result["own vehicle"] = vehicle
    return result


def _watch_adoptions(patch):
    """Each adoption of the run (the own host's, at each pass's solution, in C: own_pass.c,
    or Contacts.adopt; both end in Contacts.adopted, a pass not adopted in neither):
    whether every array it took equals the contacts' own kernel's evaluation at that
    state, made afterwards."""
    from vehicle.contacts import Contacts

    adopted, taken = [], Contacts.adopted

    def watched(self, t, q, qd):
        taken(self, t, q, qd)
        views = self._compiled.views
        took = {name: view.copy() for name, view in views.items()}
        self._key = None
        self.evaluate(t, q, qd)  # the kernel's own evaluation, the same laws
        adopted.append(all(took[name].tobytes() == views[name].tobytes() for name in views))

    patch.setattr(Contacts, "adopted", watched)
    return adopted


def test_the_own_solver_takes_exudyns_steps_and_iterations(runs):
    (_, exudyn), (histories, own) = runs["exudyn"], runs["own"]
    assert len(histories["time"]) == round(END / STEP) + 1
    for statistics in (exudyn, own):
        assert statistics["steps"] == statistics["host_steps"] == round(END / STEP)
        assert statistics["refused"] == 0
    assert own["passes_per_step"] == exudyn["passes_per_step"] >= 1.0
    assert own["newton_per_pass"] == exudyn["newton_per_pass"]


def test_each_pass_takes_the_contacts_the_systems_newton_evaluated_last(runs):
    """The own host's contacts at a pass's solution are the system's last evaluation
    (Contacts.adopt: Newton evaluates last at its solution), equal to the bit to the
    contacts' own evaluation there."""
    adopted, own = runs["adopted"], runs["own"][1]
    assert len(adopted) == round(own["passes_per_step"] * own["steps"])
    assert all(adopted)


def test_the_own_solver_agrees_with_exudyn_below_newtons_tolerance(runs):
    """Every history compared to 1e-5 % of its range (measured 1.2e-7 %, the hull's
    accelerations: the same iterates, apart by the two LUs' round-off)."""
    from vehicle.outputs import largest_difference

    difference, _ = largest_difference(runs["exudyn"][0], runs["own"][0], KEYS)
    assert 0.0 < difference <= 1e-5  # not the same run twice


def test_the_reuse_policy_converges_to_full_newtons_solution(runs):
    """Newton stops each pass at a residual below its tolerance, so two runs whose Newton
    differs are apart by what that residual moves, which falls with the tolerance (the
    same discrete solution); a run that converged elsewhere would stay apart. 100 times
    tighter: the reuse run's difference from full Newton's at least 10 times smaller
    (measured 77 times; at the runs' tolerance 4e-4 % of range, as far as full Newton's
    own run is from its run at the tighter tolerance: docs/vehicle.md)."""
    from vehicle.outputs import largest_difference

    (at_tolerance, _), (tight, _) = (largest_difference(runs[a][0], runs[b][0], KEYS)
                                     for a, b in (("own", "reuse"),
                                                  ("full tight", "reuse tight")))
    assert 0.0 < tight <= 0.1 * at_tolerance
    own, reuse = runs["own"][1], runs["reuse"][1]
    assert reuse["steps"] == own["steps"] == round(END / STEP)
    assert reuse["jacobians"] < own["jacobians"]  # it kept its matrix


def test_the_kinked_first_laws_save_solves_within_the_couplings_own_error(runs):
    """The default run (the reuse policy with kinked first laws: docs/vehicle.md, "A kink
    in the first law") takes every step at its length, in fewer solves per step than the
    same policy with the straight first laws, and ends each step where the scheme's
    tolerance lets it: its hull accelerations within 0.001 % of range of full Newton's run
    (measured 1.1e-4 %, as the straight laws' reuse run; the coupling's own error is to
    stay within 0.1 %, and measured 0.002 to 0.03 % over 2 s), while its iterates differ
    from the first solve on."""
    from vehicle.outputs import largest_difference

    kinked, straight = runs["kinked"][1], runs["reuse"][1]
    assert kinked["steps"] == kinked["host_steps"] == round(END / STEP)
    assert kinked["halved"] == 0
    assert kinked["passes_per_step"] < straight["passes_per_step"]
    assert kinked["newton_per_pass"] != straight["newton_per_pass"]
    hull, _ = largest_difference(runs["own"][0], runs["kinked"][0], KEYS[:2])
    assert 0.0 < hull <= 1e-3


def test_the_step_check_judges_the_solvers_arrays_as_exudyns_data(runs):
    """StepCheck.judge (the own run's, on the solver's arrays) and StepCheck.__call__ (the
    exudyn run's, on exudyn's data) are one check: a link moved beyond its reach in one
    step refused by both in the same words, the step's own motion passed."""
    import exudyn as exu
    from vehicle.step_check import LINK_JUMP, StepCheck

    vehicle = runs["own vehicle"]
    check, data = StepCheck(vehicle), vehicle.mbs.systemData
    t, h = data.GetTime(), STEP  # the own run's last state, written there after its run
    q0, v0 = np.array(data.GetODE2Coordinates()), np.array(data.GetODE2Coordinates_t())
    q1 = q0 + h * v0
    assert check.judge(t + h, h, q1, v0, q0, v0) is None
    q1[vehicle.mbs.GetNodeODE2Index(vehicle.link_nodes[7]) + 1] += 1.5 * LINK_JUMP
    message = check.judge(t + h, h, q1, v0, q0, v0)
    assert message.startswith("link 7") and "moved 15.0 mm" in message
    start, current = exu.ConfigurationType.StartOfStep, exu.ConfigurationType.Current
    for put, values in ((data.SetODE2Coordinates, q0), (data.SetODE2Coordinates_t, v0)):
        put(values, start)
    data.SetTime(t, start)
    data.SetODE2Coordinates(q1, current)
    assert check(vehicle.mbs, t + h) == message


def test_the_passes_and_records_in_one_call_are_the_calls_one_by_one(native_fmus):
    """The own host's pass end in one C call (own_pass.c: the contacts' adoption, the step
    check, the deflections) and Records.write's (records.c, from the contacts' kernel's
    memory and the bank's arrays) give what their parts' calls one by one and numpy's
    copies give: every history of two own runs, one each way, the same bits."""
    from tracked_vehicle import simulate
    from vehicle.model import static_points
    from vehicle.outputs import Records
    from vehicle.own_host import OwnHost

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    statics, results = static_points(fmu_dir), []
    for one_by_one in (False, True):
        with pytest.MonkeyPatch.context() as patch:
            if one_by_one:
                patch.setattr(Records, "_sources", lambda self: None)
                patch.setattr(OwnHost, "_one_call", lambda self, check: None)
            vehicle, histories, _, _ = simulate("bump", 5.0, 0.005, STEP, statics=statics,
                                                fmu_dir=fmu_dir, solver="own")
        # the calls each run took
        assert (vehicle.host._one is None) == (vehicle.records._gather is None) == one_by_one
        results.append(histories)
    together, one_by_one = results
    assert len(together["time"]) == 6
    for key, values in together.items():
        if isinstance(values, np.ndarray):
            assert values.tobytes() == one_by_one[key].tobytes(), key


class _Solver:
    """A solver core whose Newton converges only on steps up to `longest`."""

    def __init__(self, longest):
        self.longest, self.restarts = longest, 0

    def step(self, h, t_new):
        return 0 if h <= self.longest * (1 + 1e-12) else 1

    def repeat(self, h, t_new, warm):
        return self.step(h, t_new)

    def restart(self):
        self.restarts += 1

    def iterations(self):
        return 1

    def state(self, block=None, at=None):
        return (np.zeros(3),) * 3


class _Bank:
    """A bank of one pass that accepts every solution."""

    class scheme:
        passes = 1

    def __init__(self):
        self.begun, self.deflection = [], np.zeros(3)

    def begin_step(self, time):
        self.begun.append(time)

    def end_pass(self, time, deflections):
        from fmu_components.coupling.master import Verdict
        return Verdict()


def _host(longest):
    """An OwnHost over the stand-ins above (no vehicle): its step's halving alone."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.own_host import OwnHost

    host = OwnHost.__new__(OwnHost)
    host.solver, host.bank = _Solver(longest), _Bank()
    host.adopt = lambda t, q, v, at: False
    host.path = type("Path", (), {"deflections": lambda self, q, v, t, **given: q})()
    host._blocks, host._blocks_at, host._free, host._row = [None] * 2, [0, 0], 0, 24
    host._one = None
    host.refused = host.halved = host.solves = host.newton = 0
    host._start = None
    host.seconds = dict(solve=0.0, bank=0.0, deflections=0.0, record=0.0, check=0.0)
    host.shortest = STEP / 64
    return host


def test_a_step_whose_newton_fails_is_halved_and_begun_again():
    host = _host(longest=STEP / 4)
    taken, end = host._step(0.01, STEP, None)
    assert taken == STEP / 4 and end == 0.01 + STEP / 4
    assert host.bank.begun == [0.01 + STEP, 0.01 + STEP / 2, 0.01 + STEP / 4]
    assert host.halved == 2 and host.solver.restarts == 2


def test_a_step_that_fails_down_to_the_floor_stops_naming_the_time():
    from vehicle.model import VehicleError

    host = _host(longest=STEP / 1000)
    with pytest.raises(VehicleError, match=r"gave up at t = 0\.0100 s.*Newton"):
        host._step(0.01, STEP, None)
    assert host.halved == 7  # the steps of 1 ms down to 1/64 of it, each failed


class _Refusing(_Solver):
    """A solver core whose Newton matrix has an entry outside its band (unknowns 120 and
    126) at every step."""

    def step(self, h, t_new):
        return 3  # alpha_solver.STATUS: an entry outside the band and the border

    def report(self):
        return {"iterations": 1, "bad_row": 120, "bad_col": 126}


def test_an_entry_outside_the_band_stops_the_run_naming_it_not_halved():
    """A structure the solver's order does not hold is no Newton failure: halving the
    step would not change it."""
    from vehicle.model import VehicleError

    host = _host(longest=STEP)
    host.solver = _Refusing(STEP)
    names = {120: "link 32's x", 126: "link 34's x"}
    host.own = type("Own", (), {"system": type("System", (), {
        "coordinate_name": staticmethod(names.get)})()})()
    with pytest.raises(VehicleError, match=r"t = 0\.0110 s.*\(link 32's x, link 34's x\) "
                                           r"outside the band and the border"):
        host._step(0.01, STEP, None)
    assert host.halved == 0 and host.solver.restarts == 0
    assert host.bank.begun == [0.01 + STEP]


class _Repeating(_Bank):
    """A bank of two passes whose first pass asks for the step again."""

    class scheme:
        passes = 2

    def end_pass(self, time, deflections):
        from fmu_components.coupling.master import Verdict
        self.passes = getattr(self, "passes", 0) + 1
        return Verdict(repeat=self.passes % 2 == 1)


def test_a_steps_effort_is_its_last_solves_iterations_and_its_solves():
    """exudyn's adaptiveStepRecoveryIterations weighs newtonSteps (the last solve's) plus
    discontinuousIteration (the solves of the step taken)."""
    host = _host(longest=STEP)
    host.bank = _Repeating()
    host._step(0.01, STEP, None)
    assert host.effort == 1 + 2  # the stand-in's one iteration per solve, two solves
    host.bank = _Bank()
    host._step(0.011, STEP, None)
    assert host.effort == 1 + 1


def _lengths(length, asked, steps):
    """The lengths StepLength gives over `steps`: (taken or None for `asked`, effort)."""
    out = []
    for taken, effort in steps:
        asked = length.next(asked, asked if taken is None else taken, effort)
        out.append(asked)
    return out


def test_a_step_halved_again_while_it_recovers_counts_its_steps_afresh():
    """exudyn sets stepsSinceLastStepSizeReduction to 0 at every shortening: a step halved
    from a recovering half step waits RECOVERY steps at its quarter."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.own_host import RECOVERY, StepLength

    length = StepLength(STEP)
    assert _lengths(length, STEP, [(STEP / 2, 2)] + [(None, 2)] * 5) == [STEP / 2] * 6
    lengths = _lengths(length, STEP / 2, [(STEP / 4, 2)] + [(None, 2)] * (RECOVERY - 1))
    assert lengths == [STEP / 4] * (RECOVERY - 1) + [STEP / 2]
    lengths = _lengths(length, STEP / 2, [(None, 2)] * RECOVERY)
    assert lengths == [STEP / 2] * (RECOVERY - 1) + [STEP]
    assert _lengths(length, STEP, [(None, 2)] * 3) == [STEP] * 3


def test_a_recovering_step_of_many_iterations_is_not_doubled():
    """exudyn doubles only after a step of at most adaptiveStepRecoveryIterations (its
    last solve's Newton iterations plus its solves); the count goes on until one."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.own_host import RECOVERY, RECOVERY_ITERATIONS, StepLength

    length = StepLength(STEP)
    many, few = RECOVERY_ITERATIONS + 1, RECOVERY_ITERATIONS
    steps = ([(STEP / 2, few)] + [(None, few)] * (RECOVERY - 2) + [(None, many)] * 2
             + [(None, few)])
    assert _lengths(length, STEP, steps) == [STEP / 2] * (RECOVERY + 1) + [STEP]


def test_the_largest_difference_of_equal_histories_is_zero():
    """Two runs the same bits (a comparison's window before they part) give 0; else the
    key with the largest share of its range."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.outputs import largest_difference

    run = {"time": np.arange(3.0), "a": np.array([0.0, 2.0, 4.0]),
           "b": np.array([[1.0, 0.0], [3.0, 0.0], [5.0, 0.0]])}
    assert largest_difference(run, dict(run), ("a", "b")) == (0.0, "a")
    other = {**run, "b": run["b"] + [[0.0, 0.0], [0.0, 0.5], [0.0, 0.0]]}
    assert largest_difference(run, other, ("a", "b")) == (0.5 / 5.0 * 100, "b")


def _exudyns_step_lengths():
    """exudyn's own adaptive step on a spring-mass of one coordinate, its post-Newton
    function shortening some steps (a recommended half step, as the step check's and the
    coupling's retries) and solving others in 6 passes: per accepted step, the length its
    first try asked, the length taken, and its newtonSteps + discontinuousIteration."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from exudyn.itemInterface import NodeGenericODE2, ObjectGenericODE2

    mbs = exu.SystemContainer().AddSystem()
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0], initialCoordinates=[0.01],
                                       initialCoordinates_t=[0.0], numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=np.eye(1),
                                    stiffnessMatrix=np.eye(1) * 1e4))
    mbs.Assemble()
    shorten, repeat = {4, 7, 29, 32, 33, 49}, {57, 58, 59}  # accepted steps before
    steps, state = [], dict(passes=0, asked=None, shortened=set())

    def it():
        return mbs.sys["dynamicSolver"].it

    def pre_step(mbs, t):
        state["passes"] = 0
        if state["asked"] is None:
            state["asked"] = it().currentStepSize
        return True

    def post_newton(mbs, t):
        state["passes"] += 1
        k = len(steps)
        if k in shorten and k not in state["shortened"]:
            state["shortened"].add(k)
            return [1.0, 0.5 * it().currentStepSize]
        return [1.0 if k in repeat and state["passes"] < 6 else 0.0, -1.0]

    def post_step(mbs, t):
        if state["asked"] is not None:  # not the initial state's
            now = it()
            steps.append((state["asked"], now.currentStepSize,
                          now.newtonSteps + now.discontinuousIteration))
            state["asked"] = None
        return True

    mbs.SetPreStepUserFunction(pre_step)
    mbs.SetPostNewtonUserFunction(post_newton)
    mbs.SetPostStepUserFunction(post_step)
    settings = exu.SimulationSettings()
    settings.timeIntegration.numberOfSteps, settings.timeIntegration.endTime = 90, 90 * STEP
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.timeIntegration.adaptiveStep = True
    discontinuous = settings.timeIntegration.discontinuous
    discontinuous.iterationTolerance, discontinuous.maxIterations = 0.5, 8
    discontinuous.ignoreMaxIterations = True
    mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    return steps


def test_the_step_lengths_are_exudyns_adaptive_steps():
    """StepLength, given each of exudyn's accepted steps, asks the length exudyn's next
    step asked first; the run shortens a recovering step again, and solves recovered steps
    with more than RECOVERY_ITERATIONS."""
    from vehicle.own_host import RECOVERY_ITERATIONS, StepLength

    steps = _exudyns_step_lengths()
    assert min(taken for _, taken, _ in steps) == STEP / 8
    assert max(effort for *_, effort in steps) > RECOVERY_ITERATIONS
    length = StepLength(STEP)
    for (asked, taken, effort), (following, _, _) in zip(steps[:-2], steps[1:-1]):
        assert length.next(asked, taken, effort) == pytest.approx(following, rel=1e-12)


@pytest.mark.parametrize("argv, named", [
    (["--path", "python"], "--path python: the own solver runs the coupling's compiled path"),
    (["--joints", "connectors"], "--joints connectors: the own solver takes the track's joints"),
    (["--coupling", "predicted"], "--coupling predicted (a scheme the bank does not have)")])
def test_where_the_own_solver_cannot_run_the_default_run_is_refused_naming_the_flag(
        argv, named, capsys):
    """The default run is the own solver's: given settings it cannot run (the Python
    path, the joints as connectors, a scheme the bank lacks), the command line stops
    before the build naming the setting and --solver exudyn, and simulate raises naming
    solver='exudyn', both with own_refusal's reason; the defaults are the own solver's."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    import tracked_vehicle
    from vehicle.model import VehicleError

    with pytest.raises(SystemExit) as stop:
        tracked_vehicle.main(argv)
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert named in err and "add --solver exudyn" in err
    given = dict(zip((a.lstrip("-") for a in argv[::2]), argv[1::2]))
    with pytest.raises(VehicleError, match=r"solver='exudyn' \(--solver exudyn\)"):
        tracked_vehicle.simulate("bump", 3.0, 0.001, 1e-3, given.get("coupling", "iterated"),
                                 path=given.get("path", "compiled"),
                                 joints=given.get("joints", "kernel"))
    assert tracked_vehicle.own_refusal(given.get("path", "compiled"),
                                       given.get("coupling", "iterated"),
                                       given.get("joints", "kernel")) in err
    assert tracked_vehicle.own_refusal() is None  # the defaults: the own solver runs


def test_only_a_scheme_that_always_solves_again_with_a_kept_matrix_solves_first_roughly():
    """own_host.first_pass_tolerance: FIRST_PASS_LOOSENESS times Newton's tolerance for
    iterated (its first solve never ends a step) with the policies that keep a matrix; the
    full tolerance (0) for full Newton (exudyn's iterates), for the schemes whose first
    solve may end a step, and without a bank."""
    from fmu_components.coupling.schemes import scheme_named
    from vehicle.own_host import FIRST_PASS_LOOSENESS, NEWTON, first_pass_tolerance

    iterated = scheme_named("iterated")
    for name in ("reuse", "chord"):
        assert first_pass_tolerance(iterated, NEWTON[name], 0.1) == FIRST_PASS_LOOSENESS * 0.1
    assert first_pass_tolerance(iterated, NEWTON["full"], 0.1) == 0.0
    for name in ("explicit", "corrected", "converged"):
        assert first_pass_tolerance(scheme_named(name), NEWTON["reuse"], 0.1) == 0.0
    assert first_pass_tolerance(None, NEWTON["reuse"], 0.1) == 0.0


def test_the_passes_benchmark_records_the_banks_own_mismatch(native_fmus):
    """benchmarks/vehicle_passes.py over 10 steps: every step's passes recorded (at least
    the two `iterated` takes), each pass's instances' mismatches, whose worst is the
    bank's verdict's to the bit; a step ended before the pass limit by a pass within the
    tolerance, and past the least passes only after one above it; and its table printed."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    passes = load_benchmark("vehicle_passes")
    vehicle, steps, tolerance = passes.recorded_run("bump", 5.0, 0.01, straight=False)
    assert len(steps) == 10 and tolerance > 0.0
    scheme = vehicle.coupling.scheme
    for step in steps:
        assert len(step) >= scheme.least_passes >= 2
        for mismatch, worst in step:
            assert mismatch.shape == (vehicle.instances,) and mismatch.max() == worst
        if len(step) < scheme.passes:
            assert step[-1][1] <= tolerance
        if len(step) > scheme.least_passes:
            assert step[-2][1] > tolerance
    passes.table(vehicle, steps, tolerance)


def test_the_own_benchmark_runs_every_course_in_every_round_and_prints_medians(
        native_fmus, capsys):
    """benchmarks/vehicle_own.py over 5 steps, two courses in two rounds: each round runs
    both courses, and the table's median and range are those of the runs it printed."""
    import re

    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    benchmark = load_benchmark("vehicle_own")
    benchmark.main(["--speeds", "3", "--end-time", "0.005", "--rounds", "2", "--no-exudyn",
                    "--course", "bump", "sine"])
    out = capsys.readouterr().out
    runs = re.findall(r"^(\w+), 3 m/s round (\d) reuse iterated: ([\d.]+) s CPU", out, re.M)
    assert [(course, int(number)) for course, number, _ in runs] == [
        ("bump", 1), ("sine", 1), ("bump", 2), ("sine", 2)]
    for course in ("bump", "sine"):
        cpu = sorted(float(figure) for name, _, figure in runs if name == course)
        row = re.search(rf"^\| {course} \| 3 m/s \| reuse \| iterated \| ([\d.]+) \| "
                        rf"([\d.]+)-([\d.]+) \| ([\d.]+) \|$", out, re.M)
        assert row is not None, out
        median, low, high, pace = map(float, row.groups())
        # the printed figures are rounded to 0.01: the median of two is their mean
        assert abs(median - (cpu[0] + cpu[1]) / 2) <= 0.011
        assert (low, high) == (cpu[0], cpu[1]) and pace > 0.0
