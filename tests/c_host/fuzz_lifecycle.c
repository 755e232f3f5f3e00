/*
 * The hostile host's instances over their lives (fuzz_host.c runs them): malformed
 * fmi2Instantiate arguments, memory over instantiate/free cycles and logged messages,
 * instances in threads, threads calling one instance, the Python flavour's thread states,
 * and a library unloaded under a thread.
 */

#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_host.h"

/* ---- fmi2Instantiate ---- */

int run_instantiate(const char *other_uri, int offers_model_exchange) {
    fmi2CallbackFunctions no_logger = {NULL, calloc, free, NULL, NULL};
    char missing[4096];
    snprintf(missing, sizeof missing, "%s/no-such-folder", resource_uri);
    /* The cases with no FMI 3.0 form (no callbacks, an interface type FMI 3.0 has no call
       for) are skipped on an FMI 3.0 binary. */
    struct { const char *what, *name; fmi2Type type; const char *guid, *uri;
             const fmi2CallbackFunctions *callbacks; } cases[] = {
        {"NULL instance name", NULL, fmi2CoSimulation, guid, resource_uri, &quiet},
        {"empty instance name", "", fmi2CoSimulation, guid, resource_uri, &quiet},
        {"NULL callbacks", "x", fmi2CoSimulation, guid, resource_uri, NULL},
        {"NULL logger", "x", fmi2CoSimulation, "wrong", resource_uri, &no_logger},
        {"model exchange (not offered)", "x", offers_model_exchange ? (fmi2Type)7 : fmi2ModelExchange,
         guid, resource_uri, &quiet},
        {"interface type 7", "x", (fmi2Type)7, guid, resource_uri, &quiet},
        {"NULL GUID", "x", fmi2CoSimulation, NULL, resource_uri, &quiet},
        {"wrong GUID", "x", fmi2CoSimulation, "{00000000-0000-0000-0000-000000000000}", resource_uri, &quiet},
        {"NULL resources", "x", fmi2CoSimulation, guid, NULL, &quiet},
        {"empty resources", "x", fmi2CoSimulation, guid, "", &quiet},
        {"not a URI", "x", fmi2CoSimulation, guid, "/tmp", &quiet},
        {"http URI", "x", fmi2CoSimulation, guid, "http://example.com/resources", &quiet},
        {"remote file URI", "x", fmi2CoSimulation, guid, "file://host/resources", &quiet},
        {"bad escape", "x", fmi2CoSimulation, guid, "file:///tmp/%zz", &quiet},
        {"missing folder", "x", fmi2CoSimulation, guid, missing, &quiet},
        {"folder without resources", "x", fmi2CoSimulation, guid, "file:///tmp", &quiet},
        {"another FMU's resources", "x", fmi2CoSimulation, guid, other_uri, &quiet},
    };
    int n = (int)(sizeof cases / sizeof *cases), refused = 0, skipped = 0;
    for (int i = 0; i < n; i++) {
        if (fmi3_binary && (cases[i].callbacks == NULL ||
                            (cases[i].type != fmi2CoSimulation &&
                             cases[i].type != fmi2ModelExchange))) {
            skipped++;
            continue;
        }
        alarm(CALL_SECONDS);
        fmi2Component c = fmi.Instantiate(cases[i].name, cases[i].type, cases[i].guid, cases[i].uri,
                                          cases[i].callbacks, fmi2False, fmi2True);
        alarm(0);
        if (c) { fail("instantiate accepted: %s", cases[i].what); fmi.FreeInstance(c); }
        else refused++;
    }
    fmi2Component c = instantiate("good", &quiet, fmi2False);
    if (!c || !initialize(c, 0.0, 0.0)) fail("a valid instantiate after the refused ones failed");
    if (c) fmi.FreeInstance(c);
    printf("instantiate_cases %d\ninstantiate_refused %d\n", n - skipped, refused);
    return failures ? 3 : 0;
}

/* ---- memory ---- */

