/*
 * The FMI 2.0 calls of every native FMU, hand-written once (the Reference-FMUs' habit):
 * the call sequence checked with one mask per function from the FMI 2.0 state tables
 * (sections 3.2.3 and 4.2.4), values checked before anything is set, and every refusal
 * logged with the variable and the value, the instance left exactly as it was. The
 * semantics are runtime/adapter.py's (the pythonfmu flavour); the component itself is the
 * generated model.c.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "instantiation.h"
#include "runtime.h"
#include "text.h"

#define ANY_STATE                                                                          \
    (INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED |       \
     EVENT_MODE | CONTINUOUS_TIME_MODE)
#define READABLE (ANY_STATE & ~INSTANTIATED)
#define SETTABLE (INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | EVENT_MODE | CONTINUOUS_TIME_MODE)
#define BEFORE_INITIALIZED (INSTANTIATED | INITIALIZATION_MODE)

/* The states by name, in the order runtime/adapter.py lists them (sorted). */
static const struct {
    int mode;
    const char *name;
} MODES[] = {{CONTINUOUS_TIME_MODE, "ContinuousTimeMode"}, {EVENT_MODE, "EventMode"},
             {INITIALIZATION_MODE, "InitializationMode"}, {INSTANTIATED, "Instantiated"},
             {STEP_COMPLETE, "StepComplete"}, {STEP_FAILED, "StepFailed"},
             {TERMINATED, "Terminated"}};

const char *mode_name(int mode) {
    for (size_t i = 0; i < sizeof MODES / sizeof MODES[0]; i++)
        if (MODES[i].mode == mode) return MODES[i].name;
    return "unknown";
}

