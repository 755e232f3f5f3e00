/*
 * The hostile host's FMI 2.0 calls, made on an FMI 3.0 binary: each fmi2 call of the table
 * becomes its fmi3 counterpart with the same arguments, so every probe of fuzz_host.c runs
 * against the FMI 3.0 face too. The fmi2Component the host holds is a Shim: the FMI 3.0
 * instance, the host's callbacks (FMI 3.0 logs through one function and an environment)
 * and the experiment that fmi2SetupExperiment gives and fmi3EnterInitializationMode takes.
 * A Co-Simulation instance is made with early return, event mode and an intermediate
 * update callback, so every probe also runs through steps taken in pieces: fmi2DoStep
 * finishes a step that returned early (through event mode, if asked), and the callback
 * reads the inputs and the output and sets the rate it read (which changes nothing).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2_table.h"
#include "fmi3FunctionTypes.h"

static struct {
    fmi3InstantiateCoSimulationTYPE *InstantiateCoSimulation;
    fmi3InstantiateModelExchangeTYPE *InstantiateModelExchange;
    fmi3FreeInstanceTYPE *FreeInstance;
    fmi3SetDebugLoggingTYPE *SetDebugLogging;
    fmi3EnterInitializationModeTYPE *EnterInitializationMode;
    fmi3ExitInitializationModeTYPE *ExitInitializationMode;
    fmi3TerminateTYPE *Terminate;
    fmi3ResetTYPE *Reset;
    fmi3GetFloat64TYPE *GetFloat64;
    fmi3SetFloat64TYPE *SetFloat64;
    fmi3GetInt32TYPE *GetInt32;
    fmi3SetInt32TYPE *SetInt32;
    fmi3GetBooleanTYPE *GetBoolean;
    fmi3SetBooleanTYPE *SetBoolean;
    fmi3GetStringTYPE *GetString;
    fmi3SetStringTYPE *SetString;
    fmi3GetFMUStateTYPE *GetFMUState;
    fmi3SetFMUStateTYPE *SetFMUState;
    fmi3FreeFMUStateTYPE *FreeFMUState;
    fmi3SerializedFMUStateSizeTYPE *SerializedFMUStateSize;
    fmi3SerializeFMUStateTYPE *SerializeFMUState;
    fmi3DeserializeFMUStateTYPE *DeserializeFMUState;
    fmi3DoStepTYPE *DoStep;
    fmi3EnterEventModeTYPE *EnterEventMode;
    fmi3UpdateDiscreteStatesTYPE *UpdateDiscreteStates;
    fmi3EnterStepModeTYPE *EnterStepMode;
} fmi3;

typedef struct {
    fmi3Instance instance;
    fmi2CallbackFunctions callbacks;
    char *name;
    fmi2Boolean tolerance_defined, stop_defined;
    fmi2Real tolerance, start, stop;
    fmi3Float64 last_successful_time; /* fmi3DoStep's, for fmi2GetRealStatus */
    int in_logger;                    /* the FMU is inside a call that logs */
    int co_simulation;                /* made with eventModeUsed: initialization ends in Event Mode */
} Shim;

static fmi3Instance instance_of(fmi2Component c) { return c ? ((Shim *)c)->instance : NULL; }

static fmi3ValueReference inputs[2] = {0, 1}, output = 2;
static unsigned long intermediate_updates;

void fmi3_as_fmi2_variables(const fmi2ValueReference given_inputs[2], fmi2ValueReference given_output) {
    inputs[0] = given_inputs[0];
    inputs[1] = given_inputs[1];
    output = given_output;
}

unsigned long fmi3_as_fmi2_intermediate_updates(void) {
    return __atomic_load_n(&intermediate_updates, __ATOMIC_SEQ_CST);
}

static void intermediate_update(fmi3InstanceEnvironment environment, fmi3Float64 time,
                                fmi3Boolean set_requested, fmi3Boolean get_allowed,
                                fmi3Boolean finished, fmi3Boolean can_return_early,
                                fmi3Boolean *early_requested, fmi3Float64 *early_time) {
    (void)time, (void)finished, (void)can_return_early, (void)early_time;
    Shim *shim = environment;
    __atomic_add_fetch(&intermediate_updates, 1, __ATOMIC_SEQ_CST);
    fmi3Float64 values[2], out;
    *early_requested = false;
    if (get_allowed && fmi3.GetFloat64(shim->instance, inputs, 2, values, 2) == fmi3OK &&
        fmi3.GetFloat64(shim->instance, &output, 1, &out, 1) == fmi3OK && set_requested)
        fmi3.SetFloat64(shim->instance, &inputs[1], 1, &values[1], 1);
}

