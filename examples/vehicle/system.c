/* The whole vehicle's equations in C, outside exudyn (system.py loads them): at (t, q, v),
 * q and v in exudyn's own ODE2 order (the nodes' coordinates relative to their
 * references), the generalized forces f, the revolute joints' equations g (index 3, as
 * exudyn's ObjectJointRevolute2D writes them), K = -df/dq and D = -df/dv as triplets
 * (factor K + factor_t D, exudyn's convention), G = dg/dq and d(G^T lambda)/dq, and the
 * constant mass diagonal, for a solver of M a = f - G^T lambda, g = 0.
 *
 * The forces are the model's own kernels, compiled into this library with it: the
 * contacts (contacts.c: contacts_evaluate's parts, contacts_jacobian) and the track's
 * joints (joints.c: joints_evaluate's parts, joints_jacobian), the coupling bank's laws
 * (bank.c's bank_law_loads, or law_table_loads) called once for both; the dampers'
 * laws are read from the joints' call of the same laws (their deflections written into
 * its array first). Here only what exudyn's own elements compute: the coordinate
 * spring-dampers (the speed hold, the torsion bars, the dampers' connectors, the
 * tensioner), gravity (LoadMassProportional) and the revolute joints. libc and libm only. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "contacts.h"

#define SYSTEM_EXPORT CONTACTS_EXPORT

/* contacts.c's and contacts_jacobian.c's, and joints.c's, called here */
long contacts_jacobian(Contacts *c, double factor, double factor_t, double *out,
                       long capacity);
void joints_deflections(void *bound, const double *state, const double *direction);
void joints_laws(void *bound);
void joints_apply_laws(void *bound);
void contacts_kinematics(Contacts *c);
void contacts_tyre_deflections(const Contacts *c, double *deflection);
void contacts_tyre_loads(Contacts *c, const double *load, const double *slope);
void joints_jacobian(int n, double half, const double *link, const double *joint,
                     const double *qd, const double *law, const double *effort, double factor,
                     double factor_t, double *triplets);

/* exudyn's ObjectConnectorCoordinateSpringDamper between coordinates a and b (-1: the
 * ground's): with d = q_b - q_a, f = k (d - offset - drift t) + c (d' - drift), or the
 * bank's law of d (row >= 0); f acts on a, -f on b. */
typedef struct {
    int a, b, row;
    double stiffness, damping, offset, drift;
} CoordinateSpring;

/* exudyn's ObjectJointRevolute2D: g = p_1 - p_0, p_i = node i's position plus its rotation
 * times `local` (coordinates x, y, angle of node i at index[i]) */
typedef struct {
    int index[2];
    double local[2][2];
} Revolute;

/* What vsystem_new is handed: the arrays belong to the caller (system.py), allocated
 * once. `joint_arrays`: the joints' Bound's q, qd, link, joint, law, effort, generalized,
 * deflection, loads, slopes (joints.py's CompiledJoints.arrays). */
typedef struct {
    int n, m, bodies, links, springs, revolutes;
    const double *reference, *mass, *gravity; /* n each */
    Contacts *contacts;
    const int *body_index; /* the contacts' bodies' coordinates in the system (3 bodies) */
    void *joints;
    double half;
    const int *link_index; /* the links' coordinates in the system (3 links) */
    double **joint_arrays;
    const CoordinateSpring *spring;
    const Revolute *revolute;
    /* the solver's band (vsystem_keep_band; NULL: every entry kept): each coordinate's
     * position in it (-1: in the border), its half bandwidth; the entries left out of
     * the Jacobian since, and the largest of them */
    const int *band_position;
    int half_bandwidth;
    long left_out;
    double left_out_largest;
} VehicleSystem;

enum { J_Q, J_QD, J_LINK, J_JOINT, J_LAW, J_EFFORT, J_GENERALIZED, J_DEFLECTION, J_LOADS,
       J_SLOPES };

SYSTEM_EXPORT int vsystem_layout(void) { return (int)sizeof(VehicleSystem); }

/* A coordinate spring's force and its slopes by d and d' */
static double spring_force(const VehicleSystem *s, const CoordinateSpring *c, double t,
                           const double *q, const double *v, double *by_d, double *by_rate)
{
    double d = q[c->b] - (c->a >= 0 ? q[c->a] : 0.0);
    if (c->row >= 0) {
        *by_d = s->joint_arrays[J_SLOPES][c->row];
        *by_rate = 0.0; /* the bank's laws are rate-free */
        return s->joint_arrays[J_LOADS][c->row];
    }
    double rate = v[c->b] - (c->a >= 0 ? v[c->a] : 0.0);
    *by_d = c->stiffness;
    *by_rate = c->damping;
    return c->stiffness * (d - c->offset - c->drift * t) + c->damping * (rate - c->drift);
}

/* The contacts and the joints at (q, v) (their kernels' memory): the bank's laws called
 * once for the tyres, the joints and the dampers (each row's law is its own, so that
 * this gives contacts_evaluate's and joints_evaluate's numbers), the dampers' deflections
 * written with the joints' and the tyres', into the joints' array */
