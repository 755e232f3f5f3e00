"""Independent reference solutions of the model specification (docs/model-spec.md).

This module shares no code with the FMUs' run-time package: it reads the thesis's own
numbers from ``reference_data/thesis`` (in the thesis's printed units), converts them to SI
by the rules of the specification, writes the right-hand sides out plainly (every state
integrated, the damper in its rotor-angle form) and solves them with scipy's ``solve_ivp``
(Radau) at tight tolerance.

Two input conventions are provided:

* ``solve_held_rate``: the co-simulation semantics of spec section 4. Samples (t_k, x_k,
  v_k) are applied at t_k; over [t_k, t_k+1] the rate v_k is held and the deflection moves
  as x_k + v_k (t - t_k). The outputs after each step belong to t_k+1 and use that moved
  deflection, exactly as a host reads an FMU after doStep.
* ``solve_smooth``: a continuous input x(t), v(t), the physical truth the co-simulation
  approximates.
"""

import bisect
import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.interpolate import PchipInterpolator

THESIS_DATA = Path(__file__).resolve().parents[3] / "reference_data" / "thesis"
RTOL = 1e-10
ATOL_FRACTION = 1e-10  # absolute tolerance as a fraction of each state's typical size

# FMU name -> thesis component key in the CSV files, and the name of its load output.
RUBBER_KEYS = {"RoadWheelTyre": "tyre", "TrackBushRadial": "bush_radial",
               "TrackBushTorsion": "bush_torsion"}
LOAD_NAMES = {"RoadWheelTyre": "force", "TrackBushRadial": "force",
              "TrackBushTorsion": "torque"}


def thesis_rows(name):
    """The rows of one of the thesis's tables in reference_data/thesis, as dicts."""
    with open(THESIS_DATA / name, newline="") as f:
        return list(csv.DictReader(f))


# Factors that take a value in the thesis's printed unit to SI.
_TO_SI = {"N/mm": 1e3, "N.m/deg": 180.0 / math.pi, "N": 1.0, "N.m": 1.0,
          "mm/s": 1e-3, "deg/s": math.pi / 180.0}


@dataclass
class RubberSpec:
    elements: list  # [(k, c, xi)] of the structure's elements, SI
    elastic: tuple  # a0..a3 in SI
    h: float
    x_ref: float
    unilateral: bool
    # (outer, nested or None) indices into elements: the parallel branches
    branches: tuple = ((0, 1), (2, None))


# The thesis's model structures (sections 6.1-6.4): which table, which of its elements (by
# number), and how they form branches (indices into that selection). The simplified Haupt and
# Sedlan model's two elements are not printed (section 6.2); the final model is it with a
# stiffening element nested in element 1 (section 6.4), so they are its elements 1 and 3.
STRUCTURE_TABLES = {
    "final": ("appendix_4b.csv", ("1", "2", "3"), ((0, 1), (2, None))),
    "four-element": ("appendix_4a.csv", ("1", "2", "3", "4"), ((0, 1), (2, 3))),
    "haupt-sedlan": ("appendix_4b.csv", ("1", "3"), ((0, None), (1, None))),
}


def rubber_spec(fmu_name, structure="final"):
    key = RUBBER_KEYS[fmu_name]
    table, numbers, branches = STRUCTURE_TABLES[structure]
    rows = {row["element"]: row for row in thesis_rows(table) if row["component"] == key}
    if not rows:
        raise KeyError(f"the thesis gives no {structure} values for {fmu_name} ({table})")
    elements = [(float(rows[n]["k"]) * _TO_SI[rows[n]["k_unit"]],
                 float(rows[n]["c"]) * _TO_SI[rows[n]["c_unit"]],
                 float(rows[n]["xi"]) * _TO_SI[rows[n]["xi_unit"]]) for n in numbers]
    (elastic,) = [r for r in thesis_rows("elastic_functions.csv") if r["component"] == key]
    (geometric,) = [r for r in thesis_rows("geometric_multipliers.csv") if r["component"] == key]
    a = [float(elastic[f"a{p}"]) for p in range(4)]
    h, x_ref = float(geometric["h"]), float(geometric["x_ref"])
    if elastic["deflection_unit"] == "deg":  # polynomial in degrees -> in radians
        a = [coefficient * (180.0 / math.pi) ** p for p, coefficient in enumerate(a)]
    if geometric["deflection_unit"] == "deg":
        h, x_ref = h * 180.0 / math.pi, math.radians(x_ref)
    return RubberSpec(elements, tuple(a), h, x_ref, unilateral=(key == "tyre"),
                      branches=branches)


