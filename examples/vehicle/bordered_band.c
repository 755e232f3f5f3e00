/*
 * The bordered band LU (bordered_band.h). In the caller's order the matrix is
 *     [A B]   A: nb x nb, band of half bandwidth w (no pivoting: mass plus stiffness)
 *     [C E]   B, C, E dense (the border: multipliers, bodies coupled to many)
 * factorized as A = L U (in place in the band), Y = A^-1 B (in place of B), and the
 * Schur complement S = E - C Y by LU with partial pivoting (in place of E). A solve:
 * y = A^-1 r1; x2 = S^-1 (r2 - C y); x1 = y - Y x2.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bordered_band.h"

/* the loops over a row's columns vectorized (-O2's very cheap cost model leaves loops of a
   run-time count scalar); elementwise, so the same numbers */
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC optimize("vect-cost-model=dynamic")
#endif

#define BAND(m, i, j) ((m)->band[(size_t)(i) * (2 * (m)->w + 1) + (j) - (i) + (m)->w])

EXPORT void bb_free(bb_matrix *m)
{
    if (!m) return;
    free(m->order); free(m->position); free(m->band); free(m->upper); free(m->lower);
    free(m->corner); free(m->pivot); free(m->scale); free(m->work);
    free(m->first); free(m->by_first); free(m->lower_count); free(m->lower_index);
    free(m->places); free(m->last);
    free(m);
}

EXPORT bb_matrix *bb_create(int n, const int *order, int nb, int w)
{
    if (n < 1 || nb < 0 || nb > n || w < 0) return NULL;
    bb_matrix *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    int nd = n - nb;
    m->n = n; m->nb = nb; m->nd = nd; m->w = w;
    m->pivot_tolerance = 1e-12;
    m->order = malloc(sizeof(int) * n);
    m->position = malloc(sizeof(int) * n);
    m->band = malloc(sizeof(double) * ((size_t)nb * (2 * w + 1) + 1));
    m->upper = malloc(sizeof(double) * ((size_t)nb * nd + 1));
    m->lower = malloc(sizeof(double) * ((size_t)nb * nd + 1));
    m->corner = malloc(sizeof(double) * ((size_t)nd * nd + 1));
    m->pivot = malloc(sizeof(int) * (nd + 1));
    m->scale = malloc(sizeof(double) * (nb + 1));
    m->work = malloc(sizeof(double) * n);
    m->first = malloc(sizeof(int) * (nd + 1));
    m->by_first = malloc(sizeof(int) * (nd + 1));
    m->lower_count = calloc(nd + 1, sizeof(int));
    m->lower_index = malloc(sizeof(int) * ((size_t)nb * nd + 1));
    if (!m->order || !m->position || !m->band || !m->upper || !m->lower || !m->corner
        || !m->pivot || !m->scale || !m->work || !m->first || !m->by_first
        || !m->lower_count || !m->lower_index) {
        bb_free(m);
        return NULL;
    }
    for (int i = 0; i < n; i++) m->position[i] = -1;
    for (int p = 0; p < n; p++) {
        int u = order[p];
        if (u < 0 || u >= n || m->position[u] >= 0) {  /* not a permutation */
            bb_free(m);
            return NULL;
        }
        m->order[p] = u;
        m->position[u] = p;
    }
    bb_zero(m);
    return m;
}

EXPORT void bb_zero(bb_matrix *m)
{
    memset(m->band, 0, sizeof(double) * (size_t)m->nb * (2 * m->w + 1));
    memset(m->upper, 0, sizeof(double) * (size_t)m->nb * m->nd);
    if (m->lower_listed) {  /* only the entries the last factorization found not zero */
        for (int r = 0; r < m->nd; r++) {
            double *c = m->lower + (size_t)r * m->nb;
            const int *index = m->lower_index + (size_t)r * m->nb;
            for (int k = 0; k < m->lower_count[r]; k++) c[index[k]] = 0.0;
        }
    } else {
        memset(m->lower, 0, sizeof(double) * (size_t)m->nb * m->nd);
    }
    memset(m->corner, 0, sizeof(double) * (size_t)m->nd * m->nd);
    struct bb_place *places = m->places;  /* this assembly's places the last one's */
    int capacity = m->places_capacity;
    m->places = m->last; m->places_capacity = m->last_capacity;
    m->last = places; m->last_capacity = capacity;
    m->last_count = m->added;
    m->added = m->shift = m->not_found = 0;
}

