"""The run's step check (examples/vehicle/step_check.py) on the sprocket's teeth: each part
tests its largest value first, and a value beyond its threshold still gets the full
comparison and the message naming the joint. (Links and tyres: tests/test_vehicle.py.)"""

import re
import sys

import numpy as np
import pytest

from conftest import ROOT

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

NO_EXUDYN = 'exudyn is not installed: pip install -e ".[examples]"'


def test_a_pin_whose_tooth_space_jumps_is_refused_naming_the_joint(native_fmus):
    """From the laid-out state, the track at 5 m/s, a step of 1 ms: the state its start's
    velocities carry it to passes; the hull moved 20 mm further (the sprocket's tooth
    spaces with it, past the engaged pins, which stay) is refused as a tooth skipped, the
    links and the tyres within their thresholds."""
    exu = pytest.importorskip("exudyn", reason=NO_EXUDYN)
    from vehicle.course import Bump
    from vehicle.model import Vehicle
    from vehicle.step_check import TOOTH_JUMP, StepCheck

    vehicle = Vehicle(Bump(3.0), 5.0, native_fmus["RoadWheelTyre"].parent)
    vehicle.settling = True
    try:
        mbs, contacts = vehicle.mbs, vehicle.contacts
        data = mbs.systemData
        current, start = exu.ConfigurationType.Current, exu.ConfigurationType.StartOfStep
        q0 = np.array(data.GetODE2Coordinates(current))
        v0 = np.array(data.GetODE2Coordinates_t(exu.ConfigurationType.Initial))
        data.SetODE2Coordinates(q0, start)
        data.SetODE2Coordinates_t(v0, start)
        data.SetODE2Coordinates_t(v0, current)
        data.SetTime(0.1, start)
        check = StepCheck(vehicle)
        contacts.evaluate(0.1)
        check.accepted()
        engaged = np.flatnonzero(contacts.tooth_gap > 0.0)
        assert len(engaged) > 0

        def judged(hull_x):
            q = q0 + 1e-3 * v0
            q[mbs.GetNodeODE2Index(vehicle.hull_node)] += hull_x
            data.SetODE2Coordinates(q, current)
            return check(mbs, 0.101)

        assert judged(0.0) is None
        message = judged(0.02)
        found = re.fullmatch(r"joint (\d+): its pin's gap to its sprocket tooth space jumped "
                             r"by ([\d.]+) mm in one step \(a tooth skipped\)", message)
        assert found, message
        assert int(found.group(1)) in engaged and float(found.group(2)) > TOOTH_JUMP * 1e3
    finally:
        vehicle.coupling.free()
