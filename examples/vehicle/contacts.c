/* The vehicle's contacts (examples/vehicle/contacts.py, its numpy kernel, is the readable
 * reference and the fallback): the bodies' kinematics and the tyres' compressions
 * (contacts_kinematics), the forces once Python has read the tyres' loads and the
 * course's height (contacts_forces), the Jacobian's triplets (contacts_jacobian.c). The
 * same equations in the same order of operations as the numpy kernel, sums included
 * (numpy_sum: numpy's pairwise summation), so that the two give the same bits. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "contacts.h"

#define P(name) (c->parameter[P_##name])
#define ARRAY(name) (c->array[A_##name])
#define ARRAY_OF(kernel, name) ((kernel)->array[A_##name])

static int array_size(const Contacts *c, int index)
{
    switch (index) {
    case A_STATE: case A_RATES: case A_GENERALIZED: return 3 * c->bodies;
    case A_U: case A_N: case A_PINS: case A_PINS_V: return 2 * c->links;
    case A_SEATS: case A_SEATS_V: return 4 * c->links;
    case A_WHEELS: case A_WHEELS_V: return 2 * c->wheels;
    case A_COMPRESSION: case A_COMPRESSION_RATE: case A_LOADS: case A_SLOPES:
    case A_RATE_SLOPES: case A_TYRE_FORCE: return c->wheels;
    case A_GROUND: case A_GROUND_LOAD: case A_TOOTH_GAP: return c->links;
    case A_DRIVE_TORQUE: return 1;
    default: return 0;
    }
}

CONTACTS_EXPORT int contacts_layout(int *parameters, int *arrays)
{
    *parameters = P_COUNT;
    *arrays = A_COUNT;
    return (int)sizeof(Spring);
}

/* The own solver's system (system.c) evaluates its kernel `src` at every Newton iterate,
 * the last at the step's solution. Where src's last state is (q, v) to the bit (its
 * reference plus q at `index`, v at `index`, as system.c and contacts_kernel.py set it)
 * and its parameters are dst's, its results (every array) are copied into dst, a kernel
 * over the same contacts: 1; else 0, nothing copied. */
CONTACTS_EXPORT int contacts_adopt(Contacts *dst, const Contacts *src, const double *q,
                                   const double *v, const int *index)
{
    if (dst->bodies != src->bodies || dst->wheels != src->wheels || dst->links != src->links
        || memcmp(dst->parameter, src->parameter, sizeof dst->parameter) != 0)
        return 0;
    for (int i = 0; i < 3 * src->bodies; i++)
        if (!(ARRAY_OF(src, STATE)[i] == src->reference[i] + q[index[i]])
            || !(ARRAY_OF(src, RATES)[i] == v[index[i]]))
            return 0;
    for (int a = 0; a < A_COUNT; a++)
        memcpy(dst->array[a], src->array[a], sizeof(double) * (size_t)array_size(src, a));
    return 1;
}

CONTACTS_EXPORT void contacts_free(Contacts *c)
{
    if (!c) return;
    for (int i = 0; i < A_COUNT; i++) free(c->array[i]);
    free(c->reference); free(c->wheel_offset); free(c->pair_wheel); free(c->pair_coordinate);
    free(c->pair_weight); free(c->pair_gradient); free(c->spring); free(c->scratch);
    free(c->pin); free(c->candidate); free(c->in_contact); free(c->bodies_force);
    free(c->tyres); free(c->entry_wheel); free(c->entry_coordinate); free(c->entry_value);
    free(c->course_term); free(c->tyre_row); free(c->law_deflection);
    free(c);
}

/* wheels, links: the counts; reference (bodies x 3): the nodes' reference coordinates (the
 * hull, the arms, the idler's crank, the links); wheel_offset (wheels x 2): each wheel's
 * centre from its arm's node at zero rotation. NULL where memory runs out. */
