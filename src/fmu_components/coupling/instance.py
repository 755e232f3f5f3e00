"""One FMU instance as a host drives it, FMI 2.0 or 3.0, Co-Simulation or Model Exchange:
the one place in this package that calls an FMU's functions and turns their statuses into
the package's errors.

    fmu = open_fmu("fmus/fmi3/RoadWheelTyre.fmu")   # read and extracted once per process
    tyre = FmuInstance(fmu, "tyre")                  # instantiated (Co-Simulation)
    tyre.setup(parameters={"a0": 100.0})             # initialization mode (or "tyre.ssv")
    inputs, force = tyre.reals(fmu.inputs), tyre.reals(["force"])
    tyre.set(inputs, [3e-3, 0.0]); tyre.exit_initialization()
    tyre.set(inputs, [3.1e-3, 0.1]); tyre.do_step(0.0, 1e-3); tyre.get(force)
    tyre.close()                                     # terminated and freed

fmpy loads the FMU's library and declares its functions' C types; the calls a host makes
per step (values, doStep, states, derivatives) go to those functions directly, with the
value references and value arrays made once per set of variables (`reals`), because the
coupling makes them several times per host step. Where an FMI 2.0 and an FMI 3.0 call
differ (fmi2SetReal / fmi3SetFloat64 and their counts, doStep's results, initialization,
event iteration) the version is settled here, once.

Parameters come as {name: value} or as an SSP parameter set (an .ssv file, SSP 1.0), applied
at run time to the FMU as built: its names must be the FMU's Real parameters, its units of
the kinds the modelDescription declares for them (converted: N/mm for N/m), its values
within their declared min and max and accepted by the FMU; a refusal names the file, the
parameter and the value.
"""

import atexit
import math
import shutil
from ctypes import byref, c_bool, c_double, c_uint, c_void_p, pointer
from pathlib import Path
from xml.etree import ElementTree

from fmpy import calloc, extract, free, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import (FMU2Model, FMU2Slave, fmi2CallbackAllocateMemoryTYPE,
                       fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                       fmi2CallbackLoggerTYPE)
from fmpy.fmi3 import FMU3Model, FMU3Slave

from ..ssv import BASE_UNITS, SsvError, read_ssv, si_values
from .errors import CouplingError, StepDiscarded

# fmi2Status and fmi3Status: the same values from OK to Fatal (FMI 2.0.4 section 2.1.3,
# FMI 3.0.2 section 2.2.3). fmi2Pending answers only an asynchronous fmi2DoStep, which no
# instance here asks for.
OK, WARNING, DISCARD, ERROR, FATAL, PENDING = range(6)
STATUS_NAMES = ("OK", "Warning", "Discard", "Error", "Fatal", "Pending")

CO_SIMULATION, MODEL_EXCHANGE = "CoSimulation", "ModelExchange"  # fmpy's names
_FMPY_CLASSES = {("2.0", CO_SIMULATION): FMU2Slave, ("2.0", MODEL_EXCHANGE): FMU2Model,
                 ("3.0", CO_SIMULATION): FMU3Slave, ("3.0", MODEL_EXCHANGE): FMU3Model}
KEPT_MESSAGES = 5  # the newest messages an instance keeps, for its errors


def status_name(version, status):
    """'fmi2Error', 'fmi3Discard', ...: a status as the standard of `version` names it."""
    prefix = "fmi3" if version == "3.0" else "fmi2"
    return prefix + (STATUS_NAMES[status] if 0 <= status < len(STATUS_NAMES)
                     else f"Status({status})")


