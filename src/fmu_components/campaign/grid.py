"""A campaign's grid file: what to run, over which values. JSON, for example

    {"run": "station", "speeds": [3, 8, 15], "courses": {"bump": {}, "high": {"bump_height": 0.06}},
     "parameter_sets": {"thesis": {}, "soft": "soft.json", "part": "part.ssv"}, "end_time": 1.5}

One run per combination of the lists (every speed on every course with every parameter
set). The kinds of run, and their keys (defaults in ``KINDS``' entries):

* ``station``: examples/road_wheel_station.py, the FMUs' figures at each speed (m/s) and
  course (a name -> the RoadProfile's arguments: bump_height, bump_length, ripple_depth);
  ``end_time`` (s; default: the bump passed + 1 s), ``step`` (host step, s);
* ``vehicle``: examples/tracked_vehicle.py at each speed and course (bump, sine, random);
  ``end_time``, ``step``;
* ``rig``: the virtual test rig (``lab.rig``) of ``component`` at every ``preloads`` x
  ``amplitudes`` x ``frequencies`` point, on the ``engine`` model (default) or fmu;
* ``verify``: the thesis test programme through the FMUs of ``fmus``, ``fmu`` and
  ``cases`` selecting as ``fmu-components verify``'s --fmu and --case.

A parameter set is the FMU parameters' SI values: a dict, a JSON file of one, or an SSP
parameter-values file (``.ssv``). For the station, whose two FMUs have parameters of the
same names, a set is {FMU name: {parameter: value}} and an .ssv names each
``<FMU>.<parameter>``. File names are relative to the grid file. ``fmus`` (default: the
repository's fmus/) and ``examples`` (default: its examples/) are read on the client
and travel with the tasks.
"""

import itertools
import json
import math
import xml.etree.ElementTree as ElementTree
from dataclasses import dataclass
from pathlib import Path

from ..runtime.catalog import COMPONENTS
from . import tasks
from .payload import Payload

REPOSITORY = Path(__file__).resolve().parents[3]
SSV = "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}"
STATION_FMUS = ("RoadWheelTyre", "RotaryDamper")


class GridError(Exception):
    """A grid file that cannot be run as written: said in one line."""


@dataclass(frozen=True)
class Run:
    key: str  # the results table's `run`: the run's values
    values: dict  # the run's values, the leading columns of its row
    arguments: tuple  # the task function's
    cost: float = 0.0  # what it takes, roughly: the costliest go first, so that none ends alone


@dataclass
class Grid:
    kind: str
    function: object  # the task every run calls
    runs: list
    to_row: object  # (run, result) -> the row's results


def read_grid(path):
    """The Grid of a grid file."""
    path = Path(path)
    try:
        spec = json.loads(path.read_text())
    except (OSError, json.JSONDecodeError) as error:
        raise GridError(f"{path}: {error}") from None
    if not isinstance(spec, dict) or spec.get("run") not in KINDS:
        raise GridError(f"{path}: give \"run\": one of {', '.join(KINDS)}")
    return KINDS[spec["run"]](spec, path.parent)


def _list(spec, key, default=None):
    values = spec.get(key, default)
    if not isinstance(values, list) or not values:
        raise GridError(f"\"{key}\": give a list of one or more values")
    return values


def _numbers(spec, key, default=None):
    values = _list(spec, key, default)
    if any(isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v)
           for v in values):
        raise GridError(f"\"{key}\": {values} must be numbers (SI units)")
    return [float(v) for v in values]


def _named(spec, key, default):
    """{name: value} of a key given as a dict, or as a list of names (each its own value)."""
    values = spec.get(key, default)
    if isinstance(values, list):
        values = {str(v): v for v in values}
    if not isinstance(values, dict) or not values:
        raise GridError(f"\"{key}\": give one or more, by name")
    return values


