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

    run({"native": {"MyBush": own / "MyBush.fmu"}})
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


# --- every tool takes an own part: it is identified by what the FMU carries ---------------

def test_the_fmu_says_what_it_is(own, native_fmus):
    from fmu_components.export.identity import read_identity

    for path in (own / "MyBush.fmu", own / "python" / "MyBush.fmu"):
        identity = read_identity(path)
        assert (identity.name, identity.component, identity.structure) == \
            ("MyBush", "TrackBushRadial", "final")
        assert identity.own and all(identity.values[n] == v for n, v in VALUES.items())
    thesis = read_identity(native_fmus["TrackBushRadial"])
    assert thesis.component == "TrackBushRadial" and not thesis.own


def test_own_descriptions_do_not_quote_the_thesis_as_their_value(own):
    descriptions = {v.name: v.description
                    for v in read_model_description(str(own / "MyBush.fmu")).modelVariables}
    assert descriptions["k1"].endswith("this part's own value (the thesis's is 6e+07 N/m)")
    assert "Appendix 4b: 60000 N/mm" in descriptions["k1"]  # the thesis's, named as such
    assert "own value" not in descriptions["k2"]  # a thesis value it keeps


@pytest.mark.parametrize("flavour", ["native", "python"])
def test_simulate_runs_an_own_part_with_its_values(own, tmp_path, capsys, flavour):
    from fmu_components.lab.signals import sine, write_csv

    path = own / "MyBush.fmu" if flavour == "native" else own / "python" / "MyBush.fmu"
    t = time_grid(1.0, 1e-3)
    table = input_table("TrackBushRadial", t, sine(t, 0.3e-3, 0.1e-3, 2.0))
    with open(tmp_path / "in.csv", "w") as f:
        write_csv(table, f)
    assert cli.main(["simulate", str(path), str(tmp_path / "in.csv"),
                     "--out", str(tmp_path / "out.csv")]) == 0
    result = np.genfromtxt(tmp_path / "out.csv", delimiter=",", names=True)
    # (fmpy sums its steps, so it reads the input a few ulps off the sample times)
    np.testing.assert_allclose(result["force"], simulate("TrackBushRadial", VALUES, t,
                                                         table["deflection"]), rtol=1e-9)
    # --param and --params change the run, starting from the part's own values
    (tmp_path / "p.json").write_text(json.dumps({"c1": 2500.0}))
    assert cli.main(["simulate", str(path), str(tmp_path / "in.csv"), "--out",
                     str(tmp_path / "p.csv"), "--params", str(tmp_path / "p.json"),
                     "--param", "xi3=9e-3"]) == 0
    changed = np.genfromtxt(tmp_path / "p.csv", delimiter=",", names=True)
    np.testing.assert_allclose(
        changed["force"], simulate("TrackBushRadial", dict(VALUES, c1=2500.0, xi3=9e-3), t,
                                   table["deflection"]), rtol=1e-9)
    assert np.max(np.abs(changed["force"] - result["force"])) > 100.0


def test_rig_drives_an_own_part_and_names_a_wrong_component(own, tmp_path, capsys):
    arguments = ["rig", "--engine", "fmu", "--fmu", str(own / "MyBush.fmu"), "--preload",
                 "3e-4", "--amplitude", "1e-4", "--frequency", "1", "--relaxation", "1e-4",
                 "--hold", "1", "--out", str(tmp_path / "rig")]
    assert cli.main([*arguments, "--component", "TrackBushRadial"]) == 0
    with pytest.raises(SystemExit) as stop:
        cli.main([*arguments, "--component", "TrackBushTorsion"])
    assert stop.value.code == 2
    assert "is MyBush: TrackBushRadial in the 'final' structure" in capsys.readouterr().err


def test_verify_checks_an_own_part_against_a_solve_with_its_own_values(own, tmp_path, capsys):
    from fmu_components.verification import cases, reference

    assert cli.main(["verify", "--fmus", str(own), "--fmu", "MyBush", "--case",
                     "II_amplitude_0.1mm", "--report", str(tmp_path)]) == 0
    assert "MyBush  II_amplitude_0.1mm" in capsys.readouterr().out
    # the check has teeth: against the thesis's reference the part is far off
    (case,) = cases.select(["TrackBushRadial"], ["II_amplitude_0.1mm"])
    inputs = case.inputs()
    spec = reference.spec_from_parameters("TrackBushRadial", VALUES)
    own_force = cases.reference_table(case, inputs, spec)["force"]
    thesis_force = cases.reference_table(case, inputs)["force"]
    assert np.max(np.abs(own_force - thesis_force)) > 0.05 * np.ptp(thesis_force)


def test_a_unit_slip_in_the_parameters_is_named(tmp_path, capsys):
    (tmp_path / "slip.json").write_text(json.dumps({"k1": 60000.0}))  # N/mm typed as N/m
    assert cli.main(["build", "--params", str(tmp_path / "slip.json"), "--name", "Slip",
                     "--component", "TrackBushRadial", "--flavour", "native",
                     "--dest", str(tmp_path), "--no-run"]) == 0
    assert ("warning: parameter k1 = 60000 N/m is 1/1e+03 of the thesis's 6e+07 N/m: it looks "
            "like N/mm (give N/m: 60000 N/mm = 6e+07 N/m)") in capsys.readouterr().err


def test_the_build_summary_names_each_fmu_by_its_file(tmp_path, capsys):
    assert cli.main(["build", "--structure", "four-element", "--flavour", "native",
                     "--dest", str(tmp_path)]) == 0
    rows = [line.split() for line in capsys.readouterr().out.splitlines()
            if line.startswith("TrackBush")]
    assert [row[:3] for row in rows] == [["TrackBushTorsionFourElement", "native", "torque"]]
