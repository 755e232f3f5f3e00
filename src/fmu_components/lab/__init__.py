"""The tools an engineer runs on components and built FMUs: input signals (``signals``),
one FMU on an input CSV (``simulate``), the virtual test rig and its harmonic analysis
(``rig``, ``rig_plots``, ``harmonics``), the fit to measured data (``measured``, ``history``,
``fit``, ``fit_report``) and what the build command does around the build
(``build_command``); display units (``display``) and files written whole (``files``).
A library: the command line over it is ``commands``.

Imports ``runtime`` and ``export``, never ``verification`` or the command line; reads no
arguments.
"""
