"""Identify a rubber component's parameters from measured data (the API behind
``fmu-components fit``, ``commands/fit.py``).

Each DATA.csv is one measured test, in one of two formats, told apart by the header:

* a history, ``time,deflection,force`` (SI: s, m or rad, N or N.m), of any motion (sine
  loops, a step and hold, a random drive). It is simulated under its own recorded
  deflection, with the forward-difference rate (``history`` says why), and compared sample
  by sample;
* a rig table, ``preload,amplitude,frequency,dynamic_stiffness,loss_angle_deg``: one steady
  sine per row, simulated to its periodic steady state and read through the rig's
  first-harmonic analysis (``harmonics.first_harmonic``).

The fitted parameters are the Maxwell elements' k, c and xi, the elastic polynomial
a0..a3 and the geometric slope h (``--fix`` keeps any of them at its thesis value);
x_ref, where the geometric multiplier is 1, is the part's geometry (the tyre's first
contact, the torsion bush's live angle) and stays at the thesis value. The method: bounds,
log-scaled parameters (k, c, xi; sign-aware, asinh, for a0..a3 and h, which may be zero),
several starting points fitted in parallel (a campaign's tasks, or a local process pool), and
``scipy.optimize.least_squares`` on the simulated responses, which come from the compiled
native co-simulation (``history``) at the FMU's default tolerance. Each test's residuals are
divided by its measured peak-to-peak force and by the square root of its sample count, so
that every test weighs the same; a table row gives the relative error of |K*| and the
error of the loss angle in radians.

The result is PARAMS.json, every parameter of the component by its FMU name (SI), the same
set as an SSP parameter file PARAMS.ssv (with units), and a report beside them (PARAMS_report.md with 200-dpi plots): measured against fitted responses,
residuals, 95 % confidence intervals and correlations from the Jacobian at the solution,
and a warning for each parameter the data cannot identify.
"""

import json
import math
import multiprocessing
import os
import signal
import sys
import threading
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from ..errors import UsageError
from ..export.parameters import write_parameter_set
from .files import write_text
from .history import component_definition, native_history
from .measured import History, deflection_limit

# A rig-table row is a measured steady sine, so it is simulated as close to the continuous
# sine as the FMU's semantics allow: from the relaxed preload (as the rig starts), rig.py's
# samples per cycle, forward-difference rates (the path runs through the samples). Holding
# the exact rate of each sample instead lags half a step: measured on TrackBushRadial at
# 0.3 +- 0.05 mm, 0.5 Hz, 200 samples per cycle, 0.4 deg of loss angle off the reference
# solver's steady state, against 0.002 deg with the forward difference. The 10th cycle is
# analysed: for the thesis's parameters at 0.1-20 Hz its |K*| and loss angle are within
# 4e-5 of the periodic steady state (measured against the 40th).
STEADY_CYCLES = 10
FAILED_RESIDUAL = 10.0  # per sample, for a simulation the FMU refused (10 x peak-to-peak)

# What is fitted, and how each parameter is scaled.
MAXWELL = ("k", "c", "xi")  # k{K}, c{K}, xi{K} of each Maxwell element K of the structure
ELASTIC = tuple(f"elastic.a{p}" for p in range(4))
GEOMETRIC = ("geometric.h",)
LOG_SPAN = {"k": math.log(100.0), "c": math.log(100.0), "xi": math.log(1000.0)}
SYMLOG_RESOLUTION = 1e-3  # asinh scaling: linear below this fraction of a coefficient's scale
SYMLOG_SPAN = 100.0  # bound: this many times a coefficient's scale

# identifiability
CONDITION_LIMIT = 1e6
RELATIVE_CI_LIMIT = 0.5
CORRELATION_LIMIT = 0.95


# --- the parameters, scaled ------------------------------------------------------------

@dataclass
class Scaling:
    """One free parameter: value = reference * exp(u) (log) or resolution * sinh(u)."""
    name: str
    kind: str
    reference: float
    lower: float
    upper: float

    def value(self, u):
        return self.reference * (math.exp(u) if self.kind == "log" else math.sinh(u))

    def u(self, value):
        u = math.log(value / self.reference) if self.kind == "log" else math.asinh(
            value / self.reference)
        return min(max(u, self.lower), self.upper)

    def reach(self, u):
        """value(u), or +-inf where it lies beyond the floats (an interval's end far
        outside the bounds: a parameter the data do not determine)."""
        try:
            return self.value(u)
        except OverflowError:
            sign = 1.0 if self.kind == "log" else math.copysign(1.0, u)
            return math.copysign(math.inf, sign * self.reference)

    def derivative(self, u):
        """d value / d u."""
        return self.reference * (math.exp(u) if self.kind == "log" else math.cosh(u))


