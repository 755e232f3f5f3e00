"""The four components as data: variables, units, parameter values with their thesis
provenance, and how each builds its physics model.

Values are SI. Appendix 4b prints its rubber tables in ADAMS mm-N-s units (deg for the
torsion bush), so k is converted per m (per rad) and xi per m/s (rad/s); the check is the
time constant tau = c/(k*xi) = 100, 0.1 and 1.0 s of section 6.4 (spec section 1).
"""

import copy
import math

from .damper import damper_equations
from .expressions import Symbol, dependencies
from .integrator import DEFAULT_RTOL
from .model import Model
from .rubber import Branch, MaxwellElement, rubber_equations

from .units import MM, PER_DEG


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


def magnitude_problem(variable, value):
    """A message if a parameter's nonzero value is outside the magnitudes the model's
    arithmetic takes, else None."""
    if value != 0.0 and not SMALLEST_PARAMETER <= abs(value) <= LARGEST_PARAMETER:
        return (f"{variable.name} = {value!r} {variable.unit} is outside the magnitudes the "
                f"model's arithmetic takes (zero or 1e-100 to 1e100 in size)")
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


# --- rubber components (spec section 2) ---------------------------------------------------

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


FINAL = Structure(
    "final", "final three-Maxwell-element model", "section 6.4",
    "thesis sections 5-7, Appendix 4b",
    elements=((1, "outer Maxwell element of branch A"),
              (2, "Maxwell element nested across spring k1 of branch A (the stiffening "
                  "element, section 6.3)"),
              (3, "Maxwell element of branch B")),
    branches=((1, 2), (3, None)), state_symbols={1: "s", 2: "w", 3: "r"})
FOUR_ELEMENT = Structure(
    "four-element", "four-element model (two Maxwell elements, each with a nested stiffening "
    "element)", "section 6.3", "thesis section 6.3, Fig. 6.3-3, Appendix 4a",
    elements=((1, "outer Maxwell element of branch A"),
              (2, "Maxwell element nested across spring k1 of branch A (stiffening element)"),
              (3, "outer Maxwell element of branch B"),
              (4, "Maxwell element nested across spring k3 of branch B (stiffening element)")),
    branches=((1, 2), (3, 4)))
HAUPT_SEDLAN = Structure(
    "haupt-sedlan", "simplified Haupt and Sedlan model (two parallel Maxwell elements)",
    "section 6.1", "thesis sections 6.1-6.2, Fig. 6.1-1",
    elements=((1, "Maxwell element of branch A"), (2, "Maxwell element of branch B")),
    branches=((1, None), (2, None)))
STRUCTURES = {s.name: s for s in (FINAL, FOUR_ELEMENT, HAUPT_SEDLAN)}


