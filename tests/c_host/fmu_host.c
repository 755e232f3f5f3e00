/*
 * A minimal FMI 2.0 co-simulation host in C: loads an FMU's linux64 binary (or, built
 * with mingw-w64, its win64 DLL), runs a sine
 * through it and prints "time,output" per step. Used by the tests to show that the FMUs
 * load and run in a host that is not Python (no LD_PRELOAD, no Python of its own).
 *
 *   fmu_host BINARY RESOURCE_URI GUID VR_DEFLECTION VR_RATE VR_OUTPUT MEAN AMPLITUDE
 *            FREQUENCY STEP STOP [bad-input]
 *
 * With "bad-input", a NaN deflection and a negative step are sent at the middle of the
 * run; each must be answered with fmi2Error, after which the run continues. The exit code
 * is 0 only if every call returned what it should.
 */

#ifdef _WIN32
#include <windows.h>
#define dlsym(library, name) ((void *)GetProcAddress(library, name))
#else
#include <dlfcn.h>
#endif
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>

#include "fmi2Functions.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "[%s] %s status %d: ", category ? category : "", name, (int)status);
    vfprintf(stderr, message, args);
    fprintf(stderr, "\n");
    va_end(args);
}

#define LOOKUP(type, name)                                                                 \
    type *name = (type *)dlsym(library, #name);                                            \
    if (!name) { fprintf(stderr, "missing %s\n", #name); return 2; }

#define EXPECT(call, expected)                                                             \
    do {                                                                                   \
        fmi2Status s = (call);                                                             \
        if (s != (expected)) {                                                             \
            fprintf(stderr, "%s returned %d, expected %d\n", #call, (int)s, (int)(expected)); \
            return 3;                                                                      \
        }                                                                                  \
    } while (0)

int main(int argc, char **argv) {
    if (argc < 12) {
        fprintf(stderr, "usage: %s BINARY RESOURCE_URI GUID VR_DEFLECTION VR_RATE VR_OUTPUT "
                        "MEAN AMPLITUDE FREQUENCY STEP STOP [bad-input]\n", argv[0]);
        return 1;
    }
#ifdef _WIN32
    HMODULE library = LoadLibraryA(argv[1]);
    if (!library) {
        fprintf(stderr, "LoadLibraryA failed: error %lu\n", (unsigned long)GetLastError());
        return 2;
    }
#else
    void *library = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        fprintf(stderr, "dlopen failed: %s\n", dlerror());
        return 2;
    }
#endif
    LOOKUP(fmi2InstantiateTYPE, fmi2Instantiate)
    LOOKUP(fmi2SetupExperimentTYPE, fmi2SetupExperiment)
    LOOKUP(fmi2EnterInitializationModeTYPE, fmi2EnterInitializationMode)
    LOOKUP(fmi2ExitInitializationModeTYPE, fmi2ExitInitializationMode)
    LOOKUP(fmi2SetRealTYPE, fmi2SetReal)
    LOOKUP(fmi2GetRealTYPE, fmi2GetReal)
    LOOKUP(fmi2DoStepTYPE, fmi2DoStep)
    LOOKUP(fmi2TerminateTYPE, fmi2Terminate)
    LOOKUP(fmi2FreeInstanceTYPE, fmi2FreeInstance)

    fmi2ValueReference inputs[2] = {(fmi2ValueReference)atoi(argv[4]),
                                    (fmi2ValueReference)atoi(argv[5])};
    fmi2ValueReference output = (fmi2ValueReference)atoi(argv[6]);
    double mean = atof(argv[7]), amplitude = atof(argv[8]), frequency = atof(argv[9]);
    double step = atof(argv[10]), stop = atof(argv[11]);
    int bad_input = argc > 12;
    double omega = 2.0 * M_PI * frequency;

    fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};
    fmi2Component c = fmi2Instantiate("c-host", fmi2CoSimulation, argv[3], argv[2],
                                      &callbacks, fmi2False, fmi2False);
    if (!c) {
        fprintf(stderr, "fmi2Instantiate failed\n");
        return 2;
    }
    EXPECT(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), fmi2OK);
    EXPECT(fmi2EnterInitializationMode(c), fmi2OK);
    fmi2Real start[2] = {mean, amplitude * omega};
    EXPECT(fmi2SetReal(c, inputs, 2, start), fmi2OK);
    EXPECT(fmi2ExitInitializationMode(c), fmi2OK);

    long steps = lround(stop / step);
    for (long k = 0; k < steps; k++) {
        double t = k * step;
        fmi2Real values[2] = {mean + amplitude * sin(omega * t), amplitude * omega * cos(omega * t)};
        if (bad_input && k == steps / 2) {
            fmi2Real nan_values[2] = {NAN, values[1]};
            EXPECT(fmi2SetReal(c, inputs, 2, nan_values), fmi2Error);
            EXPECT(fmi2DoStep(c, t, -step, fmi2True), fmi2Error);
        }
        EXPECT(fmi2SetReal(c, inputs, 2, values), fmi2OK);
        EXPECT(fmi2DoStep(c, t, step, fmi2True), fmi2OK);
        fmi2Real value;
        EXPECT(fmi2GetReal(c, &output, 1, &value), fmi2OK);
        printf("%.17g,%.17g\n", t + step, value);
    }
    EXPECT(fmi2Terminate(c), fmi2OK);
    fmi2FreeInstance(c);
#ifdef _WIN32
    FreeLibrary(library);
#else
    dlclose(library);
#endif
    return 0;
}
