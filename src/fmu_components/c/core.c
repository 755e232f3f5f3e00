/*
 * What each FMI call does to an instance, for every native FMU and both FMI versions,
 * hand-written once (the Reference-FMUs' habit): the call sequence checked with one mask
 * per call from the FMI state tables (instance.h), values checked before anything is set, and every
 * refusal logged with the variable and the value, the instance left exactly as it was.
 * `function` is the FMI function the face was called as, for the messages. The semantics
 * are runtime/adapter.py's (the pythonfmu flavour); the component itself is the generated
 * model.c.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core.h"
#include "cosimulation.h"
#include "text.h"

/* The outputs, states and derivatives now, into outputs and locals (NaN while the
   parameters make no sense); STATUS_DISCARD where a host's states leave the model's region. */
static Status current_values(Instance *instance, const char *function, int want_outputs,
                             int want_locals, double *outputs, double *locals) {
    Now now;
    if (!model_now(instance, &now)) {
        for (int i = 0; i < MODEL_OUTPUTS; i++) outputs[i] = NAN;
        for (int i = 0; i < 2 * MODEL_CONTINUOUS; i++) locals[i] = NAN;
        return STATUS_OK;
    }
    int inside = 1;
    if (want_outputs) {
        if (instance->s.initialized && instance->type == CO_SIMULATION)
            memcpy(outputs, cosim_outputs(instance), sizeof(double) * MODEL_OUTPUTS);
        else if (instance->s.initialized)
            inside = model_continuous_outputs(now.data, now.state, now.x, now.v, NULL, 0.0, 0.0,
                                              outputs, NULL);
        else
            model_outputs(now.data, now.state, now.x, now.v, outputs);
    }
    if (want_locals) {
        for (int i = 0; i < MODEL_CONTINUOUS; i++) locals[i] = now.state[i];
        inside &= model_rates(now.data, now.state, now.x, now.v, now.contact, NULL, 0.0, 0.0,
                              locals + MODEL_CONTINUOUS, NULL);
    }
    if (!inside) {
        log_outside_region(instance, function, now.state);
        return STATUS_DISCARD;
    }
    if ((want_outputs && non_finite(instance, function, FIRST_OUTPUT, outputs, MODEL_OUTPUTS,
                                    now.x, now.v)) ||
        (want_locals && non_finite(instance, function, FIRST_STATE, locals,
                                   2 * MODEL_CONTINUOUS, now.x, now.v)))
        return STATUS_DISCARD;
    return STATUS_OK;
}

/* --- life cycle -------------------------------------------------------------------------- */

Instance *core_instantiate(HostLog log, const char *instance_name, Interface type,
                           const Face *face, int logging_on) {
    Instance *instance = calloc(1, sizeof *instance);
    char *name = malloc(strlen(instance_name) + 1);
    if (instance == NULL || name == NULL) {
        free(instance);
        free(name);
        host_log(&log, STATUS_ERROR, "out of memory: no instance made");
        return NULL;
    }
    instance->instance_name = strcpy(name, instance_name);
    instance->log = log;
    instance->log.instance_name = instance->instance_name;
    instance->log.debug_logging = logging_on;
    instance->type = type;
    instance->face = face;
    instance->magic = INSTANCE_MAGIC;
    reset_instance(instance);
    return instance;
}

void core_free_instance(Instance *instance, const char *function) {
    if (instance == NULL || instance->magic != INSTANCE_MAGIC) return;
    if (!call_claim(&instance->call)) {
        host_log_overlap(&instance->log, &instance->call, function);
        return;
    }
    instance->magic = 0;
    host_log_forget(&instance->log);
    free(instance->instance_name);
    free(instance);
}

Status core_set_debug_logging(Instance *instance, const char *function, int on, size_t n,
                              const char *const categories[]) {
    if (!call_begin(instance, ANY_STATE, function)) return STATUS_ERROR;
    char problem[MESSAGE_SIZE];
    if (host_log_set(&instance->log, function, on, n, categories, problem)) {
        log_status(instance, STATUS_ERROR, "%s", problem);
        return call_end(instance, STATUS_ERROR);
    }
    return call_end(instance, STATUS_OK);
}

Status core_setup_experiment(Instance *instance, const char *function, int tolerance_defined,
                             double tolerance, double start_time) {
    if (!call_begin(instance, INSTANTIATED, function)) return STATUS_ERROR;
    char text[REPR_SIZE];
    if (!isfinite(start_time)) {
        log_status(instance, STATUS_ERROR, "%s: startTime = %s s is not finite; call ignored",
                   function, format_repr(start_time, text));
        return call_end(instance, STATUS_ERROR);
    }
    if (tolerance_defined && !(tolerance > 0.0 && isfinite(tolerance))) {
        log_status(instance, STATUS_ERROR, "%s: tolerance = %s must be positive and finite; "
                   "call ignored", function, format_repr(tolerance, text));
        return call_end(instance, STATUS_ERROR);
    }
    instance->s.start_time = start_time;
    instance->s.last_successful_time = start_time;
    if (tolerance_defined) instance->s.tolerance = tolerance;
    return call_end(instance, STATUS_OK);
}