class FmuFile:
    """An FMU read once: its modelDescription, the folder it is extracted to, its FMI
    version ("2.0" or "3.0") and interfaces, its variables' value references by name."""

    def __init__(self, path, directory, description):
        self.path, self.directory, self.description = path, directory, description
        version = description.fmiVersion
        self.version = "3.0" if version.startswith("3.") else version
        if self.version not in ("2.0", "3.0"):
            raise ValueError(f"{path} is an FMI {version} FMU; FMI 2.0 and 3.0 are supported")
        self.fmi3 = self.version == "3.0"
        self.name = description.modelName
        variables = description.modelVariables
        self.value_references = {v.name: v.valueReference for v in variables}
        self.inputs = [v.name for v in variables if v.causality == "input"]
        self.outputs = [v.name for v in variables if v.causality == "output"]
        self.parameters = [v.name for v in variables if v.causality == "parameter"]
        # The continuous states and their derivatives, in the Model Exchange order.
        self.states = [d.variable.derivative.name for d in description.derivatives]
        self.derivatives = [d.variable.name for d in description.derivatives]
        self.event_indicators = description.numberOfEventIndicators
        self._root = None

    @property
    def co_simulation(self):
        return self.description.coSimulation is not None

    @property
    def model_exchange(self):
        return self.description.modelExchange is not None

    def interface(self, interface):
        """The modelDescription's CoSimulation or ModelExchange element (fmpy's)."""
        element = (self.description.coSimulation if interface == CO_SIMULATION else
                   self.description.modelExchange if interface == MODEL_EXCHANGE else None)
        if element is None:
            raise ValueError(f"{self.path} offers no {interface} interface "
                             f"({CO_SIMULATION} or {MODEL_EXCHANGE})")
        return element

    def provides_directional_derivatives(self, interface=CO_SIMULATION):
        """FMI 2.0's providesDirectionalDerivative, FMI 3.0's providesDirectionalDerivatives
        (fmpy reads only the former)."""
        element = self.interface(interface)
        if not self.fmi3:
            return bool(element.providesDirectionalDerivative)
        tag = self._xml().find(interface)
        return tag is not None and tag.get("providesDirectionalDerivatives") in ("true", "1")

    def _xml(self):
        if self._root is None:
            self._root = ElementTree.parse(Path(self.directory) / "modelDescription.xml")
        return self._root

    def references(self, names):
        """The value references of `names`, a ValueError naming the ones it does not have."""
        unknown = [n for n in names if n not in self.value_references]
        if unknown:
            raise ValueError(f"{self.path} has no variable {', '.join(map(repr, unknown))}; "
                             f"its variables are {', '.join(self.value_references)}")
        return [self.value_references[n] for n in names]


def parameter_values(fmu, parameters):
    """{name: value} to set: `parameters` as given (a dict, or None), or those of an .ssv
    file (a path) checked against the FmuFile `fmu`'s modelDescription and converted into
    the units it declares. Raises SsvError naming the file, the parameter and the value."""
    if parameters is None or isinstance(parameters, dict):
        return parameters
    path = str(parameters)
    description = fmu.description
    declared = {v.name: v for v in description.modelVariables
                if v.causality == "parameter" and v.type in ("Real", "Float64")}
    scales = {u.name: u.baseUnit for u in description.unitDefinitions if u.baseUnit}
    units = {name: _declared(v, "unit") or "1" for name, v in declared.items()}  # "1": none
    exponents = {unit: {k: getattr(base, k) for k in BASE_UNITS} for unit, base in
                 scales.items()}
    exponents["1"] = {}
    for unit in set(units.values()) - set(exponents):  # declared without a definition:
        exponents[unit] = {f"undefined unit {unit}": 1}  # taken only by its own name
    values = si_values(path, units, exponents)
    _, given, defined = read_ssv(path)
    given_units = {name: unit for name, _, unit in given}
    for name, value in values.items():
        base = scales.get(units[name])
        if given_units[name] in defined and base is not None:  # a base-unit value: the FMU's
            values[name] = value = (value - base.offset) / base.factor
        low, high = (_bound(declared[name], "min"), _bound(declared[name], "max"))
        if not low <= value <= high:
            raise SsvError(f"{path}: parameter {name} = {value!r} {units[name]} is outside "
                           f"the range the FMU declares, [{low!r}, {high!r}]")
    return values