@dataclass
class DamperSpec:
    C1: float
    C2: float
    I: float
    rates: np.ndarray
    torques: np.ndarray  # smoothed column of Table A6-1


def damper_spec():
    constants = {r["name"]: r for r in thesis_rows("damper_constants.csv")}
    c1 = float(constants["C1"]["value"]) * (1e-3 if constants["C1"]["unit"] == "N.mm" else 1.0)
    table = thesis_rows("table_A6-1.csv")
    return DamperSpec(c1, float(constants["C2"]["value"]), float(constants["I"]["value"]),
                      np.array([float(r["rate_rad_per_s"]) for r in table]),
                      np.array([float(r["smoothed_N_m"]) for r in table]))


# --- right-hand sides and outputs --------------------------------------------------------

class RubberEquations:
    """State: the spring deformation of each element, in the order of spec.elements (for
    the final model s, w, r); y[i] belongs to element i."""

    def __init__(self, spec, load_name):
        self.spec = spec
        self.state_size = len(spec.elements)
        self.names = (load_name, f"{load_name}_elastic", f"{load_name}_viscoelastic")
        # Spring deformations reach about c/k, where each dashpot saturates.
        self.atol = np.array([c / k for k, c, _ in spec.elements]) * ATOL_FRACTION

    def initial_state(self, x0, v0):
        return np.zeros(self.state_size)

    def rhs(self, t, y, x_of_t, rate):
        elements = self.spec.elements
        if self.spec.unilateral and x_of_t(t) <= 0.0:
            rate = 0.0
        dydt = [0.0] * self.state_size
        for outer, nested in self.spec.branches:
            k1, c1, xi1 = elements[outer]
            s = y[outer]
            if nested is None:
                dydt[outer] = rate - k1 * s * (abs(rate) + xi1) / c1
                continue
            k2, c2, xi2 = elements[nested]
            w = y[nested]
            branch = k1 * s + k2 * w
            sdot = rate - branch * (abs(rate) + xi1) / c1
            # the nested element spans spring k1: its rate is ds/dt
            dydt[outer], dydt[nested] = sdot, sdot - k2 * w * (abs(sdot) + xi2) / c2
        return dydt

    def jac(self, t, y, x_of_t, rate):
        elements = self.spec.elements
        if self.spec.unilateral and x_of_t(t) <= 0.0:
            rate = 0.0
        jacobian = np.zeros((self.state_size, self.state_size))
        for outer, nested in self.spec.branches:
            k1, c1, xi1 = elements[outer]
            b1 = (abs(rate) + xi1) / c1
            if nested is None:
                jacobian[outer, outer] = -k1 * b1
                continue
            k2, c2, xi2 = elements[nested]
            s, w = y[outer], y[nested]
            sdot = rate - (k1 * s + k2 * w) * b1
            jacobian[outer, outer], jacobian[outer, nested] = -k1 * b1, -k2 * b1
            factor = 1.0 - k2 * w * np.sign(sdot) / c2
            jacobian[nested, outer] = -k1 * b1 * factor
            jacobian[nested, nested] = -k2 * b1 * factor - k2 * (abs(sdot) + xi2) / c2
        return jacobian

    def breakpoints(self, t0, t1, x0, rate):
        """Times inside (t0, t1) where the right-hand side switches (contact)."""
        if self.spec.unilateral and rate != 0.0:
            crossing = t0 - x0 / rate
            if t0 < crossing < t1:
                return [crossing]
        return []

    def outputs(self, y, x):
        spec = self.spec
        if spec.unilateral and x <= 0.0:
            return dict.fromkeys(self.names, 0.0)
        a0, a1, a2, a3 = spec.elastic
        elastic = a0 + a1 * x + a2 * x ** 2 + a3 * x ** 3
        springs = 0.0
        for (k, _, _), deformation in zip(spec.elements, y):
            springs += k * deformation
        viscoelastic = (1.0 + spec.h * abs(x - spec.x_ref)) * springs
        force = elastic + viscoelastic
        if spec.unilateral:
            force = max(0.0, force)
        return dict(zip(self.names, (force, elastic, viscoelastic)))


