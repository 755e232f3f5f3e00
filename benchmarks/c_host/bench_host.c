/*
 * The benchmark's C host: loads FMU binaries with dlopen, feeds every instance its thesis
 * sine (the deflection at each step and the secant rate, computed before timing starts)
 * and times the FMI calls itself, as an engineer's C or C++ host would make them.
 *
 *   bench_host cost STEPS REPEATS SPEC
 *       one instance; per repeat, "DO_STEP_US CYCLE_US": microseconds per fmi2DoStep
 *       (each call timed, the clock's least cost taken off) and per fmi2SetReal (both
 *       inputs) + fmi2DoStep + fmi2GetReal (every output), timed over the next STEPS
 *       cycles as a whole, with no timer inside
 *   bench_host rollback STEPS REPEATS SPEC
 *       one instance; per repeat, "PLAIN_US CORRECTED_US GET_NS SET_NS CORRECTED_CPU_US":
 *       microseconds per
 *       plain cycle (as above) and per corrected cycle (fmi2GetFMUstate into the state it
 *       keeps, cycle, fmi2SetFMUstate back, cycle again: what the coupling library's
 *       corrected scheme asks of each FMU per host step), then nanoseconds per
 *       fmi2GetFMUstate and per fmi2SetFMUstate alone, each timed over STEPS calls, then
 *       the corrected cycle's CPU time (us, the process's)
 *   bench_host vehicle STEPS SPEC...
 *       every instance of every SPEC stepped together at 1 ms: "WALL_S INSTANCES"
 *
 * SPEC is ten arguments: COUNT BINARY RESOURCE_URI GUID VR_DEFLECTION VR_RATE VR_OUTPUTS
 * (comma-separated) MEAN AMPLITUDE FREQUENCY. Instance k of a SPEC runs the sine at phase
 * 2 pi (k mod 4) / 4.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#define STEP 1e-3
#define MAX_OUTPUTS 8
#define PHASES 4

typedef struct {
    fmi2SetRealTYPE *set_real;
    fmi2GetRealTYPE *get_real;
    fmi2DoStepTYPE *do_step;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2Component component;
    fmi2ValueReference inputs[2], outputs[MAX_OUTPUTS];
    size_t n_outputs;
    const double *x, *v; /* deflection and secant rate at each step */
} Instance;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env, (void)category;
    fprintf(stderr, "%s status %d: %s\n", name, (int)status, message);
}

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