Status core_enter_initialization_mode(Instance *instance, const char *function) {
    if (!call_begin(instance, INSTANTIATED, function)) return STATUS_ERROR;
    instance->s.mode = INITIALIZATION_MODE;
    return call_end(instance, STATUS_OK);
}

Status core_exit_initialization_mode(Instance *instance, const char *function) {
    if (!call_begin(instance, INITIALIZATION_MODE, function)) return STATUS_ERROR;
    char problem[MESSAGE_SIZE];
    if (parameter_problem(instance->s.values, problem, sizeof problem)) {
        /* Stay in initialization mode: the host may correct the parameter and retry. */
        log_status(instance, STATUS_ERROR, "%s: %s; still in initialization mode", function,
                   problem);
        return call_end(instance, STATUS_ERROR);
    }
    cosim_start(instance);
    instance->s.contact = model_contact(instance->s.deflection, instance->s.rate);
    /* FMI 3.0 section 3.2.3: Co-Simulation goes on in Event Mode when the host uses it, else
       in Step Mode; Model Exchange in Event Mode. */
    int step_mode = instance->type == CO_SIMULATION && !instance->event_mode_used;
    instance->s.mode = step_mode ? STEP_COMPLETE : EVENT_MODE;
    return call_end(instance, STATUS_OK);
}

Status core_terminate(Instance *instance, const char *function) {
    if (!call_begin(instance, STEP_COMPLETE | STEP_FAILED | EVENT_MODE | CONTINUOUS_TIME_MODE,
                    function))
        return STATUS_ERROR;
    instance->s.mode = TERMINATED;
    return call_end(instance, STATUS_OK);
}

Status core_reset(Instance *instance, const char *function) {
    if (!call_begin(instance, ANY_STATE, function)) return STATUS_ERROR;
    reset_instance(instance);
    return call_end(instance, STATUS_OK);
}

/* --- getting and setting values ------------------------------------------------------- */

static int arrays_missing(Instance *instance, const char *function, size_t n, const void *vr,
                          const void *value) {
    if (n > 0 && (vr == NULL || value == NULL)) {
        log_status(instance, STATUS_ERROR, "%s: %u values announced but an array is NULL; "
                   "call ignored", function, (unsigned)n);
        return 1;
    }
    return 0;
}

Status core_get_float64(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, double value[]) {
    if (!call_begin(instance, READABLE, function)) {
        if (instance != NULL && value != NULL && instance->magic == INSTANCE_MAGIC)
            for (size_t i = 0; i < nvr; i++) value[i] = NAN;
        return STATUS_ERROR;
    }
    if (arrays_missing(instance, function, nvr, vr, value))
        return call_end(instance, STATUS_ERROR);
    int want_indicator = 0, fmi3 = instance->face->declares_fmi3_variables;
    for (size_t i = 0; i < nvr; i++) {
        want_indicator |= IS_EVENT_INDICATOR(vr[i]);
        if (vr[i] >= MODEL_VARIABLES &&
            !(fmi3 && (IS_EVENT_INDICATOR(vr[i]) || vr[i] == TIME_REFERENCE))) {
            log_status(instance, STATUS_ERROR, "%s: no variable has value reference %u",
                       function, (unsigned)vr[i]);
            for (size_t k = 0; k < nvr; k++) value[k] = NAN;
            return call_end(instance, STATUS_ERROR);
        }
    }
    int want_outputs = 0, want_locals = 0;
    for (size_t i = 0; i < nvr; i++) {
        want_outputs |= vr[i] >= FIRST_OUTPUT && vr[i] < FIRST_PARAMETER;
        want_locals |= vr[i] >= FIRST_STATE;
    }
    double outputs[MODEL_OUTPUTS], locals[SLOTS(2 * MODEL_CONTINUOUS)];
    Status status = STATUS_OK;
    if (want_outputs || want_locals)
        status = current_values(instance, function, want_outputs, want_locals, outputs, locals);
    double indicators[SLOTS(MODEL_EVENT_INDICATORS)] = {NAN};
    Now now;
    if (want_indicator && model_now(instance, &now))
        model_event_indicators(now.data, now.x, indicators);
    for (size_t i = 0; i < nvr; i++) {
        unsigned reference = vr[i];
        if (IS_EVENT_INDICATOR(reference)) value[i] = indicators[0];
        else if (reference == TIME_REFERENCE)
            value[i] = instance->s.initialized ? instance->s.time : instance->s.start_time;
        else if (reference >= FIRST_STATE) value[i] = locals[reference - FIRST_STATE];
        else if (reference >= FIRST_PARAMETER || reference < FIRST_OUTPUT)
            value[i] = instance->s.values[reference];
        else value[i] = outputs[reference - FIRST_OUTPUT];
    }
    return call_end(instance, status);
}

