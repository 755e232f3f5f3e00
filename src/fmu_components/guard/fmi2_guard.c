/*
 * The binary of every Python-flavour FMU: a thin FMI 2.0 layer in front of pythonfmu's
 * library.
 *
 * pythonfmu's library (shipped next to this one as PYTHONFMU_ENGINE) runs the Python
 * adapter, but it can only answer fmi2OK, fmi2Discard (a step returned False) or fmi2Fatal
 * (a Python exception, after which the instance is gone and the next call crashes the host),
 * and it expects the Python C API to be present in the process already. This layer
 *
 *  - checks what fmi2Instantiate is given (interface type, GUID, resource location) as the
 *    native runtime does (instantiation.c), before Python sees it;
 *  - returns, for every call, the worst of pythonfmu's status and the statuses the adapter
 *    logged during the call, so a rejected input is fmi2Error and a warning fmi2Warning;
 *  - loads pythonfmu's library, and Python for a C host, so C hosts need no LD_PRELOAD
 *    (python_engine.c);
 *  - stops calling an instance that reported fmi2Fatal, so the host is never crashed by it,
 *    and refuses a call while another on the same instance has not returned (a second
 *    thread, or a logger calling back: call_flag.h);
 *  - keeps one Python thread state for each host thread that has none of its own
 *    (python_engine.c);
 *  - always lets pythonfmu log (it drops every message unless debug logging is on) and
 *    applies the host's logging choice itself (host_log.c, shared with the native runtime);
 *  - wraps serialized states in the envelope the native runtime uses (state_envelope.c:
 *    format version, GUID, checksum), and refuses a broken one before Python sees it;
 *  - answers fmi2GetRealStatus(fmi2LastSuccessfulTime) after a discarded step;
 *  - hashes the Python in the resources folder when an instance is made from it, and
 *    refuses a copy whose Python is not what the build wrote (PYTHON_CONTENT,
 *    python_content.c);
 *  - keeps freed instances for reuse (the pool).
 *
 * Everything else is forwarded unchanged.
 */

#define _GNU_SOURCE
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "call_flag.h"
#include "fmi2Functions.h"
#include "host_log.h"
#include "fmi2_host.h"
#include "instantiation.h"
#include "python_content.h"
#include "python_engine.h"
#include "state_envelope.h"

#if !defined(FMU_GUID) || !defined(FMU_NAME)
#error "build with -DFMU_GUID=\"...\" -DFMU_NAME=\"...\" (the FMU's GUID and model name)"
#endif
#ifndef PYTHON_CONTENT
#error "build with -DPYTHON_CONTENT=\"...\" (export/build.py, python_content_hash)"
#endif
#define STATE_FORMAT_VERSION 1u
#define PENDING_MESSAGES 8

typedef struct Guard {
    fmi2Component engine;
    fmi2CallbackFunctions engine_callbacks; /* the host's, with our logger in between */
    HostLog log;                            /* the host's logger and logging choice */
    char *instance_name;
    fmi2Status worst; /* worst status logged during the current call */
    /* Messages pythonfmu logs during a call, passed on when it has returned: a host's
       logger then never runs inside pythonfmu (which re-delivers its queue when the logger
       calls back into the FMU). */
    struct {
        fmi2Status status;
        char category[32];
        char text[MESSAGE_SIZE];
    } pending[PENDING_MESSAGES];
    int n_pending, n_dropped;
    int fatal;        /* the engine reported fmi2Fatal: never call it again */
    CallFlag call;    /* claimed while a call runs: another thread, or the logger, is refused */
    struct Guard *outer; /* the instance this thread was calling before this one */
    fmi2Real last_successful_time;
    char *resource_location; /* what pythonfmu's instance was made with */
} Guard;

/* The instance whose call this thread is inside, for fmu_guard_log. */
static __thread Guard *calling;

/* Freed instances kept for reuse. pythonfmu 0.7.0 keeps about 2 KiB per instance it makes
   and never gives it back (a sys.path entry, a class made from the entry module's source);
   an instance reset through fmi2Reset makes a fresh slave without any of that. A reused
   instance keeps its Guard, whose engine_callbacks pythonfmu refers to. The pool is not
   emptied when the library is unloaded: the interpreter may already be finalized then. */
#define POOL_SIZE 4
static pthread_mutex_t pool_lock = PTHREAD_MUTEX_INITIALIZER;
static Guard *pool[POOL_SIZE];
static int pool_count;

