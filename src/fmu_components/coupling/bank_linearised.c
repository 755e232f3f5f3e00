/*
 * The bank's linearised step: linearised.py's Linearisation.step in C, for the instances
 * whose law is their linearised answer to a step (the damper; the tyre where its tangent
 * changes over the step). Built with bank.c, as bank.c is.
 */
#include "bank.h"

/* --- the linearised step (linearised.py) ----------------------------------------------- */

#define MAX_AUGMENTED (2 * MAX_STATES + 2)

/* C = A B for d x d matrices of linearised_step's augmented pattern (d = 2n + 2: two
   n x n blocks on the diagonal, the last two columns, and the upper triangular 2 x 2
   corner; its powers, their sums and products keep it), row-major. Each entry is the sum
   of its products in the order of the inner index from +0, as in a full product, without
   the products by the pattern's zeros: each is +0 or -0 (the entries are finite), and
   adding it to a sum from +0 changes nothing, so the bits are a full product's (and
   linearised.py's _multiply's with the pattern). */
static void multiply(int d, const double *a, const double *b, double *c) {
    int n = (d - 2) / 2, s = 2 * n, t = s + 1;
    for (int k = 0; k < d * d; k++) c[k] = 0.0;
    for (int block = 0; block < s; block += n)
        for (int r = block; r < block + n; r++) {
            const double *row = a + r * d;
            double *out = c + r * d;
            for (int k = block; k < block + n; k++) {
                double sum = 0.0;
                for (int j = block; j < block + n; j++) sum += row[j] * b[j * d + k];
                out[k] = sum;
            }
            double last = 0.0, next = 0.0; /* the columns s and t */
            for (int j = block; j < block + n; j++) {
                last += row[j] * b[j * d + s];
                next += row[j] * b[j * d + t];
            }
            last += row[s] * b[s * d + s];
            next += row[s] * b[s * d + t];
            next += row[t] * b[t * d + t];
            out[s] = last;
            out[t] = next;
        }
    double corner = 0.0;
    c[s * d + s] = corner + a[s * d + s] * b[s * d + s];
    corner = 0.0;
    corner += a[s * d + s] * b[s * d + t];
    corner += a[s * d + t] * b[t * d + t];
    c[s * d + t] = corner;
    corner = 0.0;
    c[t * d + t] = corner + a[t * d + t] * b[t * d + t];
}

/* Solve A X = B (d x d, overwritten), Gaussian elimination with partial pivoting. */
static int solve(int d, double *a, double *b) {
    for (int col = 0; col < d; col++) {
        int pivot = col;
        for (int r = col + 1; r < d; r++)
            if (fabs(a[r * d + col]) > fabs(a[pivot * d + col])) pivot = r;
        if (a[pivot * d + col] == 0.0) return -1;
        if (pivot != col)
            for (int k = 0; k < d; k++) {
                double t = a[col * d + k];
                a[col * d + k] = a[pivot * d + k];
                a[pivot * d + k] = t;
                t = b[col * d + k];
                b[col * d + k] = b[pivot * d + k];
                b[pivot * d + k] = t;
            }
        for (int r = col + 1; r < d; r++) {
            double f = a[r * d + col] / a[col * d + col];
            if (f == 0.0) continue;
            for (int k = col; k < d; k++) a[r * d + k] -= f * a[col * d + k];
            for (int k = 0; k < d; k++) b[r * d + k] -= f * b[col * d + k];
        }
    }
    for (int r = d - 1; r >= 0; r--)
        for (int k = 0; k < d; k++) {
            double sum = b[r * d + k];
            for (int j = r + 1; j < d; j++) sum -= a[r * d + j] * b[j * d + k];
            b[r * d + k] = sum / a[r * d + r];
        }
    return 0;
}

/* e^M (d x d, into m): linearised.py's expm, diagonal Pade (6, 6) after scaling to a
   norm of 1/2, then squaring (Higham, Functions of Matrices, ch. 10). */
