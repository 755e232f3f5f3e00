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
while x > 0, so a step that crosses x = 0 is split at the crossing (model.rate_segments).

The equations are expression trees (expressions.py) over the parameters as symbols: the
same trees become the Python of the pythonfmu flavour and the C of the native one.
"""

from .expressions import (Assign, Element, Symbol, all_of, copysign, differs, equal, exp,
                          total, where, wrap)
from .model import ContinuousTime, Equations


class MaxwellElement:
    """Spring k in series with a dashpot of viscosity c/(|u| + xi); time constant
    tau = c/(k*xi) (Eq. 4.2.7-3). k, c, xi: parameter symbols or numbers."""

    __slots__ = ("k", "c", "xi")

    def __init__(self, k, c, xi):
        self.k, self.c, self.xi = wrap(k), wrap(c), wrap(xi)


class Branch:
    __slots__ = ("outer", "nested")

    def __init__(self, outer, nested=None):
        self.outer = outer
        self.nested = nested


def rubber_equations(branches, elastic, geometric_slope, geometric_reference, unilateral=False):
    """The equations of a rubber component. elastic: a0..a3 of Fe = a0 + a1 x + a2 x^2 +
    a3 x^3 (Eq. 5.3.1-x); geometric: h and x_ref of f = 1 + h|x - x_ref| (Eq. 5.3.2-x).

    State layout: [s, w] for each nested branch (integrated), then r for each plain
    branch (exact update)."""
    nested = [b for b in branches if b.nested is not None]
    plain = [b for b in branches if b.nested is None]
    n = 2 * len(nested)
    u, h = Symbol("u"), Symbol("h")
    speed = Symbol("speed")
    held = [Assign(speed, abs(u))]
    constants, stage, jacobian, state_scale = [], [], [], []
    for i, branch in enumerate(nested):
        outer, inner = branch.outer, branch.nested
        p, q = 2 * i, 2 * i + 1
        s, w, ds, dw = Symbol(f"Y{p}"), Symbol(f"Y{q}"), Symbol(f"f{p}"), Symbol(f"f{q}")
        fluidity, g = Symbol(f"fluidity{i}"), Symbol(f"nested_k_over_c{i}")
        constants.append(Assign(g, inner.k / inner.c))
        held.append(Assign(fluidity, (speed + outer.xi) / outer.c))  # 1/eta of the outer dashpot
        stage += [Assign(ds, u - (outer.k * s + inner.k * w) * fluidity),
                  Assign(dw, ds - g * w * (abs(ds) + inner.xi))]
        # d|ds/dt|/dy = sign(ds/dt) d(ds/dt)/dy: the nested rate rides on the outer one.
        factor = Symbol("nested_factor")
        jacobian += [Assign(factor, 1.0 - g * w * copysign(1.0, ds)),
                     Assign(Symbol(f"j{p}_{p}"), -outer.k * fluidity),
                     Assign(Symbol(f"j{p}_{q}"), -inner.k * fluidity),
                     Assign(Symbol(f"j{q}_{p}"), -outer.k * fluidity * factor),
                     Assign(Symbol(f"j{q}_{q}"), -inner.k * fluidity * factor
                            - g * (abs(ds) + inner.xi))]
        # Typical spring deformations, the force c that saturates each dashpot over k: the
        # integrator's absolute tolerance is rtol times these.
        state_scale += [outer.c / outer.k, inner.c / inner.k]
    # The plain branches' exact update: with a = k(|v| + xi)/c, dr/dt = v - a*r gives
    # r(h) = v/a + (r(0) - v/a) exp(-a h) for constant v.
    exact, rates, nominals = [], [], list(state_scale)
    for i, branch in enumerate(plain, start=n):
        element = branch.outer
        decay, steady, r = Symbol("decay"), Symbol("r_steady"), Element("state", i)
        exact += [Assign(decay, element.k * (speed + element.xi) / element.c),
                  Assign(steady, u / decay),
                  Assign(r, steady + (r - steady) * exp(-decay * h))]
        # the same branch for a host's integrator: dr/dt = v - k r (|v| + xi)/c
        rates.append(Assign(Symbol(f"f{i}"), u - element.k * Symbol(f"Y{i}")
                            * (speed + element.xi) / element.c))
        nominals.append(element.c / element.k)
    # A contact's event: x crossing 0, scaled by a millimetre (spec section 7).
    events = [Symbol("x") / 1e-3] if unilateral else []
    output_lines, outputs = _outputs(nested, plain, elastic, geometric_slope,
                                     geometric_reference, unilateral)
    return Equations(integrated=n, state_size=n + len(plain), constants=constants, held=held,
                     stage=stage, jacobian=jacobian, exact=exact,
                     initial_state=[0.0] * (n + len(plain)),  # relaxed (spec section 2)
                     output_lines=output_lines, outputs=outputs, state_scale=state_scale,
                     unilateral=unilateral,
                     continuous=ContinuousTime(n + len(plain), nominals, rates,
                                               event_indicators=events))


def _branch_stiffness(nested, plain, direction):
    """Slope of the branch forces against x for fast motion in `direction` (+1/-1): the
    rate-independent tangent of Eq. 4.2.7-2, dF/dx = k(1 - sgn(v) F/c), with the nested
    element riding on the outer spring's rate."""
    terms = []
    for i, branch in enumerate(nested):
        outer, inner = branch.outer, branch.nested
        s, w = Element("state", 2 * i), Element("state", 2 * i + 1)
        g = Symbol(f"nested_k_over_c{i}")
        outer_slip = 1.0 - direction * (outer.k * s + inner.k * w) / outer.c
        nested_direction = where(outer_slip >= 0.0, direction, -direction)
        terms.append(outer_slip * (outer.k + inner.k * (1.0 - nested_direction * g * w)))
    for i, branch in enumerate(plain, start=2 * len(nested)):
        element = branch.outer
        terms.append(element.k * (1.0 - direction * element.k * Element("state", i) / element.c))
    return total(terms)