static long rss_bytes(void) {
    long pages = 0, resident = 0;
    FILE *file = fopen("/proc/self/statm", "r");
    if (!file || fscanf(file, "%ld %ld", &pages, &resident) != 2) resident = -1;
    if (file) fclose(file);
    return resident * sysconf(_SC_PAGESIZE);
}

int run_cycles(long count, long n_messages) {
    long warm = count / 5 + 10;
    for (long k = 0; k < warm + count; k++) {
        static long start;
        if (k == warm) start = rss_bytes();
        fmi2Component c = instantiate("cycle", &quiet, fmi2False);
        if (!c || !initialize(c, 0.001, 0.0) || fmi.DoStep(c, 0.0, 1e-3, fmi2True) != fmi2OK) {
            fail("cycle %ld", k);
            return 3;
        }
        fmi.FreeInstance(c);
        if (k == warm + count - 1)
            printf("cycles %ld\nrss_per_cycle_bytes %.2f\n", count,
                   (double)(rss_bytes() - start) / (double)count);
    }
    fmi2Component c = instantiate("messages", &quiet, fmi2True);
    if (!c || !initialize(c, 0.0, 0.0)) { fail("instantiate"); return 3; }
    fmi2Real bad[2] = {NAN, 0.0};
    long warm_messages = n_messages / 5 + 10, start = 0;
    for (long k = 0; k < warm_messages + n_messages; k++) {
        if (k == warm_messages) start = rss_bytes();
        fmi.SetReal(c, vr_in, 2, bad);
    }
    printf("messages %ld\nrss_per_message_bytes %.2f\n", n_messages,
           (double)(rss_bytes() - start) / (double)n_messages);
    fmi.FreeInstance(c);
    return failures ? 3 : 0;
}

/* ---- threads ---- */

typedef struct { int phase; long steps; fmi2Real *out; int ok; } Job;

static void *run_job(void *argument) {
    Job *job = argument;
    char name[32];
    snprintf(name, sizeof name, "thread%d", job->phase);
    fmi2Component c = instantiate(name, &quiet, fmi2False);
    double offset = 0.0005 * job->phase;
    job->ok = c && initialize(c, offset, 0.02);
    for (long k = 0; job->ok && k < job->steps; k++) {
        double t = k * 1e-3;
        fmi2Real in[2] = {offset + 0.002 * sin(10.0 * t), 0.02 * cos(10.0 * t)};
        job->ok = fmi.SetReal(c, vr_in, 2, in) == fmi2OK &&
                  fmi.DoStep(c, t, 1e-3, fmi2True) == fmi2OK &&
                  fmi.GetReal(c, &vr_out, 1, &job->out[k]) == fmi2OK;
    }
    if (c) fmi.FreeInstance(c);
    return NULL;
}

int run_threads(int count, long steps) {
    Job *alone = calloc((size_t)count, sizeof *alone), *together = calloc((size_t)count, sizeof *together);
    pthread_t *threads = calloc((size_t)count, sizeof *threads);
    for (int i = 0; i < count; i++) {
        alone[i] = (Job){i, steps, calloc((size_t)steps, sizeof(fmi2Real)), 0};
        together[i] = (Job){i, steps, calloc((size_t)steps, sizeof(fmi2Real)), 0};
        run_job(&alone[i]);
    }
    alarm(CALL_SECONDS * 10);
    for (int i = 0; i < count; i++) pthread_create(&threads[i], NULL, run_job, &together[i]);
    for (int i = 0; i < count; i++) pthread_join(threads[i], NULL);
    alarm(0);
    int equal = 0;
    for (int i = 0; i < count; i++) {
        if (!alone[i].ok || !together[i].ok) fail("thread %d: a call failed", i);
        else if (memcmp(alone[i].out, together[i].out, (size_t)steps * sizeof(fmi2Real)) != 0)
            fail("thread %d differs from its single-threaded run", i);
        else equal++;
    }
    if (count > 1 && memcmp(alone[0].out, alone[1].out, (size_t)steps * sizeof(fmi2Real)) == 0)
        fail("the threads' inputs did not differ");
    printf("threads %d\nthreads_equal %d\n", count, equal);
    return failures ? 3 : 0;
}