static int expm(int d, double *m) {
    double norm = 0.0;
    for (int k = 0; k < d; k++) {
        double column = 0.0;
        for (int r = 0; r < d; r++) column += fabs(m[r * d + k]);
        if (column > norm) norm = column;
    }
    int squarings = norm > 0.5 ? (int)ceil(log2(norm / 0.5)) : 0;
    if (squarings < 0) squarings = 0;
    static const double coefficients[7] = {1.0, 1.0 / 2, 5.0 / 44, 1.0 / 66, 1.0 / 792,
                                           1.0 / 15840, 1.0 / 665280};
    double scaled[MAX_AUGMENTED * MAX_AUGMENTED], power[MAX_AUGMENTED * MAX_AUGMENTED],
        next[MAX_AUGMENTED * MAX_AUGMENTED], even[MAX_AUGMENTED * MAX_AUGMENTED],
        odd[MAX_AUGMENTED * MAX_AUGMENTED];
    double scale = ldexp(1.0, -squarings);
    for (int k = 0; k < d * d; k++) {
        scaled[k] = m[k] * scale;
        power[k] = even[k] = odd[k] = 0.0;
    }
    for (int k = 0; k < d; k++) power[k * d + k] = even[k * d + k] = 1.0;
    for (int p = 1; p <= 6; p++) {
        multiply(d, power, scaled, next);
        memcpy(power, next, sizeof(double) * d * d);
        double *sum = p % 2 ? odd : even;
        for (int k = 0; k < d * d; k++) sum[k] += coefficients[p] * power[k];
    }
    for (int k = 0; k < d * d; k++) {
        double e = even[k], o = odd[k];
        even[k] = e - o; /* the denominator */
        m[k] = e + o;    /* the numerator, then the result */
    }
    if (solve(d, even, m) != 0) return -1;
    for (int s = 0; s < squarings; s++) {
        multiply(d, m, m, next);
        memcpy(m, next, sizeof(double) * d * d);
    }
    return 0;
}

/* expm of an augmented matrix for linearised.py, which has it in Python too (the same
   bits) and calls this where the library is built */
EXPORT int bank_augmented_expm(int d, double *m) {
    if (d < 4 || d > MAX_AUGMENTED || d % 2) return -1;
    return expm(d, m);
}

#define ME(c, k) ((c)->model_functions[k])

/* linearised.py's Linearisation.step at the co-simulation instance's states: the load
   after `step` at `rate`, and (by_rate, stiffness_by_rate) / step. */
int linearised_step(Bank *bank, int i, double deflection, double rate, double step,
                    double *result) {
    Instance *c = &bank->instances[i];
    int n = c->n_states, d = 2 * n + 2, status;
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
    double m[MAX_AUGMENTED * MAX_AUGMENTED] = {0.0};
    for (int r = 0; r < n; r++) {
        for (int k = 0; k < n; k++) m[r * d + k] = m[(n + r) * d + n + k] = J(r, k);
        m[r * d + 2 * n] = J(r, n) * rate;
        m[r * d + 2 * n + 1] = derivatives[r];
        m[(n + r) * d + 2 * n] = J(r, n);
        m[(n + r) * d + 2 * n + 1] = J(r, n + 1);
    }
    m[(2 * n) * d + 2 * n + 1] = 1.0;
    for (int k = 0; k < d * d; k++) m[k] *= step;
    if (expm(d, m) != 0) return fail(bank, i, FAILED_LINEARISED, 0, bank->accepted[3 * i], step);
    double drift = 0.0, by_rate = 0.0, stiffness_by_rate = 0.0;
    for (int k = 0; k < n; k++) {
        drift += J(n, k) * m[k * d + d - 1];
        by_rate += J(n, k) * m[(n + k) * d + d - 1];
        stiffness_by_rate += J(n + 1, k) * m[(n + k) * d + d - 1];
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
