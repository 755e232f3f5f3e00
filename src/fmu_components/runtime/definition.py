"""What a component is, as data: its variables (with units, display units, descriptions and
start values), its parameters' constraints, and its equations (model.Equations), in a
``ComponentDefinition``; ``Structure``, one of the thesis's rubber model structures.

The thesis's values fill these in, one file per component family (rubber_parts.py,
damper_part.py); catalog.py assembles the four components. Both flavours are generated
from a definition: the Python flavour reads it at run time, the C printer
(export/cgen.py) writes it into the native flavour's model.c and model_config.h.
"""

import copy
import math

from .expressions import FUNCTIONS, PythonPrinter, Symbol, dependencies
from .integrator import DEFAULT_RTOL
from .model import Model


POSITIVE, NON_NEGATIVE = "positive", "zero or positive"

# Compiled models by equations (the object) and parameter values (their repr, so that
# -0.0 is not 0.0): ComponentDefinition.build_model.
_MODELS = {}
MAX_MODELS = 64

# The parameter magnitudes the model's arithmetic takes: a product, quotient or square of
# two such values stays a normal double (about 1e-308 to 1e308), so a parameter cannot
# make every step NaN or Inf (k3 = 1e-310 gives 1/k3 = Inf; a slope of 1e300 overflows).
# The native runtime checks the same bounds (cgen writes them to model_config.h).
SMALLEST_PARAMETER, LARGEST_PARAMETER = 1e-100, 1e100


def _power_of_ten(value):
    return f"{value:.0e}".replace("e+", "e")


# How both runtimes' messages name those magnitudes (cgen writes it to model_config.h).
PARAMETER_MAGNITUDES = (f"zero or {_power_of_ten(SMALLEST_PARAMETER)} to "
                        f"{_power_of_ten(LARGEST_PARAMETER)} in size")


def magnitude_problem(variable, value):
    """A message if a parameter's nonzero value is outside the magnitudes the model's
    arithmetic takes, else None."""
    if value != 0.0 and not SMALLEST_PARAMETER <= abs(value) <= LARGEST_PARAMETER:
        return (f"{variable.name} = {value!r} {variable.unit} is outside the magnitudes the "
                f"model's arithmetic takes ({PARAMETER_MAGNITUDES})")
    return None


# Within this many deflection scales of 0, in the deflection and in the rate (per second),
# every output is finite for a state the model reached (tests/test_robustness.py); beyond,
# a set or a step first makes sure of it (runtime/cosim.py, FiniteGuard).
FINITE_SCALES = 1e3

DERIVATIVE_UNITS = {"m": "m/s", "rad": "rad/s", "1": "1/s", "rad/s": "rad/s2"}


class Variable:
    __slots__ = ("name", "causality", "unit", "display_unit", "description", "start",
                 "constraint")

    def __init__(self, name, causality, unit, description, start=None, display_unit=None,
                 constraint=None):
        self.name = name
        self.causality = causality
        self.unit = unit
        self.display_unit = display_unit
        self.description = description
        self.start = start
        self.constraint = constraint  # POSITIVE, NON_NEGATIVE or None (any finite value)

    def check(self, value):
        """A message if the value cannot be this variable's, else None."""
        if not math.isfinite(value):
            return f"{self.name} = {value!r} {self.unit} is not a finite number"
        if (self.constraint == POSITIVE and value <= 0.0) or (
                self.constraint == NON_NEGATIVE and value < 0.0):
            return f"{self.name} = {value!r} {self.unit} must be {self.constraint}"
        return None


class Switch:
    """A Boolean parameter. Its value reference follows the Real variables'."""
    __slots__ = ("name", "description", "start")
    causality = "parameter"

    def __init__(self, name, description, start=False):
        self.name = name
        self.description = description
        self.start = start


