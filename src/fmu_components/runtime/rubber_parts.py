"""The thesis's rubber parts as data: the road-wheel tyre and the track bush (radial and
torsion), their element values per model structure with where the thesis prints them, and
how a part's data becomes its ComponentDefinition over the N-branch rubber model
(rubber.py; spec section 2).

Values are SI. Appendix 4b prints its rubber tables in ADAMS mm-N-s units (deg for the
torsion bush), so k is converted per m (per rad) and xi per m/s (rad/s); the check is the
time constant tau = c/(k*xi) = 100, 0.1 and 1.0 s of section 6.4 (spec section 1).
"""

import math

from .definition import NON_NEGATIVE, POSITIVE, ComponentDefinition, Structure, Variable
from .expressions import Symbol
from .rubber import Branch, MaxwellElement, rubber_equations
from .units import MM, PER_DEG


# --- the thesis's model structures ---------------------------------------------------------

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


# --- the parts' values ---------------------------------------------------------------------

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


# --- a part's data as a ComponentDefinition -------------------------------------------------

def rubber_definition(name, structure):
    """The ComponentDefinition of rubber part `name` (a key of RUBBER_PARTS) in a Structure
    whose element values the thesis gives for it."""
    part = dict(RUBBER_PARTS[name])
    elements = part.pop("elements")[structure.name]
    return _rubber_component(name, part.pop("description"), structure=structure,
                             elements=elements, **part)


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
