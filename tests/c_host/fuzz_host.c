/*
 * A careless or hostile FMI 2.0 host, in C: it dlopens an FMU's linux64 binary and drives
 * it as the contract of spec section 8 says it may, checking after each call that the
 * contract held. Run by tests/test_fuzz_host.py on both flavours.
 *
 *   fuzz_host MODE BINARY RESOURCE_URI GUID VR_DEFLECTION VR_RATE VR_OUTPUT [ARGS...]
 *
 * MODE is one of
 *   random COUNT SEED        random calls with random arguments; every refused call
 *                            (fmi2Error) must leave the serialized state and the outputs
 *                            bitwise as they were
 *   instantiate OTHER_URI ME malformed fmi2Instantiate arguments: each must give NULL
 *                            (ME: 1 if the FMU offers model exchange)
 *   states OTHER_STATE SEED  truncated, bit-flipped, random, foreign and crafted states:
 *                            each must be refused; serializing stays inside its buffer
 *   dump-state FILE          write a valid serialized state to FILE (for another FMU's run)
 *   logger                   a logger that calls back into the instance
 *   cycles COUNT MESSAGES    instantiate/free cycles and logged messages, RSS measured
 *   threads COUNT STEPS      instances in threads, compared with a single-threaded run
 *   shared THREADS CALLS     threads calling one instance at once: one steps it, the others
 *                            make calls that must fail; each call is its own or refused,
 *                            and a refusal is told to the thread that made the call
 *   thread-states CALLS      (Python flavour) the Python thread states that calls from a C
 *                            host thread make, and whether a thread's goes once it has ended
 *   unload                   a thread calls the FMU and ends after the host has closed the
 *                            library; then the library is loaded again
 *
 * Every call runs under alarm(): a hang ends the process with SIGALRM. It prints
 * "key value" lines; the exit code is 0 only if every check held.
 */

#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz_host.h"
#include "state_envelope.h"

#define STATE_CAPACITY 65536

Fmi2Table fmi;
int fmi3_binary;

const char *resource_uri, *guid, *model_name;
fmi2ValueReference vr_in[2], vr_out;
unsigned long failures;

void fail(const char *format, ...) {
    va_list args;
    va_start(args, format);
    fprintf(stderr, "FAIL: ");
    vfprintf(stderr, format, args);
    fprintf(stderr, "\n");
    va_end(args);
    if (++failures > 20) exit(3);
}

/* ---- loggers ---- */

static volatile int messages_seen;
static void quiet_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                         fmi2String category, fmi2String message, ...) {
    (void)env; (void)name; (void)status; (void)category;
    /* A printf-like host: formats the message with its (absent) arguments. */
    char text[1024];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "", args);
    va_end(args);
    messages_seen++;
}

static fmi2Component reentrant_target;
static unsigned long nested_calls, nested_accepted;
static void reentrant_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                             fmi2String category, fmi2String message, ...) {
    quiet_logger(env, name, status, category, message);
    fmi2Component c = reentrant_target;
    if (c == NULL) return;
    fmi2Real value = 0, bad = NAN;
    fmi2FMUstate state = NULL;
    fmi2Status s[5] = {fmi.GetReal(c, &vr_out, 1, &value), fmi.SetReal(c, vr_in, 1, &bad),
                       fmi.DoStep(c, 0.0, 1e-3, fmi2True), fmi.GetFMUstate(c, &state),
                       fmi.Terminate(c)};
    fmi.FreeInstance(c); /* must be ignored while the instance is inside a call */
    for (int i = 0; i < 5; i++) {
        nested_calls++;
        if (s[i] != fmi2Error) nested_accepted++;
    }
}

fmi2CallbackFunctions quiet = {quiet_logger, calloc, free, NULL, NULL};
static fmi2CallbackFunctions reentrant = {reentrant_logger, calloc, free, NULL, NULL};

/* ---- helpers ---- */

