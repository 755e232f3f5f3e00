"""The multibody-host examples (examples/): the coupling library's stepping against the
independent solve, the Kelvin helpers, and short runs of both exudyn examples checked for
physical sanity, against the station's independent reference and for what the coupling
study and --csv write. The exudyn runs need the `examples` extra (pip install -e
".[examples]"); without it they are skipped with that reason."""

import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from fmu_components.coupling import CouplingError, FmuComponent
from fmu_components.coupling.kelvin import harmonic_kelvin_equivalent, kelvin_coefficients
from fmu_components.lab.signals import secant_rates, sine, time_grid
from fmu_components.verification import reference

from conftest import ROOT, peak_to_peak

sys.path.insert(0, str(ROOT / "examples"))  # the example scripts, imported as modules

try:
    import exudyn  # noqa: F401
    HAVE_EXUDYN = True
except ImportError:
    HAVE_EXUDYN = False
needs_exudyn = pytest.mark.skipif(
    not HAVE_EXUDYN, reason='exudyn is not installed: pip install -e ".[examples]"')


# --- the coupling library's stepping, without a host --------------------------------------

def test_a_trial_steps_along_the_secant_as_the_held_rate_cosimulation(built_fmus):
    """trial(t, x) feeds x(t_prev) and the secant rate: after each accepted step the FMU's
    output is the independent solve's under that input convention."""
    t = time_grid(0.25, 1e-3)
    x = sine(t, 3.5e-3, 1e-3, 20.0)
    expected = reference.solve_held_rate("RoadWheelTyre", t, x, secant_rates(t, x))["force"]
    tyre = FmuComponent(built_fmus["RoadWheelTyre"], "tyre")
    try:
        tyre.start(t[0], x[0])
        forces = [tyre.load]
        for ti, xi in zip(t[1:], x[1:]):
            tyre.begin_step()
            tyre.trial(ti, xi - 1e-4)  # a first solve's answer, thrown away
            tyre.trial(ti, xi)
            tyre.accept()
            forces.append(tyre.load)
    finally:
        tyre.free()
    error = np.max(np.abs(np.array(forces) - expected)) / peak_to_peak(expected)
    assert error < 0.5e-2


def test_host_load_relaxed_before_start_then_lagged_with_tangent(built_fmus):
    tyre = FmuComponent(built_fmus["RoadWheelTyre"], "tyre", unilateral=True)
    try:
        x0 = 3.24e-3
        relaxed = reference.solve_held_rate("RoadWheelTyre", [0.0, 1e-3], [x0, x0],
                                            [0.0, 0.0])["force"][0]
        assert tyre.host_load(x0) == pytest.approx(relaxed, rel=1e-12)
        assert 10.5e3 < relaxed < 11.5e3  # the thesis: about 11 kN at 3.24 mm, section 5.1.1
        tyre.start(0.0, x0)
        tyre.begin_step()
        tyre.trial(1e-3, x0 + 1e-5)
        tyre.accept()
        tyre.law = tyre.lagged_law()
        load, stiffness = tyre.load, tyre.stiffness
        assert stiffness > 0.0
        assert tyre.host_load(x0 + 2e-5) == pytest.approx(load + stiffness * 1e-5, rel=1e-12)
        # A contact: nothing at or below zero compression, never a pull.
        assert tyre.host_load(0.0) == 0.0
        assert tyre.host_load(-1e-3) == 0.0
        assert tyre.host_load(1e-9) >= 0.0
    finally:
        tyre.free()


def test_kelvin_coefficients_recover_a_kelvin_element():
    """Eqs. 10.1-2 and 10.1-3 over whole cycles return a linear element's own k and c."""
    t = np.arange(2000) * 1e-3  # two cycles at 1 Hz
    x = 3e-3 + 1e-3 * np.sin(2 * np.pi * t)
    xdot = 2 * np.pi * 1e-3 * np.cos(2 * np.pi * t)
    k, c = kelvin_coefficients(x, xdot, 500.0 + 2e6 * x + 3e4 * xdot)
    assert k == pytest.approx(2e6, rel=1e-9)
    assert c == pytest.approx(3e4, rel=1e-9)


