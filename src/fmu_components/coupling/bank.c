/*
 * The coupling's per-host-step work for a bank of FMU instances in one call per pass
 * (bank.py drives it; fmu.py, law.py and schemes.py are the readable reference it follows
 * operation for operation, so that both give the same numbers).
 *
 * Each instance is an FMI 2.0 or FMI 3.0 co-simulation instance that Python made and
 * initialised; the bank is handed its instance pointer and the addresses of its library's
 * functions, and calls them itself: save the state, set the inputs, step, read the
 * outputs, restore, and the load laws F(x) = F* + K_s(x) (x - x*) (law.py) the host
 * applies between FMU steps. The arrays (laws, outputs, the host's deflections) belong to
 * the caller (numpy); the bank keeps only what an instance is.
 *
 * Built with gcc -O2 -ffp-contract=off (no fused multiply-add: the same bits as Python's
 * arithmetic). Needs libc and libm only.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT __attribute__((visibility("default")))
#endif

#define BANK_VERSION 1
#define MAX_OUTPUTS 8
/* x*, F*, K, Q, K_touch (law.py's LoadLaw), then what a host's expression of the law
   needs no more than once per pass: Q/2 and the secant's bounds K/2 and 2K, low first */
#define LAW_COLUMNS 8
#define CURVED 0.01   /* fmu.py's CURVED */
#define STATUS_OK 1   /* fmi2Warning and below */

/* FMI 2.0 and 3.0 signatures of the calls the bank makes (the standards' own). */
typedef int (*Fmi2SetReal)(void *, const unsigned *, size_t, const double *);
typedef int (*Fmi2GetReal)(void *, const unsigned *, size_t, double *);
typedef int (*Fmi2DoStep)(void *, double, double, int);
typedef int (*Fmi2GetState)(void *, void **);
typedef int (*Fmi2SetState)(void *, void *);
typedef int (*Fmi2Directional)(void *, const unsigned *, size_t, const unsigned *, size_t,
                               const double *, double *);
typedef int (*Fmi3SetFloat64)(void *, const unsigned *, size_t, const double *, size_t);
typedef int (*Fmi3GetFloat64)(void *, const unsigned *, size_t, double *, size_t);
typedef int (*Fmi3DoStep)(void *, double, double, bool, bool *, bool *, bool *, double *);
typedef int (*Fmi3Directional)(void *, const unsigned *, size_t, const unsigned *, size_t,
                               const double *, size_t, double *, size_t);

typedef int (*Fmi2SetStates)(void *, const double *, size_t);
typedef int (*Fmi2GetDerivatives)(void *, double *, size_t);
typedef int (*Fmi2Mode)(void *);
typedef struct {
    int new_discrete_states_needed, terminate, nominals_changed, values_changed,
        next_event_time_defined;
    double next_event_time;
} Fmi2EventInfo;
typedef int (*Fmi2NewDiscreteStates)(void *, Fmi2EventInfo *);

enum { SET, GET, DO_STEP, GET_STATE, SET_STATE, DIRECTIONAL, FUNCTIONS };
/* a Model Exchange instance's calls, for the linearised step (linearised.py) */
enum { ME_SET, ME_GET, ME_SET_STATES, ME_DIRECTIONAL, ME_DERIVATIVES, ME_EVENT_MODE,
       ME_NEW_DISCRETE_STATES, ME_CONTINUOUS_MODE, ME_FUNCTIONS };
#define MAX_STATES 8
/* what failed, for bank.py's message */
enum { FAILED_NONE, FAILED_SET, FAILED_GET, FAILED_DO_STEP, FAILED_GET_STATE,
       FAILED_SET_STATE, FAILED_DIRECTIONAL, FAILED_NOT_FINITE, FAILED_NO_STEP,
       FAILED_LINEARISED };
/* flags of an instance */
enum { UNILATERAL = 1, STEP_TANGENT = 2, CURVATURE = 4, LINEARISABLE = 8, LINEARISED = 16 };
/* schemes (schemes.py) */
enum { EXPLICIT, CORRECTED, CONVERGED };
/* end_pass's verdicts */
enum { ACCEPT = 0, REPEAT = 1, RETRY = 2, FAILED = -1, BUSY = -2 };

