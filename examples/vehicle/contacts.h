/* The vehicle's contacts in C (contacts_kernel.py loads them): the numpy kernel of
 * contacts.py, the same equations in the same order of operations, so that the two give
 * the same numbers. libc and libm only. */
#ifndef VEHICLE_CONTACTS_H
#define VEHICLE_CONTACTS_H

#if defined(_WIN32)
#define CONTACTS_EXPORT __declspec(dllexport)
#else
#define CONTACTS_EXPORT __attribute__((visibility("default")))
#endif

/* The model's values, in the order contacts_kernel.PARAMETERS gives them. */
enum Parameter {
    P_LINK_PITCH, P_LINK_INNER, P_LINK_OUTER, P_WHEEL_RADIUS, P_TYRE_BLEND, P_HANDOVER,
    P_CONTACT_ONSET, P_GROUND_STIFFNESS, P_GROUND_DAMPING, P_SPROCKET_STIFFNESS,
    P_SPROCKET_DAMPING, P_WHEEL_STIFFNESS, P_WHEEL_DAMPING, P_ENGAGEMENT_RAMP,
    P_ENGAGEMENT_RAMP_SQUARED, P_SPROCKET_PITCH_RADIUS, P_TOOTH_SPACING, P_IDLER_PIN_RADIUS,
    P_ROLLER_PIN_RADIUS, P_SPROCKET_X, P_SPROCKET_Y, P_ROLLER_X, P_ROLLER_Y, P_WRAP_START,
    P_WRAP_SWEEP, P_TOOTH_PHASE, P_HULL_X0, P_SETTLE_SEAT, P_SETTLE_ARM, P_SETTLE_HULL_X,
    P_SETTLE_HULL_Y, P_SETTLE_HULL_PITCH, P_TWO_PI, P_HORN_HEIGHT, P_COUNT
};

/* The arrays Python reads and writes in place (numpy views of the kernel's memory), in
 * the order of contacts_kernel.ARRAYS. */
enum Array {
    A_STATE, A_RATES, A_U, A_N, A_SEATS, A_SEATS_V, A_PINS, A_PINS_V, A_WHEELS, A_WHEELS_V,
    A_COMPRESSION, A_COMPRESSION_RATE, A_LOADS, A_SLOPES, A_RATE_SLOPES, A_TYRE_FORCE,
    A_GROUND, A_GROUND_LOAD, A_TOOTH_GAP, A_GENERALIZED, A_DRIVE_TORQUE, A_COUNT
};

/* bank.c's bank_law_loads: the bank's laws' loads and slopes at its deflections. */
typedef void (*LawLoads)(const void *bank, const double *deflection, double *loads,
                         double *slopes);

/* The course under the pins (contacts_course.c): course.py's courses, or heights given
 * (Python writes ARRAY(GROUND)). */
enum Course { COURSE_GIVEN = -1, COURSE_FLAT, COURSE_BUMP, COURSE_SINE, COURSE_RANDOM };
/* A course's values, in the order contacts_kernel.course_values gives them (C_CEILING:
 * course.py's Course.ceiling; C_WAVE, C_WAVE_STEP: a random road's k[0] and k_step). */
enum CourseValue {
    C_FRONT, C_START, C_LENGTH, C_SCALE, C_FADE, C_OFFSET, C_CEILING, C_WAVE, C_WAVE_STEP,
    C_COUNT
};

/* One spring for the Jacobian: its 2 x 2 stiffness and damping between up to three
 * members, each a body, how a force at its point loads the body (force_g), how the point
 * moves with it (motion_g), and its weight. */
typedef struct {
    double stiffness[2][2], damping[2][2];
    int members;
    int body[3];
    double force_g[3][2][3], motion_g[3][2][3], weight[3];
} Spring;

/* One end of a link's window in a tyre's blend: the joint's bisector (normal m, the
 * links' directions u_a + u_b of length size), the wheel's offset from the joint's pin,
 * the smoothstep's argument x. */
typedef struct {
    int a, b;
    double sign, size, m[2], offset[2], x;
} End;

/* A link beneath a wheel: its window, its overlap and its term in the blend. */
typedef struct {
    int wheel, link;
    double along, window, overlap, term;
    End end[2];
} Candidate;

typedef struct {
    int bodies, wheels, links, link0;
    double parameter[P_COUNT];
    double *array[A_COUNT];
    double *reference, *wheel_offset;
    /* (wheel, link beneath) pairs of the tyres' blend */
    int pairs;
    int *pair_wheel, *pair_coordinate; /* pairs x 12 */
    double *pair_weight, *pair_gradient; /* pairs x 12 */
    int springs, spring_capacity;
    Spring *spring;
    /* 1: contacts_forces leaves the springs out (c->springs then lacks them: a caller
     * that wants the Jacobian evaluates again with 0, contacts_new's) */
    int forces_only;
    Candidate *candidate; /* wheels x links */
    int *in_contact; /* wheels */
    double *scratch, *pin; /* 8 (links + wheels), links x 2 */
    double *bodies_force, *tyres; /* bodies x 3 */
    /* the tyres' Jacobian: p.D's entries (3 per wheel, 9 per pair) */
    int *entry_wheel, *entry_coordinate;
    double *entry_value;
    /* the course: its kind, values, and a random road's terms (weights of the cosines
     * and of the sines, then room for the terms of one pin: 3 x course_terms) */
    int course, course_terms;
    double course_value[C_COUNT];
    double *course_term;
    /* the tyres' laws where the kernel evaluates them (contacts_set_tyre_laws): the bank's
     * function and handle, each wheel's two rows in it, arrays of the bank's size */
    LawLoads law_loads;
    const void *bank;
    int *tyre_row; /* wheels x 2 */
    double *law_deflection, *law_load, *law_slope;
} Contacts;

/* (row, column, value) rows written into `out` while they fit `capacity`; `count` counts
 * them all (contacts_jacobian.c's triplets_put adds one) */
typedef struct {
    double *out;
    long count, capacity;
} Triplets;

void triplets_put(Triplets *t, int row, int column, double value);
double numpy_sum(const double *a, int n);
double numpy_remainder(double a, double b);
void smoothstep_derivatives(double x, double *value, double *slope, double *curvature);
CONTACTS_EXPORT void contacts_course_heights(Contacts *c);
CONTACTS_EXPORT void contacts_forces(Contacts *c, int settling);
double penalty_force(const Contacts *c, double depth, double closing, double stiffness,
                     double damping, double *by_depth, double *by_closing);

#endif
