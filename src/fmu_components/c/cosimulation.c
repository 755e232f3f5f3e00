/*
 * The co-simulation step (spec section 4): runtime/cosim.py and model.py's advance,
 * statement for statement. Inputs set before doStep(tc, h) are the values at tc; over the
 * step the rate is held and the deflection moves with it; a step either completes or
 * leaves everything as it was.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "cosimulation.h"
#include "text.h"

#define N MODEL_INTEGRATED

void cosim_start(Instance *instance) {
    Snapshot *s = &instance->s;
    build_model_data(&instance->data, s->values);
    memset(&s->memory, 0, sizeof s->memory);
    s->memory.rtol = s->tolerance;
    s->time = s->start_time;
    s->deflection = s->values[INPUT_DEFLECTION];
    s->rate = s->values[INPUT_RATE];
    model_initial_state(&instance->data, s->deflection, s->rate, s->state);
    s->initialized = 1;
    instance->outputs_fresh = 0;
}

/* As FiniteGuard (runtime/cosim.py), word for word. */
static int guard_watches(double deflection, double rate) {
    return !(FINITE_DEFLECTION_LOW <= deflection && deflection <= FINITE_DEFLECTION_HIGH &&
             FINITE_RATE_LOW <= rate && rate <= FINITE_RATE_HIGH);
}

int cosim_input_problem(Instance *instance, double deflection, double rate, char *message,
                        size_t size) {
    if (!instance->s.initialized) return 0;
    if (model_input_problem(&instance->data, instance->s.state, deflection, message, size))
        return 1;
    if (!guard_watches(deflection, rate)) return 0;
    double state[SLOTS(MODEL_STATES)], outputs[MODEL_OUTPUTS];
    memcpy(state, instance->s.state, sizeof state);
    model_take_input(&instance->data, state, deflection);
    model_outputs(&instance->data, state, deflection, rate, outputs);
    int bad = first_non_finite(outputs, MODEL_OUTPUTS);
    if (bad < 0) return 0;
    const VariableInfo *x = &MODEL_INFO.variables[INPUT_DEFLECTION];
    const VariableInfo *v = &MODEL_INFO.variables[INPUT_RATE];
    char a[REPR_SIZE], b[REPR_SIZE], c[REPR_SIZE];
    snprintf(message, size, "%s = %s %s with %s = %s %s would drive %s to %s", x->name,
             format_repr(deflection, a), x->unit, v->name, format_repr(rate, b), v->unit,
             MODEL_INFO.variables[FIRST_OUTPUT + bad].name, format_repr(outputs[bad], c));
    return 1;
}

void cosim_take_inputs(Instance *instance, double deflection, double rate) {
    Snapshot *s = &instance->s;
    model_take_input(&instance->data, s->state, deflection);
    s->deflection = deflection;
    s->rate = rate;
    instance->outputs_fresh = 0;
}

typedef struct {
    double duration, rate, x; /* the rate the rubber sees, the deflection at the start */
} Segment;

/* As model.rate_segments: the whole step, or for a contact the parts in and out of it. */
static int rate_segments(double x, double v, double h, Segment *segments) {
    if (!MODEL_INFO.unilateral) {
        segments[0] = (Segment){h, v, x};
        return 1;
    }
    double x_end = x + v * h;
    if (x > 0.0 && x_end > 0.0) {
        segments[0] = (Segment){h, v, x};
        return 1;
    }
    if (x <= 0.0 && x_end <= 0.0) {
        segments[0] = (Segment){h, 0.0, x};
        return 1;
    }
    double crossing = -x / v; /* x reaches 0 inside the step */
    segments[0] = (Segment){crossing, x > 0.0 ? v : 0.0, x};
    segments[1] = (Segment){h - crossing, x > 0.0 ? 0.0 : v, x + v * crossing};
    return 2;
}

