/*
 * FMU states: a copy of the instance's Snapshot (what the host set and what the run has
 * done; the constants and curves are rebuilt from its parameters). A serialized state is
 * the Snapshot in its envelope (state_envelope.h: format version, GUID, checksum); every
 * value in a serialized state passes the checks setting a value applies before anything of it
 * is used. A state in memory was checked when it was made (taken from the running instance,
 * or deserialized and checked), so restoring it is a copy: the coupling library's corrected
 * scheme restores every FMU once per host step (docs/coupling.md).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "state.h"
#include "state_envelope.h"
#include "text.h"

#define STATE_FORMAT_VERSION 2u
#define STATE_MAGIC 0x53544154u /* "STAT" */
#define ALL_MODES                                                                          \
    (INSTANTIATED | INITIALIZATION_MODE | STEP_COMPLETE | STEP_FAILED | TERMINATED |       \
     EVENT_MODE | CONTINUOUS_TIME_MODE)

typedef struct {
    uint32_t magic;
    const ModelInfo *model; /* this library's model: another FMU's state is refused */
    Snapshot s;
} SavedState;

/* 1, with "the state's NAME = VALUE is not valid" in message, when !ok. */
static int invalid(int ok, const char *name, double value, char *message, size_t size) {
    if (ok) return 0;
    char text[REPR_SIZE];
    snprintf(message, size, "the state's %s = %s is not valid", name, format_repr(value, text));
    return 1;
}

/* As invalid, for the first entry of values that is not finite. */
static int invalid_entry(const double *values, size_t n, const char *name, char *message,
                         size_t size) {
    for (size_t i = 0; i < n; i++) {
        if (isfinite(values[i])) continue;
        char text[REPR_SIZE];
        snprintf(message, size, "the state's %s[%u] = %s is not valid", name, (unsigned)i,
                 format_repr(values[i], text));
        return 1;
    }
    return 0;
}

/* 0 when every value of the snapshot is one the instance could have reached, else 1 with
   the reason. */
static int snapshot_problem(const Snapshot *s, char *message, size_t size) {
    int mode = s->mode;
    if (mode == 0 || (mode & (mode - 1)) != 0 || (mode & ~ALL_MODES)) {
        snprintf(message, size, "the state's FMI state %d is not one", mode);
        return 1;
    }
    char problem[MESSAGE_SIZE];
    for (unsigned vr = 0; vr < MODEL_VARIABLES; vr++) {
        int causality = MODEL_INFO.variables[vr].causality;
        if (causality == CAUSALITY_OUTPUT || causality == CAUSALITY_LOCAL) continue;
        if (variable_problem(vr, s->values[vr], problem, sizeof problem)) {
            snprintf(message, size, "the state's %s", problem);
            return 1;
        }
    }
    if (invalid(isfinite(s->start_time), "start time", s->start_time, message, size) ||
        invalid(s->tolerance > 0.0 && isfinite(s->tolerance), "tolerance", s->tolerance,
                message, size) ||
        invalid(isfinite(s->last_successful_time), "last successful time",
                s->last_successful_time, message, size) ||
        invalid(s->warned <= 3u, "warned inputs", s->warned, message, size) ||
        invalid(s->rate_from_deflection == 0 || s->rate_from_deflection == 1,
                "rate_from_deflection", s->rate_from_deflection, message, size) ||
        invalid(s->rate_warned == 0 || s->rate_warned == 1, "rate warned", s->rate_warned,
                message, size) ||
        invalid(s->has_previous == 0 || s->has_previous == 1, "last step flag",
                s->has_previous, message, size))
        return 1;
    if (s->has_previous &&
        (invalid(isfinite(s->previous_deflection), "last step's deflection",
                 s->previous_deflection, message, size) ||
         invalid(isfinite(s->previous_rate), "last step's rate", s->previous_rate, message,
                 size) ||
         invalid(s->previous_step > 0.0 && isfinite(s->previous_step), "last step's size",
                 s->previous_step, message, size)))
        return 1;
    if (!s->initialized) return 0;
    if (s->initialized != 1) {
        snprintf(message, size, "the state's initialization flag %d is not 0 or 1",
                 s->initialized);
        return 1;
    }
    if (parameter_problem(s->values, problem, sizeof problem)) {
        snprintf(message, size, "the state's parameters are not valid: %s", problem);
        return 1;
    }
    const Memory *memory = &s->memory;
    if (invalid(isfinite(s->time), "time", s->time, message, size) ||
        invalid(isfinite(s->deflection), "deflection", s->deflection, message, size) ||
        invalid(isfinite(s->rate), "rate", s->rate, message, size) ||
        invalid_entry(s->state, MODEL_STATES, "internal state", message, size) ||
        invalid(memory->rtol > 0.0 && isfinite(memory->rtol), "integrator tolerance",
                memory->rtol, message, size) ||
        invalid(memory->has_h_next == 0 || memory->has_h_next == 1, "next step flag",
                memory->has_h_next, message, size) ||
        (memory->has_h_next && invalid(memory->h_next > 0.0 && isfinite(memory->h_next),
                                       "next step size", memory->h_next, message, size)) ||
        invalid(memory->w_uses >= 0 && memory->w_uses <= MAX_W_REUSE,
                "iteration matrix uses", memory->w_uses, message, size))
        return 1;
    if (memory->w_uses &&
        (invalid(memory->w_h > 0.0 && isfinite(memory->w_h), "iteration matrix step",
                 memory->w_h, message, size) ||
         invalid_entry(memory->w, MODEL_INTEGRATED * MODEL_INTEGRATED, "iteration matrix",
                       message, size)))
        return 1;
    ModelData data;
    build_model_data(&data, s->values);
    if (model_input_problem(&data, s->state, s->deflection, problem, sizeof problem)) {
        snprintf(message, size, "the state's inputs do not fit its model state: %s", problem);
        return 1;
    }
    return 0;
}

