"""The one stiff integrator shared by every component.

A Rosenbrock-W method, ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761-787): four stages,
order 3 with an embedded order-2 solution for error control, L-stable and stiffly
accurate, free of order reduction on the Prothero-Robinson problem. Rosenbrock methods are
linearly implicit: each step factors W = I/(gamma*h) - J once and solves a few small
linear systems, so there are no Newton iterations to converge or fail. The problems here
are small (two states per nested rubber branch, two for the damper).

The integrator knows nothing of what it integrates. A *system* (``model.Model``) gives its
equations as expression trees (``equations``: ``held``, ``stage``, ``jacobian``, ``region``,
see ``model.Equations``), the printer that turns them into Python with its parameter values
(``printer``), the functions they call (``namespace``) and ``state_scale``, a typical
magnitude of each state, which sets the absolute tolerance ``rtol * state_scale``.

Steps that fail the error test, or whose stages leave the valid region or stop being
finite, are rejected and retried smaller; nothing is ever clipped. A failure comes back as
a message, never as an exception in the middle of a step.

One step, its factorisation of W and its error norm are statements built here from the
tableau and the system's equations (``factor_statements``, ``step_statements``), which
either printer prints: as Python below, as C for the native flavour (``fmu_components.export.cgen``).
The Python is straight-line code, once per system, so that a step of a two-state system
costs about two microseconds in CPython rather than tens: no loops, no lists, and no
function call per stage, which would cost more than the stage's arithmetic. A
communication step that is one integrator step, nearly every step at 1 ms, goes through a
second generated function that also holds the step-size control and the model's
closed-form part (``Rosenbrock.single_step``), bit for bit what ``integrate`` and the
model's ``advance`` would do, without their loops and calls.
"""

import math

from .expressions import (Assign, Number, Require, Symbol, all_of, differs, equal, total,
                          where)

DEFAULT_RTOL = 1e-4
"""Relative tolerance used when the host gives none in fmi2SetupExperiment."""

MAX_STEPS_PER_CALL = 100_000
STEP_GROWTH_LIMIT = 5.0
STEP_SHRINK_LIMIT = 0.2
SAFETY = 0.9
REGION_SHRINK = 0.25
# W^-1 made for step size h' is reused for steps within this relative distance of h'. Hosts
# whose clocks count integer nanoseconds, or add up step sizes, hand over communication
# steps that differ in the last bits; without the margin such a host would rebuild W every
# step, and its results would differ at the tolerance level from a host's with exact steps.
# A W-method keeps its order for any W, so the W of a step a few ulps longer is as good.
SAME_STEP_SIZE = 1e-9


class RosenbrockTableau:
    """A Rosenbrock method in the form that needs no matrix-vector products (Hairer &
    Wanner IV.7.25, as in KPP and RODAS):

        (I/(gamma*h) - J) k_i = f(y + sum_j a_ij k_j) + sum_j (c_ij/h) k_j
        y1 = y + sum_i m_i k_i,  error = sum_i e_i k_i.
    """

    def __init__(self, name, order, embedded_order, gamma, a, c, m, e):
        self.name = name
        self.order = order
        self.embedded_order = embedded_order
        self.gamma = gamma
        self.a = a  # strictly lower triangular, rows
        self.c = c
        self.m = m
        self.e = e
        # The step-size controller's power of the squared error norm (the steps compute
        # the square, which saves a root): h * err^(-1/(p+1)) for an order-p estimate.
        self.squared_error_exponent = -0.5 / (embedded_order + 1)
        # Stiffly accurate: the solution is the last stage's state plus the last k (m_j =
        # a_last,j, m_last = 1), which the step uses to save the weighted sum.
        last = len(m) - 1
        self.stiffly_accurate = m[last] == 1.0 and all(
            abs(m[j] - a[last][j]) <= 1e-14 * max(1.0, abs(m[j])) for j in range(last))

    @classmethod
    def from_standard_form(cls, name, order, embedded_order, alpha, gamma, b, bhat):
        """From the form of Hairer & Wanner IV.7.4,

            (I - gamma*h*J) k_i = h f(y + sum_j alpha_ij k_j) + h J sum_j gamma_ij k_j,

        by A = alpha Gamma^-1, C = diag(1/gamma) - Gamma^-1, m = b Gamma^-1 and
        e = (b - bhat) Gamma^-1."""
        stages = len(b)
        inverse = _lower_triangular_inverse(gamma)
        a = [[sum(alpha[i][k] * inverse[k][j] for k in range(stages)) for j in range(i)]
             for i in range(stages)]
        c = [[-inverse[i][j] for j in range(i)] for i in range(stages)]
        m = [sum(b[k] * inverse[k][j] for k in range(stages)) for j in range(stages)]
        e = [sum((b[k] - bhat[k]) * inverse[k][j] for k in range(stages)) for j in range(stages)]
        tableau = cls(name, order, embedded_order, gamma[0][0], a, c, m, e)
        tableau.standard_form = (alpha, gamma, b, bhat)
        return tableau


