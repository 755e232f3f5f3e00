"""The virtual test rig (fmu_components.lab.rig).

* Through the Python model and through either flavour of the built FMU it gives the same
  rows: the engines take the same steps with the same inputs, so they agree to 1e-9
  relative (on linux64 to the bit), far inside the integrator's tolerance (the rig's
  rtol, 1e-6).
* Its periodic steady state reproduces the independent reference solver (reference.py,
  scipy Radau at rtol 1e-10) under the same held-rate input, run two cycles longer than
  the rig ran: |K*|, loss angle, energy per cycle and secant stiffness within 0.1 %; and
  with its default secant rates, the reference solve of the continuous sine too.
* Its steady-state test stops where a long run has settled; the step and hold matches the
  reference too; a wrong parameters file is one line that says what to do.
"""

import csv
import json
import math

import numpy as np
import pytest

from fmu_components import cli

from fmu_components.verification import reference

from fmu_components.lab import rig, rig_plots
from fmu_components.lab.harmonics import first_harmonic
from fmu_components.runtime.catalog import COMPONENTS
from fmu_components.lab.signals import THESIS_SINES

QUANTITIES = ("dynamic_stiffness", "loss_angle_deg", "energy_per_cycle", "secant_stiffness")
REFERENCE_LIMIT = 1e-3  # the target: 0.1 %
LOADS = {name: COMPONENTS[name].outputs[0].name for name in COMPONENTS}


def thesis_point(name):
    """The component's standard sine (signals.THESIS_SINES): preload, amplitude, frequency."""
    return THESIS_SINES[name]


@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_model_and_fmu_engines_agree(built_fmus, name):
    preload, amplitude, frequency = thesis_point(name)
    through_model = rig.run_rig(name, [preload], [amplitude], [frequency], processes=1)[0]
    through_fmu = rig.run_rig(name, [preload], [amplitude], [frequency], engine="fmu",
                              fmu=built_fmus[name], processes=1)[0]
    assert through_fmu.cycles == through_model.cycles
    for quantity in QUANTITIES:
        assert getattr(through_fmu, quantity) == pytest.approx(
            getattr(through_model, quantity), rel=1e-9), quantity


@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_periodic_steady_state_reproduces_the_reference(name):
    preload, amplitude, frequency = thesis_point(name)
    setup = rig.make_setup(name)
    per_cycle = 100  # the reference takes a Radau solve per step
    row = rig.run_point(setup, preload, amplitude, frequency, samples_per_cycle=per_cycle)
    assert row.steady
    times, deflection, rates = rig.sine_input(setup, preload, amplitude, frequency,
                                              row.cycles + 2, samples_per_cycle=per_cycle)
    solved = reference.solve_held_rate(name, times, deflection, rates, read_after_set=True)
    expected = first_harmonic(times, deflection, solved[LOADS[name]], frequency, cycles=1)
    for quantity in QUANTITIES:
        assert getattr(row, quantity) == pytest.approx(getattr(expected, quantity),
                                                       rel=REFERENCE_LIMIT), quantity


@pytest.mark.parametrize("name, preload, amplitude, frequency", [
    ("TrackBushRadial", 3e-4, 2e-5, 20.0), ("TrackBushTorsion", *THESIS_SINES["TrackBushTorsion"])])
def test_secant_rates_follow_the_continuous_sine(name, preload, amplitude, frequency):
    """Against the reference solve of the smooth sine (no held rate at all): the rig's
    default secant rates are within 0.1 %, holding the sine's own rate at each sample is
    not (its path misses the next sample: the Maxwell springs see a different travel)."""
    omega = 2 * math.pi * frequency
    secant = rig.make_setup(name)
    row = rig.run_point(secant, preload, amplitude, frequency)
    times, deflection, _ = rig.sine_input(secant, preload, amplitude, frequency, row.cycles + 2)
    smooth = reference.solve_smooth(name, times,
                                    lambda t: preload + amplitude * math.sin(omega * t),
                                    lambda t: amplitude * omega * math.cos(omega * t))
    truth = first_harmonic(times, deflection, smooth[LOADS[name]], frequency, cycles=1)
    for quantity in QUANTITIES:
        assert getattr(row, quantity) == pytest.approx(getattr(truth, quantity),
                                                       rel=REFERENCE_LIMIT), quantity
    held = rig.run_point(rig.make_setup(name, rate="exact"), preload, amplitude, frequency)
    assert abs(held.loss_angle_deg / truth.loss_angle_deg - 1) > 10 * REFERENCE_LIMIT


