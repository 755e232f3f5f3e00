"""The one modelDescription.xml writer, for both flavours of every component and both FMI
versions.

From the catalog (variables, units, display units, descriptions, thesis start values,
direct dependencies) and what the flavour is (its GUID, its model identifier, whether it
needs Python on the host, its C sources), so that both flavours and both versions declare
the same variables, value references, units and structure.
"""

from xml.dom import minidom
from xml.etree.ElementTree import Element, SubElement, tostring

from .. import __version__
from ..runtime.units import UNITS

TOOL = "fmu-components"  # the VendorAnnotations tool that says which component an FMU is

LOG_CATEGORIES = {
    "logStatusWarning": "Log messages with Warning status.",
    "logStatusDiscard": "Log messages with Discard status.",
    "logStatusError": "Log messages with Error status.",
    "logStatusFatal": "Log messages with Fatal status.",
    "logAll": "Log all messages.",
}


def _capabilities(native):
    """What the FMUs do, claimed in the modelDescription and nothing more: both interfaces
    and directional derivatives for the native flavour, co-simulation for the Python one."""
    common = {
        "needsExecutionTool": "false" if native else "true",  # Python 3 on the host
        "canBeInstantiatedOnlyOncePerProcess": "false",
        "canNotUseMemoryManagementFunctions": "true",
        "canGetAndSetFMUstate": "true",
        "canSerializeFMUstate": "true",
        "providesDirectionalDerivative": "true" if native else "false",
    }
    co_simulation = {
        **common,
        "canHandleVariableCommunicationStepSize": "true",
        "canInterpolateInputs": "false",
        "maxOutputDerivativeOrder": "0",
        "canRunAsynchronuously": "false",
    }
    model_exchange = {**common, "completedIntegratorStepNotNeeded": "true"}
    return co_simulation, model_exchange


def model_description(definition, *, guid, model_identifier, native, source_files=(),
                      nominals=()):
    """The modelDescription.xml text of one flavour of one component; `nominals`: of the
    continuous states, at the thesis parameters."""
    view = definition.equations.continuous
    root = _root(definition, "2.0", "guid", guid,
                 numberOfEventIndicators=str(len(view.event_indicators) if native else 0))
    co_simulation, model_exchange = _capabilities(native)
    interfaces = [("ModelExchange", model_exchange)] if native else []
    for tag, capabilities in interfaces + [("CoSimulation", co_simulation)]:
        element = SubElement(root, tag, {"modelIdentifier": model_identifier, **capabilities})
        if source_files:
            files = SubElement(element, "SourceFiles")
            for name in source_files:
                SubElement(files, "File", name=name)
    _common_elements(root, definition)
    _identity_annotation(SubElement(SubElement(root, "VendorAnnotations"), "Tool", name=TOOL),
                         definition)
    variables = SubElement(root, "ModelVariables")
    index = {v.name: i + 1 for i, v in enumerate(definition.variables)}
    nominal = dict(zip((v.name for v in definition.states), nominals))
    derivative_of = {d.name: index[s.name] for s, d in zip(definition.states,
                                                           definition.derivatives)}
    for vr, variable in enumerate(definition.variables):
        variables.append(_scalar_variable(variable, vr, nominal.get(variable.name),
                                          derivative_of.get(variable.name)))
    for switch in definition.switches:
        variables.append(_switch_variable(switch, definition.switch_reference(switch.name)))
    root.append(_model_structure(definition, index))
    return xml_text(root)


def _root(definition, version, token_name, token, **extra):
    """The fmiModelDescription element: what both versions say of the FMU, with the
    version, its GUID or instantiation token (`token_name`), and its own attributes."""
    return Element("fmiModelDescription", {
        "fmiVersion": version, "modelName": definition.name, token_name: token,
        "description": definition.description, "author": "fmu-components",
        "version": __version__, "license": "MIT",
        "generationTool": f"fmu-components {__version__}",
        "variableNamingConvention": "structured", **extra})