/* the process's CPU time: on a loaded machine, what a comparison with a CPU time needs */
static double cpu_now(void) {
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

static void *lookup(void *library, const char *name) {
    void *function = dlsym(library, name);
    if (function == NULL) {
        fprintf(stderr, "missing %s\n", name);
        exit(2);
    }
    return function;
}

static void check(fmi2Status status, const char *call) {
    if (status > fmi2Warning) {
        fprintf(stderr, "%s returned %d\n", call, (int)status);
        exit(3);
    }
}

/* The sine of one phase: deflection at steps 0..steps and the secant rate of each step. */
static void sine(double mean, double amplitude, double frequency, double phase, long steps,
                 double **x, double **v) {
    *x = malloc(sizeof(double) * (steps + 2));
    *v = malloc(sizeof(double) * (steps + 1));
    for (long k = 0; k <= steps + 1; k++)
        (*x)[k] = mean + amplitude * sin(2.0 * M_PI * frequency * k * STEP + phase);
    for (long k = 0; k <= steps; k++) (*v)[k] = ((*x)[k + 1] - (*x)[k]) / STEP;
}

/* Instantiate `count` instances of one SPEC (argv[0..9]) and initialize them. */
static Instance *load(char **spec, long steps, int *count) {
    *count = atoi(spec[0]);
    void *library = dlopen(spec[1], RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        fprintf(stderr, "dlopen failed: %s\n", dlerror());
        exit(2);
    }
    fmi2InstantiateTYPE *instantiate = lookup(library, "fmi2Instantiate");
    fmi2SetupExperimentTYPE *setup = lookup(library, "fmi2SetupExperiment");
    fmi2EnterInitializationModeTYPE *enter = lookup(library, "fmi2EnterInitializationMode");
    fmi2ExitInitializationModeTYPE *exit_initialization =
        lookup(library, "fmi2ExitInitializationMode");
    static fmi2CallbackFunctions callbacks = {logger, NULL, NULL, NULL, NULL};
    double *x[PHASES], *v[PHASES];
    for (int p = 0; p < PHASES; p++)
        sine(atof(spec[7]), atof(spec[8]), atof(spec[9]), 2.0 * M_PI * p / PHASES, steps, &x[p],
             &v[p]);
    Instance *instances = calloc(*count, sizeof(Instance));
    for (int i = 0; i < *count; i++) {
        Instance *instance = &instances[i];
        instance->set_real = lookup(library, "fmi2SetReal");
        instance->get_real = lookup(library, "fmi2GetReal");
        instance->do_step = lookup(library, "fmi2DoStep");
        instance->free_instance = lookup(library, "fmi2FreeInstance");
        instance->get_state = lookup(library, "fmi2GetFMUstate");
        instance->set_state = lookup(library, "fmi2SetFMUstate");
        instance->free_state = lookup(library, "fmi2FreeFMUstate");
        instance->inputs[0] = (fmi2ValueReference)atoi(spec[4]);
        instance->inputs[1] = (fmi2ValueReference)atoi(spec[5]);
        for (char *item = strtok(strdup(spec[6]), ","); item && instance->n_outputs < MAX_OUTPUTS;
             item = strtok(NULL, ","))
            instance->outputs[instance->n_outputs++] = (fmi2ValueReference)atoi(item);
        instance->x = x[i % PHASES];
        instance->v = v[i % PHASES];
        char name[32];
        snprintf(name, sizeof name, "instance%d", i);
        instance->component = instantiate(name, fmi2CoSimulation, spec[3], spec[2], &callbacks,
                                          fmi2False, fmi2False);
        if (instance->component == NULL) {
            fprintf(stderr, "fmi2Instantiate failed\n");
            exit(2);
        }
        check(setup(instance->component, fmi2False, 0.0, 0.0, fmi2False, 0.0), "setup");
        check(enter(instance->component), "enter");
        fmi2Real start[2] = {instance->x[0], instance->v[0]};
        check(instance->set_real(instance->component, instance->inputs, 2, start), "set");
        check(exit_initialization(instance->component), "exit");
    }
    return instances;
}

/* One set + step + get of an instance at step k. */
static void cycle(Instance *instance, long k) {
    fmi2Real inputs[2] = {instance->x[k], instance->v[k]}, outputs[MAX_OUTPUTS];
    check(instance->set_real(instance->component, instance->inputs, 2, inputs), "fmi2SetReal");
    check(instance->do_step(instance->component, k * STEP, STEP, fmi2True), "fmi2DoStep");
    check(instance->get_real(instance->component, instance->outputs, instance->n_outputs,
                             outputs), "fmi2GetReal");
}

/* The clock's own cost: the least of several batches, so that a batch the busy machine
   interrupted does not inflate what is taken off each timed doStep. */
static double clock_cost(void) {
    double least = 1.0;
    for (int batch = 0; batch < 50; batch++) {
        double started = now();
        for (int i = 0; i < 1000; i++) now();
        double each = (now() - started) / 1000;
        if (each < least) least = each;
    }
    return least;
}

static int cost(long steps, int repeats, char **spec) {
    int count;
    Instance *instance = load(spec, 2 * steps * repeats, &count);
    double overhead = clock_cost();
    long k = 0;
    for (int r = 0; r < repeats; r++) {
        /* doStep alone: each call timed, the clock's cost taken off */
        double stepping = 0.0;
        for (long i = 0; i < steps; i++, k++) {
            fmi2Real inputs[2] = {instance->x[k], instance->v[k]}, outputs[MAX_OUTPUTS];
            check(instance->set_real(instance->component, instance->inputs, 2, inputs), "set");
            double before = now();
            check(instance->do_step(instance->component, k * STEP, STEP, fmi2True), "step");
            stepping += now() - before;
            check(instance->get_real(instance->component, instance->outputs,
                                     instance->n_outputs, outputs), "get");
        }
        /* the whole cycle: the next steps with no timer inside, so nothing is taken off */
        double started = now();
        for (long i = 0; i < steps; i++, k++) cycle(instance, k);
        double total = now() - started;
        printf("%.6f %.6f\n", (stepping / steps - overhead) * 1e6, total / steps * 1e6);
    }
    instance->free_instance(instance->component);
    return 0;
}

static int rollback(long steps, int repeats, char **spec) {
    int count;
    Instance *instance = load(spec, 2 * steps * repeats, &count);
    fmi2FMUstate state = NULL;
    fmi2Component c = instance->component;
    check(instance->get_state(c, &state), "fmi2GetFMUstate");
    long k = 0;
    for (int r = 0; r < repeats; r++) {
        double started = now();
        for (long i = 0; i < steps; i++, k++) cycle(instance, k);
        double plain = (now() - started) / steps;
        started = now();
        double cpu_started = cpu_now();
        for (long i = 0; i < steps; i++, k++) {
            check(instance->get_state(c, &state), "fmi2GetFMUstate");
            cycle(instance, k);
            check(instance->set_state(c, state), "fmi2SetFMUstate");
            cycle(instance, k);
        }
        double corrected = (now() - started) / steps;
        double corrected_cpu = (cpu_now() - cpu_started) / steps;
        started = now();
        for (long i = 0; i < steps; i++) check(instance->get_state(c, &state), "get");
        double get = (now() - started) / steps;
        started = now();
        for (long i = 0; i < steps; i++) check(instance->set_state(c, state), "set");
        double set = (now() - started) / steps;
        printf("%.6f %.6f %.3f %.3f %.6f\n", plain * 1e6, corrected * 1e6, get * 1e9, set * 1e9,
               corrected_cpu * 1e6);
    }
    check(instance->free_state(c, &state), "fmi2FreeFMUstate");
    instance->free_instance(c);
    return 0;
}

static int vehicle(long steps, int argc, char **argv) {
    int groups = argc / 10, total = 0;
    Instance **fleets = malloc(sizeof(Instance *) * groups);
    int *counts = malloc(sizeof(int) * groups);
    for (int g = 0; g < groups; g++) {
        fleets[g] = load(argv + 10 * g, steps, &counts[g]);
        total += counts[g];
    }
    double started = now();
    for (long k = 0; k < steps; k++)
        for (int g = 0; g < groups; g++)
            for (int i = 0; i < counts[g]; i++) cycle(&fleets[g][i], k);
    printf("%.6f %d\n", now() - started, total);
    for (int g = 0; g < groups; g++)
        for (int i = 0; i < counts[g]; i++) fleets[g][i].free_instance(fleets[g][i].component);
    return 0;
}

int main(int argc, char **argv) {
    if (argc == 14 && strcmp(argv[1], "cost") == 0)
        return cost(atol(argv[2]), atoi(argv[3]), argv + 4);
    if (argc == 14 && strcmp(argv[1], "rollback") == 0)
        return rollback(atol(argv[2]), atoi(argv[3]), argv + 4);
    if (argc >= 13 && strcmp(argv[1], "vehicle") == 0 && (argc - 3) % 10 == 0)
        return vehicle(atol(argv[2]), argc - 3, argv + 3);
    fprintf(stderr, "usage: %s cost|rollback STEPS REPEATS SPEC | vehicle STEPS SPEC...\n", argv[0]);
    return 1;
}
