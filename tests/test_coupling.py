"""The host-side coupling library (fmu_components.coupling), without a multibody host:
a mass on the tyre against a monolithic solve of the spec's equations, rollback that
leaves an FMU bit-identical, a discarded step retried shorter, memory over many
corrected steps, and the errors a host gets."""

import ast
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from fmu_components.coupling import Coupling, CouplingError, FmuComponent, LoadLaw
from fmu_components.coupling.linearised import expm
from fmu_components.verification import reference

from coupling_host import MassHost

MASS = 1000.0  # kg on one tyre: 9.8 kN, about the station's static load (11 kN)
GRAVITY = 9.81
GROUND = (1e-3, 8.0)  # m, Hz: the track link rising and falling under the tyre
VERSIONS = ("2.0", "3.0")  # the FMI versions of the native FMUs
PREFIX = {"2.0": "fmi2", "3.0": "fmi3"}


@pytest.fixture(scope="module")
def versions(all_fmus):
    """The native FMUs by FMI version: the coupling drives both alike."""
    return {"2.0": all_fmus["native"], "3.0": all_fmus["fmi3"]}


def ground(t):
    return GROUND[0] * math.sin(2 * math.pi * GROUND[1] * t)


def ground_rate(t):
    return GROUND[0] * 2 * math.pi * GROUND[1] * math.cos(2 * math.pi * GROUND[1] * t)


def mass_on_tyre_reference(end_time, t_eval):
    """The mass and the tyre's equations (spec sections 2, reference.py) in one ODE, by
    Radau at rtol 1e-10: state [z, z', s, w, r], compression x = ground - z."""
    equations = reference.equations_for("RoadWheelTyre")
    a0, a1, a2, a3 = equations.spec.elastic
    x0 = brentq(lambda x: a0 + a1 * x + a2 * x ** 2 + a3 * x ** 3 - MASS * GRAVITY,
                1e-4, 6e-3, xtol=1e-15)

    def kinematics(t, y):
        return ground(t) - y[0], ground_rate(t) - y[1]

    def rhs(t, y):
        x, rate = kinematics(t, y)
        force = equations.outputs(y[2:], x)["force"]
        return [y[1], force / MASS - GRAVITY,
                *equations.rhs(t, y[2:], lambda _: x, rate)]

    atol = np.concatenate([[1e-13, 1e-11], equations.atol])
    solution = solve_ivp(rhs, (0.0, end_time), [-x0, 0.0, 0.0, 0.0, 0.0], method="Radau",
                         rtol=1e-10, atol=atol, t_eval=t_eval)
    assert solution.success
    return np.array([rhs(t, y)[1] for t, y in zip(solution.t, solution.y.T)])


def run_mass(fmu, step, end_time, scheme="corrected", **host):
    tyre = FmuComponent(fmu, "tyre", unilateral=True)
    mass = MassHost(tyre, MASS, ground, ground_rate, scheme=scheme, gravity=GRAVITY, **host)
    mass.equilibrium(-3e-3)
    return mass, mass.run(end_time, step)


def test_mass_on_the_tyre_converges_to_the_monolithic_solve(built_fmus):
    """The error against the monolithic Radau solve (mass acceleration, max on a 2 ms grid,
    % of its range) falls with the host step, by about its square (Newmark's order)."""
    end_time = 0.4
    grid = np.arange(0.0, end_time + 1e-12, 2e-3)
    expected = mass_on_tyre_reference(end_time, grid)
    errors = []
    for step in (2e-3, 1e-3, 5e-4, 2.5e-4):
        _, result = run_mass(built_fmus["RoadWheelTyre"], step, end_time)
        got = np.interp(grid, result["time"], result["acceleration"])
        errors.append(100 * np.max(np.abs(got - expected)) / np.ptp(expected))
    assert all(later < earlier / 2.5 for earlier, later in zip(errors, errors[1:])), errors
    assert errors[-1] < 0.05, errors


@pytest.mark.parametrize("version", VERSIONS)
def test_rejected_steps_leave_the_fmu_bit_identical(versions, version):
    tyre = FmuComponent(versions[version]["RoadWheelTyre"], "tyre", unilateral=True)
    try:
        x = [3e-3, 3.4e-3, 3.1e-3]
        coupling = Coupling("converged")
        coupling.add(tyre, lambda: (x[0], 0.0))
        coupling.start(0.0)
        for time, deflection in ((1e-3, 3.2e-3), (2e-3, 3.3e-3)):  # some history
            x[0] = deflection
            coupling.begin_step(time)
            while coupling.end_pass(time).repeat:
                pass
            coupling.accept(time)
        before = tyre.serialized_state()
        for passes in (1, 2, 5):
            coupling.begin_step(3e-3)
            for deflection in x[1:1 + passes] + [3.0e-3] * max(0, passes - 2):
                x[0] = deflection
                coupling.end_pass(3e-3)
            coupling.reject()
            assert tyre.serialized_state() == before
        assert tyre.do_steps > 0 and tyre.restores > 0
    finally:
        tyre.free()


