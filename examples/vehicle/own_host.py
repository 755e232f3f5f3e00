"""The vehicle on its own solver, no exudyn in the time loop: the solver core
(alpha_solver.c, exudyn's generalized-alpha step) over the vehicle's equations in C
(system.c), joined by a small C adapter (own_system.c: the core's two callbacks, so that no
Python runs per Newton iterate), coupled to the FMUs by the coupling's compiled path (the
bank, as compiled.py's run in exudyn).

Per host step what bank_exudyn.py and exudyn_host.py do in exudyn's hooks:
Bank.begin_step(t); a solve of the step; the contacts at its solution taken from the
system's evaluation there, its Newton's last (Contacts.adopt); the step check
(StepCheck.judge on the solver's q and v); the deflections from the solution
(CompiledPath.deflections at q), these three in one C call where they are compiled
(own_pass.c);
Bank.end_pass(t, deflections): on REPEAT the step solved again from its start with the
new laws, Newton from the last pass's solution (exudyn's warm start of the next pass,
where Newton has an absolute tolerance); a verdict to retry, or a solution the step check
refuses: the step again at half its length; then Bank.accept(t, next_time) and the
bank's record of the step (outputs.record) from the last pass's q, v and a
(Vehicle.given_state). A step whose Newton fails is
halved, as exudyn's adaptive step does, down to SHORTEST_STEP of the host step, then the
run stops naming the time; after RECOVERY good steps the step is doubled again, by
exudyn's rules (StepLength).

exudyn's model (model.Vehicle) stays the description of the vehicle: the system is read
from it (system.py); its data get the run's last state at the end.
"""

import ctypes
import time

import numpy as np

import exudyn as exu

from fmu_components.coupling.bank_build import Library, function_address
from fmu_components.coupling.exudyn_host import SHORTEST_STEP

from . import alpha_solver as alpha
from .alpha_solver import HERE
from .compiled import bank_in_use
from .model import VehicleError
from .step_check import found
from .system import VehicleSystem, ordering

LIBRARY = Library("vehicle_own", [HERE / "own_system.c", HERE / "own_pass.c"],
                  [HERE / "alpha_solver.h", HERE / "bordered_band.h"],
                  "the vehicle's own solver's adapter (own_system.c)", "--solver exudyn")
CAPACITY = 65536  # triplets of the system's Jacobian
# A step's first solve to this many times Newton's absolute tolerance where the scheme always
# solves the step again (iterated: Scheme.first_solve_may_end) and the policy keeps its
# matrix: that solution only sets the FMUs' first pass, whose answers give the next law; the
# step's last solve is to the full tolerance (docs/vehicle.md, "A rough first solve")
FIRST_PASS_LOOSENESS = 1e4
# An update that grew the residual on a new Newton matrix halved up to this many times
# (alpha_solver.h's reuse_damping): Newton on laws with a kink between its iterates (a
# reversal's at the step's start: kinked_first_laws) cycles without it
DAMPING = 3
# the solver core's Newton policies (alpha_solver.h): exudyn's full Newton (a new
# factorization every iteration); "chord", the last factorization kept across
# iterations, passes and steps of the same h, a new one at the present iterate after an
# iteration that contracted the residual norm by a ratio worse than the contractivity;
# "reuse", the same with the kept matrix's steps corrected by Broyden's rank-one updates
# and the updates damped (docs/vehicle.md, The vehicle on its own solver)
NEWTON = {"full": dict(reuse_jacobian=0),
          "chord": dict(reuse_jacobian=2, reuse_contractivity=0.5),
          "reuse": dict(reuse_jacobian=2, reuse_contractivity=0.25, reuse_broyden=1,
                        reuse_damping=DAMPING)}
DEFAULT_NEWTON = "reuse"
# exudyn's adaptive step: steps that converge before a halved step is doubled
# (timeIntegration.adaptiveStepRecoverySteps), the factor (adaptiveStepIncrease), and the
# most Newton iterations of a step's last solve plus its solves (discontinuous iterations)
# with which the step may be doubled (adaptiveStepRecoveryIterations)
RECOVERY, INCREASE, RECOVERY_ITERATIONS = 10, 2.0, 7