def _outputs(nested, plain, elastic, slope, x_ref, unilateral):
    """(force, elastic part, viscoelastic part, tangent stiffness dF/dx).

    The tangent is taken in the direction of the rate; at zero rate it is the mean of
    the loading and unloading slopes. For the tyre out of contact, or pulled off the
    surface by the viscoelastic force, force and tangent are zero."""
    x, v = Symbol("x"), Symbol("v")
    a0, a1, a2, a3 = (wrap(a) for a in elastic)
    names = "elastic elastic_slope offset multiplier branch_force viscoelastic force " \
            "direction side branch_slope".split()
    (elastic_force, elastic_slope, offset, multiplier, branch_force, viscoelastic, force,
     direction, side, branch_slope) = (Symbol(n) for n in names)
    forces = [b.outer.k * Element("state", 2 * i) + b.nested.k * Element("state", 2 * i + 1)
              for i, b in enumerate(nested)]
    forces += [b.outer.k * Element("state", i) for i, b in enumerate(plain, start=2 * len(nested))]
    lines = [
        Assign(elastic_force, a0 + x * (a1 + x * (a2 + x * a3))),
        Assign(elastic_slope, a1 + x * (2.0 * a2 + 3.0 * a3 * x)),
        Assign(offset, x - x_ref),
        Assign(multiplier, 1.0 + slope * abs(offset)),
        Assign(branch_force, total(forces)),
        Assign(viscoelastic, multiplier * branch_force),
        Assign(force, elastic_force + viscoelastic),
        Assign(direction, where(v > 0.0, 1.0, where(v < 0.0, -1.0, 0.0))),
        # d|x - x_ref|/dx: the rate's direction at the kink (the mean, zero, at rest)
        Assign(side, where(equal(offset, 0.0), direction, where(offset > 0.0, 1.0, -1.0))),
        Assign(branch_slope, where(differs(v, 0.0), _branch_stiffness(nested, plain, direction),
                                   0.5 * (_branch_stiffness(nested, plain, 1.0)
                                          + _branch_stiffness(nested, plain, -1.0)))),
    ]
    # d/dx of f(x) * F_branch: f' F_branch + f dF_branch/dx, in the rate's direction.
    stiffness = elastic_slope + (slope * side * branch_force + multiplier * branch_slope)
    if not unilateral:
        return lines, [force, elastic_force, viscoelastic, stiffness]
    touching = x > 0.0
    pushing = all_of(touching, force > 0.0)
    return lines, [where(pushing, force, 0.0), where(touching, elastic_force, 0.0),
                   where(touching, viscoelastic, 0.0), where(pushing, stiffness, 0.0)]
