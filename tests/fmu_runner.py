"""Drive one FMU instance step by step through fmpy's FMU2Slave."""

import atexit
import shutil
import tempfile
from ctypes import c_double, c_uint
from pathlib import Path

import numpy as np
from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

OK, WARNING, DISCARD, ERROR, FATAL = range(5)

_EXTRACTED = {}  # (FMU path, modification time) -> its extraction, shared by the process


def _extracted(path):
    """The FMU extracted once per process (again if the file changes), removed at exit."""
    path = Path(path).resolve()
    key = (path, path.stat().st_mtime_ns)
    if key not in _EXTRACTED:
        directory = tempfile.mkdtemp(prefix=f"fmu_runner_{path.stem}_")
        atexit.register(shutil.rmtree, directory, ignore_errors=True)
        _EXTRACTED[key] = extract(str(path), directory)
    return _EXTRACTED[key]


class FmuRunner:
    """One instance; every message it logs lands in `messages` as (status, text)."""

    def __init__(self, path, instance_name="instance"):
        self.description = read_model_description(str(path))
        self.unzip_dir = _extracted(path)
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.outputs = [v.name for v in self.description.modelVariables if v.causality == "output"]
        self.inputs = [v.name for v in self.description.modelVariables if v.causality == "input"]
        self.messages = []
        self.fmu = FMU2Slave(guid=self.description.guid, unzipDirectory=self.unzip_dir,
                             modelIdentifier=self.description.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        # No fmpy logger proxy: it keeps one logger for the whole process. The FMUs pass
        # each message finished, as a format string with '%' doubled.
        self.fmu.instantiate(callbacks=self._callbacks)
        self.time = 0.0

    def _log(self, environment, instance_name, status, category, message):
        self.messages.append((status, message.decode("utf-8", "replace").replace("%%", "%")))

    def status(self, function, *args):
        """The FMI status of a call (fmpy raises for statuses above fmi2Warning)."""
        try:
            result = function(*args)
        except FMICallException as failure:
            return failure.status
        return result if isinstance(result, int) else OK

    def set_real_status(self, names, values):
        """fmi2SetReal's own status code (fmpy's setReal does not return it)."""
        n = len(names)
        vrs = (c_uint * n)(*[self.vr[name] for name in names])
        return self.status(self.fmu.fmi2SetReal, self.fmu.component, vrs, n, (c_double * n)(*values))

    def initialize(self, deflection, rate):
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        self.set_inputs(deflection, rate)
        self.fmu.exitInitializationMode()
        self.time = 0.0

    def set_inputs(self, deflection, rate):
        self.fmu.setReal([self.vr[self.inputs[0]], self.vr[self.inputs[1]]], [deflection, rate])

    def read(self):
        return self.fmu.getReal([self.vr[n] for n in self.outputs])

    def step(self, deflection, rate, h):
        self.set_inputs(deflection, rate)
        self.fmu.doStep(self.time, h)
        self.time += h
        return self.read()

    def run(self, deflection, rate, h):
        """Outputs after each step for sample arrays (the last sample is not stepped)."""
        return np.array([self.step(x, v, h) for x, v in zip(deflection[:-1], rate[:-1])])

    def free(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
