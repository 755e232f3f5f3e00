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
 * weights a cos(phase) and a sin(phase) (course.py's RandomRoad.weights). 0, or -1 where
 * memory runs out (the course is then given). */
CONTACTS_EXPORT int contacts_set_course(Contacts *c, int kind, const double *value, int terms,
                                        const double *cosine, const double *sine)
{
    free(c->course_term);
    c->course_term = NULL;
    c->course_terms = 0;
    c->course = COURSE_GIVEN;
    memcpy(c->course_value, value, sizeof(c->course_value));
    if (kind == COURSE_RANDOM) {
        c->course_term = malloc(sizeof(double) * 3 * (size_t)(terms > 0 ? terms : 1));
        if (!c->course_term) return -1;
        memcpy(c->course_term, cosine, sizeof(double) * terms);
        memcpy(c->course_term + terms, sine, sizeof(double) * terms);
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

/* RandomRoad.height: its terms, e^(i u k) turned from term to term as numpy's
 * multiply.accumulate turns it (complex products in numpy's order), summed as numpy sums a
 * row, less their sum at the start, faded in over `fade` */
static double random_height(Contacts *c, double x)
{
    const double *v = c->course_value;
    double u = (x - v[C_FRONT]) - v[C_START];
    if (!(u > 0.0)) return 0.0;
    int n = c->course_terms;
    const double *cosine = c->course_term, *sine = cosine + n;
    double *term = c->course_term + 2 * n;
    double turn_r = cos(u * v[C_WAVE]), turn_i = sin(u * v[C_WAVE]);
    double step_r = cos(u * v[C_WAVE_STEP]), step_i = sin(u * v[C_WAVE_STEP]);
    for (int j = 0; j < n; j++) {
        if (j) {
            double r = turn_r * step_r - turn_i * step_i;
            turn_i = turn_r * step_i + turn_i * step_r;
            turn_r = r;
        }
        term[j] = cosine[j] * turn_r - sine[j] * turn_i;
    }
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