class _Context(ctypes.Structure):
    """own_system.c's OwnContext."""
    _fields_ = [(name, ctypes.c_void_p) for name in ("system", "residual", "jacobian",
                                                     "constraint_jacobian", "solver")] + \
               [("n", ctypes.c_int), ("m", ctypes.c_int), ("capacity", ctypes.c_long)] + \
               [(name, ctypes.c_void_p) for name in ("scratch", "G", "H")] + \
               [("seconds", ctypes.c_double * 2),
                ("calls", ctypes.c_long * 2)]


class _Pass(ctypes.Structure):
    """own_pass.c's OwnPass."""
    _fields_ = [(name, ctypes.c_void_p) for name in (
        "adopt", "contacts", "evaluated", "index", "links", "check_contacts", "check",
        "compression", "gap", "start_compression", "start_rate", "start_gap", "deflections",
        "deflections_layout", "deflection")] + [("found", ctypes.c_double * 3)]


class OwnSystem:
    """The vehicle's system (system.VehicleSystem) as the solver core's callbacks
    (.evaluate, .jacobian, .context, as alpha_solver.PythonSystem's)."""

    def __init__(self, system, capacity=CAPACITY):
        lib = LIBRARY.load("the vehicle's own solver is not available")
        if lib is None:
            raise RuntimeError("the vehicle's own solver needs a C compiler (gcc)")
        if lib.own_layout() != ctypes.sizeof(_Context):
            raise RuntimeError("own_system.c and own_host.py disagree on the context")
        lib.own_times.argtypes = [ctypes.c_void_p] * 3
        self.lib, self.system = lib, system
        self._arrays = [np.zeros((capacity, 3)), np.zeros((6 * system.m, 3)),
                        np.zeros((system.m, 3))]
        sys_lib = system.lib
        self.struct = _Context(system.handle, function_address(sys_lib.vsystem_residual),
                               function_address(sys_lib.vsystem_jacobian_split),
                               function_address(sys_lib.vsystem_constraint_jacobian), None,
                               system.n, system.m, capacity,
                               *(a.ctypes.data for a in self._arrays))
        self.context = ctypes.addressof(self.struct)
        self.evaluate = alpha.EVALUATE(function_address(lib.own_evaluate))
        self.jacobian = alpha.JACOBIAN(function_address(lib.own_jacobian))

    def bind(self, solver):
        self.struct.solver = solver.handle

    def times(self):
        """CPU seconds in the system's evaluation (f, g, G) and its Jacobian (K, D, the
        multipliers' term), and their calls."""
        seconds, calls = np.zeros(2), np.zeros(2, dtype=np.int64)
        self.lib.own_times(self.context, seconds.ctypes.data, calls.ctypes.data)
        return seconds, calls


def first_pass_tolerance(scheme, policy, tolerance):
    """The solver core's first_pass_tolerance for a run of `scheme` (None: no bank) with
    the Newton `policy` (a value of NEWTON) at Newton's absolute `tolerance`: rough
    (FIRST_PASS_LOOSENESS times) where the scheme always solves a step again and the
    policy keeps its matrix (full Newton stays exudyn's, iterate for iterate), else 0 (the
    full tolerance)."""
    rough = (scheme is not None and not scheme.first_solve_may_end()
             and policy.get("reuse_jacobian", 0) > 0)
    return FIRST_PASS_LOOSENESS * tolerance if rough else 0.0


def kinked_first_laws(settings):
    """Whether a run with the solver core's `settings` (alpha_solver.Settings) gives each
    step's first law the reversal's kink at the accepted point (Bank.kink_first_laws):
    where its Newton damps the updates; full Newton, exudyn's, cycles on that kink
    (docs/vehicle.md, "A kink in the first law")."""
    return settings.reuse_damping > 0


