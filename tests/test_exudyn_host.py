"""The coupling in exudyn (src/fmu_components/coupling/exudyn_host.py): where the settings
give Newton an absolute tolerance, a step's second pass starts from the first pass's
solution. Needs the `examples` extra (exudyn); without it skipped with that reason."""

import math

import numpy as np
import pytest

from fmu_components.coupling import Coupling, FmuComponent

exudyn = pytest.importorskip("exudyn", reason='exudyn is not installed: pip install -e '
                                              '".[examples]"')

# a light mass (a wheel's share) pressed onto the tyre by a load about a half-wheel's
# static one (section 5.1.1), so that the springs' stiffness is comparable with the mass's
# term in exudyn's Newton matrix at 1 ms, and the cube's curvature matters
MASS, LOAD = 10.0, 9.81e3  # kg, N


def quarter_wheel(fmu, settings, step=1e-4, scheme="corrected", step_check=None):
    """A mass on a RoadWheelTyre, released off its static point, the ground beneath it a
    2 mm, 15 Hz sine; 30 steps of `scheme` (`step_check`: exudyn_host.solve's); returns
    ((pass, Newton iterations) of every pass, the mass's accelerations)."""
    from exudyn.itemInterface import (LoadCoordinate, MarkerNodeCoordinate, NodeGenericODE2,
                                      NodePointGround, ObjectConnectorCoordinateSpringDamper,
                                      ObjectGenericODE2)

    from fmu_components.coupling.exudyn_host import connector_state, solve

    mbs = exudyn.SystemContainer().AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    # the mass's height: the tyre compressed by its static 3.1 mm at the start
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0],
                                       initialCoordinates=[-3.1e-3],
                                       initialCoordinates_t=[0.0], numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=[[MASS]],
                                    stiffnessMatrix=[[0.0]], dampingMatrix=[[0.0]]))
    road = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    body = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    mbs.AddLoad(LoadCoordinate(markerNumber=body, load=-LOAD))
    tyre = FmuComponent(fmu, "tyre", unilateral=True)

    def compression(u, v, t):
        # the ground's height minus the mass's: u is the mass's coordinate less the
        # ground marker's (zero)
        return (2e-3 * math.sin(2 * math.pi * 15.0 * t) - u,
                2e-3 * 2 * math.pi * 15.0 * math.cos(2 * math.pi * 15.0 * t) - v)

    connector = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
        markerNumbers=[road, body],
        springForceUserFunction=lambda mbs, t, item, u, v, *_:
            -tyre.host_load(*compression(u, v, t))))
    # and a hardening spring beside it (a suspension's bump stop, 10 kN at 3 mm), whose
    # cube takes exudyn's Newton several iterations from its predictor
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
        markerNumbers=[road, body],
        springForceUserFunction=lambda mbs, t, item, u, v, *_: 1e4 * (u / 3e-3) ** 3))
    accelerations = []
    coupling = Coupling(scheme, record=lambda t: accelerations.append(
        float(mbs.GetNodeOutput(node, exudyn.OutputVariableType.Coordinates_tt))))
    coupling.add(tyre, lambda: compression(*(float(x) for x in connector_state(mbs, connector)),
                                           mbs.systemData.GetTime()))
    mbs.Assemble()
    iterations = []
    end_pass = coupling.end_pass

    def counted(t):
        solver = mbs.sys["dynamicSolver"].it
        iterations.append((solver.discontinuousIteration, solver.newtonSteps))
        return end_pass(t)

    coupling.end_pass = counted
    solve(mbs, coupling, 30 * step, step, settings=settings, step_check=step_check)
    return np.array(iterations), np.array(accelerations)


def settings(absolute_tolerance=None):
    settings = exudyn.SimulationSettings()
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.active = False
    settings.timeIntegration.newton.useModifiedNewton = False
    if absolute_tolerance is not None:
        settings.timeIntegration.newton.absoluteTolerance = absolute_tolerance
    return settings


def test_a_steps_second_pass_starts_from_the_first_passs_solution(native_fmus):
    """With an absolute tolerance (1e-6 N, 1e-10 of the load), each step's second pass
    starts where the first ended and converges in one Newton iteration where the first
    takes two; from exudyn's predictor (no absolute tolerance: the relative test alone,
    as before) it takes as many as the first. Both runs give the same accelerations, to
    what the tolerances allow."""
    fmu = native_fmus["RoadWheelTyre"]
    warm, warm_accelerations = quarter_wheel(fmu, settings(1e-6))
    cold, cold_accelerations = quarter_wheel(fmu, settings())
    for passes in (warm, cold):
        assert np.sum(passes[:, 0] == 0) == np.sum(passes[:, 0] == 1) == 30
    first, second = (warm[warm[:, 0] == p, 1] for p in (0, 1))
    assert np.all(second == 1) and np.all(first >= 2)
    assert np.all(cold[cold[:, 0] == 1, 1] >= 2)
    scale = np.ptp(cold_accelerations)
    assert scale > 100.0  # the mass moves (m/s2)
    assert np.max(np.abs(warm_accelerations - cold_accelerations)) < 1e-6 * scale


