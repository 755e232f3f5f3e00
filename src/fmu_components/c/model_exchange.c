/*
 * Model Exchange (spec section 7) and directional derivatives, for every native FMU: the
 * host integrates the continuous states (the leading entries of the state list), the FMU
 * gives their derivatives at the host's states and inputs (model_rates), its outputs
 * (model_continuous_outputs) and, for a contact, the event indicator whose sign change
 * switches the rubber's rate on or off in fmi2NewDiscreteStates. Where the host's states
 * leave the model's region (the damper's |z| < Z_LIMIT) the calls answer fmi2Discard, so
 * the host retries a smaller step. Directional derivatives come from the same equations
 * by forward differentiation (the generated functions' direction arguments).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "runtime.h"

#define ME_STATES (EVENT_MODE | CONTINUOUS_TIME_MODE)
#define ME_READABLE (INITIALIZATION_MODE | EVENT_MODE | CONTINUOUS_TIME_MODE | TERMINATED)
#define N MODEL_CONTINUOUS

/* The calls below belong to Model Exchange: refused, with a message, for a Co-Simulation
   instance. */
static int model_exchange(Instance *instance, const char *function) {
    if (instance->type == fmi2ModelExchange) return 1;
    log_status(instance, fmi2Error, "%s: this instance was made for Co-Simulation", function);
    return 0;
}

static int counted(Instance *instance, const char *function, size_t given, size_t expected,
                   const void *array) {
    if (given == expected && (array != NULL || expected == 0)) return 1;
    log_status(instance, fmi2Error, "%s: %u values given, the FMU has %u (or the array is "
               "NULL); call ignored", function, (unsigned)given, (unsigned)expected);
    return 0;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_STATES, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2EnterEventMode")) return call_end(instance, fmi2Error);
    instance->s.mode = EVENT_MODE;
    return call_end(instance, fmi2OK);
}

/* A contact's mode follows the sign of x at each event; nothing else changes. */
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, EVENT_MODE, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2NewDiscreteStates") || eventInfo == NULL)
        return call_end(instance, fmi2Error);
    instance->s.contact = contact_at(instance->s.deflection, instance->s.rate);
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, EVENT_MODE, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2EnterContinuousTimeMode"))
        return call_end(instance, fmi2Error);
    instance->s.mode = CONTINUOUS_TIME_MODE;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, CONTINUOUS_TIME_MODE, __func__)) return fmi2Error;
    if (enterEventMode) *enterEventMode = fmi2False;
    if (terminateSimulation) *terminateSimulation = fmi2False;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_STATES, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2SetTime")) return call_end(instance, fmi2Error);
    if (!isfinite(time)) {
        log_status(instance, fmi2Error, "fmi2SetTime: time = %g s is not finite; call ignored",
                   time);
        return call_end(instance, fmi2Error);
    }
    instance->s.time = time;
    return call_end(instance, fmi2OK);
}

