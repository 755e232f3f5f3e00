/* The vehicle's equations (system.c) as the solver core's two callbacks (alpha_solver.h),
 * so that no Python runs per Newton iterate (own_host.py loads it). The context holds the
 * vehicle's system (its functions' addresses, from system.c's library, so that one copy
 * of its code serves both), the solver (for its multipliers and coefficients) and room
 * for the system's triplets.
 *
 *   evaluate: f and g (vsystem_residual), G (vsystem_constraint_jacobian);
 *   jacobian: K + gamma' D (vsystem_jacobian_split, straight into the solver's K, with
 *             factor_t = gamma' = gamma / (h beta),
 *             the solver's D factor over its K factor; D given empty) plus the
 *             multipliers' term d(G^T lambda)/dq at the solver's present lambda, which
 *             the Newton matrix of r = M a - f + G^T lambda takes in its K block.
 *
 * Each callback's CPU time is summed (own_times), the host's split of a step's cost. */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include <time.h>

#include "alpha_solver.h"

typedef void (*residual_fn)(void *system, double t, const double *q, const double *v,
                            double *f, double *g);
typedef long (*jacobian_fn)(void *system, double t, const double *q, const double *v,
                            double factor, double factor_t, int *row, int *col,
                            double *value, long capacity, double *scratch);
typedef void (*constraint_jacobian_fn)(void *system, const double *q, const double *lambda,
                                       double *out, double *hessian);

typedef struct {
    void *system;
    residual_fn residual;
    jacobian_fn jacobian;
    constraint_jacobian_fn constraint_jacobian;
    alpha_solver *solver;
    int n, m;
    long capacity;           /* of scratch, triplets */
    double *scratch;         /* capacity x 3 */
    double *G, *H;           /* 6 m and m triplets */
    double seconds[2];       /* CPU time in evaluate, in jacobian */
    long calls[2];
} OwnContext;

EXPORT int own_layout(void) { return (int)sizeof(OwnContext); }

EXPORT void own_times(const OwnContext *c, double *seconds, long *calls)
{
    for (int i = 0; i < 2; i++) { seconds[i] = c->seconds[i]; calls[i] = c->calls[i]; }
}

static double cpu_now(void)
{
    struct timespec now;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
    return now.tv_sec + 1e-9 * now.tv_nsec;
}

/* system.c's (row, column, value) rows into the solver's triplets after those there */
static int append(alpha_triplets *t, const double *rows, long count)
{
    if (t->count + count > t->capacity) return 1;
    for (long k = 0; k < count; k++) {
        const double *e = rows + 3 * k;
        t->row[t->count] = (int)e[0];
        t->col[t->count] = (int)e[1];
        t->value[t->count] = e[2];
        t->count++;
    }
    return 0;
}

EXPORT int own_evaluate(void *context, double t, const double *q, const double *v, double *f,
                        double *g, alpha_triplets *G)
{
    OwnContext *c = context;
    double start = cpu_now();
    c->residual(c->system, t, q, v, f, g);
    c->constraint_jacobian(c->system, q, NULL, c->G, NULL);
    G->count = 0;
    int status = append(G, c->G, 6L * c->m);
    c->seconds[0] += cpu_now() - start;
    c->calls[0]++;
    return status;
}

EXPORT int own_jacobian(void *context, double t, const double *q, const double *v,
                        alpha_triplets *K, alpha_triplets *D)
{
    OwnContext *c = context;
    const alpha_solver *s = c->solver;
    double start = cpu_now();
    long capacity = K->capacity < c->capacity ? K->capacity : c->capacity;
    long count = c->jacobian(c->system, t, q, v, 1.0, s->gamma / (s->jacobian_h * s->beta),
                             K->row, K->col, K->value, capacity, c->scratch);
    D->count = 0;
    int status = count > capacity;
    K->count = status ? 0 : (int)count;
    if (!status) {
        c->constraint_jacobian(c->system, q, s->lambda, c->G, c->H);
        status = append(K, c->H, c->m);
    }
    c->seconds[1] += cpu_now() - start;
    c->calls[1]++;
    return status;
}
