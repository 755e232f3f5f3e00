"""SSP rig packages (lab/rig_package.py): fmus/ssp/<Name>Rig.ssp holds the component's FMU,
a driver FMU that plays the thesis's rig test input and the thesis's parameter set bound to
the component; SSP 1.0's schemas accept it, and two SSP tools (fmpy's simulate_ssp and
libcosim) run it to the same results as the component FMU run alone with the same input."""

import zipfile
from types import SimpleNamespace

import numpy as np
import pytest
from fmpy.ssp.simulation import simulate_ssp
from fmpy.ssp.ssd import read_ssd

from fmu_components.cli import main
from fmu_components.export.parameters import read_parameters, write_parameter_set
from fmu_components.lab.rig_package import DRIVER, write_rig_packages
from fmu_components.lab.signals import THESIS_SINES, sine
from fmu_components.runtime.catalog import COMPONENTS, component_definition

from conftest import FMU_NAMES, peak_to_peak
from fmu_runner import FmuRunner

STOP, STEP = 0.25, 1e-3  # s: a quarter cycle of the 1 Hz sines, enough to compare
NANOSECONDS = 1_000_000_000  # libcosim counts time in integer nanoseconds


@pytest.fixture(scope="module")
def packages(native_fmus, tmp_path_factory):
    return write_rig_packages(native_fmus, tmp_path_factory.mktemp("ssp"))


def bound_parameters(package, name):
    """The parameter set the .ssd binds to the component (fmpy reads it)."""
    component = next(e for e in read_ssd(str(package), validate=True).system.elements
                     if e.name == name)
    (binding,) = component.parameterBindings
    (values,) = binding.parameterValues
    return values


@pytest.mark.parametrize("name", FMU_NAMES)
def test_a_package_holds_the_fmu_a_driver_and_the_thesis_set_and_passes_ssp_schema(
        packages, native_fmus, name, tmp_path):
    package = packages[name]
    assert package.name == f"{name}Rig.ssp"
    with zipfile.ZipFile(package) as archive:
        assert sorted(archive.namelist()) == sorted([
            "SystemStructure.ssd", f"resources/{name}.fmu", f"resources/{name}RigDriver.fmu",
            f"resources/{name}.ssv"])
        assert archive.read(f"resources/{name}.fmu") == native_fmus[name].read_bytes()
        ssv = tmp_path / f"{name}.ssv"
        ssv.write_bytes(archive.read(f"resources/{name}.ssv"))
    definition = component_definition(name)
    assert read_parameters(ssv, definition) == definition.default_parameters()
    system = read_ssd(str(package), validate=True).system  # SSP 1.0's schema
    assert [(c.startElement, c.startConnector, c.endElement, c.endConnector)
            for c in system.connections] == [(DRIVER, v.name, name, v.name)
                                             for v in COMPONENTS[name].inputs]
    assert len(bound_parameters(package, name).parameters) == len(definition.parameters)


def component_columns(result, name):
    return [f"{name}.{v.name}" for v in COMPONENTS[name].outputs]


def assert_driver_plays_the_thesis_sine(name, times, deflection, rate, step):
    """The driver's outputs at `times`: the thesis sine (signals.sine) and the secant rate
    to the next point, to round-off."""
    mean, amplitude, frequency = THESIS_SINES[name]
    expected = sine(times, mean, amplitude, frequency)
    secant = (sine(times + step, mean, amplitude, frequency) - expected) / step
    assert np.max(np.abs(deflection - expected)) <= 1e-12 * amplitude
    assert np.max(np.abs(rate - secant)) <= 1e-9 * amplitude * frequency


def assert_matches_the_fmu_alone(fmu, name, deflection, rate, outputs, initial=None):
    """`outputs` (after each step) are those of the FMU run alone from rest at `initial`
    (default: the first input) with the same inputs, to 1e-9 of each output's range."""
    runner = FmuRunner(fmu)
    runner.initialize(*(initial or (deflection[0], rate[0])))
    alone = np.array([runner.step(x, v, STEP) for x, v in zip(deflection, rate)])
    runner.free()
    for column, variable in enumerate(COMPONENTS[name].outputs):
        scale = peak_to_peak(alone[:, column]) or 1.0
        difference = np.max(np.abs(outputs[:, column] - alone[:, column])) / scale
        assert difference <= 1e-9, (variable.name, difference)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmpy_runs_a_package_as_the_component_alone(packages, native_fmus, name):
    package = packages[name]
    bound = bound_parameters(package, name)
    # fmpy's simulate_ssp applies a parameter set given to it, named by element, and not
    # the .ssd's bindings: given the bound set, it runs what the package says.
    named = SimpleNamespace(parameters=[SimpleNamespace(name=f"{name}.{p.name}", value=p.value)
                                        for p in bound.parameters])
    result = simulate_ssp(str(package), stop_time=STOP, step_size=STEP, parameter_set=named)
    # a row is the time a step starts and every connector after it
    deflection_name, rate_name = (f"{DRIVER}.{v.name}" for v in COMPONENTS[name].inputs)
    assert_driver_plays_the_thesis_sine(name, result["time"] + STEP, result[deflection_name],
                                        result[rate_name], STEP)
    # fmpy starts every connection at 0: the component's first step has inputs 0, the
    # driver's outputs after each step are its inputs in the next
    deflection = np.r_[0.0, result[deflection_name][:-1]]
    rate = np.r_[0.0, result[rate_name][:-1]]
    outputs = np.column_stack([result[c] for c in component_columns(result, name)])
    assert_matches_the_fmu_alone(native_fmus[name], name, deflection, rate, outputs,
                                 initial=(0.0, 0.0))


