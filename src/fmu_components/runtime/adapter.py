"""The one FMU adapter: a pythonfmu slave configured by a ComponentDefinition.

This is the only module that knows pythonfmu. Each FMU's entry script subclasses
``ComponentSlave`` and names its definition from the catalog; everything else (variables,
parameter checks, the FMI call sequence, the co-simulation step, state save and restore)
is done here once for all four components. The modelDescription is the project's own
(fmu_components.export.model_description), the same writer as the native flavour's.

How a call reports its outcome: the status it logs. pythonfmu itself can only return
fmi2OK, fmi2Discard (do_step returned False) or fmi2Fatal (a Python exception, after which
pythonfmu drops the instance and the next call crashes the host). The FMU's binary
(guard/fmi2_guard.c) returns the worst status logged during a call instead. So a method
here never raises: it logs fmi2Error (or fmi2Warning, fmi2Discard) with a message that
names the variable and the value, and leaves the instance as it was before the call.
"""

import ctypes
import functools
import json
import math
import sys
import traceback

# Inside an FMU this package is named for its build (fmu_components_<tag>) and carries its
# own copy of pythonfmu, so that neither another FMU's copy nor the host's is used (build.py,
# spec section 8); in the development tree pythonfmu is the installed one.
if __package__ == "fmu_components.runtime":
    import pythonfmu
else:
    from .. import pythonfmu

from .cosim import REFUSED, WARNED, CoSimulation, FiniteGuard, rate_floors
from .integrator import DEFAULT_RTOL, Rosenbrock

Fmi2Slave, Fmi2Status = pythonfmu.Fmi2Slave, pythonfmu.enums.Fmi2Status

# pythonfmu 0.7.0 finds the slave class by executing the entry module's source against the
# module's namespace and then calls Py_DECREF on that namespace, a borrowed reference
# (PyModule_GetDict). Each instantiation so drops a reference it never took: after the
# first instance the entry module's namespace is freed and the next instantiation crashes
# the host. The entry module takes one extra reference when it is imported, and every
# instance gives back the one pythonfmu took: a reference count, not a stored reference,
# so that nothing grows with the number of instances.
def hold_module_namespace(namespace):
    ctypes.pythonapi.Py_IncRef(ctypes.py_object(namespace))


# It also executes the entry module's source again for each instance, which makes a new
# class each time, and keeps a reference to the class it instantiates: the entry module
# binds its name to the first class made, so that no class is left behind per instance.
_CLASSES = {}


def first_class(cls):
    return _CLASSES.setdefault(f"{cls.__module__}.{cls.__qualname__}", cls)


def forget_import_path(resources):
    """pythonfmu puts the resources folder first on sys.path for every instance it makes, to
    import the entry module; the modules are imported when the slave is made, so the entry
    goes again rather than one more staying per instance."""
    if resources and sys.path and sys.path[0] == resources:
        del sys.path[0]


# FMI 2.0 co-simulation states (section 4.2.4) and the calls each allows (the masks the
# native runtime uses too, c/core.c).
INSTANTIATED = "Instantiated"
INITIALIZATION = "InitializationMode"
STEP_COMPLETE = "StepComplete"
STEP_FAILED = "StepFailed"
TERMINATED = "Terminated"
ANY_STATE = frozenset({INSTANTIATED, INITIALIZATION, STEP_COMPLETE, STEP_FAILED, TERMINATED})
READABLE = ANY_STATE - {INSTANTIATED}
SETTABLE = frozenset({INSTANTIATED, INITIALIZATION, STEP_COMPLETE})


def fmi_call(name, allowed, on_failure=None):
    """Check the call sequence, and turn any unexpected exception into a logged fmi2Error
    instead of pythonfmu's fatal path. `on_failure(self, *args)` is what the call returns
    when it is refused."""

    def decorate(method):
        @functools.wraps(method)
        def call(self, *args):
            if self._mode not in allowed:
                self._refuse_out_of_sequence(name, allowed)
                return on_failure(self, *args) if on_failure else None
            try:
                return method(self, *args)
            except Exception as exc:
                self._internal_error(name, exc)
                return on_failure(self, *args) if on_failure else None
        return call
    return decorate


