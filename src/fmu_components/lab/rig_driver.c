/*
 * The driver of an SSP rig package (fmu_components.lab.rig_package): an FMI 2.0
 * Co-Simulation FMU without inputs that plays a component's rig test input. Its outputs at
 * each communication point t are the deflection signal(t) and the secant rate to the next
 * point, (signal(t + h) - signal(t)) / h, the rate the component holds over the step (spec
 * section 4): the held-rate path then runs through every sample, as the rig drives it
 * (lab/rig.py). The next step h is taken as long as the last one; before the first, as the
 * parameter first_step.
 *
 * driver_signal.h, generated at build time, gives DRIVER_NAME, DRIVER_GUID and
 * driver_signal(t, mean, amplitude, frequency), printed from the sine of lab/signals.py.
 * Instantiation checks and logging are the runtime's (fmi2_host.h, host_log.h).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "driver_signal.h"
#include "fmi2_host.h"

/* Value references, as the package's modelDescription.xml lists them */
enum { DEFLECTION, RATE, MEAN, AMPLITUDE, FREQUENCY, FIRST_STEP, VARIABLES };
static const double START[VARIABLES] = {0.0, 0.0, DRIVER_MEAN, DRIVER_AMPLITUDE,
                                        DRIVER_FREQUENCY, DRIVER_FIRST_STEP};

typedef struct {
    HostLog log;
    double value[VARIABLES];
    double time, step; /* the last communication point and step */
    int initialization; /* parameters may be set */
    char name[];        /* the instance's name, allocated with it */
} Driver;

static fmi2Status refuse(Driver *d, const char *message) {
    host_log(&d->log, STATUS_ERROR, message);
    return fmi2Error;
}

/* The outputs at d->time, the next step taken as d->step. */
static void update(Driver *d) {
    const double *p = d->value;
    double x = driver_signal(d->time, p[MEAN], p[AMPLITUDE], p[FREQUENCY]);
    double next = driver_signal(d->time + d->step, p[MEAN], p[AMPLITUDE], p[FREQUENCY]);
    d->value[DEFLECTION] = x;
    d->value[RATE] = (next - x) / d->step;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    (void)visible;
    HostLog log;
    if (fmi2_instantiation_refused(&log, instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                   functions, DRIVER_NAME, DRIVER_GUID,
                                   1u << fmi2CoSimulation))
        return NULL;
    Driver *d = calloc(1, sizeof *d + strlen(instanceName) + 1);
    if (d == NULL) {
        host_log(&log, STATUS_ERROR, "fmi2Instantiate: out of memory");
        return NULL;
    }
    d->log = log;
    d->log.instance_name = strcpy(d->name, instanceName);
    d->log.debug_logging = loggingOn;
    memcpy(d->value, START, sizeof START);
    d->initialization = 1;
    return d;
}

void fmi2FreeInstance(fmi2Component c) {
    Driver *d = c;
    if (d == NULL) return;
    host_log_forget(&d->log);
    free(d);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    Driver *d = c;
    char problem[MESSAGE_SIZE];
    if (host_log_set(&d->log, __func__, loggingOn, nCategories, categories, problem))
        return refuse(d, problem);
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    (void)toleranceDefined, (void)tolerance, (void)stopTimeDefined, (void)stopTime;
    ((Driver *)c)->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    Driver *d = c;
    const double *p = d->value;
    if (!(isfinite(p[MEAN]) && isfinite(p[AMPLITUDE]) && p[FREQUENCY] >= 0.0 &&
          isfinite(p[FREQUENCY]) && p[FIRST_STEP] > 0.0 && isfinite(p[FIRST_STEP]))) {
        char message[MESSAGE_SIZE];
        snprintf(message, sizeof message, "fmi2ExitInitializationMode: mean = %g, amplitude "
                 "= %g, frequency = %g Hz, first_step = %g s: give finite values, the "
                 "frequency zero or positive and first_step positive", p[MEAN], p[AMPLITUDE],
                 p[FREQUENCY], p[FIRST_STEP]);
        return refuse(d, message);
    }
    d->initialization = 0;
    d->step = d->value[FIRST_STEP];
    update(d);
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) { (void)c; return fmi2OK; }

fmi2Status fmi2Reset(fmi2Component c) {
    Driver *d = c;
    memcpy(d->value, START, sizeof START);
    d->initialization = 1;
    return fmi2OK;
}