static void log_message(fmi3InstanceEnvironment environment, fmi3Status status,
                        fmi3String category, fmi3String message) {
    Shim *shim = environment;
    /* An FMI 2.0 message is a format: its % doubled, as an FMI 2.0 FMU sends it. */
    char format[2 * 1024 + 1], *out = format;
    for (const char *p = message ? message : ""; *p && out < format + sizeof format - 2; p++) {
        if (*p == '%') *out++ = '%';
        *out++ = *p;
    }
    *out = '\0';
    __atomic_add_fetch(&shim->in_logger, 1, __ATOMIC_SEQ_CST);
    shim->callbacks.logger(shim->callbacks.componentEnvironment, shim->name, (fmi2Status)status,
                           category, format);
    __atomic_sub_fetch(&shim->in_logger, 1, __ATOMIC_SEQ_CST);
}

/* file:///a/b%20c -> /a/b c; anything else is passed on as it is, for the FMU to refuse. */
static char *path_of(const char *uri) {
    if (uri == NULL) return NULL;
    const char *p = uri;
    if (!strncmp(uri, "file:///", 8)) p = uri + 7;
    else if (!strncmp(uri, "file:/", 6) && uri[6] != '/') p = uri + 5;
    char *path = malloc(strlen(p) + 1), *out = path;
    if (path == NULL) return NULL;
    for (; *p; p++) {
        unsigned code;
        if (p != uri && *p == '%' && sscanf(p + 1, "%2x", &code) == 1 && strlen(p) >= 3) {
            *out++ = (char)code;
            p += 2;
        } else {
            *out++ = *p;
        }
    }
    *out = '\0';
    return path;
}

static fmi2Component Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                                 fmi2String uri, const fmi2CallbackFunctions *callbacks,
                                 fmi2Boolean visible, fmi2Boolean logging) {
    if (callbacks == NULL || (type != fmi2CoSimulation && type != fmi2ModelExchange))
        return NULL; /* no FMI 3.0 form */
    Shim *shim = calloc(1, sizeof *shim);
    if (shim == NULL) return NULL;
    shim->callbacks = *callbacks;
    shim->name = name ? strdup(name) : NULL;
    char *path = path_of(uri);
    fmi3LogMessageCallback logger = callbacks->logger ? log_message : NULL;
    shim->co_simulation = type == fmi2CoSimulation;
    if (type == fmi2CoSimulation)
        shim->instance = fmi3.InstantiateCoSimulation(name, guid, path, visible, logging, true,
                                                      true, NULL, 0, shim, logger,
                                                      intermediate_update);
    else
        shim->instance = fmi3.InstantiateModelExchange(name, guid, path, visible, logging, shim,
                                                       logger);
    free(path);
    if (shim->instance == NULL) {
        free(shim->name);
        free(shim);
        return NULL;
    }
    return shim;
}

static void FreeInstance(fmi2Component c) {
    Shim *shim = c;
    if (shim == NULL) return;
    fmi3.FreeInstance(shim->instance);
    /* From the logger, inside a call: the FMU ignores it, and the shim stays too. */
    if (__atomic_load_n(&shim->in_logger, __ATOMIC_SEQ_CST)) return;
    free(shim->name);
    free(shim);
}

static fmi2Status SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n,
                                  const fmi2String categories[]) {
    return (fmi2Status)fmi3.SetDebugLogging(instance_of(c), on, n, categories);
}

static fmi2Status SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined,
                                  fmi2Real tolerance, fmi2Real start, fmi2Boolean stop_defined,
                                  fmi2Real stop) {
    Shim *shim = c;
    if (shim == NULL) return fmi2Error;
    shim->tolerance_defined = tolerance_defined;
    shim->tolerance = tolerance;
    shim->start = start;
    shim->stop_defined = stop_defined;
    shim->stop = stop;
    return fmi2OK;
}

