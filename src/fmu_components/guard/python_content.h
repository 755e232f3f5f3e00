/* The hash of the Python in an FMU's resources folder, taken when an instance is made from
   it (export/build.py, python_content_hash, takes the same at build time). */
#ifndef PYTHON_CONTENT_H
#define PYTHON_CONTENT_H

#include "host_log.h"

/* 0 when the Python under the resources folder (a file URI) hashes to `expected` (16 hex
   digits); else 1, logged: its module names carry the build's hash, so an edited copy
   would share modules with an unedited one in the same process, and whichever came first
   would run for both. */
int python_content_problem(const HostLog *log, const char *resource_location,
                           const char *expected);

#endif