def test_a_host_that_gives_steps_up_gets_the_same_run(native_fmus):
    """Steps solved, then given up by the host and solved again, end where the run
    without them ends, to the bit."""
    mass, plain = run_mass(native_fmus["RoadWheelTyre"], 1e-3, 0.1)
    again, rejecting = run_mass(native_fmus["RoadWheelTyre"], 1e-3, 0.1, reject_every=3)
    assert again.rejected > 10
    assert np.array_equal(plain["load"], rejecting["load"])


@pytest.mark.parametrize("version", VERSIONS)
def test_a_discarded_step_makes_the_host_retry_shorter(versions, version):
    """The damper driven at 100 rad/s from rest: its integrator cannot finish a 1 ms
    step (Discard), so the coupling asks the host for a shorter one, which it can."""
    damper = FmuComponent(versions[version]["RotaryDamper"], "damper")
    coupling = Coupling("corrected")
    clock = [0.0]
    coupling.add(damper, lambda: (100.0 * clock[0], 100.0 if clock[0] > 0.0 else 0.0))
    coupling.start(0.0)  # at rest
    time, steps = 0.0, []
    try:
        while time < 2e-3 - 1e-12:
            step = min(1e-3, 2e-3 - time)
            while True:
                clock[0] = time + step
                coupling.begin_step(time + step)
                verdict = coupling.end_pass(time + step)
                while verdict.repeat:
                    verdict = coupling.end_pass(time + step)
                if verdict.retry_step is None:
                    break
                assert verdict.retry_step < step
                step = verdict.retry_step
            coupling.accept(time + step)
            time += step
            steps.append(step)
        assert coupling.retries >= 1
        assert steps[0] <= 5e-4 and sum(steps) == pytest.approx(2e-3)
        assert math.isfinite(damper.load) and damper.load > 0.0
    finally:
        coupling.free()


@pytest.mark.parametrize("version", VERSIONS)
def test_a_host_that_cannot_retry_gets_the_fmu_step_cut(versions, version):
    damper = FmuComponent(versions[version]["RotaryDamper"], "damper")
    coupling = Coupling("explicit", host_can_retry=False)
    deflection = [0.0]
    coupling.add(damper, lambda: (deflection[0], 0.0))
    coupling.start(0.0)  # at rest
    deflection[0] = 0.1  # then 100 rad/s over 1 ms
    try:
        coupling.begin_step(1e-3)
        assert not coupling.end_pass(1e-3).repeat
        coupling.accept(1e-3)
        assert damper.do_steps > 2  # the one discarded, then its pieces
        assert math.isfinite(damper.load)
    finally:
        coupling.free()


def test_ten_thousand_corrected_steps_keep_memory_flat(native_fmus):
    """One FMU state per instance, reused: the live states stay at one and the process
    does not grow between 2,000 and 10,000 steps (the damper also has its linearising
    Model Exchange instance working every pass)."""
    def resident_kib():
        return int(Path("/proc/self/statm").read_text().split()[1]) * 4

    tyre = FmuComponent(native_fmus["RoadWheelTyre"], "tyre", unilateral=True)
    damper = FmuComponent(native_fmus["RotaryDamper"], "damper")
    coupling = Coupling("corrected")
    clock = [0.0]
    coupling.add(tyre, lambda: (3e-3 + 1e-3 * math.sin(60 * clock[0]), 0.0))
    coupling.add(damper, lambda: (0.05 * math.sin(30 * clock[0]), 0.0))
    coupling.start(0.0)
    try:
        for step in range(1, 10_001):
            clock[0] = step * 1e-4
            coupling.begin_step(clock[0])
            while coupling.end_pass(clock[0]).repeat:
                pass
            coupling.accept(clock[0])
            if step == 2_000:
                early = resident_kib()
            assert tyre.live_states == damper.live_states == 1
        grown = resident_kib() - early
        assert tyre.do_steps == damper.do_steps == 20_000
        assert tyre.saves == 10_000 and tyre.restores == 10_000
    finally:
        coupling.free()
    assert tyre.live_states == damper.live_states == 0
    assert grown < 512, f"{grown} KiB more after 8,000 further steps"


