"""The one FMU adapter: a pythonfmu slave configured by a ComponentDefinition.

This is the only module that knows pythonfmu. Each FMU's entry script subclasses
``ComponentSlave`` and names its definition from the catalog; everything else (variables,
units, parameter checks, the co-simulation step, state save and restore, the
modelDescription's units and structure) is done here once for all four components.

pythonfmu turns a Python exception into fmi2Fatal and then drops the instance, after which
the next call crashes the host. So no method here lets an exception escape: failures are
logged with fmi2Error status and reported through do_step's return value (fmi2Discard).
"""

import math
import sys
import traceback
from xml.etree.ElementTree import Element, SubElement

from pythonfmu import Fmi2Slave
from pythonfmu.default_experiment import DefaultExperiment
from pythonfmu.enums import Fmi2Causality, Fmi2Status, Fmi2Variability
from pythonfmu.variables import Real

from .cosim import CoSimulation
from .integrator import DEFAULT_RTOL
from .units import UNITS

# What the FMUs do, claimed in the modelDescription and nothing more.
CAPABILITIES = {
    "needsExecutionTool": "true",  # a Python 3 runtime must be present on the host
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

# pythonfmu 0.7.0 finds the slave class by executing the entry module's source against the
# module's namespace and then calls Py_DECREF on that namespace, a borrowed reference
# (PyModule_GetDict). Each instantiation so drops a reference it never took: after the
# first instance the entry module's namespace is freed and the next instantiation crashes
# the host. The entry module takes one extra reference when it is imported, and every
# instance gives back the one pythonfmu took (a list entry per instance).
_NAMESPACE_REFERENCES = []


def hold_module_namespace(namespace):
    _NAMESPACE_REFERENCES.append(namespace)


INSTANTIATED, INITIALIZATION, STEPPING, TERMINATED = (
    "instantiated", "initialization mode", "step mode", "terminated")


class _RealWithUnit(Real):
    """pythonfmu's Real with the unit and display unit it does not write itself, and a
    start value that round-trips (pythonfmu prints 16 digits, which can lose the last bit)."""

    def __init__(self, name, unit, display_unit, **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit
        self.display_unit = display_unit

    def to_xml(self):
        node = super().to_xml()
        real = node.find("Real")
        if self.start is not None:
            real.set("start", repr(float(self.start)))
        if self.unit:
            real.set("unit", self.unit)
        if self.display_unit:
            real.set("displayUnit", self.display_unit)
        return node


_CAUSALITY = {"input": (Fmi2Causality.input, Fmi2Variability.continuous),
              "output": (Fmi2Causality.output, Fmi2Variability.continuous),
              "parameter": (Fmi2Causality.parameter, Fmi2Variability.fixed)}


class ComponentSlave(Fmi2Slave):
    definition = None  # a catalog.ComponentDefinition, set by each FMU's entry class
    author = "fmu-components"
    license = "MIT"
    version = "0.1.0"

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        hold_module_namespace(vars(sys.modules[type(self).__module__]))
        definition = self.definition
        self.modelName = definition.name
        self.description = definition.description
        self.default_experiment = DefaultExperiment(
            start_time=definition.default_experiment["startTime"],
            stop_time=definition.default_experiment["stopTime"],
            step_size=definition.default_experiment["stepSize"],
            tolerance=definition.default_experiment["tolerance"])
        variables = definition.variables
        self._variables = variables
        self._values = [v.start if v.start is not None else 0.0 for v in variables]
        for vr, variable in enumerate(variables):
            causality, variability = _CAUSALITY[variable.causality]
            self.register_variable(_RealWithUnit(
                variable.name, variable.unit, variable.display_unit,
                causality=causality, variability=variability, description=variable.description,
                getter=lambda vr=vr: self._values[vr], setter=lambda value: None))
        self._deflection_vr, self._rate_vr = 0, 1
        self._output_vrs = range(2, 2 + len(definition.outputs))
        self._parameter_vrs = range(2 + len(definition.outputs), len(variables))
        self._mode = INSTANTIATED
        self._start_time = 0.0
        self._tolerance = DEFAULT_RTOL
        self._cosim = None
        self._failure = None  # a message that stops every further step
        self._outputs_stale = True
        self._warned = set()

    # --- logging ----------------------------------------------------------------------

    def _error(self, message):
        self.log(message, Fmi2Status.error)

    def _fail(self, message):
        """Record a failure that makes every later doStep return fmi2Discard."""
        self._failure = message
        self._error(message)

    def _unexpected(self, where, exc):
        detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        self._fail(f"internal error in {where}: {detail}")

    # --- FMI life cycle -----------------------------------------------------------------

    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        try:
            self._start_time = float(start_time)
            if tolerance is not None:
                if not (tolerance > 0.0 and math.isfinite(tolerance)):
                    self._fail(f"tolerance {tolerance!r} must be positive and finite")
                else:
                    self._tolerance = float(tolerance)
        except Exception as exc:
            self._unexpected("setupExperiment", exc)

    def enter_initialization_mode(self):
        self._mode = INITIALIZATION

    def exit_initialization_mode(self):
        try:
            problem = self.definition.check_parameters(self._parameter_values())
            if problem:
                self._fail(problem)
                return
            model = self.definition.build_model(self._parameter_values())
            values = self._values
            self._cosim = CoSimulation(model, self._tolerance, self._start_time,
                                       values[self._deflection_vr], values[self._rate_vr])
            self._mode = STEPPING
            self._outputs_stale = True
        except Exception as exc:
            self._unexpected("exitInitializationMode", exc)

    def terminate(self):
        self._mode = TERMINATED

    def do_step(self, current_time, step_size):
        try:
            if self._failure:
                self._error(f"doStep refused: {self._failure}")
                return False
            if self._mode != STEPPING:
                self._error(f"doStep called in {self._mode}; call exitInitializationMode first")
                return False
            problem = self._cosim.do_step(current_time, step_size)
            if problem:
                self._error(problem)
                return False
            values = self._values
            values[self._deflection_vr] = self._cosim.deflection
            self._outputs_stale = True
            return True
        except Exception as exc:
            self._unexpected("doStep", exc)
            return False

    # --- values ---------------------------------------------------------------------------

    def _parameter_values(self):
        return {self._variables[vr].name: self._values[vr] for vr in self._parameter_vrs}

    def _refresh_outputs(self):
        cosim = self._cosim
        if cosim is None:
            # Before initialization is complete the outputs are those of the relaxed
            # component at the current inputs, if the parameters make sense.
            values = self._parameter_values()
            if self.definition.check_parameters(values):
                outputs = [math.nan] * len(self._output_vrs)
            else:
                model = self.definition.build_model(values)
                x, v = self._values[self._deflection_vr], self._values[self._rate_vr]
                outputs = model.outputs(model.initial_state(x, v), x, v)
        else:
            outputs = cosim.outputs()
        for vr, value in zip(self._output_vrs, outputs):
            self._values[vr] = value
        self._outputs_stale = False

    def get_real(self, vrs):
        try:
            if self._outputs_stale:
                self._refresh_outputs()
            values = self._values
            return [values[vr] for vr in vrs]
        except Exception as exc:
            self._unexpected("getReal", exc)
            return [math.nan] * len(vrs)

    def set_real(self, vrs, values):
        try:
            inputs_changed = False
            for vr, value in zip(vrs, values):
                problem = self._check_settable(vr, value)
                if problem:
                    self._error(problem)
                    continue
                if vr in (self._deflection_vr, self._rate_vr):
                    inputs_changed = True
                    self._warn_if_unmeasured(vr, value)
                self._values[vr] = float(value)
            if inputs_changed:
                self._apply_inputs()
            self._outputs_stale = True
        except Exception as exc:
            self._unexpected("setReal", exc)

    def _check_settable(self, vr, value):
        if not 0 <= vr < len(self._variables):
            return f"setReal: no variable has value reference {vr}"
        variable = self._variables[vr]
        if variable.causality == "output":
            return f"setReal: {variable.name} is an output and cannot be set"
        if variable.causality == "parameter" and self._mode not in (INSTANTIATED, INITIALIZATION):
            return (f"setReal: parameter {variable.name} is fixed once initialization is "
                    f"complete; set it before fmi2ExitInitializationMode")
        if not math.isfinite(value):
            return f"setReal: {variable.name} = {value!r} is not a finite number; value ignored"
        return None

    def _apply_inputs(self):
        if self._cosim is None:
            return
        values = self._values
        problem = self._cosim.set_inputs(values[self._deflection_vr], values[self._rate_vr])
        if problem:
            # Keep the inputs the model accepted last: the state stays consistent.
            values[self._deflection_vr] = self._cosim.deflection
            values[self._rate_vr] = self._cosim.rate
            self._error(f"setReal: {problem}; value ignored")

    def _warn_if_unmeasured(self, vr, value):
        variable = self._variables[vr]
        limits = self.definition.measured_ranges.get(variable.name)
        if limits is None or variable.name in self._warned:
            return
        low, high, measured = limits
        if not low <= value <= high:
            self._warned.add(variable.name)
            self.log(f"{variable.name} = {value:.6g} {variable.unit} is outside the range the "
                     f"thesis measured ({measured}); the model extrapolates. Warned once per "
                     f"instance.", Fmi2Status.warning)

    # --- FMU state --------------------------------------------------------------------

    def _get_fmu_state(self):
        try:
            return {"values": self._values[:], "mode": self._mode,
                    "start_time": self._start_time, "tolerance": self._tolerance,
                    "failure": self._failure, "warned": sorted(self._warned),
                    "cosim": self._cosim.snapshot() if self._cosim is not None else None}
        except Exception as exc:
            self._unexpected("getFMUstate", exc)
            return {}

    def _set_fmu_state(self, state):
        try:
            self._values = list(state["values"])
            self._mode = state["mode"]
            self._start_time = state["start_time"]
            self._tolerance = state["tolerance"]
            self._failure = state["failure"]
            self._warned = set(state["warned"])
            snapshot = state["cosim"]
            if snapshot is None:
                self._cosim = None
            else:
                model = self.definition.build_model(self._parameter_values())
                self._cosim = CoSimulation(model, self._tolerance)
                self._cosim.restore(snapshot)
            self._outputs_stale = True
        except Exception as exc:
            self._unexpected("setFMUstate", exc)

    # --- modelDescription: what pythonfmu 0.7.0 leaves out ------------------------------

    def to_xml(self, model_options=None):
        root = super().to_xml(model_options or {})
        co_simulation = root.find("CoSimulation")
        for flag, value in CAPABILITIES.items():
            co_simulation.set(flag, value)
        position = list(root).index(co_simulation) + 1
        root.insert(position, self._unit_definitions())
        root.remove(root.find("ModelStructure"))
        root.append(self._model_structure())
        return root

    def _unit_definitions(self):
        node = Element("UnitDefinitions")
        for name in sorted({v.unit for v in self._variables}):
            exponents, display_units = UNITS[name]
            unit = SubElement(node, "Unit", name=name)
            SubElement(unit, "BaseUnit", {k: str(e) for k, e in exponents.items()})
            for display, factor in display_units:
                SubElement(unit, "DisplayUnit", name=display, factor=repr(factor))
        return node

    def _model_structure(self):
        """Outputs, each with its direct dependence on the inputs, and the initial
        unknowns (depending on all knowns, so no dependency list is given)."""
        node = Element("ModelStructure")
        outputs = SubElement(node, "Outputs")
        deflection_index = str(self._deflection_vr + 1)
        for vr in self._output_vrs:
            direct = self._variables[vr].name in self.definition.direct_outputs
            SubElement(outputs, "Unknown", index=str(vr + 1),
                       dependencies=deflection_index if direct else "",
                       dependenciesKind="dependent" if direct else "")
        initial = SubElement(node, "InitialUnknowns")
        for vr in self._output_vrs:
            SubElement(initial, "Unknown", index=str(vr + 1))
        return node