def xml_text(root):
    text = minidom.parseString(tostring(root, encoding="unicode")).toprettyxml(indent="  ")
    return text.replace('<?xml version="1.0" ?>', '<?xml version="1.0" encoding="UTF-8"?>', 1)


def _common_elements(root, definition):
    """Units, log categories and default experiment: the same in both FMI versions."""
    root.append(_unit_definitions(definition))
    categories = SubElement(root, "LogCategories")
    for name, description in LOG_CATEGORIES.items():
        SubElement(categories, "Category", name=name, description=description)
    SubElement(root, "DefaultExperiment",
               {k: repr(float(v)) for k, v in definition.default_experiment.items()})


def _identity_annotation(parent, definition):
    """What the FMU is, for the project's tools (export/identity.py): whatever its name."""
    SubElement(parent, "Component", name=definition.component,
               structure=definition.structure_name)


def _variable_attributes(variable, vr):
    """Name, value reference, description, causality, variability and initial: the same in
    both FMI versions."""
    causality = variable.causality
    attributes = {"name": variable.name, "valueReference": str(vr),
                  "description": variable.description, "causality": causality,
                  "variability": "fixed" if causality == "parameter" else "continuous"}
    if causality == "parameter":
        attributes["initial"] = "exact"
    elif causality == "local":  # states and derivatives: from the inputs at initialization
        attributes["initial"] = "calculated"
    return attributes


def _real_attributes(variable, nominal, derivative_of):
    real = {"unit": variable.unit}
    if variable.display_unit:
        real["displayUnit"] = variable.display_unit
    if variable.start is not None:
        real["start"] = repr(float(variable.start))  # repr round-trips to the last bit
    if nominal is not None:
        real["nominal"] = repr(float(nominal))
    if derivative_of is not None:
        real["derivative"] = str(derivative_of)
    return real


EVENT_INDICATOR = "contact_indicator"  # FMI 3 declares the contact's event indicator


def fmi3_references(definition):
    """The Float64 variables FMI 3.0 declares and FMI 2.0 does not, {name: value reference},
    after every variable and Boolean parameter: a contact's event indicator, and the
    independent variable time. The C runtime takes these numbers from model_config.h
    (export/cgen.py) and answers them in FMI 3.0 only."""
    first = len(definition.variables) + len(definition.switches)
    references = {}
    if definition.equations.continuous.event_indicators:
        references[EVENT_INDICATOR] = first
    references["time"] = first + 1
    return references


