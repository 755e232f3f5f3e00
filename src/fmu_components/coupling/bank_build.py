"""Compiling the bank (bank.c) as the FMUs are compiled: gcc at build time, a shared
library per platform, libc and libm only.

`fmu-components build` (build_fmus.py) calls `build_bank()`, which puts the libraries
beside the sources (bank.c, bank_linearised.c, bank.h) (linux64, and win64 where mingw-w64 is installed). A bank that finds no
library there compiles one on first use into a cache (~/.cache/fmu_components, or
$FMU_COMPONENTS_CACHE); where no compiler is found it says so and names the Python path.
`Library` does the same for other C code compiled on first use (the vehicle example's
contacts, examples/vehicle/contacts_kernel.py).
"""

import ctypes
import hashlib
import os
import shutil
import subprocess
import sys
import warnings
from pathlib import Path

HERE = Path(__file__).resolve().parent
SOURCES = [HERE / "bank.c", HERE / "bank_linearised.c"]
HEADERS = [HERE / "bank.h"]
# Same bits as Python's arithmetic: no fused multiply-add, no fast math.
FLAGS = ["-O2", "-std=c99", "-ffp-contract=off", "-fno-fast-math", "-Wall", "-Wextra"]
COMPILERS = {"linux64": ("gcc", ".so", ["-shared", "-fPIC", "-fvisibility=hidden"]),
             "win64": ("x86_64-w64-mingw32-gcc", ".dll", ["-shared", "-static-libgcc"])}


def function_address(function):
    """A loaded library's function's address, for C that calls it through a pointer (a
    kernel handed another library's function)."""
    return ctypes.cast(function, ctypes.c_void_p).value


class NoCompiler(RuntimeError):
    """No C compiler for the bank: the host can use the coupling's Python path."""


def platform_name():
    if sys.platform.startswith("linux"):
        return "linux64"
    if sys.platform == "win32":
        return "win64"
    return sys.platform


def cache_directory():
    return Path(os.environ.get("FMU_COMPONENTS_CACHE")
                or Path.home() / ".cache" / "fmu_components")


class Library:
    """A shared library compiled from C sources (libc and libm only), named `stem` and
    keyed by a hash of its sources: built beside them, or on first use into the cache.
    `what` says what it is and `fallback` what to use without a compiler (the message's
    end)."""

    def __init__(self, stem, sources, headers, what, fallback):
        self.stem, self.sources, self.headers = stem, list(sources), list(headers)
        self.what, self.fallback = what, fallback

    def source_tag(self):
        """A hash of the sources: a library built from other code is never loaded."""
        digest = hashlib.sha256()
        for path in self.sources + self.headers:
            digest.update(path.read_bytes())
        return digest.hexdigest()[:12]

    def library_name(self, platform):
        return f"{self.stem}_{platform}_{self.source_tag()}{COMPILERS[platform][1]}"

    def compile(self, platform, directory):
        """Compile for `platform` into `directory` (older builds there removed); the
        library's path."""
        compiler, _, flags = COMPILERS[platform]
        if shutil.which(compiler) is None:
            raise NoCompiler(f"{compiler} not found: {self.what} needs a C compiler to build "
                             f"it once (Debian/Ubuntu: apt-get install gcc), or "
                             f"{self.fallback}")
        directory = Path(directory)
        directory.mkdir(parents=True, exist_ok=True)
        target = directory / self.library_name(platform)
        partial = target.with_suffix(f".{os.getpid()}.tmp")
        run = subprocess.run([compiler, *FLAGS, *flags, *map(str, self.sources), "-o",
                              str(partial), "-lm"], capture_output=True, text=True)
        if run.returncode != 0:
            raise RuntimeError(f"compiling {self.what} with {compiler} failed:\n{run.stderr}")
        partial.replace(target)  # atomic: a process loading it never sees half a file
        for older in directory.glob(f"{self.stem}_{platform}_*{COMPILERS[platform][1]}"):
            if older != target:
                older.unlink(missing_ok=True)
        return target

    def built(self, beside=None):
        """The library for this platform where it is built already (beside the sources,
        or `beside`, or in the cache), else None (never compiles)."""
        platform = platform_name()
        if platform not in COMPILERS:
            return None
        name = self.library_name(platform)
        for directory in (Path(beside or self.sources[0].parent), cache_directory()):
            if (directory / name).exists():
                return directory / name
        return None

    def path(self):
        """The library for this platform: built already, or compiled into the cache now."""
        platform = platform_name()
        if platform not in COMPILERS:
            raise NoCompiler(f"{self.what} has no build for platform {platform}: "
                             f"{self.fallback}")
        return self.built() or self.compile(platform, cache_directory())

    def load(self, consequence=None):
        """The library loaded (ctypes), once per process; None where it cannot be built,
        with a warning saying why and what to use instead (`fallback`), and what the
        caller does then (`consequence`)."""
        if not hasattr(self, "_loaded"):
            try:
                self._loaded = ctypes.CDLL(str(self.path()))
            except NoCompiler as missing:
                warnings.warn(f"{missing}; {consequence}" if consequence else str(missing),
                              stacklevel=2)
                self._loaded = None
        return self._loaded


BANK = Library("bank", SOURCES, HEADERS, "the coupling bank (compiled per-step work)",
               "use the Python path (path='python')")


def source_tag():
    return BANK.source_tag()


def library_name(platform):
    return BANK.library_name(platform)


def compile_bank(platform, directory):
    """Compile the bank for `platform` into `directory`; the library's path."""
    return BANK.compile(platform, directory)


def build_bank(directory=None):
    """Build the bank's libraries beside its sources (or into `directory`): linux64, and
    win64 where mingw-w64 is installed. {platform: path}, and the platforms skipped."""
    directory = Path(directory or HERE)
    built, skipped = {}, []
    for platform in COMPILERS:
        if shutil.which(COMPILERS[platform][0]) is None:
            skipped.append(platform)
            continue
        built[platform] = compile_bank(platform, directory)
    return built, skipped


def built_library():
    """The bank's library for this platform where it is built already, else None (never
    compiles)."""
    return BANK.built()


def library_path():
    """The bank's library for this platform: built beside its sources, in the cache, or
    compiled into the cache now."""
    return BANK.path()
