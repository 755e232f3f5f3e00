"""The coupling in exudyn (1.13): its step hooks, and the state of its connectors.

exudyn's implicit solvers take a step as a Newton solve followed by its post-Newton user
function, which may ask for the step to be solved again from its start (a
"discontinuous iteration") or retried with a smaller step. So:

    pre-step user function      Coupling.begin_step (also before a retried step)
    connector force functions   component.host_load(x, v), at every Newton iterate and
                                for exudyn's numerical Jacobian
    post-Newton user function   the host's step check, if one is given: [1, h/2]
                                retries a step whose solution jumped; then
                                Coupling.end_pass: [0, -1] accepts, [1, -1] solves the
                                step again, [1, h] retries it with step h
    post-step user function     Coupling.accept
    pre-Newton-residual user    a step solved again starts from the last pass's solution
    function                    (where the settings give Newton an absolute tolerance)

exudyn is imported here only, and only when these functions run.
"""

import math
import time

from .errors import StepRefused
from .master import Coupling

# A step the step check refuses is retried at half its length, down to this share of the
# host step (six halvings); one refused even there ends the solve (StepRefused).
SHORTEST_STEP = 1.0 / 64


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

    def __init__(self, mbs, coupling: Coupling, step_check=None):
        """step_check(mbs, t), if given, judges each solve's solution against the step's
        start before the coupling does: None accepts it, else a description of what
        jumped (naming the part), and the step is retried at half its length."""
        self.mbs = mbs
        self.coupling = coupling
        self.step_check = step_check
        self.shortest_step = 0.0  # solve() sets it from the host step
        self.refused = 0  # solves the step check refused
        self.failure = None
        self.attempts = 0  # steps begun, retries included
        self.solve_cpu = 0.0  # CPU seconds of the process in the dynamic solve (solve())
        self.warm_start = False  # a step's next pass starts from the last's solution
        self._solved = None  # a pass's solution, where the step is solved again
        self._warm_hook = False  # _pre_newton_residual is set in exudyn

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
        if self._warm_hook:  # a step exudyn shortened itself (its Newton failed)
            self._warm(False)
        self.coupling.begin_step(t)
        return True

    def _end_pass(self, t):
        return self.coupling.end_pass(t)

    def _post_newton(self, t):
        if self.step_check is not None:
            jumped = self.step_check(self.mbs, t)
            if jumped is not None:
                return self._refuse(t, jumped)
        verdict = self._end_pass(t)
        if verdict.retry_step is not None:
            self._warm(False)
            return [1.0, verdict.retry_step]
        self._warm(verdict.repeat)
        return [1.0 if verdict.repeat else 0.0, -1.0]

    def _refuse(self, t, jumped):
        """A solution that jumped: the components back to the step's start, the step
        retried at half its length (exudyn's recommended step: with adaptive steps it
        solves the step again from its start at that length and lengthens its steps
        again after adaptiveStepRecoverySteps good ones); below the shortest step the
        solve ends."""
        step = t - self.coupling.time
        if 0.5 * step < self.shortest_step * (1.0 - 1e-9):
            raise StepRefused(jumped, t, step)
        self.coupling.reject()
        self.refused += 1
        self._warm(False)
        return [1.0, 0.5 * step]

    def _warm(self, repeat):
        """Where the step is solved again, keep this pass's solution, and let exudyn call
        _pre_newton_residual in the next pass only: it calls it before every residual,
        and each call costs more than the function does where it has nothing to do."""
        if not self.warm_start:
            return
        if repeat:
            self._keep_state()
            if not self._warm_hook:
                self.mbs.SetPreNewtonResidualUserFunction(self._pre_newton_residual)
        elif self._warm_hook:
            self.mbs.SetPreNewtonResidualUserFunction(0)
        self._warm_hook = repeat

    def _keep_state(self):
        """Keep the current coordinates, velocities, accelerations and Lagrange multipliers
        (exudyn's copies; reading its vectors' views into arrays kept for the solve
        measured no cheaper)."""
        import exudyn as exu

        data, current = self.mbs.systemData, exu.ConfigurationType.Current
        self._solved = (data.GetODE2Coordinates(current), data.GetODE2Coordinates_t(current),
                        data.GetODE2Coordinates_tt(current), data.GetAECoordinates(current))

    def _pre_newton_residual(self, mbs, t, newton_iteration, discontinuous_iteration):
        """A step solved again (the coupling's next pass) starts from the last pass's
        solution instead of exudyn's predictor, so that its Newton iterations solve only
        what the laws' change moved. exudyn calls this after its predictor, before each
        residual (set only for a pass that follows another: _warm); generalized-alpha's
        update is linear in the Newton increment (q, v, a move by d, gamma' d, beta' d),
        so that solution is a consistent start."""
        if newton_iteration != 0 or discontinuous_iteration == 0:
            return
        import exudyn as exu

        data, current = mbs.systemData, exu.ConfigurationType.Current
        q, v, a, multipliers = self._solved
        data.SetODE2Coordinates(q, current)
        data.SetODE2Coordinates_t(v, current)
        data.SetODE2Coordinates_tt(a, current)
        data.SetAECoordinates(multipliers, current)

    def _post_step(self, t):
        self.coupling.accept(t)
        return True

    def install(self, settings):
        """Set the hooks, and the solver settings they need: up to `passes` solves of a
        step (one more, so that the last pass can still ask for a retry), and adaptive
        steps, so that a retry can shorten one. Where the settings give Newton an
        absolute tolerance (above exudyn's default) and the scheme repeats a step, a
        step's next pass starts from the last pass's solution (`_pre_newton_residual`);
        without one exudyn's relative test alone would ask that pass for 1e-8 of its own,
        much smaller, first residual, below what round-off allows."""
        import exudyn as exu

        mbs = self.mbs
        mbs.SetPreStepUserFunction(self._guarded(self._pre_step, False))
        mbs.SetPostNewtonUserFunction(self._guarded(self._post_newton, [0.0, -1.0]))
        mbs.SetPostStepUserFunction(self._guarded(self._post_step, False))
        default = exu.SimulationSettings().timeIntegration.newton.absoluteTolerance
        self.warm_start = (settings.timeIntegration.newton.absoluteTolerance > default
                           and self.coupling.scheme.passes > 1)
        self._warm_hook = False
        mbs.SetPreNewtonResidualUserFunction(0)
        discontinuous = settings.timeIntegration.discontinuous
        discontinuous.iterationTolerance = self._TOLERANCE
        discontinuous.maxIterations = self.coupling.scheme.passes + 1
        discontinuous.ignoreMaxIterations = True
        discontinuous.useRecommendedStepSize = True
        settings.timeIntegration.adaptiveStep = True

    def uninstall(self):
        for setter in (self.mbs.SetPreStepUserFunction, self.mbs.SetPostNewtonUserFunction,
                       self.mbs.SetPostStepUserFunction,
                       self.mbs.SetPreNewtonResidualUserFunction):
            setter(0)