static uint64_t rng_state;
static uint64_t next_random(void) { /* splitmix64: the same sequence on every platform */
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static unsigned below(unsigned n) { return (unsigned)(next_random() % n); }
static double uniform(void) { return (next_random() >> 11) * 0x1.0p-53; }

static double random_real(void) {
    static const double specials[] = {0.0, -0.0, 1.0, -1.0, 1e-3, 0.5, 1e300, -1e300, 1e-310,
                                      -1e-310, 1e308, 5e-324};
    switch (below(8)) {
    case 0: return NAN;
    case 1: return below(2) ? INFINITY : -INFINITY;
    case 2: return specials[below(sizeof specials / sizeof *specials)];
    case 3: { uint64_t bits = next_random(); double d; memcpy(&d, &bits, sizeof d); return d; }
    default: return (uniform() - 0.5) * pow(10.0, (double)below(7) - 3.0);
    }
}

static fmi2ValueReference random_vr(void) {
    static const fmi2ValueReference specials[] = {0x7FFFFFFFu, 0x80000000u, 0xFFFFFFFFu,
                                                  0xFFFFFFFEu, 1000u};
    switch (below(4)) {
    case 0: return below(2) ? vr_in[below(2)] : vr_out;
    case 1: return specials[below(5)];
    default: return below(24);
    }
}

fmi2Component instantiate(const char *name, const fmi2CallbackFunctions *callbacks,
                                 fmi2Boolean logging) {
    alarm(CALL_SECONDS);
    fmi2Component c = fmi.Instantiate(name, fmi2CoSimulation, guid, resource_uri, callbacks,
                                      fmi2False, logging);
    alarm(0);
    return c;
}

int initialize(fmi2Component c, double deflection, double rate) {
    fmi2Real start[2] = {deflection, rate};
    /* fmi2Warning: an input outside the range the thesis measured is still taken. */
    return fmi.SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
           fmi.EnterInitializationMode(c) == fmi2OK &&
           fmi.SetReal(c, vr_in, 2, start) <= fmi2Warning &&
           fmi.ExitInitializationMode(c) == fmi2OK;
}

/* The instance's serialized state and its inputs and output: 0 if it has none now. */
typedef struct {
    size_t size;
    unsigned char bytes[STATE_CAPACITY];
    fmi2Real values[3];
    int have_values;
} Snapshot;

static int snapshot(fmi2Component c, Snapshot *s) {
    /* The outputs first: reading them may bring cached values up to date, which the
       state then carries. */
    fmi2ValueReference vrs[3] = {vr_in[0], vr_in[1], vr_out};
    s->have_values = fmi.GetReal(c, vrs, 3, s->values) == fmi2OK;
    fmi2FMUstate state = NULL;
    s->size = 0;
    if (fmi.GetFMUstate(c, &state) != fmi2OK) return 0;
    int ok = fmi.SerializedFMUstateSize(c, state, &s->size) == fmi2OK && s->size <= STATE_CAPACITY &&
             fmi.SerializeFMUstate(c, state, (fmi2Byte *)s->bytes, s->size) == fmi2OK;
    fmi.FreeFMUstate(c, &state);
    return ok;
}

static void describe_difference(const Snapshot *a, const Snapshot *b) {
    size_t i = 0;
    while (i < a->size && i < b->size && a->bytes[i] == b->bytes[i]) i++;
    fprintf(stderr, "  state %zu -> %zu bytes, first difference at %zu:\n%.1000s\n%.1000s\n",
            a->size, b->size, i, a->size > 148 ? (const char *)a->bytes + 144 : "",
            b->size > 148 ? (const char *)b->bytes + 144 : "");
    fprintf(stderr, "  values %d [%.17g %.17g %.17g] -> %d [%.17g %.17g %.17g]\n", a->have_values,
            a->values[0], a->values[1], a->values[2], b->have_values, b->values[0], b->values[1],
            b->values[2]);
}

static int same_snapshot(const Snapshot *a, const Snapshot *b) {
    return a->size == b->size && memcmp(a->bytes, b->bytes, a->size) == 0 &&
           a->have_values == b->have_values &&
           (!a->have_values || memcmp(a->values, b->values, sizeof a->values) == 0);
}

/* ---- random calls ---- */

enum { N_FUNCTIONS = 21 };
static const char *function_names[N_FUNCTIONS] = {
    "SetupExperiment", "EnterInitializationMode", "ExitInitializationMode", "SetReal",
    "GetReal", "DoStep", "DoStep(sane)", "Terminate", "Reset", "GetFMUstate", "SetFMUstate",
    "FreeFMUstate", "SerializeFMUstate", "DeSerializeFMUstate", "SetInteger", "GetBoolean",
    "SetString", "GetRealStatus", "SetDebugLogging", "FreeInstance", "SetReal(sane)"};
static unsigned long counts[N_FUNCTIONS][5];

static fmi2Status random_call(fmi2Component *c, int f, fmi2FMUstate *saved, double *time) {
    fmi2ValueReference vrs[4];
    fmi2Real reals[4];
    size_t n = below(4) + (below(16) == 0 ? 0 : 0);
    for (size_t i = 0; i < 4; i++) { vrs[i] = random_vr(); reals[i] = random_real(); }
    switch (f) {
    case 0: return fmi.SetupExperiment(*c, below(2), random_real(), below(2) ? 0.0 : random_real(),
                                       below(2), random_real());
    case 1: return fmi.EnterInitializationMode(*c);
    case 2: return fmi.ExitInitializationMode(*c);
    case 3: return fmi.SetReal(*c, below(16) ? vrs : NULL, n, below(16) ? reals : NULL);
    case 4: return fmi.GetReal(*c, below(16) ? vrs : NULL, n, below(16) ? reals : NULL);
    case 5: return fmi.DoStep(*c, below(2) ? *time : random_real(), random_real(), below(2));
    case 6: {
        fmi2Status s = fmi.DoStep(*c, *time, 1e-3, fmi2True);
        if (s == fmi2OK) *time += 1e-3;
        return s;
    }
    case 7: return fmi.Terminate(*c);
    case 8: { fmi2Status s = fmi.Reset(*c); if (s == fmi2OK) *time = 0.0; return s; }
    case 9: {
        fmi2FMUstate state = NULL;
        fmi2Status s = fmi.GetFMUstate(*c, &state);
        if (s == fmi2OK) { if (*saved) fmi.FreeFMUstate(*c, saved); *saved = state; }
        return s;
    }
    case 10: return fmi.SetFMUstate(*c, *saved);
    case 11: { /* FMI lets the FMU set *saved to NULL; the host never reuses it */
        fmi2Status s = fmi.FreeFMUstate(*c, saved);
        *saved = NULL;
        return s;
    }
    case 12: {
        static unsigned char buffer[STATE_CAPACITY];
        size_t size = 0;
        if (*saved == NULL) return fmi.SerializeFMUstate(*c, NULL, (fmi2Byte *)buffer, 16);
        fmi.SerializedFMUstateSize(*c, *saved, &size);
        size_t given = below(2) ? size : below(size + 64);
        return fmi.SerializeFMUstate(*c, *saved, (fmi2Byte *)buffer,
                                     given < STATE_CAPACITY ? given : STATE_CAPACITY);
    }
    case 13: {
        unsigned char bytes[256];
        for (size_t i = 0; i < sizeof bytes; i++) bytes[i] = (unsigned char)next_random();
        if (below(2)) memcpy(bytes, "FMUSTATE", 8);
        fmi2FMUstate state = NULL;
        fmi2Status s = fmi.DeSerializeFMUstate(*c, (fmi2Byte *)bytes, below(sizeof bytes), &state);
        if (state) fmi.FreeFMUstate(*c, &state);
        return s;
    }
    case 14: { fmi2Integer v[4] = {1, -1, 0, 7}; return fmi.SetInteger(*c, vrs, n, v); }
    case 15: { fmi2Boolean v[4]; return fmi.GetBoolean(*c, vrs, n, v); }
    case 16: { fmi2String v[4] = {"x", "%s%n%s", "", "1e3"}; return fmi.SetString(*c, vrs, n, v); }
    case 17: { fmi2Real v; return fmi.GetRealStatus(*c, below(2) ? fmi2LastSuccessfulTime : 7, &v); }
    case 18: return fmi.SetDebugLogging(*c, below(2), 0, NULL);
    case 19:
        if (*saved) fmi.FreeFMUstate(*c, saved);
        fmi.FreeInstance(*c);
        *c = instantiate("fuzz", &quiet, below(2));
        *time = 0.0;
        return *c ? fmi2OK : fmi2Fatal;
    default: {
        fmi2Real sane[2] = {(uniform() - 0.5) * 0.02, (uniform() - 0.5) * 0.2};
        return fmi.SetReal(*c, vr_in, 2, sane);
    }
    }
}

static int run_random(long count, uint64_t seed) {
    rng_state = seed;
    fmi2Component c = instantiate("fuzz", &quiet, fmi2False);
    if (!c) { fail("instantiate"); return 3; }
    fmi2FMUstate saved = NULL;
    double time = 0.0;
    static Snapshot before, after;
    unsigned long refused_checked = 0, reinstantiated = 0;
    for (long k = 0; k < count; k++) {
        /* Sane steps and inputs are frequent, so that sequences get deep into a run. */
        int f = below(3) == 0 ? (below(2) ? 6 : 20) : (int)below(N_FUNCTIONS);
        if (f == 19 && below(50)) f = 4; /* free/instantiate is rare: it is slow */
        int check = f != 19 && below(4) == 0 && snapshot(c, &before);
        alarm(CALL_SECONDS);
        fmi2Status s = random_call(&c, f, &saved, &time);
        alarm(0);
        if (s < 0 || s > fmi2Pending) { fail("call %ld %s returned %d", k, function_names[f], s); continue; }
        counts[f][s]++;
        if (c == NULL) { fail("re-instantiate failed at call %ld", k); return 3; }
        if (check && s == fmi2Error) {
            refused_checked++;
            if (!snapshot(c, &after) || !same_snapshot(&before, &after))
            {
                fail("call %ld: refused %s changed the instance", k, function_names[f]);
                describe_difference(&before, &after);
            }
        }
        if (s == fmi2Fatal) { /* not allowed in the contract, but recover to go on */
            fail("call %ld: %s returned fmi2Fatal", k, function_names[f]);
            saved = NULL;
            fmi.FreeInstance(c);
            c = instantiate("fuzz", &quiet, fmi2False);
            reinstantiated++;
            if (!c) return 3;
        }
    }
    if (saved) fmi.FreeFMUstate(c, &saved);
    fmi.FreeInstance(c);
    unsigned long total[5] = {0};
    for (int f = 0; f < N_FUNCTIONS; f++) {
        printf("function %s", function_names[f]);
        for (int s = 0; s < 5; s++) { printf(" %lu", counts[f][s]); total[s] += counts[f][s]; }
        printf("\n");
    }
    printf("calls %ld\nstatus_ok %lu\nstatus_warning %lu\nstatus_discard %lu\nstatus_error %lu\n"
           "status_fatal %lu\nrefused_checked %lu\n", count, total[0], total[1], total[2], total[3],
           total[4], refused_checked);
    return failures ? 3 : 0;
}

/* ---- serialized states ---- */

static size_t valid_state(fmi2Component c, unsigned char *out) {
    fmi2FMUstate state = NULL;
    size_t size = 0;
    if (fmi.GetFMUstate(c, &state) != fmi2OK ||
        fmi.SerializedFMUstateSize(c, state, &size) != fmi2OK || size > STATE_CAPACITY ||
        fmi.SerializeFMUstate(c, state, (fmi2Byte *)out, size) != fmi2OK) size = 0;
    if (state) fmi.FreeFMUstate(c, &state);
    return size;
}

static fmi2Component stepped_instance(void) {
    fmi2Component c = instantiate("states", &quiet, fmi2False);
    if (!c || !initialize(c, 0.003, 0.1)) return NULL;
    for (int k = 0; k < 20; k++) {
        fmi2Real in[2] = {0.003 * cos(0.1 * k), -0.03 * sin(0.1 * k)};
        fmi.SetReal(c, vr_in, 2, in);
        fmi.DoStep(c, k * 1e-3, 1e-3, fmi2True);
    }
    return c;
}

static unsigned long states_tried, states_refused, crafted_accepted, crafted_set;

/* A state that must be refused: refused, and the instance unchanged. */
static void expect_refused(fmi2Component c, const unsigned char *bytes, size_t size, const char *what) {
    static Snapshot before, after;
    snapshot(c, &before);
    fmi2FMUstate state = NULL;
    alarm(CALL_SECONDS);
    fmi2Status s = fmi.DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &state);
    alarm(0);
    states_tried++;
    if (s == fmi2Error && state == NULL) states_refused++;
    else {
        fail("%s state (%zu bytes) gave status %d", what, size, s);
        if (state) fmi.FreeFMUstate(c, &state);
    }
    snapshot(c, &after);
    if (!same_snapshot(&before, &after)) fail("a refused %s state changed the instance", what);
}

