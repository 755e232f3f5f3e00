"""The rate check and the derived rate (runtime/cosim.py, docs/simulate.md), in both
flavours: a rate left at 0, in mm/s or of the wrong sign gives one fmi2Warning naming both
inputs; a correctly sampled input never does; rate_from_deflection derives the rate and
stays within the documented error of the independent solve; FMU states carry all of it."""

import math

import numpy as np
import pytest

from fmu_components.verification import reference
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import THESIS_SINES, secant_rates, time_grid

from conftest import FMU_NAMES, peak_to_peak
from fmu_runner import OK, WARNING, FmuRunner


def sine_input(name, samples_per_cycle, cycles=2.0, phase=0.0, amplitude=None):
    """(step, times, deflection, exact rate) of the component's thesis sine."""
    mean, thesis_amplitude, frequency = THESIS_SINES[name]
    amplitude = thesis_amplitude if amplitude is None else amplitude
    step = 1.0 / (frequency * samples_per_cycle)
    t = time_grid(cycles / frequency, step)
    omega = 2 * math.pi * frequency
    x = mean + amplitude * np.sin(omega * t + phase)
    v = amplitude * omega * np.cos(omega * t + phase)
    return step, t, x, v


def step_statuses(runner, x, v, step):
    """Initialize at the first sample, then set each sample and step; the doStep statuses."""
    runner.initialize(x[0], v[0])
    statuses = []
    for xk, vk in zip(x[:-1], v[:-1]):
        runner.set_inputs(xk, vk)
        # fmpy's doStep drops the status: the FMI function itself
        statuses.append(runner.status(runner.fmu.fmi2DoStep, runner.fmu.component, runner.time,
                                      step, 1))
        runner.time += step
    return statuses


def warnings_of(runner):
    """The rate check's warnings (not the measured-range ones)."""
    return [text for status, text in runner.messages if status == WARNING
            and ("does not fit the movement" in text or "stays 0 while" in text)]


@pytest.mark.parametrize("name", FMU_NAMES)
def test_rate_left_at_zero_while_the_deflection_moves_warns_once_naming_both_inputs(
        built_fmus, name):
    step, _, x, v = sine_input(name, 1000)
    runner = FmuRunner(built_fmus[name])
    statuses = step_statuses(runner, x, np.zeros_like(v), step)
    deflection, rate = runner.inputs
    warnings = warnings_of(runner)
    assert len(warnings) == 1 and statuses.count(WARNING) == 1
    assert set(statuses) == {OK, WARNING}
    # The second step is the first that can tell: it has a previous one to compare with.
    assert statuses.index(WARNING) == 1
    assert f"{rate} stays 0 while {deflection} moves" in warnings[0]
    assert "rate_from_deflection" in warnings[0] and "once per instance" in warnings[0]
    runner.free()


@pytest.mark.parametrize("mistake", ["display unit", "wrong sign", "half"])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_a_rate_in_the_wrong_unit_or_sign_warns_once(built_fmus, name, mistake):
    # The damper's gas spring cannot follow test A's angle with a rate 57 times too fast
    # (fmi2SetReal refuses the angle): a smaller one.
    small = 0.01 if name == "RotaryDamper" and mistake == "display unit" else None
    step, _, x, v = sine_input(name, 1000, amplitude=small)
    # mm/s where m/s is expected; deg/s where rad/s is
    factor = {"display unit": 180 / math.pi if COMPONENTS[name].inputs[1].unit == "rad/s"
              else 1000.0, "wrong sign": -1.0, "half": 0.5}[mistake]
    runner = FmuRunner(built_fmus[name])
    step_statuses(runner, x, v * factor, step)
    warnings = warnings_of(runner)
    assert len(warnings) == 1
    deflection, rate = runner.inputs
    assert f"{rate} = " in warnings[0] and f"does not fit the movement of {deflection}" in warnings[0]
    runner.free()


