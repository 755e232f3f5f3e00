/*
 * The interface between the hand-written runtime (this folder, the same for every
 * component) and one component's generated code: model_config.h (its sizes) and model.c
 * (MODEL_INFO and the model_* functions), which fmu_components.export.cgen prints at build time
 * from the same expression trees as the Python flavour's equations.
 *
 * Names follow the Python runtime (fmu_components.runtime.model): x the deflection at the
 * start of a step, u the rate the rubber or rotor sees over it, h its length, v the input
 * rate; `state` the model's state list, its first MODEL_INTEGRATED entries integrated.
 */
#ifndef MODEL_H
#define MODEL_H

#include "arithmetic.h"

#include <stddef.h>

#include "hermite.h"
#include "model_config.h"

/* Arrays of at least one entry, whatever the model's sizes. */
#define SLOTS(n) ((n) > 0 ? (n) : 1)

enum { CAUSALITY_INPUT, CAUSALITY_OUTPUT, CAUSALITY_PARAMETER, CAUSALITY_LOCAL };
enum { ANY_FINITE, POSITIVE, NON_NEGATIVE };

typedef struct {
    const char *name;
    int causality;
    const char *unit;
    int constraint;
    double start; /* NAN for outputs */
} VariableInfo;

typedef struct {
    double low, high;     /* the range the thesis measured */
    const char *measured; /* what it measured there */
} RangeInfo;

typedef struct {
    const char *name;
    size_t size;
    const unsigned *abscissae, *ordinates; /* value references of the points */
    const char *abscissa, *abscissa_unit, *ordinate, *ordinate_unit;
    int dissipative; /* the ordinate takes the abscissa's sign */
} TableInfo;

typedef struct {
    const char *name, *guid;
    const VariableInfo *variables; /* by value reference: inputs, outputs, parameters */
    RangeInfo ranges[2];           /* deflection, rate */
    const TableInfo *tables;
    int unilateral;                /* a contact: deformed only while x > 0 */
} ModelInfo;

#define INPUT_DEFLECTION 0
#define INPUT_RATE 1
#define FIRST_OUTPUT 2
#define FIRST_PARAMETER (FIRST_OUTPUT + MODEL_OUTPUTS)
#define FIRST_STATE (FIRST_PARAMETER + MODEL_PARAMETERS) /* the continuous states */
#define FIRST_DERIVATIVE (FIRST_STATE + MODEL_CONTINUOUS) /* their derivatives */

extern const ModelInfo MODEL_INFO;

/* What the equations read: the parameter values by value reference, then the derived
   constants and state scales (K); the Hermite curves built from their points. */
typedef struct {
    double K[MODEL_CONSTANTS];
    Hermite tables[SLOTS(MODEL_TABLES)];
} ModelData;

void model_derive(ModelData *m, const double *values);
void model_initial_state(ModelData *m, double x, double v, double *state);
void model_start(ModelData *m, const double *state, double x, double *y);
/* W^-1 = (I/(gamma h) - J)^-1 into w (row-major); 0 when W is singular. */
int model_factor(ModelData *m, const double *y, double u, double h, double *w);
/* One step with W^-1: the new state and the squared error norm; 0 when a stage or the
   result leaves the valid region or is not finite. */
int model_step(ModelData *m, const double *y, double u, double h, double rtol,
               const double *w, double *y_new, double *error_norm);
void model_exact(ModelData *m, double *state, double x, double u, double h);
void model_outputs(ModelData *m, const double *state, double x, double v, double *outputs);
/* A contact's mode at deflection x and rate v: 1 in contact, or touching and pressing on
   (always, for two-sided components). */
double model_contact(double x, double v);
/* 1, with the reason in message, when the model cannot take deflection x. */
int model_input_problem(ModelData *m, const double *state, double x, char *message,
                        size_t size);
/* Rewrite the state for a deflection x that model_input_problem accepted. */
void model_take_input(ModelData *m, double *state, double x);
void model_failure_hint(ModelData *m, const double *state, double v, char *message,
                        size_t size);

/* The continuous-time view (Model Exchange, the state and derivative variables, directional
   derivatives): X the MODEL_CONTINUOUS continuous states, the leading entries of the
   state list; `contact` 1 or 0, the mode of a contact as the events set it. The functions
   that take a direction (dX, dx, dv; dX may be NULL for zero) also give the derivatives
   along it (into df or doutputs, when not NULL), by forward differentiation of the same
   equations. 0 where the states leave the model's region. */
void model_nominals(ModelData *m, double *nominal);
int model_rates(ModelData *m, const double *X, double x, double v, double contact,
                const double *dX, double dx, double dv, double *f, double *df);
int model_continuous_outputs(ModelData *m, const double *state, double x, double v,
                             const double *dX, double dx, double dv, double *outputs,
                             double *doutputs);
void model_event_indicators(ModelData *m, double x, double *indicators);
/* The co-simulation's outputs and their derivatives along the inputs, at the frozen state. */
int model_outputs_direction(ModelData *m, const double *state, double x, double v, double dx,
                            double dv, double *outputs, double *doutputs);

/* Gauss-Jordan inverse of an n x n matrix (row-major) into inverse; 0 when singular
   (integrator.c, as runtime/integrator.py's invert). */
int invert(int n, double *matrix, double *inverse);

#endif