/* The range warning, once per input and instance. */
static Status warn_unmeasured(Instance *instance, int input, double value) {
    const RangeInfo *range = &MODEL_INFO.ranges[input];
    const VariableInfo *variable = &MODEL_INFO.variables[input];
    instance->s.warned |= 1u << input;
    log_status(instance, STATUS_WARNING, "%s = %.6g %s is outside the range the thesis "
               "measured (%s); the model extrapolates. Warned once per instance.",
               variable->name, value, variable->unit, range->measured);
    return STATUS_WARNING;
}

Status core_set_float64(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, const double value[]) {
    if (!call_begin(instance, SETTABLE, function)) return STATUS_ERROR;
    if (arrays_missing(instance, function, nvr, vr, value))
        return call_end(instance, STATUS_ERROR);
    Snapshot *s = &instance->s;
    /* Everything is checked before anything is set: a refused call changes nothing. */
    double inputs[2] = {s->initialized ? s->deflection : s->values[INPUT_DEFLECTION],
                        s->initialized ? s->rate : s->values[INPUT_RATE]};
    int inputs_set = 0, refused = 0;
    char problem[MESSAGE_SIZE];
    for (size_t i = 0; i < nvr; i++) {
        unsigned reference = vr[i];
        if (reference <= INPUT_RATE && isfinite(value[i])) { /* the call of every step */
            inputs[reference] = value[i];
            inputs_set = 1;
            continue;
        }
        if (reference >= MODEL_VARIABLES && instance->face->declares_fmi3_variables &&
            (IS_EVENT_INDICATOR(reference) || reference == TIME_REFERENCE)) {
            snprintf(problem, sizeof problem, "value reference %u is %s, calculated and not set",
                     reference, reference == TIME_REFERENCE ? "the independent variable time"
                                                            : "the contact's event indicator");
        } else if (reference >= MODEL_VARIABLES) {
            snprintf(problem, sizeof problem, "no variable has value reference %u", reference);
        } else if (MODEL_INFO.variables[reference].causality == CAUSALITY_OUTPUT) {
            snprintf(problem, sizeof problem, "%s is an output",
                     MODEL_INFO.variables[reference].name);
        } else if (MODEL_INFO.variables[reference].causality == CAUSALITY_LOCAL) {
            snprintf(problem, sizeof problem, "%s is the model's own (a state or its "
                     "derivative), not set", MODEL_INFO.variables[reference].name);
        } else if (MODEL_INFO.variables[reference].causality == CAUSALITY_PARAMETER &&
                   !(s->mode & BEFORE_INITIALIZED)) {
            snprintf(problem, sizeof problem, "%s is a fixed parameter, settable only before "
                     "%sExitInitializationMode", MODEL_INFO.variables[reference].name,
                     instance->face->prefix);
        } else if (!variable_problem(reference, value[i], problem, sizeof problem)) {
            continue;
        }
        log_status(instance, STATUS_ERROR, "%s: %s; nothing set", function, problem);
        refused = 1;
    }
    if (refused) return call_end(instance, STATUS_ERROR);
    int co_simulation = s->initialized && instance->type == CO_SIMULATION;
    if (inputs_set && co_simulation && cosim_input_problem(instance, inputs[INPUT_DEFLECTION],
                                                           inputs[INPUT_RATE], problem,
                                                           sizeof problem)) {
        log_status(instance, STATUS_ERROR, "%s: %s; nothing set", function, problem);
        return call_end(instance, STATUS_ERROR);
    }
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] != INPUT_DEFLECTION && vr[i] != INPUT_RATE) s->values[vr[i]] = value[i];
    Status status = STATUS_OK;
    if (inputs_set) {
        if (co_simulation) {
            cosim_take_inputs(instance, inputs[INPUT_DEFLECTION], inputs[INPUT_RATE]);
        } else if (s->initialized) { /* Model Exchange: the inputs at the host's time */
            s->deflection = inputs[INPUT_DEFLECTION];
            s->rate = inputs[INPUT_RATE];
        }
        s->values[INPUT_DEFLECTION] = inputs[INPUT_DEFLECTION];
        s->values[INPUT_RATE] = inputs[INPUT_RATE];
        for (int input = INPUT_DEFLECTION; input <= INPUT_RATE; input++) {
            const RangeInfo *range = &MODEL_INFO.ranges[input];
            if (!(s->warned & (1u << input)) &&
                !(range->low <= inputs[input] && inputs[input] <= range->high))
                status = warn_unmeasured(instance, input, inputs[input]);
        }
    }
    instance->outputs_fresh = 0;
    return call_end(instance, status);
}

