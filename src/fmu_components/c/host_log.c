#include "host_log.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(_MSC_VER)
#define THREAD_LOCAL __declspec(thread)
#else
#define THREAD_LOCAL __thread
#endif

/* How deep this thread is in host loggers called from here: a call on an instance from
   inside one is the logger calling back. */
static THREAD_LOCAL int logger_depth;

void host_log_overlap(const HostLog *log, CallFlag *call, const char *function) {
    if (!call_refusal_told(call, logger_depth > 0)) return;
    char message[MESSAGE_SIZE];
    snprintf(message, sizeof message, CALL_OVERLAP_MESSAGE, function);
    host_log(log, STATUS_ERROR, message);
}

void host_log_send(const HostLog *log, Status status, const char *category,
                   const char *message) {
    if (log->logger == NULL || log->send == NULL) return;
    logger_depth++;
    log->send(log, status, category, message);
    logger_depth--;
}

const char *log_category(Status status) {
    switch (status) {
    case STATUS_WARNING: return "logStatusWarning";
    case STATUS_DISCARD: return "logStatusDiscard";
    case STATUS_ERROR: return "logStatusError";
    case STATUS_FATAL: return "logStatusFatal";
    default: return "logAll";
    }
}

int host_log_wants(const HostLog *log, Status status, const char *category) {
    if (log->logger == NULL) return 0;
    if (status >= STATUS_WARNING) return 1;
    if (!log->debug_logging) return 0;
    if (log->n_categories == 0) return 1;
    for (size_t i = 0; i < log->n_categories; i++)
        if (strcmp(log->categories[i], "logAll") == 0 ||
            (category && strcmp(category, log->categories[i]) == 0))
            return 1;
    return 0;
}

void host_log_formatted(const HostLog *log, Status status, const char *format, va_list args) {
    char message[MESSAGE_SIZE];
    vsnprintf(message, sizeof message, format, args);
    host_log(log, status, message);
}

void host_log(const HostLog *log, Status status, const char *message) {
    const char *category = log_category(status);
    if (host_log_wants(log, status, category)) host_log_send(log, status, category, message);
}

void host_log_forget(HostLog *log) {
    for (size_t i = 0; i < log->n_categories; i++) free(log->categories[i]);
    log->n_categories = 0;
}

int host_log_set(HostLog *log, const char *function, int on, size_t n,
                 const char *const categories[], char *problem) {
    if (n > MAX_LOG_CATEGORIES) {
        snprintf(problem, MESSAGE_SIZE, "%s: %u categories given, at most %d are kept",
                 function, (unsigned)n, MAX_LOG_CATEGORIES);
        return 1;
    }
    if (n > 0 && categories == NULL) {
        snprintf(problem, MESSAGE_SIZE, "%s: %u categories announced but the list is NULL",
                 function, (unsigned)n);
        return 1;
    }
    char *copies[MAX_LOG_CATEGORIES];
    for (size_t i = 0; i < n; i++) {
        const char *category = categories[i] ? categories[i] : "";
        copies[i] = malloc(strlen(category) + 1);
        if (copies[i] == NULL) {
            while (i > 0) free(copies[--i]);
            snprintf(problem, MESSAGE_SIZE, "%s: out of memory", function);
            return 1;
        }
        strcpy(copies[i], category);
    }
    host_log_forget(log);
    log->debug_logging = on;
    for (size_t i = 0; i < n; i++) log->categories[i] = copies[i];
    log->n_categories = n;
    return 0;
}