def _lower_triangular_inverse(lower):
    n = len(lower)
    inverse = [[0.0] * n for _ in range(n)]
    for i in range(n):
        inverse[i][i] = 1.0 / lower[i][i]
        for j in range(i):
            inverse[i][j] = -sum(lower[i][k] * inverse[k][j] for k in range(j, i)) / lower[i][i]
    return inverse


_G = 0.435866521508459
ROS34PW2 = RosenbrockTableau.from_standard_form(
    "ROS34PW2", order=3, embedded_order=2,
    alpha=[[0.0, 0.0, 0.0, 0.0],
           [0.87173304301691801, 0.0, 0.0, 0.0],
           [0.84457060015369423, -0.11299064236484185, 0.0, 0.0],
           [0.0, 0.0, 1.0, 0.0]],
    gamma=[[_G, 0.0, 0.0, 0.0],
           [-0.87173304301691801, _G, 0.0, 0.0],
           [-0.90338057013044082, 0.054180672388095326, _G, 0.0],
           [0.24212380706095346, -1.2232505839045147, 0.54526025533510214, _G]],
    b=[0.24212380706095346, -1.2232505839045147, 1.5452602553351020, _G],
    bhat=[0.37810903145819369, -0.096042292212423178, 0.5, 0.2179332607542295],
)


def invert(matrix):
    """Inverse of a small dense matrix (rows), by Gauss-Jordan with partial pivoting.
    Returns None when it is singular to working precision."""
    n = len(matrix)
    work = [list(row) + [1.0 if i == j else 0.0 for j in range(n)] for i, row in enumerate(matrix)]
    for col in range(n):
        pivot = max(range(col, n), key=lambda i: abs(work[i][col]))
        if work[pivot][col] == 0.0 or not math.isfinite(work[pivot][col]):
            return None
        work[col], work[pivot] = work[pivot], work[col]
        scale = 1.0 / work[col][col]
        work[col] = [value * scale for value in work[col]]
        for i in range(n):
            if i != col and work[i][col] != 0.0:
                factor = work[i][col]
                work[i] = [a - factor * b for a, b in zip(work[i], work[col])]
    return [row[n:] for row in work]


# --- the step as statements, for either printer -------------------------------------------

def _names(prefix, n):
    return [f"{prefix}{i}" for i in range(n)]


def _combination(terms):
    """sum of coefficient * symbol, dropping zero coefficients and unit factors."""
    parts = [Symbol(name) if coefficient == 1.0 else coefficient * Symbol(name)
             for coefficient, name in terms if coefficient]
    return total(parts) if parts else Number(0.0)


def jacobian_statements(equations):
    """d rhs / dy into j0_0 .. at the stage state Y0 .. (entries the equations leave unset
    are zero): the held and stage statements first, whose values the Jacobian's may use."""
    n = equations.integrated
    zero = [Assign(Symbol(f"j{i}_{k}"), 0.0) for i in range(n) for k in range(n)]
    return zero + list(equations.held) + list(equations.stage) + list(equations.jacobian)


