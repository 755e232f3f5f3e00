"""A bank: the coupling's per-host-step work for many FMU instances in compiled code.

`Coupling` (master.py) drives each component through fmpy, one Python call after another;
`Bank` does the same steps for all its instances in one C call per pass (bank.c): save
the state, set the inputs, step, read the outputs, restore, the schemes' bookkeeping and
the load laws (law.py), through each FMU's own FMI functions. The host hands it the
deflections of all instances as one array and gets the laws back as one array (a row
x*, F*, K, Q, K_touch per instance, for its force elements to evaluate: exudyn_bank.py
gives them to exudyn's compiled symbolic functions). The Python work per host step does
not grow with the number of instances; the instances whose law is a linearised step (the
damper, and the tyre where its tangent changes over a step) are linearised in C too
(bank_linearised.c, linearised.py's operations in its order), FMI 2.0 and 3.0 alike.

    bank = Bank([tyre, damper, ...], "corrected")   # FmuComponents, not yet started
    bank.start(t0, deflections)
    while t < t_end:
        bank.begin_step(t + h)
        while True:
            host.solve_step(h)                  # its force elements: the laws in bank.laws
            verdict = bank.end_pass(t + h, host_deflections())
            ...                                 # as Coupling.end_pass's verdict
        bank.accept(t + h)

The same schemes give the same numbers as the Python path (tests/test_bank.py checks it to
the bit); `corrected`, `iterated`, `converged` and `explicit` (`predicted` and `nepce`: the Python
path). A bank is used by the thread that made it: another thread's call is refused.
"""

import ctypes
import math
import threading

import numpy as np

from .bank_build import function_address, library_path
from .errors import CouplingError, StepDiscarded
from .law import LoadLaw
from .master import Verdict, count_unconverged
from .schemes import scheme_named

MAX_OUTPUTS = 8
# x*, F*, K, Q, K_touch; then Q/2, and the secant's bounds; then the reversal's kink: where,
# the law's load there, the tangent beyond it, the side (law.py)
LAW_COLUMNS = 12
SCHEME_CODES = {"explicit": 0, "corrected": 1, "iterated": 2, "converged": 2}
UNILATERAL, STEP_TANGENT, CURVATURE, LINEARISABLE, LINEARISED, REVERSIBLE = 1, 2, 4, 8, 16, 32
ACCEPT, REPEAT, RETRY, FAILED, BUSY, NOTICE = 0, 1, 2, -1, -2, 4
FUNCTIONS = {2: ("fmi2SetReal", "fmi2GetReal", "fmi2DoStep", "fmi2GetFMUstate",
                 "fmi2SetFMUstate", "fmi2GetDirectionalDerivative"),
             3: ("fmi3SetFloat64", "fmi3GetFloat64", "fmi3DoStep", "fmi3GetFMUState",
                 "fmi3SetFMUState", "fmi3GetDirectionalDerivative")}
FAILED_CALLS = {1: "{set}", 2: "{get}", 3: "{step}", 4: "{get_state}", 5: "{set_state}",
                6: "{directional}"}
STATUS = {2: "Discard", 3: "Error", 4: "Fatal"}
MODEL_FUNCTIONS = {2: ("fmi2SetReal", "fmi2GetReal", "fmi2SetContinuousStates",
                       "fmi2GetDirectionalDerivative", "fmi2GetDerivatives",
                       "fmi2EnterEventMode", "fmi2NewDiscreteStates",
                       "fmi2EnterContinuousTimeMode"),
                   3: ("fmi3SetFloat64", "fmi3GetFloat64", "fmi3SetContinuousStates",
                       "fmi3GetDirectionalDerivative", "fmi3GetContinuousStateDerivatives",
                       "fmi3EnterEventMode", "fmi3UpdateDiscreteStates",
                       "fmi3EnterContinuousTimeMode")}

_library = None


