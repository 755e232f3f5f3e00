"""The units engineers read on the plots and reports: (factor from SI, unit) of each
component's deflection, load and rate."""

from ..runtime.units import DEG

DISPLAY = {
    "RoadWheelTyre": ((1e3, "mm"), (1e-3, "kN"), (1e3, "mm/s")),
    "TrackBushRadial": ((1e3, "mm"), (1e-3, "kN"), (1e3, "mm/s")),
    "TrackBushTorsion": ((DEG, "deg"), (1.0, "N.m"), (DEG, "deg/s")),
    # The damper as the thesis reports it: Table 11.2-1 in rad, Table A6-1 in rad/s.
    "RotaryDamper": ((1.0, "rad"), (1.0, "N.m"), (1.0, "rad/s")),
}
