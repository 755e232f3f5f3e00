"""The track's joints as one exudyn object: at each of the loop's joints a TrackBushRadial
(the law of the distance between the two links' pin seats, along their line, faded in
over the seats' first model.RADIAL_FADE) and a TrackBushTorsion (the law of the links'
relative angle plus its offset in the laid-out loop), their generalized forces on the
links' (x, y, angle) computed at once from the state, with their Jacobian (handed to
exudyn as sparse triplets), so that exudyn's Newton has the bushes' stiffness instead of
differentiating 160 connectors numerically.

Two kernels, one set of equations: `kinematics`, `forces` and `jacobian` below (numpy, the
readable reference and the fallback) and joints.c (compiled on first use, as the contacts'
kernel: bank_build.Library, -ffp-contract=off), the same operations in the same order.
The laws' loads and slopes come from the coupling's bank on the compiled path and from
the components on the Python path (Vehicle.load); while the vehicle settles, from their
relaxed tables. On the compiled path exudyn's force function is one C call
(joints_evaluate: kinematics, the bank's laws called from C through
Bank.law_loads_entry, forces) and its Jacobian function one more (`Joints.one_call`);
`evaluate` and `triplets`, three calls with Bank.law_loads, are the same operations
(tests/test_vehicle_joints.py: the same bits).
"""

import ctypes
from pathlib import Path

import numpy as np

import exudyn as exu
from exudyn.itemInterface import ObjectGenericODE2

from fmu_components.coupling.bank_build import Library

from . import layout as lay
from .law_slopes import load_and_slopes
from .model import RADIAL_FADE, radial_fade

HERE = Path(__file__).resolve().parent
# with the coupling's deflections on the compiled path (deflections.c: compiled.py), the
# step check (step_check.c: step_check.py) and the records' copies (records.c: outputs.py)
LIBRARY = Library("vehicle_joints", [HERE / name for name in ("joints.c", "deflections.c",
                                                              "step_check.c", "records.c")], [],
                  "the track joints' kernel (joints.c)", "the joints take their numpy kernel")
KERNELS = ("compiled", "numpy")


# --- the numpy kernel (joints.c's functions, operation for operation) -----------------------

def kinematics(reference, q, qd, offset):
    """(link, joint): each link's cos and sin; per joint j (link j - 1's front seat to link
    j's rear seat) the seats' separation dx, dy, distance, relative velocity wx, wy, the
    distance's rate, the torsion bush's angle (its offset added) and rate."""
    half = 0.5 * lay.LINK_PITCH
    x, y, angle = (reference + q).T
    cos, sin = np.cos(angle), np.sin(angle)
    front_x, front_y = x + cos * half, y + sin * half
    rear_x, rear_y = x + cos * -half, y + sin * -half
    dx = rear_x - np.roll(front_x, 1)
    dy = rear_y - np.roll(front_y, 1)
    distance = np.sqrt(dx * dx + dy * dy)
    vx, vy, omega = qd.T
    front_vx, front_vy = vx - omega * (sin * half), vy + omega * (cos * half)
    rear_vx, rear_vy = vx - omega * (sin * -half), vy + omega * (cos * -half)
    wx = rear_vx - np.roll(front_vx, 1)
    wy = rear_vy - np.roll(front_vy, 1)
    positive = distance > 0.0
    rate = np.where(positive, (dx * wx + dy * wy) / np.where(positive, distance, 1.0), 0.0)
    rotation = q[:, 2]
    angle = (rotation - np.roll(rotation, 1)) + offset
    return (np.stack([cos, sin], axis=1),
            np.stack([dx, dy, distance, wx, wy, rate, angle, omega - np.roll(omega, 1)],
                     axis=1))


def _arms(link):
    """Each joint's seat arms from their nodes: (link a's front seat, link b's rear)."""
    half = 0.5 * lay.LINK_PITCH
    behind = np.roll(link, 1, axis=0)  # joint j's link a = j - 1
    return behind * half, link * -half