def library():
    """The bank's shared library, loaded once per process (compiled on first use)."""
    global _library
    if _library is None:
        lib = ctypes.CDLL(str(library_path()))
        pointer, double, integer = ctypes.c_void_p, ctypes.c_double, ctypes.c_int
        lib.bank_new.restype = pointer
        lib.bank_new.argtypes = [integer]
        lib.bank_bind.argtypes = [pointer] * 9
        lib.bank_set_scheme.argtypes = [pointer, integer, integer, integer, double]
        lib.bank_set_instance.argtypes = [pointer, integer, integer, pointer, pointer, pointer,
                                          integer, integer, integer, integer]
        lib.bank_set_model.argtypes = [pointer, integer, pointer, pointer, integer, pointer,
                                       integer]
        lib.bank_state.restype = pointer
        lib.bank_state.argtypes = [pointer, integer]
        lib.bank_free.argtypes = [pointer]
        lib.bank_failure.argtypes = [pointer] * 7
        lib.bank_lagged_laws.argtypes = [pointer]
        lib.bank_law_loads.argtypes = [pointer] * 4
        lib.law_table_loads.argtypes = [pointer] * 4
        lib.bank_bind_call.argtypes = [pointer, pointer]
        lib.bank_kink_first_laws.argtypes = [pointer, integer]
        # the calls of every host step take the bank alone, as a c_void_p (no argtypes:
        # ctypes passes it as it is; converting arguments cost more than the calls' work)
        for name in ("bank_begin_step", "bank_end_pass", "bank_accept"):
            getattr(lib, name).argtypes = None
        lib.bank_reject.argtypes = [pointer]
        _library = lib
    return _library


class _Call(ctypes.Structure):
    """bank.h's BankCall: the arguments and results of a host step's calls."""
    _fields_ = [("time", ctypes.c_double), ("mismatch", ctypes.c_double),
                ("next", ctypes.c_double), ("begun", ctypes.c_double),
                ("total_passes", ctypes.c_int64), ("pass_", ctypes.c_int),
                ("max_pieces", ctypes.c_int), ("n_flagged", ctypes.c_int),
                ("cut", ctypes.c_int)]


_thread = threading.get_ident
_new = object.__new__


def _verdict(mismatch, repeat=False):
    """Verdict(repeat=repeat, mismatch=mismatch), made at a third of the dataclass's
    cost (its defaults are class attributes): two per host step."""
    verdict = _new(Verdict)
    verdict.mismatch = mismatch
    if repeat:
        verdict.repeat = True
    return verdict


def _address(array):
    return array.ctypes.data_as(ctypes.c_void_p)


def _addresses(dll, names):
    """The named functions' addresses in a loaded FMU library, as a C array of pointers."""
    return (ctypes.c_void_p * len(names))(*[function_address(getattr(dll, name))
                                             for name in names])


def _law_loads(function, handle, n, deflection, slopes):
    """(loads, slopes where asked) of n laws at `deflection` by bank.c's `function`."""
    deflection = np.ascontiguousarray(deflection, dtype=float)
    loads = np.empty(n)
    slope = np.empty(n) if slopes else None
    function(handle, _address(deflection), _address(loads),
             _address(slope) if slopes else None)
    return (loads, slope) if slopes else loads