/* As Model.advance: the state is written only once the whole step has succeeded. */
static int advance(Instance *instance, double x, double v, double h, char *message,
                   size_t size) {
    Snapshot *s = &instance->s;
    double work[SLOTS(MODEL_STATES)], y[SLOTS(N)];
    memcpy(work, s->state, sizeof work);
    Segment segments[2];
    int count = rate_segments(x, v, h, segments);
    for (int k = 0; k < count; k++) {
        const Segment *segment = &segments[k];
        if (!(segment->duration > 0.0)) continue;
        if (N) {
            model_start(&instance->data, work, segment->x, y);
            char problem[MESSAGE_SIZE];
            if (integrate(&instance->data, &s->memory, y, segment->rate, segment->duration,
                          problem, sizeof problem)) {
                char hint[MESSAGE_SIZE];
                model_failure_hint(&instance->data, s->state, v, hint, sizeof hint);
                snprintf(message, size, hint[0] ? "%s; %s" : "%s%s", problem, hint);
                return 1;
            }
        }
        model_exact(&instance->data, work, segment->x, segment->rate, segment->duration);
        for (int i = 0; i < N; i++) work[i] = y[i];
    }
    memcpy(s->state, work, sizeof work);
    return 0;
}

/* As cosim.rate_inconsistency: 1 with the secant rate over the last step when the held
   rates at its ends do not fit the deflection's movement. */
static int rate_inconsistency(const Snapshot *s, double *secant) {
    double moved = s->deflection - s->previous_deflection;
    double step = s->previous_step;
    double low = s->previous_rate <= s->rate ? s->previous_rate : s->rate;
    double high = s->previous_rate <= s->rate ? s->rate : s->previous_rate;
    low *= step;
    high *= step;
    double largest = fabs(moved);
    if (fabs(low) > largest) largest = fabs(low);
    if (fabs(high) > largest) largest = fabs(high);
    double allowance = RATE_MARGIN * largest + (RATE_STILL + RATE_CREEP * step);
    if (moved < low - allowance || moved > high + allowance) {
        *secant = moved / step;
        return 1;
    }
    return 0;
}

/* As adapter.rate_warning, word for word. */
static void rate_warning(const Snapshot *s, double secant, char *message, size_t size) {
    const char *x = MODEL_INFO.variables[INPUT_DEFLECTION].name;
    const VariableInfo *v = &MODEL_INFO.variables[INPUT_RATE];
    char what[MESSAGE_SIZE];
    if (s->rate == 0.0)
        snprintf(what, sizeof what, "%s stays 0 while %s moves", v->name, x);
    else
        snprintf(what, sizeof what, "%s = %.6g %s does not fit the movement of %s", v->name,
                 s->rate, v->unit, x);
    snprintf(message, size, "%s (%.6g %s over the last step); the rate-dependent "
             "force is wrong. Give %s in %s with the sign of d(%s)/dt, or set "
             "rate_from_deflection to derive it. Warned once per instance.", what, secant,
             v->unit, v->name, v->unit, x);
}

static int unguarded_step(Instance *instance, double current_time, double step_size,
                          char *message, size_t size);

/* A step that ends beyond the guard's bounds: taken, and undone with
   STEP_FAILED_TO_COMPLETE if an output after it is not finite (as CoSimulation._guarded_step). */
static int guarded_step(Instance *instance, double current_time, double step_size,
                        char *message, size_t size) {
    Snapshot before = instance->s;
    int outcome = unguarded_step(instance, current_time, step_size, message, size);
    if (outcome != STEP_DONE && outcome != STEP_WARNED) return outcome;
    const double *outputs = cosim_outputs(instance);
    int bad = first_non_finite(outputs, MODEL_OUTPUTS);
    if (bad < 0) return outcome;
    char a[REPR_SIZE], b[REPR_SIZE];
    snprintf(message, size, "step from t = %.9g s by %.6g s failed: it would drive %s to %s "
             "(%s = %s %s at its end); nothing changed: take a smaller step", current_time,
             step_size, MODEL_INFO.variables[FIRST_OUTPUT + bad].name,
             format_repr(outputs[bad], a), MODEL_INFO.variables[INPUT_DEFLECTION].name,
             format_repr(instance->s.deflection, b), MODEL_INFO.variables[INPUT_DEFLECTION].unit);
    instance->s = before;
    instance->outputs_fresh = 0;
    return STEP_FAILED_TO_COMPLETE;
}

