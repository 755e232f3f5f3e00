"""Files written whole or not at all.

A command stopped half-way (Ctrl-C, an error) must not leave a half-written result that
looks like a whole one: each file is written under a temporary name beside it and renamed
to its own name once complete (a rename within a folder is atomic on POSIX and Windows).
"""

import os
from contextlib import contextmanager, suppress
from pathlib import Path


@contextmanager
def written_whole(path):
    """Yields the temporary path to write `path` to; it becomes `path` when the block ends
    normally and is removed when it raises (KeyboardInterrupt too). The temporary name
    keeps the suffix, so that a writer that goes by it (matplotlib) writes the same format."""
    path = Path(path)
    temporary = path.with_name(f".{path.stem}.{os.getpid()}.part{path.suffix}")
    try:
        yield temporary
        os.replace(temporary, path)
    except BaseException:
        with suppress(FileNotFoundError):
            os.unlink(temporary)
        raise


def save_figure(figure, path, **options):
    """figure.savefig(path, **options), written whole."""
    with written_whole(path) as temporary:
        figure.savefig(temporary, **options)
    return path


def write_text(path, text):
    """Path(path).write_text(text), written whole."""
    with written_whole(path) as temporary:
        temporary.write_text(text)
    return path
