"""Coupling the component FMUs to a multibody host: the pattern both examples use.

A host integrates the bodies; each FMU integrates its own component. They meet once per
ACCEPTED host step, in the host's post-step hook:

    post-step at time t:  for every component, read its deflection x(t) from the host,
                          component.advance(t, x)      # one fmi2DoStep over [t_prev, t]

The FMU is fed x(t_prev) and the secant rate (x(t) - x(t_prev)) / (t - t_prev), so over
the step it moves along exactly the straight path between the two accepted host states
(spec section 4: the FMU holds the rate and moves the deflection with it). It is never
stepped from a force callback (Newton iterations and Runge-Kutta stages call those many
times per step) nor before a step (a rejected step would already have advanced it).

Between post-steps the host asks for the load at the deflection of its current iterate:

    component.host_load(x, rate)  ->  F_n + K_n * (x - x_n)

F_n and K_n are the FMU's `force` (or `torque`) and `stiffness` outputs after the last
accepted step at deflection x_n: the explicit one-step lag of the load, corrected by the
tangent stiffness. Because the correction depends on the host's coordinates, a host that
differentiates its force elements (exudyn's connectors do) puts K_n into its Newton
Jacobian: the component is implicit in its stiffness and explicit only in what the
stiffness does not predict (relaxation, hysteresis, the damper's rotor). With
`use_stiffness=False` the load is the plain lagged F_n.

Before `start`, while the FMU is in initialization mode, `host_load` is the relaxed
component's output at x (the FMU's outputs depend directly on its deflection), which is
what a host's static-equilibrium solve needs.

Signs and units are the FMUs': SI, and the load is the one that must be APPLIED to the
component to produce the deflection; the bodies the component connects feel minus that
on the side that moves the deflection positive.

`KelvinElement` is a linear spring and dashpot with the same interface, for runs with
linearised components; `harmonic_kelvin_equivalent` finds its coefficients from an FMU's
response with Eqs. 10.1-2 and 10.1-3 of the thesis.
"""

import math
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_FMU_DIR = ROOT / "fmus"

# One extraction per FMU file and process, shared by all its instances.
_UNPACKED = {}


def _unpacked(path):
    path = Path(path).resolve()
    if path not in _UNPACKED:
        if not path.exists():
            raise FileNotFoundError(f"{path} does not exist: build the FMUs first "
                                    f"(python build_fmus.py --no-run)")
        _UNPACKED[path] = (read_model_description(str(path)), extract(str(path)))
    return _UNPACKED[path]


def fmu_path(name, fmu_dir=None):
    return Path(fmu_dir or DEFAULT_FMU_DIR) / f"{name}.fmu"


