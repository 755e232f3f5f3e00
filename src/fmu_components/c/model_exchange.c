/*
 * Model Exchange (spec section 7) and directional derivatives, for every native FMU: the
 * host integrates the continuous states (the leading entries of the state list), the FMU
 * gives their derivatives at the host's states and inputs (model_rates), its outputs
 * (model_continuous_outputs) and, for a contact, the event indicator whose sign change
 * switches the rubber's rate on or off in the event update. Where the host's states
 * leave the model's region (the damper's |z| < Z_LIMIT) the calls answer STATUS_DISCARD, so
 * the host retries a smaller step. Directional derivatives come from the same equations
 * by forward differentiation (the generated functions' direction arguments).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "model_exchange.h"
#include "text.h"

#define ME_STATES (EVENT_MODE | CONTINUOUS_TIME_MODE)
#define ME_READABLE (INITIALIZATION_MODE | EVENT_MODE | CONTINUOUS_TIME_MODE | TERMINATED)
#define N MODEL_CONTINUOUS

/* The calls below belong to Model Exchange: refused, with a message, for a Co-Simulation
   instance. */
static int model_exchange(Instance *instance, const char *function) {
    if (instance->type == MODEL_EXCHANGE) return 1;
    log_status(instance, STATUS_ERROR, "%s: this instance was made for Co-Simulation", function);
    return 0;
}

static int counted(Instance *instance, const char *function, size_t given, size_t expected,
                   const void *array) {
    if (given == expected && (array != NULL || expected == 0)) return 1;
    log_status(instance, STATUS_ERROR, "%s: %u values given, the FMU has %u (or the array is "
               "NULL); call ignored", function, (unsigned)given, (unsigned)expected);
    return 0;
}

/* Model Exchange; and Co-Simulation from Step Mode for a host that asked for event mode
   at instantiation (FMI 3.0: after a step returned early at a tyre's contact). */
Status core_enter_event_mode(Instance *instance, const char *function) {
    if (!call_begin(instance, instance->face->enters_event_mode_from, function))
        return STATUS_ERROR;
    if (instance->type == CO_SIMULATION && !instance->event_mode_used) {
        log_status(instance, STATUS_ERROR, "%s: this Co-Simulation instance was made without "
                   "eventModeUsed", function);
        return call_end(instance, STATUS_ERROR);
    }
    if (instance->type == CO_SIMULATION && instance->s.mode != STEP_COMPLETE) {
        call_refused(instance, 1, STEP_COMPLETE, function); /* logs, and ends the call */
        return STATUS_ERROR;
    }
    instance->s.mode = EVENT_MODE;
    return call_end(instance, STATUS_OK);
}

/* A contact's mode follows the sign of x at each event; nothing else changes (the face
   answers: no new discrete states needed, no next event time, nothing else changed). In
   Co-Simulation the step itself follows the contact: nothing to update. */
Status core_update_discrete_states(Instance *instance, const char *function) {
    if (!call_begin(instance, EVENT_MODE, function)) return STATUS_ERROR;
    if (instance->type == MODEL_EXCHANGE)
        instance->s.contact = model_contact(instance->s.deflection, instance->s.rate);
    return call_end(instance, STATUS_OK);
}

/* Co-Simulation: from Event Mode into Step Mode (FMI 3.0 section 3.2.3), the only way there
   for a host that uses event mode. */
Status core_enter_step_mode(Instance *instance, const char *function) {
    if (!call_begin(instance, EVENT_MODE, function)) return STATUS_ERROR;
    if (instance->type != CO_SIMULATION) {
        log_status(instance, STATUS_ERROR, "%s: this instance was made for Model Exchange",
                   function);
        return call_end(instance, STATUS_ERROR);
    }
    instance->s.mode = STEP_COMPLETE;
    return call_end(instance, STATUS_OK);
}

Status core_enter_continuous_time_mode(Instance *instance, const char *function) {
    if (!call_begin(instance, EVENT_MODE, function)) return STATUS_ERROR;
    if (!model_exchange(instance, function))
        return call_end(instance, STATUS_ERROR);
    instance->s.mode = CONTINUOUS_TIME_MODE;
    return call_end(instance, STATUS_OK);
}

/* Nothing to do: the contact's event comes from its indicator (the face answers no event
   and no termination). */
Status core_completed_integrator_step(Instance *instance, const char *function) {
    if (!call_begin(instance, CONTINUOUS_TIME_MODE, function)) return STATUS_ERROR;
    return call_end(instance, STATUS_OK);
}

Status core_set_time(Instance *instance, const char *function, double time) {
    if (!call_begin(instance, ME_STATES, function)) return STATUS_ERROR;
    if (!model_exchange(instance, function)) return call_end(instance, STATUS_ERROR);
    if (!isfinite(time)) {
        char text[REPR_SIZE];
        log_status(instance, STATUS_ERROR, "%s: time = %s s is not finite; call ignored",
                   function, format_repr(time, text));
        return call_end(instance, STATUS_ERROR);
    }
    instance->s.time = time;
    return call_end(instance, STATUS_OK);
}

