/* The vehicle's contact forces and their Jacobian (contacts._forces, contacts._triplets
 * and contacts._tyre_triplets in C; contacts.c has the kinematics): ground, sprocket
 * teeth, idler and roller, tyres, and while settling the damping of every body. */
#include <math.h>
#include <string.h>

#include "contacts.h"

#define P(name) (c->parameter[P_##name])
#define ARRAY(name) (c->array[A_##name])

/* Whether a point at (r0, r1) from a centre lies surely beyond `reach` of it (hypot > reach):
 * its squared distance past reach's square by a margin far above the round-off of either
 * (1e-9 relative), so that a pair beyond it would have given no force, to the bit; NaN
 * is never beyond (the full computation says what it gives). */
static int surely_beyond(double r0, double r1, double reach)
{
    return r0 * r0 + r1 * r1 > reach * reach * (1.0 + 1e-9);
}

/* d(point)/d(body's x, y, angle): how a force at a point fixed on the body loads it, and
 * how the point moves with it. */
static void point_g(const Contacts *c, int body, const double *point, double g[2][3])
{
    const double *position = ARRAY(STATE) + 3 * body;
    double r0 = point[0] - position[0], r1 = point[1] - position[1];
    g[0][0] = 1.0; g[0][1] = 0.0; g[0][2] = -r1;
    g[1][0] = 0.0; g[1][1] = 1.0; g[1][2] = r0;
}

static Spring *new_spring(Contacts *c, const double stiffness[2][2],
                          const double damping[2][2])
{
    Spring *s = &c->spring[c->springs++];
    memcpy(s->stiffness, stiffness, sizeof(s->stiffness));
    memcpy(s->damping, damping, sizeof(s->damping));
    s->members = 0;
    return s;
}

static void add_member(Spring *s, int body, const double force_g[2][3],
                       const double motion_g[2][3], double weight)
{
    int m = s->members++;
    s->body[m] = body;
    memcpy(s->force_g[m], force_g, sizeof(s->force_g[m]));
    memcpy(s->motion_g[m], motion_g, sizeof(s->motion_g[m]));
    s->weight[m] = weight;
}

/* A spring on pin j: the two seats that make it, half each (contacts._pin_springs). */
static Spring *pin_spring(Contacts *c, int j, const double stiffness[2][2],
                          const double damping[2][2])
{
    int behind = (j + c->links - 1) % c->links;
    double g[2][3];
    Spring *s = new_spring(c, stiffness, damping);
    point_g(c, c->link0 + behind, ARRAY(SEATS) + 4 * behind + 2, g);
    add_member(s, c->link0 + behind, g, g, 0.5);
    point_g(c, c->link0 + j, ARRAY(SEATS) + 4 * j, g);
    add_member(s, c->link0 + j, g, g, 0.5);
    return s;
}

static void normal_matrices(double k, double damping, const double normal[2],
                            double stiffness_out[2][2], double damping_out[2][2])
{
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 2; j++) {
            stiffness_out[i][j] = k * (normal[i] * normal[j]);
            damping_out[i][j] = damping * (normal[i] * normal[j]);
        }
}

/* Forces on a body at points (contacts' on_body): the sum of the forces (row after row,
 * as numpy sums over its first axis) and of their moments (numpy's 1-d sum). */
static void on_body(Contacts *c, int body, const double *points, int point_stride,
                    const double *forces, int count)
{
    double *b = c->bodies_force + 3 * body, *moment = c->scratch;
    const double *position = ARRAY(STATE) + 3 * body;
    double sum0 = 0.0, sum1 = 0.0;
    for (int i = 0; i < count; i++) {
        const double *point = points + point_stride * i, *f = forces + 2 * i;
        sum0 = i ? sum0 + f[0] : f[0];
        sum1 = i ? sum1 + f[1] : f[1];
        double r0 = point[0] - position[0], r1 = point[1] - position[1];
        moment[i] = r0 * f[1] - r1 * f[0];
    }
    b[0] += sum0;
    b[1] += sum1;
    b[2] += numpy_sum(moment, count);
}