static void evaluate_kernels(VehicleSystem *s, const double *q, const double *v,
                             int forces_only)
{
    Contacts *c = s->contacts;
    c->forces_only = forces_only; /* the residual's: the contacts' springs left out */
    for (int i = 0; i < 3 * s->bodies; i++) {
        c->array[A_STATE][i] = c->reference[i] + q[s->body_index[i]];
        c->array[A_RATES][i] = v[s->body_index[i]];
    }
    contacts_kinematics(c);
    double **j = s->joint_arrays;
    for (int i = 0; i < 3 * s->links; i++) {
        j[J_Q][i] = q[s->link_index[i]];
        j[J_QD][i] = v[s->link_index[i]];
    }
    for (int k = 0; k < s->springs; k++) {
        const CoordinateSpring *spring = s->spring + k;
        if (spring->row >= 0)
            j[J_DEFLECTION][spring->row] = q[spring->b] - (spring->a >= 0 ? q[spring->a] : 0.0);
    }
    /* the links' cos and sin: the contacts' where their angles are the same bits (the
     * links in the same order there) */
    int same = s->links == c->links;
    for (int i = 0; same && i < 3 * s->links; i++)
        same = s->link_index[i] == s->body_index[3 * c->link0 + i];
    if (same)
        joints_deflections(s->joints, c->array[A_STATE] + 3 * c->link0, c->array[A_U]);
    else
        joints_deflections(s->joints, NULL, NULL);
    contacts_tyre_deflections(c, j[J_DEFLECTION]);
    joints_laws(s->joints);
    contacts_tyre_loads(c, j[J_LOADS], j[J_SLOPES]);
    contacts_forces(c, 0);
    joints_apply_laws(s->joints);
}

/* A revolute joint's node i: its position's arm (rotation times local) */
static void revolute_arm(const VehicleSystem *s, const Revolute *r, int i, const double *q,
                         double arm[2])
{
    int x = r->index[i];
    double angle = s->reference[x + 2] + q[x + 2];
    double cos_a = cos(angle), sin_a = sin(angle);
    arm[0] = cos_a * r->local[i][0] - sin_a * r->local[i][1];
    arm[1] = sin_a * r->local[i][0] + cos_a * r->local[i][1];
}

/* g (m): the revolute joints' equations at q */
SYSTEM_EXPORT void vsystem_constraints(const VehicleSystem *s, const double *q, double *g)
{
    for (int k = 0; k < s->revolutes; k++) {
        const Revolute *r = s->revolute + k;
        double p[2][2];
        for (int i = 0; i < 2; i++) {
            int x = r->index[i];
            revolute_arm(s, r, i, q, p[i]);
            p[i][0] += s->reference[x] + q[x];
            p[i][1] += s->reference[x + 1] + q[x + 1];
        }
        g[2 * k] = p[1][0] - p[0][0];
        g[2 * k + 1] = p[1][1] - p[0][1];
    }
}

/* f (n) at (t, q, v), and g (m) where g is not NULL */
SYSTEM_EXPORT void vsystem_residual(VehicleSystem *s, double t, const double *q,
                                    const double *v, double *f, double *g)
{
    evaluate_kernels(s, q, v, 1);
    memcpy(f, s->gravity, sizeof(double) * s->n);
    const double *contact = s->contacts->array[A_GENERALIZED];
    for (int i = 0; i < 3 * s->bodies; i++) f[s->body_index[i]] += contact[i];
    const double *joint = s->joint_arrays[J_GENERALIZED];
    for (int i = 0; i < 3 * s->links; i++) f[s->link_index[i]] += joint[i];
    for (int k = 0; k < s->springs; k++) {
        const CoordinateSpring *c = s->spring + k;
        double by_d, by_rate, force = spring_force(s, c, t, q, v, &by_d, &by_rate);
        if (c->a >= 0) f[c->a] += force;
        f[c->b] -= force;
    }
    if (g != NULL) vsystem_constraints(s, q, g);
}

/* Where the Jacobian's entries go: (row, column, value) rows of doubles (`rows`, Python's
 * view) or the solver core's own row, column and value arrays (alpha_triplets), written
 * straight there so that no copy of them is made per Newton matrix; counted past the
 * capacity, as triplets_put */
typedef struct {
    double *rows;
    int *row, *col;
    double *value;
    long count, capacity;
} Sink;

static void sink_put(Sink *k, int row, int column, double value)
{
    if (k->count < k->capacity) {
        if (k->rows != NULL) {
            double *entry = k->rows + 3 * k->count;
            entry[0] = row;
            entry[1] = column;
            entry[2] = value;
        } else {
            k->row[k->count] = row;
            k->col[k->count] = column;
            k->value[k->count] = value;
        }
    }
    k->count++;
}

/* An entry, where it is not zero and falls in the solver's band or border: the kernels'
 * blocks hold zeros beyond where their elements reach (a tyre's blend over the neighbours
 * of the links beneath it), which a band need not hold, and where a tyre's blend reaches
 * further (a wheel over two sharp bends in a row: system.py's REACH) the entries beyond
 * the band are left out, counted: the Newton matrix is then inexact, the residual not */