def test_harmonic_equivalents_of_the_fmus_are_physical(built_fmus):
    """Tyre: k_eq between its elastic slope and the loop's steepest tangent, c_eq > 0.
    Damper: dissipative (c_eq > 0), and softer than its gas spring at small deflection."""
    k, c, mean_load = harmonic_kelvin_equivalent(
        built_fmus["RoadWheelTyre"], 3.24e-3, 1e-3, 10.0)
    elastic_slope = 2.17e6 - 2 * 2.14e8 * 3.24e-3 + 3 * 1.82e11 * 3.24e-3 ** 2  # Eq. 5.3.1-3
    assert elastic_slope < k < 3 * elastic_slope
    assert c > 0.0
    assert 9e3 < mean_load < 13e3
    k, c, _ = harmonic_kelvin_equivalent(built_fmus["RotaryDamper"], 0.0, 0.1, 2.0)
    assert c > 0.0
    assert 0.0 < k < 2 * 800.0 / 0.03  # gas-spring stiffness 2 C1 / C2 at zero deflection


# --- road-wheel station in exudyn -----------------------------------------------------------

@pytest.fixture(scope="module")
def station_runs(built_fmus):
    import road_wheel_station as station

    fmu_dir = built_fmus["RoadWheelTyre"].parent
    profile = station.RoadProfile()
    speed = 8.0  # the bump lies between 0.125 and 0.25 s
    tyre = FmuComponent(built_fmus["RoadWheelTyre"], "tyre_static")
    linear = station.Linearisation(fmu_dir, station.static_tyre_compression(tyre))
    tyre.free()
    runs = {"FMUs": station.simulate(speed, profile, 2.5e-4, fmu_dir, end_time=0.3),
            "linear": station.simulate(speed, profile, 2.5e-4, fmu_dir, linear, end_time=0.3)}
    return station, runs


@needs_exudyn
@pytest.mark.parametrize("model", ["FMUs", "linear"])
def test_station_starts_in_static_equilibrium(station_runs, model):
    station, runs = station_runs
    result = runs[model]
    g = station.GRAVITY
    assert abs(result["hull_acceleration"][0]) < 1e-6 * g
    assert result["hull_force"][0] == pytest.approx(station.HULL_MASS * g, rel=1e-9)
    assert result["tyre_force"][0] == pytest.approx(station.STATION_MASS * g, rel=1e-9)
    assert result["damper_torque"][0] == 0.0
    assert result["arm_angle"][0] == 0.0


@needs_exudyn
@pytest.mark.parametrize("model", ["FMUs", "linear"])
def test_station_outputs_are_finite_and_the_tyre_never_pulls(station_runs, model):
    _, runs = station_runs
    result = runs[model]
    for key in ("hull_acceleration", "hull_force", "arm_angle", "damper_torque",
                "tyre_compression", "tyre_force"):
        assert np.all(np.isfinite(result[key])), key
    assert np.all(result["tyre_force"] >= 0.0)
    # The bump was driven over: the arm went into bump and the tyre was loaded above static.
    assert result["arm_angle"].max() > math.radians(2.0)
    assert result["tyre_force"].max() > 1.5 * result["tyre_force"][0]


@needs_exudyn
def test_station_force_into_hull_is_what_moves_it(station_runs):
    """The pivot's reaction on the hull (exudyn's joint force) equals M (a + g): the
    hull's only vertical loads are its weight and the pivot."""
    station, runs = station_runs
    result = runs["FMUs"]
    expected = station.HULL_MASS * (result["hull_acceleration"] + station.GRAVITY)
    assert np.max(np.abs(result["hull_force"] - expected)) < 1e-6 * np.max(np.abs(expected))


@needs_exudyn
def test_station_damper_dissipates_energy(station_runs):
    """The FMU's dashpot dissipates (its power T_d(w_r) w_r is never negative), and the work
    done on the damper by the arm is positive and covers that dissipation, the rest being
    stored in its gas spring and rotor."""
    _, runs = station_runs
    result = runs["FMUs"]
    dissipation = result["dashpot_dissipation"]
    assert np.all(np.diff(dissipation) >= 0.0)
    assert dissipation[-1] > 100.0  # J: the bump passes through the damper
    assert np.all(result["damper_work"] >= -1e-3)  # J: a passive part, relaxed at the start
    work = result["damper_work"][-1]
    assert work > 0.0
    assert work >= 0.98 * dissipation[-1]


