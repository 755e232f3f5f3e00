"""The vehicle's check of each solve's solution against its step's start
(exudyn_host's `step_check`): a solution that jumps is refused and the step retried
shorter (docs/vehicle.md, The bush's fade and the step check).

exudyn's Newton can converge, within one step, on a solution no motion in that step gives:
a link on the ground turning 21 deg and moving 47 mm through a wheel in 1 ms (the radial
bushes and the contacts give a step several solutions). Such a solution moves a body
further than its velocity at the step's start and any physical acceleration carry it in
the step. What is compared, beyond the motion at the start's velocity (generalized-alpha
moves a coordinate by h v0 plus h^2 times a mean of the step's accelerations):

* each link's centre and angle: more than LINK_JUMP or LINK_TURN (at 1 ms, 20 000 m/s2:
  300 kN on a 15 kg link, several times the largest wheel load; and 1.7e5 rad/s2);
* each tyre's compression (both ends of the step in contact): more than TYRE_JUMP (its
  static compression, 3.2 mm, in one step);
* each pin's gap to its sprocket tooth space (engaged at both ends): more than TOOTH_JUMP
  (50 kN of tooth load at the teeth's 5 MN/m): a tooth skipped.

The thresholds do not shrink with a shortened step: a jump stays a jump. The steps of a
run at 5 m/s measured 2.5 to 18 times below them (docs/vehicle.md).

The rule is step_check.c's (in the joints' library, compiled on first use), one call per
part a pass; links_verdict and contacts_verdict below are its numpy reference, operation
for operation (the same verdicts and values to the bit: tests/test_vehicle_step_check.py),
and the fallback without a compiler.
"""

import ctypes
import math

import numpy as np

import exudyn as exu

from fmu_components.coupling.bank_build import function_address

from . import joints as joints_kernel
from . import layout as lay
from .contacts_kernel import index_or_slice

LINK_JUMP = 0.01  # m
LINK_TURN = math.radians(5.0)
TYRE_JUMP = 3.2e-3  # m
TOOTH_JUMP = 0.01  # m
# what jumped (step_check.c's enum): nothing, a link, a tyre's compression, a pin's gap
PASSED, LINK, TYRE, TOOTH = range(4)


class _Layout(ctypes.Structure):
    """step_check.c's StepCheckLayout."""
    _fields_ = [("links", ctypes.c_int), ("wheels", ctypes.c_int)] + \
               [(name, ctypes.c_double) for name in ("link_jump", "link_turn", "tyre_jump",
                                                     "tooth_jump")] + \
               [("link_index", ctypes.c_void_p)]


# --- the rule in numpy: the reference of step_check.c, operation for operation -------------

def _argmax(values):
    """numpy's argmax (the first NaN, else the first largest), as step_check.c picks."""
    return int(np.argmax(values))


def links_verdict(h, q1, q0, v0, links, count):
    """(LINK, k, (moved, turned)) for the link k that moved or turned beyond LINK_JUMP or
    LINK_TURN (the largest by them) beyond its motion h v0 at the step's start, else
    (PASSED, -1, ()); `links`: the links' (x, y, angle) in q, `count` of them."""
    beyond = (q1[links] - q0[links] - h * v0[links]).reshape(count, 3)
    moved = np.hypot(beyond[:, 0], beyond[:, 1])
    turned = np.abs(beyond[:, 2])
    k = _argmax(np.maximum(moved / LINK_JUMP, turned / LINK_TURN))
    if moved[k] > LINK_JUMP or turned[k] > LINK_TURN:
        return LINK, k, (float(moved[k]), float(turned[k]))
    return PASSED, -1, ()