def read_parameter_set(value, folder, qualified=False):
    """The values of one parameter set (module docstring): {name: SI value}, or with
    `qualified` {FMU name: {name: SI value}}."""
    if isinstance(value, str):
        path = folder / value
        if path.suffix == ".ssv":
            value = read_ssv(path)
            return _by_fmu(value, path) if qualified else value
        try:
            value = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as error:
            raise GridError(f"parameter set {path}: {error}") from None
    if not isinstance(value, dict):
        raise GridError(f"parameter set {value!r}: give a dict, a .json or an .ssv file")
    return value


def read_ssv(path):
    """{parameter name: value} of an SSP parameter-values file's Real parameters."""
    try:
        root = ElementTree.parse(path).getroot()
    except (OSError, ElementTree.ParseError) as error:
        raise GridError(f"parameter set {path}: {error}") from None
    values = {}
    for parameter in root.iter(f"{SSV}Parameter"):
        real = parameter.find(f"{SSV}Real")
        if real is None:
            raise GridError(f"{path}: parameter {parameter.get('name')!r} is not a Real")
        values[parameter.get("name")] = float(real.get("value"))
    return values


def _by_fmu(values, path):
    grouped = {}
    for name, value in values.items():
        fmu, _, parameter = name.partition(".")
        if fmu not in STATION_FMUS or not parameter:
            raise GridError(f"{path}: parameter {name!r}: name it <FMU>.<parameter>, the FMU "
                            f"one of {', '.join(STATION_FMUS)}")
        grouped.setdefault(fmu, {})[parameter] = value
    return grouped


def _folder(spec, key, folder, default):
    path = folder / spec[key] if key in spec else default
    if not path.is_dir():
        raise GridError(f"\"{key}\": {path} is no folder")
    return path


def _fmus(spec, folder, names):
    """A payload of the named components' FMUs from the grid's FMU folder."""
    fmus = _folder(spec, "fmus", folder, REPOSITORY / "fmus")
    missing = [str(fmus / f"{n}.fmu") for n in names if not (fmus / f"{n}.fmu").exists()]
    if missing:
        raise GridError(f"not built: {', '.join(missing)} (run fmu-components build first)")
    return Payload.of_files("fmus", [fmus / f"{n}.fmu" for n in names])


def _product(**axes):
    """Every combination of the axes' {name: value}: (key, {axis: name}, values)."""
    names = list(axes)
    for combination in itertools.product(*(list(axes[n].items()) for n in names)):
        labels = {n: label for n, (label, _) in zip(names, combination)}
        key = " ".join(f"{n}={labels[n]}" for n in names)
        yield key, labels, [value for _, value in combination]


def _results(run, result):
    return result


def station_grid(spec, folder):
    examples = Payload.of(_folder(spec, "examples", folder, REPOSITORY / "examples"))
    fmus = _fmus(spec, folder, STATION_FMUS)
    speeds = {f"{v:g}": v for v in _numbers(spec, "speeds")}
    courses = _named(spec, "courses", {"bump": {}})
    sets = {name: read_parameter_set(value, folder, qualified=True)
            for name, value in _named(spec, "parameter_sets", {"thesis": {}}).items()}
    end_time, step = spec.get("end_time"), spec.get("step", 1e-4)
    runs = [Run(key, dict(labels, speed=speed),
                (examples, fmus, speed, course, parameters, end_time, step))
            for key, labels, (speed, course, parameters)
            in _product(speed=speeds, course=courses, parameter_set=sets)]
    return Grid("station", tasks.station_run, runs, _results)


def vehicle_grid(spec, folder):
    examples = Payload.of(_folder(spec, "examples", folder, REPOSITORY / "examples"))
    fmus = _fmus(spec, folder, sorted(COMPONENTS))
    speeds = {f"{v:g}": v for v in _numbers(spec, "speeds")}
    courses = _named(spec, "courses", ["bump"])
    end_time, step = spec.get("end_time", 1.0), spec.get("step", 1e-3)
    runs = [Run(key, dict(labels, speed=speed), (examples, fmus, speed, course, end_time, step))
            for key, labels, (speed, course) in _product(speed=speeds, course=courses)]
    return Grid("vehicle", tasks.vehicle_run, runs, _results)


