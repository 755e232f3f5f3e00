/* The monotone Hermite curve: runtime/hermite.py, statement for statement. */
#include "hermite.h"

#include <math.h>
#include <stdio.h>

#include "text.h"

static int sign(double value) { return (value > 0.0) - (value < 0.0); }

/* Three-point end slope, limited to keep the end interval monotone. */
static double end_slope(double h0, double h1, double m0, double m1) {
    double d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
    if (sign(d) != sign(m0)) return 0.0;
    if (sign(m0) != sign(m1) && fabs(d) > 3.0 * fabs(m0)) return 3.0 * m0;
    return d;
}

void hermite_build(Hermite *curve, const double *xs, const double *ys, size_t size) {
    double h[HERMITE_POINTS] = {0}, m[HERMITE_POINTS] = {0}, d[HERMITE_POINTS] = {0};
    curve->size = size;
    for (size_t i = 0; i < size; i++) {
        curve->xs[i] = xs[i];
        d[i] = 0.0;
    }
    for (size_t i = 0; i + 1 < size; i++) {
        h[i] = xs[i + 1] - xs[i];
        m[i] = (ys[i + 1] - ys[i]) / h[i];
    }
    for (size_t k = 1; k + 1 < size; k++) {
        if (m[k - 1] * m[k] > 0.0) {
            double w1 = 2.0 * h[k] + h[k - 1];
            double w2 = h[k] + 2.0 * h[k - 1];
            d[k] = (w1 + w2) / (w1 / m[k - 1] + w2 / m[k]);
        }
    }
    d[0] = end_slope(h[0], h[1], m[0], m[1]);
    d[size - 1] = end_slope(h[size - 2], h[size - 3], m[size - 2], m[size - 3]);
    for (size_t i = 0; i + 1 < size; i++) {
        HermitePiece *piece = &curve->pieces[i];
        piece->lower = xs[i];
        piece->upper = xs[i + 1];
        piece->x0 = xs[i];
        piece->y0 = ys[i];
        piece->d0 = d[i];
        piece->c2 = (3.0 * m[i] - 2.0 * d[i] - d[i + 1]) / h[i];
        piece->c3 = (d[i] + d[i + 1] - 2.0 * m[i]) / (h[i] * h[i]);
    }
    curve->pieces[size - 1] = (HermitePiece){-INFINITY, xs[0], xs[0], ys[0], d[0], 0.0, 0.0};
    curve->pieces[size] = (HermitePiece){xs[size - 1], INFINITY, xs[size - 1], ys[size - 1],
                                         d[size - 1], 0.0, 0.0};
    curve->last = 0;
}

static const HermitePiece *piece_at(Hermite *curve, double x) {
    const HermitePiece *piece = &curve->pieces[curve->last];
    if (!(piece->lower <= x && x < piece->upper)) {
        size_t n = curve->size;
        size_t index;
        if (x < curve->xs[0]) {
            index = n - 1; /* below */
        } else if (x >= curve->xs[n - 1]) {
            index = n; /* above */
        } else {
            size_t lo = 0, hi = n; /* bisect_right(xs, x) - 1; NaN lands on the last piece */
            while (lo < hi) {
                size_t mid = (lo + hi) / 2;
                if (x < curve->xs[mid]) hi = mid;
                else lo = mid + 1;
            }
            index = lo - 1 < n - 2 ? lo - 1 : n - 2;
        }
        curve->last = index;
        piece = &curve->pieces[index];
    }
    return piece;
}

double hermite_value(Hermite *curve, double x) {
    const HermitePiece *p = piece_at(curve, x);
    double t = x - p->x0;
    return p->y0 + t * (p->d0 + t * (p->c2 + t * p->c3));
}

double hermite_slope(Hermite *curve, double x) {
    const HermitePiece *p = piece_at(curve, x);
    double t = x - p->x0;
    return p->d0 + t * (2.0 * p->c2 + 3.0 * t * p->c3);
}

int hermite_problem(const double *xs, const double *ys, size_t size, char *message,
                    size_t message_size) {
    if (size < 3) {
        snprintf(message, message_size, "table needs at least 3 points, got %u",
                 (unsigned)size);
        return 1;
    }
    for (size_t i = 0; i < size; i++) {
        if (!(isfinite(xs[i]) && isfinite(ys[i]))) {
            char x[32], y[32];
            snprintf(message, message_size, "table point %u is not finite: (%s, %s)",
                     (unsigned)(i + 1), format_repr(xs[i], x), format_repr(ys[i], y));
            return 1;
        }
    }
    for (size_t i = 1; i < size; i++) {
        if (!(xs[i] > xs[i - 1])) {
            snprintf(message, message_size,
                     "table abscissae must increase strictly: point %u (%.6g) does not "
                     "exceed point %u (%.6g)", (unsigned)(i + 1), xs[i], (unsigned)i, xs[i - 1]);
            return 1;
        }
        if (ys[i] < ys[i - 1]) {
            snprintf(message, message_size,
                     "table ordinates must not decrease: point %u (%.6g) is below point "
                     "%u (%.6g)", (unsigned)(i + 1), ys[i], (unsigned)i, ys[i - 1]);
            return 1;
        }
    }
    return 0;
}
