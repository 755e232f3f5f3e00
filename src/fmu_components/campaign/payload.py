"""Files that travel with the tasks: a worker needs no access to the client's files.

A ``Payload`` holds a file's (or a folder's, zipped) bytes and their digest. On a worker,
``resolve`` swaps every payload among a task's arguments for a local copy, written once per
worker process into its own temporary folder and found again by the digest; a task runs
the same wherever it lands. A task's arguments may be plain values, tuples, lists, dicts
or dataclasses holding payloads.
"""

import dataclasses
import hashlib
import io
import os
import shutil
import tempfile
import zipfile
from pathlib import Path

_LOCAL = {}  # digest -> local path, in this process
_FOLDER = None  # this process's folder for them


@dataclasses.dataclass(frozen=True)
class Payload:
    """A file's bytes (`folder`: a folder's, zipped) under its own name."""
    name: str
    data: bytes
    folder: bool = False

    @property
    def digest(self):
        return hashlib.sha256(self.data).hexdigest()

    @classmethod
    def of(cls, path):
        """The file or folder at `path`."""
        path = Path(path)
        if not path.is_dir():
            return cls(path.name, path.read_bytes())
        files = [p for p in sorted(path.rglob("*"))
                 if p.is_file() and "__pycache__" not in p.parts]
        return cls.of_files(path.name, files, path)

    @classmethod
    def of_files(cls, name, files, root=None):
        """A folder `name` of these files (at their paths below `root`, else by name)."""
        buffer = io.BytesIO()
        with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as archive:
            for item in files:
                item = Path(item)
                inside = item.relative_to(root).as_posix() if root else item.name
                # a fixed date: the same files make the same bytes, so the same digest
                info = zipfile.ZipInfo(inside, date_time=(1980, 1, 1, 0, 0, 0))
                info.compress_type = zipfile.ZIP_DEFLATED
                archive.writestr(info, item.read_bytes())
        return cls(name, buffer.getvalue(), folder=True)

    def local(self):
        """Its local copy's path (written on first use in this process)."""
        global _FOLDER
        digest = self.digest
        if digest not in _LOCAL:
            if _FOLDER is None:
                _FOLDER = tempfile.mkdtemp(prefix="fmu_components_campaign_")
                import atexit

                atexit.register(shutil.rmtree, _FOLDER, ignore_errors=True)
            target = Path(_FOLDER) / digest[:16] / self.name
            target.parent.mkdir(parents=True, exist_ok=True)
            if self.folder:
                with zipfile.ZipFile(io.BytesIO(self.data)) as archive:
                    archive.extractall(target)
            else:
                partial = target.with_name(f".{self.name}.{os.getpid()}.part")
                partial.write_bytes(self.data)
                os.replace(partial, target)
            _LOCAL[digest] = target
        return _LOCAL[digest]


def resolve(value):
    """`value` with every payload in it replaced by its local copy's path (a str)."""
    if isinstance(value, Payload):
        return str(value.local())
    if isinstance(value, tuple) and hasattr(value, "_fields"):  # a named tuple
        return type(value)(*(resolve(v) for v in value))
    if isinstance(value, (list, tuple)):
        return type(value)(resolve(v) for v in value)
    if isinstance(value, dict):
        return {k: resolve(v) for k, v in value.items()}
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        changes = {f.name: resolve(getattr(value, f.name)) for f in dataclasses.fields(value)}
        changed = {k: v for k, v in changes.items() if v is not getattr(value, k)}
        return dataclasses.replace(value, **changed) if changed else value
    return value