def maxwell_quantity(name):
    """'k', 'c' or 'xi' for a Maxwell element's parameter (k1, xi3, ...), else None."""
    quantity = name.rstrip("0123456789")
    return quantity if quantity in MAXWELL and quantity != name else None


def fitted_names(definition):
    """The parameters the fit identifies, in the catalog's order."""
    return [p.name for p in definition.parameters
            if maxwell_quantity(p.name) or p.name in ELASTIC + GEOMETRIC]


def scalings(names, thesis, deflection_scale, force_scale):
    result = []
    for name in names:
        if maxwell_quantity(name):
            span = LOG_SPAN[maxwell_quantity(name)]
            result.append(Scaling(name, "log", thesis[name], -span, span))
        else:
            power = int(name[-1]) if name in ELASTIC else -1  # h: per deflection
            scale = force_scale / deflection_scale ** power if name in ELASTIC else \
                1.0 / deflection_scale
            bound = math.asinh(SYMLOG_SPAN / SYMLOG_RESOLUTION)
            result.append(Scaling(name, "symlog", SYMLOG_RESOLUTION * scale,
                                  0.0 if name == "geometric.h" else -bound, bound))
    return result


# --- the problem ------------------------------------------------------------------------

@dataclass
class Problem:
    component: str
    structure: str
    tests: list
    fixed: dict  # name -> value of every parameter not fitted
    free: list  # Scaling
    starts: list = field(default_factory=list)

    def parameters(self, u):
        values = dict(self.fixed)
        values.update({s.name: s.value(ui) for s, ui in zip(self.free, u)})
        return values

    def responses(self, values):
        """Per test: the simulated force (History) or the (|K*|, loss angle) rows."""
        return [simulate_test(self.component, self.structure, test, values)
                for test in self.tests]

    def residuals(self, u):
        values = self.parameters(u)
        return np.concatenate([residuals_of(test, response)
                               for test, response in zip(self.tests, self.responses(values))])


def simulate_test(component, structure, test, values):
    history = native_history(component, structure)
    if isinstance(test, History):
        return history.run(values, test.times, test.deflection, check=False)
    return np.array([rig_point(history, values, *row[:3]) for row in test.rows])


def rig_point(history, values, preload, amplitude, frequency):
    """(|K*|, loss angle deg) of a steady sine from the relaxed preload."""
    from .harmonics import HarmonicError, first_harmonic
    from .rig import SAMPLES_PER_CYCLE

    omega = 2.0 * math.pi * frequency
    t = np.arange(STEADY_CYCLES * SAMPLES_PER_CYCLE + 1) * (1.0 / (frequency * SAMPLES_PER_CYCLE))
    x = preload + amplitude * np.sin(omega * t)
    force = history.run(values, t, x, check=False)
    try:
        result = first_harmonic(t, x, force, frequency, cycles=1)
    except HarmonicError:
        return (math.nan, math.nan)
    return (result.dynamic_stiffness, result.loss_angle_deg)


def residuals_of(test, response):
    if isinstance(test, History):
        r = (response - test.force) / (test.scale * math.sqrt(len(test.force)))
    else:
        measured = test.rows[:, 3:5]
        r = np.column_stack([response[:, 0] / measured[:, 0] - 1.0,
                             np.radians(response[:, 1] - measured[:, 1])]).ravel()
    return np.where(np.isfinite(r), r, FAILED_RESIDUAL)


# --- the fit ----------------------------------------------------------------------------

_PROBLEM = None  # the problem a pool worker solves
_SIMULATIONS = None  # a counter shared with the parent: the residual evaluations run


def _adopt(problem, simulations=None):
    global _PROBLEM, _SIMULATIONS
    _PROBLEM, _SIMULATIONS = problem, simulations


def _start_worker(problem, simulations):
    # Ctrl-C goes to the whole process group: the parent answers it and ends the workers.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    _adopt(problem, simulations)


def _counted_residuals(u):
    residuals = _PROBLEM.residuals(u)
    if _SIMULATIONS is not None:
        with _SIMULATIONS.get_lock():
            _SIMULATIONS.value += 1
    return residuals


