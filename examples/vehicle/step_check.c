/* The vehicle's step check in C (step_check.py, StepCheck.judge; the rule and its
 * thresholds explained there): a solve's solution q1 against its step's start q0, v0 of
 * length h: each link's motion beyond h v0, each tyre's compression beyond h times its
 * rate (wheels in contact at both ends), each pin's gap to its sprocket tooth space (engaged
 * at both ends). step_check.py's links_verdict and contacts_verdict are the numpy
 * reference, the same operations in the same order (-ffp-contract=off), each largest value
 * picked as numpy's argmax picks it (the first NaN, else the first largest). libc and libm
 * only. */
#include <math.h>

#if defined(_WIN32)
#define STEP_CHECK_EXPORT __declspec(dllexport)
#else
#define STEP_CHECK_EXPORT __attribute__((visibility("default")))
#endif

/* step_check.py's _Layout */
typedef struct {
    int links, wheels;
    double link_jump, link_turn, tyre_jump, tooth_jump;
    const int *link_index; /* links x 3: each link's x, y, angle in q */
} StepCheckLayout;

enum { PASSED = 0, LINK = 1, TYRE = 2, TOOTH = 3 };

STEP_CHECK_EXPORT int step_check_layout(void) { return (int)sizeof(StepCheckLayout); }

/* numpy's argmax's pick: the first NaN, else the first largest; index -1 before the first */
typedef struct {
    int index;
    double value;
} Largest;

static int takes_over(const Largest *largest, double value)
{
    if (largest->index < 0)
        return 1;
    if (isnan(largest->value))
        return 0;
    return isnan(value) || value > largest->value;
}

static void consider(Largest *largest, int index, double value)
{
    if (takes_over(largest, value)) {
        largest->index = index;
        largest->value = value;
    }
}

/* where the largest is beyond `threshold`: found[0] its index, found[1] its value */
static int beyond(const Largest *largest, double threshold, double *found)
{
    if (largest->index < 0 || !(largest->value > threshold))
        return 0;
    found[0] = largest->index;
    found[1] = largest->value;
    return 1;
}

/* PASSED, or LINK with found[0] the link's index, found[1] and found[2] its motion and
 * turn beyond h v0 (the largest of them by their thresholds) */
STEP_CHECK_EXPORT int step_check_links(const StepCheckLayout *c, double h, const double *q1,
                                       const double *q0, const double *v0, double *found)
{
    Largest largest = {-1, 0.0};
    double moved_best = 0.0, turned_best = 0.0;
    for (int k = 0; k < c->links; k++) {
        const int *at = c->link_index + 3 * k;
        double dx = q1[at[0]] - q0[at[0]] - h * v0[at[0]];
        double dy = q1[at[1]] - q0[at[1]] - h * v0[at[1]];
        double dt = q1[at[2]] - q0[at[2]] - h * v0[at[2]];
        double moved = hypot(dx, dy), turned = fabs(dt);
        double a = moved / c->link_jump, b = turned / c->link_turn;
        double ratio = (isnan(a) || isnan(b)) ? NAN : (a >= b ? a : b); /* np.maximum */
        if (takes_over(&largest, ratio)) {
            consider(&largest, k, ratio);
            moved_best = moved;
            turned_best = turned;
        }
    }
    if (largest.index >= 0 && (moved_best > c->link_jump || turned_best > c->link_turn)) {
        found[0] = largest.index;
        found[1] = moved_best;
        found[2] = turned_best;
        return LINK;
    }
    return PASSED;
}

/* PASSED, or TYRE (TOOTH) with found[0] the wheel's (joint's) index and found[1] its jump
 * of compression beyond h times its rate at the start (of gap): the contacts' values at the
 * solution (compression1, gap1) against the start's. A wheel is in contact where its
 * compression is above -inf, a pin engaged where its gap is above 0. */
STEP_CHECK_EXPORT int step_check_contacts(const StepCheckLayout *c, double h,
                                          const double *compression1, const double *gap1,
                                          const double *compression0, const double *rate0,
                                          const double *gap0, double *found)
{
    Largest tyre = {-1, 0.0}, tooth = {-1, 0.0};
    for (int w = 0; w < c->wheels; w++) {
        int both = compression0[w] > -INFINITY && compression1[w] > -INFINITY;
        double jump = fabs(compression1[w] - compression0[w] - h * rate0[w]);
        consider(&tyre, w, both ? jump : 0.0);
    }
    if (beyond(&tyre, c->tyre_jump, found))
        return TYRE;
    for (int j = 0; j < c->links; j++) {
        int both = gap0[j] > 0.0 && gap1[j] > 0.0;
        consider(&tooth, j, both ? fabs(gap1[j] - gap0[j]) : 0.0);
    }
    return beyond(&tooth, c->tooth_jump, found) ? TOOTH : PASSED;
}