static fmi2Status EnterInitializationMode(fmi2Component c) {
    Shim *shim = c;
    if (shim == NULL) return (fmi2Status)fmi3.EnterInitializationMode(NULL, 0, 0, 0, 0, 0);
    return (fmi2Status)fmi3.EnterInitializationMode(shim->instance, shim->tolerance_defined,
                                                    shim->tolerance, shim->start,
                                                    shim->stop_defined, shim->stop);
}

/* FMI 2.0 Co-Simulation goes on in Step Mode; an FMI 3.0 instance made with eventModeUsed
   is in Event Mode after initialization, and gets there through it. */
static fmi2Status ExitInitializationMode(fmi2Component c) {
    fmi3Instance instance = instance_of(c);
    fmi2Status status = (fmi2Status)fmi3.ExitInitializationMode(instance);
    if (status > fmi2Warning || c == NULL || !((Shim *)c)->co_simulation) return status;
    fmi2Status update = (fmi2Status)fmi3.UpdateDiscreteStates(instance, NULL, NULL, NULL, NULL,
                                                              NULL, NULL);
    if (update > fmi2Warning) return update;
    fmi2Status step_mode = (fmi2Status)fmi3.EnterStepMode(instance);
    status = update > status ? update : status;
    return step_mode > status ? step_mode : status;
}
static fmi2Status Terminate(fmi2Component c) { return (fmi2Status)fmi3.Terminate(instance_of(c)); }
static fmi2Status Reset(fmi2Component c) { return (fmi2Status)fmi3.Reset(instance_of(c)); }

static fmi2Status GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          fmi2Real value[]) {
    return (fmi2Status)fmi3.GetFloat64(instance_of(c), vr, n, value, n);
}
static fmi2Status SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                          const fmi2Real value[]) {
    return (fmi2Status)fmi3.SetFloat64(instance_of(c), vr, n, value, n);
}
static fmi2Status GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                             fmi2Integer value[]) {
    return (fmi2Status)fmi3.GetInt32(instance_of(c), vr, n, value, n);
}
static fmi2Status SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                             const fmi2Integer value[]) {
    return (fmi2Status)fmi3.SetInt32(instance_of(c), vr, n, value, n);
}

/* fmi2Boolean is an int, fmi3Boolean a bool: copied through a buffer of the call's size. */
static fmi2Status GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                             fmi2Boolean value[]) {
    bool *values = value && n ? calloc(n, sizeof *values) : NULL;
    fmi2Status status = (fmi2Status)fmi3.GetBoolean(instance_of(c), vr, n, values, n);
    for (size_t i = 0; values && i < n; i++) value[i] = values[i];
    free(values);
    return status;
}
static fmi2Status SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                             const fmi2Boolean value[]) {
    bool *values = value && n ? calloc(n, sizeof *values) : NULL;
    for (size_t i = 0; values && i < n; i++) values[i] = value[i] != 0;
    fmi2Status status = (fmi2Status)fmi3.SetBoolean(instance_of(c), vr, n, values, n);
    free(values);
    return status;
}

static fmi2Status GetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                            fmi2String value[]) {
    return (fmi2Status)fmi3.GetString(instance_of(c), vr, n, value, n);
}
static fmi2Status SetString(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                            const fmi2String value[]) {
    return (fmi2Status)fmi3.SetString(instance_of(c), vr, n, value, n);
}

static fmi2Status GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    return (fmi2Status)fmi3.GetFMUState(instance_of(c), state);
}
static fmi2Status SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    return (fmi2Status)fmi3.SetFMUState(instance_of(c), state);
}
static fmi2Status FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    return (fmi2Status)fmi3.FreeFMUState(instance_of(c), state);
}
static fmi2Status SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    return (fmi2Status)fmi3.SerializedFMUStateSize(instance_of(c), state, size);
}
static fmi2Status SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[],
                                    size_t size) {
    return (fmi2Status)fmi3.SerializeFMUState(instance_of(c), state, (fmi3Byte *)bytes, size);
}
static fmi2Status DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                      fmi2FMUstate *state) {
    return (fmi2Status)fmi3.DeserializeFMUState(instance_of(c), (const fmi3Byte *)bytes, size,
                                                state);
}

