"""A whole deflection history through the compiled native co-simulation: the fit's fast
inner simulation.

    force = simulate("TrackBushRadial", {"k3": 2e7}, times, deflection)

The component's generated model (``cgen.ModelCode``), the native runtime (``c/``) and the
driver ``history.c`` beside this module are compiled into one shared library with the native build's gcc
flags (``build.C_FLAGS``), once per content: the library is cached under
``$FMU_COMPONENTS_CACHE`` (default ``~/.cache/fmu-components``) by a hash of everything
that goes into it. The driver makes the FMI calls a host makes, so the forces are the
built native FMU's, bit for bit, at the cost of the model alone (no host per step).

Rate: a measured history has no rate of its own. The FMU holds the rate over each step
and moves the deflection with it (spec section 4), so the forward difference
(x[i+1] - x[i]) / h over step i (``signals.secant_rates``) makes the FMU's deflection pass
through every sample; any other estimate (central, backward) makes it leave the samples
between them and lag or lead the measured force.
"""

import ctypes
import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from ..runtime import catalog
from ..runtime.catalog import component_definition
from .signals import secant_rates

DRIVER = Path(__file__).with_name("history.c")  # the FMI calls of a host, in C
STRUCTURES = tuple(catalog.STRUCTURES)


class HistoryError(RuntimeError):
    """A history the FMU refused (its message says why)."""


def cache_folder():
    return Path(os.environ.get("FMU_COMPONENTS_CACHE",
                               Path.home() / ".cache" / "fmu-components")) / "history"


def _content_key(definition):
    from ..export.build import C_FLAGS, C_SOURCE, runtime_files
    from ..export.cgen import ModelCode

    code = ModelCode(definition, "")
    digest = hashlib.sha256(" ".join(C_FLAGS).encode())
    digest.update(code.config_header().encode())
    digest.update(code.source().encode())
    sources, headers = runtime_files()
    for path in [C_SOURCE / name for name in sources + headers] + [DRIVER]:
        digest.update(path.read_bytes())
    return f"{definition.name}-{digest.hexdigest()[:20]}"


def compiled_library(definition):
    """(path of the shared library, its GUID, the file URI of its resources folder),
    compiled if the cache does not hold it yet."""
    folder = cache_folder() / _content_key(definition)
    library = folder / "history.so"
    if not library.exists():
        from ..export.build import compile_native, native_sources

        folder.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=folder.parent) as tmp:
            work = Path(tmp) / "work"
            guid, files = native_sources(definition, work / "sources")
            shutil.copy2(DRIVER, work / "sources" / DRIVER.name)
            try:
                compile_native("gcc", work / "sources", [*files, DRIVER.name],
                               work / "history.so", ["-fPIC"])
            except (OSError, subprocess.CalledProcessError) as error:
                raise HistoryError(f"cannot compile {definition.name}'s native model for the "
                                   f"fast simulation ({error}); install gcc") from None
            (work / "resources").mkdir()
            (work / "resources" / "fmu-guid.txt").write_text(guid + "\n")
            shutil.rmtree(work / "sources")
            try:
                work.rename(folder)
            except OSError:  # another process got there first: its copy is the same
                if not library.exists():
                    raise
    guid = (folder / "resources" / "fmu-guid.txt").read_text().strip()
    return library, guid, (folder / "resources").as_uri()


_DOUBLES = np.ctypeslib.ndpointer(dtype=np.float64, flags="C_CONTIGUOUS")
_UINTS = np.ctypeslib.ndpointer(dtype=np.uint32, flags="C_CONTIGUOUS")


class NativeHistory:
    """One component's compiled history driver, loaded in this process."""

    def __init__(self, definition, output=None):
        self.definition = definition
        path, guid, resources = compiled_library(definition)
        self._guid, self._resources = guid.encode(), resources.encode()
        self._run = ctypes.CDLL(str(path)).history_run
        self._run.restype = ctypes.c_int
        self._run.argtypes = [ctypes.c_char_p, ctypes.c_char_p, _UINTS, _DOUBLES, ctypes.c_size_t,
                              ctypes.c_uint, ctypes.c_uint, ctypes.c_uint, ctypes.c_double,
                              _DOUBLES, _DOUBLES, _DOUBLES, ctypes.c_size_t, _DOUBLES,
                              ctypes.c_char_p, ctypes.c_size_t]
        self.vr = {v.name: i for i, v in enumerate(definition.variables)}
        self.output = output or definition.outputs[0].name

    def run(self, parameters, times, deflection, rate=None, tolerance=None, check=True):
        """The output at every sample; parameters (name -> SI value) left out keep the thesis
        values. check: raise HistoryError on a refused call, else return NaN from there on."""
        unknown = set(parameters) - {p.name for p in self.definition.parameters}
        if unknown:
            raise KeyError(f"{self.definition.name} has no parameter {sorted(unknown)[0]!r}")
        times = np.ascontiguousarray(times, dtype=np.float64)
        deflection = np.ascontiguousarray(deflection, dtype=np.float64)
        rate = secant_rates(times, deflection) if rate is None else rate
        rate = np.ascontiguousarray(rate, dtype=np.float64)
        if not len(times) == len(deflection) == len(rate):
            raise ValueError("times, deflection and rate must have the same length")
        references = np.array([self.vr[n] for n in parameters], dtype=np.uint32)
        values = np.array([float(v) for v in parameters.values()], dtype=np.float64)
        out = np.empty(len(times))
        message = ctypes.create_string_buffer(1024)
        failed = self._run(self._guid, self._resources, references, values, len(values),
                           self.vr[self.definition.inputs[0].name],
                           self.vr[self.definition.inputs[1].name], self.vr[self.output],
                           tolerance or 0.0, times, deflection, rate, len(times), out,
                           message, len(message))
        if failed and check:
            where = "at initialization" if failed == 1 else f"at t = {times[failed - 2]:.6g} s"
            raise HistoryError(f"{self.definition.name} refused the history {where}: "
                               f"{message.value.decode(errors='replace')}")
        return out


_LOADED = {}


def native_history(component, structure="final"):
    """The loaded driver of a component (one per process)."""
    key = (component, structure)
    if key not in _LOADED:
        _LOADED[key] = NativeHistory(component_definition(component, structure))
    return _LOADED[key]


def simulate(component, parameters, times, deflection, rate=None, structure="final",
             tolerance=None, check=True):
    """The component's load (force or torque) at every sample of a deflection history run
    through the native co-simulation; rate: held over each step, by default the forward
    difference (see the module's docstring)."""
    return native_history(component, structure).run(parameters, times, deflection, rate,
                                                     tolerance, check)
