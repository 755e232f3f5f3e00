/*
 * Messages to the host's logger, shared by every binary (both flavours, both FMI
 * versions): errors and warnings always reach the host, whatever loggingOn says; other
 * messages when the host switched debug logging on for their category (or for all). The
 * logger's signature is the FMI version's: its face gives the `send` that calls it.
 */
#ifndef HOST_LOG_H
#define HOST_LOG_H

#include <stdarg.h>
#include <stddef.h>

#include "call_flag.h"
#include "status.h"

#define MAX_LOG_CATEGORIES 16
#define MESSAGE_SIZE 1024

typedef void (*HostLogger)(void); /* the host's logger, cast back to its type by `send` */
struct HostLog;
typedef void (*HostLogSend)(const struct HostLog *log, Status status, const char *category,
                            const char *message);

typedef struct HostLog {
    HostLogger logger; /* may be NULL: then nothing is logged */
    HostLogSend send;  /* calls the logger the way its FMI version's signature says */
    void *environment;
    const char *instance_name;
    int debug_logging;
    size_t n_categories; /* 0: every category */
    char *categories[MAX_LOG_CATEGORIES];
} HostLog;

/* The category a status is logged under (the modelDescription's LogCategories). */
const char *log_category(Status status);

int host_log_wants(const HostLog *log, Status status, const char *category);

/* Pass one finished message on (an FMI 2 logger gets it as a format string with any '%'
   doubled: hosts that format print it exactly, and hosts that do not still get the text). */
void host_log_send(const HostLog *log, Status status, const char *category,
                   const char *message);

/* Log a message under its status's category, if the host wants it. */
void host_log(const HostLog *log, Status status, const char *message);
/* As host_log, the message formatted from format and args (cut to MESSAGE_SIZE). */
void host_log_formatted(const HostLog *log, Status status, const char *format, va_list args);

/* fmi2SetDebugLogging, fmi3SetDebugLogging (`function`): 0, or 1 with the reason in
   problem[MESSAGE_SIZE]. */
int host_log_set(HostLog *log, const char *function, int on, size_t n,
                 const char *const categories[], char *problem);
void host_log_forget(HostLog *log);

/* A call refused because another call on its instance has not returned (call_flag.h): the
   host is told, unless this thread is inside a host logger that host_log_send called (a
   logger calling back) and has been told once during the running call. */
void host_log_overlap(const HostLog *log, CallFlag *call, const char *function);

#endif
