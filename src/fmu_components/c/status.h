/* What every call answers, whatever the FMI version: the values of fmi2Status and
   fmi3Status (OK to Fatal), so each face passes them on as they are. */
#ifndef STATUS_H
#define STATUS_H

typedef enum {
    STATUS_OK,
    STATUS_WARNING,
    STATUS_DISCARD,
    STATUS_ERROR,
    STATUS_FATAL,
} Status;

#endif