def _rubber_component(name, description, *, structure, deflection, deflection_meaning, load,
                      angular, elements, elastic, geometric, unilateral, measured_range):
    """elements: per element of the structure (k, c, xi, (thesis text of each), source);
    elastic: (a0..a3, thesis text); geometric: (h, x_ref, thesis text). The description's
    {model} is the structure's title with its thesis place."""
    length, load_unit = ("rad", "N.m") if angular else ("m", "N")
    display = "deg" if angular else "mm"
    stiffness = f"{load_unit}/{length}"
    model = f"{structure.title} ({structure.cited})"
    description = description.format(model=model, Model=model[0].upper() + model[1:])
    inputs = (
        Variable(deflection, "input", length, deflection_meaning, 0.0, display),
        Variable(f"{deflection}_rate", "input", f"{length}/s",
                 f"Rate dx/dt of {deflection.replace('_', ' ')}, held over each communication step",
                 0.0, f"{display}/s"),
    )
    count = {1: "one", 2: "two", 3: "three", 4: "four"}[len(structure.elements)]
    outputs = (
        Variable(load, "output", load_unit, f"{load.capitalize()} F applied to the component "
                 f"to produce the deflection: Fe(x) + f(x)*(FA + FB) (Eq. 6.1-1)"),
        Variable(f"{load}_elastic", "output", load_unit, "Elastic part Fe(x) (section 5.3.1)"),
        Variable(f"{load}_viscoelastic", "output", load_unit,
                 f"Viscoelastic part f(x)*(FA + FB) of the {count} Maxwell elements "
                 f"({structure.section})"),
        Variable("stiffness", "output", stiffness, "Instantaneous tangent stiffness dF/dx "
                 "in the direction of motion (mean of loading and unloading at zero rate)",
                 display_unit=f"{load_unit}/{display}"),
    )
    parameters = []
    roles = dict(structure.elements)
    for (index, role), (k, c, xi, thesis, source) in zip(structure.elements, elements):
        parameters += [
            Variable(f"k{index}", "parameter", stiffness, f"Spring stiffness of the {role} "
                     f"({source}: {thesis[0]})", k, f"{load_unit}/{display}", POSITIVE),
            Variable(f"c{index}", "parameter", load_unit, f"Maximum damping force c of the "
                     f"{role}: viscosity c/(|rate| + xi) ({source}: {thesis[1]})", c,
                     constraint=POSITIVE),
            Variable(f"xi{index}", "parameter", f"{length}/s", f"Rate constant xi of the {role};"
                     f" time constant c/(k xi) ({source}: {thesis[2]})", xi, f"{display}/s",
                     POSITIVE),
        ]
    a, elastic_thesis = elastic
    for power, coefficient in enumerate(a):
        unit = load_unit if power == 0 else f"{load_unit}/{length}" + (str(power) if power > 1 else "")
        parameters.append(Variable(f"elastic.a{power}", "parameter", unit,
                                   f"Coefficient of x^{power} in the elastic force Fe(x) "
                                   f"({elastic_thesis})", coefficient))
    h, x_ref, geometric_thesis = geometric
    parameters += [
        Variable("geometric.h", "parameter", f"1/{length}", f"Slope h of the geometric "
                 f"multiplier f(x) = 1 + h*|x - x_ref| ({geometric_thesis})", h, f"1/{display}",
                 NON_NEGATIVE),
        Variable("geometric.x_ref", "parameter", length, f"Reference deflection x_ref of the "
                 f"geometric multiplier ({geometric_thesis})", x_ref, display),
    ]

    symbols = structure.state_symbols
    states = tuple(
        Variable(f"state.{symbols[i]}", "local", length, f"Deformation {symbols[i]} of spring "
                 f"k{i}, in the {roles[i]} (spec section 2)", display_unit=display)
        for i in structure.state_order())

    def element(i):
        return MaxwellElement(Symbol(f"k{i}"), Symbol(f"c{i}"), Symbol(f"xi{i}"))

    equations = rubber_equations(
        branches=[Branch(element(outer), nested=None if inner is None else element(inner))
                  for outer, inner in structure.branches],
        elastic=[Symbol(f"elastic.a{p}") for p in range(4)],
        geometric_slope=Symbol("geometric.h"), geometric_reference=Symbol("geometric.x_ref"),
        unilateral=unilateral)

    return ComponentDefinition(
        name, description, inputs, outputs, parameters, states, equations,
        measured_ranges={deflection: measured_range}, structure_name=structure.name)


def _thesis_elements(source, rows):
    """Elements from a thesis table: rows of (k, c, xi, (k, c, xi as printed))."""
    return [(k, c, xi, thesis, source) for k, c, xi, thesis in rows]


def _derived_haupt_sedlan(final):
    """The simplified Haupt and Sedlan model of a component: its final model without the
    stiffening element. Section 6.4 builds the final model from this one by nesting element 2
    in element 1; section 6.2 does not print its two elements' values (Figs. 6.2-3 to
    6.2-5), so these are the final model's elements 1 and 3 (Appendix 4b)."""
    return [(k, c, xi, thesis, f"{source}, element {number}")
            for number, (k, c, xi, thesis, source) in ((1, final[0]), (3, final[2]))]


