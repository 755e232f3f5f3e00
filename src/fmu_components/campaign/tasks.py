"""The tasks a campaign's workers run: each a plain function of its arguments, which carry
the FMUs and any example code as payloads (``payload``), so that a worker needs none of
the client's files. Each returns what the client turns into one row of the results table.
"""

import dataclasses
import importlib
import sys
import time
from pathlib import Path


# --- the thesis test programme (fmu-components verify) --------------------------------------

def verify_case(case, fmu, tables, identity):
    """One case through one FMU against its reference (``verification.verify.run_case``):
    an Outcome. tables: the case's (inputs, reference, options), None for an own part."""
    from ..verification.verify import run_case

    return run_case(case, fmu, identity=identity, tables=tables)


def verify_and_draw_case(case, fmu, tables, identity):
    """``verify_case`` and the case's plot for the report, drawn here, where the case ran:
    (Outcome, PNG bytes or None)."""
    from ..verification.report import case_png

    outcome = verify_case(case, fmu, tables, identity)
    return outcome, case_png(outcome)


def verify_row(outcome):
    return {"run": f"{outcome.name}/{outcome.case.name}", "fmu": outcome.name,
            "case": outcome.case.name, "passed": outcome.passed,
            "strict_error_percent": outcome.strict_error if outcome.errors else None,
            "worst_output": outcome.worst_output,
            "outside_band": outcome.outliers, "problem": outcome.problem,
            "wall_s": outcome.wall_time}


# --- the measurements (fmu-components validate) ---------------------------------------------

def validate_case(case, fmu, outputs):
    """One case of the validation through its component's FMU: (fmpy's result, wall s)."""
    from ..verification.cases import simulate_case

    return simulate_case(fmu, case.inputs(), case.options(), outputs, label=case.key)


def validate_row(result, wall):
    """The case's row: its samples, each output's range over the run, the wall time."""
    row = {"samples": len(result)}
    for name in result.dtype.names[1:]:
        row[f"{name}_min"], row[f"{name}_max"] = float(result[name].min()), float(result[name].max())
    return {**row, "wall_s": wall}


# --- the fit (fmu-components fit) ------------------------------------------------------------

# s: a task's share of a Jacobian's evaluations at least this long, or the columns stay
# with their start. Measured (benchmarks/campaign.py, 2 workers against one process, a
# loaded 2-core machine): the radial bush's 14 columns over 2 x 2001 samples (3 ms an
# evaluation) ran 0.71 times as fast, over 2 x 20001 samples 0.45 times: the tasks'
# transport and the client's own evaluations cost more than a share of 0.02 or 0.2 s.
COLUMNS_PAY = 1.0