CONTACTS_EXPORT Contacts *contacts_new(int wheels, int links, const double *reference,
                                       const double *wheel_offset)
{
    Contacts *c = calloc(1, sizeof(Contacts));
    if (!c) return NULL;
    c->wheels = wheels;
    c->links = links;
    c->link0 = 2 + wheels;
    c->bodies = c->link0 + links;
    c->course = COURSE_GIVEN;
    int ok = 1;
    for (int i = 0; i < A_COUNT; i++)
        ok &= (c->array[i] = calloc((size_t)array_size(c, i), sizeof(double))) != NULL;
    int pairs = wheels * links;
    /* ground, five of the sprocket, idler, roller per pin; the settling's dampers */
    c->spring_capacity = 8 * links + 2 + wheels + 2 * links;
    ok &= (c->reference = malloc(sizeof(double) * 3 * c->bodies)) != NULL;
    ok &= (c->wheel_offset = malloc(sizeof(double) * 2 * wheels)) != NULL;
    ok &= (c->pair_wheel = malloc(sizeof(int) * pairs)) != NULL;
    ok &= (c->pair_coordinate = malloc(sizeof(int) * 12 * pairs)) != NULL;
    ok &= (c->pair_weight = malloc(sizeof(double) * pairs)) != NULL;
    ok &= (c->pair_gradient = malloc(sizeof(double) * 12 * pairs)) != NULL;
    ok &= (c->spring = malloc(sizeof(Spring) * c->spring_capacity)) != NULL;
    ok &= (c->scratch = malloc(sizeof(double) * 8 * (links + wheels))) != NULL;
    ok &= (c->pin = malloc(sizeof(double) * 2 * links)) != NULL;
    ok &= (c->candidate = malloc(sizeof(Candidate) * pairs)) != NULL;
    ok &= (c->in_contact = malloc(sizeof(int) * wheels)) != NULL;
    ok &= (c->bodies_force = malloc(sizeof(double) * 3 * c->bodies)) != NULL;
    ok &= (c->tyres = malloc(sizeof(double) * 3 * c->bodies)) != NULL;
    int entries = 3 * wheels + 9 * pairs;
    ok &= (c->entry_wheel = malloc(sizeof(int) * entries)) != NULL;
    ok &= (c->entry_coordinate = malloc(sizeof(int) * entries)) != NULL;
    ok &= (c->entry_value = malloc(sizeof(double) * entries)) != NULL;
    if (!ok) {
        contacts_free(c);
        return NULL;
    }
    memcpy(c->reference, reference, sizeof(double) * 3 * c->bodies);
    memcpy(c->wheel_offset, wheel_offset, sizeof(double) * 2 * wheels);
    return c;
}

CONTACTS_EXPORT double *contacts_array(Contacts *c, int index, int *size)
{
    *size = array_size(c, index);
    return index == -1 ? c->parameter : c->array[index];
}

CONTACTS_EXPORT double *contacts_parameters(Contacts *c)
{
    return c->parameter;
}

/* --- numpy's order of operations ---------------------------------------------------- */

/* np.sum of a 1-d array: pairwise, eight accumulators per block of up to 128. */
double numpy_sum(const double *a, int n)
{
    if (n < 8) {
        double sum = 0.0;
        for (int i = 0; i < n; i++) sum += a[i];
        return sum;
    }
    if (n <= 128) {
        double r[8];
        int i;
        for (int j = 0; j < 8; j++) r[j] = a[j];
        for (i = 8; i < n - (n % 8); i += 8)
            for (int j = 0; j < 8; j++) r[j] += a[i + j];
        double sum = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]));
        for (; i < n; i++) sum += a[i];
        return sum;
    }
    int half = n / 2;
    half -= half % 8;
    return numpy_sum(a, half) + numpy_sum(a + half, n - half);
}

/* np.remainder(a, b) for b > 0: the result takes the divisor's sign. */
double numpy_remainder(double a, double b)
{
    double mod = fmod(a, b);
    if (mod != 0.0) {
        if ((b < 0) != (mod < 0)) mod += b;
    } else {
        mod = copysign(0.0, b);
    }
    return mod;
}

static double smoothstep(double x)
{
    x = x < 0.0 ? 0.0 : (x > 1.0 ? 1.0 : x);
    return x * x * (3.0 - 2.0 * x);
}

/* The smoothstep and its first and second derivatives. */
void smoothstep_derivatives(double x, double *value, double *slope, double *curvature)
{
    int inside = x > 0.0 && x < 1.0;
    *value = smoothstep(x);
    *slope = inside ? 6.0 * x * (1.0 - x) : 0.0;
    *curvature = inside ? 6.0 - 12.0 * x : 0.0;
}

/* A penalty contact with a smooth onset (contacts._penalty): its force and its slopes by
 * depth and by closing rate, zero where it does not push. */
double penalty_force(const Contacts *c, double depth, double closing, double stiffness,
                      double damping, double *by_depth, double *by_closing)
{
    double onset = P(CONTACT_ONSET);
    double d = depth > 0.0 ? depth : 0.0;
    double ramp = d / onset < 1.0 ? d / onset : 1.0;
    double spring = stiffness * (d < onset ? 0.5 * d * ramp : d - 0.5 * onset);
    double force = spring + damping * ramp * closing;
    int touching = force > 0.0;
    *by_depth = touching ? stiffness * ramp : 0.0;
    *by_closing = touching ? damping * ramp : 0.0;
    return touching ? force : 0.0;
}