def forces(link, joint, law):
    """(effort, generalized): per joint the radial force applied g = load * fade(L) and its
    slopes by L and by its rate; each link's generalized force (n x 3)."""
    distance = joint[:, 2]
    s = np.minimum(distance / RADIAL_FADE, 1.0)
    share = radial_fade(distance, np.minimum)
    share_slope = 2.0 * (1.0 - s) / RADIAL_FADE
    # the bush never pushes its seats apart (model.radial_pull): a load below zero is cut,
    # its slopes with it
    cut = law[:, 0] < 0.0
    load = np.where(cut, 0.0, law[:, 0])
    effort = np.stack([load * share, np.where(cut, 0.0, law[:, 1]) * share + load * share_slope,
                       np.where(cut, 0.0, law[:, 2]) * share], axis=1)
    length = np.where(distance > 0.0, distance, 1.0)
    ux, uy = effort[:, 0] * (joint[:, 0] / length), effort[:, 0] * (joint[:, 1] / length)
    torque = law[:, 3]
    ra, rb = _arms(link)
    as_b = np.stack([-ux, -uy, -(rb[:, 0] * uy - rb[:, 1] * ux) - torque], axis=1)
    as_a = np.stack([ux, uy, (ra[:, 0] * uy - ra[:, 1] * ux) + torque], axis=1)
    return effort, as_b + np.roll(as_a, -1, axis=0)


def jacobian(link, joint, qd, law, effort, factor, factor_t):
    """joints.c's joints_jacobian: per joint 36 (row, column, value) triplets of factor K
    + factor_t C over (link a's x, y, angle, link b's), row-major."""
    n = len(joint)
    ra, rb = _arms(link)
    zero, one = np.zeros(n), np.ones(n)
    B = np.stack([np.stack([-one, zero, ra[:, 1], one, zero, -rb[:, 1]], axis=1),
                  np.stack([zero, -one, -ra[:, 0], zero, one, rb[:, 0]], axis=1)], axis=1)
    distance = joint[:, 2]
    length = np.where(distance > 0.0, distance, 1.0)
    e0, e1 = joint[:, 0] / length, joint[:, 1] / length
    ratio, beta = joint[:, 5] / length, effort[:, 0] / length
    alpha = effort[:, 1] - beta
    wa, wb = np.roll(qd[:, 2], 1), qd[:, 2]
    He = np.zeros((n, 6))
    He[:, 2] = (wa * ra[:, 0]) * e0 + (wa * ra[:, 1]) * e1
    He[:, 5] = (-wb * rb[:, 0]) * e0 + (-wb * rb[:, 1]) * e1
    c = B[:, 0] * e0[:, None] + B[:, 1] * e1[:, None]
    Bw = B[:, 0] * joint[:, 3, None] + B[:, 1] * joint[:, 4, None]
    row = Bw / length[:, None] - ratio[:, None] * c + He
    BtB = B[:, 0, :, None] * B[:, 0, None, :] + B[:, 1, :, None] * B[:, 1, None, :]
    gv = effort[:, 2, None, None]
    K = (alpha[:, None, None] * c[:, :, None] * c[:, None, :] + beta[:, None, None] * BtB
         + gv * c[:, :, None] * row[:, None, :])
    C = gv * c[:, :, None] * c[:, None, :]
    ux, uy = effort[:, 0] * e0, effort[:, 0] * e1
    K[:, 2, 2] += ra[:, 0] * ux + ra[:, 1] * uy
    K[:, 5, 5] -= rb[:, 0] * ux + rb[:, 1] * uy
    for matrix, slope in ((K, law[:, 4]), (C, law[:, 5])):
        matrix[:, 2, 2] += slope
        matrix[:, 2, 5] -= slope
        matrix[:, 5, 2] -= slope
        matrix[:, 5, 5] += slope
    coordinate = 3 * np.stack([np.roll(np.arange(n), 1)] * 3 + [np.arange(n)] * 3,
                              axis=1) + np.tile(np.arange(3), 2)  # (joint, 6)
    rows = np.broadcast_to(coordinate[:, :, None], (n, 6, 6))
    columns = np.broadcast_to(coordinate[:, None, :], (n, 6, 6))
    return np.stack([rows, columns, factor * K + factor_t * C], axis=-1).reshape(-1, 3)


# --- the C kernel ----------------------------------------------------------------------------

def library():
    """joints.c's library, its functions declared; None where it cannot be built (with a
    warning saying why and what to use: bank_build.Library.load)."""
    lib = LIBRARY.load()
    if lib is not None and lib.joints_forces.argtypes is None:
        declare(lib)
    return lib


