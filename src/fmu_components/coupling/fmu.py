"""One co-simulation FMU instance as a host drives it: save the state at the start of a
host step, step along the secant to the host's trial motion, restore, accept.

An FMU here is a two-port element: inputs deflection and its rate, outputs its load
(force or torque, the first output) and its `stiffness`, as the project's FMUs declare
them (docs/model-spec.md section 4): the inputs set before doStep(t, h) are the values
at t, the FMU holds the rate over the step and its outputs belong to t + h.
"""

import math
import warnings
from pathlib import Path

from .errors import CouplingError, StepDiscarded
from .instance import WARNING, FmuInstance, open_fmu
from .law import LoadLaw
from .linearised import Linearisation


# FMUs whose `stiffness` output is the instantaneous tangent while their internal dynamics
# act within a host step: their answer to a step is linearised (linearised.py). The
# damper's is its gas spring's, which its rotor relaxes in a fraction of a millisecond.
LINEARISED_MODELS = {"RotaryDamper"}
# Where the tangent changes by more than this over a step, the curvature of a "tangent"
# component's law is the one along the step (its states' change included, linearised.py).
CURVED = 0.01


class FmuComponent:
    """A co-simulation FMU with a deflection and a rate input, driven by a host.

    Life cycle: construct (instantiated, in initialization mode, `parameters` set: a dict
    or an SSP .ssv file, applied to the FMU as built, instance.py) ->
    `relaxed_outputs(x)` for a host's static solve -> `start(t0, x0)` -> per host step
    `begin_step()`, `trial(t, x)` (any number of times), `accept()` or `reject()` ->
    `free()`. In between, the host applies `host_load(x, v)`, the component's current
    load law (law.py), which the coupling scheme sets from the laws offered here.

    `trial` steps the FMU from the last accepted point (time, deflection) along the
    secant to (t, x), restoring the state saved by `begin_step` first if it has already
    stepped in this host step. Counters (`do_steps`, `saves`, `restores`) say what it
    cost; one FMU state is kept per instance and reused (getting the FMU state given the
    existing state), and freed with the instance.

    `step_model` says how the component's answer to a host step is predicted:
    "tangent", its load and `stiffness` (the rubber components: their stiffness is the
    rate-independent tangent in the direction of motion), or "linearised", its Model
    Exchange Jacobian along the step (linearised.py; default for LINEARISED_MODELS).
    """

    def __init__(self, path, instance_name, parameters=None, tolerance=None,
                 unilateral=False, step_model=None):
        fmu = open_fmu(path)
        self.name = instance_name
        self.unilateral = unilateral  # a contact: no load at x <= 0, never a pulling load
        # explicit coupling lags the load of a component whose stiffness is no step tangent
        self.stiffness_is_step_tangent = fmu.name not in LINEARISED_MODELS
        if step_model is None:
            step_model = "tangent" if self.stiffness_is_step_tangent else "linearised"
        if step_model not in ("tangent", "linearised"):
            raise ValueError(f"step_model {step_model!r}: 'tangent' or 'linearised'")
        self._linearisable = fmu.model_exchange and bool(fmu.states)
        if step_model == "linearised" and not self._linearisable:
            warnings.warn(f"{instance_name}: {Path(path).name} offers no Model Exchange to "
                          f"linearise its step with; its `stiffness` output stands in",
                          stacklevel=2)
            step_model = "tangent"
        self.step_model = step_model
        # the curvature of the load laws comes from the stiffness's directional derivative
        self._curvature = fmu.provides_directional_derivatives()
        self.touch_stiffness = 0.0  # the last contact stiffness the FMU reported
        self.peak_load = 0.0  # largest |load| seen: the scale of load mismatches
        self.warnings_logged = 0
        self.input_names, self.output_names = fmu.inputs, fmu.outputs
        if len(self.input_names) != 2 or "stiffness" not in self.output_names:
            raise ValueError(f"{path}: a coupled FMU has two inputs (deflection and rate) "
                             f"and a `stiffness` output; this one has inputs "
                             f"{self.input_names} and outputs {self.output_names}")
        self.load_name = self.output_names[0]  # force or torque
        # the state saved at a step's start is set again for each trial: rollback
        self.instance = instance = FmuInstance(fmu, instance_name, on_message=self._heard,
                                               rollback=True)
        self._inputs = instance.reals(self.input_names)
        self._outputs = instance.reals(self.output_names)
        self._stiffness_by_deflection = instance.jacobian(["stiffness"], self.input_names[:1])
        self._stiffness_output = instance.reals(["stiffness"])
        instance.setup(parameters, tolerance, start_time=0.0)
        self._fmu_file, self._parameters = fmu, instance.parameters  # an .ssv file's, read
        self._linearisation = None  # made when first needed
        self._states = None  # the Reals of the states it linearises about
        self._state = instance.new_state()  # NULL until the first save
        self.started = False
        self.time = None  # last accepted point
        self.deflection = 0.0
        self.rate = 0.0  # the secant rate of the last accepted step
        self.previous_rate = 0.0  # the one before it
        self.outputs = {}  # after the last accepted step
        self.trial_outputs = None  # after the last trial, until accept or reject
        self._trial_point = None
        self._stepped = False  # stepped since the state was saved
        self._saved = False
        self.law = None
        # the tangent for motion the other way from the accepted point (reversible_law)
        self.reverse_stiffness = None
        # a step's first law with the reversal's kink at the accepted point, for a host
        # whose Newton copes with a kink at the step's start (reversible_law)
        self.kinked_first_law = False
        self.do_steps = self.saves = self.restores = 0

    # --- FMI calls (instance.py makes them, and raises for their refusals) ----------------

    def _heard(self, status, text):
        if status == WARNING:
            self.warnings_logged += 1
            warnings.warn(f"{self.name}: {text}", stacklevel=2)

    @property
    def messages(self):
        """What the FMU logged, newest last (a few kept)."""
        return self.instance.messages

    def _read(self, time):
        self.instance.time = time
        values = self.instance.get(self._outputs)
        for name, value in zip(self.output_names, values):
            if not math.isfinite(value):
                raise CouplingError(self.name, time, f"output {name} = {value!r} is not "
                                    f"finite{self.instance.said()}")
        return dict(zip(self.output_names, values))

    # --- values ---------------------------------------------------------------------------

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
        self.instance.time = 0.0
        self.instance.set(self._inputs, [deflection, 0.0])
        return self._read(0.0)

    def host_load(self, deflection, rate=0.0):
        """The load the host applies at the deflection and rate of its current iterate:
        before start the relaxed component's (a static solve), then the load law."""
        if not self.started:
            return self.relaxed_outputs(deflection)[self.load_name]
        return self.law(deflection, rate)

    # --- load laws (law.py) ------------------------------------------------------------

    def _law(self, deflection, load, stiffness, curvature=0.0, kink=None, beyond=None,
             side=0.0):
        return LoadLaw(deflection, load, stiffness, curvature, unilateral=self.unilateral,
                       touch_stiffness=self.touch_stiffness, kink=kink, beyond=beyond,
                       side=side)

    def lagged_law(self):
        """The load law about the last accepted step, for a host that cannot repeat one:
        the `stiffness` output as the tangent where it is one over a step ("tangent"
        components), else the plain lagged load."""
        stiffness = self.stiffness if self.stiffness_is_step_tangent else 0.0
        return self._law(self.deflection, self.load, stiffness)

    def predicted_law(self, time, linearised=None):
        """The load law for the first solve of a step to `time`: about the last accepted
        step with the `stiffness` output ("tangent"), or about the linearised answer to
        the step continuing at the last rate ("linearised"; `linearised=True` asks for
        it whatever the step model, where the FMU offers Model Exchange)."""
        if linearised is None:
            linearised = self.step_model == "linearised"
        if not linearised and self._reversible():
            return self.reversible_law()
        if not (linearised and self._linearisable):
            return self.lagged_law()
        step = time - self.time
        predicted, tangent, _ = self._linearised_step(self.deflection, self.rate, step)
        return self._law(self.deflection + self.rate * step, predicted, tangent)

    def _reversible(self):
        """True where the `stiffness` output is the step's tangent in the direction of
        motion, so that the tangent for a reversal is the output at the mirrored rate."""
        return self.step_model == "tangent" and self.stiffness_is_step_tangent

    def reversible_law(self):
        """The law for the first solve of a step of a component whose tangent depends on
        the direction of motion (the rubber's: law.py, A reversal): about the last
        accepted point with the `stiffness` output, the tangent of the last step's
        direction; where the step may reverse, the mean of the tangents for motion either
        way (a reversal meets up to four times the loading tangent). It may where the
        last rate, extrapolated by its last change, is no larger than that change: the
        direction is not known (the track bushes ringing from step to step; a wheel's
        tyre moving smoothly keeps its direction's tangent). With `kinked_first_law`
        (and a last rate) the law has both instead: the last direction's tangent on its
        side of the accepted point, the other way's beyond it, the FMU's own kink there
        (docs/vehicle.md, "A kink in the first law"). The tangent for motion the
        other way is the `stiffness` output at the mirrored rate (the FMU's states are
        not changed, and the next trial sets its inputs again); the law about the step's
        answer keeps it for the kink (_reversal)."""
        self.reverse_stiffness = self.stiffness
        if self.rate:
            self.instance.time = self.time
            self.instance.set(self._inputs, [self.deflection, -self.rate])
            self.reverse_stiffness = self.instance.get(self._stiffness_output)[0]
        tangent, kink = self.stiffness, {}
        if self.kinked_first_law and self.rate:
            kink = {"kink": self.deflection, "beyond": self.reverse_stiffness,
                    "side": _sign(self.rate)}
        elif not abs(2.0 * self.rate - self.previous_rate) > abs(self.rate - self.previous_rate):
            tangent = 0.5 * (tangent + self.reverse_stiffness)
        return self._law(self.deflection, self.load, tangent, **kink)

    def _reversal(self, deflection):
        """The kink of a law about a trial that ended at `deflection`: at the accepted
        point, beyond it the tangent for motion the other way from the trial's, at the
        accepted point (reversible_law's tangents); {} where there is none."""
        if self.reverse_stiffness is None:
            return {}
        side = _sign(deflection - self.deflection)
        beyond = self.reverse_stiffness if side == _sign(self.rate) else self.stiffness
        return {"kink": self.deflection, "beyond": beyond, "side": side}

    def corrected_law(self):
        """The load law about the FMU's answer to the last trial: its load, the step's
        tangent (the `stiffness` output, or the linearised one) and the curvature of the
        `stiffness` output (its directional derivative by the deflection)."""
        time, deflection, secant = self._trial_point
        outputs = self.trial_outputs
        stiffness = outputs["stiffness"]
        curvature = (self.instance.directional_derivative(self._stiffness_by_deflection, 0)[0]
                     if self._curvature else 0.0)
        tangent = stiffness
        if self.step_model == "linearised":
            _, tangent, _ = self._linearised_step(deflection, secant, time - self.time)
            # the same shape of the elastic force, reached through the step's tangent
            curvature = curvature * (tangent / stiffness) ** 2 if stiffness else 0.0
        elif (self._linearisable
              and abs(curvature * (deflection - self.deflection)) > CURVED * abs(stiffness)):
            # The tangent changes over the step (the tyre's over a 4 ms step of a hopping
            # wheel, by a third): its change with the end point along the step, the
            # states' change included, is what the second solve needs (the frozen one
            # leaves twice the error at 4 ms).
            _, _, curvature = self._linearised_step(deflection, secant, time - self.time)
        return self._law(deflection, outputs[self.load_name], tangent, curvature,
                         **self._reversal(deflection))

    def linearisation(self):
        """The Model Exchange side instance that linearises the step, made when first
        needed (the bank hands it to its C code)."""
        if self._linearisation is None:
            self._linearisation = Linearisation(self._fmu_file, f"{self.name}.linearisation",
                                                self._parameters)
            self._states = self.instance.reals(self._linearisation.state_names)
        return self._linearisation

    def _linearised_step(self, deflection, rate, step):
        """(load after `step` at `rate`, its tangent by the end deflection), linearised
        at the FMU's current states and `deflection`: the accepted point's (a
        prediction) or a trial's end (the tangent for the next pass)."""
        linearisation = self.linearisation()
        states = self.instance.get(self._states)
        try:
            return linearisation.step(states, deflection, rate, step)
        except CouplingError as error:
            raise CouplingError(self.name, self.time, f"the linearised step at deflection "
                                f"{deflection!r}, rate {rate!r}: {error}") from None

    def load_scale(self, load):
        return max(self.peak_load, abs(load), 1e-12)

    def _seen(self, outputs):
        self.peak_load = max(self.peak_load, abs(outputs[self.load_name]))
        if outputs["stiffness"] > 0.0:
            self.touch_stiffness = outputs["stiffness"]

    # --- stepping -------------------------------------------------------------------------

    def start(self, time, deflection, rate=0.0):
        """Leave initialization mode with the component relaxed at `deflection`."""
        self.instance.time = time
        self.instance.set(self._inputs, [deflection, rate])
        self.instance.exit_initialization()
        self.started = True
        self.time, self.deflection, self.rate = time, deflection, rate
        self.previous_rate = rate
        self.outputs = self._read(time)
        self._seen(self.outputs)
        self.law = self.lagged_law()

    def begin_step(self):
        """The host starts a step from the last accepted point: undo any trial of a step
        it gave up, and save the state for the trials to come."""
        if self._stepped:
            self._restore()
        self.instance.time = self.time
        self.instance.get_state(self._state)
        self.saves += 1
        self._saved = True
        self.trial_outputs = self._trial_point = None
        self.reverse_stiffness = None

    def _restore(self):
        self.instance.time = self.time
        self.instance.set_state(self._state)
        self.restores += 1
        self._stepped = False

    def trial(self, time, deflection, rate=None, pieces=1):
        """Outputs after stepping from the last accepted point along the secant to
        (time, deflection), in `pieces` equal doSteps; the host's `rate` there is not
        needed (the secant is the rate that matches the host's motion over the step).
        Raises StepDiscarded (the state is restored) if the FMU cannot complete the
        step, CouplingError if it refuses it."""
        if not self._saved:
            raise RuntimeError(f"{self.name}: begin_step() before trial()")
        step = time - self.time
        if step <= 0.0:
            raise ValueError(f"{self.name}: trial to t = {time!r} s, not after the last "
                             f"accepted t = {self.time!r} s")
        if self._stepped:
            self._restore()
        secant = (deflection - self.deflection) / step
        self._stepped = True
        instance = self.instance
        piece = step / pieces
        for i in range(pieces):
            start = self.time + i * piece
            instance.time = start
            instance.set(self._inputs, [self.deflection + secant * i * piece, secant])
            self.do_steps += 1
            try:
                instance.do_step(start, piece)
            except StepDiscarded:
                self._restore()  # back at the step's start, as the host retries from there
                raise
        self.trial_outputs = self._read(time)
        self._seen(self.trial_outputs)
        self._trial_point = (time, deflection, secant)
        return self.trial_outputs

    def accept(self):
        """The host accepted its step: the last trial becomes the accepted point."""
        if self._trial_point is None:
            raise RuntimeError(f"{self.name}: accept() without a trial")
        self.previous_rate = self.rate
        self.time, self.deflection, self.rate = self._trial_point
        self.outputs = self.trial_outputs
        self.trial_outputs = self._trial_point = None
        self._stepped = self._saved = False

    def reject(self):
        """The host gave up its step: back to the last accepted point."""
        if self._stepped:
            self._restore()
        self.trial_outputs = self._trial_point = None

    @property
    def live_states(self):
        """FMU states this instance holds (0 or 1: the one it reuses)."""
        return 1 if self._state else 0

    def serialized_state(self):
        """The FMU's current state, serialized (bytes), e.g. to compare two states."""
        return self.instance.serialized_state()

    def free(self):
        if self._linearisation is not None:
            self._linearisation.free()
        try:
            self.instance.free_state(self._state)
        finally:
            self.instance.close()  # terminated only once initialized, as FMI 2.0 asks


def _sign(value):
    return 1.0 if value > 0.0 else -1.0 if value < 0.0 else 0.0
