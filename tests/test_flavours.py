"""The two flavours of each FMU are one model: on linux64 the native FMU reproduces the Python
FMU bit for bit (same equations printed by two printers, same arithmetic in the same
order), on every case of the thesis test programme and on the runs that leave the
integrator's single-step path (jittered steps, the tyre lifting off, the damper in
blow-off). And the native FMU is what it claims: nothing but the C library and libm, only
the FMI functions exported, rebuildable from its sources."""

import math
import shutil
import subprocess
import sys
import zipfile

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu

from fmu_components.verification import cases

from conftest import FMU_NAMES
from fmu_runner import FmuRunner


def run_case(path, case):
    inputs, _, options = cases.read(case)
    return simulate_fmu(str(path), stop_time=options["StopTime"],
                        output_interval=options["StepSize"], relative_tolerance=options["RelTol"],
                        input=inputs)


@pytest.mark.parametrize("case", cases.CASES, ids=lambda c: c.key)
def test_native_reproduces_python_bit_for_bit_on_every_verification_case(all_fmus, case):
    native = run_case(all_fmus["native"][case.fmu], case)
    python = run_case(all_fmus["python"][case.fmu], case)
    for name in native.dtype.names:
        assert np.array_equal(native[name], python[name]), name


def jittered(name, amplitude, frequency, mean=0.0, steps=1500):
    """Steps from 0.3 to 1.8 ms, the deflection sampled off the path the rate predicts."""
    rows, t = [], 0.0
    for k in range(steps):
        h = 1e-3 * (0.3 + 0.25 * (k % 7))
        x = mean + amplitude * math.sin(2 * math.pi * frequency * t)
        x_next = mean + amplitude * math.sin(2 * math.pi * frequency * (t + h))
        rows.append((x, (x_next - x) / h, h))
        t += h
    return rows


# Runs off the single-step path: jittered steps everywhere, the tyre leaving the track link
# every cycle, the damper driven into blow-off (Table A6-1 beyond 2 rad/s).
OFF_PATH = {"jittered steps": {n: (n, *a) for n, a in {
                "RoadWheelTyre": (1e-3, 3.0, 3.5e-3), "TrackBushRadial": (1e-4, 5.0, 3e-4),
                "TrackBushTorsion": (0.1, 2.0, 0.17), "RotaryDamper": (0.21, 3.0)}.items()},
            "tyre lift-off": {"RoadWheelTyre": ("RoadWheelTyre", 4e-3, 3.0, 1e-3)},
            "damper blow-off": {"RotaryDamper": ("RotaryDamper", 0.21, 8.0)}}


@pytest.mark.parametrize("run, name", [(r, n) for r, runs in OFF_PATH.items() for n in runs])
def test_native_reproduces_python_bit_for_bit_off_the_single_step_path(all_fmus, run, name):
    rows = jittered(*OFF_PATH[run][name])
    results = []
    for flavour in ("native", "python"):
        runner = FmuRunner(all_fmus[flavour][name], instance_name=flavour)
        runner.initialize(rows[0][0], rows[0][1])
        results.append(np.array([runner.step(x, v, h) for x, v, h in rows]))
        runner.free()
    assert np.all(np.isfinite(results[0]))
    if run == "tyre lift-off":
        assert np.any(results[0][:, 0] == 0.0) and np.max(results[0][:, 0]) > 1e4
    assert np.array_equal(results[0], results[1])


def unzip(fmu, directory):
    with zipfile.ZipFile(fmu) as archive:
        archive.extractall(directory)
    return directory


@pytest.mark.parametrize("name", FMU_NAMES)
def test_native_binary_needs_only_the_c_library_and_exports_only_fmi(native_fmus, tmp_path, name):
    binary = unzip(native_fmus[name], tmp_path) / "binaries" / "linux64" / f"{name}.so"
    libraries = subprocess.run(["ldd", str(binary)], capture_output=True, text=True).stdout
    needed = {line.split()[0] for line in libraries.splitlines() if line.strip()}
    assert not any("python" in n or "stdc++" in n for n in needed), needed
    assert {n.split(".so")[0] for n in needed} <= {"linux-vdso", "libm", "libc",
                                                   "/lib64/ld-linux-x86-64"}, needed
    symbols = subprocess.run(["nm", "-D", "--defined-only", str(binary)], capture_output=True,
                             text=True).stdout.split()
    exported = {s for s in symbols if s.startswith(("fmi2", "model_", "hermite", "cosim"))}
    assert exported and all(s.startswith("fmi2") for s in exported), exported
    assert "fmi2DoStep" in exported and "fmi2Instantiate" in exported


@pytest.mark.skipif(shutil.which("x86_64-w64-mingw32-objdump") is None
                    and shutil.which("objdump") is None, reason="needs objdump")
@pytest.mark.parametrize("name", FMU_NAMES)
def test_native_win64_dll_imports_only_windows_system_libraries(native_fmus, tmp_path, name):
    unzip(native_fmus[name], tmp_path)
    dll = tmp_path / "binaries" / "win64" / f"{name}.dll"
    if not dll.exists():
        pytest.skip("built without mingw-w64: no win64 binary (.ci/run installs it)")
    dump = subprocess.run([shutil.which("x86_64-w64-mingw32-objdump") or "objdump", "-p",
                           str(dll)], capture_output=True, text=True, check=True).stdout
    imports = {line.split(":", 1)[1].strip().upper() for line in dump.splitlines()
               if "DLL Name:" in line}
    assert imports <= {"KERNEL32.DLL", "MSVCRT.DLL"}, imports
    exports = dump[dump.index("[Ordinal/Name Pointer] Table"):].split("\n\n")[0]
    names = [line.split()[-1] for line in exports.splitlines()[1:] if line.strip()]
    assert "fmi2DoStep" in names and all(n.startswith("fmi2") for n in names), names


@pytest.mark.skipif(shutil.which("cmake") is None, reason="fmpy compile needs cmake")
def test_fmpy_compile_rebuilds_the_native_fmu_from_its_sources_with_the_same_results(
        native_fmus, tmp_path):
    name = "RotaryDamper"
    rebuilt = tmp_path / f"{name}.fmu"
    shutil.copy(native_fmus[name], rebuilt)
    with zipfile.ZipFile(rebuilt) as archive:
        original = archive.read(f"binaries/linux64/{name}.so")
    subprocess.run([sys.executable, "-m", "fmpy.cli", "compile", str(rebuilt.resolve())],
                   check=True, capture_output=True)
    with zipfile.ZipFile(rebuilt) as archive:
        assert archive.read(f"binaries/linux64/{name}.so") != original  # really rebuilt
    assert read_model_description(str(rebuilt)).guid == read_model_description(
        str(native_fmus[name])).guid
    case = next(c for c in cases.CASES if c.key == "RotaryDamper/high_frequency_8Hz")
    first, second = run_case(native_fmus[name], case), run_case(rebuilt, case)
    for column in first.dtype.names:
        assert np.array_equal(first[column], second[column]), column
