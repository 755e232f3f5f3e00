"""Carbon-black-filled natural rubber components: the tyre and the track bush.

The thesis's final model (section 6.4, Fig. 6.4-1, Appendix 4b; spec section 2), written
once for any number of parallel branches:

    F = Fe(x) + f(x) * sum(branch forces)                                (Eq. 6.1-1, 6.1-3)

Each branch is a nonlinear Maxwell element, a spring k in series with a dashpot of
viscosity eta = c / (|u| + xi), u being the rate across the element (Eq. 4.2.7-1, 6.1-2).
A branch may carry a nested element of the same kind in parallel with its spring, the
"stiffening" element of section 6.3. For a branch with spring deformation s and nested
spring deformation w, under a deflection rate v:

    F_branch = k1*s + k2*w                         (force through the outer dashpot)
    ds/dt = v - F_branch*(|v| + xi1)/c1
    dw/dt = ds/dt - k2*w*(|ds/dt| + xi2)/c2        (the nested element spans spring k1)

and for a branch without nesting, with spring deformation r,

    F_branch = k*r,   dr/dt = v - k*r*(|v| + xi)/c.

The co-simulation step holds v, so a branch without nesting is linear in r and is
advanced by its exact exponential solution. Branches with nesting are nonlinear (|ds/dt|)
and go to the stiff integrator. The branches do not interact: each sees only v.

The tyre is a unilateral contact: the rubber deforms by max(x, 0) and its rate is v only
while x > 0, so a step that crosses x = 0 is split at the crossing.
"""

import math


class MaxwellElement:
    """Spring k in series with a dashpot of viscosity c/(|u| + xi); time constant
    tau = c/(k*xi) (Eq. 4.2.7-3)."""

    __slots__ = ("k", "c", "xi")

    def __init__(self, k, c, xi):
        self.k = k
        self.c = c
        self.xi = xi


class Branch:
    __slots__ = ("outer", "nested")

    def __init__(self, outer, nested=None):
        self.outer = outer
        self.nested = nested


