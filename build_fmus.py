"""Build both flavours of the four FMUs and run each once: ``fmu-components build``.

Kept so that ``python build_fmus.py`` works from the repository root; the code is in
``src/fmu_components/commands/build.py`` (the command),
``src/fmu_components/lab/build_command.py`` (its checks and the run) and
``src/fmu_components/export/build.py`` (the build).
"""

import sys

SETUP = ('python3.11 -m venv .venv && .venv/bin/pip install -e ".[test]", '
         'then run .venv/bin/python build_fmus.py')

if __name__ == "__main__":
    try:
        from fmu_components.cli import main
    except ModuleNotFoundError as missing:
        # Run by a Python without the project installed: say how to get the environment.
        print(f"build_fmus.py: error: {missing.name} is not installed in {sys.executable}; "
              f"create the project's environment: {SETUP}", file=sys.stderr)
        sys.exit(2)  # a usage error, as the command-line tool's
    sys.exit(main(["build", *sys.argv[1:]]))
