/*
 * exudyn's generalized-alpha step (exudyn's CSolverImplicitSecondOrderTimeInt and
 * CSolverBase::Newton; Arnold and Bruls 2007, Algorithm 1) for
 *     M a = f(t, q, v) - G(q)^T lambda,   g(q) = 0   (index 3), M constant diagonal:
 *   alpha_m = (2 rho - 1) / (rho + 1), alpha_f = rho / (rho + 1),
 *   gamma = 1/2 + alpha_f - alpha_m, beta = (gamma + 1/2)^2 / 4;
 *   predictor: q += h v + h^2 (1/2 - beta) a_alg; v += h (1 - gamma) a_alg;
 *              a_alg = (alpha_f a - alpha_m a_alg) / (1 - alpha_m);
 *              q += h^2 beta a_alg; v += h gamma a_alg; a = 0; lambda = 0;
 *   Newton on the residual r = [M a - f + G^T lambda; g], its norm taken unscaled, its
 *   coordinate rows then scaled by beta h^2 (the Newton matrix
 *   [beta h^2 (beta' M + K + gamma' D), G^T; G, 0], beta' = (1 - alpha_m) /
 *   (h^2 beta (1 - alpha_f)), gamma' = gamma / (h beta)); the update
 *   q -= dq, v -= gamma' dq, a -= beta' dq, lambda -= dlambda / (beta h^2);
 *   after convergence a_alg += (1 - alpha_f) / (1 - alpha_m) a.
 * Convergence, modified Newton, its restarts and the switch to full Newton as exudyn's
 * Newton; modified Newton keeps its Jacobian from step to step as exudyn's does, except
 * that a step of another h (or after a failed step) starts with a new one. The Newton
 * matrix is a bordered band (bordered_band.c).
 * The reuse policy (reuse_jacobian, not exudyn's): the last factorization kept across
 * iterations, the passes of a step (1) and its steps of the same h (2); a new one at the
 * present iterate (no restart) after an iteration whose residual norm contracted by a
 * ratio worse than reuse_contractivity, or too slowly for the iterations left; an
 * iterate whose residual grew on a kept matrix undone and a new matrix made at the one
 * before; past a solve's first iteration, an update on a new matrix that grew it halved
 * up to reuse_damping times while it still grows (a kink in the forces between the
 * iterates: Newton would cycle across it); an iterate beyond maximum_solution_norm
 * or not a number: the pass again from its start with a new matrix, or, where the
 * iteration's matrix was new, the step not converged. A step of another h, a restart or
 * a failed step start with a new one. Convergence is tested as exudyn's.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "alpha_solver.h"

static int triplets_init(alpha_triplets *t, int capacity)
{
    t->capacity = capacity;
    t->count = 0;
    t->row = malloc(sizeof(int) * (capacity + 1));
    t->col = malloc(sizeof(int) * (capacity + 1));
    t->value = malloc(sizeof(double) * (capacity + 1));
    return t->row && t->col && t->value;
}

static void triplets_free(alpha_triplets *t)
{
    free(t->row); free(t->col); free(t->value);
}

EXPORT void alpha_free(alpha_solver *s)
{
    if (!s) return;
    bb_free(s->matrix);
    triplets_free(&s->K); triplets_free(&s->D); triplets_free(&s->G);
    double *arrays[] = {s->mass, s->q, s->v, s->a, s->a_alg, s->lambda, s->q0, s->v0, s->a0,
                        s->a_alg0, s->lambda0, s->f, s->g, s->residual, s->delta, s->q1, s->v1,
                        s->a1, s->lambda1, s->steps};
    for (size_t i = 0; i < sizeof arrays / sizeof *arrays; i++) free(arrays[i]);
    free(s);
}

EXPORT alpha_solver *alpha_create(int nq, int nm, const double *mass, const int *order, int nb,
                                  int w, int capacity, const alpha_settings *settings,
                                  alpha_evaluate_fn evaluate, alpha_jacobian_fn jacobian,
                                  void *context)
{
    alpha_solver *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->nq = nq; s->nm = nm; s->n = nq + nm;
    s->set = *settings;
    s->evaluate = evaluate; s->jacobian = jacobian; s->context = context;
    double rho = settings->spectral_radius;
    s->alpha_m = (2 * rho - 1) / (rho + 1);
    s->alpha_f = rho / (rho + 1);
    s->gamma = 0.5 + s->alpha_f - s->alpha_m;
    s->beta = 0.25 * (s->gamma + 0.5) * (s->gamma + 0.5);
    s->matrix = bb_create(s->n, order, nb, w);
    int ok = s->matrix != NULL && triplets_init(&s->K, capacity)
             && triplets_init(&s->D, capacity) && triplets_init(&s->G, capacity);
    double **coordinates[] = {&s->mass, &s->q, &s->v, &s->a, &s->a_alg, &s->q0, &s->v0,
                              &s->a0, &s->a_alg0, &s->f, &s->q1, &s->v1, &s->a1};
    for (size_t i = 0; ok && i < sizeof coordinates / sizeof *coordinates; i++)
        ok = (*coordinates[i] = calloc(nq + 1, sizeof(double))) != NULL;
    double **multipliers[] = {&s->lambda, &s->lambda0, &s->g, &s->lambda1};
    for (size_t i = 0; ok && i < sizeof multipliers / sizeof *multipliers; i++)
        ok = (*multipliers[i] = calloc(nm + 1, sizeof(double))) != NULL;
    ok = ok && (s->residual = calloc(s->n, sizeof(double))) != NULL
         && (s->delta = calloc(s->n, sizeof(double))) != NULL
         && (s->steps = calloc((size_t)s->n * (settings->max_iterations + 1),
                               sizeof(double))) != NULL;
    if (!ok) { alpha_free(s); return NULL; }
    memcpy(s->mass, mass, sizeof(double) * nq);
    s->matrix->pivot_tolerance = settings->pivot_tolerance;
    s->jacobian_update_requested = 1;
    s->max_steps = settings->max_iterations + 1;
    return s;
}

/* Other settings from the next step on (the spectral radius and the pivot tolerance kept;
   max_iterations at most the first's); the Newton matrix kept. 1 if refused. */
