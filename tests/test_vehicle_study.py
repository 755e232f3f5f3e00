"""The vehicle's accuracy study (benchmarks/vehicle_study.py): it compares two runs at
the times both reached, never across different step sequences by interpolation, and
lets exudyn's Newton iterate long enough that a step is not halved in one run only. The
study itself is a benchmark; these check its comparison on made-up histories."""

import numpy as np
import pytest

from conftest import load_benchmark

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'


@pytest.fixture(scope="module")
def study():
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    return load_benchmark("vehicle_study")


def history(times, signal):
    times = np.asarray(times, dtype=float)
    return {"time": times, "hull_vertical_acceleration": signal(times),
            "tyre_force": np.stack([signal(times), 2 * signal(times)], axis=1)}


def oscillation(t):
    # about the link-passing frequency at 5 m/s (33 Hz) and a tenth of a millisecond
    # wide features, which a 1 ms history interpolated onto 0.5 ms times misses
    return np.sin(2 * np.pi * 33 * t) + 0.5 * np.sin(2 * np.pi * 700 * t)


def test_the_same_motion_on_a_halved_step_sequence_differs_by_nothing(study):
    """One run took 1 ms steps, the other halved some (exudyn does where its Newton
    fails): where both reached the same time with the same value, there is no error,
    whatever the values between."""
    microseconds = np.arange(0, 50_001, 1000)
    coarse = history(microseconds / 1e6, oscillation)
    halved = np.concatenate([microseconds[microseconds < 30_000],
                             np.arange(30_000, 50_001, 500)])
    fine = history(halved / 1e6, oscillation)
    error, _ = study.difference(coarse, fine)
    assert error == 0.0
    assert study.difference(coarse, fine, "tyre_force")[0] == 0.0
    assert study.parting(coarse, fine) == pytest.approx(0.0305)
    assert study.parting(coarse, coarse) is None


def test_a_difference_is_found_where_and_in_the_units_it_is(study):
    reference = history(np.arange(0, 0.0505, 1e-3), oscillation)
    run = {key: np.array(value, dtype=float) for key, value in reference.items()}
    span = np.ptp(reference["hull_vertical_acceleration"])
    run["hull_vertical_acceleration"][20] += 0.01 * span  # 1 % of the range at 20 ms
    run["tyre_force"][30, 1] += 0.02 * np.ptp(reference["tyre_force"][:, 1])
    error, at = study.difference(run, reference)
    assert error == pytest.approx(1.0)
    assert at == pytest.approx(0.020)
    windows = dict(study.by_window(run, reference, 0.01))
    assert windows[0.02] == pytest.approx(1.0)
    assert windows[0.0] == windows[0.03] == 0.0
    # each instance in % of its own range: the second wheel's 2 %
    assert study.difference(run, reference, "tyre_force") == (pytest.approx(2.0),
                                                              pytest.approx(0.030))


def test_the_study_lets_newton_iterate_longer_than_exudyns_default(study):
    settings = study.newton_limit(100)()
    assert settings.timeIntegration.newton.maxIterations == 100
    assert study.model.run_settings().timeIntegration.newton.maxIterations == 25
    # the own solver's too, in each of its Newton policies
    from vehicle.alpha_solver import Settings
    policies = study.own_newton_limit(100)
    assert set(policies) == set(study.own_host.NEWTON)
    for name, policy in policies.items():
        assert Settings(**policy).max_iterations == 100
        assert Settings(**study.own_host.NEWTON[name]).max_iterations == 25


def test_the_study_runs_on_the_own_solver_by_default(study, capsys):
    """The default study's runs are the own solver's (tracked_vehicle's default);
    --solver exudyn reaches them; the Python path is refused on the own solver naming
    --solver exudyn."""
    assert study.parse([]).solver == "own"
    assert study.parse(["--solver", "exudyn"]).solver == "exudyn"
    with pytest.raises(SystemExit):
        study.parse(["--path", "python"])
    err = capsys.readouterr().err
    assert "--path python" in err and "add --solver exudyn" in err


def test_the_study_runs_with_the_solver_settings_it_is_given(study, monkeypatch):
    """--spectral-radius and --newton-tolerance reach every run; --spread runs `converged`
    to its tolerance, and leaves the scheme's own tolerance as it was after."""
    asked = []

    def simulate(*args, **settings):
        asked.append((args[4], study.Converged().tolerance, settings))
        raise study.model.VehicleError("stopped here")

    monkeypatch.setattr(study, "simulate", simulate)
    own = study.Converged.tolerance
    args = study.parse(["--spectral-radius", "0.3", "--newton-tolerance", "0.01",
                        "--spread", "1e-6"])
    assert study.run(args, 5e-4, "corrected", None) is None
    assert study.run(args, 5e-4, "converged", None, args.spread) is None
    for scheme, tolerance, settings in asked:
        assert settings["spectral_radius"] == 0.3
        assert settings["newton_tolerance"] == 0.01
        assert settings["solver"] == "own"  # the default
    assert [(scheme, tolerance) for scheme, tolerance, _ in asked] == [
        ("corrected", own), ("converged", 1e-6)]
    assert study.Converged.tolerance == own
    defaults = study.parse([])
    assert defaults.spectral_radius == study.model.SPECTRAL_RADIUS
    assert defaults.newton_tolerance == study.model.NEWTON_TOLERANCE
    assert defaults.spread is None


