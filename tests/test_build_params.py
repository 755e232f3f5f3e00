"""build --params: an engineer's own part as FMUs of both flavours under its own name, with
the parameter file's values as start values; they reproduce the fit's fast simulation."""

import json
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from fmu_components import cli
from fmu_components.lab.history import simulate
from fmu_components.lab.signals import dual_sine, input_table, secant_rates, time_grid

VALUES = {"k1": 4.1e7, "c1": 5000.0, "xi3": 7e-3, "elastic.a1": 9.1e7, "geometric.h": 120.0}


@pytest.fixture(scope="module")
def own(tmp_path_factory):
    folder = tmp_path_factory.mktemp("own")
    params = folder / "bush.json"
    params.write_text(json.dumps(VALUES))
    assert cli.main(["build", "--params", str(params), "--name", "MyBush", "--component",
                     "TrackBushRadial", "--dest", str(folder / "fmus"), "--no-run"]) == 0
    return folder / "fmus"


@pytest.mark.parametrize("flavour", ["native", "python"])
def test_own_fmu_reproduces_the_fast_simulation(own, flavour):
    path = own / "MyBush.fmu" if flavour == "native" else own / "python" / "MyBush.fmu"
    description = read_model_description(str(path))
    assert description.modelName == "MyBush"
    assert description.coSimulation.modelIdentifier == "MyBush"
    starts = {v.name: float(v.start) for v in description.modelVariables if v.name in VALUES}
    assert starts == VALUES
    with zipfile.ZipFile(path) as fmu:
        assert "binaries/linux64/MyBush.so" in fmu.namelist()
    t = time_grid(1.0, 1e-3)
    x = dual_sine(t, 0.1e-3, [(0.2e-3, 2.0), (0.03e-3, 11.0)])
    result = simulate_fmu(str(path), stop_time=1.0, output_interval=1e-3,
                          input=input_table("TrackBushRadial", t, x, secant_rates(t, x)),
                          output=["force"])
    np.testing.assert_array_equal(result["force"], simulate("TrackBushRadial", VALUES, t, x))


def test_guids_differ_from_the_shipped_build(own):
    native = read_model_description(str(own / "MyBush.fmu")).guid
    python = read_model_description(str(own / "python" / "MyBush.fmu")).guid
    assert native != python


@pytest.mark.parametrize("argv, words", [
    (["--name", "MyBush", "--component", "TrackBushRadial"], "go together"),
    (["--name", "my bush", "--component", "TrackBushRadial", "--params", "{p}"], "--name my bush"),
    (["--name", "MyBush", "--component", "TrackBushRadial", "--params", "{bad}"], "no parameter 'k9'"),
    (["--name", "MyBush", "--component", "TrackBushRadial", "--params", "{negative}"], "k1"),
])
def test_own_build_mistakes_are_one_line(tmp_path, capsys, argv, words):
    files = {"p": {"k1": 1e7}, "bad": {"k9": 1.0}, "negative": {"k1": -1.0}}
    paths = {}
    for key, content in files.items():
        paths[key] = tmp_path / f"{key}.json"
        paths[key].write_text(json.dumps(content))
    argv = [a.format(**paths) for a in argv]
    with pytest.raises(SystemExit) as exit_:
        cli.main(["build", "--dest", str(tmp_path / "fmus"), "--no-run", *argv])
    assert exit_.value.code == 2
    message = capsys.readouterr().err.strip()
    assert words in message and "\n" not in message


def test_own_fmu_runs_the_components_sine(own, capsys):
    from fmu_components.lab.build_command import run

    run({"native": {"MyBush": own / "MyBush.fmu"}}, "TrackBushRadial")
    (row,) = [line for line in capsys.readouterr().out.splitlines() if line.startswith("MyBush")]
    assert row.split()[2] == "force"


def test_own_part_in_another_structure(tmp_path):
    values = {"k1": 5e7, "c2": 9e4, "xi2": 4e-3}
    params = tmp_path / "hs.json"
    params.write_text(json.dumps(values))
    assert cli.main(["build", "--params", str(params), "--name", "MyHauptSedlan",
                     "--component", "TrackBushRadial", "--structure", "haupt-sedlan",
                     "--flavour", "native", "--dest", str(tmp_path), "--no-run"]) == 0
    t = time_grid(1.0, 1e-3)
    x = dual_sine(t, 0.2e-3, [(0.1e-3, 3.0)])
    result = simulate_fmu(str(tmp_path / "MyHauptSedlan.fmu"), stop_time=1.0,
                          output_interval=1e-3, output=["force"],
                          input=input_table("TrackBushRadial", t, x, secant_rates(t, x)))
    np.testing.assert_array_equal(
        result["force"], simulate("TrackBushRadial", values, t, x, structure="haupt-sedlan"))