@pytest.mark.parametrize("version", VERSIONS)
def test_fmu_errors_name_the_component_and_the_time(versions, version):
    tyre = FmuComponent(versions[version]["RoadWheelTyre"], "front_tyre", unilateral=True)
    try:
        tyre.start(0.0, 3e-3)
        tyre.begin_step()
        with pytest.raises(CouplingError, match=rf"front_tyre at t = 0 s: .*{PREFIX[version]}"
                                                r"Error.*compression"):
            tyre.trial(1e-3, math.nan)
    finally:
        tyre.free()


def test_a_non_finite_output_raises(native_fmus):
    tyre = FmuComponent(native_fmus["RoadWheelTyre"], "rear_tyre", unilateral=True)
    try:
        tyre.start(0.0, 3e-3)
        tyre.begin_step()
        real = tyre.instance.get
        tyre.instance.get = lambda reals: [math.inf if i == 0 else v
                                           for i, v in enumerate(real(reals))]
        with pytest.raises(CouplingError, match=r"rear_tyre at t = 0.001 s: output force = "
                                                r"inf is not finite"):
            tyre.trial(1e-3, 3.1e-3)
        tyre.instance.get = real
    finally:
        tyre.free()


def test_the_iterated_scheme_solves_again_only_where_two_solves_leave_the_loads_apart(
        native_fmus):
    """`iterated` takes corrected's two solves (also where the first already agrees), a
    third where the second's loads still differ by more than 1e-4 of their scale, none
    where they agree, and warns where its eight solves are spent."""
    from fmu_components.coupling.schemes import Converged, scheme_named

    iterated = scheme_named("iterated")
    assert not iterated.done(1, 0.0) and iterated.done(2, 0.0) and Converged().done(1, 0.0)
    tyre = FmuComponent(native_fmus["RoadWheelTyre"], "tyre", unilateral=True)
    coupling = Coupling("iterated")
    deflection = [3e-3]
    coupling.add(tyre, lambda: (deflection[0], 0.0))
    coupling.start(0.0)
    try:
        coupling.begin_step(1e-3)
        repeats = []
        for x in (3.5e-3, 3.2e-3, 3.2e-3):  # the third at the second's: its law is exact
            deflection[0] = x
            repeats.append(coupling.end_pass(1e-3).repeat)
        assert repeats == [True, True, False]
        coupling.accept(1e-3)
        coupling.begin_step(2e-3)
        with pytest.warns(UserWarning, match="still differ .* after 8 passes"):
            for k in range(8):  # a host far from the law at every pass
                deflection[0] = 3.5e-3 if k % 2 else 3.1e-3
                verdict = coupling.end_pass(2e-3)
        assert not verdict.repeat and coupling.unconverged_steps == 1
    finally:
        coupling.free()


def test_the_converged_scheme_warns_where_its_pass_limit_stops_it(native_fmus):
    tyre = FmuComponent(native_fmus["RoadWheelTyre"], "tyre", unilateral=True)
    coupling = Coupling("converged")
    coupling.scheme.passes = 2
    deflection = [3e-3]
    coupling.add(tyre, lambda: (deflection[0], 0.0))
    coupling.start(0.0)
    try:
        coupling.begin_step(1e-3)
        deflection[0] = 3.5e-3  # a host far from the law: its answer moves each pass
        coupling.end_pass(1e-3)
        deflection[0] = 3.2e-3
        with pytest.warns(UserWarning, match="still differ .* after 2 passes"):
            coupling.end_pass(1e-3)
        assert coupling.unconverged_steps == 1
    finally:
        coupling.free()


def test_load_laws():
    law = LoadLaw(3e-3, 1e4, 8e6)
    assert law(3.1e-3) == pytest.approx(1e4 + 8e6 * 1e-4)
    curved = LoadLaw(3e-3, 1e4, 8e6, curvature=4e9)
    assert curved(3.1e-3) == pytest.approx(1e4 + (8e6 + 2e9 * 1e-4) * 1e-4)
    assert curved(2e-3) == pytest.approx(1e4 - 6e6 * 1e-3)
    assert curved(-2e-3) == pytest.approx(1e4 - 4e6 * 5e-3)  # secant held at K/2: monotone
    contact = LoadLaw(3e-3, 1e4, 8e6, unilateral=True, touch_stiffness=2e6)
    assert contact(0.0) == contact(-1e-3) == 0.0
    assert contact(1e-3) == 0.0  # 1e4 - 8e6 * 2e-3 < 0: no pull
    lifted = LoadLaw(-1e-4, 0.0, 0.0, unilateral=True, touch_stiffness=2e6)
    assert lifted(5e-4) == pytest.approx(1e3)  # out of contact, the contact's stiffness