def _declared(variable, attribute):
    """A variable's attribute, or its declared type's."""
    value = getattr(variable, attribute, None)
    if value is None and variable.declaredType is not None:
        value = getattr(variable.declaredType, attribute, None)
    return value


def _bound(variable, which):
    value = _declared(variable, which)
    if value is None:
        return -math.inf if which == "min" else math.inf
    return float(value)


_OPENED = {}  # (path, modified, size) -> FmuFile: one extraction per FMU file and process
_EXTRACTED = []


def open_fmu(path):
    """The FmuFile of an .fmu file (extracted once per process into a temporary folder,
    removed at exit) or of a folder an FMU is extracted to."""
    if isinstance(path, FmuFile):
        return path
    path = Path(path).resolve()
    if path.is_dir():
        if not (path / "modelDescription.xml").is_file():
            raise FileNotFoundError(f"{path} is a folder without modelDescription.xml: give "
                                    f"an .fmu file or the folder one is extracted to")
        return FmuFile(path, str(path), read_model_description(str(path)))
    if not path.is_file():
        raise FileNotFoundError(f"{path} does not exist")
    stat = path.stat()
    key = (path, stat.st_mtime_ns, stat.st_size)  # a file rebuilt in place is read again
    if key not in _OPENED:
        description = read_model_description(str(path))
        directory = extract(str(path))
        if not _EXTRACTED:
            atexit.register(_remove_extracted)
        _EXTRACTED.append(directory)
        _OPENED[key] = FmuFile(path, directory, description)
    return _OPENED[key]


def _remove_extracted():
    for directory in _EXTRACTED:
        shutil.rmtree(directory, ignore_errors=True)


class Reals:
    """Some Real (FMI 3.0: Float64) variables of an instance, with the value references
    and the value array one call takes, made once."""
    __slots__ = ("names", "count", "references", "values")

    def __init__(self, names, references):
        self.names = list(names)
        self.count = len(references)
        self.references = (c_uint * self.count)(*references)
        self.values = (c_double * self.count)()