class Bank:
    """FmuComponents (fmu.py: instantiated, in initialization mode, not started) coupled
    to one host by one scheme, their per-step work done in C. The arrays a host reads:
    `laws` (rows x*, F*, K, Q, K_touch: the law of law.py, with each component's
    `unilateral`; then Q/2, K/2 and 2K, the lower bound first; then the reversal's kink:
    where, the law's load there, the tangent beyond, the side), `outputs` and `trial_outputs` (columns as each component's
    output_names), `accepted` (time, deflection, secant rate of the last accepted step)."""

    def __init__(self, components, scheme="corrected", host_can_retry=True, record=None,
                 linearise="c"):
        """linearise: "c", the linearised steps in C (bank_linearised.c, FMI 2.0 and 3.0:
        the Python path's numbers to the bit, as linearised.py does the same operations
        in the same order), or "python", by linearised.py itself (at its cost)."""
        if linearise not in ("c", "python"):
            raise ValueError(f"linearise {linearise!r}: 'c' or 'python'")
        self.linearise = linearise
        self.scheme = scheme_named(scheme) if isinstance(scheme, str) else scheme
        if self.scheme.name not in SCHEME_CODES:
            raise ValueError(f"the bank runs the schemes {', '.join(SCHEME_CODES)}; "
                             f"{self.scheme.name!r} runs on the Python path (Coupling)")
        self.components = list(components)
        self.record = record
        self.host_can_retry = host_can_retry
        self._owner = threading.get_ident()
        n = self.n = len(self.components)
        self._lib = lib = library()
        self.deflection = np.zeros(n)  # the host's, as end_pass was given it
        self.laws = np.zeros((n, LAW_COLUMNS))
        self.accepted = np.zeros((n, 3))
        self.outputs = np.zeros((n, MAX_OUTPUTS))
        self.trial_outputs = np.zeros((n, MAX_OUTPUTS))
        self._seen = np.zeros((n, 2))  # peak |load|, the last contact stiffness
        self._counts = np.zeros((n, 3), dtype=np.int64)  # doSteps, saves, restores
        self._flagged = np.zeros(max(n, 1), dtype=np.intc)
        self._handle = lib.bank_new(n)
        if not self._handle:
            raise MemoryError("no memory for the bank")
        lib.bank_bind(self._handle, *map(_address, (
            self.deflection, self.laws, self.accepted, self.outputs, self.trial_outputs,
            self._seen, self._counts, self._flagged)))
        lib.bank_set_scheme(self._handle, SCHEME_CODES[self.scheme.name], self.scheme.passes,
                            self.scheme.least_passes, self.scheme.tolerance)
        self.unilateral = np.array([c.unilateral for c in self.components], dtype=bool)
        # instances whose laws may have a reversal's kink (fmu.py's reversible_law)
        self.reversible = np.array([self.scheme.name != "explicit" and c._reversible()
                                    for c in self.components], dtype=bool)
        self.load_index = np.zeros(n, dtype=int)
        self._python_laws = 0  # instances whose first law Python makes (_predicted_law)
        for i, component in enumerate(self.components):
            self._hand_over(i, component)
        # each instance's load's cell in `outputs`, flat (loads; a reader of its own)
        self.load_cells = np.arange(n) * MAX_OUTPUTS + self.load_index
        # a host step's calls: their arguments and results in a block bound once, the
        # functions and the bank's pointer looked up once (a fixed few microseconds of
        # Python per host step, whatever the number of instances)
        self._call = _Call(max_pieces=1 if host_can_retry else 64, next=math.nan,
                           begun=math.nan)  # NaN: no step begun early
        lib.bank_bind_call(self._handle, ctypes.byref(self._call))
        self._bank = ctypes.c_void_p(self._handle)
        self._begin, self._end, self._accept = lib.bank_begin_step, lib.bank_end_pass, \
            lib.bank_accept
        # accept(time, next_time) begins the next step in its call, where no instance's
        # first law is made in Python
        self._early = not self._python_laws
        self._warn_above = (self.scheme.tolerance if self.scheme.warn_unconverged
                            else float("inf"))
        self.time = None
        self.steps = self.retries = 0
        self.unconverged_steps = 0

    def _hand_over(self, i, component):
        """Give the C bank the instance pointer and its library's function addresses."""
        instance = component.instance
        version = 3 if instance.fmi3 else 2
        functions = _addresses(instance.fmpy.dll, FUNCTIONS[version])
        if len(component.output_names) > MAX_OUTPUTS:
            raise ValueError(f"{component.name}: more than {MAX_OUTPUTS} outputs")
        vrs = (ctypes.c_uint * (3 + len(component.output_names)))(
            *component._inputs.references, instance.fmu.value_references["stiffness"],
            *component._outputs.references)
        load = component.output_names.index(component.load_name)
        self.load_index[i] = load
        flags = ((UNILATERAL if component.unilateral else 0)
                 | (STEP_TANGENT if component.stiffness_is_step_tangent else 0)
                 | (CURVATURE if component._curvature else 0)
                 | (LINEARISABLE if component._linearisable else 0)
                 | (LINEARISED if component.step_model == "linearised" else 0)
                 | (REVERSIBLE if component._reversible() else 0))
        if self._lib.bank_set_instance(self._handle, i, version, instance.component, functions, vrs,
                                       len(component.output_names), load,
                                       component.output_names.index("stiffness"), flags):
            raise ValueError(f"{component.name}: the bank cannot take this instance")
        if self.linearise == "c" and component._linearisable and (
                component.step_model == "linearised" or component._curvature):
            self._hand_over_model(i, component)
        elif component.step_model == "linearised":
            self._python_laws += 1

    def _hand_over_model(self, i, component):
        """The Model Exchange side instance that linearises the component's step
        (linearised.py makes it; the bank calls it)."""
        model = component.linearisation()
        instance = model._instance
        names = MODEL_FUNCTIONS[3 if instance.fmi3 else 2]
        functions = _addresses(instance.fmpy.dll, names)
        vrs = (ctypes.c_uint * (2 * model.n + 4))(
            *instance.fmu.references(model.state_names), *model._jacobian.unknowns,
            *model._inputs.references)
        if self._lib.bank_set_model(self._handle, i, instance.component, functions, model.n, vrs,
                                    int(model._contact_events)):
            raise ValueError(f"{component.name}: the bank cannot linearise this instance "
                             f"({model.n} states)")

    # --- the protocol (master.py's) ---------------------------------------------------------

    def _self_check(self):
        if threading.get_ident() != self._owner:
            raise RuntimeError(f"this bank of {self.n} FMU instances belongs to thread "
                               f"{self._owner} and was called from thread "
                               f"{threading.get_ident()}: FMU instances are stepped by one "
                               f"thread; make a bank per thread")

    def start(self, time, deflection, rate=None):
        """Leave initialization mode with every component relaxed at its deflection."""
        self._self_check()
        deflection = np.asarray(deflection, dtype=float)
        rate = np.zeros(self.n) if rate is None else np.asarray(rate, dtype=float)
        for i, component in enumerate(self.components):
            component.start(time, float(deflection[i]), float(rate[i]))
            values = [component.outputs[name] for name in component.output_names]
            self.outputs[i, :len(values)] = values
            self.accepted[i] = time, deflection[i], rate[i]
            self._seen[i] = component.peak_load, component.touch_stiffness
        self.deflection[:] = deflection
        self.time = time
        self._lib.bank_lagged_laws(self._handle)

    @property
    def passes(self):
        """Passes of the current step so far."""
        return self._call.pass_

    @property
    def total_passes(self):
        return self._call.total_passes

    @property
    def last_mismatch(self):
        """The last pass's mismatch (a retried pass leaves the one before)."""
        return self._call.mismatch

    def begin_step(self, time):
        """The host starts a step to `time` from the last accepted point (where
        accept(..., next_time=time) began it already, nothing is left to do)."""
        if _thread() != self._owner:
            self._self_check()
        call = self._call
        if time == call.begun:
            call.pass_ = 0
            return
        call.time = time
        flagged = self._begin(self._bank)
        if flagged:
            if flagged < 0:
                self._raise(busy=flagged == BUSY)
            for i in self._flagged[:flagged]:
                self._predicted_law(i, time)

    def end_pass(self, time, deflection):
        """After the host's solve to `time`, its deflections: step each FMU along the
        secant to them and judge the pass (master.py's Verdict)."""
        if _thread() != self._owner:
            self._self_check()
        if deflection is not self.deflection:
            self.deflection[...] = deflection
        call = self._call
        call.time = time
        verdict = self._end(self._bank)
        if verdict == ACCEPT:  # nothing cut, no law for Python (else NOTICE is added)
            mismatch = call.mismatch
            if mismatch > self._warn_above:
                count_unconverged(self, time, mismatch)
            return _verdict(mismatch)
        if verdict == REPEAT:
            return _verdict(call.mismatch, repeat=True)
        return self._noticed(verdict, time)

    def _noticed(self, verdict, time):
        """end_pass's verdict where the pass cut a step, listed laws for Python, was
        discarded or failed."""
        call = self._call
        if call.cut:
            self.retries += call.cut
        if verdict in (FAILED, BUSY):
            self._raise(busy=verdict == BUSY)
        if verdict == RETRY:
            if not self.host_can_retry:
                self._raise(cut_too=True)
            self.retries += 1
            return Verdict(retry_step=0.5 * (time - self.time))
        if verdict == ACCEPT + NOTICE:
            mismatch = call.mismatch
            if mismatch > self._warn_above:
                count_unconverged(self, time, mismatch)
            return _verdict(mismatch)
        if call.n_flagged:
            for i in self._flagged[:call.n_flagged]:
                self._corrected_law(i, time)
        return _verdict(call.mismatch, repeat=True)

    def accept(self, time, next_time=None, record=True):
        """The host accepted its step to `time` (at the time reached: only records).
        `next_time`, the end of the host's next step where it knows it: that step begins
        in the same call (its saves and first laws now; `laws` are then the next step's),
        and begin_step(next_time) has nothing left to do (one C call fewer per host
        step). Leave it out on the last step. record False: the host calls `record`
        itself after this call (to time it apart)."""
        if _thread() != self._owner:
            self._self_check()
        if time > self.time:
            call = self._call
            call.time = time
            call.next = next_time if next_time is not None and self._early else math.nan
            if self._accept(self._bank):
                self._raise()
            self.time = time
            self.steps += 1
        if self.record and record:
            self.record(time)

    def reject(self):
        self._self_check()
        if self._lib.bank_reject(self._handle):
            self._raise()

    # --- the laws ----------------------------------------------------------------------------

    def kink_first_laws(self, on=True):
        """Each step's first law with the reversal's kink at the accepted point, for every
        instance (fmu.py's `kinked_first_law`, reversible_law): for a host whose Newton
        copes with a kink at the step's start (the vehicle's own solver, whose Newton
        damps an update that grew the residual on a new matrix)."""
        for component in self.components:
            component.kinked_first_law = on
        if self._handle:
            self._lib.bank_kink_first_laws(self._handle, int(on))

    def law_loads(self, deflection, slopes=False):
        """The current laws' loads at the host's deflections (and their slopes)."""
        return _law_loads(self._lib.bank_law_loads, self._handle, self.n, deflection, slopes)

    def law_loads_entry(self):
        """(the address of bank.c's bank_law_loads, the bank's handle), for C code that
        evaluates the laws itself at every iterate: bank_law_loads(handle, deflection,
        loads, slopes), arrays of n (slopes may be NULL), as law_loads; valid while the
        bank lives."""
        return function_address(self._lib.bank_law_loads), self._handle

    def law_table(self):
        """The present laws as a LawTable (copies): evaluated as now after the bank
        has moved on or is gone."""
        return LawTable(self.laws, self.unilateral)

    def _linearised(self, i, deflection, rate, step):
        component = self.components[i]
        component.time = self.accepted[i, 0]  # for its messages
        return component._linearised_step(deflection, rate, step)

    def _predicted_law(self, i, time):
        """fmu.py's predicted_law for a linearised component."""
        accepted_time, deflection, rate = self.accepted[i]
        step = time - accepted_time
        predicted, tangent, _ = self._linearised(i, deflection, rate, step)
        self._set_law(i, deflection + rate * step, predicted, tangent, 0.0)

    def _set_law(self, i, deflection, load, stiffness, curvature, kink=None):
        """A row of `laws` (bank.c's set_law; `kink`: (where, the tangent beyond, the
        side), bank.c's set_kink after it)."""
        low, high = ((0.5 * stiffness, 2.0 * stiffness) if stiffness >= 0.0
                     else (2.0 * stiffness, 0.5 * stiffness))
        where, beyond, side = kink or (deflection, stiffness, 0.0)
        law = LoadLaw(deflection, load, stiffness, curvature, kink=where, beyond=beyond,
                      side=side)
        self.laws[i] = (deflection, load, stiffness, curvature, self._seen[i, 1],
                        0.5 * curvature, low, high, where, law.kink_load, beyond, side)

    def _corrected_law(self, i, time):
        """fmu.py's corrected_law where it linearises (the bank wrote the rest)."""
        component = self.components[i]
        accepted_time, accepted_deflection, _ = self.accepted[i]
        deflection = self.laws[i, 0]
        stiffness = self.trial_outputs[i, component.output_names.index("stiffness")]
        secant = (deflection - accepted_deflection) / (time - accepted_time)
        load, tangent, curvature = self.laws[i, 1:4]
        if component.step_model == "linearised":
            _, tangent, _ = self._linearised(i, deflection, secant, time - accepted_time)
            curvature = curvature * (tangent / stiffness) ** 2 if stiffness else 0.0
            self._set_law(i, deflection, load, tangent, curvature)
            return
        curvature = self._linearised(i, deflection, secant, time - accepted_time)[2]
        # the reversal's kink as bank.c wrote it
        self._set_law(i, deflection, load, tangent, curvature, tuple(self.laws[i, [8, 10, 11]]))

    # --- values ------------------------------------------------------------------------------

    @property
    def loads(self):
        """Each instance's load after the last accepted step."""
        return self.outputs.take(self.load_cells)

    def costs(self):
        steps, n = max(self.steps, 1), max(self.n, 1)
        do_steps, saves, restores = self._counts.sum(axis=0)
        return {"do_steps": do_steps / steps / n, "saves": saves / steps / n,
                "restores": restores / steps / n, "passes": self.total_passes / steps}

    # --- faults ------------------------------------------------------------------------------

    def _raise(self, cut_too=False, busy=False):
        if busy:
            raise RuntimeError(f"the bank of {self.n} instances is in use by another call "
                               f"(a call from an FMU's logger, or another thread)")
        instance, call, status, output = (ctypes.c_int() for _ in range(4))
        time, step = ctypes.c_double(), ctypes.c_double()
        self._lib.bank_failure(self._handle, *(ctypes.byref(v) for v in (
            instance, call, status, output, time, step)))
        component = self.components[instance.value]
        said = f": {component.messages[-1]}" if component.messages else ""
        version = 3 if component.instance.fmi3 else 2
        status_name = f"fmi{version}{STATUS.get(status.value, 'Error')}"
        names = dict(zip(("set", "get", "step", "get_state", "set_state", "directional"),
                         FUNCTIONS[version]))
        if cut_too:
            discarded = StepDiscarded(component.name, time.value, step.value,
                                      component.messages[-1] if component.messages
                                      else "no message")
            raise CouplingError(component.name, time.value,
                                f"{discarded} (cut into 64 steps too)")
        if call.value == 7:
            name = component.output_names[output.value]
            value = self.trial_outputs[instance.value, output.value]
            raise CouplingError(component.name, time.value, f"output {name} = {value!r} is "
                                f"not finite{said}")
        if call.value == 9:
            raise CouplingError(component.name, self.accepted[instance.value, 0],
                                f"the linearised step over {step.value:.6g} s: its Model "
                                f"Exchange instance returned {status_name}")
        if call.value == 8:
            raise ValueError(f"{component.name}: a trial or acceptance at t = "
                             f"{time.value!r} s, not after the last accepted step")
        if call.value == 3:
            raise CouplingError(component.name, time.value, f"{names['step']} by "
                                f"{step.value:.6g} s returned {status_name}{said}")
        if call.value in FAILED_CALLS:
            raise CouplingError(component.name, time.value,
                                f"{FAILED_CALLS[call.value].format(**names)} returned "
                                f"{status_name}{said}")
        raise RuntimeError(f"the bank failed in {component.name} at t = {time.value!r} s")

    def free(self):
        """Free the bank and its components (their saved states with them)."""
        if self._handle:
            for i, component in enumerate(self.components):
                state = self._lib.bank_state(self._handle, i)
                if state:
                    component._state.value = state
            self._lib.bank_free(self._handle)
            self._handle = None
        for component in self.components:
            component.free()

    def __del__(self):
        if getattr(self, "_handle", None):
            self._lib.bank_free(self._handle)
            self._handle = None