def solver_for(vehicle, laws, relative_tolerance=1e-8):
    """(OwnSystem, AlphaSolver) for `vehicle` with the laws of `laws` (a bank or a
    LawTable), with the run's settings: the vehicle's spectral radius and Newton absolute
    tolerance, its Newton policy (vehicle.own_newton, a key of NEWTON; None:
    DEFAULT_NEWTON). (exudyn's documentation of newton.absoluteTolerance divides the
    residual's norm by the number of coordinates; its runs of the vehicle take the
    core's iterations with the norm itself, to round-off: tests/test_vehicle_own.py.)"""
    system = VehicleSystem(vehicle, laws)
    own = OwnSystem(system)
    order, half_bandwidth, border = ordering(system)
    system.keep_band(order, half_bandwidth, border)
    policy = NEWTON[vehicle.own_newton or DEFAULT_NEWTON]
    settings = alpha.Settings(spectral_radius=vehicle.spectral_radius,
                              relative_tolerance=relative_tolerance,
                              absolute_tolerance=vehicle.newton_tolerance,
                              first_pass_tolerance=first_pass_tolerance(
                                  getattr(laws, "scheme", None), policy,
                                  vehicle.newton_tolerance),
                              use_modified_newton=0, **policy)
    solver = alpha.AlphaSolver(own, system.mass_diagonal(), system.m, order,
                               len(order) - border, half_bandwidth, settings, CAPACITY)
    own.bind(solver)
    return own, solver


class StepLength:
    """The host step's length as exudyn's adaptive step sets it (CSolverBase::SolveSteps):
    the steps converged since the last shortening counted from every shortening (a step
    halved again while it recovers counts from there); a shortened step doubled, up to
    the host step, after RECOVERY of them, where the last one's effort (its last solve's
    Newton iterations plus its solves) is at most RECOVERY_ITERATIONS (else at the next
    step within it)."""

    def __init__(self, step):
        self.step, self.good = step, 0

    def next(self, asked, taken, effort):
        """The next step's length after a step asked at `asked` was taken at `taken`
        (shorter: halved) with `effort`."""
        self.good = 1 if taken < asked else self.good + 1
        if (taken < self.step and self.good >= RECOVERY
                and effort <= RECOVERY_ITERATIONS):
            self.good = 0
            return min(INCREASE * taken, self.step)
        return taken