def fit_runner(engine, say=None, pays=COLUMNS_PAY):
    """``lab.fit.fit``'s runner, at the grain that pays on the engine's workers. By default
    each start's whole fit is a task (the measured tests travel inside the problem):
    hundreds of residual evaluations, no task per evaluation. With more workers than
    starts and an evaluation so costly that a worker's share of a Jacobian's columns
    takes `pays` seconds or more (one evaluation timed here first), the starts run side by
    side from here and each finite-difference Jacobian's columns go to the workers as a
    batch of tasks (``jacobian_columns``). Either way the numbers are the serial fit's:
    the same evaluations, the same arithmetic. A start that fails ends the fit with its
    message. say(text) hears which grain was taken."""
    from ..lab.fit import solve_start
    from .engine import Failure, Progress

    def run(problem, points):
        starts = len(points)
        engine.start()
        chunks = engine.workers // starts if engine.client is not None else 0
        if chunks > 1:
            started = time.perf_counter()
            problem.residuals(points[0])
            share = (time.perf_counter() - started) * -(-len(problem.free) // chunks)
            chunks = chunks if share >= pays else 0
        progress = Progress(starts, what=f"fitting from {starts} start{'s' if starts > 1 else ''}")
        try:
            if chunks > 1:
                if say is not None:
                    say(f"each Jacobian's {len(problem.free)} columns in {chunks} tasks "
                        f"per start")
                outcomes = _starts_here(problem, points, jacobian_columns(engine, chunks),
                                        progress)
            else:
                outcomes = [None] * starts
                for index, outcome in engine.stream(solve_start, [(problem, p) for p in points]):
                    if isinstance(outcome, Failure):
                        raise RuntimeError(f"the fit from start {index + 1}: {outcome.message}")
                    outcomes[index] = outcome
                    progress.update(f"start {index + 1}")
        finally:
            progress.close()
        return outcomes
    return run


def _starts_here(problem, points, columns, progress):
    """Every start's fit in a thread of this process (its Jacobians' columns on the
    engine; the native simulation releases the GIL): the outcomes in order."""
    from concurrent.futures import ThreadPoolExecutor, as_completed

    from ..lab.fit import solve_start

    with ThreadPoolExecutor(len(points)) as pool:
        futures = {pool.submit(solve_start, problem, p, columns): i for i, p in enumerate(points)}
        outcomes = [None] * len(points)
        for future in as_completed(futures):
            index = futures[future]
            try:
                outcomes[index] = future.result()
            except Exception as error:
                raise RuntimeError(f"the fit from start {index + 1}: {type(error).__name__}: "
                                   f"{error}") from None
            progress.update(f"start {index + 1}")
    return outcomes


def evaluations(function, points):
    """function at each point: one task's share of a Jacobian's columns."""
    return [function(point) for point in points]


def jacobian_columns(engine, chunks):
    """A map-like callable for scipy's least_squares (``workers``): the points of a
    finite-difference Jacobian in `chunks` tasks on the engine, each evaluating its
    consecutive share; the values in the points' order."""
    from .engine import Failure

    def columns(function, points):
        points = list(points)
        size = -(-len(points) // chunks)
        shares = [points[i:i + size] for i in range(0, len(points), size)]
        values = []
        for result in engine.map(evaluations, [(function, share) for share in shares]):
            if isinstance(result, Failure):
                raise RuntimeError(f"a Jacobian's columns: {result.message}")
            values += result
        return values
    return columns


# --- the virtual test rig (fmu-components rig) -----------------------------------------------

def rig_point(setup, point, options):
    """One rig point to periodic steady state (``lab.rig.run_point``): a RigRow."""
    from ..lab.rig import run_point

    return run_point(setup, *point, **options)


def rig_runner(engine):
    """``lab.rig.run_rig``'s runner: the points on the engine, the FMU of an FMU engine
    travelling with them; a point that fails is a RigError naming it, once the others
    are done."""
    from ..lab.rig import RigError
    from .engine import Failure
    from .payload import Payload

    def run(tasks):
        travelling = {}
        tasks = [(dataclasses.replace(setup, fmu=travelling.setdefault(
            setup.fmu, Payload.of(setup.fmu))) if setup.fmu else setup, point, options)
            for setup, point, options in tasks]
        rows = engine.map(rig_point, tasks)
        for (_, point, _), row in zip(tasks, rows):
            if isinstance(row, Failure):
                raise RigError(f"preload {point[0]:g}, amplitude {point[1]:g}, frequency "
                               f"{point[2]:g} Hz: {row.message}")
        return rows
    return run


def structures_runner(engine):
    """``lab.rig_plots.compare_structures``' runner: each structure's records a task on the
    engine; one that fails is a RigError naming it."""
    from ..lab.rig import RigError
    from ..lab.rig_plots import structure_records
    from .engine import Failure

    def run(structures):
        results = engine.map(structure_records, [(s,) for s in structures])
        for structure, result in zip(structures, results):
            if isinstance(result, Failure):
                raise RigError(f"the {structure} structure: {result.message}")
        return results
    return run


def rig_row(run, row, wall):
    values = dataclasses.asdict(row)
    return {"run": run, **values, "wall_s": wall}


def timed(function, *arguments):
    """(function's result, wall seconds)."""
    started = time.perf_counter()
    result = function(*arguments)
    return result, time.perf_counter() - started


def timed_rig_point(setup, point, options):
    return timed(rig_point, setup, point, options)


# --- the multibody examples (examples/) -----------------------------------------------------

def _example(folder, module):
    """A module of the examples folder the task carried (its local copy)."""
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module(module)


def station_run(examples, fmus, speed, course, parameters, end_time, step):
    """The road-wheel station (examples/road_wheel_station.py) at `speed` (m/s) over
    `course` (RoadProfile's arguments), its FMUs with `parameters` (by FMU name): its
    figures (peaks) and the wall time."""
    station = _example(examples, "road_wheel_station")
    started = time.perf_counter()
    profile = station.RoadProfile(**course)
    result = station.simulate(speed, profile, step, Path(fmus), end_time=end_time,
                              parameters=parameters)
    found = station.peaks(result, ripple_from=profile.end / speed + station.RIPPLE_DELAY)
    found["simulated_time"] = float(result["time"][-1])
    found["wall_s"] = time.perf_counter() - started
    return found


def vehicle_run(examples, fmus, speed, course, end_time, step):
    """The tracked vehicle (examples/tracked_vehicle.py) at `speed` (m/s) on the course
    named `course`: its figures and the wall time."""
    vehicle = _example(examples, "tracked_vehicle")
    outputs = _example(examples, "vehicle.outputs")
    started = time.perf_counter()
    _, result, _, _ = vehicle.simulate(course, speed, end_time, step, fmu_dir=Path(fmus))
    found = outputs.figures(result)
    found["simulated_time"] = float(result["time"][-1] - result["time"][0])
    found["wall_s"] = time.perf_counter() - started
    return found
