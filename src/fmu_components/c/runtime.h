/*
 * The native runtime, hand-written once for every component: an instance, its
 * co-simulation (cosimulation.c), its integrator (integrator.c), its FMU states (state.c)
 * and the FMI calls (fmi2_functions.c). It follows the Python runtime
 * (fmu_components.runtime: adapter.py, cosim.py, integrator.py, model.py) statement for
 * statement, so that both flavours take the same steps and give the same bits.
 *
 * No globals: everything an instance has is in its Instance, so instances are independent
 * and calls on different instances from different threads are safe; two calls on one
 * instance at once are refused (call_flag.h).
 */
#ifndef RUNTIME_H
#define RUNTIME_H

#include <stddef.h>
#include <stdint.h>

#include "call_flag.h"
#include "fmi2Functions.h"
#include "host_log.h"
#include "model.h"

/* FMI 2.0 states (sections 3.2.3 and 4.2.4), as bits so a call can name where it is
   allowed in one mask. */
enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION_MODE = 1 << 1,
    STEP_COMPLETE = 1 << 2,
    STEP_FAILED = 1 << 3,
    TERMINATED = 1 << 4,
    EVENT_MODE = 1 << 5,
    CONTINUOUS_TIME_MODE = 1 << 6,
};
const char *mode_name(int mode);

/* The integrator's constants (DEFAULT_RTOL, SAFETY, ..., the controller's exponent) are
   runtime/integrator.py's, written into model_config.h by the generator. */

#define W_SIZE SLOTS(MODEL_INTEGRATED * MODEL_INTEGRATED)

/* What the integrator remembers between calls (Rosenbrock: h_next, w). */
typedef struct {
    double rtol;
    int has_h_next;
    double h_next;   /* the step size the controller wants next */
    int w_uses;      /* 0: no W^-1 kept; else how many steps have used it */
    double w_h;      /* the step size it was made for */
    double w[W_SIZE];
    uint64_t accepted_steps, rejected_steps;
} Memory;

/* Everything a saved FMU state holds: what the host set and what the run has done. */
typedef struct {
    int mode;
    double values[MODEL_VARIABLES]; /* by value reference; inputs while not initialized */
    double start_time, tolerance;
    int initialized; /* the co-simulation exists: after fmi2ExitInitializationMode */
    double time, deflection, rate;
    double state[SLOTS(MODEL_STATES)];
    Memory memory;
    unsigned warned; /* bit per input: its range warning has been given */
    double last_successful_time;
    double contact;  /* Model Exchange: 1 or 0, a contact's mode as the events set it */
    int warned_states_outside; /* fmi2SetContinuousStates outside its mode: warned once */
    int rate_from_deflection; /* the Boolean parameter (value reference RATE_FROM_DEFLECTION) */
    /* The last step, for the rate check and the derived rate (runtime/cosim.py). */
    int has_previous;
    double previous_deflection, previous_rate, previous_step;
    int rate_warned; /* the rate check has warned */
} Snapshot;

/* The Boolean parameter's value reference: after every Real variable. */
#define RATE_FROM_DEFLECTION MODEL_VARIABLES

typedef struct {
    Snapshot s;
    ModelData data;  /* from s.values at initialization: constants and curves */
    int outputs_fresh;
    double outputs[MODEL_OUTPUTS];
    fmi2Type type;
    HostLog log;
    char *instance_name;
    CallFlag call; /* claimed while a call runs: another thread, or the logger, is refused */
    uint32_t magic;
} Instance;

#define INSTANCE_MAGIC 0x54565247u /* "TVRG" */

/* The opening of every call on an instance: 1 when the call may go on (and has the instance
   to itself until call_end), 0 when it is refused: no instance, another call on it not
   returned (call_flag.h), or a state where FMI does not allow the call (logged). */
int call_refused(Instance *instance, int claimed, int allowed, const char *function);

static inline int call_begin(Instance *instance, int allowed, const char *function) {
    if (instance != NULL && instance->magic == INSTANCE_MAGIC) {
        int claimed = call_claim(&instance->call);
        if (claimed && (instance->s.mode & allowed)) return 1;
        return call_refused(instance, claimed, allowed, function);
    }
    return 0;
}

static inline fmi2Status call_end(Instance *instance, fmi2Status status) {
    call_release(&instance->call);
    return status;
}

/* A message for the host, formatted, under its status's category. */
void log_status(const Instance *instance, fmi2Status status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* What the model is evaluated at now: the running instance's, or before initialization
   the relaxed component's at the current inputs (built in `scratch` and `relaxed`). */
typedef struct {
    ModelData *data;
    const double *state;
    double x, v, contact;
    ModelData scratch;
    double relaxed[SLOTS(MODEL_STATES)];
} Now;
/* 0 while the parameters make no sense. */
int model_now(Instance *instance, Now *now);
/* A contact's mode at deflection x and rate v: 1 in contact, or touching and pressing on
   (always, for two-sided components). */
double contact_at(double x, double v);

/* --- parameters (fmi2_functions.c) -------------------------------------------------- */

/* 0 when the values make sense, else 1 with the message (variable and value named). */
int parameter_problem(const double *values, char *message, size_t size);
int variable_problem(unsigned vr, double value, char *message, size_t size);
/* Constants and curves from the parameter values (checked). */
void build_model_data(ModelData *data, const double *values);

/* --- co-simulation (cosimulation.c) ------------------------------------------------- */

void cosim_start(Instance *instance);
/* 0, or 1 with a message: the model cannot take the deflection. */
int cosim_input_problem(Instance *instance, double deflection, char *message, size_t size);
/* Inputs that cosim_input_problem accepted. */
void cosim_take_inputs(Instance *instance, double deflection, double rate);
/* STEP_WARNED: done, but the rate did not fit the deflection's movement (once per run); the
   message is then the rate check's warning. */
enum { STEP_DONE, STEP_REFUSED, STEP_FAILED_TO_COMPLETE, STEP_WARNED };
int cosim_do_step(Instance *instance, double current_time, double step_size, char *message,
                  size_t size);
const double *cosim_outputs(Instance *instance);

/* --- integrator (integrator.c) ------------------------------------------------------ */

int single_step(ModelData *data, Memory *memory, double *state, double x, double u, double h);
int integrate(ModelData *data, Memory *memory, double *y, double u, double duration,
              char *message, size_t size);

#endif