@functools.lru_cache(maxsize=None)
def guard_log_function(resources):
    """The guard's fmu_guard_log (guard/fmi2_guard.c) in the FMU's own binary, or None (the
    adapter run without it): messages then go through pythonfmu's log queue."""
    import glob
    import os
    binaries = os.path.join(os.path.dirname(os.path.abspath(resources)), "binaries", "*", "*.so")
    for path in glob.glob(binaries):
        try:
            function = ctypes.CDLL(path).fmu_guard_log
        except (OSError, AttributeError):
            continue
        function.argtypes = (ctypes.c_int, ctypes.c_char_p, ctypes.c_char_p)
        function.restype = ctypes.c_int
        return function
    return None


def unsigned(vr):
    """A value reference as the host sent it: pythonfmu passes FMI's unsigned int as a
    signed one, so references from 2**31 up arrive negative."""
    return vr & 0xFFFFFFFF


def _nan_values(self, vrs):
    return [math.nan] * len(vrs)


# The catalog lists a component's variables inputs first: deflection, then its rate.
DEFLECTION_VR, RATE_VR = 0, 1


class ComponentSlave(Fmi2Slave):
    definition = None  # a catalog.ComponentDefinition, set by each FMU's entry class

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        hold_module_namespace(vars(sys.modules[type(self).__module__]))
        forget_import_path(self.resources)
        definition = self.definition
        variables = definition.variables
        self._variables = variables
        # Value references are catalog order. No variable is registered with pythonfmu: every
        # call that would read its registry is the adapter's own, and the modelDescription
        # is the project's (fmu_components.export.model_description). A slave then holds no
        # reference cycle, and goes as soon as pythonfmu lets go of it.
        self._values = [v.start if v.start is not None else 0.0 for v in variables]
        self._output_vrs = range(2, 2 + len(definition.outputs))
        self._parameter_vrs = range(self._output_vrs.stop,
                                    self._output_vrs.stop + len(definition.parameters))
        self._local_vrs = range(self._parameter_vrs.stop, len(variables))  # states, derivatives
        self._switch_vrs = range(len(variables), len(variables) + len(definition.switches))
        self._switches = [s.start for s in definition.switches]  # rate_from_deflection
        self._mode = INSTANTIATED
        self._start_time = 0.0
        self._tolerance = DEFAULT_RTOL
        self._cosim = None
        self._outputs_stale = True
        self._warned = set()
        self._arm_range_checks()

    # --- logging ----------------------------------------------------------------------

    def log(self, msg, status=Fmi2Status.ok, category=None, debug=None):
        send = guard_log_function(self.resources) if self.resources else None
        if category is None:
            category = f"logStatus{status.name.capitalize()}"
            if category not in self.log_categories:
                category = "logAll"
        if send is None or not send(int(status), category.encode(), str(msg).encode()):
            super().log(msg, status, category)

    def _error(self, message):
        self.log(message, Fmi2Status.error)

    def _refuse_out_of_sequence(self, name, allowed):
        self._error(f"{name} is not allowed in state {self._mode} (allowed in: "
                    f"{', '.join(sorted(allowed))}); call ignored")

    def _internal_error(self, name, exc):
        detail = "".join(traceback.format_exception_only(type(exc), exc)).strip()
        self._error(f"{name} failed inside the FMU ({detail}); call ignored")

    # --- FMI life cycle -----------------------------------------------------------------

    @fmi_call("fmi2SetupExperiment", {INSTANTIATED})
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        if not math.isfinite(start_time):
            self._error(f"fmi2SetupExperiment: startTime = {start_time!r} s is not finite; "
                        f"call ignored")
            return
        if tolerance is not None and not (tolerance > 0.0 and math.isfinite(tolerance)):
            self._error(f"fmi2SetupExperiment: tolerance = {tolerance!r} must be positive "
                        f"and finite; call ignored")
            return
        self._start_time = float(start_time)
        if tolerance is not None:
            self._tolerance = float(tolerance)

    @fmi_call("fmi2EnterInitializationMode", {INSTANTIATED})
    def enter_initialization_mode(self):
        self._mode = INITIALIZATION

    @fmi_call("fmi2ExitInitializationMode", {INITIALIZATION})
    def exit_initialization_mode(self):
        values = self._parameter_values()
        problem = self.definition.check_parameters(values)
        if problem:
            # Stay in initialization mode: the host may correct the parameter and retry.
            self._error(f"fmi2ExitInitializationMode: {problem}; still in initialization mode")
            return
        model = self.definition.build_model(values)
        deflection, rate = self._values[DEFLECTION_VR], self._values[RATE_VR]
        self._cosim = self._new_cosim(model, self._tolerance, self._start_time, deflection, rate)
        self._mode = STEP_COMPLETE
        self._outputs_stale = True

    def _new_cosim(self, model, *args):
        return CoSimulation(model, *args, rate_floors=rate_floors(self.definition.deflection_scale),
                            rate_from_deflection=self._switches[0],
                            guard=FiniteGuard(self.definition))

    @fmi_call("fmi2Terminate", {STEP_COMPLETE, STEP_FAILED})
    def terminate(self):
        self._mode = TERMINATED

    def do_step(self, current_time, step_size):
        # The hottest call: fmi_call's sequence check and exception guard, written inline.
        if self._mode != STEP_COMPLETE:
            self._refuse_out_of_sequence("fmi2DoStep", {STEP_COMPLETE})
            return False
        try:
            cosim = self._cosim
            outcome = cosim.do_step(current_time, step_size)
            if outcome is None:
                # The deflection has moved on with the step (see _current_inputs).
                self._outputs_stale = True
                return True
            kind, problem = outcome
            if kind == WARNED:
                self._outputs_stale = True
                self.log(rate_warning(self.definition, cosim.rate, problem), Fmi2Status.warning)
                return True
            if kind == REFUSED:
                self._error(f"fmi2DoStep: {problem}; step refused")
            else:
                # The step could not be completed and nothing changed: fmi2Discard, after
                # which the host restores a state or retries (FMI 2.0 section 4.2.3).
                self._mode = STEP_FAILED
                self.log(f"fmi2DoStep: {problem}", Fmi2Status.discard)
            return False
        except Exception as exc:
            self._internal_error("fmi2DoStep", exc)
            return False

    # --- values ---------------------------------------------------------------------------

    def _parameter_values(self, values=None):
        values = self._values if values is None else values
        return {self._variables[vr].name: values[vr] for vr in self._parameter_vrs}

    def _current_inputs(self):
        """[deflection, rate] now. Once initialized the co-simulation holds them: the
        deflection moves on with each step, and do_step does not copy it into _values."""
        cosim = self._cosim
        return [cosim.deflection, cosim.rate] if cosim is not None else self._values[:2]

    def _model_now(self):
        """(model, state, deflection, rate) now: the co-simulation's, or before
        initialization is complete the relaxed component's at the current inputs; None
        while the parameters make no sense."""
        cosim = self._cosim
        if cosim is not None:
            return cosim.model, cosim.state, cosim.deflection, cosim.rate
        values = self._parameter_values()
        if self.definition.check_parameters(values):
            return None
        model = self.definition.build_model(values)
        x, v = self._values[DEFLECTION_VR], self._values[RATE_VR]
        return model, model.initial_state(x, v), x, v

    def _refresh_outputs(self):
        if self._cosim is not None:
            outputs = self._cosim.outputs()
        else:
            now = self._model_now()
            outputs = [math.nan] * len(self._output_vrs) if now is None else now[0].outputs(*now[1:])
        for vr, value in zip(self._output_vrs, outputs):
            self._values[vr] = value
        self._outputs_stale = False

    def _refresh_locals(self):
        """The continuous states and their derivatives at the current inputs (the rubber
        rate the contact allows: x > 0 for the tyre)."""
        now = self._model_now()
        n = len(self.definition.states)
        if now is None:
            self._values[self._local_vrs.start:] = [math.nan] * (2 * n)
            return
        model, state, x, v = now
        states = list(state[:n])
        rates = model.rates(states, x, v, model.contact(x, v))
        self._values[self._local_vrs.start:] = states + list(rates or [math.nan] * n)

    def get_real(self, vrs):
        # A hot call (every output, every step): fmi_call's checks written inline.
        if self._mode not in READABLE:
            self._refuse_out_of_sequence("fmi2GetReal", READABLE)
            return _nan_values(self, vrs)
        try:
            # Unknown references are refused before any cached value is brought up to date:
            # a refused call leaves the instance (and its serialized state) as it was.
            if vrs and (min(vrs) < 0 or max(vrs) >= len(self._variables)):
                raise IndexError
            if self._outputs_stale:
                self._refresh_outputs()
            if vrs and max(vrs) >= self._local_vrs.start:
                self._refresh_locals()
            values = self._values
            return [values[vr] for vr in vrs]
        except IndexError:
            unknown = [vr for vr in vrs if not 0 <= vr < len(self._variables)]
            self._error(f"fmi2GetReal: no variable has value reference {unsigned(unknown[0])}")
        except Exception as exc:
            self._internal_error("fmi2GetReal", exc)
        return _nan_values(self, vrs)

    def set_real(self, vrs, values):
        # A hot call (the inputs, every step): fmi_call's checks written inline.
        if self._mode not in SETTABLE:
            self._refuse_out_of_sequence("fmi2SetReal", SETTABLE)
            return
        try:
            # Everything is checked before anything is set: a refused call changes nothing.
            inputs = self._current_inputs()
            inputs_set = refused = False
            for vr, value in zip(vrs, values):
                if (vr == DEFLECTION_VR or vr == RATE_VR) and math.isfinite(value):
                    inputs[vr] = float(value)
                    inputs_set = True
                    continue
                problem = self._check_settable(vr, value)
                if problem:
                    self._error(f"fmi2SetReal: {problem}; nothing set")
                    refused = True
            if refused:
                return
            if inputs_set and self._cosim is not None:
                problem = self._cosim.input_problem(inputs[DEFLECTION_VR], inputs[RATE_VR])
                if problem:
                    self._error(f"fmi2SetReal: {problem}; nothing set")
                    return
            for vr, value in zip(vrs, values):
                if vr != DEFLECTION_VR and vr != RATE_VR:
                    self._values[vr] = float(value)
            if inputs_set:
                self._apply_inputs(*inputs)
            self._outputs_stale = True
        except Exception as exc:
            self._internal_error("fmi2SetReal", exc)

    def _check_settable(self, vr, value):
        if not 0 <= vr < len(self._variables):
            return f"no variable has value reference {unsigned(vr)}"
        variable = self._variables[vr]
        if variable.causality == "output":
            return f"{variable.name} is an output"
        if variable.causality == "local":
            return f"{variable.name} is the model's own (a state or its derivative), not set"
        if variable.causality == "parameter" and self._mode not in (INSTANTIATED, INITIALIZATION):
            return (f"{variable.name} is a fixed parameter, settable only before "
                    f"fmi2ExitInitializationMode")
        return variable.check(value)

    def _apply_inputs(self, deflection, rate):
        """Take both inputs (checked), and warn once for each outside its measured range."""
        if self._cosim is not None:
            self._cosim.take_inputs(deflection, rate)
        self._values[DEFLECTION_VR], self._values[RATE_VR] = deflection, rate
        if self._range_checks:
            for vr, value in ((DEFLECTION_VR, deflection), (RATE_VR, rate)):
                if vr in self._range_checks:
                    self._warn_if_unmeasured(vr, value)

    def _arm_range_checks(self):
        """The inputs with a measured range that have not been warned about yet."""
        self._range_checks = {
            vr: self.definition.measured_ranges[self._variables[vr].name]
            for vr in (DEFLECTION_VR, RATE_VR)
            if self._variables[vr].name in self.definition.measured_ranges
            and self._variables[vr].name not in self._warned}

    def _warn_if_unmeasured(self, vr, value):
        low, high, measured = self._range_checks[vr]
        if not low <= value <= high:
            variable = self._variables[vr]
            self._warned.add(variable.name)
            del self._range_checks[vr]
            self.log(f"{variable.name} = {value:.6g} {variable.unit} is outside the range the "
                     f"thesis measured ({measured}); the model extrapolates. Warned once per "
                     f"instance.", Fmi2Status.warning)

    # The FMUs have Real variables and Boolean parameters only (pythonfmu's own versions of
    # these would raise).
    def _refuse_non_real(self, call, vrs):
        if vrs:
            self._error(f"{call}: no variable of this type has value reference "
                        f"{unsigned(vrs[0])}")

    def get_integer(self, vrs):
        self._refuse_non_real("fmi2GetInteger", vrs)
        return [0] * len(vrs)

    @fmi_call("fmi2GetBoolean", READABLE, on_failure=lambda self, vrs: [False] * len(vrs))
    def get_boolean(self, vrs):
        unknown = [vr for vr in vrs if vr not in self._switch_vrs]
        if unknown:
            self._error(f"fmi2GetBoolean: no Boolean variable has value reference "
                        f"{unsigned(unknown[0])}")
            return [False] * len(vrs)
        return [self._switches[vr - self._switch_vrs.start] for vr in vrs]

    def get_string(self, vrs):
        self._refuse_non_real("fmi2GetString", vrs)
        return [""] * len(vrs)

    def set_integer(self, vrs, values):
        self._refuse_non_real("fmi2SetInteger", vrs)

    @fmi_call("fmi2SetBoolean", SETTABLE)
    def set_boolean(self, vrs, values):
        for vr in vrs:
            if vr not in self._switch_vrs:
                self._error(f"fmi2SetBoolean: no Boolean variable has value reference "
                            f"{unsigned(vr)}; nothing set")
                return
            if self._mode not in (INSTANTIATED, INITIALIZATION):
                name = self.definition.switches[vr - self._switch_vrs.start].name
                last = "true" if values[-1] else "false"
                self._error(f"fmi2SetBoolean: {name} = {last} is a fixed parameter, settable "
                            f"only before fmi2ExitInitializationMode; nothing set")
                return
        for vr, value in zip(vrs, values):
            self._switches[vr - self._switch_vrs.start] = bool(value)

    def set_string(self, vrs, values):
        self._refuse_non_real("fmi2SetString", vrs)

    # --- FMU state --------------------------------------------------------------------

    @fmi_call("fmi2GetFMUstate", ANY_STATE, on_failure=lambda self: {})
    def _get_fmu_state(self):
        return {"model": self.definition.name, "values": self._values[:], "mode": self._mode,
                "start_time": self._start_time, "tolerance": self._tolerance,
                "warned": sorted(self._warned), "switches": self._switches[:],
                "cosim": self._cosim.snapshot() if self._cosim is not None else None}

    @fmi_call("fmi2SetFMUstate", ANY_STATE)
    def _set_fmu_state(self, state):
        try:
            problem = self._state_problem(state)
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            problem = f"the state is incomplete ({type(exc).__name__}: {exc})"
        if problem:
            self._error(f"fmi2SetFMUstate: {problem}; state unchanged")
            return
        values = [float(v) for v in state["values"]]
        self._switches = [bool(v) for v in state["switches"]]
        cosim = None
        if state["cosim"] is not None:
            cosim = self._new_cosim(self.definition.build_model(self._parameter_values(values)),
                                    state["tolerance"])
            cosim.restore(state["cosim"])
        self._values = values
        self._mode = state["mode"]
        self._start_time = state["start_time"]
        self._tolerance = state["tolerance"]
        self._warned = set(state["warned"])
        self._arm_range_checks()
        self._cosim = cosim
        self._outputs_stale = True

    def _state_problem(self, state):
        """Why a state cannot be this instance's, or None: every value passes the checks
        fmi2SetReal applies, and the co-simulation's values are ones a run could reach."""
        if not isinstance(state, dict):
            return "not a state"
        if state.get("invalid"):
            return state["invalid"]
        if state.get("model") != self.definition.name:
            return f"the state belongs to {state.get('model')!r}, not to {self.definition.name}"
        values = state["values"]
        if len(values) != len(self._variables) or state["mode"] not in ANY_STATE:
            return (f"the state has {len(values)} values and FMI state {state['mode']!r}; this "
                    f"FMU has {len(self._variables)} variables")
        for variable, value in zip(self._variables, values):
            problem = variable.causality in ("input", "parameter") and variable.check(float(value))
            if problem:
                return f"the state's {problem}"
        inputs = {v.name for v in self.definition.inputs}
        switches = state["switches"]
        problem = _first_invalid([
            ("start time", state["start_time"], _finite),
            ("tolerance", state["tolerance"], _positive),
            ("warned inputs", state["warned"], lambda v: set(v) <= inputs),
            ("switches", switches, lambda v: len(v) == len(self._switches)
             and all(isinstance(b, bool) for b in v))])
        if problem:
            return problem
        cosim = state["cosim"]
        if cosim is None:
            return None
        problem = self.definition.check_parameters(self._parameter_values(values))
        if problem:
            return f"the state's parameters are not valid: {problem}"
        memory = cosim["integrator"]
        size = self.definition.equations.state_size
        n = self.definition.equations.integrated
        w = memory["w"]
        problem = _first_invalid([
            ("rate warned", cosim["rate_warned"], lambda v: isinstance(v, bool)),
            ("last step", cosim["previous"], lambda v: v is None or (
                len(v) == 3 and all(_finite(x) for x in v) and _positive(v[2]))),
            ("time", cosim["time"], _finite),
            ("deflection", cosim["deflection"], _finite),
            ("rate", cosim["rate"], _finite),
            ("internal state size", len(cosim["state"]), lambda v: v == size),
            *((f"internal state[{i}]", v, _finite) for i, v in enumerate(cosim["state"])),
            ("integrator tolerance", cosim["rtol"], _positive),
            ("next step size", memory["h_next"], lambda v: v is None or _positive(v)),
            ("iteration matrix", w, lambda v: v is None or (
                _positive(v[0]) and len(v[1]) == n * n and all(_finite(x) for x in v[1])
                and 1 <= int(v[2]) <= Rosenbrock.MAX_W_REUSE))])
        if problem:
            return problem
        model = self.definition.build_model(self._parameter_values(values))
        problem = model.check_input(list(cosim["state"]), cosim["deflection"])
        if problem:
            return f"the state's inputs do not fit its model state: {problem}"
        return None

    @staticmethod
    def _fmu_state_to_bytes(state):
        return json.dumps(state).encode("utf-8")

    @staticmethod
    def _fmu_state_from_bytes(state):
        # No instance to log to here: a broken buffer becomes a state that
        # fmi2SetFMUstate refuses with a message (the guard has checked its envelope).
        try:
            decoded = json.loads(state.decode("utf-8"))
            return decoded if isinstance(decoded, dict) else {"invalid": "not a state"}
        except Exception as exc:
            return {"invalid": f"the serialized state cannot be read ({exc})"}


def rate_warning(definition, rate, secant):
    """The rate check's message (runtime/cosim.py), word for word the native flavour's."""
    deflection, rate_input = definition.inputs
    if rate == 0.0:
        what = f"{rate_input.name} stays 0 while {deflection.name} moves"
    else:
        what = (f"{rate_input.name} = {rate:.6g} {rate_input.unit} does not fit the movement "
                f"of {deflection.name}")
    return (f"fmi2DoStep: {what} ({secant:.6g} {rate_input.unit} over the last step); the "
            f"rate-dependent force is wrong. Give {rate_input.name} in {rate_input.unit} with "
            f"the sign of d({deflection.name})/dt, or set rate_from_deflection to derive it. "
            f"Warned once per instance.")


def _first_invalid(checks):
    """"the state's NAME = VALUE is not valid" for the first (name, value, test) whose test
    fails, else None."""
    for name, value, test in checks:
        if not test(value):
            return f"the state's {name} = {value!r} is not valid"
    return None


def _finite(value):
    return isinstance(value, (int, float)) and math.isfinite(value)


def _positive(value):
    return _finite(value) and value > 0.0
