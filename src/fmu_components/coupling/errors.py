"""What the coupling raises."""


class CouplingError(RuntimeError):
    """An FMU refused a call or returned something a host cannot use. The message names
    the component, the time and what the FMU logged; `status` is the FMI status the call
    answered (2 Discard, 3 Error, 4 Fatal), None where the error is not a call's status."""

    def __init__(self, component, time, message, status=None):
        super().__init__(f"{component} at t = {time:.9g} s: {message}")
        self.component = component
        self.time = time
        self.status = status


class StepDiscarded(Exception):
    """fmi2DoStep answered fmi2Discard: the FMU could not complete the step it was given
    and is back at the state saved at the step's start. The host retries a shorter step."""

    def __init__(self, component, time, step, message):
        super().__init__(f"{component}: the step from t = {time:.9g} s by {step:.3g} s was "
                         f"discarded ({message}); retry a shorter host step")
        self.component = component
        self.time = time
        self.step = step


class StepRefused(RuntimeError):
    """The host's check refused a step's solution (it jumped: `what` says where) at every
    step length down to the shortest the host tries."""

    def __init__(self, what, time, step):
        super().__init__(f"{what} at t = {time:.4f} s, on steps down to {step:.3g} s")
        self.what = what
        self.time = time
        self.step = step