def test_steady_state_is_where_a_long_run_settles():
    """TrackBushRadial at 0.3 mm and 20 Hz, among the slowest points of the documented sweep
    to settle (docs/rig.md)."""
    setup = rig.make_setup("TrackBushRadial")
    row = rig.run_point(setup, 3e-4, 3e-4, 20.0)
    assert row.steady and row.cycles > rig.MIN_CYCLES
    record = rig.sine_record(setup, 3e-4, 3e-4, 20.0, 4 * row.cycles)
    settled = first_harmonic(*record, 20.0, cycles=1)
    # the rig stops when the change still to come is below STEADY (1e-5); 1e-4 leaves room
    # for the geometric estimate of it
    def distance(result):
        return max(abs(getattr(result, q) / getattr(settled, q) - 1) for q in QUANTITIES)

    assert distance(row) < 1e-4
    # two cycles are not enough, and the rig says so
    early = rig.run_point(setup, 3e-4, 3e-4, 20.0, max_cycles=2)
    assert not early.steady and early.change > 1e-3
    assert distance(early) > max(1e-4, 10 * distance(row))


@pytest.mark.parametrize("name", ["TrackBushTorsion", "RoadWheelTyre"])
def test_step_and_hold_reproduces_the_reference(name):
    preload, amplitude, _ = thesis_point(name)
    setup = rig.make_setup(name)
    times, deflection, force = rig.relaxation_record(setup, preload, amplitude, hold=50.0)
    assert times[-1] == pytest.approx(rig.RISE_TIME + 50.0)
    assert np.all(np.diff(times) <= rig.LONGEST_STEP * (1 + 1e-12))
    rates = np.where(times < rig.RISE_TIME, amplitude / rig.RISE_TIME, 0.0)
    solved = reference.solve_held_rate(name, times, deflection, rates, read_after_set=True)
    expected = solved[LOADS[name]]
    assert np.max(np.abs(force - expected)) < 1e-3 * np.ptp(expected)
    # it relaxes: the force falls after the ramp
    held = times >= rig.RISE_TIME
    assert force[held][-1] < force[held][0] - 0.05 * np.ptp(expected)


def test_command_writes_the_table_and_plots(tmp_path):
    out = tmp_path / "rig"
    status = cli.main(["rig", "--component", "TrackBushRadial", "--preload", "3e-4",
                       "--amplitude", "2e-5", "1e-4", "--frequency", "1", "10",
                       "--hold", "10", "--out", str(out), "--processes", "2"])
    assert status == 0
    with open(out / "rig.csv", newline="") as f:
        lines = list(csv.reader(f))
    assert lines[0] == rig.csv_header(rig.CSV_COLUMNS, "TrackBushRadial")
    assert len(lines) == 5
    rows = rig.read_rows(out / "rig.csv")
    assert [(r["amplitude"], r["frequency"]) for r in rows] == [
        (2e-5, 1.0), (2e-5, 10.0), (1e-4, 1.0), (1e-4, 10.0)]
    assert all(r["dynamic_stiffness"] > 0 and 0 < r["loss_angle_deg"] < 90 for r in rows)
    # the Payne effect: the dynamic stiffness falls with amplitude
    assert rows[2]["dynamic_stiffness"] < rows[0]["dynamic_stiffness"]
    for name in ("rig_frequency.png", "rig_amplitude.png", "rig_relaxation.png",
                 "relaxation.csv"):
        assert (out / name).stat().st_size > 1000
    assert not (out / "equivalent.csv").exists()


