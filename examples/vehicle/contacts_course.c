/* The course's height under the pins, in the kernel (contacts_kernel.py hands the course
 * over): course.py's Course.height for its courses (flat, bump, sine, random road), the
 * same operations in the same order, so that the heights are numpy's bits; a course of
 * another kind is given, its heights written by Python. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "contacts.h"

#define P(name) (c->parameter[P_##name])
#define ARRAY(name) (c->array[A_##name])

/* kind: enum Course; value: C_COUNT values (enum CourseValue); a random road's `terms`
 * wave numbers k, amplitudes and phases. 0, or -1 where memory runs out (the course is
 * then given). */
CONTACTS_EXPORT int contacts_set_course(Contacts *c, int kind, const double *value, int terms,
                                        const double *k, const double *amplitude,
                                        const double *phase)
{
    free(c->course_term);
    c->course_term = NULL;
    c->course_terms = 0;
    c->course = COURSE_GIVEN;
    memcpy(c->course_value, value, sizeof(c->course_value));
    if (kind == COURSE_RANDOM) {
        c->course_term = malloc(sizeof(double) * 4 * (size_t)(terms > 0 ? terms : 1));
        if (!c->course_term) return -1;
        memcpy(c->course_term, k, sizeof(double) * terms);
        memcpy(c->course_term + terms, amplitude, sizeof(double) * terms);
        memcpy(c->course_term + 2 * terms, phase, sizeof(double) * terms);
        c->course_terms = terms;
    }
    c->course = kind;
    return 0;
}

/* (x - front - start) / length, as Course.along */
static double along(const Contacts *c, double x)
{
    const double *v = c->course_value;
    return ((x - v[C_FRONT]) - v[C_START]) / v[C_LENGTH];
}

/* RandomRoad.height: its cosines summed as numpy sums a row, less their sum at the start,
 * faded in over `fade` */
static double random_height(Contacts *c, double x)
{
    const double *v = c->course_value;
    double u = (x - v[C_FRONT]) - v[C_START];
    if (!(u > 0.0)) return 0.0;
    int n = c->course_terms;
    const double *k = c->course_term, *amplitude = k + n, *phase = k + 2 * n;
    double *term = c->course_term + 3 * n;
    for (int j = 0; j < n; j++) term[j] = amplitude[j] * cos(u * k[j] + phase[j]);
    double fade = u / v[C_FADE];
    return (numpy_sum(term, n) - v[C_OFFSET]) * (fade > 1.0 ? 1.0 : fade);
}

/* ARRAY(GROUND) at the pins, unless the course is given (contacts_forces calls it): as
 * course.py's Course.under, the course's ceiling under a pin whose link's ground face is
 * above it (it cannot meet the course), the course's height under the others */
CONTACTS_EXPORT void contacts_course_heights(Contacts *c)
{
    double *ground = ARRAY(GROUND);
    const double *pins = ARRAY(PINS), *v = c->course_value;
    for (int j = 0; j < c->links && c->course != COURSE_GIVEN; j++) {
        double x = pins[2 * j], u;
        if (pins[2 * j + 1] - P(LINK_OUTER) > v[C_CEILING]) {
            ground[j] = v[C_CEILING];
            continue;
        }
        switch (c->course) {
        case COURSE_BUMP:
            u = along(c, x);
            ground[j] = u > 0.0 && u < 1.0 ? v[C_SCALE] * (1.0 - cos(P(TWO_PI) * u)) : 0.0;
            break;
        case COURSE_SINE:
            u = along(c, x);
            ground[j] = u > 0.0 ? v[C_SCALE] * (1.0 - cos(P(TWO_PI) * u)) : 0.0;
            break;
        case COURSE_RANDOM:
            ground[j] = random_height(c, x);
            break;
        default:
            ground[j] = 0.0;
        }
    }
}