/* ---- threads calling one instance ---- */

static fmi2Component shared_instance;
static long calls_per_thread;
static __thread unsigned long overlap_messages; /* refusals told to this thread */
static unsigned long good_refused, good_told, bad_ok, bad_calls, good_reads;

static void shared_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                          fmi2String category, fmi2String message, ...) {
    (void)env; (void)name; (void)status; (void)category;
    if (message && strstr(message, "another call on this instance has not returned"))
        overlap_messages++;
}

/* A call of the stepping thread: its own status, or fmi2Error with the refusal told. */
static int own_or_told(fmi2Status status, unsigned long told_before, const char *what) {
    if (status == fmi2OK) return 1;
    if (status == fmi2Error && overlap_messages > told_before) {
        good_refused++;
        good_told++;
        return 0;
    }
    fail("the stepping thread's %s gave %d%s", what, status,
         status == fmi2Error ? " without a refusal told to it" : "");
    return 0;
}

static void *stepping_thread(void *unused) {
    (void)unused;
    double time = 0.0, set[2] = {0.0, 0.0};
    for (long k = 0; k < calls_per_thread; k++) {
        double t = time;
        fmi2Real in[2] = {0.002 * sin(10.0 * t), 0.02 * cos(10.0 * t)}, back[3];
        fmi2ValueReference vrs[3] = {vr_in[0], vr_in[1], vr_out};
        unsigned long told = overlap_messages;
        if (own_or_told(fmi.SetReal(shared_instance, vr_in, 2, in), told, "fmi2SetReal"))
            memcpy(set, in, sizeof set);
        told = overlap_messages;
        if (own_or_told(fmi.DoStep(shared_instance, time, 1e-3, fmi2True), told, "fmi2DoStep"))
            time += 1e-3;
        told = overlap_messages;
        if (own_or_told(fmi.GetReal(shared_instance, vrs, 3, back), told, "fmi2GetReal")) {
            good_reads++;
            /* No other thread changes the instance: the inputs read back are the last set. */
            if (back[0] != set[0] || back[1] != set[1] || !isfinite(back[2]))
                fail("read back [%g %g %g] after setting [%g %g]", back[0], back[1], back[2],
                     set[0], set[1]);
        }
    }
    return NULL;
}

/* Calls that fail on their own: a NaN input, a negative step, an unknown reference. */
static void *failing_thread(void *unused) {
    (void)unused;
    fmi2Real nan_input[1] = {NAN}, value;
    fmi2ValueReference unknown = 0xFFFFFFF0u;
    for (long k = 0; k < calls_per_thread; k++) {
        fmi2Status s[3] = {fmi.SetReal(shared_instance, vr_in, 1, nan_input),
                           fmi.DoStep(shared_instance, 0.0, -1.0, fmi2True),
                           fmi.GetReal(shared_instance, &unknown, 1, &value)};
        for (int i = 0; i < 3; i++) {
            __atomic_add_fetch(&bad_calls, 1, __ATOMIC_RELAXED);
            if (s[i] != fmi2Error) __atomic_add_fetch(&bad_ok, 1, __ATOMIC_RELAXED);
        }
        usleep((useconds_t)(k % 4) * 10); /* pauses of 0 to 30 us: the stepping thread gets in */
    }
    return NULL;
}

