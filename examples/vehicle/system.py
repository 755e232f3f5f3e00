"""The whole vehicle's equations in C, outside exudyn (system.c): at (t, q, v), q and v in
exudyn's own ODE2 order, the generalized forces f, the revolute joints' equations g
(index 3), K = -df/dq and D = -df/dv as triplets, G = dg/dq, the multipliers' force's
derivative d(G^T lambda)/dq and the constant mass diagonal: the vehicle's side of an own
implicit solver of M a = f - G^T lambda, g = 0 (docs/vehicle.md, The vehicle's equations
in C), and `ordering`, the unknowns' order for its bordered-band LU.

Built from the exudyn model that model.Vehicle made (its items read back: every rigid
body, coordinate spring-damper, revolute joint, mass-proportional load and generic
object, an item of another kind refused), with the model's own C kernels (contacts.c,
joints.c, compiled into this library) and the coupling bank's laws (bank.c, through a
Bank or a LawTable: `laws`), as the compiled path evaluates them.
"""

import ctypes
from pathlib import Path

import numpy as np

from fmu_components.coupling.bank_build import Library

from . import contacts_kernel, joints
from . import layout as lay

HERE = Path(__file__).resolve().parent
LIBRARY = Library("vehicle_system",
                  [HERE / name for name in ("system.c", "joints.c", "contacts.c",
                                            "contacts_forces.c", "contacts_jacobian.c",
                                            "contacts_course.c")],
                  [HERE / "contacts.h"], "the vehicle's equations in C (system.c)",
                  "evaluate the vehicle in exudyn")
CAPACITY = 16384  # triplets of one Jacobian (grown where a state has more)


class _Spring(ctypes.Structure):
    """system.c's CoordinateSpring."""
    _fields_ = [("a", ctypes.c_int), ("b", ctypes.c_int), ("row", ctypes.c_int),
                ("stiffness", ctypes.c_double), ("damping", ctypes.c_double),
                ("offset", ctypes.c_double), ("drift", ctypes.c_double)]


class _Revolute(ctypes.Structure):
    """system.c's Revolute."""
    _fields_ = [("index", ctypes.c_int * 2), ("local", (ctypes.c_double * 2) * 2)]


class _System(ctypes.Structure):
    """system.c's VehicleSystem."""
    _fields_ = [(name, ctypes.c_int) for name in ("n", "m", "bodies", "links", "springs",
                                                  "revolutes")] + \
               [(name, ctypes.c_void_p) for name in ("reference", "mass", "gravity",
                                                     "contacts", "body_index", "joints")] + \
               [("half", ctypes.c_double)] + \
               [(name, ctypes.c_void_p) for name in ("link_index", "joint_arrays", "spring",
                                                     "revolute", "band_position")] + \
               [("half_bandwidth", ctypes.c_int), ("left_out", ctypes.c_long),
                ("left_out_largest", ctypes.c_double)]


def library():
    """system.c's library (the contacts' and joints' kernels in it), declared; None where
    it cannot be built."""
    lib = LIBRARY.load("the vehicle's equations in C are not available")
    if lib is not None and lib.vsystem_residual.argtypes is None:
        contacts_kernel.declare(lib)
        joints.declare(lib)
        pointer, real = ctypes.c_void_p, ctypes.c_double
        lib.vsystem_residual.argtypes = [pointer, real] + [pointer] * 4
        lib.vsystem_constraints.argtypes = [pointer] * 3
        lib.vsystem_jacobian.argtypes = [pointer, real, pointer, pointer, real, real, pointer,
                                         ctypes.c_long, pointer]
        lib.vsystem_jacobian.restype = ctypes.c_long
        lib.vsystem_constraint_jacobian.argtypes = [pointer] * 5
        lib.vsystem_mass.argtypes = [pointer] * 2
        if lib.vsystem_layout() != ctypes.sizeof(_System):
            raise RuntimeError("system.c and system.py disagree on the system's layout")
    return lib


def _at(array):
    return array.ctypes.data


