/*
 * An instance of a native FMU (instance.c), below every call that works on it: what it
 * holds (the host's values, the run's Snapshot, the model data built from the parameters),
 * its FMI state and the call sequence checked on entry (call_begin, call_end), its
 * messages, its values checked (parameter_problem, variable_problem), and the model
 * evaluated at the instance's current point (model_now). The calls (core.c, cosimulation.c,
 * model_exchange.c, state.c) and the faces stand on it; it calls none of them.
 *
 * No globals: everything an instance has is in its Instance, so instances are independent
 * and calls on different instances from different threads are safe; two calls on one
 * instance at once are refused (call_flag.h).
 */
#ifndef INSTANCE_H
#define INSTANCE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "call_flag.h"
#include "host_log.h"
#include "integrator.h"
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
    int declares_fmi3_variables; /* the event indicator and time are variables */
    int enters_event_mode_from; /* the modes fmiXEnterEventMode is allowed in */
} Face;

struct Instance;
const char *mode_name(const struct Instance *instance, int mode);

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
/* A contact's event indicator and the independent variable: Float64 variables that FMI 3.0
   declares and FMI 2.0 does not (Face.declares_fmi3_variables). */
#define IS_EVENT_INDICATOR(vr) (MODEL_EVENT_INDICATORS > 0 && (vr) == MODEL_EVENT_INDICATOR_REFERENCE)
#define TIME_REFERENCE MODEL_TIME_REFERENCE

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
    /* The contact change the last step returned at: its time, and 1 if the contact began
       there (0 if it ended). */
    double contact_change_time;
    int contact_change_to;
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

/* --- values and model data ------------------------------------------------------------ */

/* 0 when the values make sense, else 1 with the message (variable and value named). */
int parameter_problem(const double *values, char *message, size_t size);
int variable_problem(unsigned vr, double value, char *message, size_t size);
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
/* Constants and curves from the parameter values (checked). */
void build_model_data(ModelData *data, const double *values);
/* The instance as fmi2Instantiate or fmi2Reset leave it: start values, nothing run. */
void reset_instance(Instance *instance);

#endif