def test_exudyn_calls_the_warm_start_in_a_steps_repeated_passes_only(native_fmus, monkeypatch):
    """exudyn calls the pre-Newton-residual function before every residual of every solve
    where it is set: it is set for a step's repeated pass alone, and never for a scheme
    that does not repeat a step."""
    from fmu_components.coupling.exudyn_host import ExudynCoupling

    calls = []
    warm_start = ExudynCoupling._pre_newton_residual

    def counted(self, mbs, t, newton_iteration, discontinuous_iteration):
        calls.append(discontinuous_iteration)
        warm_start(self, mbs, t, newton_iteration, discontinuous_iteration)

    monkeypatch.setattr(ExudynCoupling, "_pre_newton_residual", counted)
    passes, _ = quarter_wheel(native_fmus["RoadWheelTyre"], settings(1e-6))
    # one call before each residual of the 30 second passes: the first, and one per
    # Newton iteration
    assert sorted(set(calls)) == [1]
    assert len(calls) == np.sum(passes[passes[:, 0] == 1, 1] + 1)
    calls.clear()
    passes, _ = quarter_wheel(native_fmus["RoadWheelTyre"], settings(1e-6), scheme="explicit")
    assert len(passes) == 30 and calls == []


def test_the_newton_tolerance_benchmark_prints_both_tables():
    """benchmarks/coupling_newton.py --quick: for each example a row for exudyn's default
    and one per tolerance, each with its iteration counts, fewer in the warm-started
    second solve (its other figures are the benchmark's, not a test's)."""
    import subprocess
    import sys
    from pathlib import Path

    script = Path(__file__).resolve().parents[1] / "benchmarks" / "coupling_newton.py"
    run = subprocess.run([sys.executable, str(script), "--quick", "--tolerances", "0.1"],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stderr
    rows = [line.split("|")[1:-1] for line in run.stdout.splitlines()
            if line.startswith("| ") and not line.startswith("| Newton")]
    assert [row[0].strip() for row in rows] == ["default", "0.1"] * 2
    for row in rows:
        first, second = (float(x) for x in row[-1].split("/"))
        assert first >= 1.0 and second >= 1.0
        if row[0].strip() != "default":  # the second solve starts from the first's end
            assert second < first


def _steps_judged(refuse):
    """A step check that refuses the solutions `refuse(start, end)` names, recording the
    (start, end) of every solve it judged."""
    judged = []

    def check(mbs, t):
        start = mbs.systemData.GetTime(exudyn.ConfigurationType.StartOfStep)
        judged.append((start, t))
        return "the mass jumped" if refuse(start, t) else None
    return check, judged


def test_a_step_whose_solution_jumps_is_refused_and_retried_shorter(native_fmus):
    """The host's step check refuses every solution of a step across t = 1.05 ms longer
    than a quarter of the host step (0.1 ms): that step is solved again from its start at
    half its length, twice, and the run goes on to its end, the FMU's trials of the
    refused solves undone."""
    check, judged = _steps_judged(lambda start, end: start < 1.05e-3 < end
                                  and end - start > 0.26e-4)
    _, accelerations = quarter_wheel(native_fmus["RoadWheelTyre"], settings(), step_check=check)
    crossing = [(start, end) for start, end in judged if start < 1.05e-3 < end]
    lengths = sorted({round((end - start) * 1e7) for start, end in crossing}, reverse=True)
    assert lengths == [1000, 500, 250]  # 0.1, 0.05, 0.025 ms (in 0.1 us)
    assert judged[-1][1] == pytest.approx(3e-3)
    assert len(accelerations) > 31 and np.all(np.isfinite(accelerations))


def test_a_step_refused_at_the_shortest_step_ends_the_solve(native_fmus):
    """A solution refused however short the step (down to 1/64 of the host step) ends the
    solve with what jumped and the time."""
    from fmu_components.coupling import StepRefused

    check, judged = _steps_judged(lambda start, end: end > 1.07e-3)
    with pytest.raises(StepRefused, match=r"the mass jumped at t = 0\.0011 s, on steps "
                                          r"down to 1\.56e-06 s"):
        quarter_wheel(native_fmus["RoadWheelTyre"], settings(), step_check=check)
    assert min(end - start for start, end in judged) == pytest.approx(1e-4 / 64)