/* The FMUs have Float64 variables and Boolean parameters only. */
Status core_no_variable_of_type(Instance *instance, const char *function, size_t nvr,
                                const unsigned vr[], int allowed) {
    if (!call_begin(instance, allowed, function)) return STATUS_ERROR;
    if (nvr == 0) return call_end(instance, STATUS_OK);
    if (vr == NULL) log_status(instance, STATUS_ERROR, "%s: the value references are NULL",
                               function);
    else log_status(instance, STATUS_ERROR, "%s: no variable of this type has value reference "
                    "%u", function, (unsigned)vr[0]);
    return call_end(instance, STATUS_ERROR);
}

/* 1, logged, when a value reference is not the Boolean parameter's (the only one). */
static int not_boolean(Instance *instance, const char *function, size_t nvr,
                       const unsigned vr[], const char *consequence) {
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == RATE_FROM_DEFLECTION) continue;
        log_status(instance, STATUS_ERROR, "%s: no Boolean variable has value reference %u%s",
                   function, (unsigned)vr[i], consequence);
        return 1;
    }
    return 0;
}

Status core_get_boolean(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, const void *value, int *flag) {
    *flag = 0;
    if (!call_begin(instance, READABLE, function)) return STATUS_ERROR;
    if (arrays_missing(instance, function, nvr, vr, value))
        return call_end(instance, STATUS_ERROR);
    int refused = not_boolean(instance, function, nvr, vr, "");
    *flag = !refused && instance->s.rate_from_deflection;
    return call_end(instance, refused ? STATUS_ERROR : STATUS_OK);
}

Status core_set_boolean(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, const void *value, int last) {
    if (!call_begin(instance, SETTABLE, function)) return STATUS_ERROR;
    if (arrays_missing(instance, function, nvr, vr, value))
        return call_end(instance, STATUS_ERROR);
    if (not_boolean(instance, function, nvr, vr, "; nothing set"))
        return call_end(instance, STATUS_ERROR);
    if (nvr > 0 && !(instance->s.mode & BEFORE_INITIALIZED)) {
        log_status(instance, STATUS_ERROR, "%s: rate_from_deflection = %s is a fixed parameter, "
                   "settable only before %sExitInitializationMode; nothing set", function,
                   last ? "true" : "false", instance->face->prefix);
        return call_end(instance, STATUS_ERROR);
    }
    if (nvr > 0) instance->s.rate_from_deflection = last;
    return call_end(instance, STATUS_OK);
}

/* --- what the FMUs do not offer ----------------------------------------------------------- */

Status core_not_offered(Instance *instance, const char *function, const char *why) {
    if (!call_begin(instance, ANY_STATE, function)) return STATUS_ERROR;
    log_status(instance, STATUS_ERROR, "%s: %s", function, why);
    return call_end(instance, STATUS_ERROR);
}

/* --- co-simulation ------------------------------------------------------------------------- */

Status core_do_step(Instance *instance, const char *function, double current_time,
                    double step_size) {
    if (!call_begin(instance, STEP_COMPLETE, function)) return STATUS_ERROR;
    char problem[MESSAGE_SIZE];
    int in_pieces = instance->early_return_allowed || instance->intermediate_update;
    switch (in_pieces ? cosim_do_step_in_pieces(instance, current_time, step_size, problem,
                                                sizeof problem)
                      : cosim_do_step(instance, current_time, step_size, problem,
                                      sizeof problem)) {
    case STEP_DONE:
        instance->s.last_successful_time = instance->s.time;
        return call_end(instance, STATUS_OK);
    case STEP_WARNED:
        instance->s.last_successful_time = instance->s.time;
        log_status(instance, STATUS_WARNING, "%s: %s", function, problem);
        return call_end(instance, STATUS_WARNING);
    case STEP_REFUSED:
        log_status(instance, STATUS_ERROR, "%s: %s; step refused", function, problem);
        return call_end(instance, STATUS_ERROR);
    default:
        /* Nothing changed: a discarded step, after which the host restores a state or
           resets (FMI 2.0 section 4.2.3). */
        instance->s.mode = STEP_FAILED;
        instance->s.last_successful_time = current_time;
        log_status(instance, STATUS_DISCARD, "%s: %s", function, problem);
        return call_end(instance, STATUS_DISCARD);
    }
}

Status core_last_successful_time(Instance *instance, const char *function, double *value) {
    if (!call_begin(instance, ANY_STATE, function)) return STATUS_ERROR;
    if (value == NULL) {
        log_status(instance, STATUS_ERROR, "%s: the place for the time is NULL", function);
        return call_end(instance, STATUS_ERROR);
    }
    *value = instance->s.last_successful_time;
    return call_end(instance, STATUS_OK);
}
