"""Coupling schemes: which load law the host applies in each solve of a step, and when a
step is done (master.py runs them; the laws are the components', fmu.py).

For a host that can repeat a step (FMU states restored between its solves):

    corrected   two solves: the first with the law predicted for the step, the second
                with the law about the FMU's answer to the first; two FMU steps per host
                step (the default)
    iterated    corrected's two solves, then more until the FMU's load and the host's
                agree to 1e-4 of the component's peak load, each with the law about the
                FMU's latest answer (at most 8; a warning where that limit stops a step
                first): where two solves leave too much, as at the whole vehicle's
                near-slack joints (docs/vehicle.md); the vehicle's default
    converged   as iterated, to 1e-9 and 20 solves: the reference the others are
                measured against

For a host that cannot (one solve, one FMU step per host step):

    explicit    the law about the last accepted step: load and `stiffness` (for the
                damper, whose `stiffness` is no tangent over a step, the plain load)
    predicted   every component's linearised answer to the step (its Model Exchange
                Jacobian along the step continuing at the last rate)
    nepce       explicit, plus the energy its lag put into the interface in the last
                step given back in the next (NEPCE, Benedikt et al. 2013; Sadjina and
                Pedersen 2019)
"""


class Scheme:
    name = "scheme"
    passes = 1  # at most, per host step
    least_passes = 1  # before the tolerance may end a step
    tolerance = 0.0  # mismatch (of the load scale) below which a step is done early
    warn_unconverged = False

    def first_law(self, component, time):
        """The law for the first solve of a step to `time`."""
        return component.predicted_law(time)

    def next_law(self, component):
        """The law for the next solve, about the FMU's answer to the host's last one."""
        return component.corrected_law()

    def mismatch(self, component, deflection, rate, outputs):
        """|FMU load - load the host applied| at the host's solution, over a load scale."""
        load = outputs[component.load_name]
        return abs(load - component.host_load(deflection, rate)) / component.load_scale(load)

    def done(self, passes, mismatch):
        return passes >= self.passes or (passes >= self.least_passes
                                         and mismatch <= self.tolerance)

    def first_solve_may_end(self):
        """Whether a step's first solve can be its last (the scheme done after one pass
        where the loads agree): where it cannot, a host may solve it only roughly, as its
        answer serves only the next law."""
        return self.done(1, 0.0)


class Corrected(Scheme):
    name = "corrected"
    passes = 2


class Converged(Scheme):
    name = "converged"
    passes = 20
    tolerance = 1e-9
    warn_unconverged = True

    def __init__(self, tolerance=None, passes=None):
        if tolerance is not None:
            self.tolerance = tolerance
        if passes is not None:
            self.passes = passes


class Iterated(Converged):
    name = "iterated"
    passes = 8
    least_passes = 2  # corrected's: a first solve within the tolerance may still be
    # further off than corrected's second (the law it used is only a prediction)
    tolerance = 1e-4


class Explicit(Scheme):
    name = "explicit"

    def first_law(self, component, time):
        return component.lagged_law()


class Predicted(Scheme):
    name = "predicted"

    def first_law(self, component, time):
        return component.predicted_law(time, linearised=True)


class Nepce(Explicit):
    """Over a step the FMU does W_f = (F_n + F_n+1) dx / 2 along the secant, the host
    W_h = (F_h(x_n) + F_h(x_n+1)) dx / 2 with its law. The residual W_f - W_h goes back
    over the next step as a constant load c = dE dx' / (dx'^2 + e^2): dx' the
    displacement expected of that step (the last one's), e a small displacement (1e-3 of
    the peak load over the stiffness) below which the motion is too small to carry it."""
    name = "nepce"

    def __init__(self):
        self._corrections = {}

    def first_law(self, component, time):
        law = component.lagged_law()
        correction = self._corrections.get(component, 0.0)
        return _Shifted(law, correction) if correction else law

    def mismatch(self, component, deflection, rate, outputs):
        # the law this step used, its correction included, and the FMU's answer
        correction = self._corrections.get(component, 0.0)
        residual = outputs[component.load_name] - component.host_load(deflection, rate)
        dx = deflection - component.deflection
        energy = 0.5 * dx * (residual - correction)
        stiffness = abs(component.outputs.get("stiffness", 0.0)) or 1.0
        floor = 1e-3 * max(component.peak_load, 1e-9) / stiffness
        self._corrections[component] = energy * dx / (dx * dx + floor * floor)
        return super().mismatch(component, deflection, rate, outputs)


class _Shifted:
    """A load law plus a constant."""
    __slots__ = ("law", "shift")

    def __init__(self, law, shift):
        self.law, self.shift = law, shift

    def __call__(self, deflection, rate=0.0):
        return self.law(deflection, rate) + self.shift


SCHEMES = {scheme.name: scheme
           for scheme in (Corrected, Iterated, Converged, Explicit, Predicted, Nepce)}
REPEATING = ("corrected", "iterated", "converged")  # need a host that repeats a step


def scheme_named(name):
    try:
        return SCHEMES[name]()
    except KeyError:
        raise ValueError(f"no coupling scheme {name!r}; the schemes are "
                         f"{', '.join(SCHEMES)}") from None