@pytest.mark.parametrize("argv", [["--spread", "0"], ["--newton-tolerance", "0"],
                                  ["--spectral-radius", "1.5"]])
def test_the_study_refuses_settings_that_make_no_run(study, argv):
    with pytest.raises(SystemExit):
        study.parse(argv)


def test_the_spread_column_compares_the_third_run_with_converged(study):
    reference = history(np.arange(0, 0.0505, 1e-3), oscillation)
    moved = {key: np.array(value, dtype=float) for key, value in reference.items()}
    moved["hull_vertical_acceleration"][10] += 0.003 * np.ptp(
        reference["hull_vertical_acceleration"])
    assert study.spread((None, reference, moved), study.KEY) == "0.3"
    assert study.spread((None, reference), study.KEY) == "-"
    assert study.spread((None, None, moved), study.KEY) == "-"


class Check:
    """A stand-in for the vehicle's step check: refuses what `jumps` names."""

    def __init__(self, jumps=()):
        self.jumps = jumps

    def judge(self, t, h, *state):
        return "jumped" if round(t * 1e6) in self.jumps else None


def test_same_steps_refuses_a_step_over_a_time_the_followed_run_reached(study):
    # the followed run halved its steps from 30 to 32 ms; a step from s to t is judged as
    # either host asks (t, its length)
    followed = np.array([0.0, 0.029, 0.030, 0.0305, 0.031, 0.0315, 0.032, 0.033])
    check = study.same_steps(followed, Check)().judge
    assert check(0.029, 0.029 - 0.028) is None
    assert check(0.0305, 0.0305 - 0.030) is None
    assert check(0.033, 0.033 - 0.032) is None
    assert "passes over 30.5000 ms" in check(0.031, 0.031 - 0.030)
    assert "passes over 31.0000 ms" in check(0.032, 0.032 - 0.0305)
    # a shorter step than the followed run's goes (the steps part; the study says where)
    assert check(0.0325, 0.0325 - 0.032) is None
    # the step check's own refusal stands where the followed run went on
    assert study.same_steps(followed, Check)(jumps={29000}).judge(0.029, 0.001) == "jumped"


def test_same_steps_reaches_exudyns_hook_through_judge(study):
    """exudyn's hook (StepCheck.__call__) judges the step from its start in exudyn's
    data: the same-steps check refuses there too."""
    state = np.zeros(3)

    class Hook(Check):
        __call__ = study.step_check.StepCheck.__call__

    class Data:
        def __init__(self, start):
            self.start = start
            self.systemData = self

        def GetTime(self, configuration):
            return self.start

        def GetODE2Coordinates(self, configuration=None):
            return state

        GetODE2Coordinates_t = GetODE2Coordinates

    check = study.same_steps(np.array([0.0, 0.030, 0.0305, 0.031]), Hook)()
    assert "passes over 30.5000 ms" in check(Data(0.030), 0.031)
    assert check(Data(0.030), 0.0305) is None


def test_the_same_steps_flag_reaches_the_converged_run_only(study, monkeypatch):
    """--same-steps: the converged run is solved with the check that follows the default
    run's times, the default run with the vehicle's own; the check is put back after."""
    own = study.step_check.StepCheck
    monkeypatch.setattr(study.model, "run_settings", study.model.run_settings)
    monkeypatch.setattr(study.own_host, "NEWTON", study.own_host.NEWTON)
    monkeypatch.setattr(study.model, "static_points", lambda: None)
    checks = {}
    times = np.arange(0, 0.0505, 1e-3)

    def run(args, step, scheme, statics):
        checks[scheme] = study.step_check.StepCheck
        checks["course"] = args.course
        made = history(times, oscillation)
        made.update({key: made["tyre_force"] for key in study.LOADS.values()})
        return {**made, "cpu": 1.0, "unconverged": 0, "steps": 50,
                "newton_per_pass": 3.0, "passes_per_step": 2.0}

    monkeypatch.setattr(study, "run", run)
    study.main(["--same-steps", "--course", "sine"])
    assert checks[study.model.COUPLING] is own and checks["course"] == "sine"
    assert checks["converged"] is not own and issubclass(checks["converged"], own)
    assert study.step_check.StepCheck is own
    study.main(["--course", "random"])
    assert checks["converged"] is own and checks["course"] == "random"
