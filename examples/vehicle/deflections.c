/* The coupling's deflections of the vehicle on the compiled path in one call
 * (compiled.py, CompiledPath.deflections): every bank instance's deflection from the
 * system's coordinates q and the tyres' compressions of the contacts' last evaluation.
 *
 * A tyre's deflection is its wheel's compression (-out_of_contact where the wheel is out
 * of contact: compression -inf); a damper's the hull's rotation less its arm's; a radial
 * bush's the distance between its pin seats and a torsion bush's the links' relative angle
 * with its offset, as joints.c's joints_kinematics computes them (the joints' kernel, the
 * same bits as joints.py's numpy kernel). libc and libm only. */
#include <math.h>

#if defined(_WIN32)
#define DEFLECTIONS_EXPORT __declspec(dllexport)
#else
#define DEFLECTIONS_EXPORT __attribute__((visibility("default")))
#endif

void joints_kinematics(int n, double half, const double *reference, const double *q,
                       const double *qd, const double *offset, double *link, double *joint);

/* compiled.py's _Deflections: the rows of the bank's instances and the joints' kernel's
 * arrays (links' q, rates left at zero, link, joint: scratch) */
typedef struct {
    int links, wheels, tyres_per_wheel, dampers;
    double half, out_of_contact;
    int hull_rotation;
    const int *link_index; /* links x 3, the links' coordinates in q */
    const int *tyre_rows, *arm_rotation, *damper_rows, *radial_rows, *torsion_rows;
    const double *reference, *offset, *still;
    double *q_links, *link, *joint;
} Deflections;

DEFLECTIONS_EXPORT int deflections_layout(void) { return (int)sizeof(Deflections); }

DEFLECTIONS_EXPORT void deflections(const Deflections *d, const double *q,
                                    const double *compression, double *deflection)
{
    for (int w = 0; w < d->wheels; w++) {
        double x = compression[w] > -INFINITY ? compression[w] : -d->out_of_contact;
        for (int k = 0; k < d->tyres_per_wheel; k++)
            deflection[d->tyre_rows[d->tyres_per_wheel * w + k]] = x;
    }
    for (int i = 0; i < d->dampers; i++)
        deflection[d->damper_rows[i]] = q[d->hull_rotation] - q[d->arm_rotation[i]];
    for (int k = 0; k < 3 * d->links; k++)
        d->q_links[k] = q[d->link_index[k]];
    joints_kinematics(d->links, d->half, d->reference, d->q_links, d->still, d->offset,
                      d->link, d->joint);
    for (int j = 0; j < d->links; j++) {
        deflection[d->radial_rows[j]] = d->joint[8 * j + 2];
        deflection[d->torsion_rows[j]] = d->joint[8 * j + 6];
    }
}