void log_status(const Instance *instance, fmi2Status status, const char *format, ...) {
    char message[MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    host_log(&instance->log, status, message);
}

int call_refused(Instance *instance, int claimed, int allowed, const char *function) {
    if (!claimed) {
        host_log_overlap(&instance->log, &instance->call, function);
        return 0;
    }
    char list[256] = "";
    for (size_t i = 0; i < sizeof MODES / sizeof MODES[0]; i++) {
        if (!(allowed & MODES[i].mode)) continue;
        if (list[0]) strncat(list, ", ", sizeof list - strlen(list) - 1);
        strncat(list, MODES[i].name, sizeof list - strlen(list) - 1);
    }
    log_status(instance, fmi2Error, "%s is not allowed in state %s (allowed in: %s); call "
               "ignored", function, mode_name(instance->s.mode), list);
    call_end(instance, fmi2Error);
    return 0;
}

/* --- values ----------------------------------------------------------------------------- */

int variable_problem(unsigned vr, double value, char *message, size_t size) {
    const VariableInfo *variable = &MODEL_INFO.variables[vr];
    char text[REPR_SIZE];
    if (!isfinite(value)) {
        snprintf(message, size, "%s = %s %s is not a finite number", variable->name,
                 format_repr(value, text), variable->unit);
        return 1;
    }
    if ((variable->constraint == POSITIVE && value <= 0.0) ||
        (variable->constraint == NON_NEGATIVE && value < 0.0)) {
        snprintf(message, size, "%s = %s %s must be %s", variable->name,
                 format_repr(value, text), variable->unit,
                 variable->constraint == POSITIVE ? "positive" : "zero or positive");
        return 1;
    }
    return 0;
}

static void table_points(const TableInfo *table, const double *values, double *xs, double *ys) {
    for (size_t i = 0; i < table->size; i++) {
        xs[i] = values[table->abscissae[i]];
        ys[i] = values[table->ordinates[i]];
    }
}

/* As ComponentDefinition.check_parameters: each parameter, then each table. */
int parameter_problem(const double *values, char *message, size_t size) {
    char problem[MESSAGE_SIZE];
    for (unsigned vr = FIRST_PARAMETER; vr < FIRST_STATE; vr++) {
        if (variable_problem(vr, values[vr], problem, sizeof problem)) {
            snprintf(message, size, "parameter %s", problem);
            return 1;
        }
        /* As catalog.magnitude_problem: outside these, 1/k or k*k overflows. */
        double size_of = fabs(values[vr]);
        if (values[vr] != 0.0 && !(size_of >= SMALLEST_PARAMETER && size_of <= LARGEST_PARAMETER)) {
            char text[REPR_SIZE];
            snprintf(message, size, "parameter %s = %s %s is outside the magnitudes the model's "
                     "arithmetic takes (zero or 1e-100 to 1e100 in size)",
                     MODEL_INFO.variables[vr].name, format_repr(values[vr], text),
                     MODEL_INFO.variables[vr].unit);
            return 1;
        }
    }
    for (int t = 0; t < MODEL_TABLES; t++) {
        const TableInfo *table = &MODEL_INFO.tables[t];
        double xs[HERMITE_POINTS], ys[HERMITE_POINTS];
        table_points(table, values, xs, ys);
        if (hermite_problem(xs, ys, table->size, problem, sizeof problem)) {
            snprintf(message, size, "%s table: %s", table->name, problem);
            return 1;
        }
        for (size_t i = 0; table->dissipative && i < table->size; i++) {
            if (xs[i] * ys[i] < 0.0 || (xs[i] == 0.0 && ys[i] != 0.0)) {
                snprintf(message, size, "%s table: %s %.6g %s at %s %.6g %s would feed energy "
                         "in; a %s's %s takes the sign of its %s", table->name, table->ordinate,
                         ys[i], table->ordinate_unit, table->abscissa, xs[i],
                         table->abscissa_unit, table->name, table->ordinate, table->abscissa);
                return 1;
            }
        }
    }
    return 0;
}

void build_model_data(ModelData *data, const double *values) {
    model_derive(data, values);
    for (int t = 0; t < MODEL_TABLES; t++) {
        const TableInfo *table = &MODEL_INFO.tables[t];
        double xs[HERMITE_POINTS], ys[HERMITE_POINTS];
        table_points(table, values, xs, ys);
        hermite_build(&data->tables[t], xs, ys, table->size);
    }
}

static void reset_instance(Instance *instance) {
    Snapshot *s = &instance->s;
    memset(s, 0, sizeof *s);
    s->mode = INSTANTIATED;
    for (int vr = 0; vr < MODEL_VARIABLES; vr++) {
        double start = MODEL_INFO.variables[vr].start;
        s->values[vr] = isnan(start) ? 0.0 : start;
    }
    s->tolerance = DEFAULT_RTOL;
    instance->outputs_fresh = 0;
}

int model_now(Instance *instance, Now *now) {
    Snapshot *s = &instance->s;
    if (s->initialized) {
        now->data = &instance->data;
        now->state = s->state;
        now->x = s->deflection;
        now->v = s->rate;
        now->contact = s->contact;
        return 1;
    }
    char problem[MESSAGE_SIZE];
    if (parameter_problem(s->values, problem, sizeof problem)) return 0;
    now->x = s->values[INPUT_DEFLECTION];
    now->v = s->values[INPUT_RATE];
    now->contact = contact_at(now->x, now->v);
    build_model_data(&now->scratch, s->values);
    model_initial_state(&now->scratch, now->x, now->v, now->relaxed);
    now->data = &now->scratch;
    now->state = now->relaxed;
    return 1;
}

double contact_at(double x, double v) {
    return !MODEL_INFO.unilateral || x > 0.0 || (x == 0.0 && v > 0.0) ? 1.0 : 0.0;
}

/* The outputs, states and derivatives now, into outputs and locals (NaN while the
   parameters make no sense); fmi2Discard where a host's states leave the model's region. */
static fmi2Status current_values(Instance *instance, int want_outputs, int want_locals,
                                 double *outputs, double *locals) {
    Now now;
    if (!model_now(instance, &now)) {
        for (int i = 0; i < MODEL_OUTPUTS; i++) outputs[i] = NAN;
        for (int i = 0; i < 2 * MODEL_CONTINUOUS; i++) locals[i] = NAN;
        return fmi2OK;
    }
    int inside = 1;
    if (want_outputs) {
        if (instance->s.initialized && instance->type == fmi2CoSimulation)
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
    if (inside) return fmi2OK;
    log_status(instance, fmi2Discard, "fmi2GetReal: the states are outside the region the "
               "model is defined in; retry with a smaller step");
    return fmi2Discard;
}

/* --- life cycle -------------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    (void)visible;
    HostLog log = instantiation_log(instanceName, functions);
    if (instantiation_problem(&log, instanceName, fmuType, fmuGUID, fmuResourceLocation,
                              functions, MODEL_INFO.name, MODEL_INFO.guid,
                              1u << fmi2CoSimulation | 1u << fmi2ModelExchange))
        return NULL;
    Instance *instance = calloc(1, sizeof *instance);
    char *name = malloc(strlen(instanceName) + 1);
    if (instance == NULL || name == NULL) {
        free(instance);
        free(name);
        host_log(&log, fmi2Error, "fmi2Instantiate: out of memory");
        return NULL;
    }
    instance->instance_name = strcpy(name, instanceName);
    instance->log = log;
    instance->log.instance_name = instance->instance_name;
    instance->log.debug_logging = loggingOn;
    instance->type = fmuType;
    instance->magic = INSTANCE_MAGIC;
    reset_instance(instance);
    return instance;
}

void fmi2FreeInstance(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (instance == NULL || instance->magic != INSTANCE_MAGIC) return;
    if (!call_claim(&instance->call)) {
        host_log_overlap(&instance->log, &instance->call, __func__);
        return;
    }
    instance->magic = 0;
    host_log_forget(&instance->log);
    free(instance->instance_name);
    free(instance);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ANY_STATE, __func__)) return fmi2Error;
    char problem[MESSAGE_SIZE];
    if (host_log_set(&instance->log, loggingOn, nCategories, categories, problem)) {
        log_status(instance, fmi2Error, "%s", problem);
        return call_end(instance, fmi2Error);
    }
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    (void)stopTimeDefined, (void)stopTime;
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, INSTANTIATED, __func__)) return fmi2Error;
    char text[REPR_SIZE];
    if (!isfinite(startTime)) {
        log_status(instance, fmi2Error, "fmi2SetupExperiment: startTime = %s s is not finite; "
                   "call ignored", format_repr(startTime, text));
        return call_end(instance, fmi2Error);
    }
    if (toleranceDefined && !(tolerance > 0.0 && isfinite(tolerance))) {
        log_status(instance, fmi2Error, "fmi2SetupExperiment: tolerance = %s must be positive "
                   "and finite; call ignored", format_repr(tolerance, text));
        return call_end(instance, fmi2Error);
    }
    instance->s.start_time = startTime;
    instance->s.last_successful_time = startTime;
    if (toleranceDefined) instance->s.tolerance = tolerance;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, INSTANTIATED, __func__)) return fmi2Error;
    instance->s.mode = INITIALIZATION_MODE;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, INITIALIZATION_MODE, __func__)) return fmi2Error;
    char problem[MESSAGE_SIZE];
    if (parameter_problem(instance->s.values, problem, sizeof problem)) {
        /* Stay in initialization mode: the host may correct the parameter and retry. */
        log_status(instance, fmi2Error, "fmi2ExitInitializationMode: %s; still in "
                   "initialization mode", problem);
        return call_end(instance, fmi2Error);
    }
    cosim_start(instance);
    instance->s.contact = contact_at(instance->s.deflection, instance->s.rate);
    instance->s.mode = instance->type == fmi2CoSimulation ? STEP_COMPLETE : EVENT_MODE;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, STEP_COMPLETE | STEP_FAILED | EVENT_MODE | CONTINUOUS_TIME_MODE,
                    __func__))
        return fmi2Error;
    instance->s.mode = TERMINATED;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2Reset(fmi2Component c) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ANY_STATE, __func__)) return fmi2Error;
    reset_instance(instance);
    return call_end(instance, fmi2OK);
}