/* --- kinematics ---------------------------------------------------------------------- */

static void bodies_kinematics(Contacts *c)
{
    double half = 0.5 * P(LINK_PITCH);
    const double *state = ARRAY(STATE), *rates = ARRAY(RATES);
    double *u = ARRAY(U), *n = ARRAY(N), *seats = ARRAY(SEATS), *seats_v = ARRAY(SEATS_V);
    for (int i = 0; i < c->links; i++) {
        const double *link = state + 3 * (c->link0 + i), *link_v = rates + 3 * (c->link0 + i);
        u[2 * i] = cos(link[2]);
        u[2 * i + 1] = sin(link[2]);
        n[2 * i] = -u[2 * i + 1];
        n[2 * i + 1] = u[2 * i];
        double hu0 = half * u[2 * i], hu1 = half * u[2 * i + 1];
        double seat_v0 = -link_v[2] * hu1, seat_v1 = link_v[2] * hu0;
        double *seat = seats + 4 * i, *seat_v = seats_v + 4 * i;
        seat[0] = link[0] - hu0;
        seat[1] = link[1] - hu1;
        seat[2] = link[0] + hu0;
        seat[3] = link[1] + hu1;
        seat_v[0] = link_v[0] - seat_v0;
        seat_v[1] = link_v[1] - seat_v1;
        seat_v[2] = link_v[0] + seat_v0;
        seat_v[3] = link_v[1] + seat_v1;
    }
    /* pin j: between link j - 1's front seat and link j's rear seat */
    for (int j = 0; j < c->links; j++) {
        int behind = (j + c->links - 1) % c->links;
        for (int k = 0; k < 2; k++) {
            ARRAY(PINS)[2 * j + k] = 0.5 * (seats[4 * behind + 2 + k] + seats[4 * j + k]);
            ARRAY(PINS_V)[2 * j + k] = 0.5 * (seats_v[4 * behind + 2 + k] + seats_v[4 * j + k]);
        }
    }
    for (int w = 0; w < c->wheels; w++) {
        const double *arm = state + 3 * (1 + w), *arm_v = rates + 3 * (1 + w);
        const double *offset = c->wheel_offset + 2 * w;
        double cs = cos(arm[2]), sn = sin(arm[2]);
        double turned0 = cs * offset[0] - sn * offset[1], turned1 = sn * offset[0] + cs * offset[1];
        ARRAY(WHEELS)[2 * w] = arm[0] + turned0;
        ARRAY(WHEELS)[2 * w + 1] = arm[1] + turned1;
        ARRAY(WHEELS_V)[2 * w] = arm_v[0] + -arm_v[2] * turned1;
        ARRAY(WHEELS_V)[2 * w + 1] = arm_v[1] + arm_v[2] * turned0;
    }
}

/* One end of a link's window: its joint's bisector (normal m, |u_a + u_b| = size), the
 * wheel's offset from the joint's pin, the smoothstep's argument. */
static void window_end(const Contacts *c, const double *wheel, int a, int b, double sign,
                       int pin, End *end)
{
    const double *u = ARRAY(U), *pins = ARRAY(PINS);
    double mean0 = u[2 * a] + u[2 * b], mean1 = u[2 * a + 1] + u[2 * b + 1];
    end->a = a;
    end->b = b;
    end->sign = sign;
    end->size = hypot(mean0, mean1);
    end->m[0] = mean0 / end->size;
    end->m[1] = mean1 / end->size;
    end->offset[0] = wheel[0] - pins[2 * pin];
    end->offset[1] = wheel[1] - pins[2 * pin + 1];
    end->x = sign * (end->offset[0] * end->m[0] + end->offset[1] * end->m[1]) / P(HANDOVER) + 0.5;
}

/* The gradient of a kept pair's term by (x, y, angle) of the arm and of the links behind,
 * beneath and ahead (contacts._tyre_kinematics). */
