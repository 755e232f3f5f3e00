/*
 * The native runtime's core, hand-written once for every component and every FMI version:
 * the calls a face makes (core.c here, and model_exchange.h, state.h) on an instance
 * (instance.h), its co-simulation (cosimulation.c), its integrator (integrator.c), its FMU
 * states (state.c) and Model Exchange (model_exchange.c). A thin face per FMI version
 * (fmi2_face.c, fmi3_face.c) turns each FMI function into a core call; the core knows no FMI
 * header. It follows the Python runtime (fmu_components.runtime: adapter.py, cosim.py,
 * integrator.py, model.py) statement for statement, so that both flavours take the same
 * steps and give the same bits.
 */
#ifndef CORE_H
#define CORE_H

#include <stddef.h>

#include "instance.h"
#include "model_exchange.h"
#include "state.h"

/* --- the calls (core.c) -------------------------------------------------------------------
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

#endif