EXPORT int alpha_configure(alpha_solver *s, const alpha_settings *settings)
{
    if (settings->max_iterations + 1 > s->max_steps) return 1;
    double rho = s->set.spectral_radius, pivot = s->set.pivot_tolerance;
    s->set = *settings;
    s->set.spectral_radius = rho;
    s->set.pivot_tolerance = pivot;
    return 0;
}

/* alpha_m, alpha_f, beta, gamma */
EXPORT void alpha_coefficients(const alpha_solver *s, double *out)
{
    out[0] = s->alpha_m; out[1] = s->alpha_f; out[2] = s->beta; out[3] = s->gamma;
}

static int from_matrix(alpha_solver *s, int status)
{
    s->bad_row = s->matrix->bad_row;
    s->bad_col = s->matrix->bad_col;
    return status == BB_OUTSIDE ? ALPHA_OUTSIDE
           : status == BB_PIVOT ? ALPHA_PIVOT : ALPHA_SINGULAR;
}

static int evaluate(alpha_solver *s, double t, const double *q, const double *v)
{
    s->G.count = 0;
    if (s->evaluate(s->context, t, q, v, s->f, s->g, &s->G) != 0 || s->G.count > s->G.capacity)
        return ALPHA_CALLBACK;
    return ALPHA_CONVERGED;
}

/* exudyn's ComputeNewtonResidual: r = [M a - f + G^T lambda; g]; its L2 norm, before the
   coordinate rows are scaled by `scale` */
static int residual(alpha_solver *s, double t, double scale, double *norm)
{
    int status = evaluate(s, t, s->q, s->v);
    if (status) return status;
    double *r = s->residual;
    for (int i = 0; i < s->nq; i++) r[i] = s->mass[i] * s->a[i] - s->f[i];
    const alpha_triplets *G = &s->G;
    for (int k = 0; k < G->count; k++) r[G->col[k]] += G->value[k] * s->lambda[G->row[k]];
    for (int j = 0; j < s->nm; j++) r[s->nq + j] = s->g[j];
    double sum = 0.0;
    for (int i = 0; i < s->n; i++) sum += r[i] * r[i];
    *norm = sqrt(sum);
    for (int i = 0; i < s->nq; i++) r[i] *= scale;
    return ALPHA_CONVERGED;
}

/* G and G^T into the matrix at the multipliers' rows and columns */
static int add_constraints(alpha_solver *s)
{
    const alpha_triplets *G = &s->G;
    for (int k = 0; k < G->count; k++) {
        int status = bb_add(s->matrix, s->nq + G->row[k], G->col[k], G->value[k]);
        if (!status) status = bb_add(s->matrix, G->col[k], s->nq + G->row[k], G->value[k]);
        if (status) return from_matrix(s, status);
    }
    return ALPHA_CONVERGED;
}

