"""Reference experiments inside the FMUs (FMI-LS-REF with MA-HS-Experiments files), their
replay by ``fmu-components verify X.fmu`` for any FMU that carries them, and JUnit XML
from ``verify`` and ``validate``.

The manifest and the experiments files are validated against the standards' schemas in
tests/schema/ (modelica/fmi-ls-ref and modelica/ma-hs-experiments); the FMI 3.0 schemas
they refer to by URL are read from fmpy's copies, with no network.
"""

import shutil
import zipfile
from pathlib import Path
from xml.etree import ElementTree

import fmpy
import numpy as np
import pytest
from fmpy.util import read_csv
from lxml import etree

from fmu_components import cli
from fmu_components.export.parameters import read_parameters
from fmu_components.lab.signals import write_csv
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.verification import cases as programme
from fmu_components.verification import embedded
from fmu_components.verification.ls_ref import (DOCUMENTATION, FOLDER, MANIFEST,
                                                read_experiments)

SCHEMAS = Path(__file__).parent / "schema"
FMI3_SCHEMAS = Path(fmpy.__file__).parent / "schema" / "fmi3"
REMOTE = "https://raw.githubusercontent.com/modelica/fmi-standard/main/schema/"
XS = "{http://www.w3.org/2001/XMLSchema}"
NAME = "TrackBushRadial"
CHEAP = ["II_amplitude_0.1mm", "III_frequency_20Hz"]  # a second or less each through an FMU


class FmiSchemas(etree.Resolver):
    """The FMI 3.0 schemas the standards' schemas name by URL, from fmpy's copies."""

    def resolve(self, url, public_id, context):
        if url.startswith(REMOTE):
            return self.resolve_filename(str(FMI3_SCHEMAS / url[len(REMOTE):]), context)
        return None


def schema(name):
    parser = etree.XMLParser(no_network=True)
    parser.resolvers.add(FmiSchemas())
    tree = etree.parse(str(SCHEMAS / name), parser)
    # The experiments schema imports the FMI annotation schema without a namespace, which
    # XML Schema forbids in a schema without a target namespace; the sibling manifest
    # schema includes it instead (modelica/fmi-ls-ref #40), as is done here.
    for element in tree.getroot().findall(f"{XS}import"):
        if element.get("namespace") is None:
            element.tag = f"{XS}include"
    return etree.XMLSchema(tree)


@pytest.fixture(scope="module")
def carrying(all_fmus, tmp_path_factory):
    """{flavour: path} of the TrackBushRadial FMUs of every flavour with their experiments,
    added as `fmu-components build` adds them."""
    folder = tmp_path_factory.mktemp("ls_ref")
    files = embedded.fmu_files(NAME, NAME)
    found = {}
    for flavour, paths in all_fmus.items():
        path = shutil.copy(paths[NAME], folder / f"{flavour}.fmu")
        embedded.add_files(path, files)
        found[flavour] = Path(path)
    return found


def read(path, member):
    with zipfile.ZipFile(path) as archive:
        return archive.read(member)


def test_every_flavour_carries_the_whole_programme(carrying):
    cases = programme.select([NAME])
    for path in carrying.values():
        related, experiments = read_experiments(path)
        assert [e.name for e in experiments] == [c.name for c in cases]
        assert {r.role for r in related} == {"parameter", "experiment/validation", "document"}
        assert not any(e.problem for e in experiments)
        assert b"Deviation to expect" in read(path, DOCUMENTATION)


def test_references_are_the_independent_solvers_and_the_parameters_the_thesiss(carrying,
                                                                                 tmp_path):
    path = carrying["native"]
    for case in programme.select([NAME], CHEAP):
        committed = programme.case_paths(case)
        assert read(path, f"{FOLDER}/cases/{case.name}_ref.csv") == \
            committed["ref.csv"].read_bytes()
        assert read(path, f"{FOLDER}/cases/{case.name}_in.csv") == \
            committed["in.csv"].read_bytes()
    ssv = tmp_path / "set.ssv"
    ssv.write_bytes(read(path, f"{FOLDER}/{NAME}.ssv"))
    assert read_parameters(ssv, COMPONENTS[NAME]) == COMPONENTS[NAME].default_parameters()
    experiment = next(e for e in read_experiments(path)[1] if e.name == CHEAP[0])
    case = programme.select([NAME], CHEAP[:1])[0]
    assert (experiment.start_time, experiment.stop_time, experiment.step_size,
            experiment.tolerance, experiment.limit) == (0.0, case.stop_time, case.step,
                                                        1e-4, 0.005)


def test_manifest_and_experiments_follow_the_standards_schemas(carrying):
    manifest = schema("fmi3LayeredStandardReferenceManifest.xsd")
    experiments = schema("maHarmonizedSpecificationExperiments.xsd")
    for path in carrying.values():
        manifest.assertValid(etree.fromstring(read(path, MANIFEST)))
        experiments.assertValid(etree.fromstring(read(path, f"{FOLDER}/verification.exp")))
    # the schemas do hold the files to something: a role the standard does not define
    wrong = read(carrying["native"], MANIFEST).replace(b'role="document"', b'role="manual"')
    assert not manifest.validate(etree.fromstring(wrong))