static Guard *pool_take(const char *resource_location) {
    Guard *found = NULL;
    pthread_mutex_lock(&pool_lock);
    for (int i = 0; i < pool_count && found == NULL; i++)
        if (strcmp(pool[i]->resource_location, resource_location) == 0) {
            found = pool[i];
            pool[i] = pool[--pool_count];
        }
    pthread_mutex_unlock(&pool_lock);
    return found;
}

static int pool_put(Guard *guard) {
    int kept = 0;
    pthread_mutex_lock(&pool_lock);
    if (pool_count < POOL_SIZE) {
        pool[pool_count++] = guard;
        kept = 1;
    }
    pthread_mutex_unlock(&pool_lock);
    return kept;
}

static void release(Guard *guard) {
    host_log_forget(&guard->log);
    free(guard->instance_name);
    free(guard->resource_location);
    free(guard);
}

/* The guard's own error messages. */
static fmi2Status guard_error(const Guard *guard, const char *format, ...) {
    char message[MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    host_log(&guard->log, STATUS_ERROR, message);
    return fmi2Error;
}

/* Remember the worst status seen during the call, and keep the message if the host wants
   it, to pass on when pythonfmu has returned. */
static void guard_logger(fmi2ComponentEnvironment environment, fmi2String instance_name,
                         fmi2Status status, fmi2String category, fmi2String message, ...) {
    (void)instance_name;
    Guard *guard = (Guard *)environment;
    if (status > guard->worst) guard->worst = status;
    if (!host_log_wants(&guard->log, (Status)status, category)) return;
    if (guard->n_pending == PENDING_MESSAGES) {
        guard->n_dropped++;
        return;
    }
    int i = guard->n_pending++;
    guard->pending[i].status = status;
    snprintf(guard->pending[i].category, sizeof guard->pending[i].category, "%s",
             category ? category : "");
    snprintf(guard->pending[i].text, sizeof guard->pending[i].text, "%s", message ? message : "");
}

/* The opening of every call that has claimed the instance. */
static void enter(Guard *guard) {
    guard->outer = calling;
    calling = guard;
    guard->worst = fmi2OK;
    python_thread_enter();
}

/* A call that found another on the instance not returned: refused, touching nothing. */
static fmi2Status overlapping(Guard *guard, const char *function) {
    host_log_overlap(&guard->log, &guard->call, function);
    return fmi2Error;
}

/* The end of every call: the messages kept during it go to the host (the instance still
   claimed, so a logger calling back is refused), then the call's status. */
static fmi2Status finish(Guard *guard, fmi2Status status) {
    for (int i = 0; i < guard->n_pending; i++)
        host_log_send(&guard->log, (Status)guard->pending[i].status, guard->pending[i].category,
                      guard->pending[i].text);
    if (guard->n_dropped) {
        char message[96];
        snprintf(message, sizeof message, "%d more messages of this call were dropped",
                 guard->n_dropped);
        host_log_send(&guard->log, STATUS_WARNING, "logStatusWarning", message);
    }
    guard->n_pending = guard->n_dropped = 0;
    calling = guard->outer;
    call_release(&guard->call);
    return status;
}

static fmi2Status refuse(Guard *guard, const char *function) {
    return guard_error(guard, "%s refused: this instance failed fatally; free it", function);
}

static fmi2Status settle(Guard *guard, fmi2Status status) {
    if (status > guard->worst) guard->worst = status;
    if (guard->worst == fmi2Fatal) guard->fatal = 1;
    return guard->worst;
}

/* The adapter's way to log (runtime/adapter.py): straight to the instance this thread is
   calling, rather than through pythonfmu's log queue, which keeps about 190 bytes of every
   message it passes on. 0 if this thread is inside no call of this library. */
__attribute__((visibility("default"))) int fmu_guard_log(int status, const char *category,
                                                         const char *message) {
    if (calling == NULL) return 0;
    guard_logger(calling, NULL, (fmi2Status)status, category, message);
    return 1;
}

/* The opening of every call passed to pythonfmu: the instance, claimed, with the call's
   worst status started at fmi2OK; or NULL, with the status to return in *refused, for a
   missing instance, one with another call not returned, or one that failed fatally. */
static Guard *open_call(fmi2Component c, const char *function, fmi2Status *refused) {
    Guard *guard = (Guard *)c;
    *refused = fmi2Error;
    if (guard == NULL) return NULL;
    if (!call_claim(&guard->call)) {
        *refused = overlapping(guard, function);
        return NULL;
    }
    enter(guard);
    if (guard->fatal) {
        *refused = finish(guard, refuse(guard, function));
        return NULL;
    }
    return guard;
}

/* The end of a call passed to pythonfmu: the worst of its status and those logged. */
static fmi2Status close_call(Guard *guard, fmi2Status status) {
    return finish(guard, settle(guard, status));
}

/* open_call for a call that gives pythonfmu n values, which it reads without looking:
   arrays that are NULL are refused here. */
static Guard *open_values_call(fmi2Component c, const char *function, size_t n,
                               const void *references, const void *values,
                               fmi2Status *refused) {
    Guard *guard = open_call(c, function, refused);
    if (guard == NULL || n == 0 || (references != NULL && values != NULL)) return guard;
    *refused = finish(guard, guard_error(guard, "%s: %u values announced but an array is "
                                         "NULL; call ignored", function, (unsigned)n));
    return NULL;
}

/* A call that gives pythonfmu nothing but the instance. */
static fmi2Status forward(fmi2Component c, const char *function,
                          fmi2Status (*call)(fmi2Component)) {
    fmi2Status refused;
    Guard *guard = open_call(c, function, &refused);
    return guard ? close_call(guard, call(guard->engine)) : refused;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    HostLog log;
    if (fmi2_instantiation_refused(&log, instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                   functions, FMU_NAME, FMU_GUID, 1u << fmi2CoSimulation))
        return NULL;
    const char *engine_problem = engine_load();
    if (engine_problem != NULL) {
        host_log(&log, STATUS_ERROR, engine_problem);
        return NULL;
    }
    Guard *guard = pool_take(fmuResourceLocation);
    int reused = guard != NULL;
    if (!reused && python_content_problem(&log, fmuResourceLocation, PYTHON_CONTENT)) return NULL;
    if (!reused) guard = calloc(1, sizeof *guard);
    if (guard == NULL) return NULL;
    free(guard->instance_name);
    guard->instance_name = strdup(instanceName);
    if (!reused) guard->resource_location = strdup(fmuResourceLocation);
    guard->log = log;
    guard->log.instance_name = guard->instance_name;
    guard->log.debug_logging = loggingOn;
    guard->engine_callbacks = *functions;
    guard->engine_callbacks.logger = guard_logger;
    guard->engine_callbacks.componentEnvironment = guard;
    guard->last_successful_time = 0.0;
    call_claim(&guard->call); /* a new instance, or a freed one: nobody else has it */
    enter(guard);
    if (reused) {
        settle(guard, engine.reset(guard->engine));
    } else {
        guard->engine = engine.instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                           &guard->engine_callbacks, visible, fmi2True);
    }
    finish(guard, fmi2OK);
    if (guard->engine == NULL || guard->worst >= fmi2Error || guard->instance_name == NULL ||
        guard->resource_location == NULL) {
        /* A half-made instance is not freed through pythonfmu: it may be broken. */
        release(guard);
        return NULL;
    }
    return guard;
}