static int run_states(const char *other_file, uint64_t seed) {
    rng_state = seed;
    fmi2Component c = stepped_instance();
    if (!c) { fail("instantiate"); return 3; }
    static unsigned char good[STATE_CAPACITY], bad[STATE_CAPACITY + 64];
    size_t size = valid_state(c, good);
    if (size <= ENVELOPE_OVERHEAD) { fail("no valid state"); return 3; }
    printf("state_bytes %zu\n", size);
    /* The valid state itself round-trips. */
    fmi2FMUstate state = NULL;
    if (fmi.DeSerializeFMUstate(c, (fmi2Byte *)good, size, &state) != fmi2OK ||
        fmi.SetFMUstate(c, state) != fmi2OK) fail("a valid state was refused");
    fmi.FreeFMUstate(c, &state);
    /* Truncated: every length. */
    for (size_t n = 0; n < size; n++) expect_refused(c, good, n, "truncated");
    /* Longer than it says. */
    memcpy(bad, good, size); bad[size] = 0;
    expect_refused(c, bad, size + 1, "extended");
    /* Bit-flipped: every byte, a random bit. */
    for (size_t i = 0; i < size; i++) {
        memcpy(bad, good, size);
        bad[i] ^= (unsigned char)(1u << below(8));
        expect_refused(c, bad, size, "bit-flipped");
    }
    /* Random bytes, with and without the magic. */
    for (int k = 0; k < 200; k++) {
        size_t n = below((unsigned)size * 2);
        for (size_t i = 0; i < n; i++) bad[i] = (unsigned char)next_random();
        if (k % 2 && n >= 8) memcpy(bad, "FMUSTATE", 8);
        expect_refused(c, bad, n, "random");
    }
    /* From another FMU. */
    FILE *file = fopen(other_file, "rb");
    if (!file) { fail("cannot read %s", other_file); return 3; }
    size_t other = fread(bad, 1, STATE_CAPACITY, file);
    fclose(file);
    expect_refused(c, bad, other, "another FMU's");
    /* Another format version, with a correct checksum. */
    size_t length = size - ENVELOPE_OVERHEAD;
    const unsigned char *payload = good + ENVELOPE_OVERHEAD - 4;
    /* the format version follows the 8-byte tag, 4 bytes little-endian: one past it */
    uint32_t version = (uint32_t)good[8] | (uint32_t)good[9] << 8 | (uint32_t)good[10] << 16
                       | (uint32_t)good[11] << 24;
    envelope_write(bad, model_name, guid, version + 1, payload, length);
    expect_refused(c, bad, size, "another version's");
    /* Crafted: the payload changed, the envelope and checksum remade. Each must be refused
       or, if accepted, give finite outputs. */
    static unsigned char crafted_payload[STATE_CAPACITY];
    for (int k = 0; k < 400; k++) {
        memcpy(crafted_payload, payload, length);
        int edits = 1 + (int)below(3);
        for (int e = 0; e < edits; e++) {
            size_t at = below((unsigned)length);
            static const char junk[] = "-0123456789.eE+nNaI\"[]{},:x";
            crafted_payload[at] = below(2) ? (unsigned char)junk[below(sizeof junk - 1)]
                                           : (unsigned char)next_random();
        }
        envelope_write(bad, model_name, guid, version, crafted_payload, length);
        fmi2FMUstate s = NULL;
        alarm(CALL_SECONDS);
        fmi2Status status = fmi.DeSerializeFMUstate(c, (fmi2Byte *)bad, size, &s);
        alarm(0);
        if (status == fmi2OK) {
            crafted_accepted++;
            fmi2Real out = 0;
            if (fmi.SetFMUstate(c, s) == fmi2OK) {
                crafted_set++;
                fmi2Status step = fmi.DoStep(c, 0.0, 1e-3, fmi2True);
                if (step <= fmi2Warning &&
                    (fmi.GetReal(c, &vr_out, 1, &out) != fmi2OK || !isfinite(out)))
                    fail("an accepted crafted state gave output %g", out);
            }
            fmi.FreeFMUstate(c, &s);
            /* back to the valid state */
            fmi.DeSerializeFMUstate(c, (fmi2Byte *)good, size, &s);
            fmi.SetFMUstate(c, s);
            fmi.FreeFMUstate(c, &s);
        } else if (status != fmi2Error) fail("a crafted state gave status %d", status);
    }
    /* Serializing stays inside the buffer: too small is refused unwritten, larger is
       written only up to the state's size. */
    fmi.GetFMUstate(c, &state);
    memset(bad, 0xA5, sizeof bad);
    if (fmi.SerializeFMUstate(c, state, (fmi2Byte *)bad, size - 1) != fmi2Error) fail("short buffer accepted");
    for (size_t i = 0; i < size + 64; i++) if (bad[i] != 0xA5) { fail("short buffer written"); break; }
    if (fmi.SerializeFMUstate(c, state, (fmi2Byte *)bad, size + 64) != fmi2OK) fail("large buffer refused");
    for (size_t i = size; i < size + 64; i++) if (bad[i] != 0xA5) { fail("written past the state"); break; }
    fmi.FreeFMUstate(c, &state);
    fmi.FreeInstance(c);
    printf("states_tried %lu\nstates_refused %lu\ncrafted 400\ncrafted_deserialized %lu\n"
           "crafted_set %lu\n", states_tried, states_refused, crafted_accepted, crafted_set);
    return failures ? 3 : 0;
}