def test_verify_replays_the_experiments_of_each_flavour(carrying, tmp_path, capsys):
    junit = tmp_path / "results.xml"
    paths = [str(carrying[f]) for f in ("native", "python", "fmi3")]
    argv = ["verify", *paths, "--junit", str(junit)]
    for name in CHEAP:
        argv += ["--case", name]
    assert cli.main(argv) == 0
    printed = capsys.readouterr().out
    assert "6 of 6 experiments pass" in printed
    root = ElementTree.parse(junit).getroot()
    assert (root.get("tests"), root.get("failures")) == ("6", "0")
    assert [s.get("name") for s in root.iter("testsuite")] == paths
    assert not list(root.iter("failure"))


FOREIGN_MANIFEST = """<?xml version="1.0" encoding="UTF-8"?>
<fmiReferences xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
    fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
    fmi-ls:fmi-ls-description="Layered Standard providing information on related files included in an FMU.">
  <Related type="application/x-ma-hs-experiments" source="tests/smoke.exp" role="experiment/smoke-test"/>
</fmiReferences>
"""
FOREIGN_EXPERIMENT = """
  <Experiment name="{name}" tolerance="1e-4">
    <TransientSimulation startTime="0" stopTime="{stop}" stepSize="{step}"/>
    <Parameters source="../params/stiffness%20in%20mm.ssv"/>
    <Stimuli source="data/in.csv"/>
    <References source="data/{references}"/>
  </Experiment>"""
# k1 in N/mm and the elastic slope in N/mm: converted to the FMU's N/m by the units' factors
FOREIGN_SSV = """<?xml version="1.0" encoding="UTF-8"?>
<ssv:ParameterSet xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues"
    xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" version="1.0" name="mm">
  <ssv:Parameters>
    <ssv:Parameter name="k1"><ssv:Real value="{k1}" unit="N/mm"/></ssv:Parameter>
    <ssv:Parameter name="elastic.a1"><ssv:Real value="{a1}" unit="N/mm"/></ssv:Parameter>
  </ssv:Parameters>
  <ssv:Units>
    <ssc:Unit name="N/mm"><ssc:BaseUnit kg="1" s="-2" factor="1000"/></ssc:Unit>
  </ssv:Units>
</ssv:ParameterSet>
"""


def test_a_foreign_fmus_failing_reference_is_reported(all_fmus, tmp_path, capsys):
    """Another tool's FMU (one of ours under another name, with a manifest of its own and no
    acceptance annotation: the deviation is held to the tolerance) whose second experiment's
    reference is 2 % off."""
    case = programme.select([NAME], CHEAP[:1])[0]
    committed = programme.case_paths(case)
    reference = read_csv(committed["ref.csv"])
    off = reference.copy()
    for name in off.dtype.names[1:]:
        off[name] *= 1.02
    shifted = tmp_path / "off.csv"
    with shifted.open("w", newline="") as file:
        write_csv(off, file)
    values = COMPONENTS[NAME].default_parameters()
    foreign = Path(shutil.copy(all_fmus["native"][NAME], tmp_path / "Foreign.fmu"))
    embedded.add_files(foreign, {
        MANIFEST: FOREIGN_MANIFEST,
        f"{FOLDER}/tests/smoke.exp": '<?xml version="1.0" encoding="UTF-8"?>\n'
        '<Experiments name="Smoke tests">' + "".join(
            FOREIGN_EXPERIMENT.format(name=name, references=references, stop=case.stop_time,
                                      step=case.step)
            for name, references in (("as_built", "ref.csv"), ("two_percent_off", "ref_off.csv")))
        + "\n</Experiments>\n",
        f"{FOLDER}/params/stiffness in mm.ssv": FOREIGN_SSV.format(
            k1=values["k1"] / 1000, a1=values["elastic.a1"] / 1000),
        f"{FOLDER}/tests/data/in.csv": committed["in.csv"].read_bytes(),
        f"{FOLDER}/tests/data/ref.csv": committed["ref.csv"].read_bytes(),
        f"{FOLDER}/tests/data/ref_off.csv": shifted.read_bytes()})
    bare = shutil.copy(all_fmus["native"][NAME], tmp_path / "Bare.fmu")  # no manifest
    junit = tmp_path / "results.xml"
    assert cli.main(["verify", str(foreign), str(bare), "--junit", str(junit)]) == 1
    printed = capsys.readouterr().out
    assert "1 of 3 experiments pass" in printed
    rows = {line.split()[1]: line for line in printed.splitlines()
            if line.startswith(str(foreign))}
    assert " pass " in rows["as_built"] and "FAIL" in rows["two_percent_off"]
    failures = {case.get("name"): case.find("failure").get("message")
                for case in ElementTree.parse(junit).getroot().iter("testcase")
                if case.find("failure") is not None}
    assert set(failures) == {"two_percent_off", "reference experiments"}
    assert "limit 0.0001" in failures["two_percent_off"]
    assert "carries no extra/org.fmi-standard.fmi-ls-ref" in failures["reference experiments"]


