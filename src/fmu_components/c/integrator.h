/*
 * The integrator (integrator.c): runtime/integrator.py's Rosenbrock loop around the generated
 * step, over the model alone. It knows no instance: the caller keeps its Memory.
 */
#ifndef INTEGRATOR_H
#define INTEGRATOR_H

#include <stddef.h>
#include <stdint.h>

#include "model.h"

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

int single_step(ModelData *data, Memory *memory, double *state, double x, double u, double h);
int integrate(ModelData *data, Memory *memory, double *y, double u, double duration,
              char *message, size_t size);

#endif
