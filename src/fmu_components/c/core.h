/*
 * The native runtime's core, hand-written once for every component and every FMI version:
 * an instance, what each call does to it (core.c), its co-simulation (cosimulation.c), its
 * integrator (integrator.c), its FMU states (state.c) and Model Exchange (model_exchange.c).
 * A thin face per FMI version (fmi2_face.c, fmi3_face.c) turns each FMI function into a
 * core call; the core knows no FMI header. It follows the Python runtime
 * (fmu_components.runtime: adapter.py, cosim.py, integrator.py, model.py) statement for
 * statement, so that both flavours take the same steps and give the same bits.
 *
 * No globals: everything an instance has is in its Instance, so instances are independent
 * and calls on different instances from different threads are safe; two calls on one
 * instance at once are refused (call_flag.h).
 */
#ifndef CORE_H
#define CORE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "call_flag.h"
#include "host_log.h"
#include "model.h"

/* The FMI states (FMI 2.0 sections 3.2.3 and 4.2.4; FMI 3.0 sections 3.2 and 4.2), as bits
   so a call can name where it is allowed in one mask. STEP_COMPLETE is FMI 3's Step Mode;
   STEP_FAILED follows a discarded step, until the host restores a state or resets. */
enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION_MODE = 1 << 1,
    STEP_COMPLETE = 1 << 2,
    STEP_FAILED = 1 << 3,
    TERMINATED = 1 << 4,
    EVENT_MODE = 1 << 5,
    CONTINUOUS_TIME_MODE = 1 << 6,
    INTERMEDIATE_UPDATE = 1 << 7, /* FMI 3.0: inside a step, in the host's callback */
};
#define MODES 8
#define ANY_STATE                                                                          \
    (INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED |       \
     EVENT_MODE | CONTINUOUS_TIME_MODE)
#define READABLE ((ANY_STATE & ~INSTANTIATED) | INTERMEDIATE_UPDATE)
#define SETTABLE                                                                           \
    (INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | EVENT_MODE | CONTINUOUS_TIME_MODE | \
     INTERMEDIATE_UPDATE)
#define BEFORE_INITIALIZED (INSTANTIATED | INITIALIZATION_MODE)

typedef enum { MODEL_EXCHANGE, CO_SIMULATION } Interface; /* fmi2Type's values */

/* What differs between the FMI versions in what the core says: the calls' prefix, and the
   states' names (by bit, in the order of the enum above). */
typedef struct {
    const char *prefix; /* "fmi2", "fmi3" */
    const char *mode_names[MODES];
} Face;

struct Instance;
const char *mode_name(const struct Instance *instance, int mode);

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
/* A contact's event indicator, a variable in FMI 3.0 (model_description_fmi3). */
#define EVENT_INDICATOR (RATE_FROM_DEFLECTION + 1)
#define IS_EVENT_INDICATOR(vr) (MODEL_EVENT_INDICATORS > 0 && (vr) == EVENT_INDICATOR)
/* The independent variable, declared in FMI 3.0 (readable in both). */
#define TIME_REFERENCE (RATE_FROM_DEFLECTION + 2)

struct Instance;
/* The host's intermediate update at time t inside a step (FMI 3.0 Co-Simulation): 1 when
   it asks the step to return early there. */
typedef int (*IntermediateUpdate)(struct Instance *instance, double t, int can_return_early);

typedef struct Instance {
    Snapshot s;
    ModelData data;  /* from s.values at initialization: constants and curves */
    int outputs_fresh;
    double outputs[MODEL_OUTPUTS];
    Interface type;
    const Face *face;
    HostLog log;
    char *instance_name;
    CallFlag call; /* claimed while a call runs: another thread, or the logger, is refused */
    uint32_t magic;
    /* What an FMI 3.0 Co-Simulation host allows a step (cosim_do_step_in_pieces). */
    int early_return_allowed, event_mode_used;
    IntermediateUpdate intermediate_update; /* NULL: the host takes none */
    void *intermediate_context;            /* the face's: the host's callback */
    int returned_early; /* the last step: 0 whole, RETURNED_AT_CONTACT or RETURNED_ON_REQUEST */
} Instance;

enum { RETURNED_AT_CONTACT = 1, RETURNED_ON_REQUEST = 2 };

#define INSTANCE_MAGIC 0x54565247u /* "TVRG" */

/* The opening of every call on an instance: 1 when the call may go on (and has the instance
   to itself until call_end), 0 when it is refused: no instance, another call on it not
   returned (call_flag.h), or a state where FMI does not allow the call (logged). */
int call_refused(Instance *instance, int claimed, int allowed, const char *function);

#ifndef THREAD_LOCAL
#if defined(_MSC_VER)
#define THREAD_LOCAL __declspec(thread)
#else
#define THREAD_LOCAL __thread
#endif
#endif
/* The instance whose intermediate update this thread is inside (cosimulation.c): its step
   keeps the call flag, and the host's calls from the callback, on this thread, go in. */
extern THREAD_LOCAL Instance *updating_instance;

static inline int call_begin(Instance *instance, int allowed, const char *function) {
    if (instance != NULL && instance->magic == INSTANCE_MAGIC) {
        int claimed = updating_instance == instance || call_claim(&instance->call);
        if (claimed && (instance->s.mode & allowed)) return 1;
        return call_refused(instance, claimed, allowed, function);
    }
    return 0;
}

static inline Status call_end(Instance *instance, Status status) {
    if (updating_instance != instance) call_release(&instance->call);
    return status;
}