def solve_start(problem, u0, columns=None):
    """One start's fit of `problem` from u0, in this process (a campaign's worker runs
    it): as a pool worker's. columns(residuals, points), if given, evaluates the
    finite-difference Jacobian's columns (the residuals at each point, in order)
    elsewhere, a campaign's engine; the numbers are the same, scipy's arithmetic being
    the same whoever evaluates them."""
    _adopt(problem)
    return _solve_from(u0, columns)


def _solve_from(u0, columns=None):
    problem = _PROBLEM
    lower = [s.lower for s in problem.free]
    upper = [s.upper for s in problem.free]
    # the residuals themselves, not the counting global, when they travel to other workers
    residuals = problem.residuals if columns is not None else _counted_residuals
    result = least_squares(residuals, u0, bounds=(lower, upper), method="trf",
                           diff_step=1e-4, x_scale=1.0, ftol=1e-10, xtol=1e-10, gtol=1e-10,
                           max_nfev=200, workers=columns)
    return result.x, float(result.cost), result.jac, int(result.nfev), result.message


@dataclass
class FitResult:
    component: str
    structure: str
    values: dict  # every parameter of the component
    free: list  # Scaling
    u: np.ndarray
    jacobian: np.ndarray
    residuals: np.ndarray
    starts: list  # (cost, function evaluations, message) per start
    tests: list
    wall_time: float
    thesis: dict

    @property
    def samples(self):
        return len(self.residuals)

    def covariance(self):
        """Of u, from the Jacobian at the solution: s^2 (J'J)^-1."""
        m, n = self.jacobian.shape
        variance = float(self.residuals @ self.residuals) / max(m - n, 1)
        return variance * np.linalg.pinv(self.jacobian.T @ self.jacobian)

    def confidence(self):
        """Per free parameter: (low, high) of its 95 % interval, its half-width relative to
        its value. An end beyond the floats is +-inf, and so is the half-width: the
        interval is unbounded."""
        sigma = np.sqrt(np.maximum(np.diag(self.covariance()), 0.0))
        rows = {}
        for s, ui, si in zip(self.free, self.u, sigma):
            low, high = s.reach(ui - 1.96 * si), s.reach(ui + 1.96 * si)
            value = s.value(ui)
            rows[s.name] = (low, high, (high - low) / 2.0 / abs(value) if value else math.inf)
        return rows

    @staticmethod
    def too_wide(relative):
        """A 95 % interval this wide (relative half-width) leaves the parameter unidentified."""
        return relative > RELATIVE_CI_LIMIT

    def responses(self):
        """Per test, the fitted model's response (as Problem.responses)."""
        return [simulate_test(self.component, self.structure, test, self.values)
                for test in self.tests]

    def correlation(self):
        c = self.covariance()
        d = np.sqrt(np.maximum(np.diag(c), 1e-300))
        return c / np.outer(d, d)

    def condition(self):
        s = np.linalg.svd(self.jacobian, compute_uv=False)
        return float(s[0] / s[-1]) if s[-1] > 0 else math.inf

    def warnings(self):
        notes = []
        condition = self.condition()
        if condition > CONDITION_LIMIT:
            notes.append(f"the Jacobian is near-singular (condition number {condition:.2g}): "
                         f"some combination of parameters is not determined by these data")
        for name, (low, high, relative) in self.confidence().items():
            if name in ELASTIC + GEOMETRIC and low <= 0.0 <= high:
                notes.append(f"{name} is not told apart from 0 by these data (95 % interval "
                             f"{low:.3g} .. {high:.3g}); --fix keeps the thesis value, "
                             f"{self.thesis[name]:g}")
            elif self.too_wide(relative):
                width = "unbounded" if math.isinf(relative) else \
                    f"+-{relative * 100:.0f} % of its value"
                notes.append(f"{name} is not identifiable from these data: its 95 % interval "
                             f"is {width}; fix it (--fix) or add tests that excite it")
        correlation = self.correlation()
        names = [s.name for s in self.free]
        for i in range(len(names)):
            for j in range(i + 1, len(names)):
                if abs(correlation[i, j]) > CORRELATION_LIMIT:
                    notes.append(f"{names[i]} and {names[j]} are correlated "
                                 f"({correlation[i, j]:+.3f}): the data fix a combination of "
                                 f"them, not each")
        return notes