def test_a_law_with_a_kink_goes_on_with_the_tangent_beyond_it():
    law = LoadLaw(3e-3, 1e4, 8e6, kink=2.9e-3, beyond=3e7, side=1.0)
    assert law(3.1e-3) == pytest.approx(1e4 + 8e6 * 1e-4)  # on its side, as without
    assert law.kink_load == pytest.approx(1e4 - 8e6 * 1e-4)
    assert law(2.8e-3) == pytest.approx(law.kink_load - 3e7 * 1e-4)  # beyond: continuous
    unkinked = LoadLaw(3e-3, 1e4, 8e6, kink=2.9e-3, beyond=3e7, side=0.0)
    assert unkinked(2.8e-3) == LoadLaw(3e-3, 1e4, 8e6)(2.8e-3)


def _bush_stepped_loading(path, steps=20, rate=2e-3, step=1e-3, last_rate=None):
    """A track bush pulled at `rate` from 0.3 mm (the last step at `last_rate`), stepped as
    a host would (corrected's protocol, one trial per step): its friction-like branches
    loaded in that direction."""
    bush = FmuComponent(path, "bush")
    bush.start(0.0, 3e-4)
    x = 3e-4
    for n in range(1, steps + 1):
        x += (last_rate if n == steps and last_rate is not None else rate) * step
        bush.begin_step()
        bush.trial(n * step, x)
        bush.accept()
    return bush


def test_the_laws_have_the_tangent_of_a_reversal(native_fmus):
    """A step that reverses the motion meets the bush's unloading tangent, up to four
    times its loading one (law.py, A reversal). The law about a trial that ended on the
    loading side gives the FMU's answer to the reversed step within a tenth of its change
    (8.7 %; its loading tangent alone: 55 % off). The first law of a step keeps the
    loading tangent where the motion goes on steadily, and where it slows enough to
    reverse takes the mean of both ways' tangents, which cuts the worst of the lagged
    law's error either way (to 0.60 of it here: the reversal's 820 to 351 N, going on's
    24 to 493 N)."""
    path = native_fmus["TrackBushRadial"]
    bush = _bush_stepped_loading(path)
    try:
        time, start, load = bush.time + 1e-3, bush.deflection, bush.load
        bush.begin_step()
        assert bush.predicted_law(time) == bush.lagged_law()  # going on steadily
        reversed_to = start - 5e-6
        bush.trial(time, start + 1e-6)  # the host's first solve went on loading
        second = bush.corrected_law()
        answer = bush.trial(time, reversed_to)[bush.load_name]
        assert abs(second(reversed_to) - answer) < 0.1 * abs(answer - load)
    finally:
        bush.free()
    bush = _bush_stepped_loading(path, last_rate=5e-4)  # slowing down: may reverse
    try:
        time, start = bush.time + 1e-3, bush.deflection
        ends = (start - 5e-6, start + 5e-6)  # reversed, and going on
        bush.begin_step()
        first, lagged = bush.predicted_law(time), bush.lagged_law()
        answers = [bush.trial(time, x)[bush.load_name] for x in ends]
        worst = max(abs(first(x) - answer) for x, answer in zip(ends, answers))
        assert worst < 0.7 * max(abs(lagged(x) - answer) for x, answer in zip(ends, answers))
    finally:
        bush.free()


def test_matrix_exponential_against_a_closed_form():
    for a, b in ((-3.0, 2.0), (-300.0, 40.0)):  # also a stiff one, scaled and squared
        matrix = np.array([[a, b], [-b, a]])
        expected = math.exp(a) * np.array([[math.cos(b), math.sin(b)],
                                           [-math.sin(b), math.cos(b)]])
        assert np.allclose(expm(matrix), expected, rtol=1e-12, atol=1e-14 * math.exp(a) + 1e-300)


