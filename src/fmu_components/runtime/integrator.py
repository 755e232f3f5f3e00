"""The one stiff integrator shared by every component.

A Rosenbrock-W method, ROS34PW2 (Rang & Angermann, BIT 45 (2005) 761-787): four stages,
order 3 with an embedded order-2 solution for error control, L-stable and stiffly
accurate. Rosenbrock methods are linearly implicit: each step factors
``W = I/(gamma*h) - J`` once and solves four small linear systems, so there are no
Newton iterations to converge or fail. The problems here are small (two states per
nested rubber branch, two for the damper), so ``W`` is factored by a plain dense LU.

The integrator knows nothing of what it integrates. A *system* provides

* ``rhs(y, u)``: dy/dt for the state list ``y`` and an input ``u`` held over the step,
* ``jacobian(y, u)``: d rhs / dy as a list of rows,
* ``inside(y)``: False where the state leaves the region the model is defined in
  (or ``None`` when the model is defined everywhere),
* ``state_scale``: a typical magnitude of each state, which sets the absolute tolerance
  ``rtol * state_scale``.

Steps that fail the error test, or whose stages leave the valid region, are rejected and
retried smaller; nothing is ever clipped. A failure comes back as a message, never as an
exception in the middle of a step.
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
    """Coefficients in the standard form of Hairer & Wanner (IV.7.4):

    (I - gamma*h*J) k_i = h f(y + sum_j alpha_ij k_j) + h J sum_j gamma_ij k_j
    y1 = y + sum_i b_i k_i,  embedded y1^ = y + sum_i bhat_i k_i.

    On construction they are transformed to the form that needs no matrix-vector
    products (Hairer & Wanner IV.7.25): with u_i = sum_j Gamma_ij k_j,

    (I/(gamma*h) - J) u_i = f(y + sum_j a_ij u_j) + sum_j (c_ij/h) u_j
    y1 = y + sum_i m_i u_i,  error = sum_i e_i u_i,

    where A = alpha Gamma^-1, C = diag(1/gamma) - Gamma^-1, m = b Gamma^-1 and
    e = (b - bhat) Gamma^-1.
    """

    def __init__(self, name, order, embedded_order, alpha, gamma, b, bhat):
        self.name = name
        self.order = order
        self.embedded_order = embedded_order
        self.alpha = alpha
        self.gamma_matrix = gamma
        self.b = b
        self.bhat = bhat
        self.gamma = gamma[0][0]
        stages = len(b)
        gamma_inv = _lower_triangular_inverse(gamma)
        self.a = [[sum(alpha[i][k] * gamma_inv[k][j] for k in range(stages)) for j in range(i)]
                  for i in range(stages)]
        self.c = [[-gamma_inv[i][j] for j in range(i)] for i in range(stages)]
        self.m = [sum(b[k] * gamma_inv[k][j] for k in range(stages)) for j in range(stages)]
        self.e = [sum((b[k] - bhat[k]) * gamma_inv[k][j] for k in range(stages))
                  for j in range(stages)]


def _lower_triangular_inverse(lower):
    n = len(lower)
    inverse = [[0.0] * n for _ in range(n)]
    for i in range(n):
        inverse[i][i] = 1.0 / lower[i][i]
        for j in range(i):
            inverse[i][j] = -sum(lower[i][k] * inverse[k][j] for k in range(j, i)) / lower[i][i]
    return inverse


_G = 0.435866521508459
ROS34PW2 = RosenbrockTableau(
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


def lu_factor(matrix):
    """Dense LU with partial pivoting, in place on a copy. Returns (lu, pivots), or
    None when the matrix is singular to working precision."""
    n = len(matrix)
    lu = [row[:] for row in matrix]
    pivots = list(range(n))
    for k in range(n):
        p = max(range(k, n), key=lambda i: abs(lu[i][k]))
        if lu[p][k] == 0.0 or not math.isfinite(lu[p][k]):
            return None
        if p != k:
            lu[k], lu[p] = lu[p], lu[k]
            pivots[k], pivots[p] = pivots[p], pivots[k]
        pivot_row = lu[k]
        inv = 1.0 / pivot_row[k]
        for i in range(k + 1, n):
            row = lu[i]
            factor = row[k] * inv
            row[k] = factor
            if factor != 0.0:
                for j in range(k + 1, n):
                    row[j] -= factor * pivot_row[j]
    return lu, pivots


def lu_solve(factored, rhs):
    lu, pivots = factored
    n = len(lu)
    x = [rhs[p] for p in pivots]
    for i in range(n):
        row = lu[i]
        x[i] -= sum(row[j] * x[j] for j in range(i))
    for i in range(n - 1, -1, -1):
        row = lu[i]
        x[i] = (x[i] - sum(row[j] * x[j] for j in range(i + 1, n))) / row[i]
    return x


class Rosenbrock:
    """Adaptive ROS34PW2 integration of an autonomous system over a given duration.

    The step size the controller would take next is kept in ``h_next`` between calls,
    so that consecutive communication steps do not restart from a guess; it is part of
    the state a host saves with fmi2GetFMUstate.
    """

    def __init__(self, rtol=DEFAULT_RTOL, tableau=ROS34PW2):
        if not (rtol > 0.0 and math.isfinite(rtol)):
            raise ValueError(f"tolerance must be a positive finite number, got {rtol!r}")
        self.rtol = rtol
        self.tableau = tableau
        self.h_next = None
        self.accepted_steps = 0
        self.rejected_steps = 0
        self._exponent = -1.0 / (tableau.embedded_order + 1)

    def step(self, system, y, u, h):
        """One step of size h. Returns (y_new, error_vector), or None when a stage or
        the result leaves the valid region or is not finite."""
        tab = self.tableau
        n = len(y)
        inside = system.inside
        jac = system.jacobian(y, u)
        diag = 1.0 / (tab.gamma * h)
        w = [[(diag if i == j else 0.0) - jac[i][j] for j in range(n)] for i in range(n)]
        factored = lu_factor(w)
        if factored is None:
            return None
        stages = []
        for i in range(len(tab.m)):
            a_row = tab.a[i]
            if i == 0:
                y_stage = y
            else:
                y_stage = [y[q] + sum(a_row[j] * stages[j][q] for j in range(i)) for q in range(n)]
                if inside is not None and not inside(y_stage):
                    return None
            f = system.rhs(y_stage, u)
            c_row = tab.c[i]
            rhs = [f[q] + sum(c_row[j] * stages[j][q] for j in range(i)) / h for q in range(n)]
            stages.append(lu_solve(factored, rhs))
        y_new = [y[q] + sum(tab.m[i] * stages[i][q] for i in range(len(stages))) for q in range(n)]
        if not all(math.isfinite(value) for value in y_new):
            return None
        if inside is not None and not inside(y_new):
            return None
        # The embedded solution is not L-stable (|Rhat(inf)| = 0.48), so a raw estimate
        # would report stiff transients as error at any step size. Filtering it through
        # (I - gamma*h*J)^-1 leaves the non-stiff part and damps the stiff part
        # (Hairer & Wanner IV.8, the RADAU5 estimate).
        error = lu_solve(factored, [diag * sum(tab.e[i] * stages[i][q] for i in range(len(stages)))
                                    for q in range(n)])
        return y_new, error

    def error_norm(self, system, y, y_new, error):
        """RMS of the error relative to rtol*(|y| + state scale); accept when <= 1."""
        rtol = self.rtol
        total = 0.0
        for y0, y1, e, scale in zip(y, y_new, error, system.state_scale):
            weight = rtol * (scale + max(abs(y0), abs(y1)))
            total += (e / weight) ** 2
        return math.sqrt(total / len(y))

    def integrate(self, system, y, u, duration):
        """Advance the state list ``y`` in place over ``duration`` with input ``u`` held.

        Returns None on success. On failure returns a message and leaves ``y`` at the
        start value: the caller never sees a partly advanced state.
        """
        if duration <= 0.0 or not y:
            return None
        start = y[:]
        # h is the step size the controller wants; the step actually tried may be cut
        # short to land on the end of the interval, and the controller then scales its
        # own h (not the short step) by what the error estimate allows.
        h = self.h_next if self.h_next is not None else duration
        h_min = 1e-12 * duration
        t = 0.0
        steps = 0
        just_rejected = False
        while True:
            remaining = duration - t
            if remaining <= 1e-13 * duration:
                return None
            h_try = min(h, remaining)
            steps += 1
            if steps > MAX_STEPS_PER_CALL:
                y[:] = start
                return (f"integrator needed more than {MAX_STEPS_PER_CALL} steps for a "
                        f"{duration:.6g} s interval at tolerance {self.rtol:.3g}")
            result = self.step(system, y, u, h_try)
            if result is None:
                self.rejected_steps += 1
                h = h_try * REGION_SHRINK
                just_rejected = True
            else:
                y_new, error = result
                err = self.error_norm(system, y, y_new, error)
                allowed = h_try * SAFETY * err ** self._exponent if err > 0.0 else math.inf
                if err <= 1.0:
                    self.accepted_steps += 1
                    y[:] = y_new
                    t += h_try
                    h = min(STEP_GROWTH_LIMIT * h, max(STEP_SHRINK_LIMIT * h, allowed))
                    if just_rejected:
                        h = min(h, h_try)
                        just_rejected = False
                    self.h_next = h
                    continue
                self.rejected_steps += 1
                h = max(STEP_SHRINK_LIMIT * h_try, allowed)
                if just_rejected:
                    # A second failure in a row means the estimate is not yet in its
                    # asymptotic regime (a stiff boundary layer): cut hard.
                    h = min(h, STEP_SHRINK_LIMIT * h_try)
                just_rejected = True
            if h < h_min:
                y[:] = start
                return (f"integrator step size fell below {h_min:.3g} s without meeting "
                        f"tolerance {self.rtol:.3g} (state {', '.join(f'{v:.6g}' for v in start)})")
