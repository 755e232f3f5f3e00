/*
 * The native floor: an FMI 2.0 Co-Simulation FMU with a component's inputs and outputs and
 * no work in it (force = deflection), no checks, no logging. What a host's calls cost by
 * themselves; benchmarks/run.py builds it in the run and measures it next to the FMUs.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define VARIABLES 6 /* deflection, rate, force, force_elastic, force_viscoelastic, stiffness */

typedef struct {
    double values[VARIABLES];
} Floor;

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid,
                              fmi2String resources, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean logging) {
    (void)name, (void)type, (void)guid, (void)resources, (void)functions, (void)visible;
    (void)logging;
    return calloc(1, sizeof(Floor));
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       const fmi2Real value[]) {
    for (size_t i = 0; i < n; i++) ((Floor *)c)->values[vr[i]] = value[i];
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                       fmi2Real value[]) {
    for (size_t i = 0; i < n; i++) value[i] = ((Floor *)c)->values[vr[i]];
    return fmi2OK;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)t, (void)h, (void)no_prior;
    ((Floor *)c)->values[2] = ((Floor *)c)->values[0];
    return fmi2OK;
}

/* Everything else a host may look up: accepted and ignored, or not offered. */
#define ACCEPT(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2OK; }
#define REFUSE(name, ...) fmi2Status name(__VA_ARGS__) { return fmi2Error; }
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
ACCEPT(fmi2SetDebugLogging, fmi2Component c, fmi2Boolean on, size_t n, const fmi2String k[])
ACCEPT(fmi2SetupExperiment, fmi2Component c, fmi2Boolean a, fmi2Real b, fmi2Real d,
       fmi2Boolean e, fmi2Real f)
ACCEPT(fmi2EnterInitializationMode, fmi2Component c)
ACCEPT(fmi2ExitInitializationMode, fmi2Component c)
ACCEPT(fmi2Terminate, fmi2Component c)
ACCEPT(fmi2Reset, fmi2Component c)
REFUSE(fmi2GetInteger, fmi2Component c, const fmi2ValueReference v[], size_t n, fmi2Integer x[])
REFUSE(fmi2GetBoolean, fmi2Component c, const fmi2ValueReference v[], size_t n, fmi2Boolean x[])
REFUSE(fmi2GetString, fmi2Component c, const fmi2ValueReference v[], size_t n, fmi2String x[])
REFUSE(fmi2SetInteger, fmi2Component c, const fmi2ValueReference v[], size_t n,
       const fmi2Integer x[])
REFUSE(fmi2SetBoolean, fmi2Component c, const fmi2ValueReference v[], size_t n,
       const fmi2Boolean x[])
REFUSE(fmi2SetString, fmi2Component c, const fmi2ValueReference v[], size_t n,
       const fmi2String x[])
REFUSE(fmi2GetFMUstate, fmi2Component c, fmi2FMUstate *s)
REFUSE(fmi2SetFMUstate, fmi2Component c, fmi2FMUstate s)
REFUSE(fmi2FreeFMUstate, fmi2Component c, fmi2FMUstate *s)
REFUSE(fmi2SerializedFMUstateSize, fmi2Component c, fmi2FMUstate s, size_t *n)
REFUSE(fmi2SerializeFMUstate, fmi2Component c, fmi2FMUstate s, fmi2Byte b[], size_t n)
REFUSE(fmi2DeSerializeFMUstate, fmi2Component c, const fmi2Byte b[], size_t n, fmi2FMUstate *s)
REFUSE(fmi2GetDirectionalDerivative, fmi2Component c, const fmi2ValueReference u[], size_t n,
       const fmi2ValueReference k[], size_t m, const fmi2Real dk[], fmi2Real du[])
REFUSE(fmi2SetRealInputDerivatives, fmi2Component c, const fmi2ValueReference v[], size_t n,
       const fmi2Integer o[], const fmi2Real x[])
REFUSE(fmi2GetRealOutputDerivatives, fmi2Component c, const fmi2ValueReference v[], size_t n,
       const fmi2Integer o[], fmi2Real x[])
REFUSE(fmi2CancelStep, fmi2Component c)
REFUSE(fmi2GetStatus, fmi2Component c, const fmi2StatusKind s, fmi2Status *x)
REFUSE(fmi2GetRealStatus, fmi2Component c, const fmi2StatusKind s, fmi2Real *x)
REFUSE(fmi2GetIntegerStatus, fmi2Component c, const fmi2StatusKind s, fmi2Integer *x)
REFUSE(fmi2GetBooleanStatus, fmi2Component c, const fmi2StatusKind s, fmi2Boolean *x)
REFUSE(fmi2GetStringStatus, fmi2Component c, const fmi2StatusKind s, fmi2String *x)
