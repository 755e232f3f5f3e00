/* The track's joints in C (joints.py loads it; its numpy kernel is the readable reference):
 * per joint the radial bush's seat distance and the torsion bush's relative angle, with
 * their rates (joints_kinematics); the two bushes' generalized forces on the links' (x, y,
 * angle) once Python has read their laws' loads and slopes (joints_forces); their Jacobian
 * as exudyn's triplets (joints_jacobian); on the compiled path the three at once, the bank's
 * laws called from here (joints_evaluate, joints_evaluate_jacobian). The same operations in the same order as the
 * numpy kernel, so that the two give the same bits. libc and libm only.
 *
 * Joint j joins link a = j - 1 (its front seat, local +half) to link b = j (its rear seat,
 * local -half). Arrays, row-major: link (n x 2: cos, sin of the link's angle); joint (n x 8:
 * the seats' separation dx, dy, their distance L, relative velocity wx, wy, the distance's
 * rate, the torsion bush's angle and rate); law (n x 6: the radial law's load, its slope by
 * deflection and by rate, the same for the torsion law); effort (n x 3: the radial force
 * applied, g = load * fade(L), and its slopes by L and by its rate). */
#include <math.h>
#include <stdlib.h>

#if defined(_WIN32)
#define JOINTS_EXPORT __declspec(dllexport)
#else
#define JOINTS_EXPORT __attribute__((visibility("default")))
#endif

/* Each link's cos and sin (link); where `state` is not NULL, a link whose angle is
 * state's (x, y, angle rows) to the bit takes its cos and sin from `direction` (n x 2:
 * the contacts' kernel's of the same angles) */
static void directions(int n, const double *reference, const double *q, const double *state,
                       const double *direction, double *link)
{
    for (int k = 0; k < n; k++) {
        double angle = reference[3 * k + 2] + q[3 * k + 2];
        if (state != NULL && angle == state[3 * k + 2]) {
            link[2 * k] = direction[2 * k];
            link[2 * k + 1] = direction[2 * k + 1];
            continue;
        }
        link[2 * k] = cos(angle);
        link[2 * k + 1] = sin(angle);
    }
}

/* joints_kinematics once `link` is set */
static void seats(int n, double half, const double *reference, const double *q,
                  const double *qd, const double *offset, const double *link, double *joint)
{
    for (int j = 0; j < n; j++) {
        int a = (j + n - 1) % n, b = j;
        const double *ca = link + 2 * a, *cb = link + 2 * b;
        double xa = reference[3 * a] + q[3 * a], ya = reference[3 * a + 1] + q[3 * a + 1];
        double xb = reference[3 * b] + q[3 * b], yb = reference[3 * b + 1] + q[3 * b + 1];
        double front_x = xa + ca[0] * half, front_y = ya + ca[1] * half;
        double rear_x = xb + cb[0] * -half, rear_y = yb + cb[1] * -half;
        double *out = joint + 8 * j;
        out[0] = rear_x - front_x;
        out[1] = rear_y - front_y;
        out[2] = sqrt(out[0] * out[0] + out[1] * out[1]);
        /* the seats' velocities: the node's plus omega x (its arm from the node) */
        double wa = qd[3 * a + 2], wb = qd[3 * b + 2];
        double front_vx = qd[3 * a] - wa * (ca[1] * half);
        double front_vy = qd[3 * a + 1] + wa * (ca[0] * half);
        double rear_vx = qd[3 * b] - wb * (cb[1] * -half);
        double rear_vy = qd[3 * b + 1] + wb * (cb[0] * -half);
        out[3] = rear_vx - front_vx;
        out[4] = rear_vy - front_vy;
        out[5] = out[2] > 0.0 ? (out[0] * out[3] + out[1] * out[4]) / out[2] : 0.0;
        out[6] = (q[3 * b + 2] - q[3 * a + 2]) + offset[j];
        out[7] = wb - wa;
    }
}

JOINTS_EXPORT void joints_kinematics(int n, double half, const double *reference,
                                     const double *q, const double *qd, const double *offset,
                                     double *link, double *joint)
{
    directions(n, reference, q, NULL, NULL, link);
    seats(n, half, reference, q, qd, offset, link, joint);
}

/* The seats' arms from their links' nodes: a's front seat, b's rear seat. */
static void arms(const double *link, int a, int b, double half, double ra[2], double rb[2])
{
    ra[0] = link[2 * a] * half;
    ra[1] = link[2 * a + 1] * half;
    rb[0] = link[2 * b] * -half;
    rb[1] = link[2 * b + 1] * -half;
}

/* The radial bush's force along the seats' line, never pushing, faded in over their first
 * `fade` of distance (model.radial_fade); the torsion bush's torque; each link's generalized force
 * (its rows in `generalized`), the joint it is b of first, then the one it is a of. */
