/*
 * The FMI 3.0 face's cost beside the FMI 2.0 one's: one C host loads a component's FMI 2.0
 * and FMI 3.0 binaries (the same core) and times the set + step + get cycle of each, in
 * alternating blocks of STEPS cycles on the same sine, with no timer inside a block.
 *
 *   bench_fmi3 STEPS REPEATS FMI2_LIBRARY FMI2_RESOURCE_URI FMI3_LIBRARY FMI3_RESOURCE_PATH
 *              TOKEN2 TOKEN3 VR_DEFLECTION VR_RATE VR_OUTPUTS MEAN AMPLITUDE FREQUENCY
 *
 * prints per repeat "FMI2_US FMI3_US".
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"
#include "fmi3Functions.h"

#define STEP 1e-3
#define MAX_OUTPUTS 8

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void *library(const char *path) {
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        fprintf(stderr, "dlopen failed: %s\n", dlerror());
        exit(2);
    }
    return handle;
}

static void *lookup(void *handle, const char *name) {
    void *function = dlsym(handle, name);
    if (function == NULL) {
        fprintf(stderr, "missing %s\n", name);
        exit(2);
    }
    return function;
}

static void fail(const char *call) {
    fprintf(stderr, "%s failed\n", call);
    exit(3);
}

static void logger2(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                 fmi2String m, ...) {
    (void)e, (void)n, (void)c;
    fprintf(stderr, "fmi2 status %d: %s\n", (int)s, m);
}

static void logger3(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m) {
    (void)e, (void)c;
    fprintf(stderr, "fmi3 status %d: %s\n", (int)s, m);
}

int main(int argc, char **argv) {
    if (argc != 15) {
        fprintf(stderr, "usage: %s STEPS REPEATS FMI2_LIBRARY FMI2_URI FMI3_LIBRARY FMI3_PATH "
                "TOKEN2 TOKEN3 VR_X VR_V VR_OUTPUTS MEAN AMPLITUDE FREQUENCY\n", argv[0]);
        return 1;
    }
    long steps = atol(argv[1]);
    int repeats = atoi(argv[2]);
    unsigned inputs[2] = {(unsigned)atoi(argv[9]), (unsigned)atoi(argv[10])}, outputs[MAX_OUTPUTS];
    size_t n_outputs = 0;
    for (char *item = strtok(argv[11], ","); item && n_outputs < MAX_OUTPUTS; item = strtok(NULL, ","))
        outputs[n_outputs++] = (unsigned)atoi(item);
    double mean = atof(argv[12]), amplitude = atof(argv[13]), frequency = atof(argv[14]);
    long total = 2 * steps * repeats + 2;
    double *x = malloc(sizeof(double) * (total + 1)), *v = malloc(sizeof(double) * total);
    for (long k = 0; k <= total; k++) x[k] = mean + amplitude * sin(2 * M_PI * frequency * k * STEP);
    for (long k = 0; k < total; k++) v[k] = (x[k + 1] - x[k]) / STEP;

    void *l2 = library(argv[3]), *l3 = library(argv[5]);
    fmi2SetRealTYPE *set2 = lookup(l2, "fmi2SetReal");
    fmi2DoStepTYPE *step2 = lookup(l2, "fmi2DoStep");
    fmi2GetRealTYPE *get2 = lookup(l2, "fmi2GetReal");
    fmi3SetFloat64TYPE *set3 = lookup(l3, "fmi3SetFloat64");
    fmi3DoStepTYPE *step3 = lookup(l3, "fmi3DoStep");
    fmi3GetFloat64TYPE *get3 = lookup(l3, "fmi3GetFloat64");

    static fmi2CallbackFunctions callbacks = {logger2, NULL, NULL, NULL, NULL};
    fmi2Component c2 = ((fmi2InstantiateTYPE *)lookup(l2, "fmi2Instantiate"))(
        "fmi2", fmi2CoSimulation, argv[7], argv[4], &callbacks, fmi2False, fmi2False);
    fmi3Instance c3 = ((fmi3InstantiateCoSimulationTYPE *)lookup(l3, "fmi3InstantiateCoSimulation"))(
        "fmi3", argv[8], argv[6], false, false, false, false, NULL, 0, NULL, logger3, NULL);
    if (c2 == NULL || c3 == NULL) fail("instantiate");
    double start[2] = {x[0], v[0]}, out[MAX_OUTPUTS];
    if (((fmi2SetupExperimentTYPE *)lookup(l2, "fmi2SetupExperiment"))(c2, fmi2False, 0, 0, fmi2False, 0) ||
        ((fmi2EnterInitializationModeTYPE *)lookup(l2, "fmi2EnterInitializationMode"))(c2) ||
        set2(c2, inputs, 2, start) ||
        ((fmi2ExitInitializationModeTYPE *)lookup(l2, "fmi2ExitInitializationMode"))(c2))
        fail("fmi2 initialization");
    if (((fmi3EnterInitializationModeTYPE *)lookup(l3, "fmi3EnterInitializationMode"))(c3, false, 0, 0, false, 0) ||
        set3(c3, inputs, 2, start, 2) ||
        ((fmi3ExitInitializationModeTYPE *)lookup(l3, "fmi3ExitInitializationMode"))(c3))
        fail("fmi3 initialization");
    long k2 = 0, k3 = 0;
    for (int r = 0; r < repeats; r++) {
        double started = now();
        for (long i = 0; i < steps; i++, k2++) {
            double in[2] = {x[k2], v[k2]};
            if (set2(c2, inputs, 2, in) > fmi2Warning || step2(c2, k2 * STEP, STEP, fmi2True) > fmi2Warning ||
                get2(c2, outputs, n_outputs, out) > fmi2Warning)
                fail("fmi2 cycle");
        }
        double fmi2_time = (now() - started) / steps;
        started = now();
        for (long i = 0; i < steps; i++, k3++) {
            double in[2] = {x[k3], v[k3]}, last;
            bool event, terminate, early;
            if (set3(c3, inputs, 2, in, 2) > fmi3Warning ||
                step3(c3, k3 * STEP, STEP, true, &event, &terminate, &early, &last) > fmi3Warning ||
                get3(c3, outputs, n_outputs, out, n_outputs) > fmi3Warning)
                fail("fmi3 cycle");
        }
        double fmi3_time = (now() - started) / steps;
        printf("%.6f %.6f\n", fmi2_time * 1e6, fmi3_time * 1e6);
    }
    return 0;
}