static void pair_gradient(const Contacts *c, const Candidate *pair, double gradient[4][3])
{
    const double *n = ARRAY(N), *state = ARRAY(STATE);
    double half = 0.5 * P(LINK_PITCH);
    memset(gradient, 0, sizeof(double) * 12);
    double by_wheel[2] = {-n[2 * pair->link], -n[2 * pair->link + 1]};
    gradient[2][0] = n[2 * pair->link];
    gradient[2][1] = n[2 * pair->link + 1];
    gradient[2][2] = pair->along;
    for (int e = 0; e < 2; e++) {
        const End *end = &pair->end[e];
        double value, slope, curvature;
        smoothstep_derivatives(end->x, &value, &slope, &curvature);
        double scale = end->sign * P(TYRE_BLEND) * slope / (value > 1e-300 ? value : 1e-300)
                       / P(HANDOVER);
        by_wheel[0] = by_wheel[0] + scale * end->m[0];
        by_wheel[1] = by_wheel[1] + scale * end->m[1];
        double along = end->offset[0] * end->m[0] + end->offset[1] * end->m[1];
        double across0 = end->offset[0] - along * end->m[0];
        double across1 = end->offset[1] - along * end->m[1];
        int slots[2] = {1 + e, 2 + e}, bodies[2] = {end->a, end->b};
        double seats[2] = {half, -half};
        for (int s = 0; s < 2; s++) {
            double *g = gradient[slots[s]];
            const double *nb = n + 2 * bodies[s];
            g[0] -= 0.5 * scale * end->m[0];
            g[1] -= 0.5 * scale * end->m[1];
            double turn = (-0.5 * seats[s] * (end->m[0] * nb[0] + end->m[1] * nb[1])
                           + (across0 * nb[0] + across1 * nb[1]) / end->size);
            g[2] += scale * turn;
        }
    }
    const double *wheel = ARRAY(WHEELS) + 2 * pair->wheel;
    const double *arm = state + 3 * (1 + pair->wheel);
    double arm0 = wheel[0] - arm[0], arm1 = wheel[1] - arm[1];
    gradient[0][0] = by_wheel[0];
    gradient[0][1] = by_wheel[1];
    gradient[0][2] = -by_wheel[0] * arm1 + by_wheel[1] * arm0;
}

/* Per wheel the tyre's compression, a smooth maximum of the overlaps of the links beneath
 * it, each faded in and out over HANDOVER about its joints, and its rate; per kept (wheel,
 * link) pair its weight and gradient (contacts._tyre_kinematics). */
static void tyre_kinematics(Contacts *c)
{
    const double *wheels = ARRAY(WHEELS), *u = ARRAY(U), *n = ARRAY(N), *state = ARRAY(STATE);
    int links = c->links, count = 0;
    double blend = P(TYRE_BLEND);
    for (int w = 0; w < c->wheels; w++) {
        for (int l = 0; l < links; l++) {
            const double *link = state + 3 * (c->link0 + l);
            double r0 = wheels[2 * w] - link[0], r1 = wheels[2 * w + 1] - link[1];
            double along = r0 * u[2 * l] + r1 * u[2 * l + 1];
            double height = r0 * n[2 * l] + r1 * n[2 * l + 1];
            if (!(fabs(along) < P(LINK_PITCH) && height > 0.0 && height < 2 * P(WHEEL_RADIUS)))
                continue;
            Candidate *pair = &c->candidate[count++];
            int behind = (l + links - 1) % links, ahead = (l + 1) % links;
            pair->wheel = w;
            pair->link = l;
            pair->along = along;
            window_end(c, wheels + 2 * w, behind, l, 1.0, l, &pair->end[0]);
            window_end(c, wheels + 2 * w, l, ahead, -1.0, ahead, &pair->end[1]);
            pair->window = smoothstep(pair->end[0].x) * smoothstep(pair->end[1].x);
            pair->overlap = P(WHEEL_RADIUS) - (height - P(LINK_INNER));
        }
    }
    double *top = c->scratch, *total = c->scratch + c->wheels;
    for (int w = 0; w < c->wheels; w++) {
        top[w] = -INFINITY;
        total[w] = 0.0;
    }
    for (int i = 0; i < count; i++) {
        const Candidate *pair = &c->candidate[i];
        if (pair->window > 0.0 && pair->overlap > top[pair->wheel])
            top[pair->wheel] = pair->overlap;
    }
    /* a link whose overlap is 40 blend widths below the largest weighs e^-40: left out */
    int kept = 0;
    for (int i = 0; i < count; i++) {
        Candidate *pair = &c->candidate[i];
        if (pair->window > 0.0 && pair->overlap > top[pair->wheel] - 40 * blend) {
            pair->term = pair->window * exp((pair->overlap - top[pair->wheel]) / blend);
            total[pair->wheel] += pair->term;
            c->candidate[kept++] = *pair;
        }
    }
    c->pairs = kept;
    for (int w = 0; w < c->wheels; w++) {
        c->in_contact[w] = total[w] > 0.0;
        ARRAY(COMPRESSION)[w] = c->in_contact[w] ? top[w] + blend * log(total[w]) : -INFINITY;
        ARRAY(COMPRESSION_RATE)[w] = 0.0;
    }
    for (int i = 0; i < kept; i++) {
        const Candidate *pair = &c->candidate[i];
        int w = pair->wheel, l = pair->link;
        int bodies[4] = {1 + w, c->link0 + (l + links - 1) % links, c->link0 + l,
                         c->link0 + (l + 1) % links};
        double gradient[4][3], product[12];
        pair_gradient(c, pair, gradient);
        c->pair_wheel[i] = w;
        c->pair_weight[i] = pair->term / (c->in_contact[w] ? total[w] : 1.0);
        for (int s = 0; s < 4; s++)
            for (int k = 0; k < 3; k++) {
                c->pair_coordinate[12 * i + 3 * s + k] = 3 * bodies[s] + k;
                c->pair_gradient[12 * i + 3 * s + k] = gradient[s][k];
                product[3 * s + k] = gradient[s][k] * ARRAY(RATES)[3 * bodies[s] + k];
            }
        /* the compression's rate: its gradient times the velocities, the windows' fading
         * included */
        ARRAY(COMPRESSION_RATE)[w] += c->pair_weight[i] * numpy_sum(product, 12);
    }
}

