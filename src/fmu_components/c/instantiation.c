#include "instantiation.h"

#include <ctype.h>
#include <stdio.h>
#include <string.h>

#define MAX_PATH_LENGTH 4096

static int hex(int c) {
    if (c >= '0' && c <= '9') return c - '0';
    c = tolower(c);
    return c >= 'a' && c <= 'f' ? c - 'a' + 10 : -1;
}

/* The path of a file URI, percent-decoded: file:///p, file:/p, file://localhost/p; on
   Windows file:///C:/p gives C:/p. 0 on success. */
static int uri_path(const char *uri, char *path, size_t size) {
    if (strncmp(uri, "file:", 5) != 0) return 1;
    const char *p = uri + 5;
    if (strncmp(p, "//localhost/", 12) == 0) p += 11;
    else if (strncmp(p, "///", 3) == 0) p += 2;
    else if (strncmp(p, "//", 2) == 0) return 1; /* a remote host */
#ifdef _WIN32
    if (p[0] == '/' && isalpha((unsigned char)p[1]) && p[2] == ':') p++;
#endif
    size_t n = 0;
    for (; *p; p++) {
        int c = (unsigned char)*p;
        if (c == '%') {
            int high = hex((unsigned char)p[1]), low = high < 0 ? -1 : hex((unsigned char)p[2]);
            if (low < 0) return 1;
            c = 16 * high + low;
            p += 2;
        }
        if (c == '\0' || n + 1 >= size) return 1;
        path[n++] = (char)c;
    }
    while (n > 1 && path[n - 1] == '/') n--;
    path[n] = '\0';
    return n == 0;
}

static int resource_problem(const char *uri, const char *guid, char *problem, size_t size) {
    char folder[MAX_PATH_LENGTH], identity[MAX_PATH_LENGTH + 32];
    if (uri == NULL || uri[0] == '\0') {
        snprintf(problem, size, "fmuResourceLocation is missing: pass the file URI of the "
                 "unzipped FMU's resources folder");
        return 1;
    }
    if (uri_path(uri, folder, sizeof folder)) {
        snprintf(problem, size, "fmuResourceLocation '%.300s' is not a local file URI "
                 "(file:///path/to/resources)", uri);
        return 1;
    }
    snprintf(identity, sizeof identity, "%s/%s", folder, IDENTITY_FILE);
    FILE *file = fopen(identity, "rb");
    if (file == NULL) {
        snprintf(problem, size, "fmuResourceLocation '%.300s' is not the resources folder of "
                 "an unzipped FMU of this kind: it has no %s", uri, IDENTITY_FILE);
        return 1;
    }
    char text[128] = "";
    size_t read = fread(text, 1, sizeof text - 1, file);
    fclose(file);
    while (read > 0 && (text[read - 1] == '\n' || text[read - 1] == '\r')) read--;
    text[read] = '\0';
    if (strcmp(text, guid) != 0) {
        snprintf(problem, size, "fmuResourceLocation '%.300s' belongs to another FMU: its %s "
                 "holds GUID %.64s, this FMU's is %s", uri, IDENTITY_FILE, text, guid);
        return 1;
    }
    return 0;
}

HostLog instantiation_log(fmi2String instance_name, const fmi2CallbackFunctions *functions) {
    HostLog log = {0};
    if (functions != NULL) {
        log.logger = functions->logger;
        log.environment = functions->componentEnvironment;
    }
    log.instance_name = instance_name;
    return log;
}

int instantiation_problem(const HostLog *log, fmi2String instance_name, fmi2Type type,
                          fmi2String guid, fmi2String resource_location,
                          const fmi2CallbackFunctions *functions, const char *name,
                          const char *expected_guid, unsigned types) {
    char problem[MESSAGE_SIZE], reason[MESSAGE_SIZE - 32];
    if (instance_name == NULL || instance_name[0] == '\0' || functions == NULL) {
        snprintf(problem, sizeof problem, "fmi2Instantiate: the instance name or the callback "
                 "functions are missing");
    } else if ((unsigned)type > fmi2CoSimulation || !(types & (1u << type))) {
        snprintf(problem, sizeof problem, "fmi2Instantiate: %s does not offer the interface "
                 "type %d asked for (%s)", name, (int)type,
                 types == (1u << fmi2CoSimulation) ? "Co-Simulation only"
                                                   : "Model Exchange and Co-Simulation");
    } else if (guid == NULL || strcmp(guid, expected_guid) != 0) {
        snprintf(problem, sizeof problem, "fmi2Instantiate: GUID %.100s is not this FMU's (%s "
                 "%s): the modelDescription and the binary belong to different FMUs",
                 guid ? guid : "(NULL)", name, expected_guid);
    } else if (resource_problem(resource_location, expected_guid, reason, sizeof reason)) {
        snprintf(problem, sizeof problem, "fmi2Instantiate: %s", reason);
    } else {
        return 0;
    }
    host_log(log, fmi2Error, problem);
    return 1;
}