static int unknown(Driver *d, const char *function, const fmi2ValueReference vr[], size_t n,
                   unsigned first) {
    for (size_t i = 0; i < n; i++)
        if (vr[i] < first || vr[i] >= VARIABLES) {
            char message[MESSAGE_SIZE];
            snprintf(message, sizeof message, "%s: value reference %u is not one of this "
                     "driver's Reals %u to %d", function, vr[i], first, VARIABLES - 1);
            refuse(d, message);
            return 1;
        }
    return 0;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    Driver *d = c;
    if (unknown(d, __func__, vr, nvr, 0)) return fmi2Error;
    if (d->initialization) { /* the outputs of the parameters as they are now */
        d->step = d->value[FIRST_STEP];
        update(d);
    }
    for (size_t i = 0; i < nvr; i++) value[i] = d->value[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    Driver *d = c;
    if (unknown(d, __func__, vr, nvr, MEAN)) return fmi2Error;
    if (!d->initialization)
        return refuse(d, "fmi2SetReal: the driver's parameters are fixed once initialized");
    for (size_t i = 0; i < nvr; i++) d->value[vr[i]] = value[i];
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    Driver *d = c;
    if (!(communicationStepSize > 0.0))
        return refuse(d, "fmi2DoStep: the communication step must be positive");
    d->time = currentCommunicationPoint + communicationStepSize;
    d->step = communicationStepSize;
    update(d);
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return refuse(c, "fmi2CancelStep: the rig driver never steps asynchronously");
}

/* What a driver without Integers, Booleans, Strings, states or derivatives does not do:
   refused, whatever the arguments. */
#pragma GCC diagnostic ignored "-Wunused-parameter"
#define NOT_OFFERED(call, ...)                                                              \
    fmi2Status call(fmi2Component c, __VA_ARGS__) {                                          \
        return refuse(c, #call ": not offered by the rig driver");                          \
    }
NOT_OFFERED(fmi2GetInteger, const fmi2ValueReference vr[], size_t n, fmi2Integer v[])
NOT_OFFERED(fmi2GetBoolean, const fmi2ValueReference vr[], size_t n, fmi2Boolean v[])
NOT_OFFERED(fmi2GetString, const fmi2ValueReference vr[], size_t n, fmi2String v[])
NOT_OFFERED(fmi2SetInteger, const fmi2ValueReference vr[], size_t n, const fmi2Integer v[])
NOT_OFFERED(fmi2SetBoolean, const fmi2ValueReference vr[], size_t n, const fmi2Boolean v[])
NOT_OFFERED(fmi2SetString, const fmi2ValueReference vr[], size_t n, const fmi2String v[])
NOT_OFFERED(fmi2GetFMUstate, fmi2FMUstate *state)
NOT_OFFERED(fmi2SetFMUstate, fmi2FMUstate state)
NOT_OFFERED(fmi2FreeFMUstate, fmi2FMUstate *state)
NOT_OFFERED(fmi2SerializedFMUstateSize, fmi2FMUstate state, size_t *size)
NOT_OFFERED(fmi2SerializeFMUstate, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
NOT_OFFERED(fmi2DeSerializeFMUstate, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state)
NOT_OFFERED(fmi2GetDirectionalDerivative, const fmi2ValueReference u[], size_t nu,
            const fmi2ValueReference z[], size_t nz, const fmi2Real dz[], fmi2Real dv[])
NOT_OFFERED(fmi2SetRealInputDerivatives, const fmi2ValueReference vr[], size_t n,
            const fmi2Integer order[], const fmi2Real value[])
NOT_OFFERED(fmi2GetRealOutputDerivatives, const fmi2ValueReference vr[], size_t n,
            const fmi2Integer order[], fmi2Real value[])
NOT_OFFERED(fmi2GetStatus, const fmi2StatusKind s, fmi2Status *value)
NOT_OFFERED(fmi2GetRealStatus, const fmi2StatusKind s, fmi2Real *value)
NOT_OFFERED(fmi2GetIntegerStatus, const fmi2StatusKind s, fmi2Integer *value)
NOT_OFFERED(fmi2GetBooleanStatus, const fmi2StatusKind s, fmi2Boolean *value)
NOT_OFFERED(fmi2GetStringStatus, const fmi2StatusKind s, fmi2String *value)
