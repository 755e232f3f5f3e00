"""What a host may rely on (spec section 8), both flavours, through the raw C interface:
what fmi2Instantiate is given is checked (interface type, GUID, resource location),
NULL arrays and undersized buffers are refused, a logger may call back into the instance,
messages with '%' reach a printf-style logger intact, instances in two threads are
independent, and memory does not grow with instantiate/free cycles or logged messages."""

import ctypes
import gc
import math
import threading
import zipfile
from ctypes import POINTER, byref, c_char_p, c_double, c_int, c_size_t, c_uint, c_void_p

import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

from fmu_components.lab.signals import thesis_sine

from fmu_runner import ERROR, OK, FmuRunner

CO_SIMULATION, MODEL_EXCHANGE = 1, 0


class Raw:
    """An FMU's binary loaded with ctypes, and what its logger received."""

    def __init__(self, fmu, directory):
        with zipfile.ZipFile(fmu) as archive:
            archive.extractall(directory)
        self.description = read_model_description(str(directory / "modelDescription.xml"))
        name = self.description.coSimulation.modelIdentifier
        self.library = ctypes.CDLL(str(directory / "binaries" / "linux64" / f"{name}.so"))
        self.resources = (directory / "resources").as_uri()
        self.guid = self.description.guid
        self.messages = []
        self.keep = True  # False: count messages only (memory measurements)
        self.counted = 0
        self.on_message = None
        self.callbacks = fmi2CallbackFunctions()
        self.callbacks.logger = fmi2CallbackLoggerTYPE(self._log)
        functions = {
            "fmi2Instantiate": (c_void_p, [c_char_p, c_int, c_char_p, c_char_p, c_void_p, c_int,
                                           c_int]),
            "fmi2FreeInstance": (None, [c_void_p]),
            "fmi2SetupExperiment": (c_int, [c_void_p, c_int, c_double, c_double, c_int, c_double]),
            "fmi2EnterInitializationMode": (c_int, [c_void_p]),
            "fmi2ExitInitializationMode": (c_int, [c_void_p]),
            "fmi2SetReal": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double)]),
            "fmi2GetReal": (c_int, [c_void_p, POINTER(c_uint), c_size_t, POINTER(c_double)]),
            "fmi2DoStep": (c_int, [c_void_p, c_double, c_double, c_int]),
            "fmi2GetFMUstate": (c_int, [c_void_p, POINTER(c_void_p)]),
            "fmi2FreeFMUstate": (c_int, [c_void_p, POINTER(c_void_p)]),
            "fmi2SerializedFMUstateSize": (c_int, [c_void_p, c_void_p, POINTER(c_size_t)]),
            "fmi2SerializeFMUstate": (c_int, [c_void_p, c_void_p, c_void_p, c_size_t]),
        }
        for function, (restype, argtypes) in functions.items():
            getattr(self.library, function).restype = restype
            getattr(self.library, function).argtypes = argtypes
        self.lib = self.library

    def _log(self, environment, instance_name, status, category, message):
        self.counted += 1
        if self.keep:
            self.messages.append((status, message.decode("utf-8", "replace")))
        if self.on_message:
            self.on_message()

    def instantiate(self, name=b"raw", kind=CO_SIMULATION, guid=None, resources=None):
        guid = self.guid.encode() if guid is None else guid
        resources = self.resources.encode() if resources is None else resources
        return self.lib.fmi2Instantiate(name, kind, guid, resources, ctypes.addressof(self.callbacks),
                                        0, 0)

    def initialized(self, deflection=0.0, rate=0.0):
        c = self.instantiate()
        assert c
        assert self.lib.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == OK
        assert self.lib.fmi2EnterInitializationMode(c) == OK
        assert self.set(c, [0, 1], [deflection, rate]) == OK
        assert self.lib.fmi2ExitInitializationMode(c) == OK
        return c

    def set(self, c, vrs, values):
        return self.lib.fmi2SetReal(c, (c_uint * len(vrs))(*vrs), len(vrs),
                                    (c_double * len(values))(*values))

    def last_error(self):
        return [m for s, m in self.messages if s == ERROR][-1]


