import importlib.util
from pathlib import Path

import numpy as np
import pytest

from fmu_components.export.build import build
from fmu_components.runtime.catalog import COMPONENTS

ROOT = Path(__file__).resolve().parents[1]
FMU_NAMES = sorted(COMPONENTS)
FLAVOURS = ("native", "python")


def load_benchmark(name):
    """benchmarks/<name>.py, imported as a module (the benchmarks are scripts, not a
    package)."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="session")
def all_fmus(tmp_path_factory):
    """Both flavours of the four FMUs, {flavour: {name: path}}, built once per test session
    from the current source."""
    destination = tmp_path_factory.mktemp("fmus")
    return build(FMU_NAMES, destination)


class Flavour(dict):
    """{name: path} of the four FMUs of one flavour, which it names."""

    def __init__(self, flavour, paths):
        super().__init__(paths)
        self.flavour = flavour


@pytest.fixture(scope="session", params=FLAVOURS)
def built_fmus(request, all_fmus):
    """The four FMUs of one flavour: every test that takes it runs on both."""
    return Flavour(request.param, all_fmus[request.param])


@pytest.fixture(scope="session")
def native_fmus(all_fmus):
    return all_fmus["native"]


@pytest.fixture(scope="session")
def python_fmus(all_fmus):
    return all_fmus["python"]


def default_parameters(name):
    return COMPONENTS[name].default_parameters()


def peak_to_peak(values):
    values = np.asarray(values)
    return float(values.max() - values.min())
