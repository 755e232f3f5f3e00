/*
 * The bank's linearised step: linearised.py's Linearisation.step in C, for the instances
 * whose law is their linearised answer to a step (the damper; the tyre where its tangent
 * changes over the step). Built with bank.c, as bank.c is.
 */
#include "bank.h"

/* --- the linearised step (linearised.py) ----------------------------------------------- */

#define MAX_AUGMENTED (2 * MAX_STATES + 2)

/* The augmented matrix of linearised_step (d = 2n + 2, rows and columns [Y, P, s, 1]):
   two equal n x n blocks on the diagonal (A), the last two columns of the first 2n rows
   (u), and the upper triangular 2 x 2 corner; zero elsewhere. Its powers, their sums,
   products and quotients keep this pattern and the two blocks equal, so it is held
   compact: the block once. Every operation below is the one the full d x d algorithm
   (linearised.py's expm, _multiply and _solve) makes on an entry of the pattern, in the
   same order; what the full algorithm adds are products by the pattern's zeros (each
   +0 or -0, the entries being finite: a sum they join keeps its value) and the second
   block's repetition of the first block's operations on the same numbers. So the bits
   are the full algorithm's (tests/test_bank.py). */
typedef struct {
    int n;
    double block[MAX_STATES * MAX_STATES]; /* row-major n x n */
    double u[2 * MAX_STATES][2];           /* the columns s and t of the first 2n rows */
    double ss, st, tt;                     /* the corner */
} Augmented;

/* m = c I (the entries of n's pattern only: the arrays are sized for the largest n) */
static void diagonal(int n, double c, Augmented *m) {
    m->n = n;
    for (int k = 0; k < n * n; k++) m->block[k] = k % (n + 1) ? 0.0 : c;
    for (int r = 0; r < 2 * n; r++) m->u[r][0] = m->u[r][1] = 0.0;
    m->ss = m->tt = c;
    m->st = 0.0;
}

static void copy(const Augmented *from, Augmented *to) {
    int n = from->n;
    to->n = n;
    memcpy(to->block, from->block, sizeof(double) * n * n);
    memcpy(to->u, from->u, sizeof(double) * 4 * n);
    to->ss = from->ss, to->st = from->st, to->tt = from->tt;
}

/* c = a b (c is neither a nor b); n given, so that the sizes below compile unrolled */
static inline __attribute__((always_inline)) void multiply_n(const Augmented *a,
                                                            const Augmented *b,
                                                            Augmented *c, int n) {
    c->n = n;
    for (int r = 0; r < n; r++)
        for (int k = 0; k < n; k++) {
            double sum = 0.0;
            for (int j = 0; j < n; j++) sum += a->block[r * n + j] * b->block[j * n + k];
            c->block[r * n + k] = sum;
        }
    for (int r = 0; r < 2 * n; r++) {
        const double *row = a->block + (r % n) * n;
        const double (*u)[2] = b->u + (r / n) * n; /* the rows of r's block */
        double last = 0.0, next = 0.0;
        for (int j = 0; j < n; j++) {
            last += row[j] * u[j][0];
            next += row[j] * u[j][1];
        }
        last += a->u[r][0] * b->ss;
        next += a->u[r][0] * b->st;
        next += a->u[r][1] * b->tt;
        c->u[r][0] = last;
        c->u[r][1] = next;
    }
    double corner = 0.0;
    c->ss = corner + a->ss * b->ss;
    corner = 0.0;
    corner += a->ss * b->st;
    corner += a->st * b->tt;
    c->st = corner;
    corner = 0.0;
    c->tt = corner + a->tt * b->tt;
}

/* the damper's n = 2 and the rubber FMUs' 3 at known sizes (1.2 times faster) */
static void multiply(const Augmented *a, const Augmented *b, Augmented *c) {
    if (a->n == 2) multiply_n(a, b, c, 2);
    else if (a->n == 3) multiply_n(a, b, c, 3);
    else multiply_n(a, b, c, a->n);
}

/* y = y + c x, entry by entry */
static void add_scaled(Augmented *y, double c, const Augmented *x) {
    int n = x->n;
    for (int k = 0; k < n * n; k++) y->block[k] += c * x->block[k];
    for (int r = 0; r < 2 * n; r++) {
        y->u[r][0] += c * x->u[r][0];
        y->u[r][1] += c * x->u[r][1];
    }
    y->ss += c * x->ss;
    y->st += c * x->st;
    y->tt += c * x->tt;
}

