"""The command line's commands, one module per command: its arguments (``configure``, with
examples in ``EXAMPLES``) and what it does when it runs (``run_command``, the exit status).
``cluster`` holds the options of those that run many FMU runs (--scheduler, --jobs).

Each is a thin layer over the API a user's script imports (``lab``, ``verification``,
``campaign``, ``export``): it reads the arguments, calls the API, prints, and turns a mistake into a
one-line ``errors.UsageError``. A command imports what it uses when it runs, so that
``fmu-components --help`` imports none of them.

Imports every layer below it; only ``cli`` imports it.
"""
