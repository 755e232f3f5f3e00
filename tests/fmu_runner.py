"""Drive one FMU instance step by step through fmpy's FMU2Slave."""

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave


class FmuRunner:
    def __init__(self, path, unzip_dir=None, instance_name="instance"):
        self.description = read_model_description(str(path))
        self.unzip_dir = unzip_dir or extract(str(path))
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.outputs = [v.name for v in self.description.modelVariables if v.causality == "output"]
        self.inputs = [v.name for v in self.description.modelVariables if v.causality == "input"]
        self.fmu = FMU2Slave(guid=self.description.guid, unzipDirectory=self.unzip_dir,
                             modelIdentifier=self.description.coSimulation.modelIdentifier,
                             instanceName=instance_name)
        self.fmu.instantiate()

    def initialize(self, deflection, rate, start_time=0.0, tolerance=None, parameters=None):
        self.fmu.setupExperiment(tolerance=tolerance, startTime=start_time)
        self.fmu.enterInitializationMode()
        if parameters:
            self.fmu.setReal([self.vr[n] for n in parameters], list(parameters.values()))
        self.set_inputs(deflection, rate)
        self.fmu.exitInitializationMode()
        self.time = start_time

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
