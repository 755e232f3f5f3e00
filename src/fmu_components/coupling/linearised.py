"""A component's answer to a host step, linearised with its Model Exchange Jacobian.

For a component whose `stiffness` output is the instantaneous tangent but whose internal
dynamics act within a host step (the damper: its rotor follows the arm in a fraction of
a millisecond, so over a 1-4 ms step the torque answers the arm's motion far more softly
than the gas spring's stiffness says), the coupling asks the FMU itself. A Model Exchange
instance of the same FMU, set to the co-simulation instance's states (the `state.*`
variables both interfaces expose), gives by getDirectionalDerivative the Jacobians

    A = df/dX, B = df/d(x, v), C = dF/dX, D = dF/d(x, v)

at that point, f the state derivatives and F the load. Along the secant path a step
feeds, x(s) = x0 + v s (s in [0, h]), the linearised states obey

    dY/ds = A Y + B_x v s + B_v (v - v0) + f0,

so one matrix exponential of an augmented system gives the load after the step at the
rate v0 (its prediction), and its derivative by the end deflection, dF(h)/dx(h) (the
step's tangent, in which the rotor's inertia and the dashpot's slope appear). Nothing
here steps the FMU: no fmi2DoStep, no state of the co-simulation instance touched.
"""

import ctypes
import math

import numpy as np

from .bank_build import built_library
from .instance import MODEL_EXCHANGE, FmuInstance

# Where the bank's library is built, Linearisation.step takes the exponential from its C
# twin of expm (bank_linearised.c: the same bits, tests/test_bank.py), 40 times faster;
# False: always the Python below.
USE_COMPILED = True
_compiled = []  # the C function once looked up, or None


# The small matrices below are plain Python: each product and sum in the order bank.c's
# C has them (bank_linearised.c, compiled without fused multiply-add), so that the
# compiled path's linearised step gives this one's numbers to the bit. numpy's BLAS and
# LAPACK sum in their own orders, with fused multiply-adds, and differed in the last bits.

def _multiply(a, b, pattern=None):
    """A B of square matrices (lists of rows). With a pattern (per row, the columns that
    can be nonzero in both), the products by its zeros are left out: each sum starts
    from +0, to which a zero adds nothing, so the bits are those of the full product."""
    d = len(a)
    if pattern is None:
        pattern = [range(d)] * d
    product = []
    for row, columns in zip(a, pattern):
        out = [0.0] * d
        for k in columns:
            out[k] = sum((row[j] * b[j][k] for j in columns), 0.0)
        product.append(out)
    return product


def augmented_pattern(d):
    """Per row, the columns that can be nonzero in Linearisation.step's augmented matrix
    (two blocks of A on the diagonal, the last two columns, the 2 x 2 corner), which its
    powers, their sums and products keep (bank_linearised.c's pattern)."""
    n = (d - 2) // 2
    return [list(range(0 if r < n else n, n if r < n else 2 * n)) * (r < 2 * n)
            + list(range(d - 1 if r == d - 1 else 2 * n, d)) for r in range(d)]


def _solve(a, b):
    """X with A X = B (square, lists of rows; both overwritten): Gaussian elimination with
    partial pivoting."""
    d = len(a)
    for col in range(d):
        pivot = col
        for r in range(col + 1, d):
            if abs(a[r][col]) > abs(a[pivot][col]):
                pivot = r
        if a[pivot][col] == 0.0:
            raise ZeroDivisionError("singular matrix in the linearised step")
        a[col], a[pivot] = a[pivot], a[col]
        b[col], b[pivot] = b[pivot], b[col]
        for r in range(col + 1, d):
            f = a[r][col] / a[col][col]
            if f == 0.0:
                continue
            a[r][col:] = [x - f * y for x, y in zip(a[r][col:], a[col][col:])]
            b[r] = [x - f * y for x, y in zip(b[r], b[col])]
    for r in range(d - 1, -1, -1):
        for k in range(d):
            total = b[r][k]
            for j in range(r + 1, d):
                total -= a[r][j] * b[j][k]
            b[r][k] = total / a[r][r]
    return b


def expm(matrix, pattern=None):
    """e^M of a small matrix (lists of rows, or a numpy array): diagonal Pade (6, 6) after
    scaling to a norm of 1/2, then squaring (Higham, Functions of Matrices, ch. 10);
    `pattern`, the matrix's, as _multiply takes it."""
    rows = matrix.tolist() if hasattr(matrix, "tolist") else [list(r) for r in matrix]
    d = len(rows)
    norm = max(sum((abs(x) for x in column), 0.0) for column in zip(*rows))
    squarings = max(0, math.ceil(math.log2(norm / 0.5))) if norm > 0.5 else 0
    scale = 2.0 ** -squarings
    scaled = [[x * scale for x in row] for row in rows]
    coefficients = (1.0, 1 / 2, 5 / 44, 1 / 66, 1 / 792, 1 / 15840, 1 / 665280)
    identity = [[1.0 if r == k else 0.0 for k in range(d)] for r in range(d)]
    power, even, odd = identity, [row[:] for row in identity], [[0.0] * d for _ in range(d)]
    for k in range(1, 7):
        power = _multiply(power, scaled, pattern)
        total = odd if k % 2 else even
        for row, powers in zip(total, power):
            row[:] = [x + coefficients[k] * y for x, y in zip(row, powers)]
    denominator = [[e - o for e, o in zip(re, ro)] for re, ro in zip(even, odd)]
    result = _solve(denominator, [[e + o for e, o in zip(re, ro)] for re, ro in zip(even, odd)])
    for _ in range(squarings):
        result = _multiply(result, result, pattern)
    return result


