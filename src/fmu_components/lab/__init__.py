"""The tools an engineer runs on components and built FMUs: input signals (``signals``),
one FMU on an input CSV (``simulate``), the virtual test rig and its harmonic analysis
(``rig``, ``harmonics``), the fit to measured data (``measured``, ``history``, ``fit``,
``fit_report``) and the build command (``build_command``).

Imports ``runtime`` and ``export``, never ``verification`` or the command line.
"""