@pytest.fixture
def raw(built_fmus, tmp_path):
    def load(name):
        return Raw(built_fmus[name], tmp_path / name)
    return load


def other_resources(built_fmus, tmp_path):
    """The resources folder of another FMU (the damper's)."""
    return Raw(built_fmus["RotaryDamper"], tmp_path / "other").resources.encode()


@pytest.mark.parametrize("case, expected", [
    ("wrong GUID", "is not this FMU's"),
    ("no GUID", "is not this FMU's"),
    ("unknown interface type", "does not offer the interface type"),
    ("no instance name", "instance name"),
    ("no resource location", "fmuResourceLocation is missing"),
    ("empty resource location", "fmuResourceLocation is missing"),
    ("not a file URI", "is not a local file URI"),
    ("a remote file URI", "is not a local file URI"),
    ("a folder without the FMU", "has no fmu-guid.txt"),
    ("another FMU's resources", "belongs to another FMU"),
])
def test_instantiate_refuses_what_is_not_this_fmu_with_a_message(built_fmus, raw, tmp_path, case,
                                                                 expected):
    fmu = raw("TrackBushTorsion")
    arguments = {
        "wrong GUID": {"guid": b"{00000000-0000-0000-0000-000000000000}"},
        "no GUID": {"guid": c_char_p()},
        "unknown interface type": {"kind": 7},
        "no instance name": {"name": None},
        "no resource location": {"resources": c_char_p()},
        "empty resource location": {"resources": b""},
        "not a file URI": {"resources": b"http://example.org/resources"},
        "a remote file URI": {"resources": b"file://server/share/resources"},
        "a folder without the FMU": {"resources": tmp_path.as_uri().encode()},
        "another FMU's resources": {"resources": other_resources(built_fmus, tmp_path)},
    }[case]
    assert not fmu.instantiate(**arguments)
    assert expected in fmu.last_error(), fmu.messages


def test_python_flavour_refuses_model_exchange(python_fmus, tmp_path):
    fmu = Raw(python_fmus["TrackBushTorsion"], tmp_path)
    assert not fmu.instantiate(kind=MODEL_EXCHANGE)
    assert "does not offer the interface type 0" in fmu.last_error()


def test_null_arrays_and_an_undersized_state_buffer_are_refused(raw):
    fmu = raw("TrackBushTorsion")
    c = fmu.initialized(math.radians(10))
    assert fmu.lib.fmi2SetReal(c, None, 2, None) == ERROR
    assert fmu.lib.fmi2GetReal(c, None, 1, None) == ERROR
    assert fmu.lib.fmi2GetFMUstate(c, None) == ERROR
    assert fmu.lib.fmi2DoStep(None, 0.0, 1e-3, 1) == ERROR
    fmu.lib.fmi2FreeInstance(None)
    state, size = c_void_p(), c_size_t()
    assert fmu.lib.fmi2GetFMUstate(c, byref(state)) == OK
    assert fmu.lib.fmi2SerializedFMUstateSize(c, state, byref(size)) == OK
    buffer = (ctypes.c_ubyte * (size.value + 64))(*([0xA5] * (size.value + 64)))
    assert fmu.lib.fmi2SerializeFMUstate(c, state, buffer, size.value - 1) == ERROR
    assert "the buffer holds" in fmu.last_error()
    assert all(b == 0xA5 for b in buffer)  # nothing written, not even inside the buffer
    assert fmu.lib.fmi2SerializeFMUstate(c, state, buffer, size.value) == OK
    assert all(b == 0xA5 for b in buffer[size.value:])  # nothing past it
    assert fmu.lib.fmi2FreeFMUstate(c, byref(state)) == OK
    fmu.lib.fmi2FreeInstance(c)