def compiled_expm():
    """The bank library's exponential of an augmented matrix, or None where the library
    is not built (it is not compiled for this)."""
    if not _compiled:
        path = built_library()
        function = None
        if path is not None:
            function = ctypes.CDLL(str(path)).bank_augmented_expm
            function.argtypes = [ctypes.c_int, ctypes.c_void_p]
        _compiled.append(function)
    return _compiled[0]


def augmented_expm(m):
    """expm of Linearisation.step's augmented matrix (lists of rows), in C where built."""
    d = len(m)
    function = compiled_expm() if USE_COMPILED else None
    if function is None:
        return expm(m, augmented_pattern(d))
    flat = (ctypes.c_double * (d * d))(*[x for row in m for x in row])
    if function(d, flat) != 0:
        raise ZeroDivisionError("singular matrix in the linearised step")
    return [flat[r * d:(r + 1) * d] for r in range(d)]


def _dot(a, b):
    return sum((x * y for x, y in zip(a, b)), 0.0)


class Linearisation:
    """A Model Exchange side instance of a component's FMU (an FmuFile, instance.py), set
    to the co-simulation instance's states to linearise its response to a step."""

    def __init__(self, fmu, instance_name, parameters=None):
        if not fmu.model_exchange or not fmu.states:
            raise ValueError(f"{fmu.name} offers no Model Exchange with states: no "
                             f"linearised step response")
        self.name = instance_name
        self.state_names = fmu.states
        self.n = n = len(self.state_names)
        self._contact_events = fmu.event_indicators > 0
        # Its messages repeat what the co-simulation instance says of the same inputs.
        self._instance = instance = FmuInstance(fmu, instance_name, MODEL_EXCHANGE)
        instance.setup(parameters)
        instance.exit_initialization()
        self._contact = None
        self._inputs = instance.reals(fmu.inputs)
        self._load = instance.reals(fmu.outputs[:1])
        # One directional derivative per known (each state, then deflection and rate), of
        # every unknown (the derivatives, then the load and the stiffness).
        self._jacobian = instance.jacobian(fmu.derivatives + [fmu.outputs[0], "stiffness"],
                                           self.state_names + fmu.inputs)
        self._knowns = range(n + 2)

    def _at(self, states, deflection, rate):
        """Set the side instance to (states, deflection, rate); the Jacobians there."""
        fmu, n = self._instance, self.n
        fmu.set(self._inputs, [deflection, rate])
        contact = deflection > 0.0
        if self._contact_events and contact != self._contact:
            # the contact's mode switches in event mode only (docs/model-exchange.md)
            fmu.event()
            self._contact = contact
        fmu.set_states(states)
        jacobian = np.empty((n + 2, n + 2))
        for j in self._knowns:
            jacobian[:, j] = fmu.directional_derivative(self._jacobian, j)
        return jacobian, np.array(fmu.derivatives()), fmu.get(self._load)[0]

    def step(self, states, deflection, rate, step):
        """(load after the step at the held `rate`, d load / d end deflection,
        d stiffness / d end deflection): the linearised answer of the component at
        (states, deflection) to a step of length `step` along x0 + v s, and the
        sensitivities of its load and its `stiffness` output to the end point (the
        latter through the states too: the curvature the step really has)."""
        n = self.n
        jacobian, derivatives, load = self._at(states, deflection, rate)
        jacobian, derivatives = jacobian.tolist(), derivatives.tolist()
        c, d_x, d_v = jacobian[n][:n], jacobian[n][n], jacobian[n][n + 1]
        c_k, dk_x, dk_v = jacobian[n + 1][:n], jacobian[n + 1][n], jacobian[n + 1][n + 1]
        # Augmented state [Y, P, s, 1]: Y the drift at rate v0, P = dY/dv.
        d = 2 * n + 2
        m = [[0.0] * d for _ in range(d)]
        for r in range(n):
            m[r][:n] = m[n + r][n:2 * n] = jacobian[r][:n]
            m[r][2 * n] = jacobian[r][n] * rate
            m[r][2 * n + 1] = derivatives[r]
            m[n + r][2 * n] = jacobian[r][n]
            m[n + r][2 * n + 1] = jacobian[r][n + 1]
        m[2 * n][2 * n + 1] = 1.0
        m = [[x * step for x in row] for row in m]
        end = [row[2 * n + 1] for row in augmented_expm(m)]
        predicted = load + _dot(c, end[:n]) + d_x * rate * step
        by_rate = _dot(c, end[n:2 * n]) + d_x * step + d_v
        stiffness_by_rate = _dot(c_k, end[n:2 * n]) + dk_x * step + dk_v
        return predicted, by_rate / step, stiffness_by_rate / step

    def free(self):
        self._instance.close()