def test_damper_gives_equivalent_stiffness_and_damping(tmp_path):
    out = tmp_path / "damper"
    assert cli.main(["rig", "--component", "RotaryDamper", "--preload", "0", "--amplitude",
                     "0.21", "--frequency", "0.75", "--hold", "1", "--out", str(out)]) == 0
    rows = rig.read_rows(out / "equivalent.csv")
    (k, ) = rig.read_rows(out / "rig.csv")
    delta = math.radians(k["loss_angle_deg"])
    omega = 2 * math.pi * 0.75
    assert rows[0]["equivalent_stiffness"] == pytest.approx(
        k["dynamic_stiffness"] * math.cos(delta), rel=1e-12)
    assert rows[0]["equivalent_damping"] == pytest.approx(
        k["dynamic_stiffness"] * math.sin(delta) / omega, rel=1e-12)
    # the energy of a cycle is that of the equivalent dashpot, pi c_eq omega A^2
    assert k["energy_per_cycle"] == pytest.approx(
        math.pi * rows[0]["equivalent_damping"] * omega * 0.21 ** 2, rel=1e-3)


def test_params_file_changes_the_model(tmp_path):
    params = tmp_path / "stiffer.json"
    params.write_text(json.dumps({"elastic.a1": 2 * 81.8e6}))
    thesis = rig.run_rig("TrackBushRadial", [3e-4], [1e-4], [1.0], processes=1)[0]
    stiffer = rig.run_rig("TrackBushRadial", [3e-4], [1e-4], [1.0], params=str(params),
                          processes=1)[0]
    # an elastic spring in parallel adds its stiffness to K' and nothing to K''
    assert stiffer.equivalent_stiffness - thesis.equivalent_stiffness == pytest.approx(81.8e6, rel=1e-3)
    assert stiffer.energy_per_cycle == pytest.approx(thesis.energy_per_cycle, rel=1e-6)


