/* What FMI 2.0 gives a binary to reach its host (the logger among the callback functions,
   the GUID, the resource location as a file URI), shared by the native FMI 2 face and the
   Python flavour's guard and the rig's driver. */
#ifndef FMI2_HOST_H
#define FMI2_HOST_H

#include "fmi2Functions.h"
#include "instantiation.h"

/* fmi2Instantiate's arguments checked (instantiation.h) for the FMU `name` with `guid` that
   offers the interface types in `types` (bits 1 << fmi2ModelExchange, 1 << fmi2CoSimulation);
   `log` is set to the host's logger (may be NULL) for the instance being made. 0 when
   right, else 1 with the reason logged. fmi2GetTypesPlatform and fmi2GetVersion live here
   too: every FMI 2.0 binary answers them alike. */
int fmi2_instantiation_refused(HostLog *log, fmi2String instance_name, fmi2Type type,
                               fmi2String guid, fmi2String resource_location,
                               const fmi2CallbackFunctions *functions, const char *name,
                               const char *expected_guid, unsigned types);

#endif