CONTACTS_EXPORT void contacts_kinematics(Contacts *c)
{
    bodies_kinematics(c);
    tyre_kinematics(c);
}

/* Where the bank's laws give the tyres' loads: bank.c's bank_law_loads (`law_loads`) and
 * the bank (`bank`, `size` instances), `rows` each wheel's two tyres' rows in it (wheels
 * x 2). NULL: the loads are given (Python writes ARRAY(LOADS), ARRAY(SLOPES),
 * ARRAY(RATE_SLOPES)). 0, or -1 where memory runs out (the loads are then given). */
CONTACTS_EXPORT int contacts_set_tyre_laws(Contacts *c, LawLoads law_loads, const void *bank,
                                           int size, const int *rows)
{
    free(c->tyre_row);
    free(c->law_deflection);
    c->tyre_row = NULL;
    c->law_deflection = NULL;
    c->law_loads = NULL;
    if (!law_loads) return 0;
    c->tyre_row = malloc(sizeof(int) * 2 * c->wheels);
    c->law_deflection = calloc(3 * (size_t)size, sizeof(double)); /* the others stay 0 */
    if (!c->tyre_row || !c->law_deflection) return -1;
    memcpy(c->tyre_row, rows, sizeof(int) * 2 * c->wheels);
    c->law_load = c->law_deflection + size;
    c->law_slope = c->law_deflection + 2 * size;
    c->bank = bank;
    c->law_loads = law_loads;
    return 0;
}

/* model.Vehicle.tyre_loads on the compiled path, in two halves about the bank's laws'
 * call: each wheel's two tyres at its compression (-HORN_HEIGHT out of contact) into
 * `deflection` (the bank's rows)... */
CONTACTS_EXPORT void contacts_tyre_deflections(const Contacts *c, double *deflection)
{
    for (int w = 0; w < c->wheels; w++) {
        double x = ARRAY(COMPRESSION)[w];
        x = isfinite(x) ? x : -P(HORN_HEIGHT);
        deflection[c->tyre_row[2 * w]] = deflection[c->tyre_row[2 * w + 1]] = x;
    }
}

/* ...and their loads and slopes (the bank's rows) summed as numpy sums a row; the bank's
 * laws are rate-free (no slope by the rate) */
CONTACTS_EXPORT void contacts_tyre_loads(Contacts *c, const double *load, const double *slope)
{
    for (int w = 0; w < c->wheels; w++) {
        const int *row = c->tyre_row + 2 * w;
        double loads[2] = {load[row[0]], load[row[1]]};
        double slopes[2] = {slope[row[0]], slope[row[1]]};
        ARRAY(LOADS)[w] = numpy_sum(loads, 2);
        ARRAY(SLOPES)[w] = numpy_sum(slopes, 2);
        ARRAY(RATE_SLOPES)[w] = 0.0;
    }
}

static void tyre_loads(Contacts *c)
{
    contacts_tyre_deflections(c, c->law_deflection);
    c->law_loads(c->bank, c->law_deflection, c->law_load, c->law_slope);
    contacts_tyre_loads(c, c->law_load, c->law_slope);
}

/* One evaluation in one call, where the kernel has the tyres' laws and the course:
 * the kinematics, the tyres' loads, the forces. -1 where it lacks the laws. */
CONTACTS_EXPORT int contacts_evaluate(Contacts *c, int settling)
{
    if (!c->law_loads) return -1;
    contacts_kinematics(c);
    tyre_loads(c);
    contacts_forces(c, settling);
    return 0;
}
