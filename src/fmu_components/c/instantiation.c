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
int uri_path(const char *uri, char *path, size_t size) {
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

static int resource_problem(const InstantiationRequest *r, const char *guid, char *problem,
                            size_t size) {
    char folder[MAX_PATH_LENGTH], identity[MAX_PATH_LENGTH + 32];
    const char *given = r->resource;
    if (given == NULL || given[0] == '\0') {
        snprintf(problem, size, "%s is missing: pass %s of the unzipped FMU's resources folder",
                 r->resource_name, r->resource_is_uri ? "the file URI" : "the path");
        return 1;
    }
    if (r->resource_is_uri) {
        if (uri_path(given, folder, sizeof folder)) {
            snprintf(problem, size, "%s '%.300s' is not a local file URI "
                     "(file:///path/to/resources)", r->resource_name, given);
            return 1;
        }
    } else {
        size_t n = strlen(given);
        if (n >= sizeof folder) {
            snprintf(problem, size, "%s '%.300s...' is longer than %d characters",
                     r->resource_name, given, MAX_PATH_LENGTH - 1);
            return 1;
        }
        memcpy(folder, given, n + 1);
        while (n > 1 && (folder[n - 1] == '/' || folder[n - 1] == '\\')) folder[--n] = '\0';
    }
    snprintf(identity, sizeof identity, "%s/%s", folder, IDENTITY_FILE);
    FILE *file = fopen(identity, "rb");
    if (file == NULL) {
        snprintf(problem, size, "%s '%.300s' is not the resources folder of an unzipped FMU "
                 "of this kind: it has no %s", r->resource_name, given, IDENTITY_FILE);
        return 1;
    }
    char text[128] = "";
    size_t read = fread(text, 1, sizeof text - 1, file);
    fclose(file);
    while (read > 0 && (text[read - 1] == '\n' || text[read - 1] == '\r')) read--;
    text[read] = '\0';
    if (strcmp(text, guid) != 0) {
        snprintf(problem, size, "%s '%.300s' belongs to another FMU: its %s holds %.64s, "
                 "this FMU's %s is %s", r->resource_name, given, IDENTITY_FILE, text,
                 r->token_name, guid);
        return 1;
    }
    return 0;
}

int instantiation_problem(const HostLog *log, const InstantiationRequest *r, const char *name,
                          const char *expected) {
    char problem[MESSAGE_SIZE], reason[MESSAGE_SIZE - 64];
    if (r->instance_name == NULL || r->instance_name[0] == '\0' || r->callbacks_missing) {
        snprintf(problem, sizeof problem, "%s: the instance name %s missing", r->function,
                 r->callbacks_missing ? "or the callback functions are" : "is");
    } else if (r->interface_problem) {
        snprintf(problem, sizeof problem, "%s: %s %s", r->function, name, r->interface_problem);
    } else if (r->token == NULL || strcmp(r->token, expected) != 0) {
        snprintf(problem, sizeof problem, "%s: %s %.100s is not this FMU's (%s %s): the "
                 "modelDescription and the binary belong to different FMUs", r->function,
                 r->token_name, r->token ? r->token : "(NULL)", name, expected);
    } else if (resource_problem(r, expected, reason, sizeof reason)) {
        snprintf(problem, sizeof problem, "%s: %s", r->function, reason);
    } else {
        return 0;
    }
    host_log(log, STATUS_ERROR, problem);
    return 1;
}
