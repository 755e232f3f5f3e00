"""SI units of the FMU variables, with the display units engineers read them in.

Each entry: unit name -> (SI base-unit exponents, [(display unit, factor)]), where a
display value is factor * SI value (FMI 2.0 section 2.2.2).
"""

import math

DEG = 180.0 / math.pi  # degrees per radian: a value in rad times DEG is in deg
PER_DEG = DEG  # multiplies a per-degree value into per-radian
RAD_PER_DEG = math.pi / 180.0  # a value in deg times RAD_PER_DEG is in rad
MM = 1e-3  # a value in mm times MM is in m



def column_name(header):
    """A CSV column's name without the unit its header gives in brackets:
    'preload [m]' -> 'preload' (a header without one is its name)."""
    return header.split(" [", 1)[0].strip()


UNITS = {
    "m": ({"m": 1}, [("mm", 1e3)]),
    "m/s": ({"m": 1, "s": -1}, [("mm/s", 1e3)]),
    "rad": ({"rad": 1}, [("deg", DEG)]),
    "rad/s": ({"rad": 1, "s": -1}, [("deg/s", DEG)]),
    "N": ({"kg": 1, "m": 1, "s": -2}, [("kN", 1e-3)]),
    "N.m": ({"kg": 1, "m": 2, "s": -2}, [("kN.m", 1e-3)]),
    "N/m": ({"kg": 1, "s": -2}, [("N/mm", 1e-3)]),
    "N/m2": ({"kg": 1, "m": -1, "s": -2}, [("N/mm2", 1e-6)]),
    "N/m3": ({"kg": 1, "m": -2, "s": -2}, [("N/mm3", 1e-9)]),
    "N.m/rad": ({"kg": 1, "m": 2, "s": -2, "rad": -1}, [("N.m/deg", 1.0 / DEG)]),
    "N.m/rad2": ({"kg": 1, "m": 2, "s": -2, "rad": -2}, [("N.m/deg2", 1.0 / DEG ** 2)]),
    "N.m/rad3": ({"kg": 1, "m": 2, "s": -2, "rad": -3}, [("N.m/deg3", 1.0 / DEG ** 3)]),
    "1/m": ({"m": -1}, [("1/mm", 1e-3)]),
    "1/rad": ({"rad": -1}, [("1/deg", 1.0 / DEG)]),
    "kg.m2": ({"kg": 1, "m": 2}, []),
    "1": ({}, []),
    "1/s": ({"s": -1}, []),
    "rad/s2": ({"rad": 1, "s": -2}, [("deg/s2", DEG)]),
}
