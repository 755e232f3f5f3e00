"""The options every command that runs many independent FMU runs shares: where they run.

    --scheduler ADDRESS   an existing Dask cluster (``dask scheduler`` / ``dask worker``)
    --jobs N              else a local cluster of N worker processes (default: one per
                          core); 1 runs them one after another in this process

Not a command: the commands ``verify``, ``validate``, ``rig``, ``fit`` and ``campaign``
take these (docs/campaigns.md).
"""

import sys
from contextlib import contextmanager

from ..errors import UsageError


def add_arguments(parser, aliases=()):
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="run on this Dask cluster (its scheduler, e.g. tcp://HOST:8786); "
                             "default: a local cluster")
    parser.add_argument("--jobs", *aliases, type=int, default=None, metavar="N",
                        help="worker processes of the local cluster (default: one per core; "
                             "1: one run after another in this process)")


@contextmanager
def engine(args):
    """The Engine of the parsed options (it starts when its first tasks come), closed
    afterwards; its errors are the user's to fix."""
    from ..campaign.engine import Engine, EngineError

    try:
        started = Engine(args.scheduler, args.jobs,
                         say=lambda text: print(text, file=sys.stderr, flush=True))
        try:
            yield started
        finally:
            started.close()
    except EngineError as error:
        raise UsageError(str(error)) from None