/* exudyn's ComputeNewtonJacobian, factorized */
static int newton_matrix(alpha_solver *s, double t, double h)
{
    double scale = s->beta * h * h;
    double beta_prime = (1 - s->alpha_m) / (h * h * s->beta * (1 - s->alpha_f));
    double gamma_prime = s->gamma / (h * s->beta);
    s->K.count = s->D.count = 0;
    s->jacobian_h = h;
    if (s->jacobian(s->context, t, s->q, s->v, &s->K, &s->D) != 0
        || s->K.count > s->K.capacity || s->D.count > s->D.capacity)
        return ALPHA_CALLBACK;
    bb_matrix *m = s->matrix;
    bb_zero(m);
    int status = BB_OK;
    for (int i = 0; i < s->nq && !status; i++)
        status = bb_add(m, i, i, s->mass[i] * (beta_prime * scale));
    if (!status)
        status = bb_add_many(m, s->K.count, s->K.row, s->K.col, s->K.value, scale);
    if (!status)
        status = bb_add_many(m, s->D.count, s->D.row, s->D.col, s->D.value, gamma_prime * scale);
    if (status) return from_matrix(s, status);
    if ((status = add_constraints(s))) return status;
    if ((status = bb_factorize(m))) return from_matrix(s, status);
    s->jacobians++;
    s->total_jacobians++;
    s->factorized_h = h;
    return ALPHA_CONVERGED;
}

/* exudyn's ComputeNewtonUpdate(initial=true): the predictor from the step's start */
static void predict(alpha_solver *s, double h)
{
    int nq = s->nq;
    memcpy(s->q, s->q0, sizeof(double) * nq);
    memcpy(s->v, s->v0, sizeof(double) * nq);
    memcpy(s->a, s->a0, sizeof(double) * nq);
    memcpy(s->a_alg, s->a_alg0, sizeof(double) * nq);
    memset(s->lambda, 0, sizeof(double) * s->nm);
    double am = s->alpha_m, af = s->alpha_f;
    for (int i = 0; i < nq; i++) {
        s->q[i] += h * s->v[i];
        s->q[i] += h * h * (0.5 - s->beta) * s->a_alg[i];
        s->v[i] += h * (1. - s->gamma) * s->a_alg[i];
        s->a_alg[i] *= -am / (1 - am);
        s->a_alg[i] += af / (1 - am) * s->a[i];
        s->q[i] += h * h * s->beta * s->a_alg[i];
        s->v[i] += h * s->gamma * s->a_alg[i];
        s->a[i] = 0.0;
    }
}

/* The state kept as the step's start (keep) or set back to it (!keep). */
static void copy_start(alpha_solver *s, int keep)
{
    double *now[] = {s->q, s->v, s->a, s->a_alg, s->lambda};
    double *start[] = {s->q0, s->v0, s->a0, s->a_alg0, s->lambda0};
    for (int k = 0; k < 5; k++) {
        size_t bytes = sizeof(double) * (size_t)(k < 4 ? s->nq : s->nm);
        if (bytes)
            memcpy(keep ? start[k] : now[k], keep ? now[k] : start[k], bytes);
    }
}

static void restore(alpha_solver *s) { copy_start(s, 0); }

/* One step from the current state to t_new = t + h (the caller's time, as exudyn's
   step index times h); on any status but ALPHA_CONVERGED the state is the step's start. */
static int solve(alpha_solver *s, double h, double t_new, int warm, double tolerance);

EXPORT int alpha_step(alpha_solver *s, double h, double t_new)
{
    copy_start(s, 1);
    if (s->set.reuse_jacobian == 1) s->jacobian_update_requested = 1;
    double first = s->set.first_pass_tolerance;
    return solve(s, h, t_new, 0, first > 0.0 ? first : s->set.absolute_tolerance);
}

/* The state back at the last step's start (its time too): a host's retry of a solved step
   at another h */
EXPORT void alpha_restart(alpha_solver *s)
{
    restore(s);
    s->t = s->t0;
    s->jacobian_update_requested = 1;
}

/* The last step solved again from its start to t_new = t + h (a coupled host's next pass,
   its loads changed); warm: Newton starts from the present solution (q, v, a, lambda)
   instead of the predictor's, the algorithmic accelerations the predictor's (exudyn's
   pre-Newton-residual user function setting the last pass's solution). Its status as
   alpha_step's (on failure the state is the step's start). */
