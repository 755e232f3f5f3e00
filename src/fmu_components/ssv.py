"""Parameter sets as SSP parameter-value files (``.ssv``, SSP 1.0's
SystemStructureParameterValues), the format fmpy, libcosim, OMSimulator and Dymola read.

    write_ssv("bush.ssv", "TrackBushRadial thesis", [("k1", 6e7, "N/m", "...")],
              {"N/m": {"kg": 1, "s": -2}})
    values = si_values("bush.ssv", {"k1": "N/m"}, {"N/m": {"kg": 1, "s": -2}})

Every value a file gives is a Real with a unit that the file's ``Units`` defines (SSP 1.0
section 5: a ``unit`` attribute references a unit definition of the enclosing file). On
reading, a value in another unit of the same dimension (N/mm for N/m, given with its
``BaseUnit`` factor) is converted to SI; a name the part does not have, a unit of another
dimension, an undefined unit or a value that is no finite number is refused, naming the
file, the parameter and the value. Whether a value is in the part's range is the part's to
say (its definition, or the FMU itself).

Standard library only: the host-side coupling library reads these files too.
"""

import math
import os
from xml.etree import ElementTree

SSV = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
SSC = "http://ssp-standard.org/SSP1/SystemStructureCommon"
BASE_UNITS = ("kg", "m", "s", "A", "K", "mol", "cd", "rad")


class SsvError(ValueError):
    """A parameter file that cannot be used: said in one line, naming the file."""


def ssv_text(set_name, parameters, unit_exponents, generation_tool="fmu-components"):
    """The XML of a parameter set: `parameters` as (name, SI value, SI unit, description or
    None); `unit_exponents` maps each unit used to its SI base-unit exponents."""
    ElementTree.register_namespace("ssv", SSV)
    ElementTree.register_namespace("ssc", SSC)
    root = ElementTree.Element(f"{{{SSV}}}ParameterSet",
                               {"version": "1.0", "name": set_name,
                                "generationTool": generation_tool})
    listed = ElementTree.SubElement(root, f"{{{SSV}}}Parameters")
    used = []
    for name, value, unit, description in parameters:
        attributes = {"name": name}
        if description:
            attributes["description"] = description
        parameter = ElementTree.SubElement(listed, f"{{{SSV}}}Parameter", attributes)
        real = {"value": repr(float(value))}  # repr: the double back bit for bit
        if unit:
            real["unit"] = unit
            if unit not in used:
                used.append(unit)
        ElementTree.SubElement(parameter, f"{{{SSV}}}Real", real)
    if used:
        units = ElementTree.SubElement(root, f"{{{SSV}}}Units")
        for unit in used:
            definition = ElementTree.SubElement(units, f"{{{SSC}}}Unit", {"name": unit})
            ElementTree.SubElement(definition, f"{{{SSC}}}BaseUnit",
                                   {k: str(e) for k, e in unit_exponents[unit].items() if e})
    ElementTree.indent(root)
    return ElementTree.tostring(root, encoding="unicode", xml_declaration=True) + "\n"


def write_ssv(path, set_name, parameters, unit_exponents):
    """Write ssv_text(...) to `path`, whole or not at all (a temporary file renamed)."""
    temporary = f"{path}.part"
    with open(temporary, "w", encoding="utf-8") as file:
        file.write(ssv_text(set_name, parameters, unit_exponents))
    os.replace(temporary, path)


def read_ssv(path):
    """(set name, [(name, value, unit or None)], {unit: (exponents, factor, offset)}) of an
    .ssv file, as written; only its Real parameters are taken (a part's are all Real)."""
    try:
        root = ElementTree.parse(path).getroot()
    except OSError as error:
        raise SsvError(f"cannot read the parameter file {path}: {error.strerror}") from None
    except ElementTree.ParseError as error:
        raise SsvError(f"{path} is not XML ({error}); an .ssv file is SSP 1.0 "
                       f"SystemStructureParameterValues") from None
    if root.tag != f"{{{SSV}}}ParameterSet":
        raise SsvError(f"{path}: its root is <{root.tag}>, not an SSP 1.0 "
                       f"<ssv:ParameterSet> ({SSV})")
    units = {}
    for unit in root.iterfind(f"{{{SSV}}}Units/{{{SSC}}}Unit"):
        base = unit.find(f"{{{SSC}}}BaseUnit")
        attributes = base.attrib if base is not None else {}
        try:
            exponents = {k: int(attributes.get(k, 0)) for k in BASE_UNITS
                         if int(attributes.get(k, 0))}
            scale = (float(attributes.get("factor", 1.0)), float(attributes.get("offset", 0.0)))
        except ValueError:
            raise SsvError(f"{path}: unit {unit.get('name')!r} has a BaseUnit that is not "
                           f"numbers: {dict(attributes)}") from None
        units[unit.get("name")] = (exponents, *scale)
    parameters = []
    for parameter in root.iterfind(f"{{{SSV}}}Parameters/{{{SSV}}}Parameter"):
        name = parameter.get("name")
        real = parameter.find(f"{{{SSV}}}Real")
        if real is None:
            kinds = [child.tag.rsplit("}", 1)[-1] for child in parameter]
            raise SsvError(f"{path}: parameter {name!r} is {'/'.join(kinds) or 'empty'}; "
                           f"a part's parameters are Real values")
        text = real.get("value")
        try:
            value = float(text)
        except (TypeError, ValueError):
            raise SsvError(f"{path}: parameter {name} = {text!r} is not a number") from None
        parameters.append((name, value, real.get("unit")))
    return root.get("name"), parameters, units


def si_values(path, si_units, unit_exponents):
    """{name: SI value} of an .ssv file for a part whose parameters have the SI units
    `si_units` ({name: unit}); `unit_exponents` gives those units' base-unit exponents."""
    _, parameters, units = read_ssv(path)
    values = {}
    for name, value, unit in parameters:
        if name not in si_units:
            raise SsvError(f"{path}: parameter {name!r} = {value!r} {unit or ''}: the part has "
                           f"no such parameter; its parameters are: {', '.join(si_units)}")
        if name in values:
            raise SsvError(f"{path}: parameter {name!r} is given twice")
        if not math.isfinite(value):
            raise SsvError(f"{path}: parameter {name} = {value!r} is not a finite number")
        values[name] = _in_si(path, name, value, unit, si_units[name], units, unit_exponents)
    return values


def _in_si(path, name, value, unit, si_unit, units, unit_exponents):
    """A value given in `unit` as a value in the parameter's SI unit."""
    if unit is None or unit == si_unit and unit not in units:
        return value  # no unit: the variable's own (SSP 1.0); or its SI unit, named so
    if unit not in units:
        raise SsvError(f"{path}: parameter {name} = {value!r} {unit}: the file defines no "
                       f"unit {unit!r} in its <Units>; give the value in {si_unit}")
    exponents, factor, offset = units[unit]
    if exponents != {k: e for k, e in unit_exponents[si_unit].items() if e}:
        raise SsvError(f"{path}: parameter {name} = {value!r} {unit} is not in a unit of "
                       f"{si_unit}'s kind; give it in {si_unit}")
    converted = factor * value + offset
    if not math.isfinite(converted):
        raise SsvError(f"{path}: parameter {name} = {value!r} {unit} is no finite value in "
                       f"{si_unit}")
    return converted