def test_a_logger_calling_back_into_the_instance_is_refused_and_harms_nothing(raw):
    fmu = raw("TrackBushTorsion")
    c = fmu.initialized(math.radians(10))
    nested = []
    value = (c_double * 1)()
    fmu.on_message = lambda: nested.append(
        fmu.lib.fmi2GetReal(c, (c_uint * 1)(2), 1, value))
    assert fmu.set(c, [0], [math.nan]) == ERROR  # logs, and the logger calls back
    fmu.on_message = None
    # The first nested call is refused and told why (so the logger runs once more and calls
    # back again); that one is refused without a word, which ends the recursion.
    assert nested == [ERROR, ERROR]
    assert "fmi2GetReal refused: another call on this instance has not returned" in fmu.last_error()
    assert fmu.lib.fmi2DoStep(c, 0.0, 1e-3, 1) == OK
    assert fmu.lib.fmi2GetReal(c, (c_uint * 1)(2), 1, value) == OK and math.isfinite(value[0])
    fmu.lib.fmi2FreeInstance(c)


@pytest.mark.parametrize("vr", [2**31, 2**32 - 1])
def test_an_unknown_value_reference_is_named_as_the_unsigned_number_the_host_sent(raw, vr):
    fmu = raw("TrackBushTorsion")
    c = fmu.initialized()
    value = (c_double * 1)(1.0)
    assert fmu.lib.fmi2GetReal(c, (c_uint * 1)(vr), 1, value) == ERROR
    assert f"value reference {vr}" in fmu.last_error()
    assert fmu.set(c, [vr], [1.0]) == ERROR
    assert f"value reference {vr}" in fmu.last_error()
    fmu.lib.fmi2FreeInstance(c)


def test_a_message_with_percent_signs_reaches_a_formatting_logger_as_written(raw, tmp_path):
    fmu = raw("TrackBushTorsion")
    uri = (tmp_path / "100%s%n").as_uri()  # percent-encoded: file:///.../100%25s%25n
    assert not fmu.instantiate(resources=uri.encode())
    message = fmu.last_error()
    # The logger is printf-like: every '%' comes doubled, so that formatting prints it.
    assert "%%" in message and "%" not in message.replace("%%", "")
    assert uri in message.replace("%%", "%")


def test_instances_in_two_threads_are_independent(built_fmus):
    name = "TrackBushTorsion"
    t, x, v = thesis_sine(name, 1.0, 1e-3)

    def run(phase, results):
        runner = FmuRunner(built_fmus[name], instance_name=f"thread{phase}")
        xs = x + phase * 0.01
        runner.initialize(xs[0], v[0])
        results[phase] = runner.run(xs, v, 1e-3)
        runner.free()

    alone = {}
    for phase in (0, 1):
        run(phase, alone)
    together = {}
    threads = [threading.Thread(target=run, args=(phase, together)) for phase in (0, 1)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    for phase in (0, 1):
        assert np.array_equal(together[phase], alone[phase])
    assert not np.array_equal(alone[0], alone[1])


def rss_kib():
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:"))


def growth_kib(action, repeats):
    """RSS growth over `repeats` more calls of `action`, after as many to warm up."""
    for _ in range(repeats):
        action()
    gc.collect()
    before = rss_kib()
    for _ in range(repeats):
        action()
    gc.collect()
    return rss_kib() - before


def test_memory_does_not_grow_with_logged_messages(raw, built_fmus):
    # The Python flavour's adapter logs through its guard (fmu_guard_log): pythonfmu's log
    # queue, which keeps about 180 bytes of each message, is not used.
    fmu = raw("RotaryDamper")
    fmu.keep = False
    c = fmu.initialized()
    assert growth_kib(lambda: fmu.set(c, [0], [math.inf]), 20000) < 512
    assert fmu.counted == 40000
    fmu.lib.fmi2FreeInstance(c)


def test_memory_does_not_grow_with_instantiate_and_free_cycles(raw, built_fmus):
    fmu = raw("RotaryDamper")
    fmu.keep = False

    def cycle():
        c = fmu.initialized()
        fmu.lib.fmi2FreeInstance(c)

    assert growth_kib(cycle, 3000) < 512
