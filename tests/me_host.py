"""A Model Exchange host on fmpy's CVode (SUNDIALS BDF, absolute tolerance rtol times each
state's nominal), with continuous inputs: x(t) and v(t) are set at every evaluation of the
right-hand side, the event indicators and the outputs, as Model Exchange means them.

fmpy.simulate_fmu's own ME loop sets inputs only at communication points (CVode's
right-hand side does not apply them) and lets CVode integrate past those points before it
interpolates back, so there a time-varying input is held, and held late, over CVode's
steps; its errors are that host's, not the model's (README, Model Exchange).
"""

import math
import random
from ctypes import c_double

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Model
from fmpy.sundials import CVodeSolver

from fmu_components.runtime.catalog import COMPONENTS
from fmu_runner import FmuRunner


class ModelExchangeRun:
    """One ME instance on CVode; `outputs` after run() holds the outputs at the times."""

    def __init__(self, path, x_of, v_of, rtol=1e-6, instance_name="me"):
        self.description = read_model_description(str(path))
        self.fmu = FMU2Model(guid=self.description.guid, unzipDirectory=extract(str(path)),
                             modelIdentifier=self.description.modelExchange.modelIdentifier,
                             instanceName=instance_name)
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.inputs = [v.valueReference for v in self.description.modelVariables
                       if v.causality == "input"]
        self.output_vrs = [v.valueReference for v in self.description.modelVariables
                           if v.causality == "output"]
        self.x_of, self.v_of, self.rtol = x_of, v_of, rtol
        self.nx = self.description.numberOfContinuousStates
        self.nz = self.description.numberOfEventIndicators
        self.time = None
        self.events = 0

    def _set_time(self, t):
        self.time = t
        self.fmu.setTime(t)
        self.fmu.setReal(self.inputs, [self.x_of(t), self.v_of(t)])

    def _get_dx(self, dx, n):
        return self.fmu.getDerivatives(dx, n)

    def _event(self):
        self.fmu.enterEventMode()
        needed = True
        while needed:
            needed = self.fmu.newDiscreteStates()[0]
        self.fmu.enterContinuousTimeMode()
        self.events += 1

    def run(self, times):
        fmu = self.fmu
        fmu.instantiate()
        fmu.setupExperiment(startTime=times[0])
        fmu.enterInitializationMode()
        fmu.setReal(self.inputs, [self.x_of(times[0]), self.v_of(times[0])])
        fmu.exitInitializationMode()
        needed = True
        while needed:
            needed = fmu.newDiscreteStates()[0]
        fmu.enterContinuousTimeMode()
        self._set_time(times[0])
        solver = CVodeSolver(nx=self.nx, nz=self.nz, get_x=fmu.getContinuousStates,
                             set_x=fmu.setContinuousStates, get_dx=self._get_dx,
                             get_z=fmu.getEventIndicators,
                             get_nominals=fmu.getNominalsOfContinuousStates,
                             set_time=self._set_time, input=_NoInput(), startTime=times[0],
                             relativeTolerance=self.rtol, maxNumSteps=100000)
        rows = [self._outputs(times[0])]
        t = times[0]
        for t_next in times[1:]:
            while t < t_next and not np.isclose(t, t_next, rtol=0, atol=1e-12):
                state_event, _, t = solver.step(t, t_next)
                if state_event:
                    self._set_time(t)
                    self._event()
                    solver.reset(t)
            rows.append(self._outputs(t_next))
        fmu.terminate()
        fmu.freeInstance()
        self.outputs = np.array(rows)
        return self.outputs

    def _outputs(self, t):
        x = (c_double * self.nx)()
        self.fmu.getContinuousStates(x, self.nx)
        self._set_time(t)
        self.fmu.setContinuousStates(x, self.nx)
        return self.fmu.getReal(self.output_vrs)


class _NoInput:
    """The inputs are set with the time (ModelExchangeRun._set_time)."""

    def apply(self, *args, **kwargs):
        pass


# --- directional derivatives against finite differences ------------------------------

class Instance:
    """A native FMU through fmpy, in either interface: what its directional derivatives
    take (knowns) and give (unknowns)."""

    def __init__(self, path, interface):
        self.description = read_model_description(str(path))
        self.definition = COMPONENTS[self.description.modelName]
        self.vr = {v.name: v.valueReference for v in self.description.modelVariables}
        self.interface = interface
        self.n = len(self.definition.states)
        if interface == "ModelExchange":
            self.fmu = FMU2Model(guid=self.description.guid, unzipDirectory=extract(str(path)),
                                 modelIdentifier=self.description.modelExchange.modelIdentifier,
                                 instanceName="derivatives")
            self.fmu.instantiate()
        else:
            self.runner = FmuRunner(path, "derivatives")
            self.fmu = self.runner.fmu

    def knowns(self):
        inputs = [self.vr[v.name] for v in self.definition.inputs]
        states = [self.vr[v.name] for v in self.definition.states]
        return inputs + (states if self.interface == "ModelExchange" else [])

    def unknowns(self):
        outputs = [self.vr[v.name] for v in self.definition.outputs]
        derivatives = [self.vr[v.name] for v in self.definition.derivatives]
        return outputs + (derivatives if self.interface == "ModelExchange" else [])