/* FMI 2.0 allows this in Continuous-Time Mode only; some importers call it straight after
   Event Mode. It is taken there too, with one warning per instance (spec section 7). */
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_STATES, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2SetContinuousStates") ||
        !counted(instance, "fmi2SetContinuousStates", nx, N, x))
        return call_end(instance, fmi2Error);
    for (size_t i = 0; i < nx; i++) {
        if (!isfinite(x[i])) {
            log_status(instance, fmi2Error, "fmi2SetContinuousStates: %s = %g is not finite; "
                       "nothing set", MODEL_INFO.variables[FIRST_STATE + i].name, x[i]);
            return call_end(instance, fmi2Error);
        }
    }
    fmi2Status status = fmi2OK;
    if (instance->s.mode != CONTINUOUS_TIME_MODE && !instance->s.warned_states_outside) {
        instance->s.warned_states_outside = 1;
        log_status(instance, fmi2Warning, "fmi2SetContinuousStates in %s: FMI 2.0 allows it in "
                   "ContinuousTimeMode only; taken (warned once per instance)",
                   mode_name(instance->s.mode));
        status = fmi2Warning;
    }
    for (size_t i = 0; i < nx; i++) instance->s.state[i] = x[i];
    return call_end(instance, status);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_READABLE & ~INITIALIZATION_MODE, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2GetDerivatives") ||
        !counted(instance, "fmi2GetDerivatives", nx, N, derivatives))
        return call_end(instance, fmi2Error);
    Snapshot *s = &instance->s;
    if (!model_rates(&instance->data, s->state, s->deflection, s->rate, s->contact, NULL, 0.0,
                     0.0, derivatives, NULL)) {
        log_status(instance, fmi2Discard, "fmi2GetDerivatives: at t = %.9g s the states are "
                   "outside the region the model is defined in; retry with a smaller step",
                   s->time);
        return call_end(instance, fmi2Discard);
    }
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_READABLE & ~INITIALIZATION_MODE, __func__)) return fmi2Error;
    if (!model_exchange(instance, "fmi2GetEventIndicators") ||
        !counted(instance, "fmi2GetEventIndicators", ni, MODEL_EVENT_INDICATORS, eventIndicators))
        return call_end(instance, fmi2Error);
    if (ni) model_event_indicators(&instance->data, instance->s.deflection, eventIndicators);
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_READABLE, __func__)) return fmi2Error;
    Now now;
    if (!model_exchange(instance, "fmi2GetContinuousStates") ||
        !counted(instance, "fmi2GetContinuousStates", nx, N, x) || !model_now(instance, &now))
        return call_end(instance, fmi2Error);
    for (size_t i = 0; i < nx; i++) x[i] = now.state[i];
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_READABLE | INSTANTIATED, __func__)) return fmi2Error;
    Now now;
    if (!model_exchange(instance, "fmi2GetNominalsOfContinuousStates") ||
        !counted(instance, "fmi2GetNominalsOfContinuousStates", nx, N, x_nominal) ||
        !model_now(instance, &now))
        return call_end(instance, fmi2Error);
    if (nx) model_nominals(now.data, x_nominal);
    return call_end(instance, fmi2OK);
}

/* --- directional derivatives, both interfaces -------------------------------------------- */

/* Exact partial derivatives at the current point (spec section 7): in Model Exchange of
   derivatives and outputs with respect to states and inputs; in Co-Simulation of outputs
   with respect to inputs at the frozen state. */
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ME_READABLE | STEP_COMPLETE | STEP_FAILED, __func__))
        return fmi2Error;
    const char *function = "fmi2GetDirectionalDerivative";
    if ((nUnknown && (vUnknown_ref == NULL || dvUnknown == NULL)) ||
        (nKnown && (vKnown_ref == NULL || dvKnown == NULL))) {
        log_status(instance, fmi2Error, "%s: an array is NULL; call ignored", function);
        return call_end(instance, fmi2Error);
    }
    int me = instance->type == fmi2ModelExchange;
    double dX[SLOTS(N)] = {0}, dx = 0.0, dv = 0.0;
    for (size_t i = 0; i < nKnown; i++) {
        unsigned vr = vKnown_ref[i];
        if (vr == INPUT_DEFLECTION) dx += dvKnown[i];
        else if (vr == INPUT_RATE) dv += dvKnown[i];
        else if (me && vr >= FIRST_STATE && vr < FIRST_DERIVATIVE) dX[vr - FIRST_STATE] += dvKnown[i];
        else {
            log_status(instance, fmi2Error, "%s: value reference %u is not a known of %s (%s)",
                       function, vr, me ? "Model Exchange" : "Co-Simulation",
                       me ? "the inputs and the continuous states" : "the inputs");
            return call_end(instance, fmi2Error);
        }
    }
    for (size_t i = 0; i < nUnknown; i++) {
        unsigned vr = vUnknown_ref[i];
        int output = vr >= FIRST_OUTPUT && vr < FIRST_PARAMETER;
        int derivative = me && vr >= FIRST_DERIVATIVE && vr < FIRST_DERIVATIVE + N;
        if (!output && !derivative) {
            log_status(instance, fmi2Error, "%s: value reference %u is not an unknown (%s)",
                       function, vr, me ? "the outputs and the derivatives" : "the outputs");
            return call_end(instance, fmi2Error);
        }
    }
    Now now;
    if (!model_now(instance, &now)) {
        log_status(instance, fmi2Error, "%s: the parameters make no sense yet", function);
        return call_end(instance, fmi2Error);
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
        log_status(instance, fmi2Discard, "%s: the states are outside the region the model is "
                   "defined in", function);
        return call_end(instance, fmi2Discard);
    }
    for (size_t i = 0; i < nUnknown; i++) {
        unsigned vr = vUnknown_ref[i];
        dvUnknown[i] = vr < FIRST_PARAMETER ? doutputs[vr - FIRST_OUTPUT] : df[vr - FIRST_DERIVATIVE];
    }
    return call_end(instance, fmi2OK);
}
