"""The native FMUs' win64 DLLs, loaded by the C host (tests/c_host/fmu_host.c) cross-compiled
with mingw-w64 and run under wine, give what the linux64 binaries give in the same host built
with gcc: the same sine through each FMU, every step within 1e-12 of the output's
peak-to-peak range."""

import os
import shutil
import subprocess
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest

from conftest import FMU_NAMES, ROOT, peak_to_peak
from fmu_components.lab.signals import THESIS_SINES

MINGW = "x86_64-w64-mingw32-gcc"
MISSING = [tool for tool in ("wine", "wineserver", MINGW, "gcc") if shutil.which(tool) is None]
if MISSING:
    pytest.skip(f"the win64 DLLs run under wine need {', '.join(MISSING)} (Debian: apt-get "
                f"install wine64 gcc-mingw-w64-x86-64-win32)", allow_module_level=True)

HOST_SOURCE = ROOT / "tests" / "c_host" / "fmu_host.c"
HEADERS = Path(fmpy.__file__).parent / "c-code"
# value references of deflection, its rate and the first output, the same in all four FMUs
VR_DEFLECTION, VR_RATE, VR_OUTPUT = 0, 1, 2
STEP, STOP = 0.001, 2.0
TIMEOUT = 600  # the first start of wine in a fresh prefix can take tens of seconds
TOLERANCE = 1e-12  # of the output's peak-to-peak range


def clean_environment():
    """No preloaded libraries and no Python settings leaking in from the test process."""
    return {k: v for k, v in os.environ.items()
            if k not in ("LD_PRELOAD", "PYTHONPATH", "PYTHONHOME", "VIRTUAL_ENV")}


@pytest.fixture(scope="module")
def wine_environment(tmp_path_factory):
    """The environment for wine with a private prefix, created once for the module (and
    removed afterwards: a prefix takes some 700 MB)."""
    prefix = tmp_path_factory.mktemp("wine") / "prefix"
    environment = clean_environment()
    for display in ("DISPLAY", "WAYLAND_DISPLAY"):  # a console program: no windows
        environment.pop(display, None)
    environment.update(WINEPREFIX=str(prefix), WINEDEBUG="-all", WINEARCH="win64",
                       WINEDLLOVERRIDES="mscoree,mshtml=")  # no Mono or Gecko installer
    boot = subprocess.run(["wine", "wineboot", "--init"], env=environment, capture_output=True,
                          text=True, timeout=TIMEOUT)
    assert boot.returncode == 0, boot.stderr
    yield environment
    subprocess.run(["wineserver", "-k"], env=environment, capture_output=True, timeout=60)
    shutil.rmtree(prefix, ignore_errors=True)


@pytest.fixture(scope="module")
def hosts(tmp_path_factory):
    """The same C host built for linux64 with gcc and for win64 with mingw-w64."""
    directory = tmp_path_factory.mktemp("c_hosts")
    linux, windows = directory / "fmu_host", directory / "fmu_host.exe"
    flags = ["-O2", "-Wall", "-Wextra", "-Werror", f"-I{HEADERS}", str(HOST_SOURCE)]
    subprocess.run(["gcc", *flags, "-o", str(linux), "-ldl", "-lm"], check=True)
    subprocess.run([MINGW, *flags, "-o", str(windows), "-static-libgcc"], check=True)
    return linux, windows


def windows_path(path):
    """Wine maps the unix root to drive Z:."""
    return "Z:" + str(path).replace("/", "\\")


def windows_uri(path):
    """file:///Z:/unix/path (percent-encoded); the FMU drops the slash before the drive."""
    return "file:///Z:" + path.as_uri()[len("file://"):]


def rows(stdout):
    """'time,output' lines (CRLF from the win64 host) as an array."""
    return np.array([[float(v) for v in line.split(",")] for line in stdout.splitlines()
                     if line.strip()])


@pytest.mark.parametrize("name", FMU_NAMES)
def test_win64_dll_under_wine_matches_linux64(native_fmus, hosts, wine_environment, tmp_path,
                                              name):
    with zipfile.ZipFile(native_fmus[name]) as archive:
        archive.extractall(tmp_path)
    dll = tmp_path / "binaries" / "win64" / f"{name}.dll"
    assert dll.is_file(), f"{native_fmus[name]} carries no win64 binary"
    resources = tmp_path / "resources"
    guid = (resources / "fmu-guid.txt").read_text().strip()
    mean, amplitude, frequency = THESIS_SINES[name]
    arguments = [guid, str(VR_DEFLECTION), str(VR_RATE), str(VR_OUTPUT), repr(mean),
                 repr(amplitude), repr(frequency), repr(STEP), repr(STOP)]
    linux_host, windows_host = hosts

    linux = subprocess.run([str(linux_host), str(tmp_path / "binaries" / "linux64" / f"{name}.so"),
                            resources.as_uri(), *arguments], capture_output=True, text=True,
                           env=clean_environment(), timeout=TIMEOUT)
    assert linux.returncode == 0, linux.stderr
    windows = subprocess.run(["wine", str(windows_host), windows_path(dll), windows_uri(resources),
                              *arguments], capture_output=True, text=True, env=wine_environment,
                             timeout=TIMEOUT)
    assert windows.returncode == 0, windows.stderr

    expected, actual = rows(linux.stdout), rows(windows.stdout)
    assert expected.shape == actual.shape == (round(STOP / STEP), 2)
    np.testing.assert_allclose(actual[:, 0], expected[:, 0], rtol=1e-15, atol=0)
    span = peak_to_peak(expected[:, 1])
    assert span > 0
    difference = float(np.max(np.abs(actual[:, 1] - expected[:, 1]))) / span
    print(f"{name}: max |win64 - linux64| = {difference:.3g} of the peak-to-peak {span:.6g}")
    assert difference <= TOLERANCE
