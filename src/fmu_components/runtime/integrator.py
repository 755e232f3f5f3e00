"""The one stiff integrator shared by every component.

A Rosenbrock-W method, ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761-787): four stages,
order 3 with an embedded order-2 solution for error control, L-stable and stiffly
accurate, free of order reduction on the Prothero-Robinson problem. Rosenbrock methods are
linearly implicit: each step factors W = I/(gamma*h) - J once and solves a few small
linear systems, so there are no Newton iterations to converge or fail. The problems here
are small (two states per nested rubber branch, two for the damper).

The integrator knows nothing of what it integrates. A *system* provides

* ``rhs(y, u)``: dy/dt for the state sequence ``y`` and an input ``u`` held over the step,
  or instead ``rhs_source()``: the same as straight-line Python (an ``RhsSource``), which
  the integrator compiles into its stage code,
* ``jacobian(y, u)``: d rhs / dy as a sequence of rows (or, in its RhsSource, as lines
  the integrator compiles into the factorisation of W),
* ``inside(y)``: False where the state leaves the region the model is defined in (or
  ``None`` when the model is defined everywhere),
* ``state_scale``: a typical magnitude of each state, which sets the absolute tolerance
  ``rtol * state_scale``.

Steps that fail the error test, or whose stages leave the valid region or stop being
finite, are rejected and retried smaller; nothing is ever clipped. A failure comes back as
a message, never as an exception in the middle of a step.

Speed: a step is straight-line code generated from the tableau below and the system's
right-hand side, once per system, so that a step of a two-state system costs about two
microseconds in CPython rather than tens: no loops, no lists, and no function call per
stage, which would cost more than the stage's arithmetic (see ``compile_step``). A
communication step that is one integrator step, nearly every step at 1 ms, goes through a
second generated function that also holds the step-size control and the model's
closed-form part (``Rosenbrock.single_step``), bit for bit what ``integrate`` and the
model's ``advance`` would do, without their loops and calls.
"""

import math

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


class RhsSource:
    """A right-hand side as straight-line Python, for the integrator to inline.

    * ``stage``: lines that set ``f0 .. f{n-1}`` (dy/dt) from the stage state
      ``Y0 .. Y{n-1}``, the held input ``u`` and any name set by ``held``;
    * ``held``: lines that depend on ``u`` alone, run once per step rather than per stage;
    * ``region``: an expression in ``Y0 ..`` that is false where the state leaves the
      region the model is defined in (the inline form of ``system.inside``), or None;
    * ``jacobian``: lines that set the entries ``j{row}_{column}`` of d rhs / dy at the
      state ``Y0 ..`` (entries they leave unset are zero), or empty: then the integrator
      calls ``system.jacobian``;
    * ``namespace``: the functions and objects the lines name.

    A model whose whole state is not integrated also describes a communication step over
    which its input is held, for the single-step path (``Rosenbrock.single_step``): the
    model's state list is ``state``, its first n entries the integrated ones, ``x`` the
    deflection at the start of the step, ``u`` its held rate and ``h`` the step size.

    * ``start``: lines that set ``y0 .. y{n-1}``, the integrated states at the start of
      the step, from ``state`` and ``x`` (default: the first n entries of ``state``);
    * ``exact``: lines that advance the other entries of ``state`` over the step by their
      closed-form solution (they may use the names set by ``held``);
    * ``one_segment``: an expression, true when the step is a single interval over which
      the integrated states see the held input ``u`` itself and ``exact`` applies (None:
      always).

    Numbers are best written into the lines as literals (``repr``), which CPython loads
    fastest; systems with the same source and namespace share one compiled step.
    """

    def __init__(self, stage, held=(), region=None, namespace=None, jacobian=(), start=(),
                 exact=(), one_segment=None):
        self.stage = tuple(stage)
        self.held = tuple(held)
        self.region = region
        self.jacobian = tuple(jacobian)
        self.namespace = dict(namespace or {})
        self.start = tuple(start)
        self.exact = tuple(exact)
        self.one_segment = one_segment

    def start_lines(self, n):
        return self.start or tuple(f"y{i} = state[{i}]" for i in range(n))

    def key(self):
        return (self.stage, self.held, self.region, self.jacobian, self.start, self.exact,
                self.one_segment,
                tuple(sorted(self.namespace.items(), key=lambda item: item[0])))


