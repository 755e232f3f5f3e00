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


def verify_row(outcome):
    return {"run": f"{outcome.name}/{outcome.case.name}", "fmu": outcome.name,
            "case": outcome.case.name, "passed": outcome.passed,
            "strict_error_percent": outcome.strict_error if outcome.errors else None,
            "worst_output": outcome.worst_output,
            "outside_band": outcome.outliers, "problem": outcome.problem,
            "wall_s": outcome.wall_time}


# --- the measurements (fmu-components validate) ---------------------------------------------

def validate_case(case, fmu, outputs):
    """One case of the validation through its component's FMU: fmpy's result."""
    from ..verification.cases import simulate_case

    return simulate_case(fmu, case.inputs(), case.options(), outputs, label=case.key)[0]


# --- the virtual test rig (fmu-components rig) -----------------------------------------------

def rig_point(setup, point, options):
    """One rig point to periodic steady state (``lab.rig.run_point``): a RigRow."""
    from ..lab.rig import run_point

    return run_point(setup, *point, **options)


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
