"""Every subcommand's --help: a whole description, every argument explained, every default
shown; and a closed pipe ends a command quietly."""

import argparse
import subprocess
import sys

import pytest

from fmu_components import cli

from conftest import ROOT

PARSER, SUBCOMMANDS = cli._parser(list(cli.COMMANDS))


@pytest.mark.parametrize("name", sorted(cli.COMMANDS))
def test_help_shows_every_default_and_a_whole_description(name, capsys):
    with pytest.raises(SystemExit):
        cli.main([name, "--help"])
    shown = " ".join(capsys.readouterr().out.split())
    parser = SUBCOMMANDS[name]
    description = " ".join(parser.description.split())
    assert description.endswith(".") and description in shown
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        assert action.help, f"{name} {action.option_strings or action.dest} has no help"
        default = action.default
        if default in (None, False, []) or action.required:
            continue
        shown_default = " ".join(map(str, default)) if isinstance(default, list) else str(default)
        assert "default" in action.help or f"(default: {shown_default})" in shown, \
            f"{name} {action.option_strings}: default {default!r} not shown"


def test_signal_without_its_values_is_a_usage_error_not_a_zero_signal():
    result = subprocess.run([sys.executable, "-m", "fmu_components", "signal", "RoadWheelTyre",
                             "sine"], capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 2 and result.stdout == ""
    assert "--mean, --amplitude" in result.stderr
    result = subprocess.run([sys.executable, "-m", "fmu_components", "signal", "RoadWheelTyre",
                             "sine", "--mean", "3.5e-3", "--amplitude", "0"],
                            capture_output=True, text=True, cwd=ROOT)
    assert result.returncode == 2 and "--amplitude 0.001" in result.stderr


def test_a_closed_pipe_ends_quietly():
    command = (f"{sys.executable} -m fmu_components signal RoadWheelTyre sine --mean 3.5e-3 "
               f"--amplitude 1e-3 --stop-time 100 --step 1e-4 | head -1")
    result = subprocess.run(["bash", "-c", command], capture_output=True, text=True, cwd=ROOT)
    assert result.stdout == '"time","compression","compression_rate"\n'
    assert result.stderr == ""


def test_the_top_level_help_imports_no_command():
    """The one-line summaries are in the registry: `fmu-components --help` imports none of
    the command modules, nor what they use (scipy, the lab, the verification)."""
    code = ("import sys\nfrom fmu_components import cli\n"
            "try:\n    cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(' '.join(sorted(sys.modules)), file=sys.stderr)")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            cwd=ROOT)
    assert result.returncode == 0, result.stderr
    for name in cli.COMMANDS:
        assert name in result.stdout
    loaded = result.stderr.split()
    heavy = [m for m in loaded if m.split(".")[0] in ("scipy", "numpy", "fmpy", "matplotlib")
             or m.startswith(("fmu_components.commands", "fmu_components.lab",
                              "fmu_components.verification", "fmu_components.export"))]
    assert not heavy, heavy