# --- track span in exudyn ------------------------------------------------------------------

@pytest.fixture(scope="module")
def span_run(built_fmus):
    import track_span

    span = track_span.TrackSpan(links=10, fmu_dir=built_fmus["TrackBushRadial"].parent)
    return track_span, span, span.run(0.15, 1e-3)


@needs_exudyn
def test_span_starts_in_static_equilibrium_under_the_tension(span_run):
    track_span, span, result = span_run
    assert result["joint_torque"].shape == (len(result["time"]), span.links + 1)
    assert np.max(np.abs(result["link_acceleration"][0])) < 1e-6 * track_span.GRAVITY
    # Gravity sags the span, so the pins carry a little more than the horizontal tension.
    forces = result["radial_force"][0]
    assert np.all(forces >= track_span.TENSION) and np.all(forces < 1.01 * track_span.TENSION)
    assert result["link_height"][0][span.links // 2] < -5e-3
    # Both end links are held level: the joint angles add up to nothing.
    assert abs(np.sum(result["joint_angle"][0])) < 1e-9
    # Near the straight line the bushes hold the -130 N.m of their 10 deg live angle.
    assert np.all(np.abs(result["joint_torque"][0] + 130.4) < 40.0)


@needs_exudyn
def test_span_outputs_are_finite_and_the_lift_travels(span_run):
    _, span, result = span_run
    for key in ("joint_torque", "joint_angle", "radial_force", "link_height"):
        assert np.all(np.isfinite(result[key])), key
    rise = result["link_height"][:, -1] - result["link_height"][0, -1]  # link next to the wheel
    assert rise.max() > 0.5 * span.lift
    assert peak_to_peak(result["joint_torque"][:, -1]) > 5.0  # N.m at the lifted joint


# --- coupling in exudyn: the study, the reference, errors, CSV ------------------------------

@needs_exudyn
def test_station_study_against_its_independent_reference(native_fmus):
    """Over the first 0.2 s at 8 m/s: the station's own equations with the ME FMUs (Radau)
    agree with the converged co-simulation at a fine step; the study's rows count what
    each scheme costs, and `corrected` adds far less error of its own than `explicit`."""
    import road_wheel_station as station

    fmu_dir = native_fmus["RoadWheelTyre"].parent
    reference, agreement, table = station.coupling_study(
        8.0, station.RoadProfile(), fmu_dir, steps=(1e-3,),
        schemes=("explicit", "corrected", "converged"), end_time=0.2)
    assert reference["events"] >= 0 and reference["evaluations"] > 0
    assert agreement["hull_acceleration"] < 0.05 and agreement["tyre_force"] < 0.1, agreement
    explicit, corrected, converged = (table[s, 1e-3] for s in ("explicit", "corrected",
                                                                "converged"))
    assert explicit["costs"]["do_steps"] == 1.0 and explicit["costs"]["restores"] == 0.0
    assert corrected["costs"]["do_steps"] == 2.0 and corrected["costs"]["restores"] == 1.0
    assert converged["costs"]["do_steps"] > 2.0
    assert corrected["own"]["hull_acceleration"] < explicit["own"]["hull_acceleration"] / 20
    assert converged["own"]["hull_acceleration"] == 0.0
    # What remains against the reference is exudyn's own step error, the same for both.
    assert corrected["total"]["hull_acceleration"] == pytest.approx(
        converged["total"]["hull_acceleration"], abs=0.1)


@needs_exudyn
def test_the_coupling_study_benchmark_prints_both_tables():
    """benchmarks/coupling_study.py, cut to one host step and a short run."""
    import subprocess

    run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "coupling_study.py"),
                          "--steps", "2e-3", "--end-time", "0.04"],
                         capture_output=True, text=True, timeout=600, cwd=ROOT)
    assert run.returncode == 0, run.stderr[-2000:]
    for heading in ("## Road-wheel station at 8 m/s", "## Track span"):
        assert heading in run.stdout
    rows = [line for line in run.stdout.splitlines() if line.startswith("| corrected | 2 ms")]
    assert len(rows) == 2 and all("| 2.00 | 1.00 | 1.00 | 2.00 |" in row for row in rows)
    # The station's long silent parts, the reference solve and its fine co-simulation, show
    # their progress on stderr, up to the end of the run.
    for bar in ("reference (Radau)", "converged at 0.03125 ms"):
        assert re.search(re.escape(bar) + r": 100%.*0\.040/0\.040 s simulated", run.stderr), bar