def _names(prefix, n):
    """'p0, p1, ..,' as a tuple display's contents (a trailing comma for one)."""
    return ", ".join(f"{prefix}{i}" for i in range(n)) + ","


def rhs_source(system, n):
    """The system's RhsSource, or one that calls its ``rhs`` method."""
    if hasattr(system, "rhs_source"):
        return system.rhs_source()
    states = _names("Y", n)
    region = None if system.inside is None else f"inside(({states}))"
    return RhsSource([f"{_names('f', n)} = rhs(({states}), u)"], region=region,
                     namespace={"rhs": system.rhs, "inside": system.inside})


def _compile(source_text, namespace, label):
    namespace = {"math": math, "invert": invert, **namespace}
    exec(compile(source_text, label, "exec"), namespace)
    return namespace


def _compile_function(signature, body, result, source):
    """One generated function: ``def signature:`` running `body` (lines) then returning
    `result`, with the source's namespace."""
    lines = [f"def {signature}:"] + [f"    {line}" for line in body] + [f"    return {result}"]
    name = signature.split("(")[0]
    return _compile("\n".join(lines) + "\n", source.namespace, f"<{name}>")[name]


def compile_rhs(system, n):
    """The system's right-hand side as a function ``rhs(y, u) -> tuple``, compiled from its
    source: what the integrator's stages compute, callable on its own (tests, tools)."""
    source = rhs_source(system, n)
    return _compile_function("rhs(y, u)", [f"{_names('Y', n)} = y", *source.held, *source.stage],
                             f"({_names('f', n)})", source)


def compile_exact(source):
    """The source's closed-form update as a function ``exact(state, u, h)``, for a model's
    own step when it does not take the single-step path (see RhsSource)."""
    return _compile_function("exact(state, u, h)", [*source.held, *source.exact], "None",
                             source)


def _jacobian_lines(source, n):
    """Lines that leave d rhs / dy in j0_0 .. from ``y``, ``u``: the source's own, after the
    stage lines (its lines may use f0 ..), or a call of ``system.jacobian``."""
    if n == 0:
        return []
    names = [[f"j{i}_{k}" for k in range(n)] for i in range(n)]
    if not source.jacobian:
        return [f"({', '.join('(' + ', '.join(row) + ',)' for row in names)},) = "
                "system.jacobian(y, u)"]
    return ([f"{_names('Y', n)} = y", f"{' = '.join(name for row in names for name in row)} = 0.0",
             *source.held, *source.stage, *source.jacobian])


def compile_jacobian(source, n):
    """The source's Jacobian as a function ``jacobian(y, u) -> rows``: the one the
    integrator factors, callable on its own (the model's ``jacobian``, tests)."""
    rows = " ".join("(" + ", ".join(f"j{i}_{k}" for k in range(n)) + ",)," for i in range(n))
    return _compile_function("jacobian(y, u)", _jacobian_lines(source, n), f"({rows})",
                             source)


def compile_start(source, n):
    """The source's start of a step as a function ``start(state, x) -> (y0, ..)``."""
    return _compile_function("start(state, x)", source.start_lines(n), f"({_names('y', n)})",
                             source)


