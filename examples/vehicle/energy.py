"""The energy audit of the vehicle's contacts: the power each class of contact force puts
into the bodies (tyres, pins on the ground, sprocket teeth, idler, roller), the speed
hold's, and the sprocket's split into the drive (the tooth spaces turning relative to the
hull), its springs' stored energy and its dampers' loss. A passive contact puts no net
energy in; what the drive puts in, the bushes' and dampers' losses take out
(benchmarks/vehicle_energy.py, docs/vehicle.md)."""

import numpy as np


class Audit:
    """Kept by Contacts._forces while set as `contacts.audit`: `power` by class (W) at the
    state last evaluated."""

    def __init__(self):
        self.power, self._last = {}, None

    def begin(self):
        self.power, self._last = {}, None

    def mark(self, name, contacts, pin, bodies):
        """The power of the forces added to `pin` and `bodies` since the last mark."""
        last_pin, last_bodies = self._last or (0.0, 0.0)
        self._last = pin.copy(), bodies.copy()
        generalized = bodies - last_bodies
        contacts.onto_links(generalized, contacts.onto_seats(pin - last_pin))
        self.power[name] = float(generalized.reshape(-1) @ contacts.qd)

    def sprocket(self, tooth_force, stored, damped, drive_velocity):
        """The drive's power (the tooth forces on the tooth spaces' motion relative to the
        hull), the teeth's stored energy (J) and their dampers' loss (W)."""
        self.power["drive"] = float(np.sum(tooth_force * drive_velocity))
        self.power["sprocket_stored"] = float(np.sum(stored))
        self.power["sprocket_damped"] = float(np.sum(damped))


def audited_run(vehicle, end_time, step):
    """Runs the vehicle (settled) with the audit at every accepted step; returns (time,
    {class: power}, histories, the VehicleError's text or None)."""
    from .model import VehicleError

    contacts, rows = vehicle.contacts, []
    record = vehicle._record

    def audited(t):
        record(t)
        contacts.audit, contacts._key = Audit(), None
        contacts.evaluate(t)
        power = dict(contacts.audit.power)
        contacts.audit, contacts._key = None, None
        x, rate = contacts.hull[0] - contacts.reference[0, 0], contacts.hull_v[0]
        stiffness, damping = vehicle.surge
        power["speed hold"] = -(stiffness * (x - vehicle.speed * t)
                                + damping * (rate - vehicle.speed)) * rate
        rows.append((t, power))

    vehicle.prepare()
    vehicle.coupling.record = audited
    if vehicle.compiled_path is not None:
        vehicle.compiled_path.bank.record = audited
    error = None
    try:
        vehicle.run(end_time, step, settle=False)
    except VehicleError as stop:
        error = str(stop)
    from .outputs import histories
    time = np.array([t for t, _ in rows])
    power = {key: np.array([p[key] for _, p in rows]) for key in rows[0][1]}
    return time, power, histories(vehicle), error