typedef struct {
    int fmi_version; /* 2 or 3 */
    void *functions[FUNCTIONS];
    void *instance;
    void *state; /* the one saved state, reused */
    unsigned inputs[2], outputs[MAX_OUTPUTS], stiffness_vr;
    int n_outputs, load, stiffness; /* indices into the outputs */
    int flags;
    int stepped, saved, tried;
    double trial_deflection, trial_secant;
    /* its Model Exchange side instance (linearised.py), where the bank linearises */
    void *model;
    void *model_functions[ME_FUNCTIONS];
    int n_states, events, contact;
    unsigned state_vrs[MAX_STATES], unknowns[MAX_STATES + 2], knowns[MAX_STATES + 2];
} Instance;

typedef struct {
    int n, scheme, passes;
    double tolerance;
    Instance *instances;
    /* the caller's arrays (bank.py): rows of n */
    const double *deflection;   /* the host's, read at end_pass */
    double *laws;               /* n x LAW_COLUMNS */
    double *accepted;           /* n x 3: time, deflection, secant rate of the last step */
    double *outputs;            /* n x MAX_OUTPUTS after the last accepted step */
    double *trial_outputs;      /* n x MAX_OUTPUTS after the last trial */
    double *seen;               /* n x 2: peak |load|, the last contact stiffness */
    int64_t *counts;            /* n x 3: doSteps, saves, restores */
    int *flagged;               /* instances whose law Python makes (linearised) */
    int n_flagged;
    /* the last failure */
    int failed_instance, failed_call, failed_status, failed_output;
    double failed_time, failed_step;
    int busy;
} Bank;

EXPORT int bank_version(void) { return BANK_VERSION; }

EXPORT Bank *bank_new(int n) {
    Bank *bank = calloc(1, sizeof(Bank));
    if (bank == NULL) return NULL;
    bank->instances = calloc(n > 0 ? n : 1, sizeof(Instance));
    if (bank->instances == NULL) {
        free(bank);
        return NULL;
    }
    bank->n = n;
    return bank;
}

EXPORT void bank_bind(Bank *bank, const double *deflection, double *laws, double *accepted,
                      double *outputs, double *trial_outputs, double *seen, int64_t *counts,
                      int *flagged) {
    bank->deflection = deflection;
    bank->laws = laws;
    bank->accepted = accepted;
    bank->outputs = outputs;
    bank->trial_outputs = trial_outputs;
    bank->seen = seen;
    bank->counts = counts;
    bank->flagged = flagged;
}

EXPORT void bank_set_scheme(Bank *bank, int scheme, int passes, double tolerance) {
    bank->scheme = scheme;
    bank->passes = passes;
    bank->tolerance = tolerance;
}

/* vrs: deflection, rate, stiffness, then the n_outputs outputs. */
EXPORT int bank_set_instance(Bank *bank, int i, int fmi_version, void *instance,
                             void **functions, const unsigned *vrs, int n_outputs, int load,
                             int stiffness, int flags) {
    if (i < 0 || i >= bank->n || n_outputs < 1 || n_outputs > MAX_OUTPUTS) return -1;
    Instance *c = &bank->instances[i];
    c->fmi_version = fmi_version;
    c->instance = instance;
    memcpy(c->functions, functions, sizeof c->functions);
    c->inputs[0] = vrs[0];
    c->inputs[1] = vrs[1];
    c->stiffness_vr = vrs[2];
    memcpy(c->outputs, vrs + 3, sizeof(unsigned) * n_outputs);
    c->n_outputs = n_outputs;
    c->load = load;
    c->stiffness = stiffness;
    c->flags = flags;
    return 0;
}

/* The Model Exchange instance that linearises instance i's step: vrs are the states
   (n), the derivatives (n), the load, the stiffness, the deflection and the rate. */
EXPORT int bank_set_model(Bank *bank, int i, void *model, void **functions, int n_states,
                          const unsigned *vrs, int events) {
    if (i < 0 || i >= bank->n || n_states < 1 || n_states > MAX_STATES) return -1;
    Instance *c = &bank->instances[i];
    c->model = model;
    memcpy(c->model_functions, functions, sizeof c->model_functions);
    c->n_states = n_states;
    for (int k = 0; k < n_states; k++) {
        c->state_vrs[k] = c->knowns[k] = vrs[k];
        c->unknowns[k] = vrs[n_states + k];
    }
    c->unknowns[n_states] = vrs[2 * n_states];
    c->unknowns[n_states + 1] = vrs[2 * n_states + 1];
    c->knowns[n_states] = vrs[2 * n_states + 2];
    c->knowns[n_states + 1] = vrs[2 * n_states + 3];
    c->events = events;
    c->contact = -1; /* not known: the first linearisation sets it */
    return 0;
}

