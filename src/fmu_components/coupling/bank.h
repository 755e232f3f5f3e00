/*
 * The bank's types, shared by bank.c (the step protocol, the laws) and bank_linearised.c
 * (the linearised step). See bank.c.
 */
#ifndef BANK_H
#define BANK_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if defined(_WIN32)
#define EXPORT __declspec(dllexport)
#else
#define EXPORT __attribute__((visibility("default")))
#endif

#define BANK_VERSION 1
#define MAX_OUTPUTS 8
/* x*, F*, K, Q, K_touch (law.py's LoadLaw), then what a host's expression of the law
   needs no more than once per pass: Q/2 and the secant's bounds K/2 and 2K, low first;
   then the reversal's kink: where, the law's load there, the tangent beyond, the side */
#define LAW_COLUMNS 12
#define CURVED 0.01   /* fmu.py's CURVED */
#define STATUS_OK 1   /* fmi2Warning and below */

/* FMI 2.0 and 3.0 signatures of the calls the bank makes (the standards' own). */
typedef int (*Fmi2SetReal)(void *, const unsigned *, size_t, const double *);
typedef int (*Fmi2GetReal)(void *, const unsigned *, size_t, double *);
typedef int (*Fmi2DoStep)(void *, double, double, int);
typedef int (*Fmi2GetState)(void *, void **);
typedef int (*Fmi2SetState)(void *, void *);
typedef int (*Fmi2Directional)(void *, const unsigned *, size_t, const unsigned *, size_t,
                               const double *, double *);
typedef int (*Fmi3SetFloat64)(void *, const unsigned *, size_t, const double *, size_t);
typedef int (*Fmi3GetFloat64)(void *, const unsigned *, size_t, double *, size_t);
typedef int (*Fmi3DoStep)(void *, double, double, bool, bool *, bool *, bool *, double *);
typedef int (*Fmi3Directional)(void *, const unsigned *, size_t, const unsigned *, size_t,
                               const double *, size_t, double *, size_t);

typedef int (*Fmi2SetStates)(void *, const double *, size_t);
typedef int (*Fmi2GetDerivatives)(void *, double *, size_t);
typedef int (*Fmi2Mode)(void *);
typedef struct {
    int new_discrete_states_needed, terminate, nominals_changed, values_changed,
        next_event_time_defined;
    double next_event_time;
} Fmi2EventInfo;
typedef int (*Fmi2NewDiscreteStates)(void *, Fmi2EventInfo *);
typedef int (*Fmi3UpdateDiscreteStates)(void *, bool *, bool *, bool *, bool *, bool *,
                                        double *);

enum { SET, GET, DO_STEP, GET_STATE, SET_STATE, DIRECTIONAL, FUNCTIONS };
/* a Model Exchange instance's calls, for the linearised step (linearised.py); of the
   instance's FMI version (setting states, derivatives and the modes have one signature
   in both) */
enum { ME_SET, ME_GET, ME_SET_STATES, ME_DIRECTIONAL, ME_DERIVATIVES, ME_EVENT_MODE,
       ME_NEW_DISCRETE_STATES, ME_CONTINUOUS_MODE, ME_FUNCTIONS };
#define MAX_STATES 8
/* what failed, for bank.py's message */
enum { FAILED_NONE, FAILED_SET, FAILED_GET, FAILED_DO_STEP, FAILED_GET_STATE,
       FAILED_SET_STATE, FAILED_DIRECTIONAL, FAILED_NOT_FINITE, FAILED_NO_STEP,
       FAILED_LINEARISED };
/* flags of an instance */
enum { UNILATERAL = 1, STEP_TANGENT = 2, CURVATURE = 4, LINEARISABLE = 8, LINEARISED = 16,
       REVERSIBLE = 32 };
/* schemes (schemes.py) */
enum { EXPLICIT, CORRECTED, CONVERGED };
/* end_pass's verdicts; ACCEPT and REPEAT with NOTICE added where the pass cut a step or
   listed instances for Python (the call block says which), so that a pass with neither
   costs Python no look into the block */
enum { ACCEPT = 0, REPEAT = 1, RETRY = 2, FAILED = -1, BUSY = -2, NOTICE = 4 };

typedef struct {
    int fmi_version; /* 2 or 3 */
    void *functions[FUNCTIONS];
    void *instance;
    void *state; /* the one saved state, reused */
    unsigned inputs[2], outputs[MAX_OUTPUTS], stiffness_vr;
    int n_outputs, load, stiffness; /* indices into the outputs */
    int flags;
    int stepped, saved, tried;
    double trial_deflection, trial_secant;
    /* the tangent for motion the other way from the accepted point, where it was asked
       (fmu.py's reverse_stiffness; reversible 0: not asked) */
    double reverse_stiffness;
    int reversible;
    double previous_rate; /* the secant rate of the step before the last accepted one */
    /* its Model Exchange side instance (linearised.py), where the bank linearises */
    void *model;
    void *model_functions[ME_FUNCTIONS];
    int n_states, events, contact;
    unsigned state_vrs[MAX_STATES], unknowns[MAX_STATES + 2], knowns[MAX_STATES + 2];
} Instance;

/* The arguments and results of a host step's calls (begin_step, end_pass, accept), in a
   block bank.py binds once: a call then passes the bank alone, which costs Python a
   fraction of a call with arguments to convert (bank.py's ctypes). */
typedef struct {
    double time;     /* in: the time the step reaches */
    double mismatch; /* out: the pass's mismatch (end_pass) */
    double next;     /* in (accept): the next step's end where the host knows it, or NaN */
    double begun;    /* out: the time of the step accept began, or NaN */
    int64_t total_passes; /* out: passes since the bank was made */
    int pass;        /* out: the step's passes so far (begin_step: 0, end_pass: + 1) */
    int max_pieces;  /* in: 1, or a discarded step's most pieces for a host that cannot retry */
    int n_flagged;   /* out: instances whose law Python makes (listed in `flagged`) */
    int cut;         /* out: steps cut into pieces in the pass */
} BankCall;

typedef struct {
    int n, scheme, passes, least_passes;
    int kinked_first_laws; /* fmu.py's kinked_first_law, for every instance */
    BankCall *call;
    double tolerance;
    Instance *instances;
    /* the caller's arrays (bank.py): rows of n */
    const double *deflection;   /* the host's, read at end_pass */
    double *laws;               /* n x LAW_COLUMNS */
    double *accepted;           /* n x 3: time, deflection, secant rate of the last step */
    double *outputs;            /* n x MAX_OUTPUTS after the last accepted step */
    double *trial_outputs;      /* n x MAX_OUTPUTS after the last trial */
    double *seen;               /* n x 2: peak |load|, the last contact stiffness */
    int64_t *counts;            /* n x 3: doSteps, saves, restores */
    int *flagged;               /* instances whose law Python makes (linearised) */
    int n_flagged;
    /* the last failure */
    int failed_instance, failed_call, failed_status, failed_output;
    double failed_time, failed_step;
    int busy;
} Bank;

/* Laws (n rows of LAW_COLUMNS) and whether each is unilateral, apart from a bank: the laws
   of one moment, evaluated as the bank evaluates its own (law_table_loads) */
typedef struct {
    int n;
    const double *laws;
    const int *unilateral;
} LawTable;

int fail(Bank *bank, int i, int call, int status, double time, double step);
void set_law(Bank *bank, int i, double x, double load, double k, double q);
int linearised_step(Bank *bank, int i, double deflection, double rate, double step,
                    double *result);
int predicted_law(Bank *bank, int i, double time);

#endif
