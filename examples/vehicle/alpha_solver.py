"""An own implicit solver core for the vehicle: exudyn's generalized-alpha step
(alpha_solver.c) for index-3 constrained second-order systems
    M a = f(t, q, v) - G(q)^T lambda,   g(q) = 0,
M constant diagonal, its Newton matrix a bordered band with a fixed pattern (bordered_band.c):
the unknowns (coordinates, then multipliers) in the caller's order, the first of that order
in a band of given half bandwidth (no pivoting; a pivot that is not positive is an error
naming its unknown), the rest in a dense border (its Schur complement, partial pivoting);
an entry outside the pattern is an error naming its row and column. Compiled on first use
(bank_build.Library, as the joints' and contacts' kernels).

The system is two C callbacks with a context pointer (alpha_solver.h): `evaluate` gives f,
g and G's triplets at (t, q, v); `jacobian` gives the triplets of K = -df/dq and
D = -df/dv. `PythonSystem` makes them from Python functions (the tests' small models).
"""

import ctypes
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from fmu_components.coupling.bank_build import Library

HERE = Path(__file__).resolve().parent
LIBRARY = Library("vehicle_alpha", [HERE / "bordered_band.c", HERE / "alpha_solver.c"],
                  [HERE / "bordered_band.h", HERE / "alpha_solver.h"],
                  "the vehicle's solver core (alpha_solver.c)", "exudyn's own solver")
STATUS = {0: "converged", 1: "not converged", 2: "band pivot not positive",
          3: "entry outside the band and the border", 4: "border singular",
          5: "callback failed"}
OUTSIDE = 3  # alpha_solver.h's ALPHA_OUTSIDE: the Newton matrix's structure, not Newton
BB_OUTSIDE, BB_PIVOT, BB_SINGULAR = 1, 2, 3
TRACE = 64  # alpha_solver.h's ALPHA_TRACE: iterations of a solve traced

_pointer, _int, _real = ctypes.c_void_p, ctypes.c_int, ctypes.c_double


class Triplets(ctypes.Structure):
    _fields_ = [("capacity", _int), ("count", _int), ("row", ctypes.POINTER(_int)),
                ("col", ctypes.POINTER(_int)), ("value", ctypes.POINTER(_real))]


_REALS = ctypes.POINTER(_real)
EVALUATE = ctypes.CFUNCTYPE(_int, _pointer, _real, _REALS, _REALS, _REALS, _REALS,
                            ctypes.POINTER(Triplets))
JACOBIAN = ctypes.CFUNCTYPE(_int, _pointer, _real, _REALS, _REALS, ctypes.POINTER(Triplets),
                            ctypes.POINTER(Triplets))


class Settings(ctypes.Structure):
    """exudyn's generalizedAlpha.spectralRadius and newton settings of the same names, their
    defaults exudyn's (1.13.6), full Newton unless use_modified_newton (exudyn's default)
    or reuse_jacobian (the reuse policy, alpha_solver.h: 1 the factorization kept across
    a step's iterations and passes, 2 across its steps of the same h too; a new one after
    an iteration that contracted the residual norm by a ratio worse than
    reuse_contractivity; reuse_damping: the halvings of an update on a new matrix that
    grew it)."""
    _fields_ = [("spectral_radius", _real), ("relative_tolerance", _real),
                ("absolute_tolerance", _real), ("maximum_solution_norm", _real),
                ("modified_newton_contractivity", _real), ("pivot_tolerance", _real),
                ("max_iterations", _int), ("use_modified_newton", _int),
                ("max_modified_newton_iterations", _int),
                ("max_modified_newton_restart_iterations", _int),
                ("adapt_initial_residual", _int), ("reuse_jacobian", _int),
                ("reuse_contractivity", _real), ("reuse_broyden", _int),
                ("first_pass_tolerance", _real), ("reuse_damping", _int)]
    DEFAULTS = dict(spectral_radius=0.9, relative_tolerance=1e-8, absolute_tolerance=1e-10,
                    maximum_solution_norm=1e38, modified_newton_contractivity=0.5,
                    pivot_tolerance=1e-12, max_iterations=25, use_modified_newton=0,
                    max_modified_newton_iterations=8,
                    max_modified_newton_restart_iterations=7, adapt_initial_residual=1,
                    reuse_jacobian=0, reuse_contractivity=0.5, reuse_broyden=0,
                    first_pass_tolerance=0.0, reuse_damping=0)

    def __init__(self, **given):
        unknown = set(given) - set(self.DEFAULTS)
        if unknown:
            raise TypeError(f"no such solver setting: {sorted(unknown)}")
        super().__init__(**{**self.DEFAULTS, **given})


class StructureError(ValueError):
    """The bordered band's pattern or factorization refused the matrix; `row`, `col`
    the unknowns concerned."""

    def __init__(self, message, row, col):
        super().__init__(message)
        self.row, self.col = row, col