static int run_dump_state(const char *path) {
    fmi2Component c = stepped_instance();
    static unsigned char bytes[STATE_CAPACITY];
    size_t size = c ? valid_state(c, bytes) : 0;
    FILE *file = fopen(path, "wb");
    if (!size || !file || fwrite(bytes, 1, size, file) != size) { fail("dump-state"); return 3; }
    fclose(file);
    fmi.FreeInstance(c);
    return 0;
}

/* ---- a re-entrant logger ---- */

static int run_logger(void) {
    fmi2Component c = instantiate("logger", &reentrant, fmi2True);
    if (!c || !initialize(c, 0.0, 0.0)) { fail("instantiate"); return 3; }
    reentrant_target = c;
    fmi2Real bad[2] = {NAN, 0.0};
    for (int k = 0; k < 50; k++) {
        alarm(CALL_SECONDS);
        if (fmi.SetReal(c, vr_in, 2, bad) != fmi2Error) fail("NaN accepted");
        if (fmi.DoStep(c, 0.0, -1.0, fmi2True) != fmi2Error) fail("negative step accepted");
        alarm(0);
    }
    reentrant_target = NULL;
    fmi2Real out = NAN, in[2] = {0.001, 0.0};
    if (fmi.SetReal(c, vr_in, 2, in) != fmi2OK || fmi.DoStep(c, 0.0, 1e-3, fmi2True) != fmi2OK ||
        fmi.GetReal(c, &vr_out, 1, &out) != fmi2OK || !isfinite(out))
        fail("the instance does not work after the re-entrant logger");
    fmi.FreeInstance(c);
    printf("messages %d\nnested_calls %lu\nnested_accepted %lu\n", messages_seen, nested_calls,
           nested_accepted);
    if (messages_seen < 100) fail("only %d messages reached the logger", messages_seen);
    return failures ? 3 : 0;
}

