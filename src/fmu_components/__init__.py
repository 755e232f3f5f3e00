"""Tracked-vehicle running-gear components as FMI 2.0 and FMI 3.0 FMUs, in two flavours from
one definition of their equations: native C and pythonfmu.

The layers, each importing only those above it in this list:

* ``runtime``: the one definition of the equations (expressions, rubber, damper) and of
  the components (definition, rubber_parts, damper_part, catalog), and the Python runtime
  that travels inside the Python FMUs (standard library only);
  ``c/``, the native runtime that travels as sources inside the native FMUs;
  ``guard/``, the Python FMUs' binary in C, which takes shared pieces from ``c/``;
* ``coupling``: the host-side coupling library that steps the FMUs with a multibody host
  (fmpy and numpy only; it imports nothing else of this package, so any Python host can
  use it alone);
* ``export``: building the FMUs (the C printer, the modelDescription writer, the build);
* ``lab``: the tools an engineer runs, as a library (signals, simulate, rig, fit, the build's
  run); it never reads the command line;
* ``verification``: the FMUs against an independent solve of the same equations, and the
  model against the thesis's measurements; a library too;
* ``campaign``: many independent runs at once on a local or remote Dask cluster, the
  files they need travelling with them, into one results table; a library too;
* ``commands``: the command line's commands, one module each, over the layers above;
* ``cli``: the command line's registry and entry point.

This file travels inside the Python FMUs too, so it imports nothing.
"Spec section N" in comments refers to the model specification, docs/model-spec.md.
"""

__version__ = "0.1.0"