class ComponentDefinition:
    """Everything the generic FMU adapter needs to know about one component."""

    def __init__(self, name, description, inputs, outputs, parameters, states, equations,
                 measured_ranges, stop_time=2.0, structure_name="final"):
        self.name = name
        # Which of the four components this is, in which of the thesis's structures: an
        # engineer's own part (with_values) keeps both under a name of its own.
        self.component = name
        self.structure_name = structure_name
        self.description = description
        self.inputs = inputs  # (deflection, rate)
        self.outputs = outputs
        self.parameters = parameters
        # the continuous states (locals: what a Model Exchange host integrates, and what any
        # host may read), each with its derivative
        self.states = states
        self.derivatives = tuple(
            Variable(f"der({v.name})", "local", DERIVATIVE_UNITS[v.unit],
                     f"Time derivative of {v.name}") for v in states)
        assert len(states) == equations.continuous.states, name
        self.equations = equations  # model.Equations over the parameters' names
        self.measured_ranges = measured_ranges  # input name -> (low, high, what the thesis measured)
        # The size of a deflection, for the floors of the rate check (runtime/cosim.py).
        low, high, _ = measured_ranges[inputs[0].name]
        self.deflection_scale = max(abs(b) for b in (low, high) if math.isfinite(b))
        bound = FINITE_SCALES * self.deflection_scale
        self.finite_bounds = ((-bound, bound), (-bound, bound))  # deflection, rate
        deflection, rate = (v.name for v in inputs)
        self.switches = (Switch(
            "rate_from_deflection",
            f"Derive {rate} from the {deflection} samples instead of reading it: the "
            f"backward difference over the previous communication step, held over the next "
            f"(the first step takes the input). For hosts that cannot supply a rate; it lags "
            f"by about one step (docs/simulate.md)."),)
        self.default_experiment = {"startTime": 0.0, "stopTime": stop_time,
                                   "stepSize": 1e-3, "tolerance": DEFAULT_RTOL}

    @property
    def variables(self):
        """By value reference: inputs, outputs, parameters, states, their derivatives."""
        return (list(self.inputs) + list(self.outputs) + list(self.parameters)
                + list(self.states) + list(self.derivatives))

    def switch_reference(self, name):
        """The value reference of a Boolean parameter: after every Real variable."""
        return len(self.variables) + [s.name for s in self.switches].index(name)

    def structure(self):
        """The ModelStructure, read off the equations: {output or derivative name: the
        inputs and states it depends on}, in either interface (an output of the
        co-simulation depends on the inputs and states its equations read; in the
        continuous-time view on those its own equations read)."""
        e, view = self.equations, self.equations.continuous
        names = {"x": self.inputs[0].name, "v": self.inputs[1].name}
        names.update({("state", i): v.name for i, v in enumerate(self.states)})
        names.update({f"Y{i}": v.name for i, v in enumerate(self.states)})
        knowns = set(names)
        co_simulation = dependencies(e.output_lines, e.outputs, knowns)
        continuous = dependencies(*e.continuous_output_statements(), knowns)
        rates = dependencies(e.rate_statements(), [Symbol(f"f{i}") for i in range(view.states)],
                             knowns)
        structure = {}
        for variable, *sets in zip(self.outputs, co_simulation, continuous):
            structure[variable.name] = {names[k] for group in sets for k in group}
        for variable, read in zip(self.derivatives, rates):
            structure[variable.name] = {names[k] for k in read}
        return structure

    def build_model(self, values):
        """The Python model with these parameter values (name -> value). A model is read-only
        once made, so instances with the same equations and values share one: making
        another instance compiles nothing."""
        key = (self.equations, tuple(sorted((n, repr(v)) for n, v in values.items())))
        cached = _MODELS.get(key)
        if cached is None:
            if len(_MODELS) >= MAX_MODELS:
                _MODELS.clear()  # a host sweeping parameters: do not grow forever
            cached = _MODELS[key] = Model(self.equations, values)
        return cached

    def default_parameters(self):
        """The thesis value of every parameter, by name."""
        return {p.name: p.start for p in self.parameters}

    def state_nominals(self, values=None):
        """Each continuous state's typical magnitude at these parameter values (name ->
        value; default the start values), as the Python model computes it: the nominals'
        expressions alone, without compiling the model."""
        printer = PythonPrinter(values or self.default_parameters())
        namespace = {name: getattr(math, name) for name in FUNCTIONS}
        return [float(eval(printer.expression(e), namespace))
                for e in self.equations.continuous.nominals]

    def with_values(self, name, values):
        """This component under another name, with other parameters' start values (name ->
        SI value; the others keep theirs): an engineer's own part, such as one identified
        by ``fmu-components fit``."""
        twin = copy.copy(self)
        twin.name = name
        twin.description = f"{name}: {self.description} Parameter values of its own."
        twin.parameters = []
        for parameter in self.parameters:
            if parameter.name in values and float(values[parameter.name]) != parameter.start:
                thesis = parameter.start
                parameter = copy.copy(parameter)
                parameter.start = float(values[parameter.name])
                # The description quotes the thesis: say whose value the start value is.
                parameter.description = (f"{parameter.description}; this part's own value "
                                         f"(the thesis's is {thesis:.6g} {parameter.unit})")
            twin.parameters.append(parameter)
        return twin

    def check_parameters(self, values):
        """A message naming the first parameter (or table) that makes no physical sense,
        else None."""
        for parameter in self.parameters:
            value = values[parameter.name]
            problem = parameter.check(value) or magnitude_problem(parameter, value)
            if problem:
                return f"parameter {problem}"
        for table in self.equations.tables:
            problem = table.check(values)
            if problem:
                return problem
        return None


class Structure:
    """One of the thesis's model structures as data for the N-branch rubber model: its
    Maxwell elements (number K, role) and how they form branches, (outer K, nested K or
    None). Parameters are k{K}, c{K}, xi{K}; each element's spring deformation is a state,
    named by ``state_symbols`` (default s{K})."""

    def __init__(self, name, title, section, cited, elements, branches, state_symbols=None):
        self.name = name
        self.title = title  # the model's name in a component's description
        self.section = section  # the section that defines it
        self.cited = cited  # where the thesis describes it and gives its values
        self.elements = elements  # ((K, role), ...)
        self.branches = branches  # ((outer K, nested K or None), ...)
        self.state_symbols = state_symbols or {index: f"s{index}" for index, _ in elements}

    def state_order(self):
        """Element numbers in the rubber model's state layout: [outer, nested] of each
        nested branch, then the outer element of each plain one (rubber_equations)."""
        nested = [k for outer, inner in self.branches if inner is not None for k in (outer, inner)]
        return nested + [outer for outer, inner in self.branches if inner is None]