class DamperEquations:
    state_size = 2

    def __init__(self, spec):
        self.spec = spec
        curve = PchipInterpolator(spec.rates, spec.torques, extrapolate=False)
        # scipy's own piecewise-cubic coefficients, evaluated in plain Python: the solver
        # calls this a million times per case, where a scalar call into scipy costs ~20 us.
        self.knots = [float(r) for r in curve.x]
        self.coefficients = [tuple(float(c) for c in column) for column in curve.c.T]
        self.end_slopes = (self.coefficients[0][2], self._cubic(self.knots[-1])[1])
        self.atol = np.array([spec.C2, 1.0]) * ATOL_FRACTION  # rotor angle (rad), rate (rad/s)

    def _cubic(self, rate):
        """(value, slope) of the PCHIP curve inside the table."""
        i = min(max(bisect.bisect_right(self.knots, rate) - 1, 0), len(self.coefficients) - 1)
        c3, c2, c1, c0 = self.coefficients[i]
        d = rate - self.knots[i]
        return ((c3 * d + c2) * d + c1) * d + c0, (3 * c3 * d + 2 * c2) * d + c1

    def dashpot_slope(self, rate):
        if rate < self.knots[0]:
            return self.end_slopes[0]
        if rate > self.knots[-1]:
            return self.end_slopes[1]
        return self._cubic(rate)[1]

    def dashpot(self, rate):
        spec = self.spec
        if rate < self.knots[0]:
            return spec.torques[0] + self.end_slopes[0] * (rate - self.knots[0])
        if rate > self.knots[-1]:
            return spec.torques[-1] + self.end_slopes[1] * (rate - self.knots[-1])
        return self._cubic(rate)[0]

    def gas(self, deflection):
        q = deflection / self.spec.C2
        return self.spec.C1 * (1.0 / (1.0 - q) - 1.0 / (1.0 + q))

    def initial_state(self, theta0, omega0):
        return np.array([theta0, omega0])

    def rhs(self, t, y, theta_of_t, rate):
        rotor_angle, rotor_rate = y
        return [rotor_rate,
                (self.gas(theta_of_t(t) - rotor_angle) - self.dashpot(rotor_rate)) / self.spec.I]

    def jac(self, t, y, theta_of_t, rate):
        q = (theta_of_t(t) - y[0]) / self.spec.C2
        gas_slope = self.spec.C1 / self.spec.C2 * (1.0 / (1.0 - q) ** 2 + 1.0 / (1.0 + q) ** 2)
        dashpot_slope = self.dashpot_slope(y[1])
        return np.array([[0.0, 1.0], [-gas_slope / self.spec.I, -dashpot_slope / self.spec.I]])

    def breakpoints(self, t0, t1, x0, rate):
        return []

    def outputs(self, y, theta):
        deflection = theta - y[0]
        return {"torque": self.gas(deflection), "gas_deflection": deflection,
                "rotor_rate": y[1], "dashpot_torque": self.dashpot(y[1])}


def spec_from_parameters(component, values, structure="final"):
    """The spec of a part given by FMU parameter values (name -> SI; the names are the only
    thing taken from the FMUs' side), for an engineer's own part; names left out keep the
    thesis values."""
    from ..runtime.catalog import STRUCTURES, component_definition

    v = dict(component_definition(component, structure).default_parameters(), **values)
    if component == "RotaryDamper":
        points = range(1, sum(1 for name in v if name.startswith("dashpot.rate[")) + 1)
        return DamperSpec(v["C1"], v["C2"], v["I"],
                          np.array([v[f"dashpot.rate[{i}]"] for i in points]),
                          np.array([v[f"dashpot.torque[{i}]"] for i in points]))
    numbers = [number for number, _ in STRUCTURES[structure].elements]
    index = {number: i for i, number in enumerate(numbers)}
    return RubberSpec(
        elements=[(v[f"k{i}"], v[f"c{i}"], v[f"xi{i}"]) for i in numbers],
        elastic=tuple(v[f"elastic.a{p}"] for p in range(4)), h=v["geometric.h"],
        x_ref=v["geometric.x_ref"], unilateral=rubber_spec(component).unilateral,
        branches=tuple((index[outer], None if inner is None else index[inner])
                       for outer, inner in STRUCTURES[structure].branches))


