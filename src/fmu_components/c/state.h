/*
 * FMU states (state.c): get, set, free, serialize and deserialize an instance's Snapshot;
 * each call is one FMI function of either version, named `function` in messages.
 */
#ifndef STATE_H
#define STATE_H

#include <stddef.h>

#include "instance.h"

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
