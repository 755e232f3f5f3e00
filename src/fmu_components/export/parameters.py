"""A part's parameter values: a base set (the thesis's, or those an FMU carries) with those
of a parameters file (PARAMS.json, FMU parameter names to SI values, as ``fmu-components
fit`` writes them, or an SSP parameter set, PARAMS.ssv: ssv.py) or of NAME=VALUE settings
in their place, checked as the FMUs check them.

A value that makes sense but lies far from anything the thesis measured or used (30 times
its value or more, either way) is most often a unit slip: ``parameter_set`` hands a
warning that names the likely unit (N/mm typed as N/m, deg as rad) to its ``warn``.
"""

import json
import math

from ..runtime.catalog import component_definition
from ..runtime.units import UNITS
from ..ssv import SsvError, si_values, write_ssv

SLIP_FACTOR = 30.0  # this far from the thesis value, either way, is worth a warning (deg: 57)


class ParameterError(ValueError):
    """Parameter values that cannot be used: said in one line with what to correct."""


def parameter_set(component, structure="final", params=None, base=None, warn=None):
    """The full parameter set: `base` (default: the thesis values), with those of `params`
    (a dict of FMU parameter names -> SI values, or a .json or .ssv file of them) in their place.
    warn(message) hears of each given value that looks like a unit slip."""
    definition = component_definition(component, structure)
    values = dict(base or definition.default_parameters())
    if params is None:
        return values
    source = ""  # a file's values are refused naming the file
    if not isinstance(params, dict):
        source = f"{params}: "
        params = read_parameters(params, definition)
    unknown = sorted(set(params) - set(values))
    if unknown:
        raise ParameterError(f"{source}{component} ({structure}) has no parameter "
                             f"{', '.join(map(repr, unknown))}; its parameters are: "
                             f"{', '.join(values)}")
    for name, value in params.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"{source}parameter {name!r} = {value!r} must be a number "
                                 f"(SI units)")
        values[name] = float(value)
    problem = definition.check_parameters(values)
    if problem:
        raise ParameterError(f"{source}{problem}; correct it in the parameters file")
    if warn is not None:
        for message in unit_slips(definition, params):
            warn(message)
    return values


def read_parameters(path, definition):
    """{name: SI value} of a parameters file: .ssv (SSP, units converted to SI and checked
    against the definition's) or JSON (SI values)."""
    if str(path).lower().endswith(".ssv"):
        try:
            return si_values(path, {p.name: p.unit for p in definition.parameters},
                             {unit: exponents for unit, (exponents, _) in UNITS.items()})
        except SsvError as error:
            raise ParameterError(str(error)) from None
    try:
        with open(path) as f:
            params = json.load(f)
    except OSError as error:
        raise ParameterError(f"cannot read the parameters file {path}: "
                             f"{error.strerror}") from None
    except json.JSONDecodeError as error:
        raise ParameterError(f"{path} is not JSON ({error.msg}, line {error.lineno}); write an "
                             f"object of parameter names to SI values") from None
    if not isinstance(params, dict):
        raise ParameterError(f"{path} must hold a JSON object of parameter names to SI values")
    return params


def write_parameter_set(path, definition, values, set_name):
    """An .ssv of `values` ({name: SI value}) for the part `definition` describes, each with
    its SI unit and description."""
    described = {p.name: p for p in definition.parameters}
    write_ssv(path, set_name,
              [(name, value, described[name].unit, described[name].description)
               for name, value in values.items()],
              {unit: exponents for unit, (exponents, _) in UNITS.items()})


def settings(texts):
    """{name: value} of NAME=VALUE settings (a command line's --param), each checked."""
    params = {}
    for text in texts or ():
        name, equals, value = text.partition("=")
        try:
            if not (equals and name.strip()):
                raise ValueError
            params[name.strip()] = float(value)
        except ValueError:
            raise ParameterError(f"--param {text!r}: write NAME=VALUE with the value in SI, "
                                 f"e.g. --param k1=6e7") from None
    return params


def unit_slips(definition, params):
    """A message for each value SLIP_FACTOR times or more off the thesis's, naming the unit it
    would be right in where one fits (within a factor of 10)."""
    thesis = definition.default_parameters()
    units = {p.name: p.unit for p in definition.parameters}
    messages = []
    for name, value in params.items():
        reference = thesis[name]
        if value == 0.0 or reference == 0.0 or math.copysign(1.0, value) != math.copysign(
                1.0, reference):
            continue  # no scale to compare with; a sign is no unit
        ratio = abs(value / reference)
        if 1.0 / SLIP_FACTOR < ratio < SLIP_FACTOR:
            continue
        unit = units[name]
        said = (f"parameter {name} = {value:g} {unit} is {ratio:.3g} times the thesis's "
                f"{reference:.6g} {unit}" if ratio >= 1.0 else
                f"parameter {name} = {value:g} {unit} is 1/{1.0 / ratio:.3g} of the thesis's "
                f"{reference:.6g} {unit}")
        likely = [(display, factor) for display, factor in UNITS[unit][1]
                  if abs(math.log10(abs(value / factor / reference))) < 1.0]
        if likely:
            display, factor = likely[0]
            said += (f": it looks like {display} (give {unit}: {value:g} {display} = "
                     f"{value / factor:.6g} {unit})")
        else:
            said += f": check its unit ({unit}, SI)"
        messages.append(said)
    return messages
