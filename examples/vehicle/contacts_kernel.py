"""The vehicle's contacts in C (contacts.c, contacts_forces.c, contacts_jacobian.c):
compiled on first use as the coupling's bank is (bank_build.Library: gcc,
-ffp-contract=off, a cache keyed by a hash of the sources), the same equations in the same
order of operations as contacts.py's numpy kernel, which stays the readable reference and
the fallback. One evaluation: the kernel's kinematics (bodies, pins, the tyres'
compressions), the tyres' loads and the course's height under the pins, then the kernel's
forces; the Jacobian's triplets on exudyn's call. On the compiled path an evaluation is
one C call: the kernel calls the bank's laws itself (Bank.law_loads_entry; the operations
of Vehicle.tyre_loads) and evaluates course.py's courses (contacts_course.c); otherwise
Python gives the loads (Vehicle.tyre_loads) and the heights of a course of another class
between two calls. The kernel's memory is allocated once. Its results stay there while
exudyn's Newton iterates; each is handed on as the numpy kernel's attribute (a copy, as
the numpy kernel's are new arrays each time) only when a reader first asks for it after
an evaluation (`publish`, Contacts.__getattr__): the coupling's readers, the step check
and the records, a few times a step, not at every iterate, each what it reads.
"""

import ctypes
import math
import weakref
from pathlib import Path

import numpy as np

from fmu_components.coupling.bank_build import Library, function_address

from . import layout as lay
from . import model
from .course import Bump, Course, RandomRoad, Sine
from .settle_damping import SETTLE_DAMPING

HERE = Path(__file__).resolve().parent
LIBRARY = Library("vehicle_contacts",
                  [HERE / name for name in ("contacts.c", "contacts_forces.c",
                                            "contacts_jacobian.c", "contacts_course.c")],
                  [HERE / "contacts.h"], "the vehicle's contacts kernel (contacts.c)",
                  "use the numpy kernel (--contacts numpy, or vehicle.contacts.use('numpy'))")
# contacts.h's enum Parameter, in its order
PARAMETERS = ("LINK_PITCH", "LINK_INNER", "LINK_OUTER", "WHEEL_RADIUS", "TYRE_BLEND",
              "HANDOVER", "CONTACT_ONSET", "GROUND_STIFFNESS", "GROUND_DAMPING",
              "SPROCKET_STIFFNESS", "SPROCKET_DAMPING", "WHEEL_STIFFNESS", "WHEEL_DAMPING",
              "ENGAGEMENT_RAMP", "ENGAGEMENT_RAMP_SQUARED", "SPROCKET_PITCH_RADIUS",
              "TOOTH_SPACING", "IDLER_PIN_RADIUS", "ROLLER_PIN_RADIUS", "SPROCKET_X",
              "SPROCKET_Y", "ROLLER_X", "ROLLER_Y", "WRAP_START", "WRAP_SWEEP",
              "TOOTH_PHASE", "HULL_X0", "SETTLE_SEAT", "SETTLE_ARM", "SETTLE_HULL_X",
              "SETTLE_HULL_Y", "SETTLE_HULL_PITCH", "TWO_PI", "HORN_HEIGHT")
# contacts.h's enum Array, in its order: the Contacts attribute each is read as, its shape
# in (bodies, links, wheels)
ARRAYS = (("state", ("b", 3)), ("rates", ("b", 3)), ("u", ("l", 2)), ("n", ("l", 2)),
          ("seats", ("l", 2, 2)), ("seats_v", ("l", 2, 2)), ("pins", ("l", 2)),
          ("pins_v", ("l", 2)), ("wheels", ("w", 2)), ("wheels_v", ("w", 2)),
          ("compression", ("w",)), ("compression_rate", ("w",)), ("loads", ("w",)),
          ("slopes", ("w",)), ("rate_slopes", ("w",)), ("tyre_force", ("w",)),
          ("ground", ("l",)), ("ground_load", ("l",)), ("tooth_gap", ("l",)),
          ("generalized", ("g",)), ("drive_torque", (1,)))