static void swap(double *x, double *y) {
    double t = *x;
    *x = *y;
    *y = t;
}

/* Solve A X = B (B overwritten by X, A by its elimination): Gaussian elimination with
   partial pivoting, as the full matrix has it. The pivots of the first 2n columns lie in
   their own block (the rows below it are zero there), the second block's elimination
   repeats the first's (its multipliers applied to its own rows of u), and the corner's
   columns need none. */
static int solve(Augmented *a, Augmented *b) {
    int n = a->n;
    for (int col = 0; col < n; col++) {
        int pivot = col;
        for (int r = col + 1; r < n; r++)
            if (fabs(a->block[r * n + col]) > fabs(a->block[pivot * n + col])) pivot = r;
        if (a->block[pivot * n + col] == 0.0) return -1;
        if (pivot != col) {
            for (int k = 0; k < n; k++) {
                swap(&a->block[col * n + k], &a->block[pivot * n + k]);
                swap(&b->block[col * n + k], &b->block[pivot * n + k]);
            }
            for (int half = 0; half < 2 * n; half += n)
                for (int k = 0; k < 2; k++) {
                    swap(&a->u[half + col][k], &a->u[half + pivot][k]);
                    swap(&b->u[half + col][k], &b->u[half + pivot][k]);
                }
        }
        for (int r = col + 1; r < n; r++) {
            double f = a->block[r * n + col] / a->block[col * n + col];
            if (f == 0.0) continue;
            for (int k = col; k < n; k++) a->block[r * n + k] -= f * a->block[col * n + k];
            for (int k = 0; k < n; k++) b->block[r * n + k] -= f * b->block[col * n + k];
            for (int half = 0; half < 2 * n; half += n)
                for (int k = 0; k < 2; k++) {
                    a->u[half + r][k] -= f * a->u[half + col][k];
                    b->u[half + r][k] -= f * b->u[half + col][k];
                }
        }
    }
    /* back substitution, from the last row up: the corner, then each block's rows */
    double ts = 0.0 / a->tt; /* the row t's entry in the column s: a zero divided */
    b->tt = b->tt / a->tt;
    b->st = (b->st - a->st * b->tt) / a->ss;
    b->ss = (b->ss - a->st * ts) / a->ss;
    for (int r = n - 1; r >= 0; r--) {
        const double *row = a->block + r * n;
        for (int k = 0; k < n; k++) {
            double sum = b->block[r * n + k];
            for (int j = r + 1; j < n; j++) sum -= row[j] * b->block[j * n + k];
            b->block[r * n + k] = sum / row[r];
        }
        for (int half = 0; half < 2 * n; half += n) {
            double last = b->u[half + r][0], next = b->u[half + r][1];
            for (int j = r + 1; j < n; j++) {
                last -= row[j] * b->u[half + j][0];
                next -= row[j] * b->u[half + j][1];
            }
            last -= a->u[half + r][0] * b->ss;
            last -= a->u[half + r][1] * ts;
            next -= a->u[half + r][0] * b->st;
            next -= a->u[half + r][1] * b->tt;
            b->u[half + r][0] = last / row[r];
            b->u[half + r][1] = next / row[r];
        }
    }
    return 0;
}

/* e^M (into m): linearised.py's expm, diagonal Pade (6, 6) after scaling to a norm of
   1/2, then squaring (Higham, Functions of Matrices, ch. 10). */