def contacts_verdict(h, compression1, gap1, compression0, rate0, gap0):
    """(TYRE, w, (jump,)) for the wheel w in contact at both ends (compression above -inf)
    whose compression jumped beyond TYRE_JUMP past h times its rate at the start (the
    largest), else (TOOTH, j, (skip,)) for the pin j engaged at both ends (gap above 0)
    whose gap to its tooth space jumped beyond TOOTH_JUMP, else (PASSED, -1, ())."""
    jump = np.abs(compression1 - compression0 - h * rate0)
    jump = np.where((compression0 > -np.inf) & (compression1 > -np.inf), jump, 0.0)
    w = _argmax(jump)
    if jump[w] > TYRE_JUMP:
        return TYRE, w, (float(jump[w]),)
    skip = np.where((gap0 > 0.0) & (gap1 > 0.0), np.abs(gap1 - gap0), 0.0)
    j = _argmax(skip)
    if skip[j] > TOOTH_JUMP:
        return TOOTH, j, (float(skip[j]),)
    return PASSED, -1, ()


class _CompiledCheck:
    """step_check.c over the check's layout (its arrays and addresses made once)."""

    def __init__(self, lib, links, wheels):
        lib.step_check_links.argtypes = [ctypes.c_void_p, ctypes.c_double] + \
            [ctypes.c_void_p] * 4
        lib.step_check_contacts.argtypes = [ctypes.c_void_p, ctypes.c_double] + \
            [ctypes.c_void_p] * 6
        if lib.step_check_layout() != ctypes.sizeof(_Layout):
            raise RuntimeError("step_check.c and step_check.py disagree on the layout")
        self.lib = lib
        self.index = np.ascontiguousarray(np.ravel(links), dtype=np.intc)
        self.layout = _Layout(len(self.index) // 3, wheels, LINK_JUMP, LINK_TURN, TYRE_JUMP,
                              TOOTH_JUMP, self.index.ctypes.data)
        self.at = ctypes.addressof(self.layout)
        self.found = np.zeros(3)
        self.found_at = self.found.ctypes.data

    def links(self, h, q1, q0, v0):
        return found(self.lib.step_check_links(self.at, h, q1, q0, v0, self.found_at),
                     self.found)

    def contacts(self, h, *arrays):
        return found(self.lib.step_check_contacts(self.at, h, *arrays, self.found_at),
                     self.found)


def found(kind, values):
    """step_check.c's verdict as links_verdict's and contacts_verdict's: (kind, index,
    values) from its kind and its array `found`."""
    if kind == PASSED:
        return PASSED, -1, ()
    return kind, int(values[0]), tuple(float(x) for x in values[1:3 if kind == LINK else 2])


def _reals(array):
    return np.ascontiguousarray(array, dtype=float)


