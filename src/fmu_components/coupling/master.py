"""The coupling of a host's step with its components' FMU steps.

Per host step [t0, t1] a host calls, in this order (exudyn_host.py wires it to exudyn):

    begin_step(t1)          before its solve of the step (again after a retry)
    ... solve ...           force elements call component.host_load(x, v) at every iterate
    end_pass(t1)            after the solve: each FMU steps along the secant to the
                            host's solution; the scheme says ACCEPT, or REPEAT the solve
                            with the components' new load laws, or RETRY a shorter step
    accept()                when the host accepts the step
    reject()                when the host gives the step up for a reason of its own

The schemes (schemes.py) decide the load laws and how many passes a step takes.
"""

import warnings
from dataclasses import dataclass

from .errors import CouplingError, StepDiscarded
from .schemes import scheme_named


@dataclass
class Verdict:
    repeat: bool = False  # solve the step again with the new load laws
    retry_step: float = None  # reject the step, retry it with this step size
    mismatch: float = 0.0  # largest |FMU load - host load| / load scale of the pass


ACCEPT = Verdict()
# A host that cannot retry a step gets a discarded FMU step cut into up to this many pieces.
MAX_PIECES = 64


def count_unconverged(coupling, time, mismatch):
    """A step the pass limit stopped before its loads agreed: counted in the coupling's
    (a Coupling's or a Bank's) unconverged_steps, the first with a warning."""
    coupling.unconverged_steps += 1
    if coupling.unconverged_steps == 1:
        warnings.warn(f"{coupling.scheme.name} coupling: at t = {time:.6g} s the loads still "
                      f"differ by {mismatch:.2g} of their scale after {coupling.passes} "
                      f"passes (the limit); further steps like it are counted in "
                      f"unconverged_steps", stacklevel=3)


class Coupling:
    """Components coupled to one host by one scheme. `add(component, read_state)` pairs a
    component with the function that returns its (deflection, rate) at the host's current
    state; `record(t)`, if given, is called after each accepted step."""

    def __init__(self, scheme="corrected", record=None, host_can_retry=True):
        self.scheme = scheme_named(scheme) if isinstance(scheme, str) else scheme
        self.record = record
        self.host_can_retry = host_can_retry
        self.entries = []
        self.time = None
        self.passes = 0  # in the current step
        self.steps = 0  # accepted
        self.total_passes = 0
        self.retries = 0  # steps retried shorter (or FMU steps cut) for a discarded one
        self.unconverged_steps = 0
        self.last_mismatch = 0.0

    def add(self, component, read_state):
        self.entries.append((component, read_state))

    @property
    def components(self):
        return [component for component, _ in self.entries]

    def start(self, time):
        self.time = time
        for component, read_state in self.entries:
            deflection, rate = read_state()
            component.start(time, deflection, rate)
            component.law = component.lagged_law()

    def begin_step(self, time):
        """The host starts a step to `time` from the last accepted point."""
        self.passes = 0
        for component in self.components:
            component.begin_step()
            component.law = self.scheme.first_law(component, time)

    def end_pass(self, time):
        """After the host's solve to `time`: step each FMU to the host's solution and
        judge the pass."""
        self.passes += 1
        self.total_passes += 1
        results = []
        try:
            for component, read_state in self.entries:
                deflection, rate = read_state()
                outputs = self._trial(component, time, deflection, rate)
                results.append((component, deflection, rate, outputs))
        except StepDiscarded as discarded:
            for component in self.components:
                component.reject()
            if not self.host_can_retry:
                raise CouplingError(discarded.component, discarded.time,
                                    f"{discarded} (cut into {MAX_PIECES} steps too)") from None
            self.retries += 1
            return Verdict(retry_step=0.5 * (time - self.time))
        mismatch = max((self.scheme.mismatch(c, x, v, out) for c, x, v, out in results),
                       default=0.0)
        self.last_mismatch = mismatch
        if self.scheme.done(self.passes, mismatch):
            if mismatch > self.scheme.tolerance and self.scheme.warn_unconverged:
                count_unconverged(self, time, mismatch)
            return Verdict(mismatch=mismatch)
        for component in self.components:
            component.law = self.scheme.next_law(component)
        return Verdict(repeat=True, mismatch=mismatch)

    def _trial(self, component, time, deflection, rate):
        """The component's trial; a host that cannot retry a step gets the FMU's step
        cut into pieces along the same secant instead (up to MAX_PIECES)."""
        pieces = 1
        while True:
            try:
                return component.trial(time, deflection, rate, pieces=pieces)
            except StepDiscarded:
                if self.host_can_retry or pieces >= MAX_PIECES:
                    raise
                pieces *= 2
                self.retries += 1

    def accept(self, time):
        """The host accepted its step to `time`. A call at the time already reached (a
        host reporting its initial state) only records."""
        if time <= self.time:
            if self.record:
                self.record(time)
            return
        for component in self.components:
            component.accept()
        self.time = time
        self.steps += 1
        if self.record:
            self.record(time)

    def reject(self):
        for component in self.components:
            component.reject()

    def free(self):
        for component in self.components:
            component.free()

    def costs(self):
        """Per accepted host step and component: FMU doSteps, state saves and restores,
        and the host's solves."""
        steps = max(self.steps, 1)
        n = max(len(self.entries), 1)
        return {"do_steps": sum(c.do_steps for c in self.components) / steps / n,
                "saves": sum(c.saves for c in self.components) / steps / n,
                "restores": sum(c.restores for c in self.components) / steps / n,
                "passes": self.total_passes / steps}
