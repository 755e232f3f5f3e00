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
        self.slopes = d
        self._h = h
        self._last = n - 2

    def value_and_slope(self, x):
        xs = self.xs
        if x <= xs[0]:
            return self.ys[0] + self.slopes[0] * (x - xs[0]), self.slopes[0]
        if x >= xs[-1]:
            return self.ys[-1] + self.slopes[-1] * (x - xs[-1]), self.slopes[-1]
        i = min(bisect.bisect_right(xs, x) - 1, self._last)
        h = self._h[i]
        t = (x - xs[i]) / h
        y0, y1 = self.ys[i], self.ys[i + 1]
        d0, d1 = self.slopes[i] * h, self.slopes[i + 1] * h
        # Cubic Hermite basis on t in [0, 1].
        t2 = t * t
        t3 = t2 * t
        value = ((2 * t3 - 3 * t2 + 1) * y0 + (t3 - 2 * t2 + t) * d0
                 + (-2 * t3 + 3 * t2) * y1 + (t3 - t2) * d1)
        slope = ((6 * t2 - 6 * t) * y0 + (3 * t2 - 4 * t + 1) * d0
                 + (-6 * t2 + 6 * t) * y1 + (3 * t2 - 2 * t) * d1) / h
        return value, slope

    def __call__(self, x):
        return self.value_and_slope(x)[0]