static void put(VehicleSystem *s, Sink *k, int row, int column, double value)
{
    if (value == 0.0) return;
    if (s->band_position != NULL) {
        int i = s->band_position[row], j = s->band_position[column];
        if (i >= 0 && j >= 0 && abs(i - j) > s->half_bandwidth) {
            s->left_out++;
            if (fabs(value) > s->left_out_largest) s->left_out_largest = fabs(value);
            return;
        }
    }
    sink_put(k, row, column, value);
}

/* factor K + factor_t D (K = -df/dq, D = -df/dv) at (t, q, v) into `result` while they fit
 * its capacity (repeated entries add, zeros left out); how many there are. `scratch`: room
 * for the joints' triplets (36 a joint) and the contacts' (`capacity` of them). */
static long jacobian_into(VehicleSystem *s, double t, const double *q, const double *v,
                          double factor, double factor_t, Sink result, long capacity,
                          double *scratch)
{
    evaluate_kernels(s, q, v, 0);
    double **j = s->joint_arrays;
    joints_jacobian(s->links, s->half, j[J_LINK], j[J_JOINT], j[J_QD], j[J_LAW], j[J_EFFORT],
                    factor, factor_t, scratch);
    for (long k = 0; k < 36L * s->links; k++) {
        const double *e = scratch + 3 * k;
        put(s, &result, s->link_index[(int)e[0]], s->link_index[(int)e[1]], e[2]);
    }
    long contacts = contacts_jacobian(s->contacts, factor, factor_t, scratch, capacity);
    for (long k = 0; k < contacts && k < capacity; k++) {
        const double *e = scratch + 3 * k;
        put(s, &result, s->body_index[(int)e[0]], s->body_index[(int)e[1]], e[2]);
    }
    if (contacts > capacity) result.count += contacts - capacity;
    for (int k = 0; k < s->springs; k++) {
        const CoordinateSpring *c = s->spring + k;
        double by_d, by_rate;
        spring_force(s, c, t, q, v, &by_d, &by_rate);
        /* f_a = F(q_b - q_a), f_b = -F: -df/dq */
        double value = factor * by_d + factor_t * by_rate;
        if (c->a >= 0) {
            put(s, &result, c->a, c->a, value);
            put(s, &result, c->a, c->b, -value);
            put(s, &result, c->b, c->a, -value);
        }
        put(s, &result, c->b, c->b, value);
    }
    return result.count;
}

/* jacobian_into as (row, column, value) rows of doubles into `out` */
SYSTEM_EXPORT long vsystem_jacobian(VehicleSystem *s, double t, const double *q,
                                    const double *v, double factor, double factor_t,
                                    double *out, long capacity, double *scratch)
{
    Sink rows = {out, NULL, NULL, NULL, 0, capacity};
    return jacobian_into(s, t, q, v, factor, factor_t, rows, capacity, scratch);
}

/* jacobian_into straight into a solver's row, column and value arrays (own_system.c) */
SYSTEM_EXPORT long vsystem_jacobian_split(VehicleSystem *s, double t, const double *q,
                                          const double *v, double factor, double factor_t,
                                          int *row, int *col, double *value, long capacity,
                                          double *scratch)
{
    Sink split = {NULL, row, col, value, 0, capacity};
    return jacobian_into(s, t, q, v, factor, factor_t, split, capacity, scratch);
}

/* G = dg/dq (rows of g, columns of q) as triplets, 12 per joint (6 a node) into `out`;
 * where `lambda` is not NULL, the multipliers' force's derivative d(G^T lambda)/dq, one
 * (angle, angle) entry per node, 2 per joint, into `hessian`. */
SYSTEM_EXPORT void vsystem_constraint_jacobian(const VehicleSystem *s, const double *q,
                                               const double *lambda, double *out,
                                               double *hessian)
{
    for (int k = 0; k < s->revolutes; k++) {
        const Revolute *r = s->revolute + k;
        for (int i = 0; i < 2; i++) {
            int x = r->index[i];
            double sign = i == 0 ? -1.0 : 1.0, arm[2];
            revolute_arm(s, r, i, q, arm);
            /* d(p_i)/d(x, y, angle) = [[1, 0, -arm_y], [0, 1, arm_x]] */
            double rows[2][3] = {{1.0, 0.0, -arm[1]}, {0.0, 1.0, arm[0]}};
            for (int e = 0; e < 2; e++)
                for (int c = 0; c < 3; c++) {
                    double *entry = out + 3 * (12 * k + 6 * i + 3 * e + c);
                    entry[0] = 2 * k + e;
                    entry[1] = x + c;
                    entry[2] = sign * rows[e][c];
                }
            if (lambda != NULL) {
                double *entry = hessian + 3 * (2 * k + i);
                entry[0] = entry[1] = x + 2;
                entry[2] = -sign * (arm[0] * lambda[2 * k] + arm[1] * lambda[2 * k + 1]);
            }
        }
    }
}

SYSTEM_EXPORT void vsystem_mass(const VehicleSystem *s, double *mass)
{
    memcpy(mass, s->mass, sizeof(double) * s->n);
}