/* 1 when two snapshots' parameters are the same, so the constants and curves built from one
   serve the other. */
static int same_parameters(const Snapshot *a, const Snapshot *b) {
    for (unsigned vr = 0; vr < MODEL_VARIABLES; vr++)
        if (MODEL_INFO.variables[vr].causality == CAUSALITY_PARAMETER &&
            memcmp(&a->values[vr], &b->values[vr], sizeof(double)) != 0)
            return 0;
    return 1;
}

static SavedState *saved(Instance *instance, void *state, const char *function) {
    SavedState *saved_state = (SavedState *)state;
    if (saved_state == NULL || saved_state->magic != STATE_MAGIC ||
        saved_state->model != &MODEL_INFO) {
        log_status(instance, STATUS_ERROR, "%s: the FMU state %p is NULL or not one %s made; "
                   "state unchanged", function, state, MODEL_INFO.name);
        return NULL;
    }
    return saved_state;
}

Status core_get_state(Instance *instance, const char *function, void **FMUstate) {
    if (!call_begin(instance, ALL_MODES, function)) return STATUS_ERROR;
    if (FMUstate == NULL) {
        log_status(instance, STATUS_ERROR, "%s: the place for the state is NULL", function);
        return call_end(instance, STATUS_ERROR);
    }
    SavedState *state = (SavedState *)*FMUstate;
    if (state != NULL && (state->magic != STATE_MAGIC || state->model != &MODEL_INFO)) {
        log_status(instance, STATUS_ERROR, "%s: the state to update, %p, is not one %s made",
                   function, (void *)state, MODEL_INFO.name);
        return call_end(instance, STATUS_ERROR);
    }
    if (state == NULL) state = malloc(sizeof *state);
    if (state == NULL) {
        log_status(instance, STATUS_ERROR, "%s: out of memory", function);
        return call_end(instance, STATUS_ERROR);
    }
    state->magic = STATE_MAGIC;
    state->model = &MODEL_INFO;
    state->s = instance->s;
    *FMUstate = state;
    return call_end(instance, STATUS_OK);
}

Status core_set_state(Instance *instance, const char *function, void *FMUstate) {
    if (!call_begin(instance, ALL_MODES, function)) return STATUS_ERROR;
    SavedState *state = saved(instance, FMUstate, function);
    if (state == NULL) return call_end(instance, STATUS_ERROR);
    int data_kept = instance->s.initialized && same_parameters(&instance->s, &state->s);
    instance->s = state->s;
    if (instance->s.initialized && !data_kept)
        build_model_data(&instance->data, instance->s.values);
    instance->outputs_fresh = 0;
    return call_end(instance, STATUS_OK);
}