class StepCheck:
    def __init__(self, vehicle, kernel=None):
        """kernel: "compiled" (step_check.c, in the joints' library) or "numpy" (the
        reference); default compiled where it builds."""
        self.v = vehicle
        mbs = vehicle.mbs
        links = np.array([mbs.GetNodeODE2Index(n) for n in vehicle.link_nodes])[:, None] \
            + [0, 1, 2]
        # the links' coordinates: a slice (a view) where they are one run, as exudyn has them
        self.links = index_or_slice(links)
        self.link_count = len(links)
        self.reference = np.array([mbs.GetNodeParameter(n, "referenceCoordinates")
                                   for n in vehicle.link_nodes], dtype=float)
        wheels = len(vehicle.contacts.wheel_offset)
        # the contacts' values at the last accepted step: compression, its rate, tooth gap
        self._start = [np.zeros(wheels), np.zeros(wheels), np.zeros(self.link_count)]
        self.start = None  # those arrays, once an accepted step has set them
        lib = joints_kernel.library() if kernel != "numpy" else None
        self._compiled = _CompiledCheck(lib, links, wheels) if lib is not None else None
        if self._compiled is not None:
            self._start_at = [a.ctypes.data for a in self._start]

    def accepted(self):
        """Keep the contacts' values at the accepted state (the records evaluated them)."""
        c = self.v.contacts
        for kept, name in zip(self._start, ("compression", "compression_rate", "tooth_gap")):
            kept[:] = c.last(name)[0]
        self.start = self._start

    def __call__(self, mbs, t):
        """None where the solution in exudyn's data (the exudyn run's, at t) is one the
        step can reach, else what jumped (judge)."""
        data = mbs.systemData
        start = exu.ConfigurationType.StartOfStep
        return self.judge(t, t - data.GetTime(start), np.asarray(data.GetODE2Coordinates()),
                          None, np.asarray(data.GetODE2Coordinates(start)),
                          np.asarray(data.GetODE2Coordinates_t(start)))

    def judge(self, t, h, q1, v1, q0, v0, evaluated=False, addresses=None):
        """None where the solution q1, v1 at t (v1 None: exudyn's current velocities) is
        one the step of length h from q0, v0 can reach, else what jumped: the links first
        (links_verdict), then, from the second accepted step on, the contacts evaluated at
        the solution (contacts_verdict), in step_check.c where it builds. evaluated: the
        contacts' last evaluation is at the solution with the present laws (the own host's
        Contacts.adopt took it). addresses: q1's, q0's and v0's where the caller has them
        (float arrays, C order)."""
        compiled, contacts = self._compiled, self.v.contacts
        if compiled is not None:
            if addresses is None:
                q1, q0, v0 = (_reals(a) for a in (q1, q0, v0))
                addresses = q1.ctypes.data, q0.ctypes.data, v0.ctypes.data
            kind, k, values = compiled.links(h, *addresses)
        else:
            kind, k, values = links_verdict(h, q1, q0, v0, self.links, self.link_count)
        if kind == LINK:
            return self.message(kind, k, values, q1)
        if self.start is None:
            return None
        if not evaluated:  # the coupling's deflections use this evaluation
            contacts.evaluate(t, q1, v1)
        compression, compression_at = contacts.last("compression")
        gap, gap_at = contacts.last("tooth_gap")
        if compiled is not None:
            kind, k, values = compiled.contacts(h, compression_at, gap_at, *self._start_at)
        else:
            kind, k, values = contacts_verdict(h, compression, gap, *self.start)
        return self.message(kind, k, values, q1)

    def message(self, kind, k, values, q1):
        """The verdict (kind, index, values: links_verdict's, contacts_verdict's) on the
        solution q1 in words, None where nothing jumped (a tyre's: at the contacts' last
        evaluation, the solution's)."""
        if kind == LINK:
            moved, turned = values
            return (f"link {k}{self._where(k, q1[self.links][3 * k:3 * k + 3])} moved "
                    f"{moved * 1e3:.1f} mm and turned {math.degrees(turned):.1f} deg "
                    f"in one step beyond its motion at the step's start")
        if kind == TYRE:
            compression = self.v.contacts.last("compression")[0]
            return (f"road wheel {k + 1}: its tyre's compression jumped by "
                    f"{values[0] * 1e3:.1f} mm in one step (to "
                    f"{compression[k] * 1e3:.1f} mm)")
        if kind == TOOTH:
            return (f"joint {k}: its pin's gap to its sprocket tooth space jumped by "
                    f"{values[0] * 1e3:.1f} mm in one step (a tooth skipped)")
        return None

    def entries(self):
        """(step_check_links's address, step_check_contacts's, the layout's, the start's
        compression's, rate's and tooth gap's) for C that checks itself (own_pass.c,
        which then gives `message` its verdict: found); None where the check runs its
        numpy reference."""
        compiled = self._compiled
        if compiled is None:
            return None
        return (*(function_address(f) for f in (
            compiled.lib.step_check_links, compiled.lib.step_check_contacts)),
            compiled.at, *self._start_at)

    def _where(self, k, moved):
        """Which road wheel link k is beneath, where one is within a link's pitch."""
        centre = self.reference[k, :2] + moved[:2]
        wheels = self.v.contacts.wheels  # at the contacts' last evaluation
        distance = np.hypot(*(wheels - centre).T)
        w = int(np.argmin(distance))
        if distance[w] > lay.WHEEL_RADIUS + lay.LINK_PITCH:
            return ""
        return f" (beneath road wheel {w + 1})"