int run_shared(int count, long calls) {
    static const fmi2CallbackFunctions callbacks = {shared_logger, calloc, free, NULL, NULL};
    shared_instance = instantiate("shared", &callbacks, fmi2False);
    if (!shared_instance || !initialize(shared_instance, 0.0, 0.0)) { fail("instantiate"); return 3; }
    calls_per_thread = calls;
    pthread_t threads[64];
    if (count < 2 || count > 64) { fail("2 to 64 threads"); return 3; }
    alarm(CALL_SECONDS * 10);
    pthread_create(&threads[0], NULL, stepping_thread, NULL);
    for (int i = 1; i < count; i++) pthread_create(&threads[i], NULL, failing_thread, NULL);
    for (int i = 0; i < count; i++) pthread_join(threads[i], NULL);
    alarm(0);
    if (bad_ok) fail("%lu calls that fail on their own were answered as if they had not", bad_ok);
    /* The instance still works from one thread. */
    fmi2Real out = NAN, in[2] = {0.001, 0.0}, now = 0.0;
    fmi.GetRealStatus(shared_instance, fmi2LastSuccessfulTime, &now);
    if (fmi.SetReal(shared_instance, vr_in, 2, in) != fmi2OK ||
        fmi.DoStep(shared_instance, now, 1e-3, fmi2True) > fmi2Warning ||
        fmi.GetReal(shared_instance, &vr_out, 1, &out) != fmi2OK || !isfinite(out))
        fail("the instance does not work after the threads");
    fmi.FreeInstance(shared_instance);
    printf("shared_threads %d\nshared_stepping_calls %ld\nshared_stepping_refused %lu\n"
           "shared_stepping_told %lu\nshared_stepping_reads %lu\nshared_failing_calls %lu\n"
           "shared_failing_ok %lu\n", count, 3 * calls, good_refused, good_told, good_reads,
           bad_calls, bad_ok);
    return failures ? 3 : 0;
}

/* ---- Python thread states ---- */

/* Python's C API in the process (the Python flavour's binary loaded it): a probe thread of
   its own makes a thread state, whose unique id tells how many were made before it, and
   counts the interpreter's live ones. */
static struct {
    int (*ensure)(void);
    void (*release)(int);
    void *(*get)(void);
    unsigned long long (*id)(void *);
    void *(*main_interpreter)(void);
    void *(*head)(void *);
    void *(*next)(void *);
} py;
typedef struct { unsigned long long id; long live; } Probe;

static void *probe_thread(void *result) {
    Probe *probe = result;
    int gil = py.ensure();
    probe->id = py.id(py.get());
    probe->live = 0;
    for (void *state = py.head(py.main_interpreter()); state; state = py.next(state)) probe->live++;
    py.release(gil);
    return NULL;
}

static Probe probe(void) {
    Probe result;
    pthread_t thread;
    pthread_create(&thread, NULL, probe_thread, &result);
    pthread_join(thread, NULL);
    return result;
}

static void cycles(fmi2Component c) {
    fmi2Real in[2] = {0.001, 0.0}, out;
    for (long k = 0; k < calls_per_thread; k++) {
        fmi.SetReal(c, vr_in, 2, in);
        fmi.DoStep(c, 0.0, 1e-3, fmi2True); /* refused (not the current time) after the first */
        fmi.GetReal(c, &vr_out, 1, &out);
    }
}

/* The calls, then a wait while the main thread takes the GIL: the thread then ends while
   the host holds the GIL and waits for it, which must not hang. */
static pthread_barrier_t calls_made, gil_taken;
static void *cycles_thread(void *argument) {
    cycles(argument);
    pthread_barrier_wait(&calls_made);
    pthread_barrier_wait(&gil_taken);
    return NULL;
}

