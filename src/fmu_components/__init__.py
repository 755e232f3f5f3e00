"""Tracked-vehicle running-gear components as FMI 2.0 FMUs, in two flavours from one
definition of their equations: native C (``cgen`` prints the equations, ``c/`` is the
runtime) and pythonfmu (``runtime``).

The run-time code that travels inside the Python FMUs lives in ``fmu_components.runtime``
and imports only the Python standard library; it also holds the one definition of the
equations. Everything else in this package (building, reference solves, validation) runs
on the engineer's machine and may use numpy, scipy and fmpy.

"Spec section N" in comments refers to the model specification, docs/model-spec.md.
"""

__version__ = "0.1.0"