def starting_points(free, thesis, count, seed=0):
    """The thesis values (clipped to the bounds), then log-scaled parameters spread a
    factor of up to 3 either way (the elastic and geometric ones start at the thesis)."""
    first = np.array([s.u(thesis[s.name]) for s in free])
    generator = np.random.default_rng(seed)
    points = [first]
    for _ in range(count - 1):
        shift = np.array([generator.uniform(-math.log(3), math.log(3)) if s.kind == "log"
                          else 0.0 for s in free])
        lower = np.array([s.lower for s in free])
        upper = np.array([s.upper for s in free])
        points.append(np.clip(first + shift, lower, upper))
    return points


@contextmanager
def _progress(simulations, starts, shown):
    """A progress bar on stderr of the simulations the fit has run (it draws on a terminal
    only, as verify's), followed from the shared counter twice a second."""
    if not shown:
        yield
        return
    from tqdm import tqdm

    bar = tqdm(desc=f"fitting from {starts} start{'s' if starts > 1 else ''}",
               unit=" simulations", file=sys.stderr, disable=None)
    finished = threading.Event()

    def follow():
        while not finished.wait(0.5):
            bar.update(simulations.value - bar.n)

    follower = threading.Thread(target=follow, daemon=True)
    follower.start()
    try:
        yield
    finally:
        finished.set()
        follower.join()
        bar.update(simulations.value - bar.n)
        bar.close()


def fit(component, tests, fix=(), structure="final", starts=4, jobs=None, seed=0,
        start_values=None, progress=False, runner=None):
    """Fit the free parameters to the tests (History or RigTable); a FitResult. progress:
    a progress bar on stderr (on a terminal). runner(problem, points), if given, fits
    from every starting point elsewhere (``solve_start`` on a campaign's engine) and
    returns the outcomes in order; else the starts run on `jobs` local processes."""
    import time

    definition = component_definition(component, structure)
    thesis = definition.default_parameters()
    start = dict(thesis, **(start_values or {}))
    free_names = [n for n in fitted_names(definition) if n not in set(fix)]
    if not free_names:
        raise UsageError("every fitted parameter is fixed; leave at least one free")
    deflection_scale, force_scale = data_scales(tests, definition)
    free = scalings(free_names, start, deflection_scale, force_scale)
    fixed = {n: v for n, v in start.items() if n not in free_names}
    problem = Problem(component, structure, tests, fixed, free)
    native_history(component, structure)  # compiled once, before the workers start
    points = starting_points(free, start, max(1, starts), seed)
    started = time.perf_counter()
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(points)))
    context = multiprocessing.get_context("fork")
    simulations = context.Value("q", 0)
    if runner is not None:
        outcomes = runner(problem, points)
    elif jobs == 1:
        _adopt(problem, simulations)
        with _progress(simulations, len(points), progress):
            outcomes = [_solve_from(p) for p in points]
    else:
        # A Pool, not a ProcessPoolExecutor: leaving its block on an exception (Ctrl-C)
        # terminates the workers instead of waiting for their fits to end.
        with context.Pool(jobs, initializer=_start_worker, initargs=(problem, simulations)) \
                as pool, _progress(simulations, len(points), progress):
            outcomes = pool.map(_solve_from, points, chunksize=1)
    best = min(outcomes, key=lambda o: o[1])
    u = best[0]
    values = problem.parameters(u)
    values = {name: values[name] for name in thesis}  # in the catalog's order
    return FitResult(component, structure, values, free, u, best[2], problem.residuals(u),
                     [(o[1], o[3], o[4]) for o in outcomes], tests,
                     time.perf_counter() - started, thesis)


def data_scales(tests, definition):
    """The deflection and force scales of the data, for the elastic coefficients' and h's
    scaling."""
    x, f = [], []
    for test in tests:
        if isinstance(test, History):
            x.append(np.max(np.abs(test.deflection)))
            f.append(np.max(np.abs(test.force)))
        else:
            reach = np.abs(test.rows[:, 0]) + test.rows[:, 1]
            x.append(np.max(reach))
            f.append(np.max(test.rows[:, 3] * reach))
    return float(max(x)) or deflection_limit(definition), float(max(f)) or 1.0


def write_parameters(path, values, definition):
    """PARAMS.json (FMU names to SI values) and, beside it, PARAMS.ssv: the same values as
    an SSP parameter set with their units, for the tools that read SSP (ssv.py). Returns
    the .ssv's path."""
    path = Path(path)
    write_text(path, json.dumps({n: float(v) for n, v in values.items()}, indent=2) + "\n")
    ssv = path.with_suffix(".ssv")
    write_parameter_set(ssv, definition, values, f"{definition.name} fitted ({path.name})")
    return ssv