# Each rubber component: what it is, and its element values per structure. The thesis gives
# four-element values for the torsion bush only (Appendix 4a).
RUBBER_PARTS = {
    "RoadWheelTyre": dict(
        description="Warrior road-wheel tyre, radial compression against a track link: "
                    "carbon-black-filled natural rubber, {model}. Unilateral contact: pushes, "
                    "never pulls.",
        deflection="compression", load="force", angular=False,
        deflection_meaning="Tyre compression x against the track link; x <= 0 is out of contact",
        elements={"final": _thesis_elements("Appendix 4b", [
            (1500 / MM, 1000.0, 0.0067 * MM, ("1500 N/mm", "1000 N", "0.0067 mm/s")),
            (1500 / MM, 1000.0, 6.67 * MM, ("1500 N/mm", "1000 N", "6.67 mm/s")),
            (150 / MM, 500.0, 3.33 * MM, ("150 N/mm", "500 N", "3.33 mm/s"))])},
        elastic=((0.0, 2.17e6, -2.14e8, 1.82e11), "Eq. 5.3.1-3"),
        geometric=(543.0, 0.0, "Eq. 5.3.2-2: f = 543 x + 1"),
        unilateral=True,
        # The thesis loaded the tyre to 45 kN (Fig. 5.4-3): Fe(6 mm) = 44.6 kN. The warning
        # leaves room for a bump's overshoot and comes at 10 mm, Fe = 182 kN.
        measured_range=(-math.inf, 10 * MM, "loads up to 45 kN, about 6 mm, Fig. 5.4-3; "
                                            "warned beyond 10 mm, Fe = 182 kN")),
    "TrackBushRadial": dict(
        description="Warrior track-link bush, radial (pin) deflection: carbon-black-filled "
                    "natural rubber, {model}.",
        deflection="deflection", load="force", angular=False,
        deflection_meaning="Radial deflection x of the track pin in its bush",
        elements={"final": _thesis_elements("Appendix 4b", [
            (60000 / MM, 3800.0, 0.00063 * MM, ("60000 N/mm", "3800 N", "0.00063 mm/s")),
            (60000 / MM, 3800.0, 0.63 * MM, ("60000 N/mm", "3800 N", "0.63 mm/s")),
            (17000 / MM, 100000.0, 5.9 * MM, ("17000 N/mm", "100000 N", "5.9 mm/s"))])},
        elastic=((0.0, 81.8e6, 0.0, 0.0), "Eq. 5.3.1-2"),
        geometric=(0.0, 0.0, "Appendix 4b: f = 1"),
        unilateral=False,
        measured_range=(-0.6 * MM, 0.6 * MM, "radial load up to 50 kN, section 5.1.2")),
    "TrackBushTorsion": dict(
        description="Warrior track-link bush, torsion about the pin: angle between adjacent "
                    "links, zero with links in line, live angle about 10 deg. {Model}.",
        deflection="angle", load="torque", angular=True,
        deflection_meaning="Angle x between adjacent track links, zero with the links in line "
                           "(live angle about 10 deg)",
        elements={
            "final": _thesis_elements("Appendix 4b", [
                (10 * PER_DEG, 20.0, 0.02 / PER_DEG, ("10 N.m/deg", "20 N.m", "0.02 deg/s")),
                (10 * PER_DEG, 20.0, 20 / PER_DEG, ("10 N.m/deg", "20 N.m", "20 deg/s")),
                (3 * PER_DEG, 40.0, 13.3 / PER_DEG, ("3 N.m/deg", "40 N.m", "13.3 deg/s"))]),
            "four-element": _thesis_elements("Appendix 4a", [
                (10 * PER_DEG, 20.0, 0.02 / PER_DEG, ("10 N.m/deg", "20 N.m", "0.02 deg/s")),
                (20 * PER_DEG, 20.0, 20 / PER_DEG, ("20 N.m/deg", "20 N.m", "20 deg/s")),
                (3 * PER_DEG, 40.0, 13.3 / PER_DEG, ("3 N.m/deg", "40 N.m", "13.3 deg/s")),
                (40 * PER_DEG, 40.0, 20 / PER_DEG, ("40 N.m/deg", "40 N.m", "20 deg/s"))])},
        # Eq. 5.3.1-1 prints -130.4 N.m, Appendices 4a and 4b +130.4; the torque is near zero
        # at the 10 deg live angle only with the minus sign (spec section 2).
        elastic=((-130.4, 12.4 * PER_DEG, 0.0, 0.0), "Eq. 5.3.1-1: 12.4 N.m/deg * angle - 130.4 N.m"),
        geometric=(0.033 * PER_DEG, 10.0 / PER_DEG, "Eq. 5.3.2-1: f = 0.033|angle - 10 deg| + 1"),
        unilateral=False,
        # Section 5.1.2: the live angle is 10 deg, and the largest torsion, around the
        # sprocket, about 23 deg; the rig tests (spec section 5) went from -10 to 30 deg.
        measured_range=(-13.0 / PER_DEG, 33.0 / PER_DEG,
                        "-13 to 33 deg: the live angle 10 deg +/- the largest torsion, about "
                        "23 deg around the sprocket, section 5.1.2")),
}
for _part in RUBBER_PARTS.values():
    _part["elements"]["haupt-sedlan"] = _derived_haupt_sedlan(_part["elements"]["final"])