def declare(lib):
    """joints.c's functions' argument types on `lib` (its own library, or another that
    compiles joints.c in: system.py's)."""
    pointer, integer, real = ctypes.c_void_p, ctypes.c_int, ctypes.c_double
    lib.joints_kinematics.argtypes = [integer, real] + [pointer] * 6
    lib.joints_forces.argtypes = [integer, real, real] + [pointer] * 5
    lib.joints_jacobian.argtypes = [integer, real] + [pointer] * 5 + [real, real, pointer]
    lib.joints_bind.argtypes = [integer, real, real, pointer, pointer, integer, pointer,
                                pointer, pointer]
    lib.joints_bind.restype = pointer
    lib.joints_unbind.argtypes = [pointer]
    lib.joints_evaluate.argtypes = [pointer]
    lib.joints_evaluate_jacobian.argtypes = [pointer, real, real, pointer]


class CompiledJoints:
    """joints.c over arrays allocated once (their addresses taken once)."""

    def __init__(self, lib, reference, offset):
        n = len(reference)
        self.lib, self.n = lib, n
        self.arrays = {"reference": np.ascontiguousarray(reference, dtype=float),
                       "offset": np.ascontiguousarray(offset, dtype=float),
                       "q": np.zeros((n, 3)), "qd": np.zeros((n, 3)), "link": np.zeros((n, 2)),
                       "joint": np.zeros((n, 8)), "law": np.zeros((n, 6)),
                       "effort": np.zeros((n, 3)), "generalized": np.zeros((n, 3)),
                       "triplets": np.zeros((36 * n, 3))}
        self.at = {name: array.ctypes.data for name, array in self.arrays.items()}

    def kinematics(self, q, qd):
        a, at = self.arrays, self.at
        a["q"][:], a["qd"][:] = q, qd
        self.lib.joints_kinematics(self.n, 0.5 * lay.LINK_PITCH, at["reference"], at["q"],
                                   at["qd"], at["offset"], at["link"], at["joint"])
        return a["link"].copy(), a["joint"].copy()

    def forces(self, law):
        a, at = self.arrays, self.at
        a["law"][:] = law
        self.lib.joints_forces(self.n, 0.5 * lay.LINK_PITCH, RADIAL_FADE, at["link"],
                               at["joint"], at["law"], at["effort"], at["generalized"])
        return a["effort"].copy(), a["generalized"].copy()

    def jacobian(self, factor, factor_t, copy=True):
        """At the state and laws of the last forces() call (without `copy`, a view of the
        kernel's memory, valid until its next call)."""
        at = self.at
        self.lib.joints_jacobian(self.n, 0.5 * lay.LINK_PITCH, at["link"], at["joint"],
                                 at["qd"], at["law"], at["effort"], factor, factor_t,
                                 at["triplets"])
        triplets = self.arrays["triplets"]
        return triplets.copy() if copy else triplets

    # --- one call per evaluation: the bank's laws called from C (Bank.law_loads_entry) ----

    def bind(self, bank, radial_rows, torsion_rows):
        """Let joints_evaluate call `bank`'s laws (again where the bank is another one)."""
        if getattr(self, "_bank", None) is bank:
            return
        self.unbind()
        a = self.arrays
        a.update(radial_rows=np.ascontiguousarray(radial_rows, dtype=ctypes.c_int),
                 torsion_rows=np.ascontiguousarray(torsion_rows, dtype=ctypes.c_int),
                 deflection=np.zeros(bank.n), loads=np.zeros(bank.n), slopes=np.zeros(bank.n))
        self.at.update((name, a[name].ctypes.data) for name in (
            "radial_rows", "torsion_rows", "deflection", "loads", "slopes"))
        names = ("reference", "offset", "q", "qd", "link", "joint", "law", "effort",
                 "generalized", "deflection", "loads", "slopes")
        self._bound_arrays = (ctypes.c_void_p * len(names))(*(self.at[n] for n in names))
        self.bound = self.lib.joints_bind(self.n, 0.5 * lay.LINK_PITCH, RADIAL_FADE,
                                          *bank.law_loads_entry(), bank.n,
                                          self.at["radial_rows"], self.at["torsion_rows"],
                                          self._bound_arrays)
        if not self.bound:
            raise MemoryError("the vehicle's joints kernel: out of memory")
        self._bank = bank
        self._generalized = a["generalized"].reshape(-1)
        self._q, self._qd = a["q"].reshape(-1), a["qd"].reshape(-1)  # views
        self._triplets_at = self.at["triplets"]

    def unbind(self):
        if getattr(self, "bound", None):
            self.lib.joints_unbind(self.bound)
        self.bound, self._bank = None, None

    def __del__(self):
        self.unbind()

    def evaluate_once(self, q, qd):
        """The links' generalized forces at (q, qd: 3 n each, exudyn's lists or arrays),
        one C call (kinematics, the bound bank's laws, forces): a view of the kernel's
        memory, valid until its next call. q and qd are written into the arrays the kernel
        reads (the cheapest conversion of exudyn's lists: docs/vehicle.md)."""
        self._q[:], self._qd[:] = q, qd
        self.lib.joints_evaluate(self.bound)
        return self._generalized

    def jacobian_once(self, q, qd, factor, factor_t):
        """The triplets at (q, qd) with the bound bank's laws, one C call (evaluated
        again there, then joints_jacobian): a view of the kernel's memory."""
        self._q[:], self._qd[:] = q, qd
        self.lib.joints_evaluate_jacobian(self.bound, factor, factor_t, self._triplets_at)
        return self.arrays["triplets"]