/* A message for the host, formatted, under its status's category. */
void log_status(const Instance *instance, Status status, const char *format, ...)
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

/* --- parameters (core.c) -------------------------------------------------------------- */

/* 0 when the values make sense, else 1 with the message (variable and value named). */
int parameter_problem(const double *values, char *message, size_t size);
int variable_problem(unsigned vr, double value, char *message, size_t size);
/* Constants and curves from the parameter values (checked). */
/* STATUS_DISCARD, logged with the time and the continuous states X, for states outside the
   model's region (the damper's |z| < Z_LIMIT). */
void log_outside_region(const Instance *instance, const char *function, const double *X);
/* The index of the first of n values that is not finite, or -1. */
static inline int first_non_finite(const double *values, int n) {
    for (int i = 0; i < n; i++)
        if (!isfinite(values[i])) return i;
    return -1;
}

/* 1, logged as STATUS_DISCARD with the inputs, when one of the n values (variables from
   value reference `first` on) is not finite: an input or a host's state beyond the
   model's range overflowed it. */
int non_finite(Instance *instance, const char *function, unsigned first, const double *values,
               int n, double x, double v);
void build_model_data(ModelData *data, const double *values);

/* --- co-simulation (cosimulation.c) ------------------------------------------------- */

void cosim_start(Instance *instance);
/* 0, or 1 with a message: the model cannot take the deflection, or (beyond the bounds of
   FiniteGuard, runtime/cosim.py) an output at these inputs would not be finite. */
int cosim_input_problem(Instance *instance, double deflection, double rate, char *message,
                        size_t size);
/* As cosim_do_step, in pieces, for a host that lets the step return early or takes
   intermediate updates: a tyre's step ends where its contact begins or ends
   (RETURNED_AT_CONTACT), and the host is called back at the integrator's internal steps,
   where it may read the outputs, set the inputs or ask for an early return. A step that
   fails leaves everything as it was. */
int cosim_do_step_in_pieces(Instance *instance, double current_time, double step_size,
                            char *message, size_t size);
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

/* --- the calls (core.c, model_exchange.c, state.c) ----------------------------------------
   Each is one FMI function of either version, named `function` in messages; the face passes
   the host's arguments on and the status back. */

Instance *core_instantiate(HostLog log, const char *instance_name, Interface type,
                           const Face *face, int logging_on);
void core_free_instance(Instance *instance, const char *function);
Status core_set_debug_logging(Instance *instance, const char *function, int on, size_t n,
                              const char *const categories[]);
Status core_setup_experiment(Instance *instance, const char *function, int tolerance_defined,
                             double tolerance, double start_time);
Status core_enter_initialization_mode(Instance *instance, const char *function);
Status core_exit_initialization_mode(Instance *instance, const char *function);
Status core_terminate(Instance *instance, const char *function);
Status core_reset(Instance *instance, const char *function);
Status core_get_float64(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, double value[]);
Status core_set_float64(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, const double value[]);
/* The Boolean parameter: *flag its value (get); `last` the last value given (set). */
Status core_get_boolean(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, const void *value, int *flag);
Status core_set_boolean(Instance *instance, const char *function, const unsigned vr[],
                        size_t nvr, const void *value, int last);
Status core_no_variable_of_type(Instance *instance, const char *function, size_t nvr,
                                const unsigned vr[], int allowed);
Status core_not_offered(Instance *instance, const char *function, const char *why);
Status core_do_step(Instance *instance, const char *function, double current_time,
                    double step_size);
Status core_last_successful_time(Instance *instance, const char *function, double *value);
/* The outputs' first time derivatives at the communication point (orders all 1). */
Status core_output_derivatives(Instance *instance, const char *function, const unsigned vr[],
                               size_t nvr, const int orders[], double values[]);

Status core_enter_event_mode(Instance *instance, const char *function);
Status core_update_discrete_states(Instance *instance, const char *function);
Status core_enter_step_mode(Instance *instance, const char *function);
Status core_enter_continuous_time_mode(Instance *instance, const char *function);
Status core_completed_integrator_step(Instance *instance, const char *function);
Status core_set_time(Instance *instance, const char *function, double time);
Status core_set_continuous_states(Instance *instance, const char *function, const double x[],
                                  size_t nx);
Status core_get_derivatives(Instance *instance, const char *function, double derivatives[],
                            size_t nx);
Status core_get_event_indicators(Instance *instance, const char *function,
                                 double eventIndicators[], size_t ni);
Status core_get_continuous_states(Instance *instance, const char *function, double x[],
                                  size_t nx);
Status core_get_nominals(Instance *instance, const char *function, double x_nominal[],
                         size_t nx);
Status core_get_directional_derivative(Instance *instance, const char *function,
                                      const unsigned vUnknown_ref[], size_t nUnknown,
                                      const unsigned vKnown_ref[], size_t nKnown,
                                      const double dvKnown[], double dvUnknown[]);

Status core_get_state(Instance *instance, const char *function, void **state);
Status core_set_state(Instance *instance, const char *function, void *state);
Status core_free_state(Instance *instance, const char *function, void **state);
Status core_serialized_state_size(Instance *instance, const char *function, void *state,
                                  size_t *size);
Status core_serialize_state(Instance *instance, const char *function, void *state,
                            unsigned char bytes[], size_t size);
Status core_deserialize_state(Instance *instance, const char *function,
                              const unsigned char bytes[], size_t size, void **state);

#endif
