"""The vehicle on the coupling's compiled path (examples/bank_path.py, docs/coupling.md "The
bank"): every FMU instance (tyres, dampers, bushes) in one bank, whose per-step work is in
C; each connector's force the compiled symbolic expression of its instance's load law,
read from the matrix the bank sets once per pass; the contacts read the tyres' laws from
the bank's arrays (Vehicle.tyre_loads). The same operations, in the same order, as the
Python path's (model.py), so that the two give the same numbers.

Installed after the settling to the static point, which runs on the relaxed components'
Python functions (model.RelaxedTable).
"""

from contextlib import contextmanager

import numpy as np

import bank_path

from .contacts_kernel import index_or_slice
from .joints import Joints
from .model import HORN_HEIGHT, radial_fade, radial_pull


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
        link_index = np.array([mbs.GetNodeODE2Index(n) for n in links])[:, None] + [0, 1, 2]
        self.link_index, self.link_shape = index_or_slice(link_index), link_index.shape
        self.still = np.zeros(link_index.shape)  # the joints' rates, unread here
        self.hull_rotation = mbs.GetNodeODE2Index(v.hull_node) + 2
        self.arm_rotation = np.array([mbs.GetNodeODE2Index(v.arm_nodes[i - 1]) + 2
                                      for i in v.dampers])
        self.joints = v.joints or Joints(v)  # its kinematics, for the deflections
        self._compile_forces()

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

    def deflections(self, q=None, qd=None, t=None):
        """Every instance's deflection from the system's coordinates, or from (q, qd) at t
        where they are given (a host of its own: own_host.py), in one pass (the Python
        path's readers, vectorised): a tyre's compression (contacts.py), a radial bush's
        distance between its pin seats, a torsion bush's and a damper's relative
        rotation."""
        v = self.v
        if q is None:
            data = v.mbs.systemData
            q, t = np.asarray(data.GetODE2Coordinates()), data.GetTime()
        deflection = np.empty(self.bank.n)
        v.contacts.evaluate(t, q, qd)
        compression = np.where(v.contacts.in_contact, v.contacts.compression, -HORN_HEIGHT)
        deflection[self.tyre_rows] = compression[:, None]
        deflection[self.damper_rows] = q[self.hull_rotation] - q[self.arm_rotation]
        # the joints' seat distances and relative angles, as the joints' object computes
        # them (joints.py; model._seat_deflection has the same distance)
        joint = self.joints.kinematics(q[self.link_index].reshape(self.link_shape),
                                       self.still)[1]
        deflection[self.radial_rows] = joint[:, 2]
        deflection[self.torsion_rows] = joint[:, 6]
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
