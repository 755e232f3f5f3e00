"""A part's parameter values: the thesis's, with those of a PARAMS.json (FMU parameter
names to SI values, as ``fmu-components fit`` writes them) in their place, checked as the
FMUs check them."""

import json

from ..runtime.catalog import component_definition


class ParameterError(ValueError):
    """Parameter values that cannot be used: said in one line with what to correct."""


def parameter_set(component, structure="final", params=None):
    """The full parameter set: the thesis values, with those of `params` (a dict, or a
    JSON file name, of FMU parameter names -> SI values) in their place."""
    definition = component_definition(component, structure)
    values = definition.default_parameters()
    if params is None:
        return values
    if not isinstance(params, dict):
        params = read_parameters(params)
    unknown = sorted(set(params) - set(values))
    if unknown:
        raise ParameterError(f"{component} ({structure}) has no parameter "
                             f"{', '.join(map(repr, unknown))}; its parameters are: "
                             f"{', '.join(values)}")
    for name, value in params.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ParameterError(f"parameter {name!r} = {value!r} must be a number (SI units)")
        values[name] = float(value)
    problem = definition.check_parameters(values)
    if problem:
        raise ParameterError(f"{problem}; correct it in the parameters file")
    return values


def read_parameters(path):
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
