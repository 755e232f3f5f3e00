"""The one stiff integrator shared by every component.

A Rosenbrock-W method, ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761-787): four stages,
order 3 with an embedded order-2 solution for error control, L-stable and stiffly
accurate, free of order reduction on the Prothero-Robinson problem. Rosenbrock methods are
linearly implicit: each step factors W = I/(gamma*h) - J once and solves a few small
linear systems, so there are no Newton iterations to converge or fail. The problems here
are small (two states per nested rubber branch, two for the damper).

The integrator knows nothing of what it integrates. A *system* provides

* ``rhs(y, u)``: dy/dt for the state sequence ``y`` and an input ``u`` held over the step,
* ``jacobian(y, u)``: d rhs / dy as a sequence of rows,
* ``inside(y)``: False where the state leaves the region the model is defined in (or
  ``None`` when the model is defined everywhere),
* ``state_scale``: a typical magnitude of each state, which sets the absolute tolerance
  ``rtol * state_scale``.

Steps that fail the error test, or whose stages leave the valid region or stop being
finite, are rejected and retried smaller; nothing is ever clipped. A failure comes back as
a message, never as an exception in the middle of a step.

Speed: a step is straight-line code generated, once per dimension, from the tableau below,
so that the stage arithmetic of a two-state system costs a few microseconds in CPython
rather than tens (see ``compile_step``).
"""

import math

DEFAULT_RTOL = 1e-4
"""Relative tolerance used when the host gives none in fmi2SetupExperiment."""

MAX_STEPS_PER_CALL = 100_000
STEP_GROWTH_LIMIT = 5.0
STEP_SHRINK_LIMIT = 0.2
SAFETY = 0.9
REGION_SHRINK = 0.25


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


def compile_step(tableau, n):
    """Straight-line Python for one step of `tableau` on an n-state system: two generated
    functions,

    * ``factor(system, y, u, h)``: W^-1 = (I/(gamma*h) - J(y, u))^-1 as a flat tuple, or
      None when W is singular;
    * ``step(system, y, u, h, rtol, w)``: one step with that W^-1, returning
      ``(y_new, error_norm)``, or None when a stage or the result leaves the valid region
      or is not finite.

    The error is filtered through (I - gamma*h*J)^-1 = W^-1/(gamma*h) before its norm is
    taken: the embedded solution is not L-stable (|Rhat(inf)| = 0.48), and a raw estimate
    would report stiff transients as error at any step size (Hairer & Wanner IV.8, the
    RADAU5 estimate).
    """
    q = range(n)
    stages = range(len(tableau.m))

    def vector(name):
        return ", ".join(f"{name}{i}" for i in q) + ("," if n == 1 else "")

    def combination(terms):
        """sum of coefficient * symbol, dropping zero coefficients."""
        parts = [f"{coefficient!r} * {symbol}" for coefficient, symbol in terms if coefficient]
        return " + ".join(parts) if parts else "0.0"

    d = f"(1.0 / ({tableau.gamma!r} * h))"
    if n == 2:  # written out for two states, the common case here
        factor = ["def factor(system, y, u, h, isfinite=math.isfinite):",
                  "    (j00, j01), (j10, j11) = system.jacobian(y, u)",
                  f"    d = {d}",
                  "    a = d - j00",
                  "    b = d - j11",
                  "    det = a * b - j01 * j10",
                  "    if det == 0.0 or not isfinite(det):",
                  "        return None",
                  "    return (b / det, j01 / det, j10 / det, a / det)"]
    else:
        factor = ["def factor(system, y, u, h):",
                  "    jac = system.jacobian(y, u)",
                  f"    d = {d}",
                  f"    inverse = invert([[(d if i == j else 0.0) - jac[i][j] for j in range({n})]"
                  f" for i in range({n})])",
                  "    return None if inverse is None else tuple(v for row in inverse for v in row)"]
    lines = ["def step(system, y, u, h, rtol, w, isfinite=math.isfinite):",
             f"    {vector('y')} = y",
             f"    ({', '.join(f'w{i}{j}' for i in q for j in q)},) = w",
             "    rhs = system.rhs",
             "    inside = system.inside",
             f"    d = {d}",
             "    ih = 1.0 / h"]
    for s in stages:
        if s == 0:
            lines.append(f"    {vector('f')} = rhs(y, u)")
        else:
            for i in q:
                terms = [(tableau.a[s][j], f"k{j}_{i}") for j in range(s)]
                lines.append(f"    Y{i} = y{i} + {combination(terms)}")
            lines.append(f"    Y = ({vector('Y')})")
            lines.append("    if inside is not None and not inside(Y):")
            lines.append("        return None")
            lines.append(f"    {vector('f')} = rhs(Y, u)")
        for i in q:
            terms = [(tableau.c[s][j], f"k{j}_{i}") for j in range(s)]
            coupling = combination(terms)
            lines.append(f"    r{i} = f{i}" + ("" if coupling == "0.0" else f" + ih * ({coupling})"))
        for i in q:
            lines.append(f"    k{s}_{i} = " + " + ".join(f"w{i}{j} * r{j}" for j in q))
    for i in q:
        lines.append(f"    n{i} = y{i} + {combination([(tableau.m[s], f'k{s}_{i}') for s in stages])}")
        lines.append(f"    e{i} = d * ({combination([(tableau.e[s], f'k{s}_{i}') for s in stages])})")
    lines.append("    if not (" + " and ".join(f"isfinite(n{i})" for i in q) + "):")
    lines.append("        return None")
    lines.append(f"    new = ({vector('n')})")
    lines.append("    if inside is not None and not inside(new):")
    lines.append("        return None")
    lines.append("    scale = system.state_scale")
    terms = []
    for i in q:
        filtered = " + ".join(f"w{i}{j} * e{j}" for j in q)
        weight = f"rtol * (scale[{i}] + max(abs(y{i}), abs(n{i})))"
        terms.append(f"(({filtered}) / ({weight})) ** 2")
    lines.append(f"    return new, math.sqrt(({' + '.join(terms)}) / {n})")
    source = "\n".join(factor) + "\n\n\n" + "\n".join(lines) + "\n"
    namespace = {"math": math, "invert": invert}
    exec(compile(source, f"<{tableau.name} step, {n} states>", "exec"), namespace)
    return namespace["factor"], namespace["step"], source