# the numpy kernel's results that the run's readers read, as `publish` sets them
PUBLISHED = ("u", "n", "seats", "seats_v", "pins", "pins_v", "wheels", "wheels_v",
             "compression", "compression_rate", "tyre_force", "ground_load", "tooth_gap",
             "generalized", "qd", "rates", "body_pos", "hull", "hull_v", "link_pos",
             "link_angle", "link_v", "link_omega", "idler", "idler_v", "in_contact",
             "drive_torque")
# contacts.h's enum Course: the courses the kernel evaluates (contacts_course.c)
COURSE_GIVEN, COURSE_KINDS = -1, {Course: 0, Bump: 1, Sine: 2, RandomRoad: 3}


def library():
    """The kernel's library, its functions declared, loaded once per process
    (bank_build.Library.load); None, with a warning saying why and what to use, where it
    cannot be built."""
    lib = LIBRARY.load("the vehicle's contacts use their numpy kernel")
    if lib is not None and lib.contacts_new.argtypes is None:
        declare(lib)
    return lib


def declare(lib):
    """The kernel's functions' argument types on `lib` (its own library, or another that
    compiles the kernel in: system.py's); checks that contacts.h and this module agree."""
    pointer, handle = ctypes.POINTER(ctypes.c_double), ctypes.c_void_p
    lib.contacts_new.restype = handle
    lib.contacts_new.argtypes = [ctypes.c_int, ctypes.c_int, pointer, pointer]
    lib.contacts_free.argtypes = [handle]
    lib.contacts_array.restype = pointer
    lib.contacts_array.argtypes = [handle, ctypes.c_int, ctypes.POINTER(ctypes.c_int)]
    lib.contacts_kinematics.argtypes = [handle]
    lib.contacts_forces.argtypes = [handle, ctypes.c_int]
    lib.contacts_jacobian.restype = ctypes.c_long
    lib.contacts_jacobian.argtypes = [handle, ctypes.c_double, ctypes.c_double,
                                      pointer, ctypes.c_long]
    lib.contacts_set_course.argtypes = [handle, ctypes.c_int, pointer, ctypes.c_int,
                                        pointer, pointer]
    lib.contacts_course_heights.argtypes = [handle]
    lib.contacts_set_tyre_laws.argtypes = [handle, handle, handle, ctypes.c_int,
                                           ctypes.POINTER(ctypes.c_int)]
    lib.contacts_evaluate.argtypes = [handle, ctypes.c_int]
    lib.contacts_adopt.argtypes = [handle] * 5
    counts = (ctypes.c_int(), ctypes.c_int())
    lib.contacts_layout(*map(ctypes.byref, counts))
    if (counts[0].value, counts[1].value) != (len(PARAMETERS), len(ARRAYS)):
        raise RuntimeError("contacts.h and contacts_kernel.py disagree on the "
                           "kernel's parameters or arrays: rebuild both from one "
                           "revision")


def as_vector(values):
    """A vector exudyn hands a user function (a list) as an array: np.fromiter costs a
    third of np.asarray on a list."""
    if isinstance(values, list):
        return np.fromiter(values, float, len(values))
    return np.asarray(values)


def index_or_slice(index):
    """`index` (integers) as a slice where it is one run (numpy reads a slice as a view,
    without a copy), else as it is (flat)."""
    index = np.ravel(index)
    first = int(index[0])
    if np.array_equal(index, np.arange(first, first + len(index))):
        return slice(first, first + len(index))
    return index