def compile_step(tableau, n, source, state_scale):
    """Straight-line Python for one step of `tableau` on an n-state system with right-hand
    side `source` (an RhsSource): three generated functions,

    * ``factor(system, y, u, h)``: W^-1 = (I/(gamma*h) - J(y, u))^-1 as a flat tuple, or
      None when W is singular;
    * ``step(y, u, h, rtol, w)``: one step with that W^-1, returning
      ``(y_new, error_norm ** 2)``, or None when a stage or the result leaves the valid
      region or is not finite;
    * ``single_step_for(memory, system, max_reuse)``: the single-step path of a Rosenbrock
      instance (``memory``), see ``Rosenbrock.single_step``.

    The error is filtered through (I - gamma*h*J)^-1 = W^-1/(gamma*h) before its norm is
    taken: the embedded solution is not L-stable (|Rhat(inf)| = 0.48), and a raw estimate
    would report stiff transients as error at any step size (Hairer & Wanner IV.8, the
    RADAU5 estimate).
    """
    q = range(n)
    states = _names("Y", n)
    inverse = ", ".join(f"w{i}{j}" for i in q for j in q)
    d = f"(1.0 / ({tableau.gamma!r} * h))"
    jacobian = [f"    {line}" for line in _jacobian_lines(source, n)]
    if n == 2:  # written out for two states, the common case here
        factor = (["def factor(system, y, u, h, isfinite=math.isfinite):"] + jacobian +
                  [f"    d = {d}",
                   "    a = d - j0_0",
                   "    b = d - j1_1",
                   "    det = a * b - j0_1 * j1_0",
                   "    if det == 0.0 or not isfinite(det):",
                   "        return None",
                   "    return (b / det, j0_1 / det, j1_0 / det, a / det)"])
    else:
        factor = (["def factor(system, y, u, h):"] + jacobian +
                  [f"    d = {d}",
                   "    inverse = invert([" + ", ".join(
                       "[" + ", ".join(f"{'d - ' if i == k else '-'}j{i}_{k}" for k in q) + "]"
                       for i in q) + "])",
                   "    return None if inverse is None else tuple(v for row in inverse for v in row)"])
    step = ["def step(y, u, h, rtol, w):",
            f"    {_names('y', n)} = {states} = y",
            f"    ({inverse},) = w"]
    step += _step_lines(tableau, n, source, state_scale, "return None", "    ")
    step.append(f"    return ({states}), error")
    text = "\n".join(factor) + "\n\n\n" + "\n".join(step) + "\n\n\n" + "\n".join(
        _single_step_lines(tableau, n, source, state_scale, inverse)) + "\n"
    namespace = _compile(text, source.namespace, f"<{tableau.name} step, {n} states>")
    return namespace["factor"], namespace["step"], namespace["single_step_for"], text


def _step_lines(tableau, n, source, state_scale, fail, indent):
    """The body of one step from y0.. with W^-1 in w00.., input u, size h and tolerance
    rtol: it leaves the new state in Y0.. and the squared error norm in ``error``, or runs `fail`
    when a stage or the result leaves the valid region or is not finite."""
    q = range(n)
    stages = range(len(tableau.m))

    def combination(terms):
        """sum of coefficient * symbol, dropping zero coefficients and unit factors."""
        parts = [symbol if coefficient == 1.0 else f"{coefficient!r} * {symbol}"
                 for coefficient, symbol in terms if coefficient]
        return " + ".join(parts) if parts else "0.0"

    region_check = [] if source.region is None else [f"if not ({source.region}):", f"    {fail}"]
    lines = [f"d = (1.0 / ({tableau.gamma!r} * h))", "ih = 1.0 / h"]
    lines += source.held
    for s in stages:
        if s > 0:
            for i in q:
                terms = [(tableau.a[s][j], f"k{j}_{i}") for j in range(s)]
                lines.append(f"Y{i} = y{i} + {combination(terms)}")
            lines += region_check
        lines += source.stage
        right = "f"  # the right-hand side of the stage's linear system, f + sum c_ij/h k_j
        if any(tableau.c[s][j] for j in range(s)):
            right = "r"
            for i in q:
                terms = [(tableau.c[s][j], f"k{j}_{i}") for j in range(s)]
                lines.append(f"r{i} = f{i} + ih * ({combination(terms)})")
        for i in q:
            lines.append(f"k{s}_{i} = " + " + ".join(f"w{i}{j} * {right}{j}" for j in q))
    last = len(tableau.m) - 1
    for i in q:
        if tableau.stiffly_accurate:
            # y1 = y + sum_j a_last,j k_j + k_last: the last stage's state plus its k.
            lines.append(f"Y{i} = Y{i} + k{last}_{i}")
        else:
            lines.append(f"Y{i} = y{i} + {combination([(tableau.m[s], f'k{s}_{i}') for s in stages])}")
        lines.append(f"e{i} = d * ({combination([(tableau.e[s], f'k{s}_{i}') for s in stages])})")
    # A sum is finite only if every term is (or it overflows, which is no valid state
    # either), and x - x is 0 for finite x, nan for inf and nan: the test without a call.
    lines.append(f"total = {' + '.join(f'Y{i}' for i in q)}")
    lines.append("if total - total != 0.0:")
    lines.append(f"    {fail}")
    lines += region_check
    for i in q:
        # max(abs(y), abs(Y)) as conditional expressions, and squares as products: the
        # same values without calls.
        lines += [f"a{i} = y{i} if y{i} >= 0.0 else -y{i}",
                  f"b{i} = Y{i} if Y{i} >= 0.0 else -Y{i}"]
        filtered = " + ".join(f"w{i}{j} * e{j}" for j in q)
        weight = f"({float(state_scale[i])!r} + (b{i} if b{i} > a{i} else a{i}))"
        lines.append(f"z{i} = ({filtered}) / {weight}")
    # The squared norm: its tests against 1 and 0 are the norm's, and the controller
    # takes its power with half the exponent, which saves the square root.
    lines.append(f"error = ({' + '.join(f'z{i} * z{i}' for i in q)}) / ({n} * rtol * rtol)")
    return [indent + line for line in lines]