class Joints:
    """The vehicle's 80 joints (radial and torsion bush) as one exudyn generic ODE2 object
    over the links, with the coupling's readers of their deflections."""

    def __init__(self, vehicle):
        self.v = v = vehicle
        mbs = v.mbs
        self.reference = np.array([mbs.GetNodeParameter(node, "referenceCoordinates")
                                   for node in v.link_nodes], dtype=float)
        self.offset = np.asarray(v.torsion_offsets, dtype=float)
        self.radial_rows, self.torsion_rows = (np.array(v.rows[kind])
                                               for kind in ("radial", "torsion"))
        self.kernel, self._compiled, self._reading, self._once = "numpy", None, None, None
        if library() is not None:  # the three-call path's, the readers', the one-call path's
            self.kernel = "compiled"
            self._compiled, self._reading, self._once = (
                CompiledJoints(library(), self.reference, self.offset) for _ in range(3))
        self._key, self._read_key = None, None
        self._deflection = np.zeros(len(v.components))

    def add_object(self):
        v = self.v
        size = 3 * len(v.link_nodes)
        massless = exu.MatrixContainer()
        massless.SetWithSparseMatrix(np.zeros((0, 3)), size, size)
        v.mbs.AddObject(ObjectGenericODE2(
            nodeNumbers=list(v.link_nodes), massMatrix=massless,
            forceUserFunction=lambda mbs, t, item, q, qd: self.generalized(q, qd),
            jacobianUserFunction=lambda mbs, t, item, q, qd, f, f_t:
                self._sparse_jacobian(q, qd, f, f_t)))

    def use(self, kernel):
        """Evaluate with `kernel`: "compiled" (C, where it builds) or "numpy"."""
        if kernel not in KERNELS or (kernel == "compiled" and self._compiled is None):
            raise ValueError(f"joints kernel {kernel!r}: 'numpy', or 'compiled' where gcc is")
        self.kernel = kernel

    def index(self):
        """After Assemble: where the links' coordinates sit in the system's vectors."""
        mbs = self.v.mbs
        self.system_index = np.concatenate([mbs.GetNodeODE2Index(n) + np.arange(3)
                                            for n in self.v.link_nodes])

    # --- evaluation ----------------------------------------------------------------------------

    def kinematics(self, q, qd, kernel=None):
        """(link, joint) at the links' coordinates (q, qd): module `kinematics`'s."""
        q, qd = np.reshape(q, (-1, 3)), np.reshape(qd, (-1, 3))
        if self.kernel == "compiled":
            return (kernel or self._reading).kinematics(q, qd)
        return kinematics(self.reference, q, qd, self.offset)

    def laws(self, joint):
        """(n x 6) the radial law's load and its slopes by deflection and by rate at each
        joint's distance and rate, then the torsion law's at its angle and rate."""
        v, law = self.v, np.zeros((len(joint), 6))
        if v.bank is not None:  # the compiled path: the bank's laws, one call (rate-free)
            deflection = self._deflection
            deflection[self.radial_rows] = joint[:, 2]
            deflection[self.torsion_rows] = joint[:, 6]
            loads, slopes = v.bank.law_loads(deflection, slopes=True)
            law[:, 0], law[:, 1] = loads[self.radial_rows], slopes[self.radial_rows]
            law[:, 3], law[:, 4] = loads[self.torsion_rows], slopes[self.torsion_rows]
            return law
        for column, components, x, rate in ((0, v.radial, joint[:, 2], joint[:, 5]),
                                            (3, v.torsion, joint[:, 6], joint[:, 7])):
            for j, component in enumerate(components):
                law[j, column:column + 3] = load_and_slopes(v, component, float(x[j]),
                                                            float(rate[j]))
        return law

    def _laws_key(self):
        """What decides the laws now, where it is cheap to tell (None: not told)."""
        v = self.v
        if v.bank is not None:  # they change between the coupling's passes
            return v.bank.laws.tobytes()
        return "relaxed" if v.settling else None

    def evaluate(self, q, qd):
        """(link, joint, law, effort, generalized) at the links' coordinates (q, qd); once
        per state and laws where the laws can be told apart (exudyn asks for the forces
        and then the Jacobian at each Newton iterate)."""
        # exudyn's vectors converted once (a conversion costs about what the kernel does)
        q, qd = np.asarray(q, dtype=float), np.asarray(qd, dtype=float)
        laws = self._laws_key()
        key = (q.tobytes(), qd.tobytes(), self.kernel, laws)
        if laws is not None and key == self._key:
            return self._evaluated
        link, joint = self.kinematics(q, qd, self._compiled)
        law = self.laws(joint)
        if self.kernel == "compiled":
            effort, generalized = self._compiled.forces(law)
        else:
            effort, generalized = forces(link, joint, law)
        self._key, self._evaluated = key, (link, joint, law, effort, generalized)
        return self._evaluated

    def one_call(self):
        """The C kernel bound to the bank's laws where the compiled path runs (the bank
        present, the C kernel in use): one C call per evaluation; else None."""
        bank = self.v.bank
        if bank is None or self.kernel != "compiled":
            return None
        self._once.bind(bank, self.radial_rows, self.torsion_rows)
        return self._once

    def generalized(self, q, qd):
        """The links' generalized forces at (q, qd) (exudyn's force function; on the
        one-call path a view of the kernel's memory, valid until its next call)."""
        once = self.one_call()
        if once is not None:
            return once.evaluate_once(q, qd)
        return self.evaluate(q, qd)[-1].reshape(-1)

    def last_forces(self):
        """(joint, law, effort) of the last force evaluation, copies: the radial force the
        kernel applied (effort[:, 0], the law's load cut and faded) beside the law's load
        (law[:, 0]), read where they were computed (the energy audit: energy.py)."""
        once = self.one_call()
        if once is not None:
            return tuple(once.arrays[name].copy() for name in ("joint", "law", "effort"))
        _, joint, law, effort, _ = self._evaluated
        return joint.copy(), law.copy(), effort.copy()

    def triplets(self, q, qd, factor, factor_t, copy=True):
        """The Jacobian's (row, column, value) rows at (q, qd): exudyn's factor K +
        factor_t C, K and C minus the forces' derivatives by q and by qd."""
        link, joint, law, effort, _ = self.evaluate(q, qd)
        if self.kernel == "compiled":
            return self._compiled.jacobian(factor, factor_t, copy)
        return jacobian(link, joint, np.reshape(qd, (-1, 3)), law, effort, factor, factor_t)

    def jacobian(self, q, qd, factor, factor_t):
        """exudyn's Jacobian function's triplets (`triplets`; on the one-call path
        evaluated with it in one C call): a view of the kernel's memory."""
        once = self.one_call()
        if once is not None:
            return once.jacobian_once(q, qd, factor, factor_t)
        return self.triplets(q, qd, factor, factor_t, copy=False)

    def _sparse_jacobian(self, q, qd, factor, factor_t):
        size = 3 * len(self.v.link_nodes)
        matrix = exu.MatrixContainer()  # copies the triplets
        matrix.SetWithSparseMatrix(self.jacobian(q, qd, factor, factor_t), size, size)
        return matrix

    # --- the coupling's readers ----------------------------------------------------------------

    def state(self, j, kind):
        """(deflection, rate) of joint j's radial or torsion bush at the host's current
        state (the Python path's readers; one evaluation per state)."""
        data = self.v.mbs.systemData
        q = np.asarray(data.GetODE2Coordinates())[self.system_index]
        qd = np.asarray(data.GetODE2Coordinates_t())[self.system_index]
        key = (q.tobytes(), qd.tobytes(), self.kernel)
        if key != self._read_key:
            self._read_key, self._read = key, self.kinematics(q, qd)[1]
        deflection, rate = (2, 5) if kind == "radial" else (6, 7)
        return float(self._read[j, deflection]), float(self._read[j, rate])