def library():
    lib = LIBRARY.load("no own solver")
    if lib is None:
        raise RuntimeError("the solver core needs a C compiler (gcc)")
    if lib.bb_create.restype is not _pointer:
        lib.bb_create.restype = _pointer
        lib.bb_create.argtypes = [_int, _pointer, _int, _int]
        lib.bb_free.argtypes = [_pointer]
        lib.bb_zero.argtypes = [_pointer]
        lib.bb_add_many.argtypes = [_pointer, _int, _pointer, _pointer, _pointer, _real]
        lib.bb_factorize.argtypes = [_pointer]
        lib.bb_solve.argtypes = [_pointer, _pointer, _pointer]
        lib.bb_bad.argtypes = [_pointer, _pointer]
        lib.alpha_create.restype = _pointer
        lib.alpha_create.argtypes = [_int, _int, _pointer, _pointer, _int, _int, _int,
                                     ctypes.POINTER(Settings), EVALUATE, JACOBIAN, _pointer]
        lib.alpha_free.argtypes = [_pointer]
        lib.alpha_initialize.argtypes = [_pointer, _real, _pointer, _pointer, _int]
        lib.alpha_step.argtypes = [_pointer, _real, _real]
        lib.alpha_restart.argtypes = [_pointer]
        lib.alpha_repeat.argtypes = [_pointer, _real, _real, _int]
        lib.alpha_state.argtypes = [_pointer] + [_pointer] * 4
        lib.alpha_report.argtypes = [_pointer, _pointer, _pointer]
        lib.alpha_trace.argtypes = [_pointer, _pointer, _pointer]
        lib.alpha_configure.argtypes = [_pointer, ctypes.POINTER(Settings)]
        lib.alpha_coefficients.argtypes = [_pointer, _pointer]
    return lib


def _ints(values):
    return np.ascontiguousarray(values, dtype=np.intc)


def _reals(values):
    return np.ascontiguousarray(values, dtype=float)


class BorderedBand:
    """The bordered band matrix of `n` unknowns: `order` (a permutation), its first
    `n_band` in a band of half bandwidth `half_bandwidth`, the rest the border."""

    def __init__(self, n, order, n_band, half_bandwidth):
        self.lib = library()
        self.n = n
        order = _ints(order)  # alive through the call
        self.handle = self.lib.bb_create(n, order.ctypes.data, n_band, half_bandwidth)
        if not self.handle:
            raise ValueError("bordered band: order is not a permutation of the unknowns, "
                             "or the sizes are wrong")

    def __del__(self):
        if getattr(self, "handle", None):
            self.lib.bb_free(self.handle)
            self.handle = None

    def _bad(self):
        rows = np.zeros(2, dtype=np.intc)
        self.lib.bb_bad(self.handle, rows.ctypes.data)
        return int(rows[0]), int(rows[1])

    def set(self, rows, cols, values):
        """The matrix (zeroed first) from triplets; repeated entries add."""
        rows, cols, values = _ints(rows), _ints(cols), _reals(values)
        self.lib.bb_zero(self.handle)
        status = self.lib.bb_add_many(self.handle, len(values), rows.ctypes.data,
                                      cols.ctypes.data, values.ctypes.data, 1.0)
        if status == BB_OUTSIDE:
            row, col = self._bad()
            raise StructureError(f"entry ({row}, {col}) outside the band and the border",
                                 row, col)

    def factorize(self):
        status = self.lib.bb_factorize(self.handle)
        if status:
            row, col = self._bad()
            what = "band pivot not positive" if status == BB_PIVOT else "border singular"
            raise StructureError(f"{what} at unknown {row}", row, col)

    def solve(self, rhs):
        rhs = _reals(rhs)
        x = np.empty(self.n)
        self.lib.bb_solve(self.handle, rhs.ctypes.data, x.ctypes.data)
        return x


class PythonSystem:
    """C callbacks from Python functions: evaluate(t, q, v) -> (f, g, (rows, cols, G)) and
    jacobian(t, q, v) -> ((rows, cols, K), (rows, cols, D)), each with numpy arrays."""

    def __init__(self, nq, nm, evaluate, jacobian):
        self.nq, self.nm = nq, nm

        def view(pointer, n):
            return np.ctypeslib.as_array(pointer, shape=(n,))

        def fill(triplets, rows, cols, values):
            t = triplets.contents
            if len(values) > t.capacity:
                return False
            t.count = len(values)
            view(t.row, len(values))[:] = rows
            view(t.col, len(values))[:] = cols
            view(t.value, len(values))[:] = values
            return True

        def c_evaluate(context, t, q, v, f, g, G):
            try:
                f_, g_, G_ = evaluate(t, view(q, nq).copy(), view(v, nq).copy())
                view(f, nq)[:] = f_
                if nm:
                    view(g, nm)[:] = g_
                return 0 if fill(G, *G_) else 1
            except Exception:  # an error in the model: the step's status says so
                return 1

        def c_jacobian(context, t, q, v, K, D):
            try:
                K_, D_ = jacobian(t, view(q, nq).copy(), view(v, nq).copy())
                return 0 if fill(K, *K_) and fill(D, *D_) else 1
            except Exception:
                return 1

        self.evaluate, self.jacobian = EVALUATE(c_evaluate), JACOBIAN(c_jacobian)
        self.context = None


