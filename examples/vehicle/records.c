/* A record of the vehicle's run in one call (outputs.py, Records): the values an accepted
 * step keeps copied from where the run holds them (the contacts' kernel's memory, the
 * bank's arrays) into a row of the records, one after the other. libc only. */
#if defined(_WIN32)
#define RECORDS_EXPORT __declspec(dllexport)
#else
#define RECORDS_EXPORT __attribute__((visibility("default")))
#endif

/* outputs.py's _Source: `count` values of `data`, at `index` where it is given, else
 * every `stride`-th */
typedef struct {
    const double *data;
    const long *index;
    int count, stride;
} RecordSource;

RECORDS_EXPORT int records_layout(void) { return (int)sizeof(RecordSource); }

RECORDS_EXPORT void records_gather(int sources, const RecordSource *source, double *row)
{
    for (int s = 0; s < sources; s++, source++)
        for (int k = 0; k < source->count; k++)
            *row++ = source->index ? source->data[source->index[k]]
                                   : source->data[(long)k * source->stride];
}
