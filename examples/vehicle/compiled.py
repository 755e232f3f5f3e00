"""The vehicle on the coupling's compiled path (examples/bank_path.py, docs/coupling.md "The
bank"): every FMU instance (tyres, dampers, bushes) in one bank, whose per-step work is in
C; each connector's force the compiled symbolic expression of its instance's load law,
read from the matrix the bank sets once per pass; the contacts read the tyres' laws from
the bank's arrays (Vehicle.tyre_loads). The same operations, in the same order, as the
Python path's (model.py), so that the two give the same numbers.

Installed after the settling to the static point, which runs on the relaxed components'
Python functions (model.RelaxedTable).
"""

import ctypes
from contextlib import contextmanager

import numpy as np

import bank_path
from fmu_components.coupling.bank_build import function_address

from . import joints as joints_kernel
from . import layout as lay
from .joints import Joints
from .model import HORN_HEIGHT, radial_fade, radial_pull


class _Deflections(ctypes.Structure):
    """deflections.c's Deflections."""
    _fields_ = [(name, ctypes.c_int) for name in ("links", "wheels", "tyres_per_wheel",
                                                  "dampers")] + \
               [("half", ctypes.c_double), ("out_of_contact", ctypes.c_double),
                ("hull_rotation", ctypes.c_int)] + \
               [(name, ctypes.c_void_p) for name in (
                   "link_index", "tyre_rows", "arm_rotation", "damper_rows", "radial_rows",
                   "torsion_rows", "reference", "offset", "still", "q_links", "link", "joint")]