@pytest.mark.parametrize("content, message", [
    ('{"k9": 1.0}', "has no parameter 'k9'; its parameters are: k1, c1, xi1"),
    ('{"k1": "stiff"}', "must be a number"),
    ('{"k1": -1.0}', "must be positive"),
    ('[1, 2]', "must hold a JSON object"),
    ('{"k1": ', "is not JSON"),
])
def test_wrong_params_file_is_one_line(tmp_path, capsys, content, message):
    params = tmp_path / "params.json"
    params.write_text(content)
    with pytest.raises(SystemExit) as stop:
        cli.main(["rig", "--component", "TrackBushRadial", "--params", str(params),
                  "--preload", "3e-4", "--amplitude", "1e-4", "--frequency", "1",
                  "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    error = capsys.readouterr().err
    assert message in error
    assert len(error.strip().splitlines()) == 1 and "Traceback" not in error


@pytest.mark.parametrize("arguments, message", [
    (["--component", "Track"], "no component 'Track'"),
    (["--component", "RotaryDamper", "--structure", "four-element"], "no 'four-element' structure"),
    (["--component", "TrackBushRadial", "--engine", "fmu"], "needs --fmu PATH"),
    (["--component", "TrackBushRadial", "--engine", "fmu", "--fmu", "missing.fmu"], "missing.fmu: no such FMU"),
])
def test_wrong_requests_are_one_line(tmp_path, capsys, arguments, message):
    with pytest.raises(SystemExit) as stop:
        cli.main(["rig", *arguments, "--preload", "0", "--amplitude", "1e-4", "--frequency",
                  "1", "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    error = capsys.readouterr().err
    assert message in error and len(error.strip().splitlines()) == 1


def test_structure_comparison_shows_what_the_thesis_saw(tmp_path):
    """Section 6.3-6.4: the four-element model encloses the dual sine's small loops and
    relaxes fast at first; the final model less so; the simplified Haupt and Sedlan model
    least."""
    assert cli.main(["rig", "--component", "TrackBushTorsion", "--compare-structures",
                     "--out", str(tmp_path)]) == 0
    assert (tmp_path / "structures.png").stat().st_size > 1000
    assert "| four-element | Figs. 6.3-4, 6.3-5 |" in (tmp_path / "structures.md").read_text()
    table = {row["structure"]: row for row in rig_plots.compare_structures(tmp_path,
                                                                             processes=1)}
    loops = {s: row["small_loop_area_mean"] for s, row in table.items()}
    assert loops["four-element"] > loops["final"] > loops["haupt-sedlan"]
    early = {s: row["relaxed_0.1s"] for s, row in table.items()}
    assert early["four-element"] > early["final"] > early["haupt-sedlan"]


@pytest.mark.parametrize("name", sorted(COMPONENTS))
def test_the_fmu_engine_takes_fmi3_fmus_with_the_fmi2_numbers(all_fmus, name):
    """`rig --engine fmu --fmu fmus/fmi3/X.fmu` (a traceback before): the same rows as the
    FMI 2.0 FMU to the bit, the sine and the step-and-hold."""
    preload, amplitude, frequency = thesis_point(name)
    rows, holds = {}, {}
    for flavour in ("native", "fmi3"):
        path = all_fmus[flavour][name]
        rows[flavour] = rig.run_rig(name, [preload], [amplitude], [frequency], engine="fmu",
                                    fmu=path, processes=1)[0]
        setup = rig.make_setup(name, engine="fmu", fmu=path)
        holds[flavour] = rig.relaxation_record(setup, preload, amplitude, hold=1.0)[2]
    assert rows["native"] == rows["fmi3"]
    assert np.array_equal(holds["native"], holds["fmi3"])
    assert np.isfinite(holds["fmi3"]).all() and rows["fmi3"].dynamic_stiffness > 0.0


@pytest.mark.parametrize("component, preload, amplitude, meant", [
    ("RoadWheelTyre", "3.5", "1", "mm"),         # mm typed where m are expected
    ("TrackBushRadial", "0.3", "0.1", "mm"),
    ("TrackBushTorsion", "10", "5", "deg"),      # deg typed where rad are expected
])
def test_a_point_in_mm_or_deg_is_refused_as_signal_refuses_it(tmp_path, capsys, component,
                                                              preload, amplitude, meant):
    with pytest.raises(SystemExit) as stop:
        cli.main(["rig", "--component", component, "--preload", preload, "--amplitude",
                  amplitude, "--frequency", "1", "--out", str(tmp_path / "out")])
    assert stop.value.code == 2
    error = capsys.readouterr().err
    assert f"it looks like {meant}" in error and "Convert to SI" in error
    assert len(error.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_a_small_angle_that_may_be_in_deg_is_warned_about(tmp_path, capsys):
    """0.8 typed as rad for the torsion bush: past the 33 deg the thesis measured."""
    assert cli.main(["rig", "--component", "TrackBushTorsion", "--preload", "0.3",
                     "--amplitude", "0.5", "--frequency", "1", "--hold", "1",
                     "--out", str(tmp_path / "out")]) == 0
    error = capsys.readouterr().err
    assert "warning:" in error and "if the values are in deg" in error


def test_the_table_and_its_csv_say_their_units(tmp_path, capsys):
    out = tmp_path / "rig"
    assert cli.main(["rig", "--component", "TrackBushTorsion", "--preload", "0.1745",
                     "--amplitude", "0.0873", "--frequency", "1", "--hold", "1",
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()[0].split()
    for word in ("preload", "rad", "amplitude", "E/cycle", "J", "secant", "N.m/rad"):
        assert word in printed, printed
    assert printed.count("rad") == 2 and printed.count("N.m/rad") == 2  # |K*| and secant
    with open(out / "rig.csv", newline="") as f:
        header = next(csv.reader(f))
    assert header == ["preload [rad]", "amplitude [rad]", "frequency [Hz]",
                      "dynamic_stiffness [N.m/rad]", "loss_angle_deg",
                      "energy_per_cycle [J]", "secant_stiffness [N.m/rad]"]
    (row,) = rig.read_rows(out / "rig.csv")  # read back by the bare names
    assert row["preload"] == 0.1745 and row["dynamic_stiffness"] > 0