def test_a_wrong_parameter_unit_fails_the_experiment_naming_it(carrying, tmp_path, capsys):
    fmu, parameters = tmp_path / "Wrong.fmu", f"{FOLDER}/{NAME}.ssv"
    with zipfile.ZipFile(carrying["native"]) as source, zipfile.ZipFile(fmu, "w") as archive:
        for member in source.namelist():
            archive.writestr(member, source.read(member) if member != parameters else
                             FOREIGN_SSV.format(k1=60000, a1=81800).replace('s="-2"', 's="-1"'))
    assert cli.main(["verify", str(fmu), "--case", CHEAP[0]]) == 1
    assert "k1 = 60000.0 N/mm is not of the kind of the variable's unit N/m" in \
        capsys.readouterr().out


def test_an_own_part_carries_references_solved_as_it_builds(tmp_path, capsys):
    params = tmp_path / "bush.json"
    params.write_text('{"k1": 4.1e7, "xi3": 7e-3}')
    assert cli.main(["build", "--params", str(params), "--name", "MyBush", "--component",
                     NAME, "--dest", str(tmp_path / "fmus"), "--flavour", "native",
                     "--no-run"]) == 0
    fmu = tmp_path / "fmus" / "MyBush.fmu"
    [experiment] = read_experiments(fmu)[1]
    assert experiment.name in embedded.SOLVED_AT_BUILD[NAME]
    with zipfile.ZipFile(fmu) as archive:
        archive.extract(f"{FOLDER}/cases/{experiment.name}_ref.csv", tmp_path)
    own = read_csv(tmp_path / FOLDER / "cases" / f"{experiment.name}_ref.csv")
    thesis = read_csv(programme.case_paths(programme.select([NAME], [experiment.name])[0])
                      ["ref.csv"])
    assert np.max(np.abs(own["force"] - thesis["force"])) > 0.01 * np.ptp(thesis["force"])
    capsys.readouterr()
    assert cli.main(["verify", str(fmu)]) == 0
    assert "1 of 1 experiments pass" in capsys.readouterr().out


def test_verify_and_validate_write_junit(native_fmus, tmp_path):
    folder = Path(native_fmus[NAME]).parent
    junit = tmp_path / "verify.xml"
    assert cli.main(["verify", "--fmus", str(folder), "--fmu", NAME, "--case", CHEAP[1],
                     "--report", str(tmp_path / "report"), "--junit", str(junit)]) == 0
    [case] = ElementTree.parse(junit).getroot().iter("testcase")
    assert (case.get("name"), case.find("failure")) == (CHEAP[1], None)
    junit = tmp_path / "validate.xml"
    assert cli.main(["validate", "--fmus", str(folder), "--case", "damper-rotor-inertia",
                     "--case", "damper-friction", "--report", str(tmp_path / "validation"),
                     "--junit", str(junit)]) == 0
    cases = {c.get("name"): c for c in ElementTree.parse(junit).getroot().iter("testcase")}
    assert set(cases) == {"damper-rotor-inertia", "damper-friction"}
    assert cases["damper-friction"].find("skipped") is not None  # no metric: not judged
    assert cases["damper-rotor-inertia"].find("skipped") is None


@pytest.mark.parametrize("argv, words", [
    (["verify", "nothere.fmu"], "no such FMU file: nothere.fmu"),
    (["verify", "{fmu}", "--limit", "0"], "--limit 0.0: give a positive fraction"),
    (["verify", "{fmu}", "--fmu", NAME], "--fmu picks among the built FMUs of --fmus"),
    (["verify", "--limit", "0.01"], "--limit goes with FMU files"),
])
def test_replay_mistakes_are_one_line(tmp_path, capsys, argv, words):
    fmu = tmp_path / "X.fmu"
    fmu.write_bytes(b"")
    with pytest.raises(SystemExit) as stop:
        cli.main([a.format(fmu=fmu) for a in argv])
    assert stop.value.code == 2
    assert words in capsys.readouterr().err


def test_an_own_damper_carries_the_first_half_cycle_of_test_b():
    """The damper's reference solve takes ~7.5 s of CPU per simulated second: an own damper
    carries test B's first second (the whole stroke once), the same input as test B there."""
    [case] = embedded.solved_at_build("RotaryDamper")
    [whole] = programme.select(["RotaryDamper"], ["B_0.5Hz"])
    assert case.name == "B_0.5Hz_first_1s" and case.options()["StopTime"] == 1.0
    inputs, whole_inputs = case.inputs(), whole.inputs()
    assert len(inputs["time"]) == 501
    for column in ("time", "angle"):
        assert np.array_equal(inputs[column], whole_inputs[column][:501])
    # the rate held over each step (the last row's is over no step)
    assert np.array_equal(inputs["angle_rate"][:500], whole_inputs["angle_rate"][:500])
    assert inputs["angle"].min() == -0.21 and abs(inputs["angle"].max() - 0.21) < 1e-12