class KernelResults:
    """What Contacts reads of the C kernel: where its last evaluation was the kernel's
    (`_by_compiled`), an attribute of PUBLISHED not set yet is read from the kernel's
    memory on first use (`CompiledContacts.publish`, that attribute alone)."""

    _published = frozenset(PUBLISHED)

    def __getattr__(self, name):  # only for attributes not set
        if self.by_compiled() and name in self._published:
            return self._compiled.publish(name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    def by_compiled(self):
        """Whether the last evaluation was the C kernel's (its results in its memory)."""
        return bool(self.__dict__.get("_by_compiled"))

    def last(self, name):
        """The last evaluation's result `name` (of PUBLISHED) and its address: the C
        kernel's memory itself where the kernel made it and holds it as an array (no copy:
        valid until the next evaluation; its address taken once), else the attribute (a
        float array, C order)."""
        if self.by_compiled():
            compiled = self._compiled
            view = compiled.results.get(name)
            if view is not None:
                return view, compiled.addresses[name]
        value = np.ascontiguousarray(getattr(self, name), dtype=float)
        return value, value.ctypes.data

    def adopt(self, t, q, qd, kernel, addresses=None):
        """The last evaluation of `kernel` (a CompiledContacts over these contacts: the own
        solver's system's, whose Newton evaluates it last at the step's solution) as this
        one's at (t, q, qd), the system's coordinates and velocities, where it was made at
        that state (to the bit; the bank's laws have not changed since): `evaluate` there
        has nothing left to do. Its results only: exudyn's Jacobian would evaluate again.
        addresses: q's and qd's, where the caller has them (float arrays, C order). True
        where it was taken."""
        entry = self.adoption(kernel)
        if entry is None:
            return False
        if addresses is None:
            q = np.ascontiguousarray(q, dtype=float)
            qd = np.ascontiguousarray(qd, dtype=float)
            addresses = q.ctypes.data, qd.ctypes.data
        if not self._compiled.lib.contacts_adopt(entry[1], entry[2], *addresses, entry[3]):
            return False
        self.adopted(t, q, qd)
        return True

    def adoption(self, kernel):
        """contacts_adopt's call for `adopt` (or C that adopts itself, own_pass.c, then
        calls `adopted`): (its address, this object's kernel's handle, `kernel`'s, the
        contacts' coordinates' index among the system's, C ints); None where this object
        does not adopt (its numpy kernel, the audit, the settling). Made once per kernel."""
        if self.kernel != "compiled" or self.audit is not None or self.v.settling:
            return None
        if self._adoption is None or self._adoption[0] is not kernel:
            index = np.ascontiguousarray(self.system_index, dtype=np.intc)
            lib, handle = self._compiled.lib, self._compiled.handle
            self._adoption = (kernel, index, (function_address(lib.contacts_adopt), handle,
                                              kernel.handle, index.ctypes.data))
        return self._adoption[2]

    def kernel_address(self, name):
        """The address of the C kernel's array `name` (ARRAYS'), where its evaluations
        leave it."""
        return self._compiled.addresses[name]

    def adopted(self, t, q, qd):
        """After contacts_adopt took the evaluation at (t, q, qd) into this object's kernel:
        its results this object's (the last evaluation's attributes dropped) and its key
        theirs."""
        self._compiled._drop_published()
        index = self._coordinates
        self._key = (self._state(t, q[index], qd[index]), self.v.tyre_laws_key())
        self._by_compiled, self._adopted = True, True

    def _state(self, t, q, qd):
        """What an evaluation's results depend on besides the tyres' laws (its key's
        first part): the time, the state (the contacts' coordinates), the settling, the
        kernel."""
        return (t, q.tobytes(), qd.tobytes(), self.v.settling, self.kernel)

    def _evaluated(self, t, q, qd):
        """Evaluated at (t, q, qd) for the Jacobian: by this kernel (an adopted evaluation
        has the results alone)."""
        if self._adopted:
            self._key = None
        self._update(t, q, qd)


class CompiledContacts:
    """The C kernel for one Contacts object: its memory, its parameters, its views."""

    def __init__(self, contacts, lib):
        self.contacts, self.lib = contacts, lib
        links, wheels = len(contacts.nodes) - contacts.link0, contacts.link0 - 2
        self.handle = lib.contacts_new(wheels, links, _pointer(contacts.reference),
                                       _pointer(np.ascontiguousarray(contacts.wheel_offset,
                                                                     dtype=float)))
        if not self.handle:
            raise MemoryError("the vehicle's contacts kernel: out of memory")
        weakref.finalize(self, lib.contacts_free, self.handle)
        sizes = {"b": len(contacts.nodes), "g": 3 * len(contacts.nodes), "l": links, "w": wheels}
        self.views = {}
        for index, (name, shape) in enumerate(ARRAYS):
            shape = tuple(sizes.get(s, s) for s in shape)
            count = ctypes.c_int()
            data = lib.contacts_array(self.handle, index, ctypes.byref(count))
            assert count.value == math.prod(shape), name
            self.views[name] = np.ctypeslib.as_array(data, shape=shape)
        # what Contacts.last reads: the kernel's arrays and the results that are parts of
        # them (PUBLISHED's), and their addresses
        state, rates, link0 = self.views["state"], self.views["rates"], contacts.link0
        self.results = {**self.views, "hull": state[0], "hull_v": rates[0],
                        "idler": state[link0 - 1, :2]}
        self.addresses = {name: view.ctypes.data for name, view in self.results.items()}
        count = ctypes.c_int()
        self.parameters = np.ctypeslib.as_array(
            lib.contacts_array(self.handle, -1, ctypes.byref(count)), shape=(len(PARAMETERS),))
        # the state's inputs as flat views, the object's coordinates' order
        self.state, self.rates = self.views["state"].reshape(-1), self.views["rates"].reshape(-1)
        self.reference = contacts.reference.reshape(-1)
        self._course = None  # (the course, its attributes, its kind) the kernel has
        self._bank = None  # the bank whose laws the kernel calls
        self._triplets_buffer(4096)
        self._make_readers()
        self.set_parameters()

    def set_parameters(self):
        """The model's values (again after Contacts.rebase moves the tooth phase)."""
        from . import contacts as numpy_kernel

        c, values = self.contacts, {}
        for module in (lay, model, numpy_kernel):
            values.update({name: getattr(module, name) for name in PARAMETERS
                           if hasattr(module, name)})
        settle = SETTLE_DAMPING
        values.update(ENGAGEMENT_RAMP_SQUARED=model.ENGAGEMENT_RAMP ** 2,
                      SPROCKET_X=c.sprocket_local[0], SPROCKET_Y=c.sprocket_local[1],
                      ROLLER_X=c.roller_local[0], ROLLER_Y=c.roller_local[1],
                      WRAP_START=c.wrap_start, WRAP_SWEEP=c.wrap_sweep,
                      TOOTH_PHASE=c.tooth_phase, HULL_X0=c.hull_x0,
                      SETTLE_SEAT=settle["seat"], SETTLE_ARM=settle["arm"],
                      SETTLE_HULL_X=settle["hull"][0], SETTLE_HULL_Y=settle["hull"][1],
                      SETTLE_HULL_PITCH=settle["hull_pitch"], TWO_PI=2 * math.pi)
        self.parameters[:] = [float(values[name]) for name in PARAMETERS]

    def update(self, q, qd):
        """The contacts at (q, qd), the object's coordinates (arrays), in the kernel's
        memory (the last evaluation's attributes of `contacts` dropped: `publish` makes
        them again where they are read)."""
        c, v, views = self.contacts, self.contacts.v, self.views
        self._drop_published()
        np.add(self.reference, q, out=self.state)
        self.rates[:] = qd
        given = self._set_course(v.course)
        if v.bank is not None and not given:  # one call: the bank's laws called from C
            self._set_tyre_laws(v.bank)
            self.lib.contacts_evaluate(self.handle, bool(v.settling))
            return
        self.lib.contacts_kinematics(self.handle)
        for name, values in zip(("loads", "slopes", "rate_slopes"),
                                v.tyre_loads(views["compression"], views["compression_rate"])):
            views[name][:] = values
        if given:
            pins = views["pins"]
            views["ground"][:] = v.course.under(pins[:, 0], pins[:, 1] - lay.LINK_OUTER)
        self.lib.contacts_forces(self.handle, bool(v.settling))

    def _drop_published(self):
        """The last evaluation's attributes of `contacts` (published, or the numpy
        kernel's) dropped."""
        attributes = self.contacts.__dict__
        for name in self._stale(attributes.keys()):
            del attributes[name]

    def _set_tyre_laws(self, bank):
        """Let the kernel call the bank's laws for the tyres' loads (Vehicle.tyre_loads,
        the same operations), set once per bank (the run sets Vehicle.bank only while the
        bank lives)."""
        if self._bank is not bank:
            rows = np.ascontiguousarray(self.contacts.v.tyre_rows, dtype=ctypes.c_int)
            if self.lib.contacts_set_tyre_laws(self.handle, *bank.law_loads_entry(), bank.n,
                                               rows.ctypes.data_as(ctypes.POINTER(
                                                   ctypes.c_int))):
                raise MemoryError("the vehicle's contacts kernel: out of memory")
            self._bank = bank

    def _set_course(self, course):
        """Hand `course` to the kernel where it is one of course.py's (again where any of
        its attributes was set anew); True where its heights are given from Python."""
        attributes = tuple(vars(course).values())
        if self._course is None or self._course[0] is not course or \
                len(attributes) != len(self._course[1]) or \
                any(a is not b for a, b in zip(attributes, self._course[1])):
            kind, values, waves = course_values(course)
            if self.lib.contacts_set_course(self.handle, kind,
                                            _pointer(np.array(values, dtype=float)),
                                            len(waves[0]), *map(_pointer, waves)):
                raise MemoryError("the vehicle's contacts kernel: out of memory")
            self._course = (course, attributes, kind)
        return self._course[2] == COURSE_GIVEN

    def generalized(self):
        """The generalized forces of the last evaluation (a copy)."""
        return self.views["generalized"].copy()

    def publish(self, name):
        """The last evaluation's result `name` (of PUBLISHED) as the numpy kernel's
        attribute of `contacts`: a copy, as the numpy kernel's are new arrays each time (a
        reader may keep it across evaluations); returns it."""
        value = self._readers[name]()
        self.contacts.__dict__[name] = value
        return value

    def _make_readers(self):
        """Each PUBLISHED attribute's reader of the kernel's memory (publish)."""
        views, link0 = self.views, self.contacts.link0
        state, rates = views["state"], views["rates"]

        def copy(array):
            return array.copy

        readers = {name: copy(views[name]) for name in (
            "u", "n", "seats", "seats_v", "pins", "pins_v", "wheels", "wheels_v",
            "compression", "compression_rate", "tyre_force", "ground_load", "tooth_gap",
            "generalized")}
        readers.update(
            qd=copy(rates.reshape(-1)), rates=copy(rates), body_pos=copy(state[:, :2]),
            hull=copy(state[0]), hull_v=copy(rates[0]), link_pos=copy(state[link0:, :2]),
            link_angle=copy(state[link0:, 2]), link_v=copy(rates[link0:, :2]),
            link_omega=copy(rates[link0:, 2]), idler=copy(state[link0 - 1, :2]),
            idler_v=copy(rates[link0 - 1, :2]),
            in_contact=lambda: views["compression"] > -np.inf,
            drive_torque=lambda: float(views["drive_torque"][0]))
        assert readers.keys() == set(PUBLISHED)
        self._readers = readers
        self._stale = frozenset(PUBLISHED).intersection

    def _triplets_buffer(self, rows):
        self.triplets_out = np.zeros((rows, 3))
        self._triplets_address = _pointer(self.triplets_out)  # converted once

    def triplets(self, factor, factor_t):
        """The Jacobian's (row, column, value) rows at the state last evaluated (a view of
        the kernel's buffer, valid until the next call)."""
        while True:
            out = self.triplets_out
            count = self.lib.contacts_jacobian(self.handle, factor, factor_t,
                                               self._triplets_address, len(out))
            if count <= len(out):
                return out[:count]
            self._triplets_buffer(2 * count)


def course_values(course):
    """(kind, values, (cosine weights, sine weights)) of `course` for contacts_set_course
    (contacts.h's enum Course and CourseValue): the numbers its height takes, computed as
    it computes them; COURSE_GIVEN for a course of another class."""
    kind = COURSE_KINDS.get(type(course), COURSE_GIVEN)
    none = np.zeros(0)
    values = [course.front, course.start, 1.0, 0.0, 1.0, 0.0, course.ceiling(), 0.0, 0.0] \
        if kind != COURSE_GIVEN else [0.0] * 9
    waves = (none, none)
    if kind == COURSE_KINDS[Bump]:
        values[2:4] = course.length, 0.5 * course.bump_height
    elif kind == COURSE_KINDS[Sine]:
        values[2:4] = course.wavelength, course.amplitude
    elif kind == COURSE_KINDS[RandomRoad]:
        waves = tuple(np.ascontiguousarray(a, dtype=float) for a in course.weights())
        values[4:6] = course.fade, course.offset()
        values[7:9] = course.k[0], course.k_step
    return kind, tuple(values), waves


def _pointer(array):
    return array.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