@pytest.mark.parametrize("samples_per_cycle", [10, 13, 100, 1000])
@pytest.mark.parametrize("rates", ["exact", "secant", "backward secant"])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_a_correctly_sampled_sine_never_warns(built_fmus, name, rates, samples_per_cycle):
    # A phase that puts samples on the turning points and one that does not.
    # Held over a tenth of test A's cycle, the exact rate takes the damper's gas spring past
    # its limit (fmi2SetReal refuses the next angle): a smaller angle when sampled coarsely.
    small = 0.05 if name == "RotaryDamper" and samples_per_cycle < 100 else None
    for phase in (0.0, 0.3):
        step, t, x, v = sine_input(name, samples_per_cycle, phase=phase, amplitude=small)
        if rates == "secant":
            v = secant_rates(t, x)
        elif rates == "backward secant":
            v = np.concatenate([[v[0]], np.diff(x) / np.diff(t)])
        runner = FmuRunner(built_fmus[name])
        statuses = step_statuses(runner, x, v, step)
        assert set(statuses) == {OK} and not warnings_of(runner), warnings_of(runner)
        runner.free()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_a_still_or_barely_moving_input_does_not_warn(built_fmus, name):
    """Below the floor (1e-6 of the deflection's scale, plus 1e-3 of it per second) the
    motion is rounding or creep, not a missing rate."""
    mean = THESIS_SINES[name][0]
    scale = COMPONENTS[name].deflection_scale
    step = 1e-3
    dither = mean + 4e-7 * scale * np.sin(np.arange(2001) * 1.3)
    runner = FmuRunner(built_fmus[name])
    statuses = step_statuses(runner, dither, np.zeros_like(dither), step)
    assert set(statuses) == {OK} and not warnings_of(runner)
    runner.free()


# The error of a derived rate against the independent solve of the continuous input, in
# per cent of the output's peak-to-peak range, on the thesis sines (docs/simulate.md,
# measured by benchmarks/derived_rate.py: 0.50-0.75 % at 1 ms, 4.8-7.0 % at 10 ms).
DERIVED_RATE_ERROR = {1e-3: 1.0, 1e-2: 8.0}


@pytest.mark.parametrize("step", sorted(DERIVED_RATE_ERROR))
@pytest.mark.parametrize("name", FMU_NAMES)
def test_derived_rate_matches_the_reference_within_the_documented_error(built_fmus, name, step):
    mean, amplitude, frequency = THESIS_SINES[name]
    t = time_grid(2.0 / frequency, step)
    omega = 2 * math.pi * frequency

    def x_of_t(time):
        return mean + amplitude * np.sin(omega * time)

    def v_of_t(time):
        return amplitude * omega * np.cos(omega * time)

    runner = FmuRunner(built_fmus[name])
    runner.fmu.setBoolean([runner.vr["rate_from_deflection"]], [True])
    runner.initialize(x_of_t(t[0]), 0.0)
    # Outputs after each step: those at t[1:]; the rate input stays 0 (never read after the
    # first step)
    outputs = runner.run(x_of_t(t), np.zeros_like(t), step)
    assert not [text for status, text in runner.messages if status == WARNING]
    result = dict(zip(runner.outputs, outputs.T))
    runner.free()
    expected = {k: v[1:] for k, v in reference.solve_smooth(name, t, x_of_t, v_of_t).items()}
    load = runner.outputs[0]
    error = 100 * np.max(np.abs(result[load] - expected[load])) / peak_to_peak(expected[load])
    assert error <= DERIVED_RATE_ERROR[step]
    if f"{load}_elastic" in expected:  # ... and far better than no rate at all (elastic only)
        elastic = np.max(np.abs(expected[f"{load}_elastic"] - expected[load]))
        assert error < 100 * elastic / peak_to_peak(expected[load]) / 3