class VehicleSystem:
    """The vehicle `vehicle` (model.Vehicle, its joints as one object: joints="kernel")
    with the load laws of `laws` (a bank, or a LawTable of one moment): residual,
    jacobian, constraint_jacobian, mass."""

    def __init__(self, vehicle, laws):
        lib = library()
        if lib is None:
            raise RuntimeError("no C compiler: the vehicle's equations in C need gcc")
        if vehicle.joints is None:
            raise ValueError("the vehicle's equations in C take the joints as one object "
                             "(joints='kernel')")
        self.lib, self.v, self.laws = lib, vehicle, laws
        mbs = vehicle.mbs
        n = len(mbs.systemData.GetODE2Coordinates())
        self.n = n
        self.reference = np.zeros(n)
        self.mass, self.gravity = np.full(n, np.nan), np.zeros(n)
        springs, revolutes = [], []
        self._read_items(mbs, springs, revolutes)
        if np.isnan(self.mass).any():
            raise ValueError("a coordinate without a rigid body's mass")
        self.m = 2 * len(revolutes)
        self.revolute_nodes = [nodes for nodes, _ in revolutes]
        # the contacts' kernel and the joints' over this library, bound to `laws`
        self.contacts = contacts_kernel.CompiledContacts(vehicle.contacts, lib)
        self.contacts._set_course(vehicle.course)
        self.contacts._set_tyre_laws(laws)
        joint_kernel = vehicle.joints
        self.joints = joints.CompiledJoints(lib, joint_kernel.reference, joint_kernel.offset)
        self.joints.bind(laws, joint_kernel.radial_rows, joint_kernel.torsion_rows)
        self.body_index = np.ascontiguousarray(vehicle.contacts.system_index, dtype=np.intc)
        self.link_index = np.ascontiguousarray(joint_kernel.system_index, dtype=np.intc)
        names = ("q", "qd", "link", "joint", "law", "effort", "generalized", "deflection",
                 "loads", "slopes")
        self._joint_arrays = (ctypes.c_void_p * len(names))(*(self.joints.at[k] for k in names))
        self._springs = (_Spring * len(springs))(*springs)
        self._revolutes = (_Revolute * len(revolutes))(
            *(_Revolute((ctypes.c_int * 2)(*index), ((ctypes.c_double * 2) * 2)(
                *((ctypes.c_double * 2)(*p) for p in local))) for _, (index, local) in
              revolutes))
        self.system = _System(
            n, self.m, len(vehicle.contacts.nodes), len(vehicle.link_nodes), len(springs),
            len(revolutes), _at(self.reference), _at(self.mass), _at(self.gravity),
            self.contacts.handle, _at(self.body_index), self.joints.bound,
            0.5 * lay.LINK_PITCH, _at(self.link_index),
            ctypes.cast(self._joint_arrays, ctypes.c_void_p).value,
            ctypes.addressof(self._springs), ctypes.addressof(self._revolutes))
        self.handle = ctypes.addressof(self.system)
        self.f, self.g = np.zeros(n), np.zeros(self.m)
        self._triplets(CAPACITY)

    def _read_items(self, mbs, springs, revolutes):
        """The model's items as system.c's: masses, gravity, coordinate springs,
        revolute joints; the generic objects must be the contacts' and the joints'."""
        v = self.v
        coordinate = {}  # node -> its first ODE2 index (None: the ground's)
        for node in range(mbs.systemData.NumberOfNodes()):
            item = mbs.GetNode(node)
            if item["nodeType"] == "PointGround":
                coordinate[node] = None
                continue
            if item["nodeType"] != "RigidBody2D":
                raise ValueError(f"node {node}: {item['nodeType']} is not in system.c")
            index = mbs.GetNodeODE2Index(node)
            coordinate[node] = index
            self.reference[index:index + 3] = item["referenceCoordinates"]
        node_of_body = {}
        damper_rows = dict(zip(map(int, v.damper_connectors), v.rows["damper"]))
        generic = {tuple(map(int, v.contacts.nodes)), tuple(map(int, v.link_nodes))}

        def marker_coordinate(marker):
            item = mbs.GetMarker(marker)
            base = coordinate[int(item["nodeNumber"])]
            return -1 if base is None else base + item["coordinate"]

        for number in range(mbs.systemData.NumberOfObjects()):
            item = mbs.GetObject(number)
            kind = item["objectType"]
            if kind == "RigidBody2D":
                index = coordinate[int(item["nodeNumber"])]
                if np.any(item["centerOfMass"]):
                    raise ValueError(f"body {number}: a centre of mass off its node")
                node_of_body[number] = int(item["nodeNumber"])
                self.mass[index:index + 3] = item["mass"], item["mass"], item["inertia"]
            elif kind == "ConnectorCoordinateSpringDamper":
                a, b = map(marker_coordinate, item["markerNumbers"])
                if number == int(v.surge_connector):  # k (x - speed t) + c (x' - speed)
                    stiffness, damping = v.surge
                    springs.append(_Spring(a, b, -1, stiffness, damping, 0.0, v.speed))
                elif number in damper_rows:  # the bank's law of the arm's rotation
                    springs.append(_Spring(a, b, damper_rows[number], 0.0, 0.0, 0.0, 0.0))
                elif item["springForceUserFunction"] == 0:
                    springs.append(_Spring(a, b, -1, item["stiffness"], item["damping"],
                                           item["offset"], 0.0))
                else:
                    raise ValueError(f"connector {number}: a force function system.c lacks")
            elif kind == "JointRevolute2D":
                ends = [mbs.GetMarker(m) for m in item["markerNumbers"]]
                if any(e["markerType"] != "BodyPosition" for e in ends):
                    raise ValueError(f"joint {number}: markers other than body positions")
                nodes = [node_of_body[int(e["bodyNumber"])] for e in ends]
                revolutes.append((nodes, ([coordinate[node] for node in nodes],
                                          [e["localPosition"][:2] for e in ends])))
            elif kind == "GenericODE2":
                if tuple(map(int, item["nodeNumbers"])) not in generic:
                    raise ValueError(f"generic object {number}: not the contacts' or joints'")
            else:
                raise ValueError(f"object {number}: {kind} is not in system.c")
        for load in range(mbs.systemData.NumberOfLoads()):
            item = mbs.GetLoad(load)
            marker = mbs.GetMarker(item["markerNumber"])
            if item["loadType"] != "MassProportional" or marker["markerType"] != "BodyMass":
                raise ValueError(f"load {load}: {item['loadType']} is not in system.c")
            index = coordinate[node_of_body[int(marker["bodyNumber"])]]
            self.gravity[index:index + 2] += self.mass[index] * np.asarray(
                item["loadVector"][:2])

    def _triplets(self, capacity):
        self.triplets_out = np.zeros((capacity, 3))
        self._scratch = np.zeros((capacity, 3))

    # --- the equations --------------------------------------------------------------------

    def residual(self, t, q, v):
        """(f, g) at (t, q, v): views of arrays overwritten by the next call."""
        q, v = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float)
        self.lib.vsystem_residual(self.handle, t, _at(q), _at(v), _at(self.f), _at(self.g))
        return self.f, self.g

    def jacobian(self, t, q, v, factor=1.0, factor_t=0.0):
        """factor K + factor_t D (K = -df/dq, D = -df/dv) at (t, q, v) as (row, column,
        value) rows, repeated entries adding, zeros left out (a view, overwritten by the
        next call)."""
        q, v = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(v, dtype=float)
        while True:
            out = self.triplets_out
            count = self.lib.vsystem_jacobian(self.handle, t, _at(q), _at(v), factor,
                                              factor_t, _at(out), len(out), _at(self._scratch))
            if count <= len(out):
                return out[:count]
            self._triplets(2 * count)

    def keep_band(self, order, half_bandwidth, border):
        """From now on leave out of `jacobian` the entries that fall neither in the band
        nor in the border of `ordering`'s order (the few a tyre's blend writes beyond
        REACH), counted: left_out()."""
        position = positions(order).astype(np.intc)
        position[position >= len(order) - border] = -1
        self._band_position = np.ascontiguousarray(position[:self.n])
        self.system.band_position = _at(self._band_position)
        self.system.half_bandwidth = half_bandwidth

    def left_out(self):
        """(count, largest magnitude) of the Jacobian's entries keep_band left out."""
        return int(self.system.left_out), float(self.system.left_out_largest)

    def coordinate_name(self, index):
        """What unknown `index` is (a link's, the hull's, an arm's or the idler's crank's
        x, y or angle, or a revolute joint's multiplier), for messages."""
        if index >= self.n:
            return f"revolute joint {(index - self.n) // 2}'s multiplier {(index - self.n) % 2}"
        for indices, names in ((self.link_index, lambda k: f"link {k}"),
                               (self.body_index, self._body_name)):
            slots = np.flatnonzero(indices == index)
            if len(slots):
                return f"{names(slots[0] // 3)}'s {('x', 'y', 'angle')[slots[0] % 3]}"
        return f"coordinate {index}"

    def _body_name(self, body):  # the contacts' bodies: the hull, the arms, the crank
        arms = len(self.v.arm_nodes)
        return ("the hull" if body == 0 else f"arm {body}" if body <= arms
                else "the idler's crank")

    def constraint_jacobian(self, q, multipliers=None):
        """(G, H): G = dg/dq as (row, column, value) rows, and where `multipliers` are
        given H = d(G^T lambda)/dq (else None)."""
        q = np.ascontiguousarray(q, dtype=float)
        G, H = np.zeros((6 * self.m, 3)), np.zeros((self.m, 3))
        lam = None if multipliers is None else np.ascontiguousarray(multipliers, dtype=float)
        self.lib.vsystem_constraint_jacobian(self.handle, _at(q),
                                             None if lam is None else _at(lam), _at(G),
                                             _at(H))
        return G, (None if lam is None else H)

    def mass_diagonal(self):
        mass = np.zeros(self.n)
        self.lib.vsystem_mass(self.handle, _at(mass))
        return mass