@needs_exudyn
def test_station_csv_and_scheme_from_the_command_line(native_fmus, tmp_path, capsys):
    """Every CSV column and printed figure carries its unit; the linear station's CSV has
    no columns of the dashpot and rotor it does not have."""
    import csv

    import road_wheel_station as station

    station.main(["--speeds", "8", "--step", "2e-3", "--end-time", "0.1", "--coupling",
                  "explicit", "--csv", "--out", str(tmp_path),
                  "--fmu-dir", str(native_fmus["RoadWheelTyre"].parent)])
    columns = ["time (s)", "hull_acceleration (m/s2)", "hull_force (N)", "tyre_force (N)",
               "damper_torque (N.m)", "arm_angle (rad)", "tyre_compression (m)"]
    inside = ["dashpot_torque (N.m)", "rotor_rate (rad/s)"]
    tables = {}
    for suffix, expected in (("", columns + inside), ("_linear", columns)):
        with open(tmp_path / f"station_8mps{suffix}.csv", newline="") as f:
            rows = list(csv.reader(f))
        assert rows[0] == expected
        tables[suffix] = data = np.array(rows[1:], dtype=float)
        assert not np.isnan(data).all(axis=0).any()  # no column of NaN alone
    data = dict(zip(columns + inside, tables[""].T))
    assert data["time (s)"][-1] == pytest.approx(0.1)
    assert data["tyre_force (N)"][0] == pytest.approx(station.STATION_MASS * station.GRAVITY,
                                                      rel=1e-9)  # N, both half-wheels
    printed = capsys.readouterr().out.splitlines()
    rows = [line for line in printed if re.match(r"\s*8\s+(FMUs|linear)\s", line)]
    assert len(rows) == 2 and all(line.rstrip().endswith(" N.m") for line in rows), rows


@needs_exudyn
def test_an_fmu_error_in_exudyn_reaches_the_caller_with_its_own_message(native_fmus):
    """Raised in exudyn's hooks, the coupling's error stops the solve and comes back as
    itself, naming the component and the time."""
    import road_wheel_station as station

    model = station.Station(8.0, station.RoadProfile(), native_fmus["RoadWheelTyre"].parent,
                            path="python")  # the compiled path's errors: tests/test_bank.py
    trial = model.tyre.trial

    def failing(time, deflection, rate=None, pieces=1):
        if time > 0.01:
            raise CouplingError("tyre", time, "fmi2DoStep returned fmi2Error: test")
        return trial(time, deflection, rate, pieces)

    model.tyre.trial = failing
    with pytest.raises(CouplingError, match=r"tyre at t = 0.01\d* s: fmi2DoStep"):
        model.run(0.05, 1e-3)


@needs_exudyn
def test_a_discarded_fmu_step_makes_exudyn_retry_it_shorter(native_fmus):
    """A rotor-like coordinate held still for 2 ms, then driven at 100 rad/s through the
    damper: its integrator cannot finish that 1 ms step (fmi2Discard), the coupling asks
    exudyn for a shorter one, exudyn retries, and the run goes on to the end."""
    from exudyn.itemInterface import (CoordinateConstraint, MarkerNodeCoordinate,
                                      NodeGenericODE2, NodePointGround, ObjectGenericODE2,
                                      ObjectConnectorCoordinateSpringDamper)

    from fmu_components.coupling import Coupling
    from fmu_components.coupling.exudyn_host import connector_state, solve

    mbs = exudyn.SystemContainer().AddSystem()
    ground = mbs.AddNode(NodePointGround(referenceCoordinates=[0.0, 0.0, 0.0]))
    node = mbs.AddNode(NodeGenericODE2(referenceCoordinates=[0.0], initialCoordinates=[0.0],
                                       initialCoordinates_t=[0.0], numberOfODE2Coordinates=1))
    mbs.AddObject(ObjectGenericODE2(nodeNumbers=[node], massMatrix=[[0.5]],
                                    stiffnessMatrix=[[0.0]], dampingMatrix=[[0.0]]))
    held = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=ground, coordinate=0))
    moved = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=node, coordinate=0))
    mbs.AddObject(CoordinateConstraint(
        markerNumbers=[held, moved],
        offsetUserFunction=lambda mbs, t, item, offset: max(0.0, 100.0 * (t - 2e-3))))
    damper = FmuComponent(native_fmus["RotaryDamper"], "damper")
    connector = mbs.AddObject(ObjectConnectorCoordinateSpringDamper(
        markerNumbers=[held, moved],
        springForceUserFunction=lambda mbs, t, item, u, v, *_: damper.host_load(u, v)))
    times = []
    coupling = Coupling("corrected", record=times.append)
    coupling.add(damper, lambda: tuple(float(v) for v in connector_state(mbs, connector)))
    mbs.Assemble()
    host = solve(mbs, coupling, 6e-3, 1e-3)
    assert coupling.retries >= 1 and host.attempts > coupling.steps
    assert min(np.diff(times)) < 1e-3 and times[-1] == pytest.approx(6e-3)
    assert math.isfinite(damper.load) and damper.load > 0.0


