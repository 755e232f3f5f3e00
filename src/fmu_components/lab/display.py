"""The units engineers read on the plots and reports: (factor from SI, unit) of each
component's deflection, load and rate. Every angle is in deg and every torque in N.m, the
torsion bush's and the damper's alike, so that plots of the two read the same way."""

from ..runtime.units import DEG

DISPLAY = {
    "RoadWheelTyre": ((1e3, "mm"), (1e-3, "kN"), (1e3, "mm/s")),
    "TrackBushRadial": ((1e3, "mm"), (1e-3, "kN"), (1e3, "mm/s")),
    "TrackBushTorsion": ((DEG, "deg"), (1.0, "N.m"), (DEG, "deg/s")),
    # (The thesis gives the damper's tests in rad, Table 11.2-1, and rad/s, Table A6-1.)
    "RotaryDamper": ((DEG, "deg"), (1.0, "N.m"), (DEG, "deg/s")),
}