EXPORT void *bank_state(Bank *bank, int i) { return bank->instances[i].state; }

EXPORT void bank_forget_states(Bank *bank) {
    for (int i = 0; i < bank->n; i++) bank->instances[i].state = NULL;
}

EXPORT void bank_free(Bank *bank) {
    if (bank == NULL) return;
    free(bank->instances);
    free(bank);
}

EXPORT void bank_failure(Bank *bank, int *instance, int *call, int *status, int *output,
                         double *time, double *step) {
    *instance = bank->failed_instance;
    *call = bank->failed_call;
    *status = bank->failed_status;
    *output = bank->failed_output;
    *time = bank->failed_time;
    *step = bank->failed_step;
}

/* --- FMI calls, either version ----------------------------------------------------------- */

static int set_inputs(Instance *c, const double *values) {
    if (c->fmi_version == 3)
        return ((Fmi3SetFloat64)c->functions[SET])(c->instance, c->inputs, 2, values, 2);
    return ((Fmi2SetReal)c->functions[SET])(c->instance, c->inputs, 2, values);
}

static int get_outputs(Instance *c, double *values) {
    if (c->fmi_version == 3)
        return ((Fmi3GetFloat64)c->functions[GET])(c->instance, c->outputs, c->n_outputs,
                                                   values, c->n_outputs);
    return ((Fmi2GetReal)c->functions[GET])(c->instance, c->outputs, c->n_outputs, values);
}

static int do_step(Instance *c, double time, double step) {
    if (c->fmi_version == 3) {
        bool event = false, terminate = false, early = false;
        double reached = 0.0;
        return ((Fmi3DoStep)c->functions[DO_STEP])(c->instance, time, step, true, &event,
                                                   &terminate, &early, &reached);
    }
    return ((Fmi2DoStep)c->functions[DO_STEP])(c->instance, time, step, 1);
}

static int save_state(Instance *c) {
    return ((Fmi2GetState)c->functions[GET_STATE])(c->instance, &c->state);
}

static int restore_state(Instance *c) {
    return ((Fmi2SetState)c->functions[SET_STATE])(c->instance, c->state);
}

static int stiffness_by_deflection(Instance *c, double *value) {
    const double seed = 1.0;
    if (c->fmi_version == 3)
        return ((Fmi3Directional)c->functions[DIRECTIONAL])(c->instance, &c->stiffness_vr, 1,
                                                            &c->inputs[0], 1, &seed, 1, value, 1);
    return ((Fmi2Directional)c->functions[DIRECTIONAL])(c->instance, &c->stiffness_vr, 1,
                                                        &c->inputs[0], 1, &seed, value);
}

static int fail(Bank *bank, int i, int call, int status, double time, double step) {
    bank->failed_instance = i;
    bank->failed_call = call;
    bank->failed_status = status;
    bank->failed_time = time;
    bank->failed_step = step;
    return FAILED;
}

/* --- load laws (law.py) ---------------------------------------------------------------- */

static double secant(const double *law, double x) {
    double k = law[2];
    if (law[3] == 0.0) return k;
    double s = k + 0.5 * law[3] * (x - law[0]);
    double low = k >= 0.0 ? 0.5 * k : 2.0 * k, high = k >= 0.0 ? 2.0 * k : 0.5 * k;
    /* Python's min(max(s, low), high): the first of equals, NaN as it compares */
    double clamped = low > s ? low : s;
    return high < clamped ? high : clamped;
}

static double law_load(const double *law, int unilateral, double x) {
    if (unilateral) {
        if (x <= 0.0) return 0.0;
        if (law[1] <= 0.0) {
            double touch = law[4] * (x - (law[0] > 0.0 ? law[0] : 0.0));
            return touch > 0.0 ? touch : 0.0;
        }
    }
    double load = law[1] + secant(law, x) * (x - law[0]);
    return unilateral ? (load > 0.0 ? load : 0.0) : load;
}

/* The loads of the current laws at the host's deflections, and their slopes. */
EXPORT void bank_law_loads(const Bank *bank, const double *deflection, double *loads,
                           double *slopes) {
    for (int i = 0; i < bank->n; i++) {
        const double *law = bank->laws + (size_t)i * LAW_COLUMNS;
        int unilateral = bank->instances[i].flags & UNILATERAL;
        double x = deflection[i];
        loads[i] = law_load(law, unilateral, x);
        if (slopes != NULL) {
            double dx = 1e-9 * (fabs(x) > 1e-6 ? fabs(x) : 1e-6);
            slopes[i] = (law_load(law, unilateral, x + dx) - law_load(law, unilateral, x - dx))
                        / (2.0 * dx);
        }
    }
}