/* Where (row, col), both unknowns, is added (lower: 1 if in `lower`); NULL where the
   pattern has no place */
static double *place_of(const bb_matrix *m, int row, int col, int *lower)
{
    *lower = 0;
    if (row < 0 || row >= m->n || col < 0 || col >= m->n) return NULL;
    int i = m->position[row], j = m->position[col], nb = m->nb, nd = m->nd;
    if (i < nb && j < nb) return abs(i - j) > m->w ? NULL : &BAND(m, i, j);
    if (i < nb) return m->upper + (size_t)i * nd + (j - nb);
    if (j < nb) {
        *lower = 1;
        return m->lower + (size_t)(i - nb) * nb + j;
    }
    return m->corner + (size_t)(i - nb) * nd + (j - nb);
}

/* the last assembly's place of (row, col) near its rank `added` plus `shift` (the ranks
   on by the entries in or out before), or, after a place found or every BB_FAR_EVERY
   entries not found, further off (a block of entries in or out); `shift` moved to the
   one found, or one less (an entry in) where there is none, then the place found. Kept
   as this assembly's where there is room (more, twice as much, as needed). */
#define BB_NEAR 8
#define BB_FAR 512
#define BB_FAR_EVERY 16
static struct bb_place new_place(bb_matrix *m, int row, int col)
{
    struct bb_place p = {row, col, 0, NULL};
    const struct bb_place *last = m->last;
    int j = m->added + m->shift, found = -1;
    int reach = m->not_found % BB_FAR_EVERY == 0 ? BB_FAR : BB_NEAR;
    for (int d = 0; d <= 2 * reach && found < 0; d++) {  /* j, j - 1, j + 1, j - 2, ... */
        int i = j + (d % 2 ? -(d + 1) / 2 : d / 2);
        if (i >= 0 && i < m->last_count && last[i].row == row && last[i].col == col
            && last[i].at != NULL)
            found = i;
    }
    if (found >= 0) {
        p = last[found];
        m->shift = found - m->added;
        m->not_found = 0;
    } else {
        p.at = place_of(m, row, col, &p.lower);
        m->shift--;
        m->not_found++;
    }
    int k = m->added;
    if (k >= m->places_capacity) {
        int capacity = 2 * k > 1024 ? 2 * k : 1024;
        struct bb_place *more = realloc(m->places, sizeof *more * (size_t)capacity);
        if (!more) return p;  /* no room: found each time */
        m->places = more;
        m->places_capacity = capacity;
    }
    m->places[k] = p;
    m->added++;
    return p;
}

/* Add `value` at (row, col), both unknowns, where the last assembly's entry of the same
   rank (plus shift) had another (row, col) or none; BB_OUTSIDE where the pattern has no
   place. */
static int add_new(bb_matrix *m, int row, int col, double value)
{
    struct bb_place p = new_place(m, row, col);
    if (p.at == NULL) {
        m->bad_row = row; m->bad_col = col;
        return BB_OUTSIDE;
    }
    *p.at += value;
    if (p.lower) m->lower_listed = 0;
    return BB_OK;
}

EXPORT int bb_add(bb_matrix *m, int row, int col, double value)
{
    return bb_add_many(m, 1, &row, &col, &value, 1.0);
}

/* value[k] times factor at (row[k], col[k]): the places of the last assembly's entries of
   the same rank (plus shift) where their (row, col) is the same (the band or border told
   once), kept as this assembly's */
EXPORT int bb_add_many(bb_matrix *m, int count, const int *row, const int *col,
                       const double *value, double factor)
{
    int k = 0, lower = 0;
    while (k < count) {
        int a = m->added, j = a + m->shift;
        int same = count - k;  /* as far as both sequences and the room go */
        if (m->last_count - j < same) same = m->last_count - j;
        if (m->places_capacity - a < same) same = m->places_capacity - a;
        if (j >= 0 && same > 0) {
            const struct bb_place *p = m->last + j;
            struct bb_place *q = m->places + a;
            for (; same > 0 && p->row == row[k] && p->col == col[k] && p->at != NULL; same--) {
                *p->at += factor * value[k];
                lower |= p->lower;
                *q++ = *p++;
                k++;
            }
            m->added = (int)(q - m->places);
        }
        if (k < count) {
            int status = add_new(m, row[k], col[k], factor * value[k]);
            if (status != BB_OK) {
                if (lower) m->lower_listed = 0;
                return status;
            }
            k++;
        }
    }
    if (lower) m->lower_listed = 0;
    return BB_OK;
}

