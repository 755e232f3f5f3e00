"""What ``fmu-components build`` does around the build itself (``export.build``): the host
checked before it starts, an engineer's own part read from its PARAMS.json, and each built
FMU simulated once through fmpy with a summary printed. The command is
``commands/build.py``.
"""

import math
import re
import shutil
import sys
import time
from importlib.util import find_spec
from pathlib import Path

import numpy as np

from ..errors import UsageError
from ..export.build import Own
from ..export.identity import read_identity
from ..export.parameters import ParameterError, parameter_set
from ..runtime.catalog import COMPONENTS, structures_of
from .signals import THESIS_SINES, input_table, sine, time_grid


def sine_input(name, stop_time, step):
    """The thesis sine of component `name` with its exact (not secant) rate."""
    mean, amplitude, frequency = THESIS_SINES[name]
    omega = 2 * math.pi * frequency
    t = time_grid(stop_time, step)
    return input_table(name, t, sine(t, mean, amplitude, frequency),
                       rate=amplitude * omega * np.cos(omega * t))


def run(built):
    """One thesis sine through each built FMU, each named by its file (an own part or a
    structure's FMU by its own name), the sine its component's."""
    from fmpy import simulate_fmu

    print(f"\n{'FMU':28s} {'flavour':8s} {'output':12s} {'min':>11s} {'max':>11s} {'unit':>6s} "
          f"{'steps':>6s} {'wall s':>7s} {'us/step':>8s}")
    for flavour, paths in built.items():
        for path in paths.values():
            component = read_identity(path).component
            output = COMPONENTS[component].outputs[0]
            stop, step = 2.0, 1e-3
            started = time.perf_counter()
            result = simulate_fmu(str(path), stop_time=stop, output_interval=step,
                                  input=sine_input(component, stop, step), output=[output.name])
            wall = time.perf_counter() - started
            values = result[output.name]
            steps = len(values) - 1
            print(f"{Path(path).stem:28s} {flavour:8s} {output.name:12s} {values.min():11.5g} "
                  f"{values.max():11.5g} {output.unit:>6s} {steps:6d} {wall:7.2f} "
                  f"{wall / steps * 1e6:8.1f}")


def check_host(flavours, will_run):
    """Everything the build needs, checked before it starts: one line on what to install."""
    if shutil.which("gcc") is None:
        raise UsageError("gcc not found: install a C compiler (Debian/Ubuntu: apt-get install gcc)")
    needed = (["pythonfmu"] if "python" in flavours else []) + (["fmpy"] if will_run else [])
    missing = [module for module in needed if find_spec(module) is None]
    if missing:
        raise UsageError(f"{', '.join(missing)} not installed in {sys.executable}: run inside the "
                         f"project's environment (python3.11 -m venv .venv && "
                         f'.venv/bin/pip install -e ".[test]")')


def build_coupling_bank():
    """The coupling's bank (its per-step work in C) for this platform and win64, beside
    its source: a Python host's first bank then needs no compiler."""
    from fmu_components.coupling.bank_build import build_bank

    libraries, skipped = build_bank()
    for path in libraries.values():
        print(f"built {path}")
    for platform in skipped:
        warn(f"no compiler for the coupling bank's {platform} library: skipped")


def report_built(built, no_run):
    """Each built FMU's path, then (unless no_run) each run once."""
    for paths in built.values():
        for path in paths.values():
            print(f"built {path}")
    if not no_run:
        run(built)
    return 0


def warn(message):
    print(f"warning: {message}", file=sys.stderr)


def read_own(path, name, component, structure):
    """An Own from a PARAMS.json (read and checked as every tool reads it), every mistake said
    in one line."""
    if not (path and name and component):
        raise UsageError("--params, --name and --component go together: give all three")
    if not re.fullmatch(r"[A-Za-z][A-Za-z0-9_]{0,63}", name) or name in COMPONENTS:
        raise UsageError(f"--name {name}: give a new name of letters, digits and _ that "
                         f"starts with a letter (it names the FMU's C and Python identifiers)")
    if structure not in structures_of(component):
        raise UsageError(f"{component} comes in no {structure!r} structure (it has: "
                         f"{', '.join(structures_of(component))})")
    try:
        values = parameter_set(component, structure, path, warn=warn)
    except ParameterError as error:
        raise UsageError(str(error)) from None  # it names the file
    return Own(name, component, structure, values)
