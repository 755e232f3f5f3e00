"""The README's variables tables are the catalog's, and every command in it runs."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from fmu_components.export.docs import all_tables

from conftest import ROOT


def test_readme_variables_tables_match_the_catalog():
    readme = (ROOT / "README.md").read_text()
    begin, end = "<!-- variables:begin -->\n", "\n<!-- variables:end -->"
    assert readme[readme.index(begin) + len(begin):readme.index(end)] == all_tables()


# --- every command of the README is run: here, or by .ci/run, or by the test named ---------

# Commands that take minutes, or set up the machine, run elsewhere; each entry names where,
# and the test checks that the place really runs that program.
RUN_ELSEWHERE = {
    "python3.11 -m venv .venv": ".ci/run",
    ".venv/bin/pip install -e": ".ci/run",
    ".venv/bin/python build_fmus.py": ".ci/run",
    ".venv/bin/python -m pytest": ".ci/run",
    ".venv/bin/python examples/road_wheel_station.py": ".ci/run",
    ".venv/bin/python examples/track_span.py": ".ci/run",
    ".venv/bin/fmu-components validate": ".ci/run",
    ".venv/bin/fmu-components verify": ".ci/run",
    ".venv/bin/python benchmarks/run.py": "tests/test_benchmark.py",
    ".venv/bin/python benchmarks/coupling_study.py": "tests/test_examples.py",
}


def readme_commands():
    """Each command of the README's bash blocks, continuation lines joined, comments cut."""
    readme = (ROOT / "README.md").read_text()
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", readme, re.S):
        for line in block.replace("\\\n", " ").splitlines():
            line = re.sub(r"\s+#.*$", "", line).strip()
            for command in line.split(" && "):
                if command:
                    commands.append(" ".join(command.split()))
    return commands


def where_run(command):
    """Where a command that is not run here is run, else None."""
    for start, place in RUN_ELSEWHERE.items():
        if command == start or command.startswith(start + " "):
            # the full validation and verification; the README's narrower ones (a selection)
            # run here
            if start.startswith(".venv/bin/fmu-components") and command != start:
                return None
            return place
    return None


def test_every_readme_command_that_runs_elsewhere_is_run_there():
    for command in readme_commands():
        place = where_run(command)
        if place:
            # the program and its first argument: "python3.11 -m", ".venv/bin/python examples/..."
            text = (ROOT / place).read_text()
            if place.startswith("tests/"):  # the test runs the script with its own Python
                script = Path(command.split()[1])
                assert all(f'"{part}"' in text for part in script.parts), (command, place)
            else:
                assert " ".join(command.split()[:2]) in text, (command, place)


# What the README's commands write in the repository (besides /tmp)
README_WRITES = ("tyre_in.csv", "tyre_out.csv", "tyre_loop.png", "rig_radial/rig.csv",
                 "fitted/bush.json", "fmus/MyBush.fmu", "fmus/python/MyBush.fmu")


def test_what_the_readme_and_the_docs_commands_write_is_ignored_by_git():
    """So that trying them leaves the checkout clean (docs/rig.md builds other structures
    into fmus/<structure>/)."""
    for written in README_WRITES + ("fmus/four-element/TrackBushTorsionFourElement.fmu",
                                    "fmus/haupt-sedlan/python/TrackBushRadial.fmu"):
        check = subprocess.run(["git", "check-ignore", "-q", written], cwd=ROOT)
        assert check.returncode == 0, f"{written} would show up in git status"


def test_the_readme_quick_start_commands_run_as_written(all_fmus, tmp_path):
    """The README's other commands, in order, in a scratch folder that holds the built FMUs
    where the README has them: each exits 0 and writes what the README says it writes."""
    native = next(iter(all_fmus["native"].values())).parent
    (tmp_path / "fmus").mkdir()
    for fmu in native.glob("*.fmu"):
        os.symlink(fmu, tmp_path / "fmus" / fmu.name)
    bin_dir = Path(sys.executable).parent
    ran = []
    for command in readme_commands():
        if where_run(command):
            continue
        # the README's /tmp/ paths go under tmp_path before the venv's own path goes in
        # (a clone under /tmp keeps its venv)
        words = [str(tmp_path / w[len("/tmp/"):]) if w.startswith("/tmp/") else w
                 for w in shlex.split(command)]
        words = [w.replace(".venv/bin/", f"{bin_dir}/") for w in words]
        output = None
        if ">" in words:
            words, output = words[:words.index(">")], tmp_path / words[words.index(">") + 1]
        run = subprocess.run(words, cwd=tmp_path, capture_output=True, text=True, timeout=900)
        assert run.returncode == 0, (command, run.stderr[-2000:])
        if output:
            output.write_text(run.stdout)
        ran.append(command)
    assert len(ran) >= 6, ran
    for written in README_WRITES + ("hf/summary.md", "damper/summary.md"):
        assert (tmp_path / written).stat().st_size > 0, written
    header = (tmp_path / "tyre_out.csv").read_text().splitlines()[0].replace('"', "")
    assert header.split(",")[:3] == ["time", "compression", "compression_rate"]


def test_the_readme_tells_a_host_what_it_needs_in_the_readme_itself():
    """Not only in docs/: the starting state, how each load acts on the bodies, the two tyre
    instances of a wheel, the glibc floor."""
    readme = " ".join((ROOT / "README.md").read_text().split())
    for said in ("**The starting state.**", "its rotor turning at the initial arm rate",
                 "**How the loads act on the bodies.**", "**One instance is one half-wheel's "
                 "tyre**", "carries two instances", "the arm feels -`torque` and the hull "
                 "+`torque`", "glibc 2.17 or later"):
        assert said in readme, said
