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

from .integrator import RhsSource, compile_exact, compile_jacobian


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
        # Plain numbers for the hot loops: (k1, c1, xi1, k2, k2/c2, xi2) per nested branch,
        # (k, c, xi) per plain branch.
        self._nested = [(b.outer.k, b.outer.c, b.outer.xi, b.nested.k, b.nested.k / b.nested.c,
                         b.nested.xi) for b in self.nested_branches]
        self._plain = [(b.outer.k, b.outer.c, b.outer.xi) for b in self.plain_branches]
        source = self.rhs_source()
        self._advance_plain = compile_exact(source)
        self.jacobian = compile_jacobian(source, self.integrated_size)

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
        """Advance the state over a step of length h with rate v held. Returns None, or an
        error message with the state untouched: it is written only once all of the step
        has succeeded."""
        n = self.integrated_size
        work = state[:]
        for duration, rate in self.rate_segments(x, v, h):
            if duration > 0.0:
                if n:
                    integrated = work[:n]
                    problem = integrator.integrate(self, integrated, rate, duration)
                    if problem:
                        return problem
                    work[:n] = integrated
                self._advance_plain(work, rate, duration)
        state[:] = work
        return None

    # --- integrator system: the nested branches ---------------------------------------

    def rhs_source(self):
        """ds/dt and dw/dt of each nested branch (module docstring; Eq. 4.2.7-1 and 6.1-2)
        for the integrator to compile: state Y = [s, w, ...], held rate u. The plain
        branches' exact update is the ``exact`` part: with a = k(|v| + xi)/c,
        dr/dt = v - a*r gives r(h) = v/a + (r(0) - v/a) exp(-a h) for constant v."""
        held = ["speed = u if u >= 0.0 else -u"]  # |v|, as a conditional expression (no call)
        stage = []
        jacobian = []
        for i, (k1, c1, xi1, k2, g, xi2) in enumerate(self._nested):
            p, q = 2 * i, 2 * i + 1
            s, w, ds, dw = f"Y{p}", f"Y{q}", f"f{p}", f"f{q}"
            held.append(f"fluidity{i} = (speed + {xi1!r}) / {c1!r}")  # 1/eta of the outer dashpot
            stage += [f"{ds} = u - ({k1!r} * {s} + {k2!r} * {w}) * fluidity{i}",
                      # |ds/dt| as a conditional expression: the same value without a call
                      f"{dw} = {ds} - {g!r} * {w} * (({ds} if {ds} >= 0.0 else -{ds}) + {xi2!r})"]
            # d|ds/dt|/dy = sign(ds/dt) d(ds/dt)/dy: the nested rate rides on the outer one.
            jacobian += [f"nested_factor = 1.0 - {g!r} * {w} * copysign(1.0, {ds})",
                         f"j{p}_{p} = -{k1!r} * fluidity{i}",
                         f"j{p}_{q} = -{k2!r} * fluidity{i}",
                         f"j{q}_{p} = -{k1!r} * fluidity{i} * nested_factor",
                         f"j{q}_{q} = -{k2!r} * fluidity{i} * nested_factor"
                         f" - {g!r} * (abs({ds}) + {xi2!r})"]
        exact = []
        for i, (k, c, xi) in enumerate(self._plain, start=self.integrated_size):
            exact += [f"decay = {k!r} * (speed + {xi!r}) / {c!r}",
                      "r_steady = u / decay",
                      f"state[{i}] = r_steady + (state[{i}] - r_steady) * exp(-decay * h)"]
        # The tyre's step is one segment while it stays in contact (rate_segments).
        one_segment = "x > 0.0 and x + u * h > 0.0" if self.unilateral else None
        return RhsSource(stage, held, jacobian=jacobian, exact=exact, one_segment=one_segment,
                         namespace={"exp": math.exp, "copysign": math.copysign})

    # --- outputs ----------------------------------------------------------------------

    def branch_force(self, state):
        total = 0.0
        i = 0
        for k1, _, _, k2, _, _ in self._nested:
            total += k1 * state[i] + k2 * state[i + 1]
            i += 2
        for k, _, _ in self._plain:
            total += k * state[i]
            i += 1
        return total

    def _branch_stiffness(self, state, direction):
        """Slope of the branch forces against x for fast motion in `direction` (+1/-1):
        the rate-independent tangent of Eq. 4.2.7-2, dF/dx = k(1 - sgn(v) F/c), with the
        nested element riding on the outer spring's rate."""
        total = 0.0
        i = 0
        for k1, c1, _, k2, g, _ in self._nested:
            w = state[i + 1]
            outer_slip = 1.0 - direction * (k1 * state[i] + k2 * w) / c1
            nested_direction = direction if outer_slip >= 0.0 else -direction
            nested_slip = 1.0 - nested_direction * g * w
            total += outer_slip * (k1 + k2 * nested_slip)
            i += 2
        for k, c, _ in self._plain:
            total += k * (1.0 - direction * k * state[i] / c)
            i += 1
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
        h = self.geometric_slope
        multiplier = 1.0 + h * abs(offset)
        branch_force = self.branch_force(state)
        viscoelastic = multiplier * branch_force
        force = elastic + viscoelastic
        if self.unilateral and force <= 0.0:
            return 0.0, elastic, viscoelastic, 0.0
        # d/dx of f(x) * F_branch: f' F_branch + f dF_branch/dx, in the rate's direction.
        if v != 0.0:
            direction = 1.0 if v > 0.0 else -1.0
            side = direction if offset == 0.0 else (1.0 if offset > 0.0 else -1.0)
            visco_slope = (h * side * branch_force
                           + multiplier * self._branch_stiffness(state, direction))
        else:
            # f' averages to zero at the kink; elsewhere it is the same both ways.
            side = 0.0 if offset == 0.0 else (1.0 if offset > 0.0 else -1.0)
            visco_slope = h * side * branch_force + multiplier * 0.5 * (
                self._branch_stiffness(state, 1.0) + self._branch_stiffness(state, -1.0))
        return force, elastic, viscoelastic, elastic_slope + visco_slope
