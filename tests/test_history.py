"""The fit's inner simulation (fmu_components.lab.history) is the native FMU: the same forces, to the
bit, as the built FMU through fmpy, on an irregular history with parameters away from the thesis's."""

import numpy as np
import pytest
from fmpy import simulate_fmu

from fmu_components.export.build import build
from fmu_components.lab.history import HistoryError, simulate
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import dual_sine, input_table, secant_rates, time_grid

RUBBER = ("RoadWheelTyre", "TrackBushRadial", "TrackBushTorsion")
# a mean, two sine components (amplitude, Hz) and a hold, inside each measured range
HISTORIES = {"RoadWheelTyre": (3e-3, [(1.5e-3, 2.0), (0.5e-3, 7.0)]),
             "TrackBushRadial": (0.1e-3, [(0.2e-3, 1.0), (0.05e-3, 9.0)]),
             "TrackBushTorsion": (0.17, [(0.1, 0.5), (0.02, 6.0)])}


@pytest.fixture(scope="module")
def native(tmp_path_factory):
    return build(list(RUBBER), tmp_path_factory.mktemp("fmus"), flavours=("native",))["native"]


def history(name, step=1e-3, stop=1.5):
    mean, components = HISTORIES[name]
    t = time_grid(stop, step)
    x = dual_sine(t, mean, components)
    x[t > 1.0] = x[np.searchsorted(t, 1.0)]  # step and hold
    return t, x


def scaled_parameters(name, factor):
    """Every Maxwell element's k, c and xi scaled: values the thesis never had."""
    thesis = COMPONENTS[name].default_parameters()
    return {f"{q}{i}": thesis[f"{q}{i}"] * factor for q in ("k", "c", "xi") for i in (1, 2, 3)}


@pytest.mark.parametrize("name", RUBBER)
def test_history_is_the_native_fmu(native, name):
    t, x = history(name)
    parameters = scaled_parameters(name, 1.3)
    ours = simulate(name, parameters, t, x)
    load = COMPONENTS[name].outputs[0].name
    theirs = simulate_fmu(str(native[name]), stop_time=t[-1], output_interval=t[1] - t[0],
                          start_values=parameters, input=input_table(name, t, x, secant_rates(t, x)),
                          output=[load])
    assert len(theirs) == len(ours)
    np.testing.assert_allclose(theirs["time"], t, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(theirs[load], ours)  # the same code, the same bits


def test_refused_parameter_is_said():
    t, x = history("TrackBushRadial")
    with pytest.raises(HistoryError, match="k1"):
        simulate("TrackBushRadial", {"k1": -1.0}, t, x)
    force = simulate("TrackBushRadial", {"k1": -1.0}, t, x, check=False)
    assert np.isnan(force).all()
