"""Coupling schemes: which load law the host applies in each solve of a step, and when a
step is done (master.py runs them; the laws are the components', fmu.py).

    explicit    one solve per step and no rollback, for a host that cannot repeat a
                step: the law about the last accepted step (today's examples' coupling)
    corrected   two solves: the first with the law predicted from the last accepted
                step, the second with the law about the FMU's answer to the first; two
                FMU steps per host step (the recommended default)
    converged   solves until the FMU's load and the host's agree to a tolerance, each
                with the law about the FMU's latest answer; a warning where the pass
                limit stops a step first
"""


class Scheme:
    name = "scheme"
    passes = 1  # at most, per host step
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
        return passes >= self.passes or mismatch <= self.tolerance


class Explicit(Scheme):
    name = "explicit"

    def first_law(self, component, time):
        return component.lagged_law()


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


SCHEMES = {scheme.name: scheme for scheme in (Explicit, Corrected, Converged)}


def scheme_named(name):
    try:
        return SCHEMES[name]()
    except KeyError:
        raise ValueError(f"no coupling scheme {name!r}; the schemes are "
                         f"{', '.join(SCHEMES)}") from None