static void ground(Contacts *c)
{
    const double *pins = ARRAY(PINS), *pins_v = ARRAY(PINS_V);
    static const double up[2] = {0.0, 1.0};
    for (int j = 0; j < c->links; j++) {
        double depth = ARRAY(GROUND)[j] - (pins[2 * j + 1] - P(LINK_OUTER));
        double k, damping, stiffness_m[2][2], damping_m[2][2];
        double load = penalty_force(c, depth, -pins_v[2 * j + 1], P(GROUND_STIFFNESS),
                                    P(GROUND_DAMPING), &k, &damping);
        c->pin[2 * j + 1] += load;
        ARRAY(GROUND_LOAD)[j] = load;
        if (load > 0.0 && !c->forces_only) {
            normal_matrices(k, damping, up, stiffness_m, damping_m);
            pin_spring(c, j, stiffness_m, damping_m);
        }
    }
}

/* The teeth's hold w on a pin by its angle into the wrap, and its first and second
 * derivatives by that angle (contacts._engagement). */
static void engagement(const Contacts *c, double into, double *weight, double *slope,
                       double *curvature)
{
    double a, da, dda, b, db, ddb;
    smoothstep_derivatives(into / P(ENGAGEMENT_RAMP), &a, &da, &dda);
    smoothstep_derivatives((P(WRAP_SWEEP) - into) / P(ENGAGEMENT_RAMP), &b, &db, &ddb);
    *weight = a * b;
    *slope = (da * b - a * db) / P(ENGAGEMENT_RAMP);
    *curvature = (dda * b - 2.0 * da * db + a * ddb) / P(ENGAGEMENT_RAMP_SQUARED);
}

typedef struct {
    double weight, slope, curvature, slot_angle, slot[2], slot_v[2], gap[2], pull[2];
    double tooth_force[2], stored, by_angle[2], rel[2], distance;
} Tooth;

/* How the tooth space (on the hull) loads it, and how it moves: it turns back as the hull
 * travels forward. */
static void slot_motion(const Contacts *c, const Tooth *tooth, double slot_g[2][3],
                        double motion_g[2][3])
{
    point_g(c, 0, tooth->slot, slot_g);
    memcpy(motion_g, slot_g, sizeof(double) * 6);
    motion_g[0][0] += sin(tooth->slot_angle);
    motion_g[1][0] -= cos(tooth->slot_angle);
}

