/* What the hostile host's two files share (fuzz_host.c: the loading, the random calls, the
   serialized states, the re-entrant logger and main; fuzz_lifecycle.c: the instances over
   their lives). */
#ifndef FUZZ_HOST_H
#define FUZZ_HOST_H

#include "fmi2_table.h"

#define CALL_SECONDS 20 /* the first call of the Python flavour starts an interpreter */

extern Fmi2Table fmi;
extern int fmi3_binary; /* an FMI 3.0 binary, called through fmi3_as_fmi2.c */
extern const char *resource_uri, *guid, *model_name;
extern fmi2ValueReference vr_in[2], vr_out;
extern unsigned long failures;
extern fmi2CallbackFunctions quiet; /* a printf-like logger that only counts */

/* A check that did not hold: told on stderr and counted (the exit code says it). */
void fail(const char *format, ...);
fmi2Component instantiate(const char *name, const fmi2CallbackFunctions *callbacks,
                          fmi2Boolean logging);
/* 1 when the instance left initialization at these inputs. */
int initialize(fmi2Component c, double deflection, double rate);
/* The binary's functions into `fmi`: the library, or NULL with the reason on stderr. */
void *load(const char *binary);

/* The modes of fuzz_lifecycle.c (usage: fuzz_host.c): each 0 when every check held. */
int run_instantiate(const char *other_uri, int offers_model_exchange);
int run_cycles(long count, long n_messages);
int run_threads(int count, long steps);
int run_shared(int count, long calls);
int run_thread_states(long calls);
int run_unload(const char *binary, void **library);

#endif
