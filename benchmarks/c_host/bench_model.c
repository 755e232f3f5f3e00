/*
 * The native model without FMI: compiled with an FMU's sources, it steps one instance
 * through the co-simulation layer directly (the inputs taken as fmi2SetReal takes them,
 * cosim_do_step, cosim_outputs): what the FMI calls add is the difference to bench_host.
 *
 *   bench_model STEPS REPEATS RESOURCE_URI MEAN AMPLITUDE FREQUENCY
 *       per repeat, "CYCLE_US": microseconds per inputs + step + outputs
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "core.h"
#include "cosimulation.h"
#include "fmi2Functions.h"

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc != 7) {
        fprintf(stderr, "usage: %s STEPS REPEATS RESOURCE_URI MEAN AMPLITUDE FREQUENCY\n",
                argv[0]);
        return 1;
    }
    long steps = atol(argv[1]);
    int repeats = atoi(argv[2]);
    double mean = atof(argv[4]), amplitude = atof(argv[5]), frequency = atof(argv[6]);
    long n = steps * repeats;
    double *x = malloc(sizeof(double) * (n + 2)), *v = malloc(sizeof(double) * (n + 1));
    for (long k = 0; k <= n + 1; k++) x[k] = mean + amplitude * sin(2.0 * M_PI * frequency * k * 1e-3);
    for (long k = 0; k <= n; k++) v[k] = (x[k + 1] - x[k]) / 1e-3;
    fmi2CallbackFunctions callbacks = {NULL, NULL, NULL, NULL, NULL};
    Instance *instance = fmi2Instantiate("model", fmi2CoSimulation, MODEL_INFO.guid, argv[3],
                                         &callbacks, fmi2False, fmi2False);
    if (instance == NULL) return 2;
    fmi2ValueReference inputs[2] = {INPUT_DEFLECTION, INPUT_RATE};
    fmi2SetupExperiment(instance, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(instance);
    fmi2SetReal(instance, inputs, 2, (double[]){x[0], v[0]});
    fmi2ExitInitializationMode(instance);
    char message[MESSAGE_SIZE];
    double sink = 0.0;
    long k = 0;
    for (int r = 0; r < repeats; r++) {
        double started = now();
        for (long i = 0; i < steps; i++, k++) {
            if (cosim_input_problem(instance, x[k], v[k], message, sizeof message)) return 3;
            cosim_take_inputs(instance, x[k], v[k]);
            if (cosim_do_step(instance, k * 1e-3, 1e-3, message, sizeof message) != STEP_DONE)
                return 3;
            sink += cosim_outputs(instance)[0];
        }
        printf("%.6f\n", (now() - started) / steps * 1e6);
    }
    fmi2FreeInstance(instance);
    return sink == sink ? 0 : 4;
}