/* FMI 2.0 allows this in Continuous-Time Mode only; some importers call it straight after
   Event Mode. It is taken there too, with one warning per instance (spec section 7). */
Status core_set_continuous_states(Instance *instance, const char *function, const double x[],
                                  size_t nx) {
    if (!call_begin(instance, ME_STATES, function)) return STATUS_ERROR;
    if (!model_exchange(instance, function) ||
        !counted(instance, function, nx, N, x))
        return call_end(instance, STATUS_ERROR);
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(x[i])) {
            char text[REPR_SIZE];
            log_status(instance, STATUS_ERROR, "%s: %s = %s is not finite; nothing set",
                       function, MODEL_INFO.variables[FIRST_STATE + i].name,
                       format_repr(x[i], text));
            return call_end(instance, STATUS_ERROR);
        }
    }
    Status status = STATUS_OK;
    if (instance->s.mode != CONTINUOUS_TIME_MODE && !instance->s.warned_states_outside) {
        instance->s.warned_states_outside = 1;
        log_status(instance, STATUS_WARNING, "%s in %s: FMI allows it in "
                   "ContinuousTimeMode only; taken (warned once per instance)", function,
                   mode_name(instance, instance->s.mode));
        status = STATUS_WARNING;
    }
    for (size_t i = 0; i < nx; i++) instance->s.state[i] = x[i];
    return call_end(instance, status);
}

Status core_get_derivatives(Instance *instance, const char *function, double derivatives[],
                            size_t nx) {
    if (!call_begin(instance, ME_READABLE & ~INITIALIZATION_MODE, function)) return STATUS_ERROR;
    if (!model_exchange(instance, function) ||
        !counted(instance, function, nx, N, derivatives))
        return call_end(instance, STATUS_ERROR);
    Snapshot *s = &instance->s;
    if (!model_rates(&instance->data, s->state, s->deflection, s->rate, s->contact, NULL, 0.0,
                     0.0, derivatives, NULL)) {
        log_outside_region(instance, function, s->state);
        return call_end(instance, STATUS_DISCARD);
    }
    if (non_finite(instance, function, FIRST_DERIVATIVE, derivatives, N, s->deflection, s->rate))
        return call_end(instance, STATUS_DISCARD);
    return call_end(instance, STATUS_OK);
}

Status core_get_event_indicators(Instance *instance, const char *function,
                                 double eventIndicators[], size_t ni) {
    if (!call_begin(instance, ME_READABLE & ~INITIALIZATION_MODE, function)) return STATUS_ERROR;
    if (!model_exchange(instance, function) ||
        !counted(instance, function, ni, MODEL_EVENT_INDICATORS, eventIndicators))
        return call_end(instance, STATUS_ERROR);
    if (ni) model_event_indicators(&instance->data, instance->s.deflection, eventIndicators);
    return call_end(instance, STATUS_OK);
}

Status core_get_continuous_states(Instance *instance, const char *function, double x[],
                                  size_t nx) {
    if (!call_begin(instance, ME_READABLE, function)) return STATUS_ERROR;
    Now now;
    if (!model_exchange(instance, function) ||
        !counted(instance, function, nx, N, x) || !model_now(instance, &now))
        return call_end(instance, STATUS_ERROR);
    for (size_t i = 0; i < nx; i++) x[i] = now.state[i];
    return call_end(instance, STATUS_OK);
}

Status core_get_nominals(Instance *instance, const char *function, double x_nominal[],
                         size_t nx) {
    if (!call_begin(instance, ME_READABLE | INSTANTIATED, function)) return STATUS_ERROR;
    Now now;
    if (!model_exchange(instance, function) ||
        !counted(instance, function, nx, N, x_nominal) ||
        !model_now(instance, &now))
        return call_end(instance, STATUS_ERROR);
    if (nx) model_nominals(now.data, x_nominal);
    return call_end(instance, STATUS_OK);
}

/* --- directional derivatives, both interfaces -------------------------------------------- */

/* Exact partial derivatives at the current point (spec section 7): in Model Exchange of
   derivatives and outputs with respect to states and inputs; in Co-Simulation of outputs
   with respect to inputs at the frozen state. */
