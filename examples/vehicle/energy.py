"""The energy audit of the vehicle: the power each class of contact force puts into the
bodies (tyres, pins on the ground, sprocket teeth, idler, roller), the speed hold's, and
the sprocket's split into the drive (the tooth spaces turning relative to the hull), its
springs' stored energy and its dampers' loss; the work the host's forces do on the bushes
(the radial bush's load as applied: cut at zero, model.radial_pull) and the dampers; the
energy the bodies and the linear springs hold. A passive contact puts no net energy in;
what the drive puts in, the bushes' and dampers' losses take out, and what is left is the
change of the stored energy (benchmarks/vehicle_energy.py, docs/vehicle.md)."""

import numpy as np

from fmu_components.coupling.exudyn_host import connector_state

# the classes of force whose power on the bodies the audit keeps (the drive is a part of
# the sprocket's)
ON_BODIES = ("tyres", "ground", "sprocket", "idler", "roller", "speed hold")


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


class Stored:
    """The energy the bodies and the linear springs hold (J) and the linear dampers' loss
    (W) at the host's current state: every rigid body's kinetic energy and gravity's
    potential (its node at its centre of mass), and the connectors that are exudyn's own
    linear spring-dampers (no user function: the torsion bars, the tensioner)."""

    def __init__(self, vehicle):
        mbs = self.mbs = vehicle.mbs
        objects = [mbs.GetObject(i) for i in range(mbs.systemData.NumberOfObjects())]
        bodies = [o for o in objects if o["objectType"] == "RigidBody2D"]
        for o in bodies:
            if np.any(o["centerOfMass"]):
                raise ValueError(f"body {o['name']!r}: centre of mass {o['centerOfMass']} "
                                 f"off its node; the audit's energies take the node as "
                                 f"the centre: put the node there")
        nodes = [o["nodeNumber"] for o in bodies]
        self.index = np.array([mbs.GetNodeODE2Index(n) for n in nodes])[:, None] + [0, 1, 2]
        self.height = np.array([mbs.GetNodeParameter(n, "referenceCoordinates")[1]
                                for n in nodes])
        self.mass = np.array([o["mass"] for o in bodies])
        self.inertia = np.array([o["inertia"] for o in bodies])
        self.springs = [(i, o["stiffness"], o["damping"], o["offset"])
                        for i, o in enumerate(objects)
                        if o["objectType"] == "ConnectorCoordinateSpringDamper"
                        and isinstance(o["springForceUserFunction"], int)]

    def __call__(self):
        """(stored energy, linear dampers' loss)."""
        from .layout import GRAVITY

        data = self.mbs.systemData
        q = np.asarray(data.GetODE2Coordinates())[self.index]
        qd = np.asarray(data.GetODE2Coordinates_t())[self.index]
        energy = float(np.sum(0.5 * self.mass * (qd[:, 0] ** 2 + qd[:, 1] ** 2)
                              + 0.5 * self.inertia * qd[:, 2] ** 2
                              + self.mass * GRAVITY * (self.height + q[:, 1])))
        loss = 0.0
        for connector, stiffness, damping, offset in self.springs:
            x, v = (float(np.ravel(value)[0]) for value in connector_state(self.mbs, connector))
            energy += 0.5 * stiffness * (x - offset) ** 2
            loss += damping * v * v
        return energy, loss


def work(force, deflection):
    """Work done on elements (J) from their accepted histories (steps x elements):
    trapezoids in the deflection, summed over steps and elements."""
    force, deflection = np.asarray(force), np.asarray(deflection)
    return float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(deflection, axis=0)))


def radial_account(account):
    """The radial bushes' work (J) over an audited stretch: `applied`, the host's (the
    kernel's force: the law's load cut at zero and faded in, model.radial_pull and
    radial_fade); `cut`, what the law's loads below zero would have done, which the cut
    removed; `fmu`, the FMUs' recorded loads' (what the audit read before the cut: their
    difference from applied + cut is the coupling's mismatch of law and FMU, and the
    fade); where the cut acted: the share of joint-steps whose law load is below zero and
    the lowest load (N, step, joint)."""
    law, distance = account["radial_law"], account["radial_distance"]
    lowest = np.unravel_index(np.argmin(law), law.shape)
    return {"applied": work(account["radial_applied"], distance),
            "cut": work(np.minimum(law, 0.0), distance),
            "fmu": work(account["radial_fmu"], account["radial_deflection"]),
            "share_cut": float(np.mean(law < 0.0)),
            "lowest": (float(law[lowest]), int(lowest[0]), int(lowest[1]))}


