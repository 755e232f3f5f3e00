"""The one modelDescription.xml writer, for both flavours of every component.

From the catalog (variables, units, display units, descriptions, thesis start values,
direct dependencies) and what the flavour is (its GUID, its model identifier, whether it
needs Python on the host, its C sources), so that both flavours declare the same
variables, value references, units and structure.
"""

from xml.dom import minidom
from xml.etree.ElementTree import Element, SubElement, tostring

from . import __version__
from .runtime.units import UNITS

LOG_CATEGORIES = {
    "logStatusWarning": "Log messages with fmi2Warning status.",
    "logStatusDiscard": "Log messages with fmi2Discard status.",
    "logStatusError": "Log messages with fmi2Error status.",
    "logStatusFatal": "Log messages with fmi2Fatal status.",
    "logAll": "Log all messages.",
}


def _co_simulation_capabilities(needs_python):
    """What the FMUs do, claimed in the modelDescription and nothing more."""
    return {
        "needsExecutionTool": "true" if needs_python else "false",
        "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "false",
        "maxOutputDerivativeOrder": "0",
        "canRunAsynchronuously": "false",
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "false",
    }


def model_description(definition, *, guid, model_identifier, needs_python, source_files=()):
    """The modelDescription.xml text of one flavour of one component."""
    root = Element("fmiModelDescription", {
        "fmiVersion": "2.0", "modelName": definition.name, "guid": guid,
        "description": definition.description, "author": "fmu-components",
        "version": __version__, "license": "MIT",
        "generationTool": f"fmu-components {__version__}",
        "variableNamingConvention": "structured", "numberOfEventIndicators": "0"})
    co_simulation = SubElement(root, "CoSimulation", {
        "modelIdentifier": model_identifier, **_co_simulation_capabilities(needs_python)})
    if source_files:
        files = SubElement(co_simulation, "SourceFiles")
        for name in source_files:
            SubElement(files, "File", name=name)
    root.append(_unit_definitions(definition))
    categories = SubElement(root, "LogCategories")
    for name, description in LOG_CATEGORIES.items():
        SubElement(categories, "Category", name=name, description=description)
    SubElement(root, "DefaultExperiment",
               {k: repr(float(v)) for k, v in definition.default_experiment.items()})
    variables = SubElement(root, "ModelVariables")
    for vr, variable in enumerate(definition.variables):
        variables.append(_scalar_variable(variable, vr))
    root.append(_model_structure(definition))
    text = minidom.parseString(tostring(root, encoding="unicode")).toprettyxml(indent="  ")
    return text.replace('<?xml version="1.0" ?>', '<?xml version="1.0" encoding="UTF-8"?>', 1)


def _scalar_variable(variable, vr):
    causality = variable.causality
    attributes = {"name": variable.name, "valueReference": str(vr),
                  "description": variable.description, "causality": causality,
                  "variability": "fixed" if causality == "parameter" else "continuous"}
    if causality == "parameter":
        attributes["initial"] = "exact"
    node = Element("ScalarVariable", attributes)
    real = {"unit": variable.unit}
    if variable.display_unit:
        real["displayUnit"] = variable.display_unit
    if variable.start is not None:
        real["start"] = repr(float(variable.start))  # repr round-trips to the last bit
    SubElement(node, "Real", real)
    return node


def _unit_definitions(definition):
    node = Element("UnitDefinitions")
    for name in sorted({v.unit for v in definition.variables}):
        exponents, display_units = UNITS[name]
        unit = SubElement(node, "Unit", name=name)
        SubElement(unit, "BaseUnit", {k: str(e) for k, e in exponents.items()})
        for display, factor in display_units:
            SubElement(unit, "DisplayUnit", name=display, factor=repr(factor))
    return node


def _model_structure(definition):
    """Outputs, each with its direct dependence on the deflection input, and the initial
    unknowns (depending on all knowns, so no dependency list is given)."""
    node = Element("ModelStructure")
    outputs = SubElement(node, "Outputs")
    first_output = len(definition.inputs)
    deflection = "1"  # index of the first variable, the deflection input
    for i, output in enumerate(definition.outputs):
        direct = output.name in definition.direct_outputs
        SubElement(outputs, "Unknown", index=str(first_output + i + 1),
                   dependencies=deflection if direct else "",
                   dependenciesKind="dependent" if direct else "")
    initial = SubElement(node, "InitialUnknowns")
    for i in range(len(definition.outputs)):
        SubElement(initial, "Unknown", index=str(first_output + i + 1))
    return node