def _single_step_lines(tableau, n, source, state_scale, inverse):
    """``single_step_for(memory, system, max_reuse)``: the one-step case of
    ``Rosenbrock.integrate`` fused with the model's closed-form update (RhsSource.exact),
    as one function. It decides, reuses or rebuilds W^-1 and controls the step size exactly
    as ``integrate`` does, so a step it takes is bit for bit the one ``integrate`` would
    take; whenever ``integrate`` would do anything else it returns False having changed
    nothing."""
    q = range(n)
    lines = ["def single_step_for(memory, system, max_reuse):",
             "    def single_step(state, x, u, h, inf=math.inf):"]
    body = []
    if source.one_segment is not None:
        body += [f"if not ({source.one_segment}):", "    return False"]
    body += ["h_control = memory.h_next",
             "if h_control is None:",
             "    h_control = h",
             "elif h_control < h:",
             "    return False  # the controller wants more than one step"]
    body += source.start_lines(n)
    body.append(f"{_names('Y', n)} = {_names('y', n)}")
    body += ["cached = memory.w",
             f"same = {SAME_STEP_SIZE!r} * h",
             "if cached is not None and -same <= cached[0] - h <= same and cached[2] < max_reuse:",
             "    w = cached[1]",
             "    uses = cached[2] + 1",
             "else:",
             f"    w = factor(system, ({_names('y', n)}), u, h)",
             "    if w is None:",
             "        return False",
             "    uses = 1",
             f"({inverse},) = w",
             "rtol = memory.rtol"]
    body += _step_lines(tableau, n, source, state_scale, "return False", "")
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
    body += source.exact
    body += [f"state[{i}] = Y{i}" for i in q]
    body.append("return True")
    lines += ["        " + line for line in body]
    lines.append("    return single_step")
    return lines


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
    # (tableau, n, right-hand side, state scale) -> (factor, step, single_step_for, source
    # text): systems with the same equations and parameters share one compiled step.
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
        self._last_compiled = (None, None, None)  # (system, n, compiled)

    def compiled(self, system, n):
        """(factor, step, single_step_for, source text) for an n-state system."""
        last_system, last_n, compiled = self._last_compiled
        if last_system is not system or last_n != n:
            source = rhs_source(system, n)
            key = (self.tableau.name, n, source.key(), tuple(system.state_scale))
            compiled = self._compiled.get(key)
            if compiled is None:
                if len(self._compiled) >= self.MAX_COMPILED:
                    self._compiled.clear()  # a host sweeping parameters: do not grow forever
                compiled = self._compiled[key] = compile_step(self.tableau, n, source,
                                                              system.state_scale)
            self._last_compiled = (system, n, compiled)
        return compiled

    def step(self, system, y, u, h):
        """One step of size h with a fresh Jacobian: (y_new, error_norm ** 2), or None."""
        factor, step, _, _ = self.compiled(system, len(y))
        w = factor(system, y, u, h)
        return None if w is None else step(y, u, h, self.rtol, w)

    def single_step(self, system, n):
        """The single-step path for `system`, a model whose first n state entries this
        integrator advances and whose RhsSource describes the rest (``exact``), or None if
        it has none. ``single_step(state, x, u, h)`` advances the model's state list over
        a communication step of size h with the rate u held, in one integrator step, and
        returns True; it returns False, with nothing changed, when that is not what
        ``integrate`` would do (the step is not one segment, the controller wants smaller
        steps, the step is rejected). Then the model's own ``advance`` takes the step.

        Why: a communication step of 1 ms is one integrator step almost always, and the
        layers between the FMI call and the generated step (co-simulation, model,
        integrator loop) cost more than the step itself (benchmarks/results.md)."""
        if n == 0 or not hasattr(system, "rhs_source"):
            return None
        return self.compiled(system, n)[2](self, system, self.MAX_W_REUSE)

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
        factor, step, _, _ = self.compiled(system, len(y))
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
                w = factor(system, current, u, h_try)
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
