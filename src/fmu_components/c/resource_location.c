#include "resource_location.h"

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

int check_resource_location(const char *uri, const char *guid, char *path, size_t path_size,
                            char *problem, size_t size) {
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
    if (path != NULL && path_size > 0) snprintf(path, path_size, "%s", folder);
    return 0;
}