class OwnHost:
    """The run of `vehicle` (prepared on the compiled path: Vehicle.prepare) on the own
    solver; run() as exudyn_host.solve. Its counts: statistics()."""

    def __init__(self, vehicle, relative_tolerance=1e-8):
        if not vehicle.compiled:
            raise ValueError("the own solver runs the coupling's compiled path (the bank)")
        self.v = vehicle
        self.path = vehicle.compiled_path
        self.bank = self.path.bank
        self.own, self.solver = solver_for(vehicle, self.bank, relative_tolerance)
        # the contacts at a pass's solution: the system's Newton evaluated them last there
        contacts, evaluated = vehicle.contacts, self.own.system.contacts
        self.adopt = lambda t, q, v, at: contacts.adopt(t, q, v, evaluated, at)
        self.refused = 0  # solutions the step check refused
        self.halved = 0  # steps whose Newton failed
        self.solves = self.newton = 0
        self.iterations = self.effort = 0  # the last solve's Newton iterations; _step's
        self._start = None  # (q, v) at the step's start, where the step check compares
        # the solver's state (q, v, a) after the last pass, and at the last accepted step
        self._solved = self._accepted = None
        # the blocks a pass's state is read into (made once), taking turns: a pass writes
        # into the one that does not hold the accepted state (_free)
        self._blocks = [np.empty((3, self.solver.nq)) for _ in range(2)]
        self._blocks_at = [block.ctypes.data for block in self._blocks]
        self._free = 0
        self._row = 8 * self.solver.nq  # bytes from a block's q to its v
        self._accepted_at = None  # the accepted state's q's and v's addresses
        self._one = None  # own_pass.c's pass end, where the run's parts are compiled
        self.seconds = dict(solve=0.0, bank=0.0, deflections=0.0, record=0.0, check=0.0)

    # --- the state in exudyn's data (for readers of it after the run, or a record that
    # reads it: energy.audited_run's) --------------------------------------------------------

    def _put(self, t, state):
        data, current = self.v.mbs.systemData, exu.ConfigurationType.Current
        q, v, a = state
        data.SetODE2Coordinates(q, current)
        data.SetODE2Coordinates_t(v, current)
        data.SetODE2Coordinates_tt(a, current)
        data.SetTime(t, current)

    # --- one step ---------------------------------------------------------------------------

    def _solve(self, h, t_new, first, warm):
        began = time.process_time()
        self._solved = None
        status = (self.solver.step(h, t_new) if first
                  else self.solver.repeat(h, t_new, warm))
        self.seconds["solve"] += time.process_time() - began
        self.solves += 1
        self.iterations = self.solver.iterations()
        self.newton += self.iterations
        if status == alpha.OUTSIDE:  # halving would not change the matrix's structure
            report, name = self.solver.report(), self.own.system.coordinate_name
            raise VehicleError(
                f"the own solver stopped at t = {t_new:.4f} s: its Newton matrix has an "
                f"entry at ({name(report['bad_row'])}, {name(report['bad_col'])}) outside "
                f"the band and the border of its order (system.py's ordering)")
        return status

    def _one_call(self, check):
        """own_pass.c's pass end over this run's parts (the contacts' adoption, the step
        check's C, the deflections' C into the bank's input array): (the library, its
        OwnPass), or None where one of them is not compiled (_pass_end then calls them one
        by one)."""
        contacts = self.v.contacts
        adoption = contacts.adoption(self.own.system.contacts)
        entries = (None,) * 6 if check is None else check.entries()
        if adoption is None or entries is None:
            return None
        lib = self.own.lib
        lib.own_pass_end.argtypes = [ctypes.c_void_p, ctypes.c_double] + \
            [ctypes.c_void_p] * 4 + [ctypes.c_int]
        if lib.own_pass_layout() != ctypes.sizeof(_Pass):
            raise RuntimeError("own_pass.c and own_host.py disagree on the layout")
        one = _Pass(*adoption, *entries[:3], contacts.kernel_address("compression"),
                    contacts.kernel_address("tooth_gap"), *entries[3:],
                    *self.path.deflections_entry(), self.bank.deflection.ctypes.data)
        return lib, one, ctypes.addressof(one)

    def _pass_end(self, t, t_new, check):
        """The step check's and the bank's verdict on a solved pass: (refused, verdict).
        Its parts' clocks: each part's end the next one's start (in one call, own_pass.c:
        the contacts' adoption, the check and the deflections on the check's)."""
        free = self._free
        at = self._blocks_at[free]
        self._solved = q, v, _ = self.solver.state(self._blocks[free], at)[:3]
        seconds, began = self.seconds, time.process_time()
        if self._one is not None:
            lib, one, one_at = self._one
            kind = lib.own_pass_end(one_at, t_new - t, at, at + self._row, *self._accepted_at,
                                    check is not None and check.start is not None)
            if kind >= 0:  # the contacts' evaluation taken
                self.v.contacts.adopted(t_new, q, v)
                ended = time.process_time()
                seconds["check"] += ended - began
                if kind:
                    return check.message(*found(kind, one.found), q), None
                verdict = self.bank.end_pass(t_new, self.bank.deflection)
                seconds["bank"] += time.process_time() - ended
                return None, verdict
        # for the step check, the deflections and the record: where taken, their
        # evaluations at the solution have nothing left to do (evaluated)
        adopted = self.adopt(t_new, q, v, (at, at + self._row))
        if check is not None:
            jumped = check.judge(t_new, t_new - t, q, v, *self._start, evaluated=adopted,
                                 addresses=(at, *self._accepted_at))
            ended = time.process_time()
            seconds["check"] += ended - began
            began = ended
            if jumped is not None:
                return jumped, None
        deflections = self.path.deflections(q, v, t_new, out=self.bank.deflection,
                                            evaluated=adopted, q_at=at)
        ended = time.process_time()
        seconds["deflections"] += ended - began
        verdict = self.bank.end_pass(t_new, deflections)
        seconds["bank"] += time.process_time() - ended
        return None, verdict

    def _step(self, t, h, check):
        """Solve the step from t to t + h with the bank's passes; the step taken (h, or
        shorter where a verdict or the step check asked) and its end. Its effort (the
        last solve's Newton iterations plus the solves of the step taken): .effort."""
        passes = self.bank.scheme.passes + 1  # exudyn's discontinuous.maxIterations
        if check is not None:  # what the step check compares with
            self._start = self._accepted[:2]
        while True:
            t_new = t + h
            began = time.process_time()
            self.bank.begin_step(t_new)
            self.seconds["bank"] += time.process_time() - began
            retry = None
            for number in range(passes):
                status = self._solve(h, t_new, number == 0, warm=number > 0)
                if status != 0:
                    retry = "Newton"
                    break
                jumped, verdict = self._pass_end(t, t_new, check)
                if jumped is not None:
                    retry = jumped
                    self.bank.reject()
                    self.refused += 1
                    break
                if verdict.retry_step is not None:
                    retry = "the coupling"
                    break
                if not verdict.repeat:
                    self.effort = self.iterations + number + 1
                    return h, t_new
            else:  # the passes spent: accepted (exudyn's discontinuous.ignoreMaxIterations)
                self.effort = self.iterations + passes
                return h, t_new
            self.solver.restart()  # the step's start (the bank's: begin_step)
            if retry == "Newton":
                self.halved += 1
            if 0.5 * h < self.shortest * (1.0 - 1e-9):
                raise VehicleError(f"the own solver gave up at t = {t:.4f} s: the step to "
                                   f"{t_new:.4f} s failed ({retry}) on steps down to "
                                   f"{h * 1e6:.3g} us")
            h = 0.5 * h

    def _accept(self, t, next_time):
        """Accept the step (Bank.accept) and record it (the bank's record, called here to
        time it apart: outputs.record, of the solver's state, or another that reads
        exudyn's data, where it is written)."""
        began = time.process_time()
        # the last pass's solution (its block now the accepted one's), or the initial state
        if self._solved is not None:
            at = self._blocks_at[self._free]
            self._free = 1 - self._free
        state = self._accepted = self._solved or self.solver.state()[:3]
        if self._solved is None:
            at = state[0].ctypes.data  # the initial state's new block
        self._accepted_at = (at, at + self._row)
        if self.bank.record == self.v._record:
            self.v.given_state = state
        else:
            self._put(t, state)
        bank = self.bank
        try:
            bank.accept(t, next_time, record=False)
            accepted = time.process_time()
            self.seconds["bank"] += accepted - began
            if bank.record:
                bank.record(t)
        finally:
            self.v.given_state = None
        self.seconds["record"] += time.process_time() - accepted

    def run(self, end_time, step, start_time=0.0, check=None):
        """Start the bank at the host's initial state, then integrate to the first multiple
        of `step` at or after end_time. Frees the bank."""
        self.shortest = SHORTEST_STEP * step
        steps = int(np.ceil((end_time - start_time) / step - 1e-9))
        end = start_time + steps * step
        with bank_in_use(self.v):
            self._one = self._one_call(check)
            self.bank.kink_first_laws(kinked_first_laws(self.solver.settings))
            try:
                return self._run(start_time, end, step, check)
            finally:  # the components' own attribute (the bank is freed by then)
                self.bank.kink_first_laws(False)

    def _run(self, start_time, end, step, check):
        data = self.v.mbs.systemData
        current = exu.ConfigurationType.Current
        q0 = np.array(data.GetODE2Coordinates(current))
        v0 = np.array(data.GetODE2Coordinates_t(current))
        self.bank.start(start_time, *self.path.initial_state())
        try:
            status = self.solver.initialize(start_time, q0, v0)
            if status:
                raise VehicleError(f"the own solver's initial accelerations failed: "
                                   f"{alpha.STATUS[status]}")
            self._accept(start_time, None)  # the initial state's record, as exudyn's
            began = time.process_time()
            t, h, length = start_time, step, StepLength(step)
            while end - t > 1e-9 * step:
                asked = min(h, end - t)
                taken, t = self._step(t, asked, check)
                h = length.next(asked, taken, self.effort)
                self._accept(t, min(t + h, end) if end - t > 1e-9 * step else None)
            self.solve_cpu = time.process_time() - began
            self._put(t, self._accepted)  # the run's last state in exudyn's data
        finally:
            self.bank.free()
        return self

    def statistics(self):
        """As Vehicle.solver_statistics's, and the split of the solve's time."""
        seconds, calls = self.own.times()
        return {"newton_per_pass": self.newton / max(self.solves, 1),
                "passes_per_step": self.solves / max(self.bank.steps, 1),
                "steps": self.bank.steps, "host_steps": self.v.host_steps,
                "refused": self.refused, "halved": self.halved,
                "left_out": self.own.system.left_out()[0],
                "evaluate_s": seconds[0], "jacobian_s": seconds[1],
                "evaluations": int(calls[0]), "jacobians": int(calls[1]), **self.seconds}