/* The held rate the next step will use: the input, or with rate_from_deflection the
   backward difference over the last step. */
static double next_rate(const Snapshot *s) {
    if (s->has_previous && s->rate_from_deflection)
        return (s->deflection - s->previous_deflection) / s->previous_step;
    return s->rate;
}

int cosim_do_step(Instance *instance, double current_time, double step_size, char *message,
                  size_t size) {
    const Snapshot *s = &instance->s;
    double rate = next_rate(s);
    if (0.0 < step_size && step_size < INFINITY &&
        guard_watches(s->deflection + rate * step_size, rate))
        return guarded_step(instance, current_time, step_size, message, size);
    return unguarded_step(instance, current_time, step_size, message, size);
}

static int unguarded_step(Instance *instance, double current_time, double step_size,
                          char *message, size_t size) {
    Snapshot *s = &instance->s;
    char a[REPR_SIZE], b[REPR_SIZE];
    if (!(0.0 < step_size && step_size < INFINITY)) {
        snprintf(message, size, "communication step size %s s must be positive and finite",
                 format_repr(step_size, a));
        return STEP_REFUSED;
    }
    double time = s->time;
    /* |current_time - time| <= 1e-9 max(1, |time|) */
    double slack = 1e-9 * (time > 1.0 ? time : time < -1.0 ? -time : 1.0);
    double gap = current_time - time;
    if (!(-slack <= gap && gap <= slack)) {
        snprintf(message, size, "current time %s s does not follow from the last step, which "
                 "ended at %s s", format_repr(current_time, a), format_repr(time, b));
        return STEP_REFUSED;
    }
    double held_rate = s->rate, secant = 0.0;
    int warn = 0;
    if (s->has_previous) {
        if (s->rate_from_deflection) /* backward difference over the last step, held */
            s->rate = next_rate(s);
        else if (!s->rate_warned)
            warn = rate_inconsistency(s, &secant);
    }
    /* Nearly every step is one integrator step: the fused path takes it, or hands it back
       untouched to advance. */
    if (N == 0 || !single_step(&instance->data, &s->memory, s->state, s->deflection, s->rate,
                               step_size)) {
        Memory memory = s->memory;
        char problem[MESSAGE_SIZE];
        if (advance(instance, s->deflection, s->rate, step_size, problem, sizeof problem)) {
            s->memory.has_h_next = memory.has_h_next;
            s->memory.h_next = memory.h_next;
            s->memory.w_uses = memory.w_uses;
            s->memory.w_h = memory.w_h;
            memcpy(s->memory.w, memory.w, sizeof memory.w);
            s->rate = held_rate;
            snprintf(message, size, "step from t = %.9g s by %.6g s failed: %s", current_time,
                     step_size, problem);
            return STEP_FAILED_TO_COMPLETE;
        }
    }
    s->has_previous = 1;
    s->previous_deflection = s->deflection;
    s->previous_rate = s->rate;
    s->previous_step = step_size;
    s->time = current_time + step_size;
    s->deflection += s->rate * step_size;
    instance->outputs_fresh = 0;
    if (!warn) return STEP_DONE;
    s->rate_warned = 1;
    rate_warning(s, secant, message, size);
    return STEP_WARNED;
}

const double *cosim_outputs(Instance *instance) {
    if (!instance->outputs_fresh) {
        Snapshot *s = &instance->s;
        model_outputs(&instance->data, s->state, s->deflection, s->rate, instance->outputs);
        instance->outputs_fresh = 1;
    }
    return instance->outputs;
}

