"""Co-simulation semantics shared by every component (spec section 4), with no FMI in it.

* Inputs set before doStep(tc, h) are the values at tc. Over the step the rate is held
  and the deflection moves with it: x(t) = x(tc) + v(tc)*(t - tc).
* Outputs read after the step belong to tc + h. New inputs change the outputs at once,
  computed from the current internal state (the output depends directly on x).
* A step either completes or leaves everything as it was, with a message that says whether
  the call was refused (it cannot follow the last step) or failed (the integrator could not
  complete it).
* The rate is checked against the deflection's movement (rate_inconsistency), or with
  rate_from_deflection derived from it (docs/simulate.md): a rate left at 0, in the wrong
  unit or of the wrong sign would otherwise give a plausible but wrong force.

The FMU adapter wraps this class; benchmarks and tests can drive it directly.
"""

import math

from .integrator import DEFAULT_RTOL, Rosenbrock

INFINITY = math.inf
REFUSED, FAILED = "refused", "failed"  # the two ways a doStep can come back unfinished
WARNED = "warned"  # a step that completed with a warning about its inputs

# The rate check. Over the last step the deflection moved by `moved`; a rate that belongs
# to it has the step times the rates held at its two ends on either side of `moved`
# (the mean value theorem, for a rate that does not turn inside the step), give or take
# RATE_MARGIN of the larger movement: a sine sampled 10 times a cycle is off by 3.4 % at
# its fastest, a rate in mm/s by a factor 1000, a rate of the wrong sign by 200 %.
RATE_MARGIN = 0.25
# Below these the motion is too small to judge, as fractions of the deflection's scale
# (the largest bound of its measured range): rounding of the samples, and slow creep.
STILL_FRACTION = 1e-6
CREEP_FRACTION_PER_SECOND = 1e-3


def rate_floors(deflection_scale):
    """(still, creep): the movement below which a step is not judged is still + creep*h."""
    return STILL_FRACTION * deflection_scale, CREEP_FRACTION_PER_SECOND * deflection_scale


def rate_inconsistency(previous_deflection, previous_rate, step, deflection, rate, floors):
    """The rate of the secant over the last step when the held rates at its ends (the
    previous one and the current one) do not fit the deflection's movement, else None."""
    moved = deflection - previous_deflection
    low, high = (previous_rate, rate) if previous_rate <= rate else (rate, previous_rate)
    low *= step
    high *= step
    largest = max(abs(moved), abs(low), abs(high))
    allowance = RATE_MARGIN * largest + (floors[0] + floors[1] * step)
    if moved < low - allowance or moved > high + allowance:
        return moved / step
    return None


class FiniteGuard:
    """Beyond the bounds of the inputs inside which every output is finite
    (ComponentDefinition.finite_bounds), a set of inputs or a step first works out the
    outputs it leads to, and is refused if one is not finite: an infinite force answered
    with OK is worse than a refusal. Inside them it costs one comparison per input."""

    def __init__(self, definition):
        (self.x_low, self.x_high), (self.v_low, self.v_high) = definition.finite_bounds
        (self.x_name, self.x_unit), (self.v_name, self.v_unit) = (
            (v.name, v.unit) for v in definition.inputs)
        self.output_names = [v.name for v in definition.outputs]

    def watches(self, deflection, rate):
        return not (self.x_low <= deflection <= self.x_high and self.v_low <= rate <= self.v_high)

    def _first_non_finite(self, outputs):
        return next(((name, value) for name, value in zip(self.output_names, outputs)
                     if not math.isfinite(value)), None)

    def input_problem(self, outputs, deflection, rate):
        """A message if an output is not finite at these inputs, else None."""
        bad = self._first_non_finite(outputs)
        return bad and (f"{self.x_name} = {deflection!r} {self.x_unit} with {self.v_name} = "
                        f"{rate!r} {self.v_unit} would drive {bad[0]} to {bad[1]!r}")

    def step_problem(self, outputs, deflection):
        """A message if an output is not finite after a step, else None."""
        bad = self._first_non_finite(outputs)
        return bad and (f"it would drive {bad[0]} to {bad[1]!r} ({self.x_name} = "
                        f"{deflection!r} {self.x_unit} at its end); nothing changed: take a "
                        f"smaller step")


