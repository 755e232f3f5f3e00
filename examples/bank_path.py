"""Which coupling path the examples take: "compiled" (default), the coupling's bank
(fmu_components.coupling.bank: the per-step work of all instances in C, the load laws in
exudyn's compiled symbolic functions), or "python", the readable Python path (Coupling,
a Python force function per connector). The compiled path runs the schemes the bank has
(corrected, converged, explicit) and falls back to Python for the others, and where no C
compiler is found (with a warning)."""

import warnings

from fmu_components.coupling.bank import SCHEME_CODES, Bank  # noqa: F401
from fmu_components.coupling.bank_build import NoCompiler, library_path
from fmu_components.coupling.bank_exudyn import SymbolicLaws, solve, symbolic_function  # noqa: F401
from fmu_components.coupling.exudyn_host import solve as solve_python

PATHS = ("compiled", "python")
DEFAULT_PATH = "compiled"


def compiled(path, scheme):
    """True where the run takes the compiled path."""
    if path not in PATHS:
        raise ValueError(f"path {path!r}: one of {', '.join(PATHS)}")
    if path == "python" or scheme not in SCHEME_CODES:
        return False
    try:
        library_path()
    except NoCompiler as missing:
        warnings.warn(f"{missing}; taking the Python path", stacklevel=2)
        return False
    return True


def add_argument(parser):
    parser.add_argument("--path", choices=PATHS, default=DEFAULT_PATH,
                        help="the coupling's compiled path (its bank, default) or its "
                             "Python path")


def run(model, end_time, step, settings=None):
    """Integrate an example's model (its `mbs` and `coupling`; on the compiled path its
    `bank`, `laws` and `_deflections`) to end_time at a fixed host step, with exudyn's
    `settings` (both paths the same); its `host` and `coupling` are then the run's (the
    bank's costs on the compiled path)."""
    if model.compiled:
        model.host = solve(model.mbs, model.bank, model.laws, model._deflections, end_time,
                           step, settings=settings)
        model.coupling = model.bank
    else:
        model.host = solve_python(model.mbs, model.coupling, end_time, step,
                                  settings=settings)