/* --- getting and setting values ------------------------------------------------------- */

static int arrays_missing(Instance *instance, const char *function, size_t n, const void *vr,
                          const void *value) {
    if (n > 0 && (vr == NULL || value == NULL)) {
        log_status(instance, fmi2Error, "%s: %u values announced but an array is NULL; call "
                   "ignored", function, (unsigned)n);
        return 1;
    }
    return 0;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, READABLE, __func__)) {
        if (instance != NULL && value != NULL && instance->magic == INSTANCE_MAGIC)
            for (size_t i = 0; i < nvr; i++) value[i] = NAN;
        return fmi2Error;
    }
    if (arrays_missing(instance, "fmi2GetReal", nvr, vr, value))
        return call_end(instance, fmi2Error);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= MODEL_VARIABLES) {
            log_status(instance, fmi2Error, "fmi2GetReal: no variable has value reference %u",
                       (unsigned)vr[i]);
            for (size_t k = 0; k < nvr; k++) value[k] = NAN;
            return call_end(instance, fmi2Error);
        }
    }
    int want_outputs = 0, want_locals = 0;
    for (size_t i = 0; i < nvr; i++) {
        want_outputs |= vr[i] >= FIRST_OUTPUT && vr[i] < FIRST_PARAMETER;
        want_locals |= vr[i] >= FIRST_STATE;
    }
    double outputs[MODEL_OUTPUTS], locals[SLOTS(2 * MODEL_CONTINUOUS)];
    fmi2Status status = fmi2OK;
    if (want_outputs || want_locals)
        status = current_values(instance, want_outputs, want_locals, outputs, locals);
    for (size_t i = 0; i < nvr; i++) {
        unsigned reference = vr[i];
        if (reference >= FIRST_STATE) value[i] = locals[reference - FIRST_STATE];
        else if (reference >= FIRST_PARAMETER || reference < FIRST_OUTPUT)
            value[i] = instance->s.values[reference];
        else value[i] = outputs[reference - FIRST_OUTPUT];
    }
    return call_end(instance, status);
}