int run_thread_states(long calls) {
    fmi2Component c = instantiate("states", &quiet, fmi2False);
    if (!c || !initialize(c, 0.0, 0.0)) { fail("instantiate"); return 3; }
#define PY(field, name) *(void **)&py.field = dlsym(RTLD_DEFAULT, #name);
    PY(ensure, PyGILState_Ensure) PY(release, PyGILState_Release) PY(get, PyThreadState_Get)
    PY(id, PyThreadState_GetID) PY(main_interpreter, PyInterpreterState_Main)
    PY(head, PyInterpreterState_ThreadHead) PY(next, PyThreadState_Next)
#undef PY
    if (!py.ensure || !py.release || !py.get || !py.id || !py.main_interpreter || !py.head || !py.next) {
        printf("python 0\n"); /* the native flavour */
        fmi.FreeInstance(c);
        return failures ? 3 : 0;
    }
    calls_per_thread = calls;
    alarm(CALL_SECONDS * 10);
    Probe before = probe();
    cycles(c); /* this thread */
    Probe after_calls = probe();
    pthread_t thread; /* a thread that makes the same calls and ends */
    pthread_barrier_init(&calls_made, NULL, 2);
    pthread_barrier_init(&gil_taken, NULL, 2);
    pthread_create(&thread, NULL, cycles_thread, c);
    pthread_barrier_wait(&calls_made);
    int gil = py.ensure();
    pthread_barrier_wait(&gil_taken);
    pthread_join(thread, NULL);
    py.release(gil);
    fmi2Real out;
    fmi.GetReal(c, &vr_out, 1, &out); /* the next call deletes the ended thread's state */
    Probe after_thread = probe();
    alarm(0);
    fmi.FreeInstance(c);
    /* each probe makes one state itself */
    printf("python 1\ncalls %ld\nthread_states_made_by_calls %llu\n"
           "thread_states_made_by_a_thread %llu\nlive_thread_states_before %ld\n"
           "live_thread_states_after_the_thread_ended %ld\n", 3 * calls,
           after_calls.id - before.id - 1, after_thread.id - after_calls.id - 1, after_calls.live,
           after_thread.live);
    return failures ? 3 : 0;
}

/* ---- unloading ---- */

static pthread_barrier_t unload_calls_made, unload_closed;
static void *unload_worker(void *unused) {
    (void)unused;
    fmi2Component c = instantiate("unload", &quiet, fmi2False);
    if (!c || !initialize(c, 0.001, 0.0)) fail("instantiate in the thread");
    /* Calls that log nothing: a Python FMU that logs holds its library itself (the
       adapter's way to the guard's fmu_guard_log), and then nothing unloads it. */
    fmi2Real in[2] = {0.001, 0.0}, out;
    for (int k = 0; c && k < 100; k++)
        if (fmi.SetReal(c, vr_in, 2, in) != fmi2OK || fmi.DoStep(c, k * 1e-3, 1e-3, fmi2True) != fmi2OK ||
            fmi.GetReal(c, &vr_out, 1, &out) != fmi2OK)
            fail("a call in the thread failed");
    if (c) fmi.FreeInstance(c);
    pthread_barrier_wait(&unload_calls_made);
    pthread_barrier_wait(&unload_closed); /* the library is gone: the thread now ends */
    return NULL;
}

/* A thread calls the FMU, the host closes the library, the thread ends: nothing of the
   library may run at the thread's end. Then the library is loaded again and works. */
int run_unload(const char *binary, void **library) {
    pthread_t thread;
    pthread_barrier_init(&unload_calls_made, NULL, 2);
    pthread_barrier_init(&unload_closed, NULL, 2);
    alarm(CALL_SECONDS * 10);
    pthread_create(&thread, NULL, unload_worker, NULL);
    pthread_barrier_wait(&unload_calls_made);
    dlclose(*library);
    void *still = dlopen(binary, RTLD_NOW | RTLD_NOLOAD);
    int unloaded = still == NULL;
    if (still) dlclose(still);
    pthread_barrier_wait(&unload_closed);
    pthread_join(thread, NULL);
    *library = load(binary);
    if (!*library) return 3;
    fmi2Component c = instantiate("again", &quiet, fmi2False);
    fmi2Real out = NAN;
    if (!c || !initialize(c, 0.001, 0.0) || fmi.DoStep(c, 0.0, 1e-3, fmi2True) != fmi2OK ||
        fmi.GetReal(c, &vr_out, 1, &out) != fmi2OK || !isfinite(out))
        fail("the library loaded again does not work");
    if (c) fmi.FreeInstance(c);
    alarm(0);
    printf("unloaded %d\n", unloaded);
    return failures ? 3 : 0;
}