static int expm(Augmented *m) {
    int n = m->n;
    /* the largest column sum of |M| (the second block's columns are the first's) */
    double norm = 0.0, last = 0.0, next = 0.0;
    for (int k = 0; k < n; k++) {
        double column = 0.0;
        for (int r = 0; r < n; r++) column += fabs(m->block[r * n + k]);
        if (column > norm) norm = column;
    }
    for (int r = 0; r < 2 * n; r++) {
        last += fabs(m->u[r][0]);
        next += fabs(m->u[r][1]);
    }
    last += fabs(m->ss);
    next += fabs(m->st);
    next += fabs(m->tt);
    if (last > norm) norm = last;
    if (next > norm) norm = next;
    int squarings = norm > 0.5 ? (int)ceil(log2(norm / 0.5)) : 0;
    if (squarings < 0) squarings = 0;
    static const double coefficients[7] = {1.0, 1.0 / 2, 5.0 / 44, 1.0 / 66, 1.0 / 792,
                                           1.0 / 15840, 1.0 / 665280};
    Augmented scaled, powers[2], even, odd;
    double scale = ldexp(1.0, -squarings);
    copy(m, &scaled);
    for (int k = 0; k < n * n; k++) scaled.block[k] *= scale;
    for (int r = 0; r < 2 * n; r++) {
        scaled.u[r][0] *= scale;
        scaled.u[r][1] *= scale;
    }
    scaled.ss *= scale;
    scaled.st *= scale;
    scaled.tt *= scale;
    diagonal(n, 1.0, &powers[0]);
    diagonal(n, 1.0, &even);
    diagonal(n, 0.0, &odd);
    for (int p = 1; p <= 6; p++) {
        multiply(&powers[(p - 1) % 2], &scaled, &powers[p % 2]);
        add_scaled(p % 2 ? &odd : &even, coefficients[p], &powers[p % 2]);
    }
    /* the denominator into even, the numerator (then the result) into m */
    for (int k = 0; k < n * n; k++) {
        double e = even.block[k], o = odd.block[k];
        even.block[k] = e - o;
        m->block[k] = e + o;
    }
    for (int r = 0; r < 2 * n; r++)
        for (int k = 0; k < 2; k++) {
            double e = even.u[r][k], o = odd.u[r][k];
            even.u[r][k] = e - o;
            m->u[r][k] = e + o;
        }
    double e[3] = {even.ss, even.st, even.tt}, o[3] = {odd.ss, odd.st, odd.tt};
    even.ss = e[0] - o[0], even.st = e[1] - o[1], even.tt = e[2] - o[2];
    m->ss = e[0] + o[0], m->st = e[1] + o[1], m->tt = e[2] + o[2];
    if (solve(&even, m) != 0) return -1;
    Augmented *from = m, *to = &powers[0];
    for (int s = 0; s < squarings; s++) {
        multiply(from, from, to);
        to = from;
        from = from == m ? &powers[0] : m;
    }
    if (from != m) copy(from, m);
    return 0;
}

/* expm of an augmented matrix (d x d, row-major, in place) for linearised.py, which has
   it in Python too (the same bits) and calls this where the library is built; -1 for a
   matrix of another pattern, or a singular denominator. */
EXPORT int bank_augmented_expm(int d, double *m) {
    if (d < 4 || d > MAX_AUGMENTED || d % 2) return -1;
    int n = (d - 2) / 2, s = 2 * n, t = s + 1;
    Augmented compact;
    compact.n = n;
    for (int r = 0; r < d; r++)
        for (int k = 0; k < d; k++) {
            double x = m[r * d + k];
            int block = r < s && k < s && r / n == k / n;
            if (block && r < n) compact.block[r * n + k] = x;
            else if (block) {
                double first = compact.block[(r - n) * n + k - n];
                if (x != first && !(isnan(x) && isnan(first))) return -1; /* blocks differ */
            } else if (r < s && k >= s) compact.u[r][k - s] = x;
            else if (r == s && k == s) compact.ss = x;
            else if (r == s && k == t) compact.st = x;
            else if (r == t && k == t) compact.tt = x;
            else if (x != 0.0) return -1;
        }
    if (expm(&compact) != 0) return -1;
    for (int r = 0; r < d; r++)
        for (int k = 0; k < d; k++) {
            int block = r < s && k < s && r / n == k / n;
            double x = 0.0;
            if (block) x = compact.block[(r % n) * n + k % n];
            else if (r < s && k >= s) x = compact.u[r][k - s];
            else if (r == s && k == s) x = compact.ss;
            else if (r == s && k == t) x = compact.st;
            else if (r == t && k == t) x = compact.tt;
            m[r * d + k] = x;
        }
    return 0;
}

#define ME(c, k) ((c)->model_functions[k])

/* linearised.py's Linearisation.step at the co-simulation instance's states: the load
   after `step` at `rate`, and (by_rate, stiffness_by_rate) / step. */