/* The range warning, once per input and instance. */
static fmi2Status warn_unmeasured(Instance *instance, int input, double value) {
    const RangeInfo *range = &MODEL_INFO.ranges[input];
    const VariableInfo *variable = &MODEL_INFO.variables[input];
    instance->s.warned |= 1u << input;
    log_status(instance, fmi2Warning, "%s = %.6g %s is outside the range the thesis measured "
               "(%s); the model extrapolates. Warned once per instance.", variable->name, value,
               variable->unit, range->measured);
    return fmi2Warning;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, SETTABLE, __func__)) return fmi2Error;
    if (arrays_missing(instance, "fmi2SetReal", nvr, vr, value))
        return call_end(instance, fmi2Error);
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
        if (reference >= MODEL_VARIABLES) {
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
                     "fmi2ExitInitializationMode", MODEL_INFO.variables[reference].name);
        } else if (!variable_problem(reference, value[i], problem, sizeof problem)) {
            continue;
        }
        log_status(instance, fmi2Error, "fmi2SetReal: %s; nothing set", problem);
        refused = 1;
    }
    if (refused) return call_end(instance, fmi2Error);
    int co_simulation = s->initialized && instance->type == fmi2CoSimulation;
    if (inputs_set && co_simulation && cosim_input_problem(instance, inputs[INPUT_DEFLECTION],
                                                           problem, sizeof problem)) {
        log_status(instance, fmi2Error, "fmi2SetReal: %s; nothing set", problem);
        return call_end(instance, fmi2Error);
    }
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] != INPUT_DEFLECTION && vr[i] != INPUT_RATE) s->values[vr[i]] = value[i];
    fmi2Status status = fmi2OK;
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

/* The FMUs have Real variables and Boolean parameters only. */
static fmi2Status no_variable_of_type(fmi2Component c, const char *function, size_t nvr,
                                      const fmi2ValueReference vr[], int allowed) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, allowed, function)) return fmi2Error;
    if (nvr == 0) return call_end(instance, fmi2OK);
    if (vr == NULL) log_status(instance, fmi2Error, "%s: the value references are NULL", function);
    else log_status(instance, fmi2Error, "%s: no variable of this type has value reference %u",
                    function, (unsigned)vr[0]);
    return call_end(instance, fmi2Error);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    (void)value;
    return no_variable_of_type(c, "fmi2GetInteger", nvr, vr, READABLE);
}