Status core_get_directional_derivative(Instance *instance, const char *function,
                                      const unsigned vUnknown_ref[], size_t nUnknown,
                                      const unsigned vKnown_ref[], size_t nKnown,
                                      const double dvKnown[], double dvUnknown[]) {
    if (!call_begin(instance, ME_READABLE | STEP_COMPLETE | STEP_FAILED, function))
        return STATUS_ERROR;
    if ((nUnknown && (vUnknown_ref == NULL || dvUnknown == NULL)) ||
        (nKnown && (vKnown_ref == NULL || dvKnown == NULL))) {
        log_status(instance, STATUS_ERROR, "%s: an array is NULL; call ignored", function);
        return call_end(instance, STATUS_ERROR);
    }
    int me = instance->type == MODEL_EXCHANGE;
    double dX[SLOTS(N)] = {0}, dx = 0.0, dv = 0.0;
    for (size_t i = 0; i < nKnown; i++) {
        unsigned vr = vKnown_ref[i];
        if (vr == INPUT_DEFLECTION) dx += dvKnown[i];
        else if (vr == INPUT_RATE) dv += dvKnown[i];
        else if (me && vr >= FIRST_STATE && vr < FIRST_DERIVATIVE) dX[vr - FIRST_STATE] += dvKnown[i];
        else {
            log_status(instance, STATUS_ERROR, "%s: value reference %u is not a known of %s (%s)",
                       function, vr, me ? "Model Exchange" : "Co-Simulation",
                       me ? "the inputs and the continuous states" : "the inputs");
            return call_end(instance, STATUS_ERROR);
        }
    }
    for (size_t i = 0; i < nUnknown; i++) {
        unsigned vr = vUnknown_ref[i];
        int output = vr >= FIRST_OUTPUT && vr < FIRST_PARAMETER;
        int derivative = me && vr >= FIRST_DERIVATIVE && vr < FIRST_DERIVATIVE + N;
        if (!output && !derivative) {
            log_status(instance, STATUS_ERROR, "%s: value reference %u is not an unknown (%s)",
                       function, vr, me ? "the outputs and the derivatives" : "the outputs");
            return call_end(instance, STATUS_ERROR);
        }
    }
    Now now;
    if (!model_now(instance, &now)) {
        char problem[MESSAGE_SIZE];
        parameter_problem(instance->s.values, problem, sizeof problem);
        log_status(instance, STATUS_ERROR, "%s: the parameters make no sense yet: %s", function,
                   problem);
        return call_end(instance, STATUS_ERROR);
    }
    double outputs[MODEL_OUTPUTS], doutputs[MODEL_OUTPUTS], f[SLOTS(N)], df[SLOTS(N)] = {0};
    int inside;
    if (me) {
        inside = model_continuous_outputs(now.data, now.state, now.x, now.v, dX, dx, dv, outputs,
                                          doutputs) &&
                 model_rates(now.data, now.state, now.x, now.v, now.contact, dX, dx, dv, f, df);
    } else {
        inside = model_outputs_direction(now.data, now.state, now.x, now.v, dx, dv, outputs,
                                         doutputs);
    }
    if (!inside) {
        log_outside_region(instance, function, now.state);
        return call_end(instance, STATUS_DISCARD);
    }
    for (size_t i = 0; i < nUnknown; i++) {
        unsigned vr = vUnknown_ref[i];
        dvUnknown[i] = vr < FIRST_PARAMETER ? doutputs[vr - FIRST_OUTPUT] : df[vr - FIRST_DERIVATIVE];
    }
    return call_end(instance, STATUS_OK);
}

/* The outputs' first time derivatives at the communication point (Co-Simulation,
   maxOutputDerivativeOrder 1), for hosts that extrapolate: along the states' own rates
   and the deflection moving at the held rate, the rate itself held. */
Status core_output_derivatives(Instance *instance, const char *function, const unsigned vr[],
                               size_t nvr, const int orders[], double values[]) {
    if (!call_begin(instance, STEP_COMPLETE | STEP_FAILED | TERMINATED, function))
        return STATUS_ERROR;
    if (instance->type != CO_SIMULATION) {
        log_status(instance, STATUS_ERROR, "%s: this instance was made for Model Exchange",
                   function);
        return call_end(instance, STATUS_ERROR);
    }
    if (nvr && (vr == NULL || orders == NULL || values == NULL)) {
        log_status(instance, STATUS_ERROR, "%s: an array is NULL; call ignored", function);
        return call_end(instance, STATUS_ERROR);
    }
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] < FIRST_OUTPUT || vr[i] >= FIRST_PARAMETER) {
            log_status(instance, STATUS_ERROR, "%s: value reference %u is not an output; call "
                       "ignored", function, vr[i]);
            return call_end(instance, STATUS_ERROR);
        }
        if (orders[i] != 1) {
            log_status(instance, STATUS_ERROR, "%s: order %d of %s: the FMU gives the first "
                       "derivative only (maxOutputDerivativeOrder 1); call ignored", function,
                       orders[i], MODEL_INFO.variables[vr[i]].name);
            return call_end(instance, STATUS_ERROR);
        }
    }
    Snapshot *s = &instance->s;
    double f[SLOTS(N)], outputs[MODEL_OUTPUTS], doutputs[MODEL_OUTPUTS];
    double contact = model_contact(s->deflection, s->rate);
    if (!model_rates(&instance->data, s->state, s->deflection, s->rate, contact, NULL, 0.0, 0.0,
                     f, NULL) ||
        !model_continuous_outputs(&instance->data, s->state, s->deflection, s->rate, f, s->rate,
                                  0.0, outputs, doutputs)) {
        log_outside_region(instance, function, s->state);
        return call_end(instance, STATUS_DISCARD);
    }
    for (size_t i = 0; i < nvr; i++) values[i] = doutputs[vr[i] - FIRST_OUTPUT];
    return call_end(instance, STATUS_OK);
}