JOINTS_EXPORT void joints_forces(int n, double half, double fade, const double *link,
                                 const double *joint, const double *law, double *effort,
                                 double *generalized)
{
    for (int j = 0; j < n; j++) {
        const double *kin = joint + 8 * j, *l = law + 6 * j;
        double distance = kin[2];
        double s = distance / fade < 1.0 ? distance / fade : 1.0;
        double share = s * (2.0 - s), share_slope = 2.0 * (1.0 - s) / fade;
        double *e = effort + 3 * j;
        /* the bush never pushes its seats apart (model.radial_pull): a load below zero
         * is cut, its slopes with it (NaN passes) */
        int cut = l[0] < 0.0;
        double load = cut ? 0.0 : l[0];
        e[0] = load * share;
        e[1] = (cut ? 0.0 : l[1]) * share + load * share_slope;
        e[2] = (cut ? 0.0 : l[2]) * share;
    }
    for (int k = 0; k < n; k++) {
        double sum[3];
        for (int side = 0; side < 2; side++) {
            /* link k is b of joint k and a of joint k + 1 */
            int j = side == 0 ? k : (k + 1) % n;
            int a = (j + n - 1) % n, b = j;
            const double *kin = joint + 8 * j;
            double length = kin[2] > 0.0 ? kin[2] : 1.0;
            double g = effort[3 * j];
            double ux = g * (kin[0] / length), uy = g * (kin[1] / length);
            double torque = law[6 * j + 3];
            double ra[2], rb[2];
            arms(link, a, b, half, ra, rb);
            double part[3];
            if (side == 0) {
                part[0] = -ux;
                part[1] = -uy;
                part[2] = -(rb[0] * uy - rb[1] * ux) - torque;
            } else {
                part[0] = ux;
                part[1] = uy;
                part[2] = (ra[0] * uy - ra[1] * ux) + torque;
            }
            for (int i = 0; i < 3; i++) sum[i] = side == 0 ? part[i] : sum[i] + part[i];
        }
        for (int i = 0; i < 3; i++) generalized[3 * k + i] = sum[i];
    }
}

/* Per joint its 6 x 6 block over (a's x, y, angle, b's x, y, angle), factor K + factor_t
 * C, as 36 (row, column, value) triplets in row-major order: with B = d(seats'
 * separation)/d(coordinates) = [-G_a, G_b], G = [[1, 0, -r_y], [0, 1, r_x]] (r the seat's
 * arm), e the unit separation, c = B^T e, H the velocities' change with the angles:
 *   K = (g_L - g/L) c c^T + g/L B^T B + g_v c (B^T w / L - (L'/L) c + H^T e)^T
 *       + r_a.u at (a's angle)^2 - r_b.u at (b's angle)^2 + the torsion law's slope,
 *   C = g_v c c^T + the torsion law's slope by rate,
 * u = g e the force on a's seat (L' the distance's rate, w the seats' relative velocity). */
JOINTS_EXPORT void joints_jacobian(int n, double half, const double *link, const double *joint,
                                   const double *qd, const double *law, const double *effort,
                                   double factor, double factor_t, double *triplets)
{
    for (int j = 0; j < n; j++) {
        int a = (j + n - 1) % n, b = j;
        const double *kin = joint + 8 * j, *l = law + 6 * j, *ef = effort + 3 * j;
        double ra[2], rb[2];
        arms(link, a, b, half, ra, rb);
        double B[2][6] = {{-1.0, 0.0, ra[1], 1.0, 0.0, -rb[1]},
                          {0.0, -1.0, -ra[0], 0.0, 1.0, rb[0]}};
        double length = kin[2] > 0.0 ? kin[2] : 1.0;
        double e0 = kin[0] / length, e1 = kin[1] / length;
        double ratio = kin[5] / length, beta = ef[0] / length;
        double alpha = ef[1] - beta;
        double wa = qd[3 * a + 2], wb = qd[3 * b + 2];
        double He[6] = {0.0, 0.0, (wa * ra[0]) * e0 + (wa * ra[1]) * e1, 0.0, 0.0,
                        (-wb * rb[0]) * e0 + (-wb * rb[1]) * e1};
        double c[6], row[6];
        for (int i = 0; i < 6; i++) {
            c[i] = B[0][i] * e0 + B[1][i] * e1;
            double Bw = B[0][i] * kin[3] + B[1][i] * kin[4];
            row[i] = Bw / length - ratio * c[i] + He[i];
        }
        double ux = ef[0] * e0, uy = ef[0] * e1;
        double K[6][6], C[6][6];
        for (int i = 0; i < 6; i++)
            for (int k = 0; k < 6; k++) {
                double BtB = B[0][i] * B[0][k] + B[1][i] * B[1][k];
                K[i][k] = alpha * c[i] * c[k] + beta * BtB + ef[2] * c[i] * row[k];
                C[i][k] = ef[2] * c[i] * c[k];
            }
        K[2][2] += ra[0] * ux + ra[1] * uy;
        K[5][5] -= rb[0] * ux + rb[1] * uy;
        K[2][2] += l[4];
        K[2][5] -= l[4];
        K[5][2] -= l[4];
        K[5][5] += l[4];
        C[2][2] += l[5];
        C[2][5] -= l[5];
        C[5][2] -= l[5];
        C[5][5] += l[5];
        double *out = triplets + 3 * 36 * j;
        for (int i = 0; i < 6; i++)
            for (int k = 0; k < 6; k++) {
                double *entry = out + 3 * (6 * i + k);
                entry[0] = 3 * (i < 3 ? a : b) + i % 3;
                entry[1] = 3 * (k < 3 ? a : b) + k % 3;
                entry[2] = factor * K[i][k] + factor_t * C[i][k];
            }
    }
}