def factor_statements(tableau, equations):
    """W = I/(gamma h) - J at Y0 .., u, h: for two states its inverse into w0 .. w3, which
    fails when W is singular; for more, the matrix entries (the caller inverts them)."""
    n = equations.integrated
    d = Symbol("d")
    lines = jacobian_statements(equations) + [Assign(d, 1.0 / (tableau.gamma * Symbol("h")))]
    j = [[Symbol(f"j{i}_{k}") for k in range(n)] for i in range(n)]
    if n != 2:
        return lines, [[d - j[i][k] if i == k else -j[i][k] for k in range(n)] for i in range(n)]
    a, b, det = Symbol("a"), Symbol("b"), Symbol("det")
    lines += [Assign(a, d - j[0][0]), Assign(b, d - j[1][1]),
              Assign(det, a * b - j[0][1] * j[1][0]),
              # x - x is 0 for finite x: "det is finite and not zero", without a call
              Require(all_of(differs(det, 0.0), equal(det - det, 0.0))),
              Assign(Symbol("w0"), b / det), Assign(Symbol("w1"), j[0][1] / det),
              Assign(Symbol("w2"), j[1][0] / det), Assign(Symbol("w3"), a / det)]
    return lines, None


def step_statements(tableau, equations, state_scale):
    """One step from y0 .. with W^-1 in w00 .. (row-major, w{i}{j}), input u, size h and
    tolerance rtol: the new state into Y0 .. and the squared, filtered error norm into
    ``error``. It fails when a stage or the result leaves the valid region or is not
    finite.

    The error is filtered through (I - gamma*h*J)^-1 = W^-1/(gamma*h) before its norm is
    taken: the embedded solution is not L-stable (|Rhat(inf)| = 0.48), and a raw estimate
    would report stiff transients as error at any step size (Hairer & Wanner IV.8, the
    RADAU5 estimate)."""
    n = equations.integrated
    if n == 0:  # everything advances in closed form: the runtimes never take this step
        return [Assign(Symbol("error"), 0.0)]
    q = range(n)
    stages = range(len(tableau.m))
    Y, y = [Symbol(f"Y{i}") for i in q], [Symbol(f"y{i}") for i in q]
    w = [[Symbol(f"w{i}{k}") for k in q] for i in q]
    region = [] if equations.region is None else [Require(equations.region)]
    lines = [Assign(Symbol("d"), 1.0 / (tableau.gamma * Symbol("h"))),
             Assign(Symbol("ih"), 1.0 / Symbol("h"))]
    lines += [Assign(Y[i], y[i]) for i in q]
    lines += equations.held
    for s in stages:
        if s > 0:
            for i in q:
                lines.append(Assign(Y[i], _combination(
                    [(1.0, f"y{i}")] + [(tableau.a[s][j], f"k{j}_{i}") for j in range(s)])))
            lines += region
        lines += equations.stage
        right = "f"  # the right-hand side of the stage's linear system, f + sum c_ij/h k_j
        if any(tableau.c[s][j] for j in range(s)):
            right = "r"
            for i in q:
                lines.append(Assign(Symbol(f"r{i}"), Symbol(f"f{i}") + Symbol("ih") * _combination(
                    [(tableau.c[s][j], f"k{j}_{i}") for j in range(s)])))
        for i in q:
            lines.append(Assign(Symbol(f"k{s}_{i}"),
                                total([w[i][j] * Symbol(f"{right}{j}") for j in q])))
    last = len(tableau.m) - 1
    for i in q:
        if tableau.stiffly_accurate:
            # y1 = y + sum_j a_last,j k_j + k_last: the last stage's state plus its k.
            lines.append(Assign(Y[i], Y[i] + Symbol(f"k{last}_{i}")))
        else:
            lines.append(Assign(Y[i], _combination(
                [(1.0, f"y{i}")] + [(tableau.m[s], f"k{s}_{i}") for s in stages])))
        lines.append(Assign(Symbol(f"e{i}"), Symbol("d") * _combination(
            [(tableau.e[s], f"k{s}_{i}") for s in stages])))
    # A sum is finite only if every term is (or it overflows, which is no valid state
    # either), and x - x is 0 for finite x, nan for inf and nan: the test without a call.
    lines.append(Assign(Symbol("sum_Y"), total(Y)))
    lines.append(Require(equal(Symbol("sum_Y") - Symbol("sum_Y"), 0.0)))
    lines += region
    for i in q:
        a, b = Symbol(f"a{i}"), Symbol(f"b{i}")
        lines += [Assign(a, abs(y[i])), Assign(b, abs(Y[i])),
                  Assign(Symbol(f"z{i}"), total([w[i][j] * Symbol(f"e{j}") for j in q])
                         / (state_scale[i] + where(b > a, b, a)))]
    # The squared norm: its tests against 1 and 0 are the norm's, and the controller takes
    # its power with half the exponent, which saves the square root.
    lines.append(Assign(Symbol("error"), total([Symbol(f"z{i}") * Symbol(f"z{i}") for i in q])
                        / (float(n) * Symbol("rtol") * Symbol("rtol"))))
    return lines


