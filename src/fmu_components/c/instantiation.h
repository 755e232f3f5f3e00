/* What a host passes to fmi2Instantiate, checked before anything uses it, the same way in
   both flavours' binaries. */
#ifndef INSTANTIATION_H
#define INSTANTIATION_H

#include <stddef.h>

#include "host_log.h"

#define IDENTITY_FILE "fmu-guid.txt" /* in resources/: the FMU's GUID */

/* The host's logger (may be NULL) for the instance being made. */
HostLog instantiation_log(fmi2String instance_name, const fmi2CallbackFunctions *functions);

/* 0 when the arguments are right for the FMU `name` with `guid` that offers the interface
   types in `types` (bits 1 << fmi2ModelExchange, 1 << fmi2CoSimulation); else 1, with the
   reason logged. The resource location must be a file URI of this FMU's resources
   folder: its IDENTITY_FILE holds the GUID. */
int instantiation_problem(const HostLog *log, fmi2String instance_name, fmi2Type type,
                          fmi2String guid, fmi2String resource_location,
                          const fmi2CallbackFunctions *functions, const char *name,
                          const char *expected_guid, unsigned types);

#endif