def window_account(time, power, account, a, b):
    """The account (J) from step a to step b of an audited run: the radial bushes'
    (radial_account), the work done on the torsion bushes by their laws' torque (applied)
    and by their FMUs' (torsion_fmu), on the dampers by their FMUs' torque, the linear
    dampers' loss, the change of the stored energy, the work of the audited forces on the
    bodies, and the balance: that work less the bushes', dampers' and linear dampers' and
    the change of the stored energy, with the loads applied and with the FMUs' (the
    account before the cut). What remains in it is the integrator's own dissipation
    (generalized-alpha's numerical damping) and the trapezoids' error."""
    span = slice(a, b + 1)
    part = {key: value[span] for key, value in account.items() if isinstance(value, np.ndarray)}
    t = time[span]
    result = radial_account(part)
    result.update(
        torsion=work(part["torsion_applied"], part["torsion_angle"]),
        torsion_fmu=work(part["torsion_fmu"], part["torsion_deflection"]),
        dampers=work(part["damper_torque"], part["damper_angle"]),
        linear=float(np.trapezoid(power["linear dampers"][span], t)),
        stored=float(part["stored"][-1] - part["stored"][0]),
        bodies=sum(float(np.trapezoid(power[c][span], t)) for c in ON_BODIES))
    result["balance"] = (result["bodies"] - result["applied"] - result["torsion"]
                         - result["dampers"] - result["linear"] - result["stored"])
    result["balance_fmu"] = (result["balance"] + result["applied"] - result["fmu"]
                             + result["torsion"] - result["torsion_fmu"])
    return result


def audited_run(vehicle, end_time, step):
    """Runs the vehicle (settled) with the audit at every accepted step, in exudyn (a
    vehicle set to another solver is refused); returns (time,
    {class: power}, account, histories, the VehicleError's text or None). `account`, per
    step: the radial bushes' distance, law load, applied force (the joints' kernel's, as
    its last force evaluation left them: the accepted state's) and the FMUs' load and
    deflection; the torsion bushes' angle and applied torque (the kernel's: their laws'),
    their FMUs' torque and angle; the dampers' FMU torque and angle; the stored energy
    and the linear dampers' loss (Stored)."""
    from .model import VehicleError

    if vehicle.solver != "exudyn":
        raise ValueError(f"the energy audit reads the joints' forces of exudyn's last "
                         f"residual, which the {vehicle.solver} solver's Newton does not "
                         f"evaluate: run it on exudyn's (vehicle.solver = 'exudyn')")
    joints = vehicle.joints
    if joints is None:
        raise ValueError("the energy audit reads the joints' kernel: build the Vehicle "
                         "with joints='kernel'")
    contacts, rows, kept = vehicle.contacts, [], []
    record, stored = vehicle._record, Stored(vehicle)
    radial, torsion, dampers = (vehicle.rows[kind] for kind in ("radial", "torsion", "damper"))
    stale = [0]

    def audited(t):
        # the joints' last evaluation, before the record evaluates anything: exudyn's
        # last residual of the accepted pass, at its state with its laws
        joint, law, effort = joints.last_forces()
        record(t)
        loads, deflections = vehicle.accepted()
        if not np.array_equal(joint[:, 2], deflections[radial]):
            # none yet at this state (the run's start): evaluated here, the laws now
            stale[0] += 1
            data = vehicle.mbs.systemData
            index = joints.system_index
            joints.generalized(np.asarray(data.GetODE2Coordinates())[index],
                               np.asarray(data.GetODE2Coordinates_t())[index])
            joint, law, effort = joints.last_forces()
        contacts.audit, contacts._key = Audit(), None
        contacts.evaluate(t)
        power = dict(contacts.audit.power)
        contacts.audit, contacts._key = None, None
        x, rate = contacts.hull[0] - contacts.reference[0, 0], contacts.hull_v[0]
        stiffness, damping = vehicle.surge
        power["speed hold"] = -(stiffness * (x - vehicle.speed * t)
                                + damping * (rate - vehicle.speed)) * rate
        energy, power["linear dampers"] = stored()
        rows.append((t, power))
        kept.append({"radial_distance": joint[:, 2], "radial_law": law[:, 0],
                     "radial_applied": effort[:, 0], "radial_fmu": loads[radial],
                     "radial_deflection": deflections[radial], "torsion_angle": joint[:, 6],
                     "torsion_applied": law[:, 3], "torsion_fmu": loads[torsion],
                     "torsion_deflection": deflections[torsion], "damper_torque": loads[dampers],
                     "damper_angle": deflections[dampers], "stored": energy})

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
    account = {key: np.array([k[key] for k in kept]) for key in kept[0]}
    account["evaluated_at_record"] = stale[0]
    return time, power, account, histories(vehicle), error
