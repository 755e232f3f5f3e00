import importlib.util
from pathlib import Path

import numpy as np
import pytest

from fmu_components.runtime.catalog import COMPONENTS

ROOT = Path(__file__).resolve().parents[1]
FMU_NAMES = sorted(COMPONENTS)


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
    return COMPONENTS[name].default_parameters()


def peak_to_peak(values):
    values = np.asarray(values)
    return float(values.max() - values.min())