def _rubber_definition(name, structure):
    part = dict(RUBBER_PARTS[name])
    elements = part.pop("elements")[structure.name]
    return _rubber_component(name, part.pop("description"), structure=structure,
                             elements=elements, **part)


ROAD_WHEEL_TYRE = _rubber_definition("RoadWheelTyre", FINAL)
TRACK_BUSH_RADIAL = _rubber_definition("TrackBushRadial", FINAL)
TRACK_BUSH_TORSION = _rubber_definition("TrackBushTorsion", FINAL)


# --- rotary damper (spec section 3) -------------------------------------------------------

# Table A6-1, "smoothed curve" column (rad/s, N.m). The printed table lost the 0.6 rad/s
# row on the compression side; it is restored by symmetry with the rebound side
# (reference_data/thesis/table_A6-1.csv keeps all three columns and the note).
DAMPER_TABLE_RATES = (
    -14.0, -13.0, -12.0, -11.0, -10.0, -9.0, -8.0, -7.0, -6.0, -5.0, -4.0, -3.0, -2.0,
    -1.8, -1.6, -1.4, -1.2, -1.0, -0.8, -0.6, -0.4, -0.2, -0.1, 0.0, 0.1, 0.2, 0.4, 0.6, 0.8,
    1.0, 1.2, 1.4, 1.6, 1.8, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0,
    14.0)
DAMPER_TABLE_TORQUES = (
    -8050.0, -8050.0, -8050.0, -8050.0, -7950.0, -7950.0, -7800.0, -7600.0, -7400.0, -7250.0,
    -7000.0, -6500.0, -6000.0, -5800.0, -5550.0, -5200.0, -4471.0, -3250.0, -2186.0, -1306.0,
    -622.0, -194.0, -100.0, 0.0, 100.0, 194.0, 622.0, 1306.0, 2186.0, 3250.0, 4471.0, 5856.0,
    7200.0, 8000.0, 8500.0, 10300.0, 11600.0, 12100.0, 12600.0, 12850.0, 13000.0, 13200.0,
    13400.0, 13550.0, 13550.0, 13650.0, 13650.0)
TABLE_SIZE = len(DAMPER_TABLE_RATES)


def _rate_name(i):
    return f"dashpot.rate[{i + 1}]"


def _torque_name(i):
    return f"dashpot.torque[{i + 1}]"


