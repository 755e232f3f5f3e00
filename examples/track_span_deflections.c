/* The track span's deflections from the system's coordinates, in C (track_span.py loads
 * it; TrackSpan.numpy_deflections is the readable reference, and the fallback): per joint
 * the radial bush's deflection, the distance between its two pin seats, and the torsion
 * bush's, the left body's rotation minus the right one's. The same operations in the same
 * order as the numpy function, so that the two give the same bits (built with
 * -ffp-contract=off). libc and libm only.
 *
 * Bodies along the span: the sprocket (fixed, its seat at (0, 0), not turning), `nodes` - 1
 * links, then the lifting wheel (its seat at its centre). Joint j joins body j (the
 * sprocket for j = 0, else link j - 1's right end) to body j + 1 (link j's left end, or the
 * wheel). index and reference: rows x, y and angle of the links' nodes, then the wheel's
 * (3 x nodes): the node's coordinate in the system's vector, and its reference value. */
#include <math.h>
#include <stdint.h>

#if defined(_WIN32)
#define SPAN_EXPORT __declspec(dllexport)
#else
#define SPAN_EXPORT __attribute__((visibility("default")))
#endif

SPAN_EXPORT void span_deflections(int nodes, double half_pitch, const double *coordinates,
                                  const int64_t *index, const double *reference,
                                  double *deflections)
{
    const int64_t *at_x = index, *at_y = index + nodes, *at_angle = index + 2 * nodes;
    const double *x0 = reference, *y0 = reference + nodes, *angle0 = reference + 2 * nodes;
    double left_x = 0.0, left_y = 0.0, left_angle = 0.0;  /* the sprocket's seat */
    for (int j = 0; j < nodes; j++) {
        double x = x0[j] + coordinates[at_x[j]], y = y0[j] + coordinates[at_y[j]];
        double angle = angle0[j] + coordinates[at_angle[j]];
        double right_x = x, right_y = y, next_x = 0.0, next_y = 0.0;
        if (j < nodes - 1) {  /* a link: its seats half a pitch either side of its centre */
            double half_x = cos(angle) * half_pitch, half_y = sin(angle) * half_pitch;
            right_x = x - half_x;
            right_y = y - half_y;
            next_x = x + half_x;
            next_y = y + half_y;
        }
        double apart_x = right_x - left_x, apart_y = right_y - left_y;
        apart_x *= apart_x;
        apart_y *= apart_y;
        deflections[2 * j] = sqrt(apart_x + apart_y);
        deflections[2 * j + 1] = left_angle - angle;
        left_x = next_x;
        left_y = next_y;
        left_angle = angle;
    }
}
