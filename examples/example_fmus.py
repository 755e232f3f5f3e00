"""Where the examples find the FMUs: fmus/ of this repository, or --fmu-dir."""

from pathlib import Path

DEFAULT_FMU_DIR = Path(__file__).resolve().parents[1] / "fmus"


def fmu_path(name, fmu_dir=None):
    path = Path(fmu_dir or DEFAULT_FMU_DIR) / f"{name}.fmu"
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist: build the FMUs first "
                                f"(python build_fmus.py --no-run)")
    return path
