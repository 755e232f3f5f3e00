"""Tracked-vehicle running-gear components as FMI 2.0 Co-Simulation FMUs.

The run-time code that travels inside every FMU lives in ``fmu_components.runtime`` and
imports only the Python standard library. Everything else in this package (building,
reference solves, validation) runs on the engineer's machine and may use numpy, scipy
and fmpy.
"""

__version__ = "0.1.0"