# --- the step in Python -----------------------------------------------------------------------

def _function(signature, body, result):
    return "\n".join([f"def {signature}:"] + [f"    {line}" for line in body]
                     + [f"    return {result}"])


def _tuple(names):
    return "(" + ", ".join(names) + ",)"


def compile_python(text, namespace, label):
    namespace = {"math": math, "invert": invert, **namespace}
    exec(compile(text, label, "exec"), namespace)
    return namespace


def python_step(tableau, system):
    """Straight-line Python for one step of `tableau` on `system` (a compiled model:
    ``equations``, ``printer()`` and ``state_scale``): the source of three functions,

    * ``factor(y, u, h)``: W^-1 = (I/(gamma*h) - J(y, u))^-1 as a flat tuple, or None
      when W is singular;
    * ``step(y, u, h, rtol, w)``: one step with that W^-1, returning
      ``(y_new, error_norm ** 2)``, or None when a stage or the result leaves the valid
      region or is not finite;
    * ``single_step_for(memory, max_reuse)``: the single-step path of a Rosenbrock
      instance (``memory``), see ``Rosenbrock.single_step``.
    """
    equations = system.equations
    n = equations.integrated
    Y, y = _names("Y", n), _names("y", n)
    inverse = [f"w{i}{k}" for i in range(n) for k in range(n)]
    factor_lines, matrix = factor_statements(tableau, equations)
    printer = system.printer(["u", "h", *Y])
    body = [f"{_tuple(Y)} = y"] + printer.statements(factor_lines, "return None")
    if matrix is None:
        factor = _function("factor(y, u, h)", body, _tuple(_names("w", 4)))
    else:
        rows = ", ".join("[" + ", ".join(printer.expression(e) for e in row) + "]" for row in matrix)
        body.append(f"inverse = invert([{rows}])")
        factor = _function("factor(y, u, h)", body,
                           "None if inverse is None else tuple(v for row in inverse for v in row)")
    statements = step_statements(tableau, equations, [Number(s) for s in system.state_scale])
    printer = system.printer(["u", "h", "rtol", *y, *inverse])
    step = _function("step(y, u, h, rtol, w)",
                     [f"{_tuple(y)} = y", f"{_tuple(inverse)} = w",
                      *printer.statements(statements, "return None")],
                     f"{_tuple(Y)}, error")
    return "\n\n\n".join([factor, step, _single_step_source(tableau, system, statements,
                                                                inverse)]) + "\n"


