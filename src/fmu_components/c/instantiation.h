/* What a host passes to instantiate an FMU, checked before anything uses it, the same way in
   every binary (both flavours, both FMI versions). */
#ifndef INSTANTIATION_H
#define INSTANTIATION_H

#include <stddef.h>

#include "host_log.h"

#define IDENTITY_FILE "fmu-guid.txt" /* in resources/: the FMU's GUID */

typedef struct {
    const char *function;      /* fmi2Instantiate, fmi3InstantiateCoSimulation, ... */
    const char *instance_name;
    int callbacks_missing;     /* FMI 2: the callback functions are NULL */
    const char *interface_problem; /* NULL, or why the interface asked for is not offered */
    const char *token_name;    /* "GUID" (FMI 2), "instantiationToken" (FMI 3) */
    const char *token;
    const char *resource_name; /* "fmuResourceLocation" (FMI 2), "resourcePath" (FMI 3) */
    const char *resource;      /* FMI 2: a file URI; FMI 3: a path */
    int resource_is_uri;
} InstantiationRequest;

/* The path of a local file URI, percent-decoded, into path[size]: 0 on success. */
int uri_path(const char *uri, char *path, size_t size);

/* 0 when the request is right for the FMU `name` with token (GUID) `expected`; else 1,
   with the reason logged. The resource location must be this FMU's resources folder: its
   IDENTITY_FILE holds the token. */
int instantiation_problem(const HostLog *log, const InstantiationRequest *request,
                          const char *name, const char *expected);

#endif