def rig_grid(spec, folder):
    from ..lab.rig import RigError, make_setup

    component = spec.get("component")
    engine = spec.get("engine", "model")
    fmu = str(folder / spec["fmu"]) if "fmu" in spec else None
    options = {k: spec[k] for k in ("samples_per_cycle", "steady", "max_cycles") if k in spec}
    setups = {}
    try:
        for name, value in _named(spec, "parameter_sets", {"thesis": {}}).items():
            setup = make_setup(component, spec.get("structure", "final"),
                               read_parameter_set(value, folder), engine, fmu,
                               spec.get("rtol", 1e-6))
            if engine == "fmu":  # the FMU travels, not the folder it was unpacked to here
                setup = _replace(setup, fmu=Payload.of(fmu))
            setups[name] = setup
    except RigError as error:
        raise GridError(str(error)) from None
    axes = {key: {f"{v:g}": v for v in _numbers(spec, key)}
            for key in ("preloads", "amplitudes", "frequencies")}
    runs = [Run(key, dict(labels, preload=p, amplitude=a, frequency=f),
                (setups[labels["parameter_set"]], (p, a, f), options))
            for key, labels, (setup_name, p, a, f)
            in _product(parameter_set={n: n for n in setups}, preload=axes["preloads"],
                        amplitude=axes["amplitudes"], frequency=axes["frequencies"])]
    return Grid("rig", tasks.timed_rig_point, runs,
                lambda run, result: tasks.rig_row(run.key, *result))


def _replace(setup, **changes):
    import dataclasses

    return dataclasses.replace(setup, **changes)


def verify_grid(spec, folder):
    from ..verification import cases as programme
    from ..verification.verify import built_fmus

    fmus = _folder(spec, "fmus", folder, REPOSITORY / "fmus")
    found = built_fmus(fmus)
    wanted = spec.get("fmu") or list(found)
    unknown = [n for n in wanted if n not in found]
    if unknown or not wanted:
        raise GridError(f"\"fmu\": {unknown or wanted} not built in {fmus} (it has: "
                        f"{', '.join(found) or 'none'})")
    runs = [(case, *found[name]) for name in wanted
            for case in programme.select([found[name][1].component], spec.get("cases"))]
    if not runs:
        raise GridError("\"cases\": no case matches; see the case names in reference_data/<FMU>/")
    return verification_grid(runs)


def verification_grid(runs, reference_data=None, drawn=False):
    """The Grid of (case, FMU path, Identity) runs of the test programme: each FMU and
    each case's reference tables (from `reference_data`, default the committed ones)
    travel with its tasks. drawn: each task also draws its case's plot for the report
    (its result is then (Outcome, PNG bytes))."""
    from ..verification import cases as programme
    from ..verification.verify import needs_own_reference

    payloads, grid_runs = {}, []
    for case, path, identity in runs:
        payload = payloads.setdefault(path, Payload.of(path))
        tables = None if needs_own_reference(identity) else \
            programme.read(case, reference_data or programme.REFERENCE_DATA)
        grid_runs.append(Run(f"{path.stem}/{case.name}", {"fmu": path.stem, "case": case.name},
                             (case, payload, tables, identity), cost=len(case.times())))
    if drawn:
        return Grid("verify", tasks.verify_and_draw_case, grid_runs,
                    lambda run, result: tasks.verify_row(result[0]))
    return Grid("verify", tasks.verify_case, grid_runs,
                lambda run, outcome: tasks.verify_row(outcome))


def validation_grid(cases, fmu_of):
    """The Grid of the measurements' cases (``fmu-components validate``): each case through
    its component's FMU (``fmu_of(component)``, the file, travelling with the task)."""
    from ..verification.measurements import outputs_of

    payloads = {}
    runs = [Run(case.key, {"fmu": case.fmu, "case": case.name},
                (case, payloads.setdefault(case.fmu, Payload.of(fmu_of(case.fmu))),
                 outputs_of(case)), cost=len(case.times()))
            for case in cases]
    return Grid("validate", tasks.validate_case, runs,
                lambda run, result: tasks.validate_row(*result))


KINDS = {"station": station_grid, "vehicle": vehicle_grid, "rig": rig_grid,
         "verify": verify_grid}