def run_in_libcosim(package, name, steps, observed=()):
    """libcosim's run of a package: per step the component's inputs, its outputs after the
    step, the driver's outputs after it; and the last values of `observed` variables."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    log_output_level(CosimLogLevel.WARNING)
    execution = CosimExecution.from_ssp_file(str(package), step_size=round(STEP * NANOSECONDS))
    index = {s.name.decode(): s.index for s in execution.slave_infos()}
    references = {element: {v.name.decode(): v.reference for v in execution.slave_variables(i)}
                  for element, i in index.items()}
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    inputs = [references[name][v.name] for v in COMPONENTS[name].inputs]
    outputs = [references[name][v.name] for v in COMPONENTS[name].outputs]
    driver = [references[DRIVER][v.name] for v in COMPONENTS[name].inputs]
    records = []
    for k in range(steps):
        assert execution.step(), f"libcosim step {k} failed"
        records.append(observer.last_real_values(index[name], inputs + outputs)
                       + observer.last_real_values(index[DRIVER], driver))
    last = observer.last_real_values(index[name], [references[name][n] for n in observed])
    return np.array(records), dict(zip(observed, last))


@pytest.mark.parametrize("name", FMU_NAMES)
def test_libcosim_runs_a_package_as_the_component_alone(packages, native_fmus, name):
    steps = round(STOP / STEP)
    records, parameters = run_in_libcosim(packages[name], name, steps,
                                          [p.name for p in COMPONENTS[name].parameters])
    assert parameters == component_definition(name).default_parameters()
    times = np.arange(1, steps + 1) * STEP
    assert_driver_plays_the_thesis_sine(name, times, records[:, -2], records[:, -1], STEP)
    # libcosim passes the driver's outputs on before the first step: the component starts
    # from rest at the sine's mean, as the rig drives it
    assert records[0, 0] == THESIS_SINES[name][0]
    assert_matches_the_fmu_alone(native_fmus[name], name, records[:, 0], records[:, 1],
                                 records[:, 2:-2])


def test_libcosim_applies_the_parameter_set_the_package_binds(packages, tmp_path):
    """A package whose .ssv says otherwise than the FMU's start values runs with the .ssv's."""
    name = "TrackBushRadial"
    definition = component_definition(name)
    values = dict(definition.default_parameters(), k1=3e7, c3=5e4)
    changed = tmp_path / "changed.ssv"
    write_parameter_set(changed, definition, values, "changed")
    package = tmp_path / f"{name}Rig.ssp"
    with zipfile.ZipFile(packages[name]) as original, zipfile.ZipFile(package, "w") as copy:
        for item in original.namelist():
            copy.writestr(item, changed.read_bytes() if item.endswith(".ssv")
                          else original.read(item))
    _, parameters = run_in_libcosim(package, name, 1, ["k1", "c3"])
    assert parameters == {"k1": 3e7, "c3": 5e4}


def test_the_build_writes_the_rig_packages(native_fmus, tmp_path, monkeypatch):
    """`fmu-components build` packages what it built (the build itself stubbed: the FMUs
    the session built stand for it)."""
    name = "TrackBushRadial"
    monkeypatch.setattr("fmu_components.commands.build.build_coupling_bank", lambda: None)
    monkeypatch.setattr("fmu_components.commands.build.build",
                        lambda names, *_: {"native": {name: native_fmus[name]}})
    assert main(["build", "--only", name, "--flavour", "native", "--no-run",
                 "--dest", str(tmp_path)]) == 0
    with zipfile.ZipFile(tmp_path / "ssp" / f"{name}Rig.ssp") as archive:
        assert archive.read(f"resources/{name}.fmu") == native_fmus[name].read_bytes()


def test_the_driver_refuses_a_sine_it_cannot_play(packages, tmp_path):
    # An instance with a logger of its own (coupling.instance): fmpy's `logger=` would
    # become the logger of every later FMU in this process, and die with this test.
    from fmu_components.coupling.errors import CouplingError
    from fmu_components.coupling.instance import FmuInstance, open_fmu

    with zipfile.ZipFile(packages["TrackBushRadial"]) as archive:
        driver = archive.extract("resources/TrackBushRadialRigDriver.fmu", tmp_path)
    instance = FmuInstance(open_fmu(driver), "driver")
    try:
        with pytest.raises(CouplingError):
            instance.setup(parameters={"first_step": -1e-3})
            instance.exit_initialization()
        assert any("first_step = -0.001 s" in m and "positive" in m for m in instance.messages)
    finally:
        instance.close()