def _damper_component():
    inputs = (
        Variable("angle", "input", "rad", "Wheel-arm angle theta relative to the hull, at the "
                 "damper rotor", 0.0, "deg"),
        Variable("angle_rate", "input", "rad/s", "Arm angular rate d(theta)/dt, held over each "
                 "communication step; positive in bump (compression)", 0.0, "deg/s"),
    )
    outputs = (
        Variable("torque", "output", "N.m", "Torque applied to the damper to produce the arm "
                 "motion: the gas-spring torque Tg (Eq. A5-16); steady rate gives Table A6-1"),
        Variable("gas_deflection", "output", "rad", "Gas-spring deflection xd = theta - "
                 "theta_r, bounded by |xd| < C2", display_unit="deg"),
        Variable("rotor_rate", "output", "rad/s", "Rate omega_r of the rotor node between gas "
                 "spring and dashpot", display_unit="deg/s"),
        Variable("dashpot_torque", "output", "N.m", "Dashpot torque Td(omega_r) from the "
                 "Table A6-1 curve (Appendix 6)"),
        Variable("stiffness", "output", "N.m/rad", "Instantaneous tangent stiffness "
                 "d torque/d theta, the gas-spring stiffness (rotor inertia holds theta_r)",
                 display_unit="N.m/deg"),
    )
    parameters = [
        Variable("C1", "parameter", "N.m", "Gas-spring torque constant C1 (Eq. A5-16; the "
                 "thesis prints 0.8e6 in N.mm, section 13.0)", 800.0, constraint=POSITIVE),
        Variable("C2", "parameter", "rad", "Gas-spring deflection limit C2 (Eq. A5-16, "
                 "section 13.0: 0.03 rad)", 0.03, "deg", POSITIVE),
        Variable("I", "parameter", "kg.m2", "Rotor inertia at the node between gas spring "
                 "and dashpot (section 12.6: 0.118 kg.m2)", 0.118, constraint=POSITIVE),
    ]
    for i, (rate, torque) in enumerate(zip(DAMPER_TABLE_RATES, DAMPER_TABLE_TORQUES)):
        parameters.append(Variable(_rate_name(i), "parameter", "rad/s", f"Dashpot curve point "
                                   f"{i + 1}: angular rate (Table A6-1)", rate, "deg/s"))
        parameters.append(Variable(_torque_name(i), "parameter", "N.m", f"Dashpot curve point "
                                   f"{i + 1}: torque, smoothed column (Table A6-1)", torque))
    states = (
        Variable("state.z", "local", "1", "Gas-spring coordinate z, xd = C2 tanh(z) (runtime/"
                 "damper.py)"),
        Variable("state.omega_r", "local", "rad/s", "Rate omega_r of the rotor node",
                 display_unit="deg/s"),
    )
    equations = damper_equations("C1", "C2", "I", [_rate_name(i) for i in range(TABLE_SIZE)],
                                 [_torque_name(i) for i in range(TABLE_SIZE)])

    return ComponentDefinition(
        "RotaryDamper",
        "Warrior rotary suspension damper at the wheel-arm pivot: Table A6-1 dashpot "
        "(laminar, turbulent, blow-off) in series with an isothermal entrapped-gas spring, "
        "rotor inertia between them (thesis chapters 9-14, Appendices 5 and 6).",
        inputs, outputs, parameters, states, equations,
        measured_ranges={"angle": (-math.pi / 4, math.pi / 4, "rotation about +/-45 deg, section 9.1"),
                         "angle_rate": (-14.0, 14.0, "Table A6-1 spans +/-14 rad/s")})


ROTARY_DAMPER = _damper_component()

COMPONENTS = {c.name: c for c in (ROAD_WHEEL_TYRE, TRACK_BUSH_RADIAL, TRACK_BUSH_TORSION,
                                  ROTARY_DAMPER)}


def structures_of(name):
    """The model structures a component comes in (the damper has one, its own)."""
    if name not in RUBBER_PARTS:
        return (FINAL.name,)
    return tuple(s for s in STRUCTURES if s in RUBBER_PARTS[name]["elements"])


_DEFINITIONS = {(c.name, FINAL.name): c for c in COMPONENTS.values()}


def component_definition(name, structure=FINAL.name):
    """The ComponentDefinition of a component in one of the thesis's model structures
    (STRUCTURES); "final" is the shipped model, COMPONENTS[name]. KeyError names what
    exists if the pair does not."""
    if (name, structure) not in _DEFINITIONS:
        if name not in COMPONENTS:
            raise KeyError(f"no component {name!r}; components: {', '.join(sorted(COMPONENTS))}")
        if structure not in structures_of(name):
            raise KeyError(f"{name} has no {structure!r} structure; it has: "
                           f"{', '.join(structures_of(name))}")
        _DEFINITIONS[name, structure] = _rubber_definition(name, STRUCTURES[structure])
    return _DEFINITIONS[name, structure]
