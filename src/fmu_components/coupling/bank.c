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
#include "bank.h"

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

EXPORT void bank_bind_call(Bank *bank, BankCall *call) { bank->call = call; }

/* fmu.py's kinked_first_law, for every instance (bank.py's kink_first_laws) */
EXPORT void bank_kink_first_laws(Bank *bank, int on) { bank->kinked_first_laws = on; }

EXPORT void bank_set_scheme(Bank *bank, int scheme, int passes, int least_passes,
                            double tolerance) {
    bank->scheme = scheme;
    bank->passes = passes;
    bank->least_passes = least_passes;
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

static int get_stiffness(Instance *c, double *value) {
    if (c->fmi_version == 3)
        return ((Fmi3GetFloat64)c->functions[GET])(c->instance, &c->stiffness_vr, 1, value, 1);
    return ((Fmi2GetReal)c->functions[GET])(c->instance, &c->stiffness_vr, 1, value);
}

int fail(Bank *bank, int i, int call, int status, double time, double step) {
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

/* law.py's LoadLaw._about: the law about x* along its secant, without the kink or the contact */
static double about(const double *law, double x) { return law[1] + secant(law, x) * (x - law[0]); }

static double law_load(const double *law, int unilateral, double x) {
    if (unilateral) {
        if (x <= 0.0) return 0.0;
        if (law[1] <= 0.0) {
            double touch = law[4] * (x - (law[0] > 0.0 ? law[0] : 0.0));
            return touch > 0.0 ? touch : 0.0;
        }
    }
    double load = law[11] * (x - law[8]) < 0.0 ? law[9] + law[10] * (x - law[8])
                                                : about(law, x);
    return unilateral ? (load > 0.0 ? load : 0.0) : load;
}

/* A law's load at x and (where `slope` is not NULL) its slope: a central difference of the
   load over 1e-9 of max(|x|, 1e-6) either side (the law's kinks and clamps included) */
static void law_at(const double *law, int unilateral, double x, double *load, double *slope) {
    *load = law_load(law, unilateral, x);
    if (slope != NULL) {
        double dx = 1e-9 * (fabs(x) > 1e-6 ? fabs(x) : 1e-6);
        *slope = (law_load(law, unilateral, x + dx) - law_load(law, unilateral, x - dx))
                 / (2.0 * dx);
    }
}

/* The loads of the current laws at the host's deflections, and their slopes. */
EXPORT void bank_law_loads(const Bank *bank, const double *deflection, double *loads,
                           double *slopes) {
    for (int i = 0; i < bank->n; i++)
        law_at(bank->laws + (size_t)i * LAW_COLUMNS, bank->instances[i].flags & UNILATERAL,
               deflection[i], loads + i, slopes != NULL ? slopes + i : NULL);
}

/* bank_law_loads over laws kept apart from their bank (bank.h's LawTable), the same
   operations: a bank's laws of one moment evaluated after the bank is gone. */
EXPORT void law_table_loads(const LawTable *table, const double *deflection, double *loads,
                            double *slopes) {
    for (int i = 0; i < table->n; i++)
        law_at(table->laws + (size_t)i * LAW_COLUMNS, table->unilateral[i], deflection[i],
               loads + i, slopes != NULL ? slopes + i : NULL);
}

static void set_kink(Bank *bank, int i, double kink, double beyond, double side);

void set_law(Bank *bank, int i, double x, double load, double k, double q) {
    double *law = bank->laws + (size_t)i * LAW_COLUMNS;
    law[0] = x;
    law[1] = load;
    law[2] = k;
    law[3] = q;
    law[4] = bank->seen[2 * i + 1];
    law[5] = 0.5 * q;
    law[6] = k >= 0.0 ? 0.5 * k : 2.0 * k;
    law[7] = k >= 0.0 ? 2.0 * k : 0.5 * k;
    set_kink(bank, i, x, k, 0.0);
}

/* law.py's kink: beyond `kink` on the side opposite `side`, the tangent `beyond` from the
   law's load there (side 0: none) */
static void set_kink(Bank *bank, int i, double kink, double beyond, double side) {
    double *law = bank->laws + (size_t)i * LAW_COLUMNS;
    law[8] = kink;
    law[9] = about(law, kink);
    law[10] = beyond;
    law[11] = side;
}

static double sign_of(double value) { return value > 0.0 ? 1.0 : value < 0.0 ? -1.0 : 0.0; }

/* fmu.py's reversible_law: about the last accepted step with the tangent of its direction,
   or where the step may reverse (the last rate changed by as much as it extrapolates to)
   the mean of the tangents for motion either way; the other way's is the stiffness output
   at the mirrored rate */
static int reversible_law(Bank *bank, int i) {
    Instance *c = &bank->instances[i];
    const double *accepted = bank->accepted + 3 * i;
    const double *out = bank->outputs + (size_t)i * MAX_OUTPUTS;
    c->reverse_stiffness = out[c->stiffness];
    c->reversible = 1;
    if (accepted[2] != 0.0) {
        double inputs[2] = {accepted[1], -accepted[2]};
        int status = set_inputs(c, inputs);
        if (status > STATUS_OK) return fail(bank, i, FAILED_SET, status, accepted[0], 0.0);
        status = get_stiffness(c, &c->reverse_stiffness);
        if (status > STATUS_OK) return fail(bank, i, FAILED_GET, status, accepted[0], 0.0);
    }
    double tangent = out[c->stiffness];
    int kinked = bank->kinked_first_laws && accepted[2] != 0.0;
    if (!kinked
        && !(fabs(2.0 * accepted[2] - c->previous_rate) > fabs(accepted[2] - c->previous_rate)))
        tangent = 0.5 * (tangent + c->reverse_stiffness);
    set_law(bank, i, accepted[1], out[c->load], tangent, 0.0);
    if (kinked)  /* the kink at the accepted point: the other way's tangent beyond it */
        set_kink(bank, i, accepted[1], c->reverse_stiffness, sign_of(accepted[2]));
    return 0;
}

/* fmu.py's _reversal: the kink of a law about a trial that ended at x */
static void reversal(Bank *bank, int i, double x) {
    const Instance *c = &bank->instances[i];
    if (!c->reversible) return;
    const double *accepted = bank->accepted + 3 * i;
    double side = sign_of(x - accepted[1]);
    double beyond = side == sign_of(accepted[2])
                        ? c->reverse_stiffness
                        : bank->outputs[(size_t)i * MAX_OUTPUTS + c->stiffness];
    set_kink(bank, i, accepted[1], beyond, side);
}

/* fmu.py's lagged_law: about the last accepted step */
static void lagged_law(Bank *bank, int i) {
    const Instance *c = &bank->instances[i];
    const double *out = bank->outputs + (size_t)i * MAX_OUTPUTS;
    set_law(bank, i, bank->accepted[3 * i + 1], out[c->load],
            (c->flags & STEP_TANGENT) ? out[c->stiffness] : 0.0, 0.0);
}

/* At the start: the laws about the host's initial state, whose rates are the last ones. */
EXPORT void bank_lagged_laws(Bank *bank) {
    for (int i = 0; i < bank->n; i++) {
        bank->instances[i].previous_rate = bank->accepted[3 * i + 2];
        lagged_law(bank, i);
    }
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

/* Every instance: undo a trial of a step given up, save the state (where the saved one
   is not this step's start already: a step begun again, after a retry or a reject), and
   the first law of the step to `time`. Instances whose first law is their linearised step
   and which have no Model Exchange instance here are listed in `flagged` (their number
   returned). */
static int begin(Bank *bank, double time) {
    int result = 0;
    bank->n_flagged = 0;
    for (int i = 0; i < bank->n && result == 0; i++) {
        Instance *c = &bank->instances[i];
        if (c->stepped && (result = restore(bank, i)) != 0) break;
        if (!c->saved) {
            int status = save_state(c);
            if (status > STATUS_OK) {
                result = fail(bank, i, FAILED_GET_STATE, status, bank->accepted[3 * i], 0.0);
                break;
            }
            bank->counts[3 * i + 1]++;
            c->saved = 1;
        }
        c->tried = 0;
        c->reversible = 0;
        lagged_law(bank, i);
        if (bank->scheme != EXPLICIT && (c->flags & LINEARISED)) {
            if (c->model == NULL)
                bank->flagged[bank->n_flagged++] = i;
            else if ((result = predicted_law(bank, i, time)) != 0)
                break;
        } else if (bank->scheme != EXPLICIT && (c->flags & REVERSIBLE)
                   && (result = reversible_law(bank, i)) != 0)
            break;
    }
    return result == 0 ? bank->n_flagged : result;
}

/* The host begins a step to the call's time. */
EXPORT int bank_begin_step(Bank *bank) {
    if (__sync_lock_test_and_set(&bank->busy, 1)) return BUSY;
    bank->call->begun = NAN;
    bank->call->pass = 0;
    int result = begin(bank, bank->call->time);
    __sync_lock_release(&bank->busy);
    return result;
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
    reversal(bank, i, x);
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
        reversal(bank, i, x);
    }
    return 0;
}

/* After the host's solve to the call's time (its deflections in the bound array): step
   every instance, judge the pass (the scheme's mismatch, into the call's mismatch), and on
   REPEAT the next laws (instances to linearise listed in `flagged`, the call's n_flagged
   of them). A discarded step restores the whole bank (RETRY); a host that cannot retry has
   the instance's step cut into up to the call's max_pieces pieces instead. */
EXPORT int bank_end_pass(Bank *bank) {
    if (__sync_lock_test_and_set(&bank->busy, 1)) return BUSY;
    BankCall *call = bank->call;
    double time = call->time;
    /* the first pass of a step accept began, or the next of this one */
    int pass = !isnan(call->begun) ? (call->pass = 1) : ++call->pass;
    int max_pieces = call->max_pieces;
    call->total_passes++;
    call->begun = NAN;
    int *cut = &call->cut;
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
    if (pass >= bank->passes || (pass >= bank->least_passes && worst <= bank->tolerance))
        goto done;
    verdict = REPEAT;
    for (int i = 0; i < bank->n; i++)
        if (corrected_law(bank, i, time) != 0) {
            verdict = FAILED;
            break;
        }
done:
    call->n_flagged = bank->n_flagged;
    if (verdict == ACCEPT || verdict == REPEAT) {
        call->mismatch = worst;
        if (*cut || bank->n_flagged) verdict += NOTICE;
    }
    __sync_lock_release(&bank->busy);
    return verdict;
}

/* The host accepted its step (to the call's time): every instance's last trial becomes
   its accepted point. Where the host gives the next step's end (the call's `next`, a
   later time; NaN: none), the next step begins in the same call (`begun` is then its
   time): a host step's calls are three, not four. A begin that fails or lists instances
   for Python leaves `begun` NaN: the host's begin_step does it again and reports. */
EXPORT int bank_accept(Bank *bank) {
    BankCall *call = bank->call;
    double time = call->time;
    call->begun = NAN;
    for (int i = 0; i < bank->n; i++) {
        Instance *c = &bank->instances[i];
        if (!c->tried) return fail(bank, i, FAILED_NO_STEP, 0, time, 0.0);
        double *accepted = bank->accepted + 3 * i;
        c->previous_rate = accepted[2];
        accepted[0] = time;
        accepted[1] = c->trial_deflection;
        accepted[2] = c->trial_secant;
        memcpy(bank->outputs + (size_t)i * MAX_OUTPUTS,
               bank->trial_outputs + (size_t)i * MAX_OUTPUTS, sizeof(double) * MAX_OUTPUTS);
        c->stepped = c->saved = c->tried = 0;
    }
    if (call->next > time) {
        if (__sync_lock_test_and_set(&bank->busy, 1)) return 0;
        if (begin(bank, call->next) == 0) call->begun = call->next;
        __sync_lock_release(&bank->busy);
    }
    return 0;
}

/* The host gave its step up: every instance back to its last accepted point. */
EXPORT int bank_reject(Bank *bank) {
    bank->call->begun = NAN;
    for (int i = 0; i < bank->n; i++) {
        Instance *c = &bank->instances[i];
        if (c->stepped && restore(bank, i) != 0) return FAILED;
        c->tried = 0;
    }
    return 0;
}