class CompiledPath:
    def __init__(self, vehicle):
        self.v = v = vehicle
        mbs = v.mbs
        self.bank = bank_path.Bank(v.components, v.coupling.scheme.name, record=v._record)
        self.laws = bank_path.SymbolicLaws(self.bank)
        self._symbolic = []  # the compiled user functions live as long as the system
        rows = v.rows
        self.tyre_rows = np.array(rows["tyre"])
        self.damper_rows, self.radial_rows, self.torsion_rows = (
            np.array(rows[kind]) for kind in ("damper", "radial", "torsion"))
        links = v.link_nodes
        self.link_index = np.array([mbs.GetNodeODE2Index(n) for n in links])[:, None] + [0, 1, 2]
        self.hull_rotation = mbs.GetNodeODE2Index(v.hull_node) + 2
        self.arm_rotation = np.array([mbs.GetNodeODE2Index(v.arm_nodes[i - 1]) + 2
                                      for i in v.dampers])
        self.joints = v.joints or Joints(v)  # its reference and offsets, for the deflections
        self._deflections_kernel()
        self._compile_forces()

    def _deflections_kernel(self):
        """deflections.c over this path's rows and the joints' layout (arrays made once)."""
        lib = joints_kernel.library()
        if lib is None:
            raise RuntimeError("the compiled path's deflections need a C compiler (gcc)")
        if lib.deflections_layout() != ctypes.sizeof(_Deflections):
            raise RuntimeError("deflections.c and compiled.py disagree on the layout")
        lib.deflections.argtypes = [ctypes.c_void_p] * 4
        links = len(self.link_index)

        def ints(rows):
            return np.ascontiguousarray(rows, dtype=np.intc)

        self._arrays = arrays = [ints(self.link_index), ints(self.tyre_rows),
                                 ints(self.arm_rotation), ints(self.damper_rows),
                                 ints(self.radial_rows), ints(self.torsion_rows),
                                 np.ascontiguousarray(self.joints.reference, dtype=float),
                                 np.ascontiguousarray(self.joints.offset, dtype=float),
                                 np.zeros((links, 3)), np.zeros((links, 3)),
                                 np.zeros((links, 2)), np.zeros((links, 8))]
        self._layout = _Deflections(links, *self.tyre_rows.shape, len(self.damper_rows),
                                    0.5 * lay.LINK_PITCH, HORN_HEIGHT, self.hull_rotation,
                                    *(a.ctypes.data for a in arrays))
        self._lib, self._layout_at = lib, ctypes.addressof(self._layout)
        self._out = (None, None)  # the last array given to write into, and its address

    def deflections_entry(self):
        """(deflections.c's deflections' address, its layout's) for C that writes the
        deflections itself (own_pass.c): deflections(layout, q, compression, out)."""
        return function_address(self._lib.deflections), self._layout_at

    def _compile_forces(self):
        """Each connector's force the symbolic law of its instance (the Python path's
        functions in model.py, term for term), and the speed hold's."""
        laws, v, mbs = self.laws, self.v, self.v.mbs

        def radial(i):
            # the law of the seats' distance, along their line (exudyn's spring-damper),
            # faded in near zero distance as the Python path's (model.radial_fade)
            def radial_force(mbs, t, itemNumber, deltaL, deltaL_t, stiffness, damping, force):
                return (radial_pull(laws.load(i, deltaL), laws.esym.max)
                        * radial_fade(deltaL, laws.esym.min))
            return radial_force

        def coordinate(i, offset=None):
            def coordinate_force(mbs, t, itemNumber, displacement, velocity, stiffness,
                                 damping, offset_):
                return laws.load(i, displacement if offset is None else displacement + offset)
            return coordinate_force

        stiffness, damping = v.surge
        speed = v.speed

        def surge(mbs, t, itemNumber, displacement, velocity, stiffness_, damping_, offset_):
            return stiffness * (displacement - speed * t) + damping * (velocity - speed)

        functions = [(v.surge_connector, surge)]
        functions += [(c, coordinate(int(i))) for c, i in zip(v.damper_connectors,
                                                               self.damper_rows)]
        functions += [(c, radial(int(i))) for c, i in zip(v.radial_connectors,
                                                          self.radial_rows)]
        functions += [(c, coordinate(int(i), offset)) for (c, offset), i in
                      zip(v.torsion_connectors, self.torsion_rows)]
        for connector, function in functions:
            self._symbolic.append(bank_path.symbolic_function(mbs, connector, function))

    def initial_state(self):
        """(deflections, rates) at the run's start, from the Python path's readers (once):
        the bank starts relaxed there."""
        states = np.array([read() for _, read in self.v.coupling.entries], dtype=float)
        return states[:, 0], states[:, 1]

    def deflections(self, q=None, qd=None, t=None, out=None, evaluated=False, q_at=None):
        """Every instance's deflection from the system's coordinates, or from (q, qd) at t
        where they are given (a host of its own: own_host.py), in one pass (the Python
        path's readers, vectorised): a tyre's compression (contacts.py), a radial bush's
        distance between its pin seats, a torsion bush's and a damper's relative
        rotation. out: the array written (the bank's input, Bank.deflection, which
        end_pass then takes without a copy), else a new one. evaluated: the contacts'
        last evaluation is at (t, q, qd) with the present laws (Contacts.adopt took it).
        q_at: q's address where the caller has it (a float array, C order)."""
        v = self.v
        if q is None:
            data = v.mbs.systemData
            q, t = np.asarray(data.GetODE2Coordinates()), data.GetTime()
        if out is None:
            deflection = np.empty(self.bank.n)
            out_at = deflection.ctypes.data
        else:
            deflection = out
            if self._out[0] is not out:
                self._out = out, out.ctypes.data
            out_at = self._out[1]
        if not evaluated:
            v.contacts.evaluate(t, q, qd)
        compression, compression_at = v.contacts.last("compression")  # alive: the call
        if q_at is None:
            q = np.ascontiguousarray(q, dtype=float)
            q_at = q.ctypes.data
        # deflections.c: the joints' seat distances and relative angles as the joints'
        # kernel computes them (model._seat_deflection has the same distance)
        self._lib.deflections(self._layout_at, q_at, compression_at, out_at)
        return deflection


@contextmanager
def bank_in_use(vehicle):
    """The compiled path's bank the vehicle's for a run (its laws the contacts', its loads
    the records'), standing in for the Python coupling afterwards (its counts:
    Vehicle.solver_statistics); yields the CompiledPath."""
    path = vehicle.compiled_path
    vehicle.bank = path.bank
    try:
        yield path
    finally:
        vehicle.bank = None
        vehicle.coupling = path.bank


def solve_compiled(vehicle, end_time, step, settings, step_check=None):
    """The run on the compiled path; returns exudyn_host.solve's host."""
    with bank_in_use(vehicle) as path:
        return bank_path.solve(vehicle.mbs, path.bank, path.laws, path.deflections, end_time,
                               step, settings=settings, initial=path.initial_state,
                               step_check=step_check)