EXPORT int alpha_repeat(alpha_solver *s, double h, double t_new, int warm)
{
    int nq = s->nq;
    if (warm) {
        memcpy(s->q1, s->q, sizeof(double) * nq);
        memcpy(s->v1, s->v, sizeof(double) * nq);
        memcpy(s->a1, s->a, sizeof(double) * nq);
        memcpy(s->lambda1, s->lambda, sizeof(double) * s->nm);
    }
    s->t = s->t0;
    return solve(s, h, t_new, warm, s->set.absolute_tolerance);
}

/* Newton's update q -= dq, v -= gamma' dq, a -= beta' dq, lambda -= dlambda / scale by
   the solution in delta (sign -1), or that update undone (sign 1) */
static void update(alpha_solver *s, double sign, double scale, double beta_prime,
                   double gamma_prime)
{
    const double *dq = s->delta, *dl = s->delta + s->nq;
    for (int i = 0; i < s->nq; i++) {
        s->q[i] += sign * dq[i];
        s->v[i] += sign * gamma_prime * dq[i];
        s->a[i] += sign * beta_prime * dq[i];
    }
    for (int j = 0; j < s->nm; j++) s->lambda[j] += sign * dl[j] / scale;
}

/* Broyden's step (Kelley's brsol, the full step) on the kept matrix: w = A^-1 r from
   delta, corrected by the steps d_0 .. d_{m-1} taken since the matrix was made,
       w += d_{j+1} (d_j . w) / |d_j|^2  (j < m - 1),   d_m = w / (1 - d_{m-1} . w / |d_{m-1}|^2),
   into delta and kept as d_m; 1 where the update is singular (a new matrix wanted) */
static int broyden(alpha_solver *s)
{
    int n = s->n, m = s->n_steps;
    double *w = s->delta;
    for (int j = 0; j + 1 <= m; j++) {
        const double *d = s->steps + (size_t)j * n;
        double dw = 0.0, dd = 0.0;
        for (int i = 0; i < n; i++) { dw += d[i] * w[i]; dd += d[i] * d[i]; }
        if (j + 1 < m) {
            const double *next = d + n;
            for (int i = 0; i < n; i++) w[i] += next[i] * (dw / dd);
        } else {
            double denominator = 1.0 - dw / dd;
            if (!(fabs(denominator) > 1e-3)) return 1;
            for (int i = 0; i < n; i++) w[i] /= denominator;
        }
    }
    if (m < s->max_steps) {
        memcpy(s->steps + (size_t)m * n, w, sizeof(double) * n);
        s->n_steps = m + 1;
    }
    return 0;
}

/* A pass's Newton's start: the predictor's, warm: the last pass's solution kept in q1 .. */
static void start_point(alpha_solver *s, double h, int warm)
{
    predict(s, h);
    if (warm) {
        memcpy(s->q, s->q1, sizeof(double) * s->nq);
        memcpy(s->v, s->v1, sizeof(double) * s->nq);
        memcpy(s->a, s->a1, sizeof(double) * s->nq);
        memcpy(s->lambda, s->lambda1, sizeof(double) * s->nm);
    }
}

/* A step's Newton from the start kept in q0 .. lambda0, to an absolute `tolerance` on the
   residual's norm */