Status core_free_state(Instance *instance, const char *function, void **FMUstate) {
    if (!call_begin(instance, ALL_MODES, function)) return STATUS_ERROR;
    if (FMUstate == NULL || *FMUstate == NULL) return call_end(instance, STATUS_OK);
    SavedState *state = saved(instance, *FMUstate, function);
    if (state == NULL) return call_end(instance, STATUS_ERROR);
    state->magic = 0;
    free(state);
    *FMUstate = NULL;
    return call_end(instance, STATUS_OK);
}

Status core_serialized_state_size(Instance *instance, const char *function, void *FMUstate,
                                  size_t *size) {
    if (!call_begin(instance, ALL_MODES, function)) return STATUS_ERROR;
    if (saved(instance, FMUstate, function) == NULL) return call_end(instance, STATUS_ERROR);
    if (size == NULL) {
        log_status(instance, STATUS_ERROR, "%s: the place for the size is NULL", function);
        return call_end(instance, STATUS_ERROR);
    }
    *size = ENVELOPE_OVERHEAD + sizeof(Snapshot);
    return call_end(instance, STATUS_OK);
}

Status core_serialize_state(Instance *instance, const char *function, void *FMUstate,
                            unsigned char serializedState[], size_t size) {
    if (!call_begin(instance, ALL_MODES, function)) return STATUS_ERROR;
    SavedState *state = saved(instance, FMUstate, function);
    if (state == NULL) return call_end(instance, STATUS_ERROR);
    size_t needed = ENVELOPE_OVERHEAD + sizeof(Snapshot);
    if (serializedState == NULL || size < needed) {
        log_status(instance, STATUS_ERROR, "%s: the buffer holds %u bytes, the "
                   "state needs %u (%sSerializedFMUstateSize)", function, (unsigned)size,
                   (unsigned)needed, instance->face->prefix);
        return call_end(instance, STATUS_ERROR);
    }
    envelope_write((unsigned char *)serializedState, MODEL_INFO.name, MODEL_INFO.guid,
                   STATE_FORMAT_VERSION, (const unsigned char *)&state->s, sizeof(Snapshot));
    return call_end(instance, STATUS_OK);
}

Status core_deserialize_state(Instance *instance, const char *function,
                              const unsigned char serializedState[], size_t size,
                              void **FMUstate) {
    if (!call_begin(instance, ALL_MODES, function)) return STATUS_ERROR;
    const unsigned char *payload;
    size_t length;
    char problem[MESSAGE_SIZE];
    if (FMUstate == NULL) {
        log_status(instance, STATUS_ERROR, "%s: the place for the state is "
                   "NULL", function);
        return call_end(instance, STATUS_ERROR);
    }
    if (envelope_read((const unsigned char *)serializedState, size, MODEL_INFO.name,
                      MODEL_INFO.guid, STATE_FORMAT_VERSION, &payload, &length, problem,
                      sizeof problem)) {
        log_status(instance, STATUS_ERROR, "%s: %s", function, problem);
        return call_end(instance, STATUS_ERROR);
    }
    SavedState restored = {STATE_MAGIC, &MODEL_INFO, {0}};
    if (length != sizeof restored.s) {
        log_status(instance, STATUS_ERROR, "%s: the serialized state cannot "
                   "be read: %u bytes of content, this build's state has %u", function, (unsigned)length,
                   (unsigned)sizeof restored.s);
        return call_end(instance, STATUS_ERROR);
    }
    memcpy(&restored.s, payload, length);
    if (snapshot_problem(&restored.s, problem, sizeof problem)) {
        log_status(instance, STATUS_ERROR, "%s: %s", function, problem);
        return call_end(instance, STATUS_ERROR);
    }
    SavedState *state = malloc(sizeof *state);
    if (state == NULL) {
        log_status(instance, STATUS_ERROR, "%s: out of memory", function);
        return call_end(instance, STATUS_ERROR);
    }
    *state = restored;
    *FMUstate = state;
    return call_end(instance, STATUS_OK);
}
