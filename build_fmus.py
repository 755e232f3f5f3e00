"""Build both flavours of the four FMUs and run each once: ``fmu-components build``.

Kept so that ``python build_fmus.py`` works from the repository root; the code is in
``src/fmu_components/build.py``.
"""

import sys

if __name__ == "__main__":
    from fmu_components.build import main

    sys.exit(main())