def test_the_derived_rate_is_the_backward_difference_held_over_the_next_step(native_fmus):
    """The deflection the FMU carries over a step moves with the derived rate."""
    name = "TrackBushRadial"
    runner = FmuRunner(native_fmus[name])
    runner.fmu.setBoolean([runner.vr["rate_from_deflection"]], [True])
    x = [0.3e-3, 0.31e-3, 0.33e-3]
    step = 1e-3
    runner.initialize(x[0], 0.0)
    runner.step(x[0], 0.0, step)  # the first step takes the rate input
    runner.step(x[1], 123.0, step)  # a rate input is ignored once the rate is derived
    derived = runner.step(x[2], 0.0, step)
    # The same steps with the backward differences fed explicitly give the same bits.
    explicit = FmuRunner(native_fmus[name])
    explicit.initialize(x[0], 0.0)
    explicit.step(x[0], 0.0, step)
    explicit.step(x[1], (x[1] - x[0]) / step, step)
    assert explicit.step(x[2], (x[2] - x[1]) / step, step) == derived
    assert runner.fmu.getBoolean([runner.vr["rate_from_deflection"]]) == [True]
    runner.free()
    explicit.free()


def test_rate_from_deflection_is_fixed_after_initialization(built_fmus):
    runner = FmuRunner(built_fmus["RoadWheelTyre"])
    vr = runner.vr["rate_from_deflection"]
    runner.initialize(3.5e-3, 0.0)
    assert runner.fmu.getBoolean([vr]) == [False]
    assert runner.status(runner.fmu.setBoolean, [vr], [True]) > WARNING
    assert "settable only before fmi2ExitInitializationMode" in runner.messages[-1][1]
    assert runner.status(runner.fmu.setBoolean, [vr + 1], [True]) > WARNING
    assert "no Boolean variable has value reference" in runner.messages[-1][1]
    assert runner.fmu.getBoolean([vr]) == [False]
    runner.free()


@pytest.mark.parametrize("derive", [False, True])
@pytest.mark.parametrize("name", FMU_NAMES)
def test_a_restored_state_continues_identically_with_the_check_and_the_derivation(
        built_fmus, name, derive):
    """A state saved mid-run (serialized and read back) holds the last step and whether
    the check has warned: the continuation gives the same bits and the same warnings."""
    step, _, x, v = sine_input(name, 200)
    v = np.zeros_like(v) if not derive else v * 7.0  # a wrong rate: warned, or ignored

    def started():
        runner = FmuRunner(built_fmus[name])
        runner.fmu.setBoolean([runner.vr["rate_from_deflection"]], [derive])
        runner.initialize(x[0], v[0])
        runner.step(x[1], v[1], step)  # one step done: the check has its previous step
        return runner

    def rest(runner):
        outputs = [runner.step(xk, vk, step) for xk, vk in zip(x[2:-1], v[2:-1])]
        return np.array(outputs), warnings_of(runner)

    runner = started()
    time_at_save = runner.time
    saved = runner.fmu.serializeFMUstate(runner.fmu.getFMUstate())
    expected, expected_warnings = rest(runner)
    assert len(expected_warnings) == (0 if derive else 1)
    restored = FmuRunner(built_fmus[name])
    restored.fmu.setBoolean([restored.vr["rate_from_deflection"]], [not derive])
    restored.initialize(x[0], 0.0)
    restored.fmu.setFMUstate(restored.fmu.deSerializeFMUstate(saved))
    restored.time = time_at_save
    assert restored.fmu.getBoolean([restored.vr["rate_from_deflection"]]) == [derive]
    outputs, warnings = rest(restored)
    assert np.array_equal(outputs, expected) and warnings == expected_warnings
    # After the warning, a state saved then restored does not warn again.
    if not derive:
        again = restored.fmu.getFMUstate()
        restored.fmu.setFMUstate(again)
        restored.step(x[-1], 0.0, step)
        restored.step(x[-2], 0.0, step)
        assert len(warnings_of(restored)) == 1
    runner.free()
    restored.free()


def test_both_flavours_derive_the_same_bits(native_fmus, python_fmus):
    for name in FMU_NAMES:
        step, _, x, _ = sine_input(name, 100)
        runs = []
        for fmus in (native_fmus, python_fmus):
            runner = FmuRunner(fmus[name])
            runner.fmu.setBoolean([runner.vr["rate_from_deflection"]], [True])
            runner.initialize(x[0], 0.0)
            runs.append(np.array([runner.step(xk, 0.0, step) for xk in x[1:]]))
            runner.free()
        assert np.array_equal(runs[0], runs[1]), name
