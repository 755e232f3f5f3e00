#include "fmi2_host.h"

#include <stdio.h>
#include <string.h>

/* An FMI 2 logger formats its message: it gets the text as a format string with any '%'
   doubled, so hosts that format print it exactly and hosts that do not still get it. */
static void send_fmi2(const HostLog *log, Status status, const char *category,
                      const char *message) {
    fmi2CallbackLogger logger = (fmi2CallbackLogger)log->logger;
    const char *name = log->instance_name ? log->instance_name : "";
    if (strchr(message, '%') == NULL) {
        logger(log->environment, name, (fmi2Status)status, category, message);
        return;
    }
    char escaped[2 * MESSAGE_SIZE + 1];
    size_t n = 0;
    for (const char *in = message; *in && n + 2 < sizeof escaped; in++) {
        if (*in == '%') escaped[n++] = '%';
        escaped[n++] = *in;
    }
    escaped[n] = '\0';
    logger(log->environment, name, (fmi2Status)status, category, escaped);
}

/* The host's logger (may be NULL) for the instance being made. */
static HostLog fmi2_host_log(fmi2String instance_name,
                             const fmi2CallbackFunctions *functions) {
    HostLog log = {0};
    if (functions != NULL) {
        log.logger = (HostLogger)functions->logger;
        log.environment = functions->componentEnvironment;
    }
    log.send = send_fmi2;
    log.instance_name = instance_name;
    return log;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

int fmi2_instantiation_refused(HostLog *log, fmi2String instance_name, fmi2Type type,
                               fmi2String guid, fmi2String resource_location,
                               const fmi2CallbackFunctions *functions, const char *name,
                               const char *expected_guid, unsigned types) {
    *log = fmi2_host_log(instance_name, functions);
    char interface_problem[160];
    int offered = (unsigned)type <= fmi2CoSimulation && (types & (1u << type));
    if (!offered)
        snprintf(interface_problem, sizeof interface_problem, "does not offer the interface "
                 "type %d asked for (%s)", (int)type,
                 types == (1u << fmi2CoSimulation) ? "Co-Simulation only"
                                                   : "Model Exchange and Co-Simulation");
    InstantiationRequest request = {"fmi2Instantiate", instance_name, functions == NULL,
                                    offered ? NULL : interface_problem, "GUID", guid,
                                    "fmuResourceLocation", resource_location, 1};
    return instantiation_problem(log, &request, name, expected_guid);
}
