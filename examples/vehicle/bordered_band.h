/*
 * A bordered band matrix with a fixed pattern, and its LU (bordered_band.c): the unknowns
 * taken in a given order, the first `nb` of that order in a band of half bandwidth `w`
 * (factorized without pivoting), the other `nd` in a dense border (the band's rows and
 * columns to the border dense, the border's corner by its Schur complement with partial
 * pivoting). All storage allocated at creation.
 */
#ifndef BORDERED_BAND_H
#define BORDERED_BAND_H

#if defined(_WIN32)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT __attribute__((visibility("default")))
#endif

#define BB_OK 0
#define BB_OUTSIDE 1    /* an entry outside the band and the border: bad_row, bad_col */
#define BB_PIVOT 2      /* a band pivot not positive (relative to its row): bad_row */
#define BB_SINGULAR 3   /* the border's Schur complement singular: bad_row */
#define BB_MEMORY 4

/* an entry's (row, col) and where it is added: lower tells it is in `lower` */
struct bb_place {
    int row, col, lower;
    double *at;
};

typedef struct {
    int n, nb, nd, w;     /* unknowns, in the band, in the border, half bandwidth */
    int *order;           /* position -> unknown */
    int *position;        /* unknown -> position */
    double *band;         /* nb rows of 2w+1: (i, j) at band[i*(2w+1) + j - i + w] */
    double *upper;        /* nb x nd row-major: the band rows' border columns, then A^-1 B */
    double *lower;        /* nd x nb row-major: the border rows' band columns */
    double *corner;       /* nd x nd row-major: the border's corner, then its Schur LU */
    int *pivot;           /* nd: the Schur complement's row swaps */
    double *scale;        /* nb: each band row's largest magnitude (the pivot test) */
    double *work;         /* n */
    int coupled;          /* the border's columns up to the last touching the band */
    int *first;           /* nd: each border column's first band row not zero */
    int *by_first;        /* nd: the coupled border columns by their first band row */
    int *lower_count;     /* nd: each border row's band columns not zero */
    int *lower_index;     /* nd x nb: those columns, row by row */
    int lower_listed;     /* lower's entries not zero all in lower_index (bb_zero's hint) */
    /* the places of the entries added since bb_zero, in the order added, and the last
       assembly's (an assembly repeats the last one's sequence of (row, col), but for a
       few entries in or out: a place found once is reused, `shift` ranks on; not_found:
       the entries since the last one found there) */
    struct bb_place *places, *last;
    int places_capacity, last_capacity, added, last_count, shift, not_found;
    double pivot_tolerance;
    int bad_row, bad_col; /* unknowns (not positions) named by the last error */
} bb_matrix;

EXPORT bb_matrix *bb_create(int n, const int *order, int nb, int w);
EXPORT void bb_free(bb_matrix *m);
EXPORT void bb_zero(bb_matrix *m);
EXPORT int bb_add(bb_matrix *m, int row, int col, double value);
EXPORT int bb_add_many(bb_matrix *m, int count, const int *row, const int *col,
                       const double *value, double factor);
EXPORT int bb_factorize(bb_matrix *m);
EXPORT void bb_solve(bb_matrix *m, const double *rhs, double *x);
EXPORT void bb_bad(const bb_matrix *m, int *rows);

#endif