/* --- one call per evaluation (the compiled path: the bank's laws called from here) ------- */

/* bank.c's bank_law_loads: the bank's current laws' loads at `deflection` and their slopes */
typedef void (*LawLoads)(const void *bank, const double *deflection, double *loads,
                         double *slopes);

/* What joints_evaluate works on, its arrays the caller's (allocated once): the links'
 * reference, the torsion offsets, q, qd (the caller writes them), link, joint, law, effort, generalized
 * as above; the bank's rows of each joint's radial and torsion bush and its deflection,
 * loads and slopes (n_bank each; the other rows' deflections stay the caller's). */
typedef struct {
    int n, n_bank;
    double half, fade;
    LawLoads law_loads;
    const void *bank;
    const int *radial_rows, *torsion_rows;
    const double *reference, *offset;
    double *q, *qd, *link, *joint, *law, *effort, *generalized;
    double *deflection, *loads, *slopes;
} Bound;

JOINTS_EXPORT void *joints_bind(int n, double half, double fade, LawLoads law_loads,
                                const void *bank, int n_bank, const int *radial_rows,
                                const int *torsion_rows, double **arrays)
{
    Bound *b = malloc(sizeof *b);
    if (!b) return NULL;
    *b = (Bound){n, n_bank, half, fade, law_loads, bank, radial_rows, torsion_rows,
                 arrays[0], arrays[1], arrays[2], arrays[3], arrays[4], arrays[5],
                 arrays[6], arrays[7], arrays[8], arrays[9], arrays[10], arrays[11]};
    return b;
}

JOINTS_EXPORT void joints_unbind(void *bound) { free(bound); }

/* joints_evaluate in three parts, for a caller that calls the bank's laws once for more
 * than the joints (system.c): joints_kinematics (the links' cos and sin taken from
 * `direction` where their angles are `state`'s: directions above; NULL: none) and the
 * joints' deflections into the bank's rows (the other rows' stay the caller's)... */
JOINTS_EXPORT void joints_deflections(void *bound, const double *state,
                                      const double *direction)
{
    Bound *b = bound;
    int n = b->n;
    directions(n, b->reference, b->q, state, direction, b->link);
    seats(n, b->half, b->reference, b->q, b->qd, b->offset, b->link, b->joint);
    for (int j = 0; j < n; j++) {
        b->deflection[b->radial_rows[j]] = b->joint[8 * j + 2];
        b->deflection[b->torsion_rows[j]] = b->joint[8 * j + 6];
    }
}

/* ...the bank's laws at every row's deflection (loads and slopes by deflection; the
 * bank's laws are rate-free)... */
JOINTS_EXPORT void joints_laws(void *bound)
{
    Bound *b = bound;
    b->law_loads(b->bank, b->deflection, b->loads, b->slopes);
}

/* ...and the joints' laws read from them, joints_forces. */
JOINTS_EXPORT void joints_apply_laws(void *bound)
{
    Bound *b = bound;
    for (int j = 0; j < b->n; j++) {
        double *l = b->law + 6 * j;
        l[0] = b->loads[b->radial_rows[j]];
        l[1] = b->slopes[b->radial_rows[j]];
        l[2] = 0.0;
        l[3] = b->loads[b->torsion_rows[j]];
        l[4] = b->slopes[b->torsion_rows[j]];
        l[5] = 0.0;
    }
    joints_forces(b->n, b->half, b->fade, b->link, b->joint, b->law, b->effort,
                  b->generalized);
}

/* joints_kinematics, the bank's laws at the joints' deflections (joints.py's Joints.laws),
 * joints_forces: the three calls of the three-call path, the same operations. */
JOINTS_EXPORT void joints_evaluate(void *bound)
{
    joints_deflections(bound, NULL, NULL);
    joints_laws(bound);
    joints_apply_laws(bound);
}

/* The Jacobian at the bound q, qd with the bank's current laws: evaluated again there
 * (exudyn may ask at another iterate than its last forces', or after the laws changed),
 * then joints_jacobian over what that left. */
JOINTS_EXPORT void joints_evaluate_jacobian(void *bound, double factor, double factor_t,
                                            double *triplets)
{
    Bound *b = bound;
    joints_evaluate(bound);
    joints_jacobian(b->n, b->half, b->link, b->joint, b->qd, b->law, b->effort, factor,
                    factor_t, triplets);
}
