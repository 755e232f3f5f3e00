/*
 * One step of exudyn's generalized-alpha method (alpha_solver.c) for
 *     M a = f(t, q, v) - G(q)^T lambda,   g(q) = 0   (index 3),
 * M constant diagonal, with the host's system given as two callbacks.
 */
#ifndef ALPHA_SOLVER_H
#define ALPHA_SOLVER_H

#include "bordered_band.h"

/* Sparse triplets; repeated (row, col) add. The callee sets count (<= capacity). */
typedef struct {
    int capacity, count;
    int *row, *col;
    double *value;
} alpha_triplets;

/* f (nq) and g (nm) at (t, q, v), and G = dg/dq at q as triplets (row: constraint,
   col: coordinate). 0 on success. */
typedef int (*alpha_evaluate_fn)(void *context, double t, const double *q, const double *v,
                                 double *f, double *g, alpha_triplets *G);
/* K = -df/dq and D = -df/dv at (t, q, v) as triplets. 0 on success. */
typedef int (*alpha_jacobian_fn)(void *context, double t, const double *q, const double *v,
                                 alpha_triplets *K, alpha_triplets *D);

/* exudyn's timeIntegration.generalizedAlpha and .newton settings of the same names */
typedef struct {
    double spectral_radius;
    double relative_tolerance, absolute_tolerance;
    double maximum_solution_norm, modified_newton_contractivity;
    double pivot_tolerance;          /* the band's pivot test, relative to its row */
    int max_iterations;
    int use_modified_newton, max_modified_newton_iterations;
    int max_modified_newton_restart_iterations;
    int adapt_initial_residual;
    /* the reuse policy (not exudyn's; off: 0): the last factorization kept across Newton
       iterations and the passes of a step (1), and across steps of the same h too (2);
       a new one at the current iterate when an iteration's residual contracted by a
       ratio worse than reuse_contractivity */
    int reuse_jacobian;
    double reuse_contractivity;
    int reuse_broyden;   /* the kept matrix's steps corrected by Broyden's rank-one updates */
    /* a step's first solve (alpha_step) to this absolute tolerance instead (0: absolute_tolerance):
       for a coupled host that always solves the step again with new loads (alpha_repeat) */
    double first_pass_tolerance;
    /* the reuse policy: where an iteration past the first on a new matrix grew the
       residual norm, its update halved up to this many times while it still grows (0: off) */
    int reuse_damping;
} alpha_settings;

#define ALPHA_TRACE 64          /* iterations of a solve traced (alpha_trace) */

/* statuses */
#define ALPHA_CONVERGED 0
#define ALPHA_NOT_CONVERGED 1   /* the caller halves the step; the state is the step's start */
#define ALPHA_PIVOT 2           /* a band pivot not positive: bad_row */
#define ALPHA_OUTSIDE 3         /* a Jacobian entry outside the pattern: bad_row, bad_col */
#define ALPHA_SINGULAR 4        /* the border's Schur complement singular */
#define ALPHA_CALLBACK 5        /* a callback returned an error or too many triplets */

typedef struct {
    int nq, nm, n;
    alpha_settings set;
    double alpha_m, alpha_f, beta, gamma;
    double *mass;
    alpha_evaluate_fn evaluate;
    alpha_jacobian_fn jacobian;
    void *context;
    bb_matrix *matrix;
    alpha_triplets K, D, G;
    double t, *q, *v, *a, *a_alg, *lambda;   /* the state (a_alg: algorithmic accelerations) */
    double t0, *q0, *v0, *a0, *a_alg0, *lambda0; /* the step's start */
    double *q1, *v1, *a1, *lambda1;          /* a pass's solution, a warm repeat's start */
    double *f, *g, *residual, *delta;
    double *steps;      /* Broyden's: the steps since the matrix was made, (max_iterations) n */
    int n_steps, max_steps;
    int jacobian_update_requested;
    double factorized_h;
    double jacobian_h;  /* the step whose Newton matrix the jacobian callback is asked for */
    /* the last step's report */
    int iterations, jacobians, total_jacobians, bad_row, bad_col;
    double residual_norm, initial_residual;
    /* the last solve's iterations, up to ALPHA_TRACE: each one's residual norm after its
       update, and whether it made a new Newton matrix (2: after a restart from the
       pass's start) */
    double trace_norm[ALPHA_TRACE];
    int trace_factorized[ALPHA_TRACE];
} alpha_solver;

EXPORT alpha_solver *alpha_create(int nq, int nm, const double *mass, const int *order, int nb,
                                  int w, int capacity, const alpha_settings *settings,
                                  alpha_evaluate_fn evaluate, alpha_jacobian_fn jacobian,
                                  void *context);
EXPORT void alpha_free(alpha_solver *s);
EXPORT int alpha_initialize(alpha_solver *s, double t, const double *q, const double *v,
                            int compute_initial_accelerations);
EXPORT int alpha_step(alpha_solver *s, double h, double t_new);
EXPORT void alpha_restart(alpha_solver *s);
EXPORT int alpha_repeat(alpha_solver *s, double h, double t_new, int warm);
EXPORT void alpha_report(const alpha_solver *s, int *ints, double *reals);
EXPORT int alpha_configure(alpha_solver *s, const alpha_settings *settings);
EXPORT void alpha_coefficients(const alpha_solver *s, double *out);
EXPORT int alpha_trace(const alpha_solver *s, double *norms, int *factorized);
EXPORT void alpha_state(const alpha_solver *s, double *q, double *v, double *a,
                        double *lambda);

#endif
