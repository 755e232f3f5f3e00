"""The vehicle's static point: solved once by a damped dynamic solve (every component at
its relaxed load, docs/multibody-examples.md: static equilibrium) and stored, keyed by
everything that decides it, so that later runs start settled at no cost.

exudyn's static solver does not converge on the loop from its laid-out geometry (the
links' rotations, held only by the bushes and the contacts, run away in its first
iterations), so the vehicle settles in time with heavy damping on every body
(settle_damping.py), in chunks, until every velocity is below REST.
"""

import hashlib
import json
from pathlib import Path

import numpy as np

import exudyn as exu

from fmu_components.coupling.bank_build import cache_directory

from example_fmus import fmu_path

from . import contact_math, contacts, contacts_kernel, joints, layout, model, settle_damping

REST = 0.02  # m/s, rad/s: settled when no coordinate moves faster (a slow creep of the
# front arm and the pitch remains, decaying by about 7 % per 0.1 s)
CHUNK = 0.1  # s of settling between checks
FMUS = ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion", "RotaryDamper")


def _constants(module):
    return {name: repr(value) for name, value in vars(module).items()
            if name.isupper() and isinstance(value, (int, float, tuple, dict))}


def static_key(vehicle, step):
    """A digest of what decides the static point: the model's values and code (every
    constant and the source of layout, model, contacts and joints, and which kernels),
    the FMUs' files, the linear elements if any, the static values the layout was made
    from, and the settling's own step and rest."""
    files = {name: hashlib.sha256(Path(fmu_path(name, vehicle.fmu_dir)).read_bytes())
             .hexdigest() for name in FMUS}
    linear = vehicle.linear.coefficients if vehicle.linear is not None else None
    sources = [hashlib.sha256(Path(m.__file__).read_bytes()).hexdigest()
               for m in (layout, model, contacts, contact_math, joints, settle_damping)]
    # the kernels that settle it (contacts, joints), and the C kernels' sources
    sources += [vehicle.contacts.kernel, contacts_kernel.LIBRARY.source_tag(),
                vehicle.joint_elements, vehicle.joints and vehicle.joints.kernel,
                joints.LIBRARY.source_tag()]
    content = json.dumps([_constants(layout), _constants(model), _constants(contacts),
                          _constants(settle_damping), sources,
                          files, repr(linear), repr(vehicle.statics), step, REST, CHUNK],
                         sort_keys=True)
    return hashlib.sha256(content.encode()).hexdigest()[:16]


def stored_path(vehicle, step):
    return cache_directory() / f"vehicle_static_{static_key(vehicle, step)}.npy"


def settle(vehicle, longest=2.0, step=2e-3, store=True):
    """Bring the vehicle to its static point (from the store if solved before): the
    settled coordinates become the initial state. Returns the settling time it took
    (0.0 from the store)."""
    mbs = vehicle.mbs
    data = mbs.systemData
    velocities = data.GetODE2Coordinates_t(exu.ConfigurationType.Initial)
    path = stored_path(vehicle, step)
    settled, duration = None, 0.0
    if store and path.exists():
        settled = np.load(path)
    else:
        data.SetODE2Coordinates_t(0 * velocities, exu.ConfigurationType.Initial)
        while duration < longest - 1e-9:
            _settle_chunk(vehicle, min(CHUNK, longest - duration), step)
            duration += CHUNK
            settled = data.GetODE2Coordinates(exu.ConfigurationType.Current)
            moving = np.max(np.abs(data.GetODE2Coordinates_t(exu.ConfigurationType.Current)))
            data.SetODE2Coordinates(settled, exu.ConfigurationType.Initial)
            data.SetODE2Coordinates_t(0 * velocities, exu.ConfigurationType.Initial)
            if moving < REST:
                break
        else:
            raise model.VehicleError(f"the static point: still moving at {moving:.2g} m/s "
                                     f"after {longest:g} s of settling; give --settle-time "
                                     f"more")
        if store:
            path.parent.mkdir(parents=True, exist_ok=True)
            np.save(path, np.asarray(settled))
    data.SetODE2Coordinates(settled, exu.ConfigurationType.Initial)
    data.SetODE2Coordinates_t(velocities, exu.ConfigurationType.Initial)
    vehicle.contacts.rebase(settled)
    return duration


def _settle_chunk(vehicle, duration, step):
    settings = exu.SimulationSettings()
    settings.timeIntegration.verboseMode = model.VERBOSE
    settings.solution.file.write = False
    settings.solution.sensors.active = False
    settings.timeIntegration.endTime = duration
    settings.timeIntegration.numberOfSteps = int(round(duration / step))
    settings.timeIntegration.generalizedAlpha.spectralRadius = 0.0
    model.configure(settings)
    vehicle.settling = True
    try:
        if not vehicle.mbs.SolveDynamic(settings,
                                        solverType=exu.DynamicSolverType.GeneralizedAlpha):
            raise model.VehicleError("the static point: exudyn's solver failed settling the "
                                     "vehicle at rest")
    finally:
        vehicle.settling = False