int linearised_step(Bank *bank, int i, double deflection, double rate, double step,
                    double *result) {
    Instance *c = &bank->instances[i];
    int n = c->n_states, status;
    double states[MAX_STATES], jacobian[(MAX_STATES + 2) * (MAX_STATES + 2)],
        derivatives[MAX_STATES], column[MAX_STATES + 2], load;
    const double seed = 1.0;
#define CHECK(call) if ((status = (call)) > STATUS_OK) \
    return fail(bank, i, FAILED_LINEARISED, status, bank->accepted[3 * i], step)
    int fmi3 = c->fmi_version == 3;
    CHECK(fmi3 ? ((Fmi3GetFloat64)c->functions[GET])(c->instance, c->state_vrs, n, states, n)
               : ((Fmi2GetReal)c->functions[GET])(c->instance, c->state_vrs, n, states));
    double inputs[2] = {deflection, rate};
    CHECK(fmi3 ? ((Fmi3SetFloat64)ME(c, ME_SET))(c->model, c->knowns + n, 2, inputs, 2)
               : ((Fmi2SetReal)ME(c, ME_SET))(c->model, c->knowns + n, 2, inputs));
    int contact = deflection > 0.0;
    if (c->events && contact != c->contact) {
        /* the contact's mode switches in event mode only (docs/model-exchange.md) */
        CHECK(((Fmi2Mode)ME(c, ME_EVENT_MODE))(c->model));
        int again;
        do {
            if (fmi3) {
                bool update = false, terminate = false, nominals = false, values = false,
                     defined = false;
                double next = 0.0;
                CHECK(((Fmi3UpdateDiscreteStates)ME(c, ME_NEW_DISCRETE_STATES))(
                    c->model, &update, &terminate, &nominals, &values, &defined, &next));
                again = update;
            } else {
                Fmi2EventInfo info;
                memset(&info, 0, sizeof info);
                CHECK(((Fmi2NewDiscreteStates)ME(c, ME_NEW_DISCRETE_STATES))(c->model, &info));
                again = info.new_discrete_states_needed;
            }
        } while (again);
        CHECK(((Fmi2Mode)ME(c, ME_CONTINUOUS_MODE))(c->model));
        c->contact = contact;
    }
    CHECK(((Fmi2SetStates)ME(c, ME_SET_STATES))(c->model, states, n));
    int m2 = n + 2;
    for (int j = 0; j < m2; j++) {
        CHECK(fmi3 ? ((Fmi3Directional)ME(c, ME_DIRECTIONAL))(c->model, c->unknowns, m2,
                                                               &c->knowns[j], 1, &seed, 1,
                                                               column, m2)
                   : ((Fmi2Directional)ME(c, ME_DIRECTIONAL))(c->model, c->unknowns, m2,
                                                               &c->knowns[j], 1, &seed,
                                                               column));
        for (int r = 0; r < m2; r++) jacobian[r * m2 + j] = column[r];
    }
    CHECK(((Fmi2GetDerivatives)ME(c, ME_DERIVATIVES))(c->model, derivatives, n));
    CHECK(fmi3 ? ((Fmi3GetFloat64)ME(c, ME_GET))(c->model, &c->unknowns[n], 1, &load, 1)
               : ((Fmi2GetReal)ME(c, ME_GET))(c->model, &c->unknowns[n], 1, &load));
#undef CHECK
#define J(r, k) jacobian[(r) * m2 + (k)]
    /* augmented state [Y, P, s, 1]: Y the drift at rate v0, P = dY/dv */
    Augmented m;
    m.n = n;
    for (int r = 0; r < n; r++) {
        for (int k = 0; k < n; k++) m.block[r * n + k] = J(r, k) * step;
        m.u[r][0] = (J(r, n) * rate) * step;
        m.u[r][1] = derivatives[r] * step;
        m.u[n + r][0] = J(r, n) * step;
        m.u[n + r][1] = J(r, n + 1) * step;
    }
    m.ss = 0.0 * step;
    m.st = 1.0 * step;
    m.tt = 0.0 * step;
    if (expm(&m) != 0) return fail(bank, i, FAILED_LINEARISED, 0, bank->accepted[3 * i], step);
    double drift = 0.0, by_rate = 0.0, stiffness_by_rate = 0.0;
    for (int k = 0; k < n; k++) {
        drift += J(n, k) * m.u[k][1];
        by_rate += J(n, k) * m.u[n + k][1];
        stiffness_by_rate += J(n + 1, k) * m.u[n + k][1];
    }
    result[0] = load + drift + J(n, n) * rate * step;
    result[1] = (by_rate + J(n, n) * step + J(n, n + 1)) / step;
    result[2] = (stiffness_by_rate + J(n + 1, n) * step + J(n + 1, n + 1)) / step;
#undef J
    return 0;
}

/* fmu.py's predicted_law of a linearised component */
int predicted_law(Bank *bank, int i, double time) {
    const double *accepted = bank->accepted + 3 * i;
    double step = time - accepted[0], result[3];
    if (linearised_step(bank, i, accepted[1], accepted[2], step, result) != 0) return FAILED;
    set_law(bank, i, accepted[1] + accepted[2] * step, result[0], result[1], 0.0);
    return 0;
}