static void sprocket(Contacts *c)
{
    const double *hull = ARRAY(STATE), *hull_v = ARRAY(RATES);
    const double *pins = ARRAY(PINS), *pins_v = ARRAY(PINS_V);
    double stiffness = P(SPROCKET_STIFFNESS), damping = P(SPROCKET_DAMPING);
    double radius = P(SPROCKET_PITCH_RADIUS);
    double cs = cos(hull[2]), sn = sin(hull[2]);
    double centre[2] = {hull[0] + (cs * P(SPROCKET_X) - sn * P(SPROCKET_Y)),
                        hull[1] + (sn * P(SPROCKET_X) + cs * P(SPROCKET_Y))};
    double centre_v[2] = {hull_v[0] + -hull_v[2] * (centre[1] - hull[1]),
                          hull_v[1] + hull_v[2] * (centre[0] - hull[0])};
    double turned = hull[2] + P(TOOTH_PHASE) - (hull[0] - P(HULL_X0)) / radius;
    double rate = hull_v[2] - hull_v[0] / radius;
    Tooth teeth[c->links];
    double *forces = c->scratch + c->links, *points = c->scratch + 3 * c->links;
    for (int j = 0; j < c->links; j++) {
        Tooth *t = &teeth[j];
        const double *pin = pins + 2 * j, *pin_v = pins_v + 2 * j;
        t->rel[0] = pin[0] - centre[0];
        t->rel[1] = pin[1] - centre[1];
        if (surely_beyond(t->rel[0], t->rel[1], radius + 0.08)) {
            /* out of the teeth's reach (below: weight, slope and curvature 0): its tooth
             * and ramp forces are zeros, which leave the pin's sum as it is */
            t->weight = t->slope = t->curvature = 0.0;
            ARRAY(TOOTH_GAP)[j] = 0.0;
            continue;
        }
        double angle = atan2(t->rel[1], t->rel[0]);
        double into = numpy_remainder(angle - hull[2] - P(WRAP_START), P(TWO_PI));
        engagement(c, into, &t->weight, &t->slope, &t->curvature);
        t->distance = hypot(t->rel[0], t->rel[1]);
        if (t->distance > radius + 0.08) t->weight = t->slope = t->curvature = 0.0;
        double tooth = nearbyint((angle - turned) / P(TOOTH_SPACING));
        t->slot_angle = turned + tooth * P(TOOTH_SPACING);
        double radial[2] = {cos(t->slot_angle), sin(t->slot_angle)};
        for (int k = 0; k < 2; k++) t->slot[k] = centre[k] + radius * radial[k];
        t->slot_v[0] = centre_v[0] + -rate * (radius * radial[1]);
        t->slot_v[1] = centre_v[1] + rate * (radius * radial[0]);
        for (int k = 0; k < 2; k++) {
            t->gap[k] = t->slot[k] - pin[k];
            t->pull[k] = stiffness * t->gap[k] + damping * (t->slot_v[k] - pin_v[k]);
            t->tooth_force[k] = t->weight * t->pull[k];
        }
        /* the engagement is the potential w k |gap|^2 / 2: besides the pull, minus its
         * gradient by the pin's angle */
        t->stored = 0.5 * stiffness * (t->gap[0] * t->gap[0] + t->gap[1] * t->gap[1]);
        double squared = t->distance * t->distance;
        t->by_angle[0] = -t->rel[1] / squared;
        t->by_angle[1] = t->rel[0] / squared;
        double ramp_force[2] = {-(t->stored * t->slope) * t->by_angle[0],
                                -(t->stored * t->slope) * t->by_angle[1]};
        for (int k = 0; k < 2; k++) c->pin[2 * j + k] += t->tooth_force[k] + ramp_force[k];
        ARRAY(TOOTH_GAP)[j] = t->weight > 0 ? hypot(t->gap[0], t->gap[1]) : 0.0;
    }
    /* on the hull: the tooth forces at the tooth spaces, the ramp forces at the pins (w
     * turns with the hull, not the teeth) */
    int on = 0;
    for (int j = 0; j < c->links; j++)
        if (teeth[j].weight > 0.0) {
            for (int k = 0; k < 2; k++) {
                forces[2 * on + k] = -teeth[j].tooth_force[k];
                points[2 * on + k] = teeth[j].slot[k];
            }
            on++;
        }
    on_body(c, 0, points, 2, forces, on);
    on = 0;
    for (int j = 0; j < c->links; j++)
        if (teeth[j].weight > 0.0) {
            const Tooth *t = &teeth[j];
            for (int k = 0; k < 2; k++) {
                forces[2 * on + k] = -(-(t->stored * t->slope) * t->by_angle[k]);
                points[2 * on + k] = pins[2 * j + k];
            }
            on++;
        }
    on_body(c, 0, points, 2, forces, on);
    on = 0;
    double *moment = c->scratch;
    for (int j = 0; j < c->links; j++)
        if (teeth[j].weight > 0.0) {
            const Tooth *t = &teeth[j];
            double r0 = t->slot[0] - centre[0], r1 = t->slot[1] - centre[1];
            moment[on++] = r0 * t->tooth_force[1] - r1 * t->tooth_force[0];
        }
    ARRAY(DRIVE_TORQUE)[0] = -numpy_sum(moment, on);
    if (c->forces_only) return; /* below: the springs */
    double slot_g[2][3], motion_g[2][3], pin_g[2][3];
    for (int j = 0; j < c->links; j++) {
        const Tooth *t = &teeth[j];
        if (!(t->weight > 0.0)) continue;
        double k_m[2][2] = {{stiffness * t->weight, stiffness * 0.0},
                            {stiffness * 0.0, stiffness * t->weight}};
        double c_m[2][2] = {{damping * t->weight, damping * 0.0},
                            {damping * 0.0, damping * t->weight}};
        slot_motion(c, t, slot_g, motion_g);
        add_member(pin_spring(c, j, k_m, c_m), 0, slot_g, motion_g, -1.0);
    }
    /* the ramp force's change with the gap, the pull's with w, and the ramp force's with
     * the angle (contacts._forces) */
    static const double zero[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
    for (int batch = 0; batch < 3; batch++)
        for (int j = 0; j < c->links; j++) {
            const Tooth *t = &teeth[j];
            if (t->slope == 0.0) continue;
            const double *m = t->by_angle, *r = t->rel;
            double block[2][2];
            point_g(c, 0, pins + 2 * j, pin_g);
            slot_motion(c, t, slot_g, motion_g);
            if (batch == 0) {
                for (int i = 0; i < 2; i++)
                    for (int k = 0; k < 2; k++)
                        block[i][k] = -stiffness * t->slope * m[i] * t->gap[k];
                add_member(pin_spring(c, j, block, zero), 0, pin_g, motion_g, -1.0);
            } else if (batch == 1) {
                for (int i = 0; i < 2; i++)
                    for (int k = 0; k < 2; k++)
                        block[i][k] = -t->slope * t->pull[i] * m[k];
                add_member(pin_spring(c, j, block, zero), 0, slot_g, pin_g, -1.0);
            } else {
                static const double turn[2][2] = {{0.0, -1.0}, {1.0, 0.0}};
                double squared = t->distance * t->distance;
                double e[2][2] = {{-(r[1] * r[0]), -(r[1] * r[1])}, {r[0] * r[0], r[0] * r[1]}};
                for (int i = 0; i < 2; i++)
                    for (int k = 0; k < 2; k++) {
                        double m_slope = turn[i][k] / squared
                                         - 2.0 * e[i][k] / (squared * squared);
                        block[i][k] = t->stored * (t->curvature * m[i] * m[k]
                                                   + t->slope * m_slope);
                    }
                add_member(pin_spring(c, j, block, zero), 0, pin_g, pin_g, -1.0);
            }
        }
}

/* Idler (on its crank) and support roller (on the hull): pins on a circle, radial
 * penalty contact. */
static void wheel_contact(Contacts *c, const double centre[2], const double centre_v[2],
                          double radius, int body)
{
    const double *pins = ARRAY(PINS), *pins_v = ARRAY(PINS_V);
    double *forces = c->scratch + c->links, centre_g[2][3];
    int on = 0;
    point_g(c, body, centre, centre_g);
    for (int j = 0; j < c->links; j++) {
        double rel[2] = {pins[2 * j] - centre[0], pins[2 * j + 1] - centre[1]};
        if (surely_beyond(rel[0], rel[1], radius)) continue; /* no depth: no force */
        double distance = hypot(rel[0], rel[1]);
        double normal[2] = {rel[0] / distance, rel[1] / distance};
        double closing = -((pins_v[2 * j] - centre_v[0]) * normal[0]
                           + (pins_v[2 * j + 1] - centre_v[1]) * normal[1]);
        double k, damping, k_m[2][2], c_m[2][2];
        double force = penalty_force(c, radius - distance, closing, P(WHEEL_STIFFNESS),
                                     P(WHEEL_DAMPING), &k, &damping);
        if (!(force > 0.0)) continue;
        for (int i = 0; i < 2; i++) {
            double pushed = force * normal[i];
            c->pin[2 * j + i] += pushed;
            forces[2 * on + i] = -pushed;
        }
        on++;
        if (c->forces_only) continue;
        normal_matrices(k, damping, normal, k_m, c_m);
        add_member(pin_spring(c, j, k_m, c_m), body, centre_g, centre_g, -1.0);
    }
    on_body(c, body, centre, 0, forces, on);
}

static void damper(Contacts *c, int body, const double *point, double damping)
{
    static const double zero[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
    double g[2][3], c_m[2][2] = {{damping, 0.0}, {0.0, damping}};
    point_g(c, body, point, g);
    add_member(new_spring(c, zero, c_m), body, g, g, 1.0);
}

/* To rest while settling: damping of every body's velocity (settle_damping.py): the hull's
 * translation and pitch, each arm at its wheel's centre (the force there and its moment),
 * each link at its seats. */
static void settle_damping(Contacts *c, double *seat)
{
    const double *hull_v = ARRAY(RATES), *seats_v = ARRAY(SEATS_V);
    for (int i = 0; i < 4 * c->links; i++) seat[i] -= P(SETTLE_SEAT) * seats_v[i];
    double *hull = c->bodies_force;
    hull[0] -= P(SETTLE_HULL_X) * hull_v[0];
    hull[1] -= P(SETTLE_HULL_Y) * hull_v[1];
    hull[2] -= P(SETTLE_HULL_PITCH) * hull_v[2];
    static const double zero[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
    static const double pitch_g[2][3] = {{0.0, 0.0, 1.0}, {0.0, 0.0, 0.0}};
    double g[2][3], c_m[2][2] = {{P(SETTLE_HULL_X), 0.0}, {0.0, P(SETTLE_HULL_Y)}};
    point_g(c, 0, ARRAY(STATE), g);
    add_member(new_spring(c, zero, c_m), 0, g, g, 1.0);
    double pitch_m[2][2] = {{P(SETTLE_HULL_PITCH), 0.0}, {0.0, 0.0}};
    add_member(new_spring(c, zero, pitch_m), 0, pitch_g, pitch_g, 1.0);
    for (int w = 0; w < c->wheels; w++) {
        const double *wheel = ARRAY(WHEELS) + 2 * w, *arm = ARRAY(STATE) + 3 * (1 + w);
        double force[2] = {-P(SETTLE_ARM) * ARRAY(WHEELS_V)[2 * w],
                           -P(SETTLE_ARM) * ARRAY(WHEELS_V)[2 * w + 1]};
        double r0 = wheel[0] - arm[0], r1 = wheel[1] - arm[1];
        double *b = c->bodies_force + 3 * (1 + w);
        b[0] += force[0];
        b[1] += force[1];
        b[2] += r0 * force[1] - r1 * force[0];
    }
    for (int w = 0; w < c->wheels; w++)
        damper(c, 1 + w, ARRAY(WHEELS) + 2 * w, P(SETTLE_ARM));
    for (int i = 0; i < c->links; i++)
        for (int s = 0; s < 2; s++)
            damper(c, c->link0 + i, ARRAY(SEATS) + 4 * i + 2 * s, P(SETTLE_SEAT));
}

/* The forces, once ARRAY(LOADS), ARRAY(SLOPES) (the tyres' loads at the compressions)
 * are set, and ARRAY(GROUND) (the course's height under each pin) where the course is
 * given, not evaluated here (contacts_course.c). */
CONTACTS_EXPORT void contacts_forces(Contacts *c, int settling)
{
    contacts_course_heights(c);
    const double *state = ARRAY(STATE), *seats = ARRAY(SEATS);
    int size = 3 * c->bodies;
    memset(c->pin, 0, sizeof(double) * 2 * c->links);
    memset(c->bodies_force, 0, sizeof(double) * size);
    memset(c->tyres, 0, sizeof(double) * size);
    c->springs = 0;
    ground(c);
    sprocket(c);
    const double *hull = state, *hull_v = ARRAY(RATES);
    double cs = cos(hull[2]), sn = sin(hull[2]);
    double roller[2] = {hull[0] + (cs * P(ROLLER_X) - sn * P(ROLLER_Y)),
                        hull[1] + (sn * P(ROLLER_X) + cs * P(ROLLER_Y))};
    double roller_v[2] = {hull_v[0] + -hull_v[2] * (roller[1] - hull[1]),
                          hull_v[1] + hull_v[2] * (roller[0] - hull[0])};
    int idler = c->link0 - 1;
    wheel_contact(c, state + 3 * idler, ARRAY(RATES) + 3 * idler, P(IDLER_PIN_RADIUS), idler);
    wheel_contact(c, roller, roller_v, P(ROLLER_PIN_RADIUS), 0);
    /* tyres: minus the load times the compression's gradient, shared by weight */
    for (int w = 0; w < c->wheels; w++)
        ARRAY(TYRE_FORCE)[w] = c->in_contact[w] ? ARRAY(LOADS)[w] : 0.0;
    for (int i = 0; i < c->pairs; i++) {
        double share = -(ARRAY(TYRE_FORCE)[c->pair_wheel[i]] * c->pair_weight[i]);
        for (int k = 0; k < 12; k++)
            c->tyres[c->pair_coordinate[12 * i + k]] += share * c->pair_gradient[12 * i + k];
    }
    /* the pins' forces on the seats of the links either side, half each */
    double *seat = c->scratch + c->links; /* links x 2 seats x 2 */
    for (int j = 0; j < c->links; j++)
        for (int k = 0; k < 2; k++) {
            seat[4 * j + k] = 0.5 * c->pin[2 * j + k];
            seat[4 * j + 2 + k] = 0.5 * c->pin[2 * ((j + 1) % c->links) + k];
        }
    if (settling) settle_damping(c, seat);
    for (int i = 0; i < c->links; i++) {
        double *b = c->bodies_force + 3 * (c->link0 + i);
        const double *position = state + 3 * (c->link0 + i), *s = seat + 4 * i;
        double r00 = seats[4 * i] - position[0], r01 = seats[4 * i + 1] - position[1];
        double r10 = seats[4 * i + 2] - position[0], r11 = seats[4 * i + 3] - position[1];
        b[0] += s[0] + s[2];
        b[1] += s[1] + s[3];
        b[2] += r00 * s[1] - r01 * s[0] + r10 * s[3] - r11 * s[2];
    }
    for (int i = 0; i < size; i++) ARRAY(GENERALIZED)[i] = c->bodies_force[i] + c->tyres[i];
}
