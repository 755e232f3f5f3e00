/* The fmuResourceLocation a host passes to fmi2Instantiate, checked before anything uses
   it (both flavours' binaries). */
#ifndef RESOURCE_LOCATION_H
#define RESOURCE_LOCATION_H

#include <stddef.h>

#define IDENTITY_FILE "fmu-guid.txt" /* in resources/: the FMU's GUID */

/* 0 when `uri` is a file URI of the resources folder of this FMU: its IDENTITY_FILE holds
   `guid`. Else 1 with the reason in problem[size]. On success the folder's path is in
   path[path_size] (may be NULL). */
int check_resource_location(const char *uri, const char *guid, char *path, size_t path_size,
                            char *problem, size_t size);

#endif