static int solve(alpha_solver *s, double h, double t_new, int warm, double tolerance)
{
    int nq = s->nq, status;
    s->t0 = s->t;
    s->iterations = s->jacobians = 0;
    s->bad_row = s->bad_col = -1;
    if (h != s->factorized_h) s->jacobian_update_requested = 1;

    const alpha_settings *set = &s->set;
    double scale = s->beta * h * h;
    double beta_prime = (1 - s->alpha_m) / (h * h * s->beta * (1 - s->alpha_f));
    double gamma_prime = s->gamma / (h * s->beta);
    double initial, current, last, contractivity;

    start_point(s, h, warm);
    if ((status = residual(s, t_new, scale, &initial))) goto failed;
    if (initial <= tolerance) initial = 2. * tolerance;
    current = last = initial;
    int converged = 0, stop = 0, restarted = 0, add_restart_step = 0;
    int reuse = set->reuse_jacobian > 0;
    int full = !set->use_modified_newton && !reuse;
    int from_start = 0;  /* the reuse policy's restart from the pass's start */

    while (!converged && !stop && s->iterations < set->max_iterations) {
        s->iterations++;
        int made = 0;  /* a new Newton matrix at this iterate */
        if (s->jacobian_update_requested || full) {
            if ((status = newton_matrix(s, t_new, h))) goto failed;
            s->jacobian_update_requested = 0;
            made = 1 + from_start;
            from_start = 0;
        }
        if (made || s->iterations == 1) s->n_steps = 0;
        bb_solve(s->matrix, s->residual, s->delta);
        if (reuse && set->reuse_broyden && broyden(s)) {
            /* no Broyden step: a new matrix here, its Newton step */
            if ((status = newton_matrix(s, t_new, h))) goto failed;
            made = 1;
            s->n_steps = 0;
            bb_solve(s->matrix, s->residual, s->delta);
            broyden(s);
        }
        update(s, -1.0, scale, beta_prime, gamma_prime);
        if ((status = residual(s, t_new, scale, &current))) goto failed;

        if (s->iterations <= ALPHA_TRACE) {
            s->trace_norm[s->iterations - 1] = current;
            s->trace_factorized[s->iterations - 1] = made;
        }
        /* (a kept matrix's growth is its own fault, not the start's: no adaption) */
        if (set->adapt_initial_residual && current > initial && s->iterations <= 1
            && (made || !reuse))
            initial = last = current;
        if (current / initial <= set->relative_tolerance || current <= tolerance)
            converged = 1;

        if (add_restart_step && converged) {
            add_restart_step = 0;
            converged = 0;
        } else if (!converged) {
            add_restart_step = 0;
            double nu = 0.0, nv = 0.0, nl = 0.0;
            for (int i = 0; i < nq; i++) { nu += s->q[i] * s->q[i]; nv += s->v[i] * s->v[i]; }
            for (int j = 0; j < s->nm; j++) nl += s->lambda[j] * s->lambda[j];
            int diverged = 0;
            if (nu >= set->maximum_solution_norm || nv >= set->maximum_solution_norm
                || isnan(nu) || isnan(nv) || isnan(nl)) {
                if (full) stop = 1;
                else diverged = 1;
            }
            if (reuse) {
                contractivity = current / last;
                /* the iterations the present contraction would still take */
                double target = fmax(tolerance,
                                     set->relative_tolerance * initial);
                double needed = log(target / current) / log(contractivity);
                if (diverged && made) {
                    stop = 1;  /* as full Newton's */
                } else if (diverged) {  /* the pass again from its start, a new matrix */
                    s->jacobian_update_requested = from_start = 1;
                    current = last = initial;
                    start_point(s, h, warm);
                    double ignored;
                    if ((status = residual(s, t_new, scale, &ignored))) goto failed;
                } else if (made && s->iterations > 1 && !(contractivity <= 1.0)
                           && set->reuse_damping > 0) {
                    /* grown on a new matrix (a kink of the loads between the iterates):
                       the update halved while the residual still grows */
                    double share = 1.0;
                    for (int k = 0; k < set->reuse_damping && !(current <= last); k++) {
                        share *= 0.5;
                        update(s, share, scale, beta_prime, gamma_prime);
                        if ((status = residual(s, t_new, scale, &current))) goto failed;
                    }
                    s->jacobian_update_requested = 1;
                    last = current;
                } else if (!made && !(contractivity <= 1.0)) {
                    /* grown on a kept matrix: the iterate undone, a new matrix there */
                    update(s, 1.0, scale, beta_prime, gamma_prime);
                    if ((status = residual(s, t_new, scale, &current))) goto failed;
                    s->jacobian_update_requested = 1;
                } else {
                    if (!(contractivity <= set->reuse_contractivity)
                        || !(needed <= set->max_iterations - s->iterations))
                        s->jacobian_update_requested = 1;
                    last = current;
                }
                continue;
            }
            if (!full && s->iterations > set->max_modified_newton_iterations)
                s->jacobian_update_requested = 1;
            int switch_to_full = 0;
            if (!full && s->iterations > set->max_modified_newton_iterations
                                         + set->max_modified_newton_restart_iterations) {
                full = 1;
                switch_to_full = 1;
            }
            contractivity = current / last;
            last = current;
            if (!full && set->use_modified_newton
                && (diverged || switch_to_full
                    || (contractivity > set->modified_newton_contractivity && s->iterations > 2))) {
                s->jacobian_update_requested = 1;
                if (restarted && !full) full = 1;
                if (!stop && (diverged || contractivity > 2 || full)) {
                    restarted = 1;
                    current = last = initial;
                    predict(s, h);
                    double ignored;
                    if ((status = residual(s, t_new, scale, &ignored))) goto failed;
                    add_restart_step = 1;
                }
            }
        }
    }
    s->residual_norm = current;
    s->initial_residual = initial;
    if (!converged || stop) { status = ALPHA_NOT_CONVERGED; goto failed; }
    double factor = (1. - s->alpha_f) / (1. - s->alpha_m);
    for (int i = 0; i < nq; i++) s->a_alg[i] += factor * s->a[i];
    s->t = t_new;
    return ALPHA_CONVERGED;

failed:
    restore(s);
    s->jacobian_update_requested = 1;
    return status;
}