/* 1, logged, when a value reference is not the Boolean parameter's (the only one). */
static int not_boolean(Instance *instance, const char *function, size_t nvr,
                       const fmi2ValueReference vr[], const char *consequence) {
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] == RATE_FROM_DEFLECTION) continue;
        log_status(instance, fmi2Error, "%s: no Boolean variable has value reference %u%s",
                   function, (unsigned)vr[i], consequence);
        return 1;
    }
    return 0;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, READABLE, __func__)) return fmi2Error;
    if (arrays_missing(instance, "fmi2GetBoolean", nvr, vr, value))
        return call_end(instance, fmi2Error);
    int refused = not_boolean(instance, "fmi2GetBoolean", nvr, vr, "");
    for (size_t i = 0; i < nvr; i++)
        value[i] = !refused && instance->s.rate_from_deflection ? fmi2True : fmi2False;
    return call_end(instance, refused ? fmi2Error : fmi2OK);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    (void)value;
    return no_variable_of_type(c, "fmi2GetString", nvr, vr, READABLE);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    (void)value;
    return no_variable_of_type(c, "fmi2SetInteger", nvr, vr, SETTABLE);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, SETTABLE, __func__)) return fmi2Error;
    if (arrays_missing(instance, "fmi2SetBoolean", nvr, vr, value))
        return call_end(instance, fmi2Error);
    if (not_boolean(instance, "fmi2SetBoolean", nvr, vr, "; nothing set"))
        return call_end(instance, fmi2Error);
    if (nvr > 0 && !(instance->s.mode & BEFORE_INITIALIZED)) {
        log_status(instance, fmi2Error, "fmi2SetBoolean: rate_from_deflection is a fixed "
                   "parameter, settable only before fmi2ExitInitializationMode; nothing set");
        return call_end(instance, fmi2Error);
    }
    for (size_t i = 0; i < nvr; i++) instance->s.rate_from_deflection = value[i] != fmi2False;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    (void)value;
    return no_variable_of_type(c, "fmi2SetString", nvr, vr, SETTABLE);
}

/* --- what the FMUs do not offer ----------------------------------------------------------- */

static fmi2Status not_offered(fmi2Component c, const char *function, const char *why) {
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, ANY_STATE, function)) return fmi2Error;
    log_status(instance, fmi2Error, "%s: %s", function, why);
    return call_end(instance, fmi2Error);
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return not_offered(c, "fmi2SetRealInputDerivatives", "the FMU holds the rate input over a "
                       "step and takes no input derivatives (canInterpolateInputs is false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return not_offered(c, "fmi2GetRealOutputDerivatives", "maxOutputDerivativeOrder is 0");
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return not_offered(c, "fmi2CancelStep", "steps run synchronously; there is none to cancel");
}

/* --- co-simulation ------------------------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    Instance *instance = (Instance *)c;
    if (!call_begin(instance, STEP_COMPLETE, __func__)) return fmi2Error;
    char problem[MESSAGE_SIZE];
    switch (cosim_do_step(instance, currentCommunicationPoint, communicationStepSize, problem,
                          sizeof problem)) {
    case STEP_DONE:
        instance->s.last_successful_time = instance->s.time;
        return call_end(instance, fmi2OK);
    case STEP_WARNED:
        instance->s.last_successful_time = instance->s.time;
        log_status(instance, fmi2Warning, "%s", problem);
        return call_end(instance, fmi2Warning);
    case STEP_REFUSED:
        log_status(instance, fmi2Error, "fmi2DoStep: %s; step refused", problem);
        return call_end(instance, fmi2Error);
    default:
        /* Nothing changed: fmi2Discard, after which the host restores a state or resets
           (FMI 2.0 section 4.2.3). */
        instance->s.mode = STEP_FAILED;
        instance->s.last_successful_time = currentCommunicationPoint;
        log_status(instance, fmi2Discard, "fmi2DoStep: %s", problem);
        return call_end(instance, fmi2Discard);
    }
}

static fmi2Status no_status(fmi2Component c, const char *function) {
    return not_offered(c, function, "steps run synchronously, there is no status to ask for");
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s, (void)value;
    return no_status(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    Instance *instance = (Instance *)c;
    if (s != fmi2LastSuccessfulTime) return no_status(c, "fmi2GetRealStatus");
    if (!call_begin(instance, ANY_STATE, __func__)) return fmi2Error;
    if (value == NULL) return call_end(instance, fmi2Error);
    *value = instance->s.last_successful_time;
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s, (void)value;
    return no_status(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    Instance *instance = (Instance *)c;
    if (s != fmi2Terminated) return no_status(c, "fmi2GetBooleanStatus");
    if (!call_begin(instance, ANY_STATE, __func__)) return fmi2Error;
    if (value == NULL) return call_end(instance, fmi2Error);
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return call_end(instance, fmi2OK);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s, (void)value;
    return no_status(c, "fmi2GetStringStatus");
}
