"""The tracked vehicle's energy account (examples/vehicle/energy.py, docs/vehicle.md "The
radial bush never pushes"): the radial bushes' work as the host applied it (their law's
load cut at zero) apart from what the cut removed, the stored energy the balance
subtracts, and the account a short run keeps."""

import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'


def _history(distance, law, applied, fmu):
    """An account as audited_run keeps it (steps x joints), the FMUs' deflection the
    kernel's distance."""
    return {"radial_distance": distance, "radial_law": law, "radial_applied": applied,
            "radial_fmu": fmu, "radial_deflection": distance}


def test_the_radial_account_splits_the_applied_work_from_what_the_cut_removed():
    """A joint stretched from 40 to 60 um with a law load of k (L - 50 um) (-1 to +1 kN),
    applied cut at zero, its FMU's load 5 N above the law's; a second joint at a steady
    tension. The trapezoids are exact on these piecewise-linear loads (the crossing on a
    step): applied k (10 um)^2 / 2 = 5 mJ, cut -5 mJ, the FMUs' 5 N x 20 um = 0.1 mJ; 10 of
    42 joint-steps cut, the lowest load -1 kN at step 0, joint 0."""
    from vehicle.energy import radial_account

    stiffness = 1e8
    stretch = np.linspace(40e-6, 60e-6, 21)
    distance = np.stack([stretch, np.full(21, 160e-6)], axis=1)
    law = np.stack([stiffness * (stretch - 50e-6), np.full(21, 13e3)], axis=1)
    account = radial_account(_history(distance, law, np.maximum(law, 0.0), law + 5.0))
    assert account["applied"] == pytest.approx(5e-3, rel=1e-9)
    assert account["cut"] == pytest.approx(-5e-3, rel=1e-9)
    assert account["fmu"] == pytest.approx(1e-4, rel=1e-6)
    assert account["share_cut"] == pytest.approx(10 / 42)
    assert account["lowest"] == (pytest.approx(-1e3), 0, 0)
    # back again: the cut's work changes sign with the motion, the loop closes
    there_and_back = _history(*(np.concatenate([a, a[::-1][1:]]) for a in (
        distance, law, np.maximum(law, 0.0), law)))
    back = radial_account(there_and_back)
    assert abs(back["applied"]) < 1e-15 and abs(back["cut"]) < 1e-15


def test_the_stored_energy_is_the_bodies_and_the_linear_springs():
    """Stored of a small exudyn system: a rigid body (mass 2, inertia 3)
    at height 1.5 + 0.25 moving at (0.3, -0.4, 2) rad/s on a linear spring-damper of its
    angle (k 50, offset 0.1, damping 7) and one with a user function (not counted):
    1/2 m v^2 + 1/2 J w^2 + m g y + 1/2 k (angle - offset)^2, loss d w^2."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    import exudyn as exu
    from exudyn.itemInterface import (MarkerNodeCoordinate, NodePointGround,
                                      NodeRigidBody2D, ObjectConnectorCoordinateSpringDamper,
                                      ObjectRigidBody2D)
    from vehicle.energy import Stored
    from vehicle.layout import GRAVITY

    SC = exu.SystemContainer()
    mbs = SC.AddSystem()
    ground = mbs.AddNode(NodePointGround())
    node = mbs.AddNode(NodeRigidBody2D(referenceCoordinates=[1.0, 1.5, 0.0],
                                       initialCoordinates=[0.0, 0.25, 0.4],
                                       initialVelocities=[0.3, -0.4, 2.0]))
    mbs.AddObject(ObjectRigidBody2D(mass=2.0, inertia=3.0, nodeNumber=node))
    markers = [mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=n, coordinate=c))
               for n, c in ((ground, 0), (node, 2))]
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(markerNumbers=markers, stiffness=50.0,
                                                        damping=7.0, offset=0.1))
    mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
        markerNumbers=markers, springForceUserFunction=lambda mbs, t, i, x, v, *_: 1e3 * x))
    mbs.Assemble()

    class Host:
        pass

    host = Host()
    host.mbs = mbs
    energy, loss = Stored(host)()
    expected = (0.5 * 2.0 * (0.3 ** 2 + 0.4 ** 2) + 0.5 * 3.0 * 2.0 ** 2
                + 2.0 * GRAVITY * 1.75 + 0.5 * 50.0 * (0.4 - 0.1) ** 2)
    assert energy == pytest.approx(expected, rel=1e-12)
    assert loss == pytest.approx(7.0 * 2.0 ** 2, rel=1e-12)


def test_a_short_audited_run_keeps_the_loads_the_host_applied(native_fmus):
    """Ten host steps of 0.5 ms from the laid-out loop at 5 m/s on the compiled path (the
    law's load falls below zero at a few joint-steps, to about -5.7 kN): the account's
    radial distances are the accepted deflections the coupling read, its applied forces
    the kernel's (the law's load cut at zero: none below it, zero wherever the law's load
    is below zero); the radial bushes' applied work differs from the FMUs' loads' by what
    the cut removed and the coupling's mismatch alone (0.17 J of 40 J moved); and the
    balance closes: the audited forces' work on the bodies (201 J out of them) less the
    bushes', dampers' and linear dampers' and the stored energy's change leaves 1.2 J,
    the integrator's dissipation and the trapezoids' error over the start's transient
    (17.6 J at 1 ms steps)."""
    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.energy import audited_run, radial_account, window_account
    from vehicle.model import Vehicle

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
    time, power, account, result, error = audited_run(vehicle, 0.005, 5e-4)
    assert error is None and len(time) >= 11 and time[-1] == pytest.approx(0.005)
    assert account["evaluated_at_record"] <= 1  # the start's record at most
    assert np.array_equal(account["radial_distance"][1:], result["bush_radial_deflection"][1:])
    applied, law = account["radial_applied"], account["radial_law"]
    assert np.any(law < 0.0) and np.all(applied >= 0.0)
    assert np.all(applied[law < 0.0] == 0.0)
    far = account["radial_distance"] > 5e-6  # beyond the fade: the law's load as it is
    assert np.array_equal(applied[far & (law >= 0.0)], law[far & (law >= 0.0)])
    split = radial_account(account)
    scale = np.sum(np.abs(np.diff(account["radial_distance"], axis=0))
                   * np.abs(account["radial_fmu"][1:]))
    assert abs(split["fmu"] - split["applied"] - split["cut"]) < 0.02 * scale
    whole = window_account(time, power, account, 0, len(time) - 1)
    assert abs(whole["bodies"]) > 100.0
    assert abs(whole["balance"]) < 0.01 * abs(whole["bodies"])


def test_the_audit_refuses_a_vehicle_set_to_the_own_solver():
    """The audit reads the joints' forces of exudyn's last residual: a vehicle set to the
    own solver (tracked_vehicle.py's default) is refused before anything runs, naming
    exudyn's."""
    from types import SimpleNamespace

    pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.energy import audited_run

    with pytest.raises(ValueError, match=r"run it on exudyn's \(vehicle.solver = 'exudyn'\)"):
        audited_run(SimpleNamespace(solver="own"), 0.005, 5e-4)