class RubberModel:
    """A rubber component: elastic cubic Fe, geometric multiplier f and Maxwell branches.

    State layout: [s, w] for each nested branch (integrated), then r for each plain
    branch (exact update).
    """

    inside = None  # the rubber model is defined for every state

    def __init__(self, branches, elastic, geometric_slope, geometric_reference,
                 unilateral=False):
        self.elastic = tuple(elastic)  # a0..a3 of Fe = a0 + a1 x + a2 x^2 + a3 x^3 (Eq. 5.3.1-x)
        self.geometric_slope = geometric_slope  # h of f = 1 + h|x - x_ref| (Eq. 5.3.2-x)
        self.geometric_reference = geometric_reference
        self.unilateral = unilateral
        self.nested_branches = [b for b in branches if b.nested is not None]
        self.plain_branches = [b for b in branches if b.nested is None]
        self.integrated_size = 2 * len(self.nested_branches)
        self.state_size = self.integrated_size + len(self.plain_branches)
        # Typical spring deformations (the force c that saturates each dashpot, over k):
        # the integrator's absolute tolerance is rtol times these.
        self.state_scale = []
        for b in self.nested_branches:
            self.state_scale += [b.outer.c / b.outer.k, b.nested.c / b.nested.k]

    # --- initial state and step -------------------------------------------------------

    def initial_state(self, x, v):
        """Relaxed at the initial input (spec section 2)."""
        return [0.0] * self.state_size

    def check_input(self, state, x):
        return None

    def rate_segments(self, x, v, h):
        """Pieces of the step [(duration, rubber rate)] over which the rubber's own rate
        is constant: the whole step, or for the tyre the parts in and out of contact."""
        if not self.unilateral:
            return ((h, v),)
        x_end = x + v * h
        if x > 0.0 and x_end > 0.0:
            return ((h, v),)
        if x <= 0.0 and x_end <= 0.0:
            return ((h, 0.0),)
        crossing = -x / v  # time at which x reaches 0, inside the step
        if x > 0.0:
            return ((crossing, v), (h - crossing, 0.0))
        return ((crossing, 0.0), (h - crossing, v))

    def advance(self, state, x, v, h, integrator):
        """Advance the state in place over a step of length h with rate v held.
        Returns None, or an error message with the state unchanged."""
        n = self.integrated_size
        integrated = state[:n]
        for duration, rate in self.rate_segments(x, v, h):
            if duration <= 0.0:
                continue
            if n:
                problem = integrator.integrate(self, integrated, rate, duration)
                if problem:
                    return problem
            self._advance_plain(state, rate, duration)
        state[:n] = integrated
        return None

    def _advance_plain(self, state, v, duration):
        """Exact solution of dr/dt = v - a*r, a = k(|v| + xi)/c, for constant v."""
        speed = abs(v)
        for i, branch in enumerate(self.plain_branches, start=self.integrated_size):
            e = branch.outer
            a = e.k * (speed + e.xi) / e.c
            r_steady = v / a
            state[i] = r_steady + (state[i] - r_steady) * math.exp(-a * duration)

    # --- integrator system: the nested branches ---------------------------------------

    def rhs(self, y, v):
        speed = abs(v)
        dydt = []
        for i, branch in enumerate(self.nested_branches):
            outer, nested = branch.outer, branch.nested
            s, w = y[2 * i], y[2 * i + 1]
            force = outer.k * s + nested.k * w
            sdot = v - force * (speed + outer.xi) / outer.c
            wdot = sdot - nested.k * w * (abs(sdot) + nested.xi) / nested.c
            dydt += [sdot, wdot]
        return dydt

    def jacobian(self, y, v):
        n = self.integrated_size
        jac = [[0.0] * n for _ in range(n)]
        speed = abs(v)
        for i, branch in enumerate(self.nested_branches):
            outer, nested = branch.outer, branch.nested
            s, w = y[2 * i], y[2 * i + 1]
            b = (speed + outer.xi) / outer.c
            sdot = v - (outer.k * s + nested.k * w) * b
            g = nested.k / nested.c
            # d|sdot|/dy = sign(sdot) * d sdot/dy
            nested_factor = 1.0 - g * w * math.copysign(1.0, sdot)
            j = 2 * i
            jac[j][j] = -outer.k * b
            jac[j][j + 1] = -nested.k * b
            jac[j + 1][j] = -outer.k * b * nested_factor
            jac[j + 1][j + 1] = -nested.k * b * nested_factor - g * (abs(sdot) + nested.xi)
        return jac

    # --- outputs ----------------------------------------------------------------------

    def branch_force(self, state):
        total = 0.0
        for i, branch in enumerate(self.nested_branches):
            total += branch.outer.k * state[2 * i] + branch.nested.k * state[2 * i + 1]
        for i, branch in enumerate(self.plain_branches, start=self.integrated_size):
            total += branch.outer.k * state[i]
        return total

    def _branch_stiffness(self, state, direction):
        """Slope of the branch forces against x for fast motion in `direction` (+1/-1):
        the rate-independent tangent of Eq. 4.2.7-2, dF/dx = k(1 - sgn(v) F/c), with the
        nested element riding on the outer spring's rate."""
        total = 0.0
        for i, branch in enumerate(self.nested_branches):
            outer, nested = branch.outer, branch.nested
            s, w = state[2 * i], state[2 * i + 1]
            outer_slip = 1.0 - direction * (outer.k * s + nested.k * w) / outer.c
            nested_direction = direction * math.copysign(1.0, outer_slip)
            nested_slip = 1.0 - nested_direction * nested.k * w / nested.c
            total += outer_slip * (outer.k + nested.k * nested_slip)
        for i, branch in enumerate(self.plain_branches, start=self.integrated_size):
            e = branch.outer
            total += e.k * (1.0 - direction * e.k * state[i] / e.c)
        return total

    def outputs(self, state, x, v):
        """(force, elastic part, viscoelastic part, tangent stiffness dF/dx).

        The tangent is taken in the direction of the rate; at zero rate it is the mean of
        the loading and unloading slopes. For the tyre out of contact, or pulled off the
        surface by the viscoelastic force, force and tangent are zero.
        """
        if self.unilateral and x <= 0.0:
            return 0.0, 0.0, 0.0, 0.0
        a0, a1, a2, a3 = self.elastic
        elastic = a0 + x * (a1 + x * (a2 + x * a3))
        elastic_slope = a1 + x * (2.0 * a2 + 3.0 * a3 * x)
        offset = x - self.geometric_reference
        multiplier = 1.0 + self.geometric_slope * abs(offset)
        branch_force = self.branch_force(state)
        viscoelastic = multiplier * branch_force
        force = elastic + viscoelastic
        if self.unilateral and force <= 0.0:
            return 0.0, elastic, viscoelastic, 0.0

        def slope(direction):
            side = math.copysign(1.0, offset) if offset != 0.0 else direction
            return (self.geometric_slope * side * branch_force
                    + multiplier * self._branch_stiffness(state, direction))

        if v > 0.0:
            visco_slope = slope(1.0)
        elif v < 0.0:
            visco_slope = slope(-1.0)
        else:
            visco_slope = 0.5 * (slope(1.0) + slope(-1.0))
        return force, elastic, viscoelastic, elastic_slope + visco_slope