def evaluate(instance, point, knowns, unknowns):
    """The unknowns at a point {known vr: value} (ME: states set directly; CS: inputs)."""
    fmu = instance.fmu
    inputs = [vr for vr in knowns if vr in point and vr < 2]
    fmu.setReal(inputs, [point[vr] for vr in inputs])
    if instance.interface == "ModelExchange":
        states = (c_double * instance.n)(*[point[vr] for vr in knowns[2:]])
        fmu.setContinuousStates(states, instance.n)
    return np.array(fmu.getReal(unknowns))


def random_points(name, count, rng):
    """Points in the range the thesis measured, states on the scale of their nominals, rates
    of both signs, and (for the tyre) both sides of contact."""
    mean, amplitude, frequency = {"RoadWheelTyre": (2.5e-3, 3.5e-3, 1.0),  # in and out of contact
                                  "TrackBushRadial": (0.3e-3, 0.3e-3, 1.0),
                                  "TrackBushTorsion": (math.radians(10), math.radians(20), 1.0),
                                  "RotaryDamper": (0.0, 0.2, 1.0)}[name]
    model = COMPONENTS[name].build_model(COMPONENTS[name].default_parameters())
    for _ in range(count):
        x = mean + amplitude * rng.uniform(-1.0, 1.0)
        v = rng.choice([-1.0, 1.0]) * 10 ** rng.uniform(-4.0, -1.0 if name != "RotaryDamper" else 1.0)
        states = [nominal * rng.uniform(-1.0, 1.0) for nominal in model.nominals]
        yield x, v, states


def central_differences(instance, point, knowns, unknowns, direction):
    values = []
    for sign in (1.0, -1.0):
        shifted = {vr: point[vr] + sign * instance.steps[vr] * direction.get(vr, 0.0)
                   for vr in point}
        values.append(evaluate(instance, shifted, knowns, unknowns))
    return values


def continuous_input(case):
    """x(t) of a case and its rate, by a central difference of the path."""
    def x_of(t):
        return float(case.path(np.array([t]))[0])

    def v_of(t, dt=1e-6):
        return (x_of(t + dt) - x_of(t - dt)) / (2 * dt)
    return x_of, v_of




def compare_directional_derivatives(path, interface, points, seed):
    """The FMU's directional derivatives against central differences of its own outputs
    (and, in Model Exchange, derivatives) at `points` random points: (entries compared,
    entries at a kink where the one-sided differences disagree and nothing is compared,
    largest relative difference), the difference relative to the largest entry of the
    same directional derivative (norm-wise)."""
    rng = random.Random(seed)
    instance = Instance(path, interface)
    name, fmu = instance.definition.name, instance.fmu
    knowns, unknowns = instance.knowns(), instance.unknowns()
    x, v, _ = next(random_points(name, 1, rng))
    if interface == "CoSimulation":
        instance.runner.initialize(x, v)
        for k in range(300):  # a state inside the hysteresis loop
            instance.runner.step(x + 0.5 * v * 1e-3 * math.sin(k / 30), v * math.cos(k / 30), 1e-3)
    else:
        fmu.setupExperiment(startTime=0.0)
        fmu.enterInitializationMode()
        fmu.setReal(knowns[:2], [x, v])
        fmu.exitInitializationMode()
        fmu.newDiscreteStates()
        fmu.enterContinuousTimeMode()
    nominals = instance.definition.build_model(instance.definition.default_parameters()).nominals
    worst, compared, kinks = 0.0, 0, 0
    for x, v, states in random_points(name, points, rng):
        if interface == "CoSimulation" and name == "RotaryDamper":
            # the arm may move the gas spring by less than C2 from where it is
            x = fmu.getReal([knowns[0]])[0] + rng.uniform(-5e-3, 5e-3)
        point = {knowns[0]: x, knowns[1]: v}
        if interface == "ModelExchange":
            point.update(zip(knowns[2:], states))
        scale = {knowns[0]: abs(x) + 1e-3, knowns[1]: abs(v)}
        scale.update({vr: abs(point[vr]) + n for vr, n in zip(knowns[2:], nominals)})
        instance.steps = {vr: 1e-6 * scale[vr] for vr in knowns}
        for known in knowns:
            base = evaluate(instance, point, knowns, unknowns)
            analytic = np.array(fmu.getDirectionalDerivative(unknowns, [known], [1.0]))
            up, down = central_differences(instance, point, knowns, unknowns, {known: 1.0})
            step = instance.steps[known]
            numeric = (up - down) / (2 * step)
            big = np.max(np.abs(numeric)) + 1e-300
            # away from kinks the one-sided differences agree with each other
            smooth = np.abs((up - base) - (base - down)) / step <= 1e-4 * np.abs(numeric) + 1e-9 * big
            kinks += int(np.sum(~smooth))
            for i in np.flatnonzero(smooth):
                worst = max(worst, abs(analytic[i] - numeric[i]) / big)
                compared += 1
    return compared, kinks, worst
