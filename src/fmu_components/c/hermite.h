/*
 * The monotone piecewise-cubic Hermite curve of runtime/hermite.py (Fritsch-Carlson, the
 * slopes of scipy's PchipInterpolator), built and looked up with the same arithmetic in
 * the same order, so that both flavours give the same bits. Beyond the table the curve
 * continues as a straight line with its end slope.
 */
#ifndef HERMITE_H
#define HERMITE_H

#include "arithmetic.h"

#include <stddef.h>

#include "model_config.h"

#define HERMITE_POINTS (MODEL_TABLE_POINTS > 3 ? MODEL_TABLE_POINTS : 3)

/* y0 + d0 t + c2 t^2 + c3 t^3 with t = x - x0, valid for lower <= x < upper. */
typedef struct {
    double lower, upper, x0, y0, d0, c2, c3;
} HermitePiece;

typedef struct {
    size_t size;                              /* points */
    double xs[HERMITE_POINTS];
    HermitePiece pieces[HERMITE_POINTS + 1];  /* size - 1 pieces, then below, then above */
    size_t last;                              /* where the last lookup landed */
} Hermite;

/* Build the curve through (xs, ys): the caller has checked them (hermite_problem). */
void hermite_build(Hermite *curve, const double *xs, const double *ys, size_t size);
double hermite_value(Hermite *curve, double x);
double hermite_slope(Hermite *curve, double x);

/* 1 with a message when (xs, ys) cannot define a monotone curve, as
   check_monotone_table. */
int hermite_problem(const double *xs, const double *ys, size_t size, char *message,
                    size_t message_size);

#endif
