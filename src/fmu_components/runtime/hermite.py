"""Monotone C1 piecewise-cubic Hermite interpolation (Fritsch & Carlson, SIAM J. Numer.
Anal. 17 (1980) 238-246), with the interior and end slopes that scipy's
PchipInterpolator uses, so that inside the table the two agree to round-off.

Outside the table the curve continues as a straight line with the curve's end slope,
which keeps it C1 (spec section 3: "extended with the slope of the end segment"; for
Table A6-1 both end segments are flat, so the end slope is zero either way).
"""

import bisect
import math


def _sign(value):
    return (value > 0.0) - (value < 0.0)


def _end_slope(h0, h1, m0, m1):
    """Three-point end slope, limited to keep the end interval monotone."""
    d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    if _sign(d) != _sign(m0):
        return 0.0
    if _sign(m0) != _sign(m1) and abs(d) > 3.0 * abs(m0):
        return 3.0 * m0
    return d


def check_monotone_table(xs, ys):
    """Return a message if (xs, ys) cannot define a monotone curve, else None."""
    if len(xs) != len(ys):
        return f"table has {len(xs)} abscissae but {len(ys)} ordinates"
    if len(xs) < 3:
        return f"table needs at least 3 points, got {len(xs)}"
    for i, (x, y) in enumerate(zip(xs, ys)):
        if not (math.isfinite(x) and math.isfinite(y)):
            return f"table point {i + 1} is not finite: ({x!r}, {y!r})"
    for i in range(1, len(xs)):
        if not xs[i] > xs[i - 1]:
            return (f"table abscissae must increase strictly: point {i + 1} ({xs[i]:.6g}) "
                    f"does not exceed point {i} ({xs[i - 1]:.6g})")
        if ys[i] < ys[i - 1]:
            return (f"table ordinates must not decrease: point {i + 1} ({ys[i]:.6g}) "
                    f"is below point {i} ({ys[i - 1]:.6g})")
    return None


class MonotoneCubic:
    """y(x) through the points (xs, ys), xs strictly increasing, ys non-decreasing."""

    def __init__(self, xs, ys):
        problem = check_monotone_table(xs, ys)
        if problem:
            raise ValueError(problem)
        self.xs = [float(x) for x in xs]
        self.ys = [float(y) for y in ys]
        n = len(xs)
        h = [self.xs[i + 1] - self.xs[i] for i in range(n - 1)]
        m = [(self.ys[i + 1] - self.ys[i]) / h[i] for i in range(n - 1)]
        d = [0.0] * n
        for k in range(1, n - 1):
            if m[k - 1] * m[k] > 0.0:
                w1 = 2.0 * h[k] + h[k - 1]
                w2 = h[k] + 2.0 * h[k - 1]
                d[k] = (w1 + w2) / (w1 / m[k - 1] + w2 / m[k])
        d[0] = _end_slope(h[0], h[1], m[0], m[1])
        d[-1] = _end_slope(h[-1], h[-2], m[-1], m[-2])
        # Each piece is a cubic in powers of t = x - x_i, y_i + d_i t + c2 t^2 + c3 t^3,
        # valid for lower <= x < upper: (lower, upper, x_i, y_i, d_i, c2, c3). Beyond either
        # end the piece is the straight extension.
        self._pieces = [(self.xs[i], self.xs[i + 1], self.xs[i], self.ys[i], d[i],
                         (3.0 * m[i] - 2.0 * d[i] - d[i + 1]) / h[i],
                         (d[i] + d[i + 1] - 2.0 * m[i]) / (h[i] * h[i])) for i in range(n - 1)]
        self._below = (-math.inf, self.xs[0], self.xs[0], self.ys[0], d[0], 0.0, 0.0)
        self._above = (self.xs[-1], math.inf, self.xs[-1], self.ys[-1], d[-1], 0.0, 0.0)
        self._last = self._pieces[0]  # where the last lookup landed: the next is usually there

    def _piece(self, x):
        piece = self._last
        if not piece[0] <= x < piece[1]:
            if x < self.xs[0]:
                piece = self._below
            elif x >= self.xs[-1]:
                piece = self._above
            else:  # NaN lands on the last piece, as in the C runtime
                index = bisect.bisect_right(self.xs, x) - 1
                piece = self._pieces[min(index, len(self._pieces) - 1)]
            self._last = piece
        return piece

    def value(self, x):
        # The damper's hottest call (every integrator stage): _piece's test written inline.
        lower, upper, x0, y0, d0, c2, c3 = self._last
        if not lower <= x < upper:
            lower, upper, x0, y0, d0, c2, c3 = self._piece(x)
        t = x - x0
        return y0 + t * (d0 + t * (c2 + t * c3))

    def value_and_slope(self, x):
        _, _, x0, y0, d0, c2, c3 = self._piece(x)
        t = x - x0
        return y0 + t * (d0 + t * (c2 + t * c3)), d0 + t * (2.0 * c2 + 3.0 * t * c3)

    def slope(self, x):
        return self.value_and_slope(x)[1]

    __call__ = value


_SHARED = {}
MAX_SHARED = 64


def shared_curve(xs, ys):
    """The curve through these points, one object for every model with the same table: the
    models then share their compiled step too (integrator.Rosenbrock.compiled), which names
    the curve's functions."""
    key = (tuple(xs), tuple(ys))
    curve = _SHARED.get(key)
    if curve is None:
        if len(_SHARED) >= MAX_SHARED:
            _SHARED.clear()  # a host sweeping tables: do not grow forever
        curve = _SHARED[key] = MonotoneCubic(xs, ys)
    return curve