/* y <- L^-1 y in rows from .. to - 1 (the rows before done) for the right-hand sides
   (columns) lo .. hi - 1, row i's at y + i * stride */
static void band_forward(const bb_matrix *m, double *y, int from, int to, int lo, int hi,
                         int stride)
{
    int w = m->w;
    for (int i = from; i < to; i++) {
        double *yi = y + (size_t)i * stride;
        int k0 = i - w > 0 ? i - w : 0;
        for (int k = k0; k < i; k++) {
            double l = BAND(m, i, k);
            if (l == 0.0) continue;
            const double *yk = y + (size_t)k * stride;
            for (int c = lo; c < hi; c++) yi[c] -= l * yk[c];
        }
    }
}

/* y <- U^-1 y for `columns` right-hand sides, row i's at y + i * stride */
static void band_backward(const bb_matrix *m, double *y, int columns, int stride)
{
    int nb = m->nb, w = m->w;
    for (int i = nb - 1; i >= 0; i--) {
        double *yi = y + (size_t)i * stride;
        int j1 = i + w < nb - 1 ? i + w : nb - 1;
        for (int j = i + 1; j <= j1; j++) {
            double u = BAND(m, i, j);
            if (u == 0.0) continue;
            const double *yj = y + (size_t)j * stride;
            for (int c = 0; c < columns; c++) yi[c] -= u * yj[c];
        }
        double d = 1.0 / BAND(m, i, i);  /* a product: a division each is slow */
        for (int c = 0; c < columns; c++) yi[c] *= d;
    }
}

/* Y = A^-1 B for B's first `coupled` columns (in place of upper), each column's first
   row not zero in `first`: the forward pass run
   from the row where the first column becomes not zero, over the columns not zero by then
   (a border body touches few band rows: the rows above them stay zero), then the
   backward pass over all */
static void y_solve(bb_matrix *m)
{
    int nb = m->nb, nd = m->nd, coupled = m->coupled, count = 0;
    for (int k = 0; k < coupled; k++) {
        int i = m->first[k];
        int p = count++;  /* insertion by first row */
        while (p > 0 && m->first[m->by_first[p - 1]] > i) {
            m->by_first[p] = m->by_first[p - 1];
            p--;
        }
        m->by_first[p] = k;
    }
    int lo = coupled, hi = 0;
    for (int p = 0; p < count; p++) {
        int k = m->by_first[p], from = m->first[k];
        if (from >= nb) break;
        if (k < lo) lo = k;
        if (k + 1 > hi) hi = k + 1;
        int to = p + 1 < count ? m->first[m->by_first[p + 1]] : nb;
        if (to > from)  /* rows from .. to - 1 over the columns started by then */
            band_forward(m, m->upper, from, to, lo, hi, nd);
    }
    band_backward(m, m->upper, coupled, nd);
}