def equations_for(fmu_name, structure="final", spec=None):
    """The equations of a component in one of the thesis's structures with the thesis's
    values, or with `spec` (a RubberSpec or DamperSpec of other values)."""
    if fmu_name == "RotaryDamper":
        return DamperEquations(spec or damper_spec())
    return RubberEquations(spec or rubber_spec(fmu_name, structure), LOAD_NAMES[fmu_name])


# --- solvers ---------------------------------------------------------------------------

def _integrate(equations, y, t_points, x_of_t, rate):
    """Integrate from t_points[0] with the rate held; states at each later point."""
    t0, t1 = t_points[0], t_points[-1]
    edges = [t0] + equations.breakpoints(t0, t1, x_of_t(t0), rate) + [t1]
    states = []
    for a, b in zip(edges[:-1], edges[1:]):
        inside = [t for t in t_points[1:] if a < t <= b]
        sol = solve_ivp(equations.rhs, (a, b), y, method="Radau", rtol=RTOL, atol=equations.atol,
                        jac=equations.jac, args=(x_of_t, rate), t_eval=inside or None)
        if not sol.success:
            raise RuntimeError(f"reference solve failed on [{a}, {b}]: {sol.message}")
        if inside:
            states += [sol.y[:, i] for i in range(len(inside))]
        y = sol.y[:, -1]
    return states


def solve_held_rate(fmu_name, times, deflection, rate, structure="final", read_after_set=False,
                    spec=None):
    """Outputs at every sample time under the co-simulation input convention.

    Row 0 is the initial output (inputs at t_0, relaxed state); row k+1 the output after
    the step [t_k, t_k+1], at the deflection the step moved to, or with read_after_set at
    the sample deflection x_k+1 set before reading (what a host reads after fmi2SetReal).
    Consecutive steps that share the same rate along a continuous path (a hold, a ramp) are
    one interval of the held-rate input, so they are integrated in one call, which changes
    nothing but cost. spec: other values than the thesis's (see equations_for).
    """
    equations = equations_for(fmu_name, structure, spec)
    times = np.asarray(times, dtype=float)
    deflection = np.asarray(deflection, dtype=float)
    rate = np.asarray(rate, dtype=float)
    y = equations.initial_state(deflection[0], rate[0])
    rows = [equations.outputs(y, deflection[0])]
    k = 0
    n = len(times)
    while k < n - 1:
        x0, v0, t0 = deflection[k], rate[k], times[k]

        def x_of_t(t, x0=x0, v0=v0, t0=t0):
            return x0 + v0 * (t - t0)

        j = k + 1
        while j < n - 1 and rate[j] == v0 and math.isclose(
                deflection[j], x_of_t(times[j]), rel_tol=1e-12, abs_tol=1e-15):
            j += 1
        states = _integrate(equations, y, times[k:j + 1], x_of_t, v0)
        read_at = deflection[k + 1:j + 1] if read_after_set else \
            [x_of_t(t) for t in times[k + 1:j + 1]]
        rows += [equations.outputs(state, x) for state, x in zip(states, read_at)]
        y = states[-1]
        k = j
    return {key: np.array([row[key] for row in rows]) for key in rows[0]}


def solve_smooth(fmu_name, t_eval, x_of_t, v_of_t, structure="final", spec=None):
    """Outputs at t_eval for a continuous input x(t) with rate v(t); spec: other values
    than the thesis's (see equations_for)."""
    equations = equations_for(fmu_name, structure, spec)
    t_eval = np.asarray(t_eval, dtype=float)
    y0 = equations.initial_state(x_of_t(t_eval[0]), v_of_t(t_eval[0]))

    def rhs(t, y):
        return equations.rhs(t, y, x_of_t, v_of_t(t))

    def jac(t, y):
        return equations.jac(t, y, x_of_t, v_of_t(t))

    sol = solve_ivp(rhs, (t_eval[0], t_eval[-1]), y0, method="Radau", rtol=RTOL, atol=equations.atol,
                    jac=jac, t_eval=t_eval)
    if not sol.success:
        raise RuntimeError(f"reference solve failed: {sol.message}")
    rows = [equations.outputs(sol.y[:, i], x_of_t(t)) for i, t in enumerate(sol.t)]
    return {key: np.array([row[key] for row in rows]) for key in rows[0]}