class FmuComponent:
    """One FMU instance driven by a host through fmpy's FMU2Slave.

    Life cycle: construct (instantiated, in initialization mode, parameters set) ->
    optional `host_load` calls for a static solve -> `start(t0, x0)` -> `advance(t, x)`
    once per accepted host step, `host_load(x, rate)` in between -> `free()`.
    """

    def __init__(self, path, instance_name, parameters=None, tolerance=None,
                 unilateral=False, use_stiffness=True):
        description, unzip_dir = _unpacked(path)
        self.name = instance_name
        self.unilateral = unilateral  # a contact: no load at x <= 0, never a pulling load
        self.use_stiffness = use_stiffness
        self._vr = {v.name: v.valueReference for v in description.modelVariables}
        inputs = [v.name for v in description.modelVariables if v.causality == "input"]
        self.output_names = [v.name for v in description.modelVariables
                             if v.causality == "output"]
        self.load_name = self.output_names[0]  # force or torque
        self._input_vrs = [self._vr[n] for n in inputs]
        self._output_vrs = [self._vr[n] for n in self.output_names]
        self._fmu = FMU2Slave(guid=description.guid, unzipDirectory=unzip_dir,
                              modelIdentifier=description.coSimulation.modelIdentifier,
                              instanceName=instance_name)
        self._fmu.instantiate()
        self._fmu.setupExperiment(tolerance=tolerance, startTime=0.0)
        self._fmu.enterInitializationMode()
        if parameters:
            self._fmu.setReal([self._vr[n] for n in parameters], list(parameters.values()))
        self.started = False
        self.time = None
        self.deflection = 0.0
        self.outputs = {}

    # --- values ---------------------------------------------------------------------------

    def _read(self):
        self.outputs = dict(zip(self.output_names, self._fmu.getReal(self._output_vrs)))

    @property
    def load(self):
        """The FMU's force (torque) after the last accepted step."""
        return self.outputs[self.load_name]

    @property
    def stiffness(self):
        return self.outputs["stiffness"]

    def relaxed_outputs(self, deflection):
        """Outputs of the relaxed component at `deflection` (initialization mode only)."""
        if self.started:
            raise RuntimeError(f"{self.name}: relaxed outputs exist only before start()")
        self._fmu.setReal(self._input_vrs, [deflection, 0.0])
        self._read()
        return self.outputs

    def host_load(self, deflection, rate=0.0):
        """The load the host applies at the deflection of its current iterate. `rate` is
        not used: the FMU's response to rate arrives with the next accepted step."""
        if not self.started:
            return self.relaxed_outputs(deflection)[self.load_name]
        if self.unilateral and deflection <= 0.0:
            return 0.0
        load = self.load
        if self.use_stiffness:
            load += self.stiffness * (deflection - self.deflection)
        return max(load, 0.0) if self.unilateral else load

    # --- stepping -------------------------------------------------------------------------

    def start(self, time, deflection, rate=0.0):
        """Leave initialization mode with the component relaxed at `deflection`."""
        self._fmu.setReal(self._input_vrs, [deflection, rate])
        self._fmu.exitInitializationMode()
        self.started = True
        self.time = time
        self.deflection = deflection
        self._read()

    def advance(self, time, deflection, rate=None):
        """One fmi2DoStep over [last accepted time, time] along the secant from the last
        deflection to `deflection`. `rate` (the host's rate at `time`) is not needed: the
        secant is the rate that matches the host's accepted motion. A call at the time
        already reached (a host calling its post-step hook for the initial state) does
        nothing."""
        step = time - self.time
        if step <= 0.0:
            return
        secant_rate = (deflection - self.deflection) / step
        self._fmu.setReal(self._input_vrs, [self.deflection, secant_rate])
        try:
            self._fmu.doStep(self.time, step)
        except FMICallException as error:
            raise RuntimeError(f"{self.name}: doStep from t = {self.time:.6g} s by "
                               f"{step:.3g} s failed ({error}); the FMU logged why") from None
        self.time = time
        self.deflection = deflection
        self._read()

    def free(self):
        # FMI 2.0 allows fmi2Terminate only once initialization is complete.
        if self.started:
            self._fmu.terminate()
        self._fmu.freeInstance()


class KelvinElement:
    """Linear spring and dashpot in parallel about a static point, with the interface of
    FmuComponent: load = load0 + stiffness (x - x0) + damping * rate. It is linear, so the
    host applies it exactly (no lag); as a contact it does not pull."""

    def __init__(self, name, load_name, stiffness, damping, static_deflection, static_load,
                 unilateral=False):
        self.name = name
        self.load_name = load_name
        self.k = stiffness
        self.c = damping
        self.x0 = static_deflection
        self.load0 = static_load
        self.unilateral = unilateral
        self.deflection = static_deflection
        self.outputs = {}

    def host_load(self, deflection, rate=0.0):
        if self.unilateral and deflection <= 0.0:
            return 0.0
        load = self.load0 + self.k * (deflection - self.x0) + self.c * rate
        return max(load, 0.0) if self.unilateral else load

    def advance(self, time, deflection, rate=0.0):
        self.deflection = deflection
        self.outputs = {self.load_name: self.host_load(deflection, rate), "stiffness": self.k}

    start = advance  # no state of its own: starting is one evaluation

    @property
    def load(self):
        return self.outputs[self.load_name]

    def free(self):
        pass