class Rosenbrock:
    """Adaptive integration of an autonomous system over a given duration.

    Between calls it keeps ``h_next``, the step size its controller would take next, so
    that consecutive communication steps do not restart from a guess, and ``w``, the last
    W^-1 with the step size it was made for. ROS34PW2 is a W-method: its order, and its
    error estimate's, hold for any W, so W^-1 is reused while the step size stays the same,
    and rebuilt from a fresh Jacobian after MAX_W_REUSE steps or a rejected step. Both are
    part of the state a host saves with fmi2GetFMUstate: the continuation depends on them.
    """

    MAX_W_REUSE = 8
    _compiled = {}  # (tableau name, n) -> (factor, step, source), shared by all instances

    def __init__(self, rtol=DEFAULT_RTOL, tableau=ROS34PW2):
        if not (rtol > 0.0 and math.isfinite(rtol)):
            raise ValueError(f"tolerance must be a positive finite number, got {rtol!r}")
        self.rtol = rtol
        self.tableau = tableau
        self.h_next = None
        self.w = None  # (h, W^-1 as a flat tuple, uses so far)
        self.accepted_steps = 0
        self.rejected_steps = 0
        self._exponent = -1.0 / (tableau.embedded_order + 1)
        self._last_compiled = (None, None)

    def compiled(self, n):
        if self._last_compiled[0] != n:
            key = (self.tableau.name, n)
            if key not in self._compiled:
                self._compiled[key] = compile_step(self.tableau, n)
            self._last_compiled = (n, self._compiled[key])
        return self._last_compiled[1]

    def step(self, system, y, u, h):
        """One step of size h with a fresh Jacobian: (y_new, error_norm), or None."""
        factor, step, _ = self.compiled(len(y))
        w = factor(system, y, u, h)
        return None if w is None else step(system, y, u, h, self.rtol, w)

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
        factor, step, _ = self.compiled(len(y))
        rtol = self.rtol
        exponent = self._exponent
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
            if cached is not None and cached[0] == h_try and cached[2] < max_reuse:
                w = cached[1]
                self.w = (h_try, w, cached[2] + 1)
            else:
                w = factor(system, current, u, h_try)
                self.w = None if w is None else (h_try, w, 1)
            result = None if w is None else step(system, current, u, h_try, rtol, w)
            if result is None:
                self.rejected_steps += 1
                self.w = None
                h = h_try * REGION_SHRINK
                just_rejected = True
            else:
                new, err = result
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
