"""Where the examples find the FMUs: fmus/ of this repository (FMI 2.0), fmus/fmi3/ (FMI
3.0, with --fmi 3), or --fmu-dir."""

from pathlib import Path

DEFAULT_FMU_DIR = Path(__file__).resolve().parents[1] / "fmus"
FMU_DIRS = {"2": DEFAULT_FMU_DIR, "3": DEFAULT_FMU_DIR / "fmi3"}  # by FMI version


def add_fmu_arguments(parser):
    parser.add_argument("--fmu-dir", type=Path,
                        help="folder of the FMUs (default: fmus/, or fmus/fmi3/ with --fmi 3)")
    parser.add_argument("--fmi", choices=sorted(FMU_DIRS), default="2",
                        help="FMI version of the FMUs: 2 (fmus/, the default) or 3 (fmus/fmi3/); "
                             "the coupling gives the same numbers with either")


def fmu_dir_of(args):
    """The folder the parsed --fmu-dir and --fmi name."""
    return args.fmu_dir or FMU_DIRS[args.fmi]


def fmu_path(name, fmu_dir=None):
    path = Path(fmu_dir or DEFAULT_FMU_DIR) / f"{name}.fmu"
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist: build the FMUs first "
                                f"(python build_fmus.py --no-run)")
    return path
