"""The linux64 binaries load on glibc 2.17 and later: no symbol they need from glibc has a
newer version (objdump -T lists each with the version it binds), and they ask for the
libraries that hold those symbols on an older glibc."""

import re
import subprocess
import zipfile

import pytest

from conftest import FMU_NAMES, ROOT

FLOOR = (2, 17)


def glibc_versions(library):
    table = subprocess.run(["objdump", "-T", str(library)], capture_output=True, text=True,
                           check=True).stdout
    return {(tuple(int(p) for p in version.split(".")), symbol)
            for version, symbol in re.findall(r"\(GLIBC_([\d.]+)\)\s+(\S+)", table)}


def needed(library):
    headers = subprocess.run(["objdump", "-p", str(library)], capture_output=True, text=True,
                             check=True).stdout
    return set(re.findall(r"NEEDED\s+(\S+)", headers))


def extracted(fmu, member, folder):
    with zipfile.ZipFile(fmu) as archive:
        archive.extract(member, folder)
    return folder / member


@pytest.mark.parametrize("name", FMU_NAMES)
def test_native_binary_needs_nothing_newer_than_glibc_2_17(native_fmus, tmp_path, name):
    library = extracted(native_fmus[name], f"binaries/linux64/{name}.so", tmp_path)
    versions = glibc_versions(library)
    assert versions, "objdump found no glibc symbols"
    newer = sorted(f"{s}@GLIBC_{'.'.join(map(str, v))}" for v, s in versions if v > FLOOR)
    assert not newer, newer
    assert needed(library) <= {"libc.so.6", "libm.so.6", "ld-linux-x86-64.so.2"}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_python_flavours_guard_needs_nothing_newer_than_glibc_2_17(python_fmus, tmp_path, name):
    library = extracted(python_fmus[name], f"binaries/linux64/{name}.so", tmp_path)
    newer = sorted(f"{s}@GLIBC_{'.'.join(map(str, v))}" for v, s in glibc_versions(library)
                   if v > FLOOR)
    assert not newer, newer
    # dlopen and the pthread keys live in these before glibc 2.34
    assert {"libdl.so.2", "libpthread.so.0"} <= needed(library)


def test_the_readme_states_pythonfmus_own_floor(python_fmus, tmp_path):
    """pythonfmu's prebuilt library is not ours to rebuild: the README says what it needs."""
    library = extracted(python_fmus[FMU_NAMES[0]], "binaries/linux64/libpythonfmu-export.so",
                        tmp_path)
    newest = max(v for v, _ in glibc_versions(library))
    assert f"GLIBC_{'.'.join(map(str, newest))}" in (ROOT / "README.md").read_text()