EXPORT int bb_factorize(bb_matrix *m)
{
    int nb = m->nb, nd = m->nd, w = m->w;
    /* the band: each row's scale first, then Doolittle without pivoting */
    for (int i = 0; i < nb; i++) {
        double s = 0.0;
        for (int j = (i - w > 0 ? i - w : 0); j <= (i + w < nb - 1 ? i + w : nb - 1); j++) {
            double a = fabs(BAND(m, i, j));
            if (a > s) s = a;
        }
        m->scale[i] = s;
    }
    for (int k = 0; k < nb; k++) {
        double p = BAND(m, k, k);
        if (!(p > m->pivot_tolerance * m->scale[k])) {   /* also catches NaN */
            m->bad_row = m->bad_col = m->order[k];
            return BB_PIVOT;
        }
        int i1 = k + w < nb - 1 ? k + w : nb - 1;
        for (int i = k + 1; i <= i1; i++) {
            double l = BAND(m, i, k);
            if (l == 0.0) continue;
            l /= p;
            BAND(m, i, k) = l;
            for (int j = k + 1; j <= i1; j++) BAND(m, i, j) -= l * BAND(m, k, j);
        }
    }
    if (nd == 0) return BB_OK;
    /* Y = A^-1 B for the border's columns up to the last that touches the band (the
       multipliers, last in the order, touch only the border: their columns of Y are
       zero); S = E - C Y, skipping C's zeros (a border row touches few band rows) */
    int coupled = 0, *first = m->first;
    for (int k = 0; k < nd; k++) first[k] = nb;
    for (int i = 0; i < nb; i++) {  /* row by row, as stored */
        const double *b = m->upper + (size_t)i * nd;
        for (int k = 0; k < nd; k++)
            if (b[k] != 0.0 && first[k] == nb) first[k] = i;
    }
    for (int k = 0; k < nd; k++)
        if (first[k] < nb) coupled = k + 1;
    m->coupled = coupled;
    y_solve(m);
    for (int r = 0; r < nd; r++) {  /* C's entries not zero, listed for bb_solve, bb_zero */
        const double *c = m->lower + (size_t)r * nb;
        int *index = m->lower_index + (size_t)r * nb, count = 0;
        for (int j = 0; j < nb; j++) {  /* without a branch: most are zero */
            index[count] = j;
            count += c[j] != 0.0;
        }
        m->lower_count[r] = count;
    }
    m->lower_listed = 1;
    for (int r = 0; r < nd; r++) {
        double *s = m->corner + (size_t)r * nd;
        const double *c = m->lower + (size_t)r * nb;
        const int *index = m->lower_index + (size_t)r * nb;
        for (int q = 0; q < m->lower_count[r]; q++) {
            int j = index[q];
            const double *y = m->upper + (size_t)j * nd;
            for (int k = 0; k < coupled; k++) s[k] -= c[j] * y[k];
        }
    }
    /* S = P L U, partial pivoting */
    double *S = m->corner;
    for (int k = 0; k < nd; k++) {
        int p = k;
        double big = fabs(S[(size_t)k * nd + k]);
        for (int i = k + 1; i < nd; i++) {
            double a = fabs(S[(size_t)i * nd + k]);
            if (a > big) { big = a; p = i; }
        }
        m->pivot[k] = p;
        if (!(big > 0.0) || !isfinite(big)) {
            m->bad_row = m->bad_col = m->order[nb + k];
            return BB_SINGULAR;
        }
        if (p != k) {
            for (int j = 0; j < nd; j++) {
                double t = S[(size_t)k * nd + j];
                S[(size_t)k * nd + j] = S[(size_t)p * nd + j];
                S[(size_t)p * nd + j] = t;
            }
        }
        double d = S[(size_t)k * nd + k];
        for (int i = k + 1; i < nd; i++) {
            double l = S[(size_t)i * nd + k] / d;
            S[(size_t)i * nd + k] = l;
            if (l == 0.0) continue;
            for (int j = k + 1; j < nd; j++) S[(size_t)i * nd + j] -= l * S[(size_t)k * nd + j];
        }
    }
    return BB_OK;
}

/* x = M^-1 rhs, both indexed by unknowns (x may be rhs). */
EXPORT void bb_solve(bb_matrix *m, const double *rhs, double *x)
{
    int nb = m->nb, nd = m->nd;
    double *y = m->work, *z = m->work + nb;
    for (int p = 0; p < m->n; p++) y[p] = rhs[m->order[p]];
    band_forward(m, y, 0, nb, 0, 1, 1);
    band_backward(m, y, 1, 1);
    if (nd > 0) {
        for (int r = 0; r < nd; r++) {
            const double *c = m->lower + (size_t)r * nb;
            const int *index = m->lower_index + (size_t)r * nb;
            double s = z[r];
            for (int q = 0; q < m->lower_count[r]; q++) s -= c[index[q]] * y[index[q]];
            z[r] = s;
        }
        const double *S = m->corner;
        for (int k = 0; k < nd; k++)  /* the row swaps first: L's rows carry all of them */
            if (m->pivot[k] != k) { double t = z[k]; z[k] = z[m->pivot[k]]; z[m->pivot[k]] = t; }
        for (int k = 0; k < nd; k++)
            for (int i = k + 1; i < nd; i++) z[i] -= S[(size_t)i * nd + k] * z[k];
        for (int i = nd - 1; i >= 0; i--) {
            double s = z[i];
            for (int j = i + 1; j < nd; j++) s -= S[(size_t)i * nd + j] * z[j];
            z[i] = s / S[(size_t)i * nd + i];
        }
        for (int i = 0; i < nb; i++) {
            const double *u = m->upper + (size_t)i * nd;
            double s = y[i];
            for (int k = 0; k < m->coupled; k++) s -= u[k] * z[k];
            y[i] = s;
        }
    }
    for (int p = 0; p < m->n; p++) x[m->order[p]] = y[p];
}

/* the unknowns (row, col) the last error named */
EXPORT void bb_bad(const bb_matrix *m, int *rows)
{
    rows[0] = m->bad_row;
    rows[1] = m->bad_col;
}