/* A step that returns early is finished from where it returned, after event mode if the
   FMU asks for it: what an FMI 2.0 host expects of fmi2DoStep. If the rest then fails, the
   state from before the step is restored, so that a refused fmi2DoStep changes nothing. */
static fmi2Status DoStep(fmi2Component c, fmi2Real time, fmi2Real step, fmi2Boolean no_rollback) {
    fmi3Instance instance = instance_of(c);
    fmi3FMUState before = NULL;
    if (instance && fmi3.GetFMUState(instance, &before) != fmi3OK) before = NULL;
    fmi3Boolean event_needed = false, terminate, early_return = false;
    fmi3Float64 last_time = NAN, end = time + step;
    fmi2Status status = (fmi2Status)fmi3.DoStep(instance, time, step, no_rollback,
                                                &event_needed, &terminate, &early_return,
                                                &last_time);
    for (int pieces = 0; status <= fmi2Warning && early_return && last_time < end; pieces++) {
        fmi2Status next = fmi2Error; /* also for a step that never ends */
        if (pieces < 1000 &&
            (!event_needed || (fmi3.EnterEventMode(instance) == fmi3OK &&
                               fmi3.UpdateDiscreteStates(instance, NULL, NULL, NULL, NULL, NULL,
                                                         NULL) == fmi3OK &&
                               fmi3.EnterStepMode(instance) == fmi3OK)))
            next = (fmi2Status)fmi3.DoStep(instance, last_time, end - last_time, no_rollback,
                                           &event_needed, &terminate, &early_return,
                                           &last_time);
        if (next > fmi2Warning && before) {
            fmi3.SetFMUState(instance, before);
            last_time = time;
        }
        status = next > status ? next : status;
    }
    if (before) fmi3.FreeFMUState(instance, &before);
    if (c && status <= fmi2Discard) ((Shim *)c)->last_successful_time = last_time;
    return status;
}

static fmi2Status GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status *value) {
    (void)c, (void)kind, (void)value;
    return fmi2Error;
}
/* fmi2LastSuccessfulTime is what the last fmi3DoStep gave. */
static fmi2Status GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *value) {
    if (c == NULL || kind != fmi2LastSuccessfulTime || value == NULL) return fmi2Error;
    *value = ((Shim *)c)->last_successful_time;
    return fmi2OK;
}

int fmi3_as_fmi2(void *library, Fmi2Table *table) {
#define LOOKUP(name)                                                                       \
    if ((*(void **)&fmi3.name = dlsym(library, "fmi3" #name)) == NULL) return 0;
    LOOKUP(InstantiateCoSimulation) LOOKUP(InstantiateModelExchange) LOOKUP(FreeInstance)
    LOOKUP(SetDebugLogging) LOOKUP(EnterInitializationMode) LOOKUP(ExitInitializationMode)
    LOOKUP(Terminate) LOOKUP(Reset) LOOKUP(GetFloat64) LOOKUP(SetFloat64) LOOKUP(GetInt32)
    LOOKUP(SetInt32) LOOKUP(GetBoolean) LOOKUP(SetBoolean) LOOKUP(GetString) LOOKUP(SetString)
    LOOKUP(GetFMUState) LOOKUP(SetFMUState) LOOKUP(FreeFMUState) LOOKUP(SerializedFMUStateSize)
    LOOKUP(SerializeFMUState) LOOKUP(DeserializeFMUState) LOOKUP(DoStep) LOOKUP(EnterEventMode)
    LOOKUP(UpdateDiscreteStates) LOOKUP(EnterStepMode)
#undef LOOKUP
    *table = (Fmi2Table){Instantiate, FreeInstance, SetDebugLogging, SetupExperiment,
                         EnterInitializationMode, ExitInitializationMode, Terminate, Reset,
                         GetReal, GetInteger, GetBoolean, GetString, SetReal, SetInteger,
                         SetBoolean, SetString, GetFMUstate, SetFMUstate, FreeFMUstate,
                         SerializedFMUstateSize, SerializeFMUstate, DeSerializeFMUstate, DoStep,
                         GetStatus, GetRealStatus};
    return 1;
}