class CoSimulation:
    def __init__(self, model, rtol=DEFAULT_RTOL, start_time=0.0, deflection=0.0, rate=0.0,
                 rate_floors=None, rate_from_deflection=False, guard=None):
        """rate_floors: check the rate against the deflection (cosim.rate_floors), or None
        not to; rate_from_deflection: derive the rate from the deflection instead; guard: a
        FiniteGuard, or None for none."""
        self.model = model
        self.guard = guard
        self.rate_floors = rate_floors
        self.rate_from_deflection = rate_from_deflection
        # The last step: (deflection at its start, the rate held over it, its size).
        self.previous = None
        self.rate_warned = False
        self.integrator = Rosenbrock(rtol)
        self.time = start_time
        self.deflection = deflection
        self.rate = rate
        self.state = model.initial_state(deflection, rate)
        self._outputs = None
        self._single_step = self.integrator.single_step(model)

    def set_inputs(self, deflection, rate):
        """Returns an error message (and changes nothing) if the model cannot take them."""
        problem = self.input_problem(deflection, rate)
        if problem:
            return problem
        self.take_inputs(deflection, rate)
        return None

    def input_problem(self, deflection, rate):
        problem = self.model.check_input(self.state, deflection)
        guard = self.guard
        if problem or guard is None or not guard.watches(deflection, rate):
            return problem
        state = self.state[:]
        self.model.take_input(state, deflection)
        return guard.input_problem(self.model.outputs(state, deflection, rate), deflection, rate)

    def take_inputs(self, deflection, rate):
        """Inputs that input_problem has accepted."""
        self.model.take_input(self.state, deflection)
        self.deflection = deflection
        self.rate = rate
        self._outputs = None

    def do_step(self, current_time, step_size):
        """Advance to current_time + step_size.

        Returns None, (REFUSED, message) when the call cannot follow the last step, or
        (FAILED, message) when the step could not be completed. Either way nothing has
        changed: the models write their state only once the whole step has succeeded, and
        the integrator's memory is put back here. A completed step whose rate did not fit
        the deflection's movement returns (WARNED, secant rate), once per run.
        """
        if not 0.0 < step_size < INFINITY:
            return REFUSED, f"communication step size {step_size!r} s must be positive and finite"
        time = self.time
        # |current_time - time| <= 1e-9 max(1, |time|), written without calls: this runs
        # every step.
        slack = 1e-9 * (time if time > 1.0 else -time if time < -1.0 else 1.0)
        if not -slack <= current_time - time <= slack:
            return REFUSED, (f"current time {current_time!r} s does not follow from the last "
                             f"step, which ended at {time!r} s")
        guard = self.guard
        if guard is not None:
            rate = self._next_rate()
            if guard.watches(self.deflection + rate * step_size, rate):
                return self._guarded_step(current_time, step_size)
        return self._step(current_time, step_size)

    def _next_rate(self):
        """The rate the next step holds: the input, or with rate_from_deflection the
        backward difference over the last step."""
        previous = self.previous
        if previous is not None and self.rate_from_deflection:
            return (self.deflection - previous[0]) / previous[2]
        return self.rate

    def _step(self, current_time, step_size):
        """do_step once the call has been checked."""
        held_rate, previous, secant = self.rate, self.previous, None
        if previous is not None:
            if self.rate_from_deflection:
                self.rate = self._next_rate()
            elif self.rate_floors is not None and not self.rate_warned:
                secant = rate_inconsistency(previous[0], previous[1], previous[2],
                                            self.deflection, self.rate, self.rate_floors)
        # Nearly every step is one integrator step: the generated fused path takes it, or
        # hands it back untouched to the model's advance (Rosenbrock.single_step).
        single_step = self._single_step
        if single_step is not None and single_step(self.state, self.deflection, self.rate,
                                                   step_size):
            return self._completed(current_time, step_size, secant)
        integrator = self.integrator
        memory = integrator.h_next, integrator.w
        try:
            problem = self.model.advance(self.state, self.deflection, self.rate, step_size,
                                         integrator)
        except BaseException:
            integrator.h_next, integrator.w = memory
            self.rate = held_rate
            raise
        if problem:
            integrator.h_next, integrator.w = memory
            self.rate = held_rate
            return FAILED, f"step from t = {current_time:.9g} s by {step_size:.6g} s failed: {problem}"
        return self._completed(current_time, step_size, secant)

    def _guarded_step(self, current_time, step_size):
        """A step that ends beyond the guard's bounds: taken, and undone with FAILED if an
        output after it is not finite."""
        before = self.snapshot()
        outcome = self._step(current_time, step_size)
        if outcome is not None and outcome[0] != WARNED:
            return outcome
        problem = self.guard.step_problem(self.outputs(), self.deflection)
        if problem is None:
            return outcome
        self.restore(before)
        return FAILED, f"step from t = {current_time:.9g} s by {step_size:.6g} s failed: {problem}"

    def _completed(self, current_time, step_size, secant):
        self.previous = (self.deflection, self.rate, step_size)
        self.time = current_time + step_size
        self.deflection += self.rate * step_size
        self._outputs = None
        if secant is None:
            return None
        self.rate_warned = True
        return WARNED, secant

    def outputs(self):
        if self._outputs is None:
            self._outputs = self.model.outputs(self.state, self.deflection, self.rate)
        return self._outputs

    def snapshot(self):
        """Everything a continuation depends on, as plain JSON-able data."""
        return {"time": self.time, "deflection": self.deflection, "rate": self.rate,
                "state": self.state[:], "integrator": self.integrator.memory(),
                "rtol": self.integrator.rtol,
                "previous": list(self.previous) if self.previous is not None else None,
                "rate_warned": self.rate_warned}

    def restore(self, snapshot):
        self.time = snapshot["time"]
        self.deflection = snapshot["deflection"]
        self.rate = snapshot["rate"]
        self.state = list(snapshot["state"])
        self.integrator.recall(snapshot["integrator"])
        self.integrator.rtol = snapshot["rtol"]
        previous = snapshot["previous"]
        self.previous = tuple(previous) if previous is not None else None
        self.rate_warned = snapshot["rate_warned"]
        self._outputs = None
