/*
 * The calls of Model Exchange and Event Mode, and the directional derivatives and output
 * derivatives of both interfaces (model_exchange.c); each is one FMI function of either
 * version, named `function` in messages.
 */
#ifndef MODEL_EXCHANGE_H
#define MODEL_EXCHANGE_H

#include <stddef.h>

#include "instance.h"

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
/* The outputs' first time derivatives at the communication point (orders all 1). */
Status core_output_derivatives(Instance *instance, const char *function, const unsigned vr[],
                               size_t nvr, const int orders[], double values[]);

#endif
