import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

from fmu_components.runtime.catalog import COMPONENTS

ROOT = Path(__file__).resolve().parents[1]
FMU_NAMES = sorted(COMPONENTS)

# A sine inside the thesis range for each component: (mean, amplitude, frequency in Hz).
THESIS_SINES = {
    "RoadWheelTyre": (3.5e-3, 1e-3, 1.0),
    "TrackBushRadial": (0.3e-3, 0.1e-3, 1.0),
    "TrackBushTorsion": (math.radians(10.0), math.radians(5.0), 1.0),
    "RotaryDamper": (0.0, 0.21, 0.75),
}


def _load_build_script():
    spec = importlib.util.spec_from_file_location("build_fmus", ROOT / "build_fmus.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def built_fmus(tmp_path_factory):
    """The four FMUs, built once per test session from the current source."""
    destination = tmp_path_factory.mktemp("fmus")
    paths = _load_build_script().build(FMU_NAMES, destination)
    return {path.stem: path for path in paths}


def default_parameters(name):
    return {p.name: p.start for p in COMPONENTS[name].parameters}


def peak_to_peak(values):
    values = np.asarray(values)
    return float(values.max() - values.min())
