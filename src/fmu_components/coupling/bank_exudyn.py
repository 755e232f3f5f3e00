"""A bank (bank.py) in exudyn (1.13): the load laws in exudyn's compiled symbolic user
functions, the bank's per-step work in the step hooks.

exudyn evaluates a connector's force at every Newton iterate and for its numerical
Jacobian. On the Python path (exudyn_host.py) that is a Python call each time; here each
connector's force is a symbolic expression (exudyn.symbolic, an expression tree that
exudyn's C++ evaluates) of the law of law.py, its numbers x*, F*, K, Q, K_touch read from
one named symbolic matrix that the hooks set once per pass from the bank's `laws`
(with Q/2 and the secant's bounds, so that each iterate evaluates no more than it must)
(exudyn's named symbolic vectors cannot be set beyond a few entries in 1.13; its
matrices can). The hooks:

    pre-step user function      Bank.begin_step, then the laws into the matrix
    post-Newton user function   the host's deflections (one call of the example's, from
                                the system's coordinates), Bank.end_pass; on REPEAT the
                                next laws into the matrix
    post-step user function     Bank.accept, with the next step's begin

exudyn is imported only when these functions run.
"""

from . import exudyn_host
from .exudyn_host import ExudynCoupling


class SymbolicLaws:
    """The bank's laws as one named symbolic matrix, and each component's law as a
    symbolic expression of a deflection (the same operations, in the same order, as
    LoadLaw.__call__)."""

    def __init__(self, bank, name="fmu_bank_laws"):
        import exudyn as exu

        self.esym = exu.symbolic
        self.bank = bank
        self.matrix = self.esym.Matrix(name, bank.laws.tolist())

    def update(self):
        self.matrix.SetMatrix(self.bank.laws)

    def when(self, condition, if_true, if_false):
        """exudyn's IfThenElse of symbolic values or numbers."""
        real = self.esym.Real
        return self.esym.IfThenElse(*(v if isinstance(v, real) else real(float(v))
                                      for v in (condition, if_true, if_false)))

    def load(self, i, deflection):
        """The symbolic load of instance i's law at a symbolic `deflection`."""
        # exudyn's max(a, b) is b > a ? b : a and its min(a, b) b < a ? b : a (ties and NaN
        # to the first), as Python's max and min of two: LoadLaw's to the bit, each
        # argument evaluated once (an IfThenElse would evaluate the clamped secant again
        # in its branch, each time reading the law's numbers from the matrix anew)
        larger, smaller = self.esym.max, self.esym.min
        m = self.matrix
        x_star, load, k, half_q, touch, low, high = (m[i, j] for j in (0, 1, 2, 5, 4, 6, 7))
        dx = deflection - x_star
        # LoadLaw.secant, min(max(K + Q/2 dx, low), high), its bounds from the bank; with
        # Q = 0 it is K
        secant = smaller(larger(k + half_q * dx, low), high)
        about = load + secant * dx
        zero = self.esym.Real(0.0)
        if self.bank.reversible[i]:
            # beyond the reversal's kink (law.py), the tangent for motion the other way
            kink, kink_load, beyond, side = (m[i, j] for j in (8, 9, 10, 11))
            about = self.esym.IfThenElse(side * (deflection - kink) < zero,
                                         kink_load + beyond * (deflection - kink), about)
        if not self.bank.unilateral[i]:
            return about
        touching = larger(zero, touch * (deflection - larger(x_star, zero)))
        return self.esym.IfThenElse(deflection <= zero, zero,
                                    self.esym.IfThenElse(load <= zero, touching,
                                                         larger(about, zero)))


def symbolic_function(mbs, item, function, name="springForceUserFunction"):
    """Record `function` (Python, with symbolic arguments) as item's compiled user function;
    keep the returned object alive as long as the system."""
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    compiled = CreateSymbolicUserFunction(mbs, function, name, item)
    mbs.SetObjectParameter(item, name, compiled)
    return compiled


class ExudynBank(ExudynCoupling):
    """Wires a Bank into an exudyn MainSystem's step hooks; `deflections()` returns the
    host's deflection of every instance now, as one array."""

    def __init__(self, mbs, bank, laws, deflections):
        super().__init__(mbs, bank)
        self.laws, self.deflections = laws, deflections

    def install(self, settings):
        super().install(settings)
        # exudyn's step, as it computes it (its maximum step: the span over the steps); a
        # step ends at the time before plus it
        integration = settings.timeIntegration
        self._step = ((integration.endTime - integration.startTime)
                      / integration.numberOfSteps)
        self._end = integration.endTime

    def _pre_step(self, t):
        super()._pre_step(t)
        self.laws.update()
        return True

    def _post_step(self, t):
        """Bank.accept, which begins the next step in the same call where it ends a step
        later (begin_step then has nothing left to do, one C call fewer per host step;
        a step exudyn shortens or ends early is begun again by begin_step)."""
        self.coupling.accept(t, self._next_end(t))
        return True

    def _next_end(self, t):
        """Where exudyn's next step ends: its step on, and the last one cut to the end
        time; None after the last (no step to begin)."""
        if self._end - t <= 1e-9 * self._step:
            return None
        return min(t + self._step, self._end)

    def _end_pass(self, t):
        verdict = self.coupling.end_pass(t, self.deflections())
        if verdict.repeat and verdict.retry_step is None:
            self.laws.update()
        return verdict


class _Starting:
    """What exudyn_host.solve starts and frees: the bank at the host's initial state
    (`initial()`: deflections, or (deflections, rates)), its laws in the symbolic matrix."""

    def __init__(self, bank, laws, initial):
        self.bank, self.laws, self.initial = bank, laws, initial

    def start(self, time):
        state = self.initial()
        self.bank.start(time, *(state if isinstance(state, tuple) else (state,)))
        self.laws.update()

    def free(self):
        self.bank.free()


def solve(mbs, bank, laws, deflections, end_time, step, start_time=0.0, settings=None,
          initial=None, step_check=None):
    """exudyn_host.solve for a bank: start its components at the host's initial state
    (`initial()`, (deflections, rates), where the host has the rates; else `deflections()`
    at rest), integrate with generalized-alpha at `step` to the first multiple of it at or
    after end_time (`step_check` as exudyn_host.solve's). Frees the bank. Returns the
    ExudynBank."""
    return exudyn_host.solve(mbs, _Starting(bank, laws, initial or deflections), end_time,
                             step, start_time, settings,
                             host=ExudynBank(mbs, bank, laws, deflections), step_check=step_check)