class FmuInstance:
    """One instance of an FMU, from instantiation to free.

    `on_message(status, text)` hears every message the FMU logs (status: OK to Fatal
    above); the newest few are kept in `messages` whatever it does, and the errors quote
    the last. Every call whose status is Discard, Error or Fatal raises: StepDiscarded
    for a discarded doStep, CouplingError (naming the instance, `time` and the FMU's
    last message) for the rest. `time` is the time of the last step, or what the host
    sets it to, for those messages. `rollback=True` tells each doStep that the host may
    set a state saved before it (noSetFMUStatePriorToCurrentPoint false).
    """

    def __init__(self, fmu, name, interface=CO_SIMULATION, on_message=None, rollback=False):
        self.fmu = fmu = open_fmu(fmu)
        self.name = name
        self.interface = interface
        self.version, self.fmi3 = fmu.version, fmu.fmi3
        self.messages = []
        self.on_message = on_message
        self.time = 0.0
        self.parameters = None  # the values setup set
        self.initialized = False  # left initialization mode: terminate before free
        self.rollback = rollback
        element = fmu.interface(interface)
        self.fmpy = _FMPY_CLASSES[fmu.version, interface](
            guid=fmu.description.guid, unzipDirectory=fmu.directory,
            modelIdentifier=element.modelIdentifier, instanceName=name)
        try:
            if self.fmi3:
                self.fmpy.instantiate(logMessage=self._log3)
            else:
                # fmpy's `logger=` would be the logger of the whole process: each instance
                # gets callbacks of its own instead
                self._callbacks = fmi2CallbackFunctions()
                self._callbacks.logger = fmi2CallbackLoggerTYPE(self._log2)
                self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
                self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
                self.fmpy.instantiate(callbacks=self._callbacks)
        except Exception:  # fmpy says only "Failed to instantiate FMU"
            self.fmpy.freeLibrary()
            function = ("fmi3Instantiate" + interface if self.fmi3 else "fmi2Instantiate")
            raise CouplingError(name, 0.0, f"{function} returned no instance"
                                f"{self.said()}") from None
        self.component = self.fmpy.component
        self._functions = {}
        prefix = "fmi3" if self.fmi3 else "fmi2"
        self._set_reals = self._function("fmi3SetFloat64" if self.fmi3 else "fmi2SetReal")
        self._get_reals = self._function("fmi3GetFloat64" if self.fmi3 else "fmi2GetReal")
        if self.fmi3:
            self.set, self.get = self._set3, self._get3
        if interface == CO_SIMULATION:
            self._do_step = self._function(prefix + "DoStep")
            if self.fmi3:
                self._step_results = [c_bool(), c_bool(), c_bool(), c_double()]
                self._step_pointers = [pointer(r) for r in self._step_results]
                self.do_step = self._do_step3
        self._state_names = (("fmi3GetFMUState", "fmi3SetFMUState", "fmi3FreeFMUState")
                             if self.fmi3 else
                             ("fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate"))
        self._get_fmu_state, self._set_fmu_state, self._free_fmu_state = map(
            self._function, self._state_names)
        self._directional_name = prefix + "GetDirectionalDerivative"
        self._directional = self._function(self._directional_name)
        self._arrays = {}

    # --- calls and their statuses ---------------------------------------------------------

    def _function(self, name):
        """The FMU's function `name`, as fmpy declared it."""
        if name not in self._functions:
            self._functions[name] = getattr(self.fmpy.dll, name)
        return self._functions[name]

    def _log2(self, environment, instance, status, category, message):
        # FMI 2.0 messages are format strings: the project's FMUs double their '%'
        self._heard(status, message.decode("utf-8", "replace").replace("%%", "%"))

    def _log3(self, environment, status, category, message):
        self._heard(status, message.decode("utf-8", "replace"))

    def _heard(self, status, text):
        self.messages = self.messages[1 - KEPT_MESSAGES:] + [text]
        if self.on_message is not None:
            self.on_message(status, text)

    def said(self):
        return f": {self.messages[-1]}" if self.messages else ""

    def fail(self, status, function, step=None):
        """Raise the package's error for `function` having answered `status`."""
        if status == DISCARD and step is not None:
            raise StepDiscarded(self.name, self.time, step,
                                self.messages[-1] if self.messages else "no message")
        step = f" by {step:.6g} s" if step is not None else ""
        raise CouplingError(self.name, self.time, f"{function}{step} returned "
                            f"{status_name(self.version, status)}{self.said()}", status)

    def call(self, method, *args):
        """A call through fmpy's own wrapper (the calls made once, not per step): its
        FMICallException becomes the package's error like every other refusal."""
        try:
            return method(*args)
        except FMICallException as error:
            self.fail(error.status, error.function)

    # --- life cycle -----------------------------------------------------------------------

    def setup(self, parameters=None, tolerance=None, start_time=0.0):
        """Into initialization mode, the experiment set (the integrator's relative
        tolerance, default the FMU's own), with `parameters` set: {name: value} or an .ssv
        file's (parameter_values). The values set are kept in `parameters`."""
        self.time = start_time
        try:
            self.parameters = parameter_values(self.fmu, parameters)
        except SsvError as error:
            raise CouplingError(self.name, start_time, str(error)) from None
        if self.fmi3:
            self.call(self.fmpy.enterInitializationMode, tolerance, start_time)
        else:
            self.call(self.fmpy.setupExperiment, tolerance, start_time)
            self.call(self.fmpy.enterInitializationMode)
        if self.parameters:
            try:
                self.set(self.reals(list(self.parameters)), list(self.parameters.values()))
            except CouplingError as error:
                if self.parameters is parameters:
                    raise
                # the FMU refused a value of the file: say which file
                raise CouplingError(self.name, start_time, f"{parameters}: "
                                    f"{str(error).partition(': ')[2]}") from None

    def exit_initialization(self):
        """Out of initialization mode: Co-Simulation into stepping; Model Exchange through
        the event iteration into continuous-time mode."""
        self.call(self.fmpy.exitInitializationMode)
        self.initialized = True
        if self.interface == MODEL_EXCHANGE:
            self.update_discrete_states()
            self.enter_continuous_time_mode()

    def close(self):
        """Terminate (once initialized) and free the instance; its FMU states go with it."""
        try:
            if self.initialized:
                self.call(self.fmpy.terminate)
        finally:
            self.fmpy.freeInstance()

    # --- values ---------------------------------------------------------------------------

    def reals(self, names):
        """The Reals of the variables `names`, for set and get."""
        return Reals(names, self.fmu.references(names))

    def set(self, reals, values):
        reals.values[:] = values
        status = self._set_reals(self.component, reals.references, reals.count, reals.values)
        if status > WARNING:
            self.fail(status, "fmi2SetReal")

    def get(self, reals):
        """The values of `reals`, a list."""
        status = self._get_reals(self.component, reals.references, reals.count, reals.values)
        if status > WARNING:
            self.fail(status, "fmi2GetReal")
        return reals.values[:]

    def _set3(self, reals, values):
        reals.values[:] = values
        status = self._set_reals(self.component, reals.references, reals.count, reals.values,
                                 reals.count)
        if status > WARNING:
            self.fail(status, "fmi3SetFloat64")

    def _get3(self, reals):
        status = self._get_reals(self.component, reals.references, reals.count, reals.values,
                                 reals.count)
        if status > WARNING:
            self.fail(status, "fmi3GetFloat64")
        return reals.values[:]

    # --- Co-Simulation --------------------------------------------------------------------

    def do_step(self, time, step):
        """One communication step from `time`; StepDiscarded if the FMU could not finish
        it (its state is then where the FMU left it: restore a saved one)."""
        self.time = time
        status = self._do_step(self.component, time, step, not self.rollback)
        if status > WARNING:
            self.fail(status, "fmi2DoStep", step)
        self.time = time + step

    def _do_step3(self, time, step):
        self.time = time
        event, terminate, early, _ = self._step_results
        status = self._do_step(self.component, time, step, not self.rollback,
                               *self._step_pointers)
        if status > WARNING:
            self.fail(status, "fmi3DoStep", step)
        if terminate.value or early.value:
            # neither early return nor event mode was asked for at instantiation
            raise CouplingError(self.name, time, f"fmi3DoStep by {step:.6g} s returned "
                                f"{'early' if early.value else 'asking to terminate'}"
                                f"{self.said()}")
        self.time = time + step

    # --- FMU states -----------------------------------------------------------------------

    @staticmethod
    def new_state():
        """A place for an FMU state: NULL until get_state fills it."""
        return c_void_p()

    def get_state(self, state):
        """Save the FMU's state into `state` (reused if it holds one already)."""
        status = self._get_fmu_state(self.component, byref(state))
        if status > WARNING:
            self.fail(status, self._state_names[0])

    def set_state(self, state):
        status = self._set_fmu_state(self.component, state)
        if status > WARNING:
            self.fail(status, self._state_names[1])

    def free_state(self, state):
        """Free a saved state (it is NULL after)."""
        if state:
            status = self._free_fmu_state(self.component, byref(state))
            if status > WARNING:
                self.fail(status, self._state_names[2])

    def serialized_state(self):
        """The FMU's current state, serialized (bytes)."""
        state = self.new_state()
        self.get_state(state)
        try:
            return self.call(self.fmpy.serializeFMUState if self.fmi3 else
                             self.fmpy.serializeFMUstate, state)
        finally:
            self.free_state(state)

    # --- Model Exchange and derivatives ---------------------------------------------------

    def jacobian(self, unknowns, knowns):
        """A Jacobian of `unknowns` by `knowns` (names) to evaluate with `derivatives`."""
        return Jacobian(self.fmu.references(unknowns), self.fmu.references(knowns))

    def directional_derivative(self, jacobian, known):
        """d unknowns / d knowns[known] at the current point (seed 1): the Jacobian's
        column array, valid until its next call."""
        function = self._directional
        if self.fmi3:
            status = function(self.component, jacobian.unknowns, jacobian.rows,
                              jacobian.knowns[known], 1, jacobian.seed, 1,
                              jacobian.column, jacobian.rows)
        else:
            status = function(self.component, jacobian.unknowns, jacobian.rows,
                              jacobian.knowns[known], 1, jacobian.seed, jacobian.column)
        if status > WARNING:
            self.fail(status, self._directional_name)
        return jacobian.column

    def set_time(self, time):
        self.time = time
        self._vector_call("fmi2SetTime", "fmi3SetTime", time)

    def set_states(self, values):
        array = self._array("states", len(values))
        array[:] = values
        self._vector_call("fmi2SetContinuousStates", "fmi3SetContinuousStates", array,
                          len(values))

    def _read_vector(self, what, count, fmi2_name, fmi3_name):
        array = self._array(what, count)
        self._vector_call(fmi2_name, fmi3_name, array, count)
        return array[:count]

    def states(self):
        return self._read_vector("states", len(self.fmu.states), "fmi2GetContinuousStates",
                                 "fmi3GetContinuousStates")

    def derivatives(self):
        return self._read_vector("derivatives", len(self.fmu.states), "fmi2GetDerivatives",
                                 "fmi3GetContinuousStateDerivatives")

    def nominals(self):
        return self._read_vector("nominals", len(self.fmu.states),
                                 "fmi2GetNominalsOfContinuousStates",
                                 "fmi3GetNominalsOfContinuousStates")

    def event_indicators(self):
        return self._read_vector("indicators", self.fmu.event_indicators,
                                 "fmi2GetEventIndicators", "fmi3GetEventIndicators")

    def _array(self, what, count):
        if what not in self._arrays:
            self._arrays[what] = (c_double * max(count, 1))()
        return self._arrays[what]

    def _vector_call(self, fmi2_name, fmi3_name, *args):
        name = fmi3_name if self.fmi3 else fmi2_name
        status = self._function(name)(self.component, *args)
        if status > WARNING:
            self.fail(status, name)

    def enter_event_mode(self):
        self.call(self.fmpy.enterEventMode)

    def update_discrete_states(self):
        """The event iteration: update until the FMU needs no further update."""
        update = self.fmpy.updateDiscreteStates if self.fmi3 else self.fmpy.newDiscreteStates
        while True:
            again, terminate, *_ = self.call(update)
            if terminate:
                raise CouplingError(self.name, self.time, "the FMU asked to terminate in "
                                    f"its event iteration{self.said()}")
            if not again:
                return

    def enter_continuous_time_mode(self):
        self.call(self.fmpy.enterContinuousTimeMode)

    def event(self):
        """Event mode at the current point: the FMU updates its discrete states (a
        contact's mode), then continuous time again."""
        self.enter_event_mode()
        self.update_discrete_states()
        self.enter_continuous_time_mode()


class Jacobian:
    """The value references and arrays of directional derivatives, made once."""
    __slots__ = ("rows", "unknowns", "knowns", "seed", "column")

    def __init__(self, unknowns, knowns):
        self.rows = len(unknowns)
        self.unknowns = (c_uint * self.rows)(*unknowns)
        self.knowns = [(c_uint * 1)(k) for k in knowns]
        self.seed = (c_double * 1)(1.0)
        self.column = (c_double * self.rows)()