/* ---- loading ---- */

void *load(const char *binary) {
    void *library = dlopen(binary, RTLD_NOW | RTLD_LOCAL);
    if (!library) { fprintf(stderr, "dlopen failed: %s\n", dlerror()); return NULL; }
    fmi3_binary = dlsym(library, "fmi3InstantiateCoSimulation") != NULL;
    if (fmi3_binary) {
        if (fmi3_as_fmi2(library, &fmi)) return library;
        fprintf(stderr, "an FMI 3.0 function is missing\n");
        return NULL;
    }
#define LOOKUP(name)                                                                       \
    if ((*(void **)&fmi.name = dlsym(library, "fmi2" #name)) == NULL) {                   \
        fprintf(stderr, "missing fmi2%s\n", #name);                                        \
        return NULL;                                                                       \
    }
    LOOKUP(Instantiate) LOOKUP(FreeInstance) LOOKUP(SetDebugLogging) LOOKUP(SetupExperiment)
    LOOKUP(EnterInitializationMode) LOOKUP(ExitInitializationMode) LOOKUP(Terminate)
    LOOKUP(Reset) LOOKUP(GetReal) LOOKUP(GetInteger) LOOKUP(GetBoolean) LOOKUP(GetString)
    LOOKUP(SetReal) LOOKUP(SetInteger) LOOKUP(SetBoolean) LOOKUP(SetString) LOOKUP(GetFMUstate)
    LOOKUP(SetFMUstate) LOOKUP(FreeFMUstate) LOOKUP(SerializedFMUstateSize)
    LOOKUP(SerializeFMUstate) LOOKUP(DeSerializeFMUstate) LOOKUP(DoStep) LOOKUP(GetStatus)
    LOOKUP(GetRealStatus)
#undef LOOKUP
    return library;
}

int main(int argc, char **argv) {
    if (argc < 8) {
        fprintf(stderr, "usage: %s MODE BINARY RESOURCE_URI GUID VR_DEFLECTION VR_RATE VR_OUTPUT "
                        "[ARGS...]\n", argv[0]);
        return 1;
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    void *library = load(argv[2]);
    if (!library) return 2;
    resource_uri = argv[3];
    guid = argv[4];
    vr_in[0] = (fmi2ValueReference)strtoul(argv[5], NULL, 10);
    vr_in[1] = (fmi2ValueReference)strtoul(argv[6], NULL, 10);
    vr_out = (fmi2ValueReference)strtoul(argv[7], NULL, 10);
    fmi3_as_fmi2_variables(vr_in, vr_out);
    static char name[256];
    const char *slash = strrchr(argv[2], '/');
    snprintf(name, sizeof name, "%s", slash ? slash + 1 : argv[2]);
    char *dot = strrchr(name, '.');
    if (dot) *dot = '\0';
    model_name = name;

    const char *mode = argv[1];
    int status;
    if (!strcmp(mode, "random") && argc > 9) status = run_random(atol(argv[8]), strtoull(argv[9], NULL, 10));
    else if (!strcmp(mode, "instantiate") && argc > 9) status = run_instantiate(argv[8], atoi(argv[9]));
    else if (!strcmp(mode, "states") && argc > 9) status = run_states(argv[8], strtoull(argv[9], NULL, 10));
    else if (!strcmp(mode, "dump-state") && argc > 8) status = run_dump_state(argv[8]);
    else if (!strcmp(mode, "logger")) status = run_logger();
    else if (!strcmp(mode, "cycles") && argc > 9) status = run_cycles(atol(argv[8]), atol(argv[9]));
    else if (!strcmp(mode, "threads") && argc > 9) status = run_threads(atoi(argv[8]), atol(argv[9]));
    else if (!strcmp(mode, "shared") && argc > 9) status = run_shared(atoi(argv[8]), atol(argv[9]));
    else if (!strcmp(mode, "thread-states") && argc > 8) status = run_thread_states(atol(argv[8]));
    else if (!strcmp(mode, "unload")) status = run_unload(argv[2], &library);
    else { fprintf(stderr, "unknown mode or missing arguments: %s\n", mode); return 1; }
    if (fmi3_binary) printf("intermediate_updates %lu\n", fmi3_as_fmi2_intermediate_updates());
    printf("failures %lu\n", failures);
    dlclose(library);
    return status;
}
