/*
 * A whole deflection history through the native co-simulation in one call: the fit's
 * inner simulation (fmu_components.lab.history). Compiled with a component's generated
 * model.c and the native runtime into one shared library, it makes exactly the FMI calls
 * a host makes (instantiate, setup, parameters and the first inputs in initialization
 * mode, then per sample fmi2SetReal of deflection and rate, fmi2DoStep, fmi2GetReal of
 * the load), so its forces are the built FMU's, without a host's cost per call.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define EXPORTED __attribute__((visibility("default")))

typedef struct {
    char *text;
    size_t size;
} Messages;

/* Keeps the first error message for the caller (warnings, such as an input outside the
   measured range, do not stop a history). */
static void keep_message(fmi2ComponentEnvironment environment, fmi2String instance_name,
                         fmi2Status status, fmi2String category, fmi2String message, ...) {
    (void)instance_name, (void)category;
    Messages *messages = (Messages *)environment;
    if (status < fmi2Error || messages->size == 0 || messages->text[0] != '\0') return;
    /* messages come with '%' doubled (host_log.h) */
    size_t n = 0;
    for (const char *p = message; *p && n + 1 < messages->size; p++) {
        messages->text[n++] = *p;
        if (p[0] == '%' && p[1] == '%') p++;
    }
    messages->text[n] = '\0';
}

static void *allocate(size_t n, size_t size) { return calloc(n, size); }

/* Runs the history (times[n], deflection[n], rate[n]: the rate held over step i) and writes
   the output with value reference `output` at every sample into out[n] (out[0] after
   initialization). On a failed call the rest of out is NaN and the return value is the
   index of the sample it failed at plus one (the message in message[size]); 0 on success.
   tolerance <= 0 leaves the FMU's default. */
EXPORTED int history_run(const char *guid, const char *resources, const unsigned *parameters,
                         const double *values, size_t n_parameters, unsigned deflection_ref,
                         unsigned rate_ref, unsigned output, double tolerance,
                         const double *times, const double *deflection, const double *rate,
                         size_t n, double *out, char *message, size_t size) {
    Messages messages = {message, size};
    if (size > 0) message[0] = '\0';
    for (size_t i = 0; i < n; i++) out[i] = NAN;
    if (n == 0) return 0;
    fmi2CallbackFunctions callbacks = {keep_message, allocate, free, NULL, &messages};
    fmi2Component c = fmi2Instantiate("history", fmi2CoSimulation, guid, resources, &callbacks,
                                      fmi2False, fmi2False);
    if (c == NULL) return 1;
    const fmi2ValueReference inputs[2] = {deflection_ref, rate_ref};
    size_t failed = 0;
    double first[2] = {deflection[0], rate[0]};
    if (fmi2SetupExperiment(c, tolerance > 0.0, tolerance, times[0], fmi2False, 0.0) > fmi2Warning
        || fmi2EnterInitializationMode(c) > fmi2Warning
        || fmi2SetReal(c, parameters, n_parameters, values) > fmi2Warning
        || fmi2SetReal(c, inputs, 2, first) > fmi2Warning
        || fmi2ExitInitializationMode(c) > fmi2Warning
        || fmi2GetReal(c, &output, 1, &out[0]) > fmi2Warning) {
        failed = 1;
    }
    for (size_t i = 0; !failed && i + 1 < n; i++) {
        double now[2] = {deflection[i], rate[i]};
        if (fmi2SetReal(c, inputs, 2, now) > fmi2Warning
            || fmi2DoStep(c, times[i], times[i + 1] - times[i], fmi2True) > fmi2Warning
            || fmi2GetReal(c, &output, 1, &out[i + 1]) > fmi2Warning) {
            out[i + 1] = NAN;
            failed = i + 2;
        }
    }
    fmi2FreeInstance(c);
    return (int)failed;
}