def model_description_fmi3(definition, *, guid, model_identifier, source_files=(),
                           nominals=()):
    """The FMI 3.0 modelDescription.xml of a native FMU: the same variables, value
    references, units and structure as its FMI 2.0 one, and what FMI 3.0 adds (the outputs'
    first time derivatives, adjoint derivatives, the event indicator as a variable,
    intermediate update and early return; event mode in Co-Simulation for a contact)."""
    view = definition.equations.continuous
    root = _root(definition, "3.0", "instantiationToken", guid)
    common = {"modelIdentifier": model_identifier, "needsExecutionTool": "false",
              "canBeInstantiatedOnlyOncePerProcess": "false", "canGetAndSetFMUState": "true",
              "canSerializeFMUState": "true", "providesDirectionalDerivatives": "true",
              "providesAdjointDerivatives": "true"}
    SubElement(root, "ModelExchange", {**common, "needsCompletedIntegratorStep": "false"})
    SubElement(root, "CoSimulation", {
        **common, "canHandleVariableCommunicationStepSize": "true",
        "maxOutputDerivativeOrder": "1",
        # a contact's step can end where the contact begins or ends (c/cosimulation.c)
        "hasEventMode": str(definition.equations.unilateral).lower(),
        "providesIntermediateUpdate": "true", "canReturnEarlyAfterIntermediateUpdate": "true",
        "mightReturnEarlyFromDoStep": "true", "providesEvaluateDiscreteStates": "false"})
    _common_elements(root, definition)
    variables = SubElement(root, "ModelVariables")
    extra = fmi3_references(definition)
    SubElement(variables, "Float64", {
        "name": "time", "valueReference": str(extra["time"]),
        "causality": "independent", "variability": "continuous",
        "description": "Simulation time"})
    nominal = dict(zip((v.name for v in definition.states), nominals))
    references = {v.name: vr for vr, v in enumerate(definition.variables)}
    derivative_of = {d.name: references[s.name] for s, d in zip(definition.states,
                                                                definition.derivatives)}
    for vr, variable in enumerate(definition.variables):
        node = SubElement(variables, "Float64", _variable_attributes(variable, vr))
        node.attrib.update(_real_attributes(variable, nominal.get(variable.name),
                                            derivative_of.get(variable.name)))
        if variable.causality in ("input", "output"):  # read and set inside a step too
            node.set("intermediateUpdate", "true")
    for switch in definition.switches:
        SubElement(variables, "Boolean", {
            "name": switch.name, "valueReference": str(definition.switch_reference(switch.name)),
            "description": switch.description, "causality": "parameter",
            "variability": "fixed", "initial": "exact",
            "start": "true" if switch.start else "false"})
    indicators = []
    if EVENT_INDICATOR in extra:
        vr = extra[EVENT_INDICATOR]
        x = definition.inputs[0]
        SubElement(variables, "Float64", {
            "name": EVENT_INDICATOR, "valueReference": str(vr), "causality": "local",
            "variability": "continuous", "initial": "calculated",
            "description": f"The contact's event indicator: {x.name} in mm (contact while "
                           f"positive)"})
        indicators.append(vr)
    structure = definition.structure()
    node = SubElement(root, "ModelStructure")
    for tag, group in (("Output", definition.outputs),
                       ("ContinuousStateDerivative", definition.derivatives)):
        for variable in group:
            read = sorted(references[name] for name in structure[variable.name])
            SubElement(node, tag, valueReference=str(references[variable.name]),
                       dependencies=" ".join(map(str, read)),
                       dependenciesKind=" ".join(["dependent"] * len(read)))
    unknowns = list(definition.outputs) + list(definition.states) + list(definition.derivatives)
    for vr in sorted(references[v.name] for v in unknowns):
        SubElement(node, "InitialUnknown", valueReference=str(vr))
    for vr in indicators:
        SubElement(node, "EventIndicator", valueReference=str(vr),
                   dependencies=str(references[definition.inputs[0].name]),
                   dependenciesKind="dependent")
    _identity_annotation(SubElement(SubElement(root, "Annotations"), "Annotation", type=TOOL),
                         definition)
    return xml_text(root)


def _scalar_variable(variable, vr, nominal, derivative_of):
    node = Element("ScalarVariable", _variable_attributes(variable, vr))
    SubElement(node, "Real", _real_attributes(variable, nominal, derivative_of))
    return node


def _switch_variable(switch, vr):
    node = Element("ScalarVariable", {
        "name": switch.name, "valueReference": str(vr), "description": switch.description,
        "causality": "parameter", "variability": "fixed", "initial": "exact"})
    SubElement(node, "Boolean", start="true" if switch.start else "false")
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


def _model_structure(definition, index):
    """Outputs and derivatives, each with the inputs and states its equations read
    (ComponentDefinition.structure), and the initial unknowns (depending on all knowns, so
    no dependency list is given)."""
    structure = definition.structure()
    node = Element("ModelStructure")
    for tag, variables in (("Outputs", definition.outputs),
                           ("Derivatives", definition.derivatives)):
        group = SubElement(node, tag)
        for variable in variables:
            read = sorted(index[name] for name in structure[variable.name])
            SubElement(group, "Unknown", index=str(index[variable.name]),
                       dependencies=" ".join(map(str, read)),
                       dependenciesKind=" ".join(["dependent"] * len(read)))
    initial = SubElement(node, "InitialUnknowns")
    unknowns = list(definition.outputs) + list(definition.states) + list(definition.derivatives)
    for i in sorted(index[v.name] for v in unknowns):
        SubElement(initial, "Unknown", index=str(i))
    return node
