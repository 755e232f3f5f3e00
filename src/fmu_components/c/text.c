#include "text.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

const char *format_repr(double value, char *buffer) {
    if (isnan(value)) return strcpy(buffer, "nan");
    if (isinf(value)) return strcpy(buffer, value < 0 ? "-inf" : "inf");
    /* The shortest correctly rounded mantissa that reads back to the same double. */
    char scientific[REPR_SIZE];
    for (int digits = 1; digits <= 17; digits++) {
        snprintf(scientific, sizeof scientific, "%.*e", digits - 1, value);
        if (strtod(scientific, NULL) == value) break;
    }
    /* scientific: [-]d[.ddd]e[+-]xx -> the digits and the position of the point */
    const char *p = scientific;
    char *out = buffer;
    if (*p == '-') *out++ = *p++;
    char mantissa[20];
    size_t n = 0;
    for (; *p && *p != 'e'; p++)
        if (*p != '.') mantissa[n++] = *p;
    mantissa[n] = '\0';
    int point = atoi(p + 1) + 1; /* digits before the decimal point */
    if (point <= -4 || point > 16) { /* Python's repr switches to exponent notation */
        *out++ = mantissa[0];
        if (n > 1) {
            *out++ = '.';
            memcpy(out, mantissa + 1, n - 1);
            out += n - 1;
        }
        snprintf(out, REPR_SIZE - (size_t)(out - buffer), "e%c%02d", point - 1 < 0 ? '-' : '+',
                 abs(point - 1));
    } else if (point <= 0) {
        out += sprintf(out, "0.");
        for (int i = 0; i < -point; i++) *out++ = '0';
        strcpy(out, mantissa);
    } else if ((size_t)point >= n) {
        memcpy(out, mantissa, n);
        out += n;
        for (size_t i = n; i < (size_t)point; i++) *out++ = '0';
        strcpy(out, ".0");
    } else {
        memcpy(out, mantissa, (size_t)point);
        out += point;
        *out++ = '.';
        strcpy(out, mantissa + point);
    }
    return buffer;
}