class _LawTable(ctypes.Structure):
    """bank.h's LawTable."""
    _fields_ = [("n", ctypes.c_int), ("laws", ctypes.c_void_p), ("unilateral", ctypes.c_void_p)]


class LawTable:
    """A bank's laws of one moment apart from the bank (`laws`: rows as Bank.laws;
    `unilateral`: each law's), evaluated by bank.c as the bank evaluates its own
    (law_table_loads: bank_law_loads's operations). law_loads and law_loads_entry as
    Bank's, for C code that calls the laws (the vehicle's kernels)."""

    def __init__(self, laws, unilateral):
        self.laws = np.array(laws, dtype=float, order="C")
        self.n = len(self.laws)
        self.unilateral = np.array(unilateral, dtype=ctypes.c_int, order="C")
        self._lib = library()
        self._struct = _LawTable(self.n, self.laws.ctypes.data, self.unilateral.ctypes.data)
        self._handle = ctypes.addressof(self._struct)

    def law_loads(self, deflection, slopes=False):
        """The laws' loads at `deflection` (and their slopes), as Bank.law_loads."""
        return _law_loads(self._lib.law_table_loads, self._handle, self.n, deflection, slopes)

    def law_loads_entry(self):
        """(the address of bank.c's law_table_loads, the table's), valid while it lives."""
        return function_address(self._lib.law_table_loads), self._handle
