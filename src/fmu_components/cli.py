"""fmu-components: the project's command-line tool.

    fmu-components build | verify | validate | signal | simulate | rig | fit | campaign --help

Each subcommand lives in its own module of ``commands``, which provides
``configure(parser)`` (its arguments, with an example in ``EXAMPLES``) and
``run_command(args)`` (returns the exit status). A mistake the user can fix raises
``errors.UsageError``: one line that says what to do, exit status 2, no traceback.

This is the top layer: it imports the one command module asked for, none for the top-level
help (the registry below has each command's one line), and nothing imports it.
"""

import argparse
import importlib
import os
import sys
import textwrap

from .campaign.engine import one_thread_per_process
from .errors import UsageError

PROG = "fmu-components"

# name -> (module, one line of help). Modules are imported only when their command runs.
COMMANDS = {
    "build": ("fmu_components.commands.build", "build the FMUs of both flavours and run each once"),
    "verify": ("fmu_components.commands.verify",
               "verification: run the thesis test programme through the built FMUs against an "
               "independent solve of the same equations"),
    "validate": ("fmu_components.commands.validate",
                 "validation: the model against the thesis's measurements (measured, model, "
                 "difference, source)"),
    "signal": ("fmu_components.commands.signal", "write an input CSV for an FMU (SI units)"),
    "simulate": ("fmu_components.commands.simulate",
                 "simulate an FMU on an input CSV: result CSV and the force-deflection loop"),
    "rig": ("fmu_components.commands.rig", "virtual test rig: dynamic stiffness, loss angle, "
                                           "energy per cycle and secant stiffness of a component "
                                           "at periodic steady state, and its step-and-hold "
                                           "relaxation"),
    "fit": ("fmu_components.commands.fit",
            "identify a rubber component's parameters from measured data"),
    "campaign": ("fmu_components.commands.campaign",
                 "many runs over a grid of parameters (station, vehicle, rig, verify) on a "
                 "local or remote Dask cluster, into one results table"),
}


class HelpFormatter(argparse.RawDescriptionHelpFormatter):
    """The examples as written, and every option's default after its help (unless the help
    already says it)."""

    def _get_help_string(self, action):
        text = action.help or ""
        default = action.default
        if (default in (None, False, argparse.SUPPRESS) or default == [] or action.required
                or "default" in text or not action.option_strings):
            return text
        shown = " ".join(map(str, default)) if isinstance(default, (list, tuple)) else default
        return f"{text} (default: {shown})".lstrip()


def description(module, summary):
    """The module's first paragraph, whole: the subcommand's description."""
    text = (module.__doc__ or summary).strip().split("\n\n")[0]
    return textwrap.fill(" ".join(text.split()), width=90)


def _add_command(subparsers, name):
    module_name, summary = COMMANDS[name]
    module = importlib.import_module(module_name)
    parser = subparsers.add_parser(
        name, help=summary, description=description(module, summary),
        epilog=getattr(module, "EXAMPLES", None), formatter_class=HelpFormatter)
    module.configure(parser)
    parser.set_defaults(run_command=module.run_command)
    return parser


def _parser(names):
    """The parser with every command listed by its one line; the commands in `names`
    configured (their modules imported), the others not, so that the top-level help
    imports no command."""
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Tracked-vehicle running-gear components as FMI 2.0 and FMI 3.0 FMUs: "
                    "build, verify, validate and drive them.")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    configured = {}
    for name, (_, summary) in COMMANDS.items():
        if name in names:
            configured[name] = _add_command(subparsers, name)
        else:
            subparsers.add_parser(name, help=summary)
    return parser, configured


def _run(parser, args):
    try:
        return args.run_command(args)
    except UsageError as error:
        parser.exit(2, f"{parser.prog}: error: {error}\n")


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    one_thread_per_process()  # before numpy loads: the same numbers as a Dask worker's
    # Configure only the command asked for, so that one command's imports never slow another
    # and the top-level help imports none.
    wanted = [a for a in argv[:1] if a in COMMANDS]
    try:
        parser, subparsers = _parser(wanted)  # imports the command: Ctrl-C may come here too
        args = parser.parse_args(argv)
        status = _run(subparsers[args.command], args)
        sys.stdout.flush()
        return status
    except KeyboardInterrupt:
        # Ctrl-C: one line, no traceback, and the status a shell gives a process ended by
        # SIGINT. Every file a command writes is written whole or not at all (lab/files.py).
        below_a_bar = "\n" if sys.stderr.isatty() else ""  # a progress bar ends its line
        print(f"{below_a_bar}{PROG}: interrupted", file=sys.stderr)
        return 128 + 2
    except BrokenPipeError:
        # The reader stopped reading (`... | head -1`): end quietly, as SIGPIPE would, and
        # keep Python from complaining when it flushes stdout at exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 128 + 13