void fmi2FreeInstance(fmi2Component c) {
    Guard *guard = (Guard *)c;
    if (guard == NULL) return;
    if (!call_claim(&guard->call)) {
        overlapping(guard, __func__);
        return;
    }
    if (!guard->fatal) {
        host_log_forget(&guard->log);
        call_release(&guard->call);
        if (pool_put(guard)) return;
        call_claim(&guard->call);
        enter(guard);
        engine.freeInstance(guard->engine);
        finish(guard, fmi2OK);
    }
    release(guard);
}

/* Recorded here, not passed on: pythonfmu must keep logging everything. */
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    char problem[MESSAGE_SIZE];
    if (host_log_set(&guard->log, "fmi2SetDebugLogging", loggingOn, nCategories, categories,
                     problem))
        return finish(guard, guard_error(guard, "%s", problem));
    return finish(guard, fmi2OK);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    fmi2Status status = settle(guard, engine.setupExperiment(guard->engine, toleranceDefined,
                                                             tolerance, startTime,
                                                             stopTimeDefined, stopTime));
    /* Only an accepted call sets the time: a refused one (out of sequence: fmi2Error) did
       nothing, so the last successful time stays, as in fmi2DoStep. */
    if (status <= fmi2Warning) guard->last_successful_time = startTime;
    return finish(guard, status);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { return forward(c, __func__, engine.enterInitializationMode); }

fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return forward(c, __func__, engine.exitInitializationMode); }

fmi2Status fmi2Terminate(fmi2Component c) { return forward(c, __func__, engine.terminate); }

fmi2Status fmi2Reset(fmi2Component c) { return forward(c, __func__, engine.reset); }

/* The calls that get or set values, in one place: pythonfmu reads and writes their arrays
   without looking, so NULL ones are refused here. `got` is the array of a get, `set` that
   of a set. */
typedef enum {
    GET_REAL, GET_INTEGER, GET_BOOLEAN, GET_STRING, SET_REAL, SET_INTEGER, SET_BOOLEAN, SET_STRING
} ValueCall;

static fmi2Status forward_values(fmi2Component c, const char *function, ValueCall call,
                                 const fmi2ValueReference vr[], size_t nvr, void *got,
                                 const void *set) {
    fmi2Status refused;
    Guard *guard = open_values_call(c, function, nvr, vr, got ? got : set, &refused);
    if (guard == NULL) return refused;
    fmi2Component e = guard->engine;
    fmi2Status status = fmi2Error;
    switch (call) {
    case GET_REAL: status = engine.getReal(e, vr, nvr, got); break;
    case GET_INTEGER: status = engine.getInteger(e, vr, nvr, got); break;
    case GET_BOOLEAN: status = engine.getBoolean(e, vr, nvr, got); break;
    case GET_STRING: status = engine.getString(e, vr, nvr, got); break;
    case SET_REAL: status = engine.setReal(e, vr, nvr, set); break;
    case SET_INTEGER: status = engine.setInteger(e, vr, nvr, set); break;
    case SET_BOOLEAN: status = engine.setBoolean(e, vr, nvr, set); break;
    case SET_STRING: status = engine.setString(e, vr, nvr, set); break;
    }
    return close_call(guard, status);
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    return forward_values(c, __func__, GET_REAL, vr, nvr, value, NULL);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    return forward_values(c, __func__, GET_INTEGER, vr, nvr, value, NULL);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    return forward_values(c, __func__, GET_BOOLEAN, vr, nvr, value, NULL);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    return forward_values(c, __func__, GET_STRING, vr, nvr, value, NULL);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    return forward_values(c, __func__, SET_REAL, vr, nvr, NULL, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    return forward_values(c, __func__, SET_INTEGER, vr, nvr, NULL, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    return forward_values(c, __func__, SET_BOOLEAN, vr, nvr, NULL, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    return forward_values(c, __func__, SET_STRING, vr, nvr, NULL, value);
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    fmi2Status refused;
    Guard *guard = open_values_call(c, __func__, 1, FMUstate, FMUstate, &refused);
    if (guard == NULL) return refused;
    return close_call(guard, engine.getFMUstate(guard->engine, FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    fmi2Status refused;
    Guard *guard = open_values_call(c, __func__, 1, FMUstate, FMUstate, &refused);
    if (guard == NULL) return refused;
    return close_call(guard, engine.setFMUstate(guard->engine, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    if (FMUstate == NULL || *FMUstate == NULL) return finish(guard, fmi2OK);
    fmi2Status status = settle(guard, engine.freeFMUstate(guard->engine, FMUstate));
    /* pythonfmu leaves the freed pointer in place: a host that passes it again would
       hand Python a freed object. */
    *FMUstate = NULL;
    return finish(guard, status);
}

/* The serialized state is pythonfmu's bytes (the adapter's JSON) in the envelope. */
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    fmi2Status refused;
    Guard *guard = open_values_call(c, __func__, 1, FMUstate, size, &refused);
    if (guard == NULL) return refused;
    fmi2Status status = settle(guard, engine.serializedFMUstateSize(guard->engine, FMUstate, size));
    if (status <= fmi2Warning) *size += ENVELOPE_OVERHEAD;
    return finish(guard, status);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size) {
    fmi2Status refused;
    Guard *guard = open_values_call(c, __func__, 1, FMUstate, FMUstate, &refused);
    if (guard == NULL) return refused;
    size_t length = 0;
    fmi2Status status = settle(guard, engine.serializedFMUstateSize(guard->engine, FMUstate,
                                                                    &length));
    if (status > fmi2Warning) return finish(guard, status);
    if (serializedState == NULL || size < length + ENVELOPE_OVERHEAD)
        return finish(guard, guard_error(guard, "fmi2SerializeFMUstate: the buffer holds %u "
                                         "bytes, the state needs %u "
                                         "(fmi2SerializedFMUstateSize)", (unsigned)size,
                                         (unsigned)(length + ENVELOPE_OVERHEAD)));
    unsigned char *payload = malloc(length ? length : 1);
    if (payload == NULL)
        return finish(guard, guard_error(guard, "fmi2SerializeFMUstate: out of memory"));
    status = settle(guard, engine.serializeFMUstate(guard->engine, FMUstate,
                                                    (fmi2Byte *)payload, length));
    if (status <= fmi2Warning)
        envelope_write((unsigned char *)serializedState, FMU_NAME, FMU_GUID,
                       STATE_FORMAT_VERSION, payload, length);
    free(payload);
    return finish(guard, status);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    fmi2Status refused;
    Guard *guard = open_values_call(c, __func__, 1, FMUstate, FMUstate, &refused);
    if (guard == NULL) return refused;
    const unsigned char *payload;
    size_t length;
    char problem[MESSAGE_SIZE];
    if (envelope_read((const unsigned char *)serializedState, size, FMU_NAME, FMU_GUID,
                      STATE_FORMAT_VERSION, &payload, &length, problem, sizeof problem))
        return finish(guard, guard_error(guard, "fmi2DeSerializeFMUstate: %s", problem));
    return close_call(guard, engine.deSerializeFMUstate(guard->engine, (const fmi2Byte *)payload,
                                                        length, FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    return close_call(guard, engine.getDirectionalDerivative(guard->engine, vUnknown_ref, nUnknown,
                                                             vKnown_ref, nKnown, dvKnown,
                                                             dvUnknown));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    return close_call(guard, engine.setRealInputDerivatives(guard->engine, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    return close_call(guard, engine.getRealOutputDerivatives(guard->engine, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    fmi2Status refused;
    Guard *guard = open_call(c, __func__, &refused);
    if (guard == NULL) return refused;
    fmi2Status status = settle(guard, engine.doStep(guard->engine, currentCommunicationPoint,
                                                    communicationStepSize,
                                                    noSetFMUStatePriorToCurrentPoint));
    /* A completed step ends at t + h; a discarded one leaves the instance at t. A refused
       call (fmi2Error) did nothing, so the last successful time stays. */
    if (status <= fmi2Warning)
        guard->last_successful_time = currentCommunicationPoint + communicationStepSize;
    else if (status == fmi2Discard)
        guard->last_successful_time = currentCommunicationPoint;
    return finish(guard, status);
}

fmi2Status fmi2CancelStep(fmi2Component c) { return forward(c, __func__, engine.cancelStep); }

static fmi2Status unsupported_status(fmi2Component c, const char *function) {
    fmi2Status refused;
    Guard *guard = open_call(c, function, &refused);
    if (guard == NULL) return refused;
    return finish(guard, guard_error(guard, "%s: steps run synchronously, there is no status "
                                     "to ask for", function));
}

/* The two statuses a step has here: the time it last reached (after a discarded step too),
   and whether the FMU asks to end the simulation (never). The one asked for is not NULL. */
static fmi2Status step_status(fmi2Component c, const char *function, fmi2Real *time,
                              fmi2Boolean *terminated) {
    fmi2Status refused;
    Guard *guard = open_call(c, function, &refused);
    if (guard == NULL) return refused;
    if (time == NULL && terminated == NULL) return finish(guard, fmi2Error);
    if (time != NULL) *time = guard->last_successful_time;
    if (terminated != NULL) *terminated = fmi2False;
    return finish(guard, fmi2OK);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s, (void)value;
    return unsupported_status(c, __func__);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (s != fmi2LastSuccessfulTime) return unsupported_status(c, __func__);
    return step_status(c, __func__, value, NULL);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s, (void)value;
    return unsupported_status(c, __func__);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    if (s != fmi2Terminated) return unsupported_status(c, __func__);
    return step_status(c, __func__, NULL, value);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s, (void)value;
    return unsupported_status(c, __func__);
}