def _single_step_source(tableau, system, statements, inverse):
    """``single_step_for(memory, max_reuse)``: the one-step case of ``Rosenbrock.integrate``
    fused with the model's closed-form update, as one function. It decides, reuses or
    rebuilds W^-1 and controls the step size exactly as ``integrate`` does, so a step it
    takes is bit for bit the one ``integrate`` would take; whenever ``integrate`` would do
    anything else it returns False having changed nothing."""
    equations = system.equations
    n = equations.integrated
    y = _names("y", n)
    printer = system.printer(["state", "x", "u", "h", "rtol"])
    body = []
    if equations.unilateral:  # the rubber rate is u over the whole step (Model.rate_segments)
        body += ["if not (x > 0.0 and x + u * h > 0.0):", "    return False"]
    body += ["h_control = memory.h_next",
             "if h_control is None:",
             "    h_control = h",
             "elif h_control < h:",
             "    return False  # the controller wants more than one step"]
    body += printer.statements(equations.start_statements(), "return False")
    body += ["cached = memory.w",
             f"same = {SAME_STEP_SIZE!r} * h",
             "if cached is not None and -same <= cached[0] - h <= same and cached[2] < max_reuse:",
             "    w = cached[1]",
             "    uses = cached[2] + 1",
             "else:",
             f"    w = factor({_tuple(y)}, u, h)",
             "    if w is None:",
             "        return False",
             "    uses = 1",
             f"{_tuple(inverse)} = w",
             "rtol = memory.rtol"]
    printer.known.update(inverse)
    body += printer.statements(statements, "return False")
    body += ["if not error <= 1.0:",
             "    return False",
             f"allowed = h * {SAFETY!r} * error ** ({tableau.squared_error_exponent!r})"
             " if error > 0.0 else inf",
             f"grown = {STEP_GROWTH_LIMIT!r} * h_control",
             f"shrunk = {STEP_SHRINK_LIMIT!r} * h_control",
             # integrate's min(grown, max(shrunk, allowed)), without the call
             "memory.h_next = grown if allowed > grown else allowed if allowed > shrunk else shrunk",
             "memory.w = (h, w, uses)",
             "memory.accepted_steps += 1"]
    body += printer.statements(equations.exact, "return False")  # held values in scope
    body += [f"state[{i}] = Y{i}" for i in range(n)]
    body.append("return True")
    return "\n".join(["def single_step_for(memory, max_reuse):",
                      "    def single_step(state, x, u, h, inf=math.inf):",
                      *[f"        {line}" for line in body],
                      "    return single_step"])