@needs_exudyn
def test_track_span_prints_the_link_heights_it_plots(native_fmus, tmp_path, capsys):
    """The printed range is the plotted one: heights from the static state."""
    import track_span

    track_span.main(["--end-time", "0.05", "--step", "1e-3", "--csv", "--out", str(tmp_path),
                     "--fmu-dir", str(native_fmus["TrackBushRadial"].parent)])
    printed = re.search(r"link heights from static (-?[\d.]+) to (-?[\d.]+) mm",
                        capsys.readouterr().out)
    header = (tmp_path / "track_span.csv").read_text().splitlines()[0].split(",")
    assert all(re.fullmatch(r"\w+ \((s|m|m/s2|rad|N\.m|N)\)", name) for name in header), header
    data = np.genfromtxt(tmp_path / "track_span.csv", delimiter=",", names=True)
    heights = np.column_stack([data[n] for n in data.dtype.names
                               if n.startswith("link_height_")])
    rise = (heights - heights[0]) * 1e3
    assert float(printed.group(1)) == pytest.approx(rise.min(), abs=0.051)
    assert float(printed.group(2)) == pytest.approx(rise.max(), abs=0.051)


# --- the examples on FMI 3.0 FMUs ------------------------------------------------------------

@needs_exudyn
def test_the_station_on_fmi3_fmus_gives_the_fmi2_run_to_the_bit(all_fmus):
    """The station at 8 m/s, 1 ms, the default coupling (the tyre's curvature from its
    directional derivative, the damper's step linearised through a Model Exchange
    instance, every step saved and restored): FMI 3.0 FMUs give FMI 2.0's histories on the
    Python path to the bit. On the compiled path the bank linearises an FMI 2.0 damper in
    C and an FMI 3.0 one through linearised.py: the same to the matrix exponential's
    round-off."""
    import road_wheel_station as station

    def run(fmus, path):
        return station.simulate(8.0, station.RoadProfile(), 1e-3,
                                all_fmus[fmus]["RoadWheelTyre"].parent, end_time=0.2, path=path)

    runs = [run(f, "python") for f in ("native", "fmi3")]
    for key in ("hull_acceleration", "tyre_force", "damper_torque", "arm_angle"):
        assert np.array_equal(runs[0][key], runs[1][key]), key
    assert runs[0]["costs"] == runs[1]["costs"]
    assert np.ptp(runs[1]["tyre_force"]) > 1e3
    compiled = [run(f, "compiled") for f in ("native", "fmi3")]
    for key in ("hull_acceleration", "tyre_force", "damper_torque", "arm_angle"):
        scale = np.ptp(runs[0][key])
        assert np.max(np.abs(compiled[0][key] - compiled[1][key])) <= 1e-9 * scale, key


def test_the_examples_take_fmi3_fmus_with_fmi_3():
    import argparse

    import example_fmus

    parser = argparse.ArgumentParser()
    example_fmus.add_fmu_arguments(parser)
    assert example_fmus.fmu_dir_of(parser.parse_args([])) == ROOT / "fmus"
    assert example_fmus.fmu_dir_of(parser.parse_args(["--fmi", "3"])) == ROOT / "fmus" / "fmi3"
    assert example_fmus.fmu_dir_of(parser.parse_args(["--fmi", "3", "--fmu-dir", "x"])) == \
        Path("x")