/* The time from now until a contact's deflection crosses 0 within h (the first of the
   step's two rate segments), or 0 if it does not. */
static double until_contact_changes(const Snapshot *s, double h) {
    Segment segments[2];
    return rate_segments(s->deflection, next_rate(s), h, segments) == 2 ? segments[0].duration
                                                                           : 0.0;
}

/* 1 when a contact change `crossing` after a step's start at `start` is no reason to return
   early: the one the last step returned at, met again because the host set the inputs
   interpolated there (a hair off 0, to the same side), or one within a round-off of the
   step's start, where returning would make no progress. The step still takes it: the
   rate segments switch the rubber there. */
static int crossing_already_met(const Instance *instance, double start, double piece,
                                double crossing) {
    const Snapshot *s = &instance->s;
    if (crossing <= 4.0 * DBL_EPSILON * fmax(fabs(start), piece)) return 1;
    int reported = instance->returned_early == RETURNED_AT_CONTACT &&
                   s->time == instance->contact_change_time;
    int same_side = instance->contact_change_to == (next_rate(s) > 0.0);
    return reported && same_side && crossing <= 1e-9 * fmax(1.0, fabs(start));
}

int cosim_do_step_in_pieces(Instance *instance, double current_time, double step_size,
                            char *message, size_t size) {
    Snapshot *s = &instance->s, before = *s;
    double t = current_time, done = 0.0, first_deflection = 0.0, first_rate = 0.0;
    int outcome = STEP_DONE, pieces = 0;
    char warning[MESSAGE_SIZE] = "";
    for (;;) {
        double piece = step_size - done;
        double crossing = instance->early_return_allowed ? until_contact_changes(s, piece) : 0.0;
        if (crossing > 0.0 && done == 0.0 &&
            crossing_already_met(instance, current_time, piece, crossing))
            crossing = 0.0;
        if (done == 0.0) instance->returned_early = 0;
        if (crossing > 0.0) piece = crossing;
        if (instance->intermediate_update && s->memory.has_h_next && s->memory.h_next < piece)
            piece = s->memory.h_next; /* one internal step of the integrator */
        int last = piece == step_size - done;
        int result = cosim_do_step(instance, t, piece, message, size);
        if (result == STEP_WARNED) {
            snprintf(warning, sizeof warning, "%s", message);
            outcome = STEP_WARNED;
        } else if (result != STEP_DONE) {
            *s = before; /* nothing of the step is kept */
            instance->outputs_fresh = 0;
            return result;
        }
        if (pieces++ == 0) {
            first_deflection = s->previous_deflection;
            first_rate = s->previous_rate;
        }
        done += piece;
        t = current_time + done;
        if (last) {
            s->time = current_time + step_size;
            break;
        }
        if (crossing > 0.0 && piece == crossing) {
            instance->contact_change_to = s->rate > 0.0; /* 1: the contact begins */
            s->deflection = 0.0; /* where the contact changes: x + v t is 0 but for rounding */
            instance->outputs_fresh = 0;
            instance->returned_early = RETURNED_AT_CONTACT;
            instance->contact_change_time = s->time;
            break;
        }
        if (instance->intermediate_update) {
            /* The step keeps the instance: other threads stay refused, and the host's calls
               from the callback go in (call_begin). */
            s->mode = INTERMEDIATE_UPDATE;
            Instance *outer = updating_instance;
            updating_instance = instance;
            int early = instance->intermediate_update(instance, t, instance->early_return_allowed);
            updating_instance = outer;
            s->mode = STEP_COMPLETE;
            if (early && instance->early_return_allowed) {
                instance->returned_early = RETURNED_ON_REQUEST;
                break;
            }
        }
    }
    /* The rate check and the derived rate look at the host's step, not its pieces. */
    s->previous_deflection = first_deflection;
    s->previous_rate = first_rate;
    s->previous_step = done;
    if (outcome == STEP_WARNED) snprintf(message, size, "%s", warning);
    return outcome;
}