def test_the_library_imports_fmpy_and_numpy_only():
    """Of fmu_components only its parameter-set reader (ssv.py) and errors, nothing else
    outside the standard library (exudyn only in its adapter, and only inside its
    functions)."""
    package = Path(__file__).resolve().parents[1] / "src" / "fmu_components" / "coupling"
    allowed = {"fmpy", "numpy", "atexit", "ctypes", "math", "pathlib", "shutil", "warnings",
               "dataclasses", "xml", "threading"}
    # the bank's compiler: gcc at build time, or once into a cache
    allowed_in = {"bank_build.py": {"hashlib", "os", "shutil", "subprocess", "sys"},
                  "exudyn_host.py": {"time"}}  # the solve's CPU time
    for path in package.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in tree.body:  # module level
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module] if isinstance(node, ast.ImportFrom) and not node.level
                     else [])
            for name in names:
                assert name.split(".")[0] in allowed | allowed_in.get(path.name, set()), \
                    f"{path.name} imports {name}"
        package_imports = {node.module for node in ast.walk(tree)
                           if isinstance(node, ast.ImportFrom) and node.level > 1}
        assert package_imports <= {"ssv", "errors"}, (path.name, package_imports)
        lazy = {a.name for node in ast.walk(tree) if isinstance(node, ast.Import)
                for a in node.names} - allowed - allowed_in.get(path.name, set())
        adapters = ("exudyn_host.py", "bank_exudyn.py")
        assert lazy <= ({"exudyn"} if path.name in adapters else set()), path.name


# --- FMI 3.0: the same numbers as FMI 2.0, and every refusal a CouplingError ---------------

def test_fmi3_fmus_give_the_fmi2_runs_to_the_bit(versions):
    """The small host on the tyre (contact, corrected coupling with the stiffness's
    directional derivative, steps given up and solved again) and on the damper (its step
    linearised through a Model Exchange instance): FMI 3.0 gives FMI 2.0's bits."""
    runs = {}
    for version, fmus in versions.items():
        _, tyre = run_mass(fmus["RoadWheelTyre"], 1e-3, 0.1, reject_every=3)
        damper = FmuComponent(fmus["RotaryDamper"], "damper")
        assert damper.step_model == "linearised"
        rotor = MassHost(damper, 0.5, lambda t: 0.1 * math.sin(20 * t),
                         lambda t: 2.0 * math.cos(20 * t), gravity=0.0)
        runs[version] = tyre, rotor.run(0.1, 1e-3)
    (tyre2, damper2), (tyre3, damper3) = runs["2.0"], runs["3.0"]
    for key in ("load", "acceleration", "deflection"):
        assert np.array_equal(tyre2[key], tyre3[key]), key
        assert np.array_equal(damper2[key], damper3[key]), key
    assert np.ptp(tyre2["load"]) > 1e3 and np.ptp(damper2["load"]) > 10.0


@pytest.mark.parametrize("version", VERSIONS)
def test_a_refused_state_save_is_a_coupling_error(versions, version):
    """Saving the state at a step's start (getting the FMU state into the one the
    instance reuses) goes through the same translation as every other call: refused (here
    the state to update is one another FMU made), it is a CouplingError naming the
    component, the time and what the FMU said."""
    tyre = FmuComponent(versions[version]["RoadWheelTyre"], "tyre", unilateral=True)
    damper = FmuComponent(versions[version]["RotaryDamper"], "damper")
    own = None
    try:
        for component, deflection in ((tyre, 3e-3), (damper, 0.0)):
            component.start(0.0, deflection)
            component.begin_step()
        own, tyre._state.value = tyre._state.value, damper._state.value
        function = {"2.0": "fmi2GetFMUstate", "3.0": "fmi3GetFMUState"}[version]
        with pytest.raises(CouplingError, match=rf"tyre at t = 0 s: {function} returned "
                                                rf"{PREFIX[version]}Error: .*not one "
                                                r"RoadWheelTyre made"):
            tyre.begin_step()
    finally:
        if own is not None:
            tyre._state.value = own
        tyre.free()
        damper.free()


def test_only_a_scheme_that_always_solves_again_has_a_first_solve_that_cannot_end_a_step():
    """Scheme.first_solve_may_end: False only where no first solve can end a step
    (iterated's least passes), whatever its mismatch; the own solver solves such a first
    solve roughly (examples/vehicle/own_host.py)."""
    from fmu_components.coupling.schemes import scheme_named

    for name in ("explicit", "corrected", "converged", "iterated"):
        scheme = scheme_named(name)
        can_end = any(scheme.done(1, mismatch) for mismatch in (0.0, 1e-12, 1.0))
        assert scheme.first_solve_may_end() == can_end, name
    assert not scheme_named("iterated").first_solve_may_end()
    assert scheme_named("corrected").first_solve_may_end()