class AlphaSolver:
    """The solver over `system` (callbacks .evaluate, .jacobian, .context): masses (the
    diagonal of M), `n_multipliers`, the unknowns' order (coordinates 0..nq-1, multipliers
    nq..), how many of that order are in the band and its half bandwidth, the triplets'
    capacity, Settings."""

    def __init__(self, system, masses, n_multipliers, order, n_band, half_bandwidth,
                 settings=None, capacity=4096):
        self.lib = library()
        self.system = system  # its callbacks live as long as the solver
        self.nq, self.nm = len(masses), n_multipliers
        self.settings = settings or Settings()
        masses, order = _reals(masses), _ints(order)  # alive through the call
        self.handle = self.lib.alpha_create(
            self.nq, self.nm, masses.ctypes.data, order.ctypes.data, n_band,
            half_bandwidth, capacity, ctypes.byref(self.settings), system.evaluate,
            system.jacobian, system.context)
        if not self.handle:
            raise ValueError("solver: order is not a permutation of the unknowns, or the "
                             "sizes are wrong")
        self.time = 0.0
        # what state() and report() read into, made once (a host reads them every pass)
        self._lam = np.empty(max(self.nm, 1))
        self._ints, self._reals = np.zeros(5, dtype=np.intc), np.zeros(2)
        self._report_at = (self._ints.ctypes.data, self._reals.ctypes.data)
        self._lam_at = self._lam.ctypes.data

    def __del__(self):
        if getattr(self, "handle", None):
            self.lib.alpha_free(self.handle)
            self.handle = None

    def initialize(self, t, q, v, compute_initial_accelerations=True):
        q, v = _reals(q), _reals(v)  # alive through the call
        status = self.lib.alpha_initialize(self.handle, t, q.ctypes.data, v.ctypes.data,
                                           int(compute_initial_accelerations))
        self.time = t
        return status

    def step(self, h, t_new):
        """One step to t_new (= t + h, the caller's sum); its status (0: converged; on any
        other the state is the step's start)."""
        status = self.lib.alpha_step(self.handle, h, t_new)
        if status == 0:
            self.time = t_new
        return status

    def restart(self):
        """The state back at the last step's start (a retry of the step at another h)."""
        self.lib.alpha_restart(self.handle)

    def repeat(self, h, t_new, warm=False):
        """The last step solved again from its start (a coupled host's next pass); warm:
        its Newton from the present solution instead of the predictor. Status as step's."""
        status = self.lib.alpha_repeat(self.handle, h, t_new, int(warm))
        if status == 0:
            self.time = t_new
        return status

    def state(self, block=None, at=None):
        """(q, v, a, lambda): q, v and a rows of `block` (3 x nq, C order; `at` its
        address, where the caller has it) or of a new one, lambda a copy."""
        if block is None:
            block = np.empty((3, self.nq))
        if at is None:
            at = block.ctypes.data
        row = 8 * self.nq
        self.lib.alpha_state(self.handle, at, at + row, at + 2 * row, self._lam_at)
        return block[0], block[1], block[2], self._lam[:self.nm].copy()

    def iterations(self):
        """The last step's Newton iterations (report's first)."""
        self.lib.alpha_report(self.handle, *self._report_at)
        return int(self._ints[0])

    def report(self):
        """The last step's (iterations, Jacobians, residual norm, bad row, bad column)."""
        ints, reals = self._ints, self._reals
        self.lib.alpha_report(self.handle, *self._report_at)
        return dict(iterations=int(ints[0]), jacobians=int(ints[1]),
                    total_jacobians=int(ints[2]), bad_row=int(ints[3]),
                    bad_col=int(ints[4]), residual=float(reals[0]),
                    initial_residual=float(reals[1]))

    def configure(self, **changes):
        """Settings changed from the next step on (not the spectral radius, the pivot
        tolerance, nor more max_iterations than the first settings'); the Newton matrix
        kept."""
        settings = Settings(**{**{name: getattr(self.settings, name)
                                  for name, *_ in Settings._fields_}, **changes})
        if self.lib.alpha_configure(self.handle, ctypes.byref(settings)):
            raise ValueError("max_iterations above the solver's first settings'")
        self.settings = settings

    def coefficients(self):
        """generalized-alpha's alpha_m, alpha_f, beta, gamma."""
        out = np.zeros(4)
        self.lib.alpha_coefficients(self.handle, out.ctypes.data)
        return dict(zip(("alpha_m", "alpha_f", "beta", "gamma"), out))

    def trace(self):
        """The last solve's iterations (up to alpha_solver.h's ALPHA_TRACE): each one's
        residual norm after its update, and whether it made a new Newton matrix (2: at
        the pass's start again, after an iterate that diverged)."""
        norms, made = np.zeros(TRACE), np.zeros(TRACE, dtype=np.intc)
        n = self.lib.alpha_trace(self.handle, norms.ctypes.data, made.ctypes.data)
        return norms[:n], made[:n]