class Rosenbrock:
    """Adaptive integration of an autonomous system over a given duration.

    Between calls it keeps ``h_next``, the step size its controller would take next, so
    that consecutive communication steps do not restart from a guess, and ``w``, the last
    W^-1 with the step size it was made for. ROS34PW2 is a W-method: its order, and its
    error estimate's, hold for any W, so W^-1 is reused while the step size stays the same
    (to within SAME_STEP_SIZE), and rebuilt from a fresh Jacobian after MAX_W_REUSE steps
    or a rejected step. Both are part of the state a host saves with fmi2GetFMUstate: the
    continuation depends on them.
    """

    MAX_W_REUSE = 8
    # Python source and namespace -> (factor, step, single_step_for, source): systems with
    # the same equations and parameters share one compiled step.
    _compiled = {}
    MAX_COMPILED = 64

    def __init__(self, rtol=DEFAULT_RTOL, tableau=ROS34PW2):
        if not (rtol > 0.0 and math.isfinite(rtol)):
            raise ValueError(f"tolerance must be a positive finite number, got {rtol!r}")
        self.rtol = rtol
        self.tableau = tableau
        self.h_next = None
        self.w = None  # (h, W^-1 as a flat tuple, uses so far)
        self.accepted_steps = 0
        self.rejected_steps = 0
        self._last_compiled = (None, None)  # (system, compiled)

    def compiled(self, system):
        """(factor, step, single_step_for, source text) for a system (a compiled model)."""
        last_system, compiled = self._last_compiled
        if last_system is not system:
            # A model shared by many instances (catalog) keeps its step: printed once.
            compiled = system.compiled_steps.get(self.tableau.name)
            if compiled is None:
                source = python_step(self.tableau, system)
                key = (source, tuple(sorted(system.namespace.items())))
                compiled = self._compiled.get(key)
                if compiled is None:
                    if len(self._compiled) >= self.MAX_COMPILED:
                        self._compiled.clear()  # a host sweeping parameters: do not grow forever
                    functions = compile_python(source, system.namespace,
                                               f"<{self.tableau.name} step>")
                    compiled = self._compiled[key] = (functions["factor"], functions["step"],
                                                      functions["single_step_for"], source)
                system.compiled_steps[self.tableau.name] = compiled
            self._last_compiled = (system, compiled)
        return compiled

    def step(self, system, y, u, h):
        """One step of size h with a fresh Jacobian: (y_new, error_norm ** 2), or None."""
        factor, step, _, _ = self.compiled(system)
        w = factor(y, u, h)
        return None if w is None else step(y, u, h, self.rtol, w)

    def single_step(self, system):
        """The single-step path for `system`, a model whose first n state entries this
        integrator advances and whose equations advance the rest in closed form
        (``exact``), or None if it integrates nothing. ``single_step(state, x, u, h)``
        advances the model's state list over a communication step of size h with the rate
        u held, in one integrator step, and returns True; it returns False, with nothing
        changed, when that is not what ``integrate`` would do (the step is not one segment,
        the controller wants smaller steps, the step is rejected). Then the model's own
        ``advance`` takes the step.

        Why: a communication step of 1 ms is one integrator step almost always, and the
        layers between the FMI call and the generated step (co-simulation, model,
        integrator loop) cost more than the step itself (benchmarks/results.md)."""
        if system.equations.integrated == 0:
            return None
        return self.compiled(system)[2](self, self.MAX_W_REUSE)

    def memory(self):
        return {"h_next": self.h_next, "w": list(self.w) if self.w else None}

    def recall(self, memory):
        self.h_next = memory["h_next"]
        self.w = tuple(memory["w"]) if memory["w"] else None
        if self.w:
            self.w = (self.w[0], tuple(self.w[1]), self.w[2])

    def integrate(self, system, y, u, duration):
        """Advance the state list ``y`` in place over ``duration`` with input ``u`` held.

        Returns None on success. On failure returns a message and leaves ``y`` at the
        start value: the caller never sees a partly advanced state.
        """
        if duration <= 0.0 or not y:
            return None
        factor, step, _, _ = self.compiled(system)
        rtol = self.rtol
        exponent = self.tableau.squared_error_exponent
        max_reuse = self.MAX_W_REUSE
        current = tuple(y)
        # h is the step size the controller wants; the step actually tried may be cut
        # short to land on the end of the interval, and the controller then scales its
        # own h (not the short step) by what the error estimate allows.
        h = self.h_next if self.h_next is not None else duration
        h_min = 1e-12 * duration
        end = duration * (1.0 - 1e-13)
        t = 0.0
        steps = 0
        just_rejected = False
        while True:
            remaining = duration - t
            h_try = h if h < remaining else remaining
            steps += 1
            if steps > MAX_STEPS_PER_CALL:
                return (f"integrator needed more than {MAX_STEPS_PER_CALL} steps for a "
                        f"{duration:.6g} s interval at tolerance {rtol:.3g}")
            cached = self.w
            if (cached is not None and abs(cached[0] - h_try) <= SAME_STEP_SIZE * h_try
                    and cached[2] < max_reuse):
                w = cached[1]
                self.w = (h_try, w, cached[2] + 1)
            else:
                w = factor(current, u, h_try)
                self.w = None if w is None else (h_try, w, 1)
            result = None if w is None else step(current, u, h_try, rtol, w)
            if result is None:
                self.rejected_steps += 1
                self.w = None
                h = h_try * REGION_SHRINK
                just_rejected = True
            else:
                new, err = result  # err: the squared error norm
                allowed = h_try * SAFETY * err ** exponent if err > 0.0 else math.inf
                if err <= 1.0:
                    self.accepted_steps += 1
                    current = new
                    t += h_try
                    grown = STEP_GROWTH_LIMIT * h
                    h = grown if allowed > grown else max(STEP_SHRINK_LIMIT * h, allowed)
                    if just_rejected:
                        h = min(h, h_try)
                        just_rejected = False
                    self.h_next = h
                    if t >= end:
                        y[:] = current
                        return None
                    continue
                self.rejected_steps += 1
                self.w = None
                h = max(STEP_SHRINK_LIMIT * h_try, allowed)
                if just_rejected:
                    # A second failure in a row means the estimate is not yet in its
                    # asymptotic regime (a stiff boundary layer): cut hard.
                    h = min(h, STEP_SHRINK_LIMIT * h_try)
                just_rejected = True
            if h < h_min:
                return (f"integrator step size fell below {h_min:.3g} s without meeting "
                        f"tolerance {rtol:.3g} (state {', '.join(f'{v:.6g}' for v in y)})")