/* The state at t, and exudyn's computeInitialAccelerations: [M G^T; G 0] [a; lambda] =
   [f; -(G v)_q v], (G v)_q v by a forward difference along v (exudyn differentiates
   coordinate by coordinate); without it a = 0. */
EXPORT int alpha_initialize(alpha_solver *s, double t, const double *q, const double *v,
                            int compute_initial_accelerations)
{
    int nq = s->nq, nm = s->nm, status;
    s->t = t;
    memcpy(s->q, q, sizeof(double) * nq);
    memcpy(s->v, v, sizeof(double) * nq);
    memset(s->a, 0, sizeof(double) * nq);
    memset(s->lambda, 0, sizeof(double) * nm);
    s->jacobian_update_requested = 1;
    s->bad_row = s->bad_col = -1;
    if (compute_initial_accelerations) {
        double *r = s->residual, speed = 0.0, size = 0.01, e = 0.0;
        for (int i = 0; i < nq; i++) {
            speed = fmax(speed, fabs(v[i]));
            size = fmax(size, fabs(q[i]));
        }
        memset(r, 0, sizeof(double) * s->n);
        if (speed > 1e-10) {
            /* -(G(q + e v) v - G(q) v) / e into the multipliers' rows */
            e = 1e-7 * size / speed;
            for (int i = 0; i < nq; i++) s->q0[i] = q[i] + e * v[i];
            if ((status = evaluate(s, t, s->q0, v))) return status;
            for (int k = 0; k < s->G.count; k++)
                r[nq + s->G.row[k]] -= s->G.value[k] * v[s->G.col[k]] / e;
        }
        if ((status = evaluate(s, t, q, v))) return status;
        if (e > 0.0)
            for (int k = 0; k < s->G.count; k++)
                r[nq + s->G.row[k]] += s->G.value[k] * v[s->G.col[k]] / e;
        bb_zero(s->matrix);
        for (int i = 0; i < nq; i++)
            if ((status = bb_add(s->matrix, i, i, s->mass[i]))) return from_matrix(s, status);
        if ((status = add_constraints(s))) return status;
        if ((status = bb_factorize(s->matrix))) return from_matrix(s, status);
        memcpy(r, s->f, sizeof(double) * nq);
        bb_solve(s->matrix, r, s->delta);
        memcpy(s->a, s->delta, sizeof(double) * nq);
        memcpy(s->lambda, s->delta + nq, sizeof(double) * nm);
    }
    memcpy(s->a_alg, s->a, sizeof(double) * nq);
    return ALPHA_CONVERGED;
}

/* the last solve's trace (alpha_solver.h): its iterations traced */
EXPORT int alpha_trace(const alpha_solver *s, double *norms, int *factorized)
{
    int n = s->iterations < ALPHA_TRACE ? s->iterations : ALPHA_TRACE;
    memcpy(norms, s->trace_norm, sizeof(double) * n);
    memcpy(factorized, s->trace_factorized, sizeof(int) * n);
    return n;
}

EXPORT void alpha_state(const alpha_solver *s, double *q, double *v, double *a, double *lambda)
{
    memcpy(q, s->q, sizeof(double) * s->nq);
    memcpy(v, s->v, sizeof(double) * s->nq);
    memcpy(a, s->a, sizeof(double) * s->nq);
    memcpy(lambda, s->lambda, sizeof(double) * s->nm);
}

/* the last step's iterations, Jacobians, all Jacobians, bad row and column; its residual
   norm and initial residual */
EXPORT void alpha_report(const alpha_solver *s, int *ints, double *reals)
{
    ints[0] = s->iterations; ints[1] = s->jacobians; ints[2] = s->total_jacobians;
    ints[3] = s->bad_row; ints[4] = s->bad_col;
    reals[0] = s->residual_norm; reals[1] = s->initial_residual;
}