def quiet_settings(newton_tolerance=None):
    """exudyn's simulation settings for a coupled solve: quiet, no files or sensors; Newton
    to an absolute tolerance (on its residual's norm per coordinate, a scale that follows the
    step) where one is given, which
    lets a step's next pass start from the last's solution (ExudynCoupling.install)."""
    import exudyn as exu

    settings = exu.SimulationSettings()
    settings.timeIntegration.verboseMode = 0
    settings.solution.file.write = False
    settings.solution.sensors.active = False
    if newton_tolerance is not None:
        settings.timeIntegration.newton.absoluteTolerance = newton_tolerance
    return settings


def solve(mbs, coupling, end_time, step, start_time=0.0, settings=None, host=None,
          step_check=None):
    """Start the components at the host's initial state, then integrate with exudyn's
    implicit generalized-alpha at `step` (shortened only where a component asks for a
    retry, or `step_check` refuses a solution: ExudynCoupling) to the first multiple of it
    at or after end_time, coupling the components by the coupling's scheme. Frees the
    components. Returns the ExudynCoupling (its `attempts` against coupling.steps count
    retries; `solve_cpu`, the solve's CPU time, the system's building and the components'
    start left out); `host`, one made already (a bank's, bank_exudyn.py). Raises
    StepRefused where the step check refuses a step SHORTEST_STEP of `step` long."""
    import exudyn as exu

    host = host or ExudynCoupling(mbs, coupling)
    if step_check is not None:
        host.step_check = step_check
    host.shortest_step = SHORTEST_STEP * step
    if settings is None:
        settings = quiet_settings()
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
