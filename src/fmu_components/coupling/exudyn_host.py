"""The coupling in exudyn (1.13): its step hooks, and the state of its connectors.

exudyn's implicit solvers take a step as a Newton solve followed by its post-Newton user
function, which may ask for the step to be solved again from its start (a
"discontinuous iteration") or retried with a smaller step. So:

    pre-step user function      Coupling.begin_step (also before a retried step)
    connector force functions   component.host_load(x, v), at every Newton iterate and
                                for exudyn's numerical Jacobian
    post-Newton user function   Coupling.end_pass: [0, -1] accepts, [1, -1] solves the
                                step again, [1, h] retries it with step h
    post-step user function     Coupling.accept

exudyn is imported here only, and only when these functions run.
"""

import math
import time

from .master import Coupling


def connector_state(mbs, connector):
    """Displacement and velocity of a connector at the host's current state, as its force
    user function receives them."""
    import exudyn as exu

    return (mbs.GetObjectOutput(connector, exu.OutputVariableType.Displacement),
            mbs.GetObjectOutput(connector, exu.OutputVariableType.Velocity))


class ExudynCoupling:
    """Wires a Coupling into an exudyn MainSystem's step hooks. An error raised in a hook
    (an FMU's error, a non-finite output) stops the solve and is raised again by `solve`,
    with its own message, instead of exudyn's report of a failed user function."""

    # exudyn compares the post-Newton function's first value with this
    _TOLERANCE = 0.5

    def __init__(self, mbs, coupling: Coupling):
        self.mbs = mbs
        self.coupling = coupling
        self.failure = None
        self.attempts = 0  # steps begun, retries included
        self.solve_cpu = 0.0  # CPU seconds of the process in the dynamic solve (solve())

    def _guarded(self, hook, failed_value):
        def run(mbs, t):
            if self.failure is not None:
                return failed_value
            try:
                return hook(t)
            except Exception as error:  # handed back by solve()
                self.failure = error  # the pre- and post-step hooks' False stop exudyn
                return failed_value
        return run

    def _pre_step(self, t):
        self.attempts += 1
        self.coupling.begin_step(t)
        return True

    def _post_newton(self, t):
        verdict = self.coupling.end_pass(t)
        if verdict.retry_step is not None:
            return [1.0, verdict.retry_step]
        return [1.0 if verdict.repeat else 0.0, -1.0]

    def _post_step(self, t):
        self.coupling.accept(t)
        return True

    def install(self, settings):
        """Set the hooks, and the solver settings they need: up to `passes` solves of a
        step (one more, so that the last pass can still ask for a retry), and adaptive
        steps, so that a retry can shorten one."""
        mbs = self.mbs
        mbs.SetPreStepUserFunction(self._guarded(self._pre_step, False))
        mbs.SetPostNewtonUserFunction(self._guarded(self._post_newton, [0.0, -1.0]))
        mbs.SetPostStepUserFunction(self._guarded(self._post_step, False))
        discontinuous = settings.timeIntegration.discontinuous
        discontinuous.iterationTolerance = self._TOLERANCE
        discontinuous.maxIterations = self.coupling.scheme.passes + 1
        discontinuous.ignoreMaxIterations = True
        discontinuous.useRecommendedStepSize = True
        settings.timeIntegration.adaptiveStep = True

    def uninstall(self):
        for setter in (self.mbs.SetPreStepUserFunction, self.mbs.SetPostNewtonUserFunction,
                       self.mbs.SetPostStepUserFunction):
            setter(0)


def solve(mbs, coupling, end_time, step, start_time=0.0, settings=None, host=None):
    """Start the components at the host's initial state, then integrate with exudyn's
    implicit generalized-alpha at `step` (shortened only where a component asks for a
    retry) to the first multiple of it at or after end_time, coupling the components by
    the coupling's scheme. Frees the components. Returns the ExudynCoupling (its
    `attempts` against coupling.steps count retries; `solve_cpu`, the solve's CPU time,
    the system's building and the components' start left out); `host`, one made already
    (a bank's, bank_exudyn.py)."""
    import exudyn as exu

    host = host or ExudynCoupling(mbs, coupling)
    if settings is None:
        settings = exu.SimulationSettings()
        settings.timeIntegration.verboseMode = 0
        settings.solution.file.write = False
        settings.solution.sensors.active = False
    steps = math.ceil((end_time - start_time) / step - 1e-9)
    settings.timeIntegration.startTime = start_time
    settings.timeIntegration.endTime = start_time + steps * step
    settings.timeIntegration.numberOfSteps = steps
    host.install(settings)
    try:
        coupling.start(start_time)
        began = time.process_time()
        ok = mbs.SolveDynamic(settings, solverType=exu.DynamicSolverType.GeneralizedAlpha)
        host.solve_cpu = time.process_time() - began
    except Exception:
        if host.failure is not None:
            raise host.failure from None
        raise
    finally:
        host.uninstall()
        coupling.free()
    if host.failure is not None:
        raise host.failure
    if not ok:
        raise RuntimeError("exudyn's dynamic solver failed")
    return host
