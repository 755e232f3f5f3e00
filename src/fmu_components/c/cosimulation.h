/*
 * The co-simulation step (cosimulation.c, spec section 4): what core.c's doStep and setting
 * the inputs do to a Co-Simulation instance.
 */
#ifndef COSIMULATION_H
#define COSIMULATION_H

#include <stddef.h>

#include "instance.h"

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

#endif