static void set_law(Bank *bank, int i, double x, double load, double k, double q) {
    double *law = bank->laws + (size_t)i * LAW_COLUMNS;
    law[0] = x;
    law[1] = load;
    law[2] = k;
    law[3] = q;
    law[4] = bank->seen[2 * i + 1];
    law[5] = 0.5 * q;
    law[6] = k >= 0.0 ? 0.5 * k : 2.0 * k;
    law[7] = k >= 0.0 ? 2.0 * k : 0.5 * k;
}

/* fmu.py's lagged_law: about the last accepted step */
static void lagged_law(Bank *bank, int i) {
    const Instance *c = &bank->instances[i];
    const double *out = bank->outputs + (size_t)i * MAX_OUTPUTS;
    set_law(bank, i, bank->accepted[3 * i + 1], out[c->load],
            (c->flags & STEP_TANGENT) ? out[c->stiffness] : 0.0, 0.0);
}

EXPORT void bank_lagged_laws(Bank *bank) {
    for (int i = 0; i < bank->n; i++) lagged_law(bank, i);
}

/* --- the linearised step (linearised.py) ----------------------------------------------- */

/* C = A B for d x d matrices, row-major */
static void multiply(int d, const double *a, const double *b, double *c) {
    for (int r = 0; r < d; r++)
        for (int k = 0; k < d; k++) {
            double sum = 0.0;
            for (int j = 0; j < d; j++) sum += a[r * d + j] * b[j * d + k];
            c[r * d + k] = sum;
        }
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

#define MAX_AUGMENTED (2 * MAX_STATES + 2)

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

#define ME(c, k) ((c)->model_functions[k])

/* linearised.py's Linearisation.step at the co-simulation instance's states: the load
   after `step` at `rate`, and (by_rate, stiffness_by_rate) / step. */
static int linearised_step(Bank *bank, int i, double deflection, double rate, double step,
                           double *result) {
    Instance *c = &bank->instances[i];
    int n = c->n_states, d = 2 * n + 2, status;
    double states[MAX_STATES], jacobian[(MAX_STATES + 2) * (MAX_STATES + 2)],
        derivatives[MAX_STATES], column[MAX_STATES + 2], load;
    const double seed = 1.0;
#define CHECK(call) if ((status = (call)) > STATUS_OK) \
    return fail(bank, i, FAILED_LINEARISED, status, bank->accepted[3 * i], step)
    CHECK(((Fmi2GetReal)c->functions[GET])(c->instance, c->state_vrs, n, states));
    double inputs[2] = {deflection, rate};
    CHECK(((Fmi2SetReal)ME(c, ME_SET))(c->model, c->knowns + n, 2, inputs));
    int contact = deflection > 0.0;
    if (c->events && contact != c->contact) {
        /* the contact's mode switches in event mode only (docs/model-exchange.md) */
        Fmi2EventInfo info;
        CHECK(((Fmi2Mode)ME(c, ME_EVENT_MODE))(c->model));
        do {
            memset(&info, 0, sizeof info);
            CHECK(((Fmi2NewDiscreteStates)ME(c, ME_NEW_DISCRETE_STATES))(c->model, &info));
        } while (info.new_discrete_states_needed);
        CHECK(((Fmi2Mode)ME(c, ME_CONTINUOUS_MODE))(c->model));
        c->contact = contact;
    }
    CHECK(((Fmi2SetStates)ME(c, ME_SET_STATES))(c->model, states, n));
    int m2 = n + 2;
    for (int j = 0; j < m2; j++) {
        CHECK(((Fmi2Directional)ME(c, ME_DIRECTIONAL))(c->model, c->unknowns, m2,
                                                        &c->knowns[j], 1, &seed, column));
        for (int r = 0; r < m2; r++) jacobian[r * m2 + j] = column[r];
    }
    CHECK(((Fmi2GetDerivatives)ME(c, ME_DERIVATIVES))(c->model, derivatives, n));
    CHECK(((Fmi2GetReal)ME(c, ME_GET))(c->model, &c->unknowns[n], 1, &load));
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
static int predicted_law(Bank *bank, int i, double time) {
    const double *accepted = bank->accepted + 3 * i;
    double step = time - accepted[0], result[3];
    if (linearised_step(bank, i, accepted[1], accepted[2], step, result) != 0) return FAILED;
    set_law(bank, i, accepted[1] + accepted[2] * step, result[0], result[1], 0.0);
    return 0;
}

/* --- the step protocol (master.py) ----------------------------------------------------- */

static int restore(Bank *bank, int i) {
    Instance *c = &bank->instances[i];
    int status = restore_state(c);
    if (status > STATUS_OK)
        return fail(bank, i, FAILED_SET_STATE, status, bank->accepted[3 * i], 0.0);
    bank->counts[3 * i + 2]++;
    c->stepped = 0;
    return 0;
}

/* Every instance: undo a trial of a step given up, save the state, and the first law.
   Instances whose first law is their linearised step are listed in `flagged`. */
EXPORT int bank_begin_step(Bank *bank, double time) {
    if (__sync_lock_test_and_set(&bank->busy, 1)) return BUSY;
    int result = 0;
    bank->n_flagged = 0;
    for (int i = 0; i < bank->n && result == 0; i++) {
        Instance *c = &bank->instances[i];
        if (c->stepped && (result = restore(bank, i)) != 0) break;
        int status = save_state(c);
        if (status > STATUS_OK) {
            result = fail(bank, i, FAILED_GET_STATE, status, bank->accepted[3 * i], 0.0);
            break;
        }
        bank->counts[3 * i + 1]++;
        c->saved = 1;
        c->tried = 0;
        lagged_law(bank, i);
        if (bank->scheme != EXPLICIT && (c->flags & LINEARISED)) {
            if (c->model == NULL)
                bank->flagged[bank->n_flagged++] = i;
            else if ((result = predicted_law(bank, i, time)) != 0)
                break;
        }
    }
    __sync_lock_release(&bank->busy);
    return result == 0 ? bank->n_flagged : result;
}

/* fmu.py's trial: from the last accepted point along the secant to (time, x), in `pieces`
   doSteps; 1 for a discarded step (restored), FAILED for an error. */
static int trial(Bank *bank, int i, double time, int pieces) {
    Instance *c = &bank->instances[i];
    double *accepted = bank->accepted + 3 * i;
    double step = time - accepted[0];
    if (!(step > 0.0)) return fail(bank, i, FAILED_NO_STEP, 0, time, step);
    if (c->stepped && restore(bank, i) != 0) return FAILED;
    double x = bank->deflection[i];
    double rate = (x - accepted[1]) / step;
    c->stepped = 1;
    double piece = step / pieces;
    for (int k = 0; k < pieces; k++) {
        double start = accepted[0] + k * piece;
        double inputs[2] = {accepted[1] + rate * k * piece, rate};
        int status = set_inputs(c, inputs);
        if (status > STATUS_OK) return fail(bank, i, FAILED_SET, status, start, piece);
        bank->counts[3 * i]++;
        status = do_step(c, start, piece);
        if (status == 2) { /* Discard */
            fail(bank, i, FAILED_DO_STEP, status, start, piece);
            if (restore(bank, i) != 0) return FAILED;
            return 1;
        }
        if (status > STATUS_OK) return fail(bank, i, FAILED_DO_STEP, status, start, piece);
    }
    double *out = bank->trial_outputs + (size_t)i * MAX_OUTPUTS;
    int status = get_outputs(c, out);
    if (status > STATUS_OK) return fail(bank, i, FAILED_GET, status, time, step);
    for (int k = 0; k < c->n_outputs; k++)
        if (!isfinite(out[k])) {
            bank->failed_output = k;
            return fail(bank, i, FAILED_NOT_FINITE, 0, time, step);
        }
    double *seen = bank->seen + 2 * i;
    if (fabs(out[c->load]) > seen[0]) seen[0] = fabs(out[c->load]);
    if (out[c->stiffness] > 0.0) seen[1] = out[c->stiffness];
    c->trial_deflection = x;
    c->trial_secant = rate;
    c->tried = 1;
    return 0;
}

/* fmu.py's corrected_law, except the linearised steps (flagged for Python). */
static int corrected_law(Bank *bank, int i, double time) {
    Instance *c = &bank->instances[i];
    const double *out = bank->trial_outputs + (size_t)i * MAX_OUTPUTS;
    double x = bank->deflection[i], stiffness = out[c->stiffness], curvature = 0.0;
    if (c->flags & CURVATURE) {
        int status = stiffness_by_deflection(c, &curvature);
        if (status > STATUS_OK) return fail(bank, i, FAILED_DIRECTIONAL, status, time, 0.0);
    }
    set_law(bank, i, x, out[c->load], stiffness, curvature);
    const double *accepted = bank->accepted + 3 * i;
    int linearised = c->flags & LINEARISED;
    if (!linearised
        && !((c->flags & LINEARISABLE)
             && fabs(curvature * (x - accepted[1])) > CURVED * fabs(stiffness)))
        return 0;
    if (c->model == NULL) {
        bank->flagged[bank->n_flagged++] = i;
        return 0;
    }
    double step = time - accepted[0], result[3];
    if (linearised_step(bank, i, x, (x - accepted[1]) / step, step, result) != 0) return FAILED;
    double *law = bank->laws + (size_t)i * LAW_COLUMNS;
    if (linearised) {
        /* the same shape of the elastic force, reached through the step's tangent */
        double ratio = stiffness != 0.0 ? result[1] / stiffness : 0.0;
        set_law(bank, i, x, law[1], result[1],
                stiffness != 0.0 ? curvature * (ratio * ratio) : 0.0);
    } else {
        set_law(bank, i, x, law[1], law[2], result[2]);
    }
    return 0;
}

/* After the host's solve to `time` (its deflections in the bound array): step every
   instance, judge the pass (the scheme's mismatch, written to *mismatch), and on REPEAT
   the next laws (instances to linearise listed in `flagged`, *n_flagged of them). A
   discarded step restores the whole bank (RETRY); a host that cannot retry has the
   instance's step cut into up to `max_pieces` pieces instead. */
EXPORT int bank_end_pass(Bank *bank, double time, int pass, int max_pieces,
                         double *mismatch, int *n_flagged, int *cut) {
    if (__sync_lock_test_and_set(&bank->busy, 1)) return BUSY;
    int verdict = ACCEPT;
    double worst = 0.0;
    bank->n_flagged = 0;
    *cut = 0;
    for (int i = 0; i < bank->n; i++) {
        int pieces = 1, result;
        while ((result = trial(bank, i, time, pieces)) == 1 && pieces < max_pieces) {
            pieces *= 2;
            (*cut)++;
        }
        if (result == 1) {
            for (int j = 0; j < bank->n; j++)
                if (bank->instances[j].stepped && restore(bank, j) != 0) {
                    verdict = FAILED;
                    break;
                }
            if (verdict != FAILED) verdict = RETRY;
            goto done;
        }
        if (result != 0) {
            verdict = FAILED;
            goto done;
        }
    }
    for (int i = 0; i < bank->n; i++) {
        const Instance *c = &bank->instances[i];
        const double *out = bank->trial_outputs + (size_t)i * MAX_OUTPUTS;
        double load = out[c->load];
        double scale = bank->seen[2 * i] > fabs(load) ? bank->seen[2 * i] : fabs(load);
        if (scale < 1e-12) scale = 1e-12;
        double off = fabs(load - law_load(bank->laws + (size_t)i * LAW_COLUMNS,
                                          c->flags & UNILATERAL, bank->deflection[i])) / scale;
        if (off > worst || i == 0) worst = off;
    }
    if (pass >= bank->passes || worst <= bank->tolerance) goto done;
    verdict = REPEAT;
    for (int i = 0; i < bank->n; i++)
        if (corrected_law(bank, i, time) != 0) {
            verdict = FAILED;
            break;
        }
done:
    *mismatch = worst;
    *n_flagged = bank->n_flagged;
    __sync_lock_release(&bank->busy);
    return verdict;
}

/* The host accepted its step: every instance's last trial becomes its accepted point. */
EXPORT int bank_accept(Bank *bank, double time) {
    for (int i = 0; i < bank->n; i++) {
        Instance *c = &bank->instances[i];
        if (!c->tried) return fail(bank, i, FAILED_NO_STEP, 0, time, 0.0);
        double *accepted = bank->accepted + 3 * i;
        accepted[0] = time;
        accepted[1] = c->trial_deflection;
        accepted[2] = c->trial_secant;
        memcpy(bank->outputs + (size_t)i * MAX_OUTPUTS,
               bank->trial_outputs + (size_t)i * MAX_OUTPUTS, sizeof(double) * MAX_OUTPUTS);
        c->stepped = c->saved = c->tried = 0;
    }
    return 0;
}

/* The host gave its step up: every instance back to its last accepted point. */
EXPORT int bank_reject(Bank *bank) {
    for (int i = 0; i < bank->n; i++) {
        Instance *c = &bank->instances[i];
        if (c->stepped && restore(bank, i) != 0) return FAILED;
        c->tried = 0;
    }
    return 0;
}
