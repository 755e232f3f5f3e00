/* The own host's work after a pass's solve in one call (own_host.py, OwnHost._pass_end):
 * the contacts at the solution taken from the system's evaluation there
 * (contacts_kernel.py's contacts_adopt), the step check (step_check.c's two parts) and the
 * coupling's deflections into the bank's input array (deflections.c), each through its
 * own library's function, whose address the host gives: the same code as the host's calls
 * of each one by one, which stay where a part is not compiled. */
#if defined(_WIN32)
#define OWN_PASS_EXPORT __declspec(dllexport)
#else
#define OWN_PASS_EXPORT __attribute__((visibility("default")))
#endif

typedef int (*adopt_fn)(void *contacts, const void *evaluated, const double *q,
                        const double *v, const int *index);
typedef int (*links_fn)(const void *layout, double h, const double *q1, const double *q0,
                        const double *v0, double *found);
typedef int (*check_contacts_fn)(const void *layout, double h, const double *compression1,
                                 const double *gap1, const double *compression0,
                                 const double *rate0, const double *gap0, double *found);
typedef void (*deflections_fn)(const void *layout, const double *q, const double *compression,
                               double *deflection);

/* own_host.py's _Pass */
typedef struct {
    adopt_fn adopt;
    void *contacts;
    const void *evaluated;
    const int *index;
    links_fn links;
    check_contacts_fn check_contacts;
    const void *check; /* the step check's layout; NULL: no step check */
    const double *compression, *gap; /* the contacts' kernel's */
    const double *start_compression, *start_rate, *start_gap;
    deflections_fn deflections;
    const void *deflections_layout;
    double *deflection;
    double found[3];
} OwnPass;

OWN_PASS_EXPORT int own_pass_layout(void) { return (int)sizeof(OwnPass); }

/* -1: the contacts' evaluation not taken (the host does it all one by one); else what the
 * step check found (step_check.c's enum: 0 nothing, the deflections written; else found[]
 * says where); `started`: the step check has the start's contacts */
OWN_PASS_EXPORT int own_pass_end(OwnPass *p, double h, const double *q1, const double *v1,
                                 const double *q0, const double *v0, int started)
{
    if (!p->adopt(p->contacts, p->evaluated, q1, v1, p->index))
        return -1;
    if (p->check) {
        int kind = p->links(p->check, h, q1, q0, v0, p->found);
        if (kind)
            return kind;
        if (started) {
            kind = p->check_contacts(p->check, h, p->compression, p->gap, p->start_compression,
                                     p->start_rate, p->start_gap, p->found);
            if (kind)
                return kind;
        }
    }
    p->deflections(p->deflections_layout, q1, p->compression, p->deflection);
    return 0;
}
