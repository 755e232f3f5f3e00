/*
 * The content hash of the Python an FMU carries: FNV-1a 64 over each .py file under the
 * resources folder, in byte order of its relative path. It runs inside fmi2Instantiate, on
 * whatever thread the host calls from, whose stack may be small: the folders are walked
 * with a list on the heap rather than by recursion, and every buffer is on the heap.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "instantiation.h"
#include "python_content.h"

#define MAX_PYTHON_FILES 256
#define MAX_FOLDERS 4096 /* folders walked at most; more: the hash fails (unreadable) */
#define READ_SIZE 65536

typedef struct {
    char **items;
    int count, capacity, overflow;
} Paths;

/* Keeps `path` (taking it over), or frees it and marks the list overflowed. */
static void keep(Paths *paths, char *path) {
    if (path == NULL || paths->count == paths->capacity) {
        paths->overflow = 1;
        free(path);
        return;
    }
    paths->items[paths->count++] = path;
}

/* A new string "<a><separator><b>", the separator left out when a is empty. */
static char *joined(const char *a, const char *separator, const char *b) {
    size_t n = strlen(a) + strlen(separator) + strlen(b) + 1;
    char *text = malloc(n);
    if (text != NULL) snprintf(text, n, "%s%s%s", a, a[0] ? separator : "", b);
    return text;
}

/* A folder entry whose type the file system does not report (DT_UNKNOWN, older XFS) is
   told with opendir, not stat (stat links at GLIBC_2.33: glibc_floor.h). */
static int is_folder(const char *root, const char *relative, const struct dirent *entry) {
    if (entry->d_type != DT_UNKNOWN) return entry->d_type == DT_DIR;
    char *full = joined(root, "/", relative);
    DIR *inner = full ? opendir(full) : NULL;
    if (inner) closedir(inner);
    free(full);
    return inner != NULL;
}

/* The .py files under root (paths relative to it, '/' between parts), skipping hidden
   entries and __pycache__; the folders still to walk wait in `folders`. */
static void find_python(const char *root, Paths *files, Paths *folders) {
    keep(folders, joined("", "", ""));
    while (folders->count > 0) {
        char *relative = folders->items[--folders->count];
        char *folder = joined(root, "/", relative);
        DIR *directory = folder ? opendir(folder) : NULL;
        free(folder);
        struct dirent *entry;
        while (directory != NULL && (entry = readdir(directory)) != NULL) {
            const char *name = entry->d_name;
            size_t n = strlen(name);
            if (name[0] == '.' || strcmp(name, "__pycache__") == 0) continue;
            char *path = joined(relative, "/", name);
            if (path != NULL && is_folder(root, path, entry)) keep(folders, path);
            else if (n > 3 && strcmp(name + n - 3, ".py") == 0) keep(files, path);
            else free(path);
        }
        if (directory) closedir(directory);
        free(relative);
    }
}

static int by_bytes(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static uint64_t fnv1a(uint64_t hash, const unsigned char *bytes, size_t n) {
    for (size_t i = 0; i < n; i++) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
    return hash;
}

/* FNV-1a 64 over each .py file under the folder, in byte order of its relative path:
   the path, a NUL, the content, a NUL. 0 with the hash, or 1 if a file cannot be read. */
static int python_content(const char *folder, uint64_t *hash) {
    char *file_paths[MAX_PYTHON_FILES];
    Paths files = {file_paths, 0, MAX_PYTHON_FILES, 0};
    Paths folders = {malloc(MAX_FOLDERS * sizeof(char *)), 0, MAX_FOLDERS, 0};
    unsigned char *buffer = malloc(READ_SIZE);
    int failed = folders.items == NULL || buffer == NULL;
    if (!failed) find_python(folder, &files, &folders);
    failed |= files.overflow | folders.overflow;
    qsort(files.items, (size_t)files.count, sizeof *files.items, by_bytes);
    uint64_t h = 0xcbf29ce484222325ull;
    static const unsigned char nul = 0;
    for (int i = 0; i < files.count; i++) {
        char *path = joined(folder, "/", files.items[i]);
        FILE *file = path ? fopen(path, "rb") : NULL;
        failed |= file == NULL;
        h = fnv1a(fnv1a(h, (const unsigned char *)files.items[i], strlen(files.items[i])), &nul,
                  1);
        size_t n;
        while (file && (n = fread(buffer, 1, READ_SIZE, file)) > 0) h = fnv1a(h, buffer, n);
        h = fnv1a(h, &nul, 1);
        if (file) fclose(file);
        free(path);
        free(files.items[i]);
    }
    free(buffer);
    free(folders.items);
    *hash = h;
    return failed;
}

int python_content_problem(const HostLog *log, const char *resource_location,
                           const char *expected) {
    char *folder = malloc(4096), text[17];
    uint64_t hash = 0;
    int readable = folder != NULL && uri_path(resource_location, folder, 4096) == 0 &&
                   python_content(folder, &hash) == 0;
    free(folder);
    if (readable) {
        snprintf(text, sizeof text, "%016" PRIx64, hash);
        if (strcmp(text, expected) == 0) return 0;
    } else {
        snprintf(text, sizeof text, "(unreadable)");
    }
    char *message = malloc(MESSAGE_SIZE);
    if (message == NULL) return 1;
    snprintf(message, MESSAGE_SIZE, "fmi2Instantiate: the Python in %.300s hashes to %s, not "
             "to %s as built: a copy edited after the build would share its module names with "
             "an unedited one in this process. Build the FMU again (fmu-components build) "
             "rather than editing it", resource_location, text, expected);
    host_log(log, STATUS_ERROR, message);
    free(message);
    return 1;
}