# The loop's reach: an element's nonzero entries couple a link with its neighbours in the
# loop (a joint joins two; a pin's contacts load its joint's two links; a tyre's blend
# weighs the links beneath a wheel, each link's window fading over contacts.HANDOVER about
# each of its joints, so that its term depends on the directions of the neighbours at the
# ends it fades at). That reach is 1 except under a wheel over two sharp bends in a row
# (the foot of the bump at 5 m/s: two joints bent some 21 degrees each): there the wheel
# sits within HANDOVER / 2 of both bisectors of a link, whose term then moves with both of
# its neighbours, two links apart. The band is kept at REACH 1 (docs/vehicle.md, The
# vehicle on its own solver: reach 2 would widen it for entries that are rare and some
# 1e-5 of the Newton matrix's diagonal) and the solver's Jacobian leaves entries beyond it
# out, counted (VehicleSystem.keep_band): an inexact Newton matrix, an exact residual.
REACH = 1


def ordering(system, border_link=0):
    """The unknowns' order for a bordered-band LU: (order, half_bandwidth, border).
    `order[p]` is the unknown at position p (0 to n - 1 the coordinates, n to n + m - 1 the
    multipliers): first the band, the links in loop order from the one after `border_link`
    round to the one before it, 3 coordinates each; then the border, its last `border`
    positions: the hull, the arms, the crank, `border_link` (which breaks the loop) and
    the multipliers. Within the band an entry (i, j) has |p_i - p_j| <= half_bandwidth."""
    links = system.link_index.reshape(-1, 3)
    count = len(links)
    band = np.concatenate([links[(border_link + 1 + k) % count] for k in range(count - 1)])
    rest = np.setdiff1d(np.arange(system.n), system.link_index)
    order = np.concatenate([band, rest, links[border_link],
                            system.n + np.arange(system.m)]).astype(int)
    return order, 3 * REACH + 2, len(order) - len(band)


def positions(order):
    """Each unknown's position in `order` (its inverse permutation)."""
    position = np.empty(len(order), dtype=int)
    position[order] = np.arange(len(order))
    return position


def outside_band(order, half_bandwidth, border, rows, columns):
    """The entries (rows[k], columns[k]) that fall neither in the band nor in the border
    of `ordering`'s order: their indices (none where the order holds)."""
    position = positions(order)
    p, q = position[np.asarray(rows, dtype=int)], position[np.asarray(columns, dtype=int)]
    in_border = (p >= len(order) - border) | (q >= len(order) - border)
    return np.flatnonzero(~in_border & (np.abs(p - q) > half_bandwidth))


def dense(triplets, rows, columns=None):
    """The matrix of (row, column, value) rows, repeated entries added."""
    columns = rows if columns is None else columns
    r, c, values = np.asarray(triplets).T
    return np.bincount((r * columns + c).astype(int), values,
                       minlength=rows * columns).reshape(rows, columns)