def kelvin_coefficients(deflection, rate, load, moving_mass=0.0):
    """Equivalent linear stiffness and damping of a recorded response (whole cycles, or a
    long record), thesis section 10.1 after Hagedorn and Wallaschek, with mean values:

        c_eq = mean((F - mean F) * xdot) / mean(xdot^2)                       Eq. 10.1-2
        k_eq = (mean(F x) - mean F * mean x + m mean(xdot^2)) / (mean(x^2) - (mean x)^2)
                                                                              Eq. 10.1-3
    """
    x, xdot, force = (np.asarray(a, dtype=float) for a in (deflection, rate, load))
    c_eq = np.mean((force - force.mean()) * xdot) / np.mean(xdot ** 2)
    k_eq = ((np.mean(force * x) - force.mean() * x.mean() + moving_mass * np.mean(xdot ** 2))
            / (np.mean(x ** 2) - x.mean() ** 2))
    return float(k_eq), float(c_eq)


def harmonic_kelvin_equivalent(path, mean, amplitude, frequency, cycles=6, step=1e-3,
                               parameters=None):
    """Kelvin equivalent of an FMU about `mean` for the sine x = mean + amplitude
    sin(2 pi f t), from its response over the last two of `cycles` cycles (the first ones
    carry the start-up transient). The component has no moving mass of its own outside
    the FMU (m = 0 in Eq. 10.1-3). Returns (k_eq, c_eq, mean load over those cycles)."""
    component = FmuComponent(path, f"linearise_{Path(path).stem}", parameters=parameters)
    try:
        omega = 2.0 * math.pi * frequency
        samples_per_cycle = int(round(1.0 / (frequency * step)))
        n = cycles * samples_per_cycle
        t = np.arange(n + 1) * (1.0 / frequency / samples_per_cycle)
        x = mean + amplitude * np.sin(omega * t)
        component.start(0.0, x[0])
        load = np.empty(n + 1)
        load[0] = component.load
        for i in range(1, n + 1):
            component.advance(t[i], x[i])
            load[i] = component.load
    finally:
        component.free()
    # The last two cycles, each sample once (the end point closes the cycle).
    window = slice(n - 2 * samples_per_cycle, n)
    k_eq, c_eq = kelvin_coefficients(x[window], amplitude * omega * np.cos(omega * t[window]),
                                     load[window])
    return k_eq, c_eq, float(load[window].mean())


class HostCoupling:
    """The post-step hook for a set of couplings: each entry pairs a component with the
    function that reads its (deflection, rate) from the host at the accepted state.
    `record(t)` is called after all components have advanced."""

    def __init__(self, record=None):
        self.entries = []
        self.record = record

    def add(self, component, read_state):
        self.entries.append((component, read_state))

    def start(self, time):
        for component, read_state in self.entries:
            deflection, rate = read_state()
            component.start(time, deflection, rate)

    def post_step(self, time):
        for component, read_state in self.entries:
            deflection, rate = read_state()
            component.advance(time, deflection, rate)
        if self.record:
            self.record(time)

    def free(self):
        for component, _ in self.entries:
            component.free()


# --- the exudyn side (everything above works with any host) -------------------------------

def connector_state(mbs, connector):
    """Displacement and velocity of a connector at the host's current (accepted) state,
    as its force user function receives them."""
    import exudyn as exu

    return (mbs.GetObjectOutput(connector, exu.OutputVariableType.Displacement),
            mbs.GetObjectOutput(connector, exu.OutputVariableType.Velocity))


def solve_fixed_step(mbs, coupling, end_time, step, start_time=0.0):
    """Start the components at the host's initial state, then integrate with exudyn's
    implicit generalized-alpha at a fixed step (no rejected steps: every post-step is an
    accepted step), stepping the components from the post-step hook."""
    import exudyn as exu

    coupling.start(start_time)
    mbs.SetPostStepUserFunction(lambda mbs, t: coupling.post_step(t) or True)
    settings = exu.SimulationSettings()
    settings.timeIntegration.startTime = start_time
    settings.timeIntegration.endTime = end_time
    settings.timeIntegration.numberOfSteps = int(round((end_time - start_time) / step))
    settings.timeIntegration.adaptiveStep = False
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.active = False
    try:
        ok = mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
    finally:
        coupling.free()
    if not ok:
        raise RuntimeError("exudyn's dynamic solver failed")
