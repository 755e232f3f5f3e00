/*
 * The binary of every Python-flavour FMU: a thin FMI 2.0 layer in front of pythonfmu's
 * library.
 *
 * pythonfmu's library (shipped next to this one as PYTHONFMU_ENGINE) runs the Python
 * adapter, but it can only answer fmi2OK, fmi2Discard (a step returned False) or fmi2Fatal
 * (a Python exception, after which the instance is gone and the next call crashes the host),
 * and it expects the Python C API to be present in the process already. This layer
 *
 *  - checks what fmi2Instantiate is given (interface type, GUID, resource location) as the
 *    native runtime does (instantiation.c), before Python sees it;
 *  - returns, for every call, the worst of pythonfmu's status and the statuses the adapter
 *    logged during the call, so a rejected input is fmi2Error and a warning fmi2Warning;
 *  - loads the Python shared library (PYTHON_LIBRARY) with global symbols when the host
 *    process has no Python of its own, so C hosts need no LD_PRELOAD;
 *  - stops calling an instance that reported fmi2Fatal, so the host is never crashed by it,
 *    and refuses a call while another on the same instance has not returned (a second
 *    thread, or a logger calling back: call_flag.h);
 *  - keeps one Python thread state for each host thread that has none of its own (a C
 *    host's), rather than pythonfmu making and destroying one in every call, and deletes
 *    it after the thread has ended;
 *  - always lets pythonfmu log (it drops every message unless debug logging is on) and
 *    applies the host's logging choice itself (host_log.c, shared with the native runtime);
 *  - wraps serialized states in the envelope the native runtime uses (state_envelope.c:
 *    format version, GUID, checksum), and refuses a broken one before Python sees it;
 *  - answers fmi2GetRealStatus(fmi2LastSuccessfulTime) after a discarded step;
 *  - hashes the Python in the resources folder when an instance is made from it, and
 *    refuses a copy whose Python is not what the build wrote (PYTHON_CONTENT): its module
 *    names carry the build's hash, so an edited copy would share modules with an unedited
 *    one in the same process, and whichever came first would run for both.
 *
 * Everything else is forwarded unchanged.
 */

#define _GNU_SOURCE
#include <dirent.h>
#include <dlfcn.h>
#include <inttypes.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "call_flag.h"
#include "fmi2Functions.h"
#include "host_log.h"
#include "fmi2_host.h"
#include "instantiation.h"
#include "state_envelope.h"

#ifndef PYTHON_LIBRARY
#error "build with -DPYTHON_LIBRARY=\"libpython3.X.so.1.0\""
#endif
#if !defined(FMU_GUID) || !defined(FMU_NAME)
#error "build with -DFMU_GUID=\"...\" -DFMU_NAME=\"...\" (the FMU's GUID and model name)"
#endif
#ifndef PYTHON_CONTENT
#error "build with -DPYTHON_CONTENT=\"...\" (export/build.py, python_content_hash)"
#endif
#define PYTHONFMU_ENGINE "libpythonfmu-export.so"
#define STATE_FORMAT_VERSION 1u
#define PENDING_MESSAGES 8

/* pythonfmu's functions, looked up once per process. */
static struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *freeInstance;
    fmi2SetDebugLoggingTYPE *setDebugLogging;
    fmi2SetupExperimentTYPE *setupExperiment;
    fmi2EnterInitializationModeTYPE *enterInitializationMode;
    fmi2ExitInitializationModeTYPE *exitInitializationMode;
    fmi2TerminateTYPE *terminate;
    fmi2ResetTYPE *reset;
    fmi2GetRealTYPE *getReal;
    fmi2GetIntegerTYPE *getInteger;
    fmi2GetBooleanTYPE *getBoolean;
    fmi2GetStringTYPE *getString;
    fmi2SetRealTYPE *setReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetBooleanTYPE *setBoolean;
    fmi2SetStringTYPE *setString;
    fmi2GetFMUstateTYPE *getFMUstate;
    fmi2SetFMUstateTYPE *setFMUstate;
    fmi2FreeFMUstateTYPE *freeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *serializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *serializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *deSerializeFMUstate;
    fmi2GetDirectionalDerivativeTYPE *getDirectionalDerivative;
    fmi2SetRealInputDerivativesTYPE *setRealInputDerivatives;
    fmi2GetRealOutputDerivativesTYPE *getRealOutputDerivatives;
    fmi2DoStepTYPE *doStep;
    fmi2CancelStepTYPE *cancelStep;
} engine;

static pthread_once_t engine_once = PTHREAD_ONCE_INIT;
static char engine_problem[8192]; /* empty when the engine loaded */

/* The few functions of Python's C API the guard calls itself, looked up in the process (the
   guard does not link libpython). A thread state is opaque here. */
static struct {
    int (*is_initialized)(void);         /* Py_IsInitialized */
    void *(*this_thread_state)(void);    /* PyGILState_GetThisThreadState */
    int (*ensure)(void);                 /* PyGILState_Ensure */
    void (*release)(int);                /* PyGILState_Release */
    void *(*save_thread)(void);          /* PyEval_SaveThread */
    void (*clear_thread_state)(void *);  /* PyThreadState_Clear */
    void (*delete_thread_state)(void *); /* PyThreadState_Delete */
} python;

/* The Python thread state kept for a host thread that had none: made at its first call
   once the interpreter runs; when the thread ends, this key's destructor hands it to
   `ended`, and the next call into this library deletes it. */
static pthread_key_t kept_thread_state;
static int kept_thread_state_made;
static __thread int thread_state_settled; /* this thread has one of its own, or a kept one */

typedef struct Ended {
    void *state;
    struct Ended *next;
} Ended;
static pthread_mutex_t ended_lock = PTHREAD_MUTEX_INITIALIZER;
static Ended *ended;

typedef struct Guard {
    fmi2Component engine;
    fmi2CallbackFunctions engine_callbacks; /* the host's, with our logger in between */
    HostLog log;                            /* the host's logger and logging choice */
    char *instance_name;
    fmi2Status worst; /* worst status logged during the current call */
    /* Messages pythonfmu logs during a call, passed on when it has returned: a host's
       logger then never runs inside pythonfmu (which re-delivers its queue when the logger
       calls back into the FMU). */
    struct {
        fmi2Status status;
        char category[32];
        char text[MESSAGE_SIZE];
    } pending[PENDING_MESSAGES];
    int n_pending, n_dropped;
    int fatal;        /* the engine reported fmi2Fatal: never call it again */
    CallFlag call;    /* claimed while a call runs: another thread, or the logger, is refused */
    struct Guard *outer; /* the instance this thread was calling before this one */
    fmi2Real last_successful_time;
    char *resource_location; /* what pythonfmu's instance was made with */
} Guard;

/* Freed instances kept for reuse. pythonfmu 0.7.0 keeps about 2 KiB per instance it makes
   and never gives it back (a sys.path entry, a class made from the entry module's source);
   an instance reset through fmi2Reset makes a fresh slave without any of that. A reused
   instance keeps its Guard, whose engine_callbacks pythonfmu refers to. The pool is not
   emptied when the library is unloaded: the interpreter may already be finalized then. */
/* The instance whose call this thread is inside, for fmu_guard_log. */
static __thread Guard *calling;

#define POOL_SIZE 4
static pthread_mutex_t pool_lock = PTHREAD_MUTEX_INITIALIZER;
static Guard *pool[POOL_SIZE];
static int pool_count;

static Guard *pool_take(const char *resource_location) {
    Guard *found = NULL;
    pthread_mutex_lock(&pool_lock);
    for (int i = 0; i < pool_count && found == NULL; i++)
        if (strcmp(pool[i]->resource_location, resource_location) == 0) {
            found = pool[i];
            pool[i] = pool[--pool_count];
        }
    pthread_mutex_unlock(&pool_lock);
    return found;
}

static int pool_put(Guard *guard) {
    int kept = 0;
    pthread_mutex_lock(&pool_lock);
    if (pool_count < POOL_SIZE) {
        pool[pool_count++] = guard;
        kept = 1;
    }
    pthread_mutex_unlock(&pool_lock);
    return kept;
}

static void release(Guard *guard) {
    host_log_forget(&guard->log);
    free(guard->instance_name);
    free(guard->resource_location);
    free(guard);
}

/* pythonfmu's calls each ask for the GIL with PyGILState_Ensure and give it back with
   PyGILState_Release. On a thread with no Python thread state (a C host's), that makes a
   state and destroys it again in every call (an mmap and munmap among the work). A state
   made once here and kept, with the GIL given back, turns their pair into taking and
   giving back the GIL. A thread with a state of its own (a Python host's) is left alone. */
static void keep_python_thread_state(void) {
    if (thread_state_settled || !kept_thread_state_made || !python.is_initialized()) return;
    thread_state_settled = 1;
    if (python.this_thread_state() != NULL) return;
    python.ensure();
    pthread_setspecific(kept_thread_state, python.save_thread());
}

/* A thread with a kept state ends. Its end must not wait for the GIL (the host may hold it
   while it waits for the thread), so the state waits for the next call instead. */
static void hand_over_thread_state(void *state) {
    Ended *node = malloc(sizeof *node);
    if (node == NULL) return; /* the state stays with the interpreter until it ends */
    node->state = state;
    pthread_mutex_lock(&ended_lock);
    node->next = ended;
    __atomic_store_n(&ended, node, __ATOMIC_RELEASE);
    pthread_mutex_unlock(&ended_lock);
}

/* The states of threads that have ended, deleted under the GIL (none, almost always). */
static void delete_ended_thread_states(void) {
    if (__atomic_load_n(&ended, __ATOMIC_ACQUIRE) == NULL) return;
    pthread_mutex_lock(&ended_lock);
    Ended *list = ended;
    ended = NULL;
    pthread_mutex_unlock(&ended_lock);
    int alive = python.is_initialized(); /* else the interpreter has freed every state */
    int gil = alive ? python.ensure() : 0;
    while (list != NULL) {
        Ended *next = list->next;
        if (alive) {
            python.clear_thread_state(list->state);
            python.delete_thread_state(list->state);
        }
        free(list);
        list = next;
    }
    if (alive) python.release(gil);
}

/* Unloaded: no thread's end may call into this library any more. */
__attribute__((destructor)) static void forget_kept_thread_states(void) {
    if (kept_thread_state_made) pthread_key_delete(kept_thread_state);
}

static void load_engine(void) {
    /* A Python host already has the interpreter; a C host needs the shared library, with
       its symbols global because pythonfmu's library leaves them undefined. */
    if (dlsym(RTLD_DEFAULT, "Py_IsInitialized") == NULL &&
        dlopen(PYTHON_LIBRARY, RTLD_NOW | RTLD_GLOBAL) == NULL) {
        snprintf(engine_problem, sizeof engine_problem,
                 "this FMU runs Python: the shared library %s must be on the loader path (%s)",
                 PYTHON_LIBRARY, dlerror());
        return;
    }
#define PYTHON(field, name)                                                                 \
    if ((*(void **)&python.field = dlsym(RTLD_DEFAULT, #name)) == NULL) {                   \
        snprintf(engine_problem, sizeof engine_problem, "the Python library lacks " #name);  \
        return;                                                                             \
    }
    PYTHON(is_initialized, Py_IsInitialized)
    PYTHON(this_thread_state, PyGILState_GetThisThreadState)
    PYTHON(ensure, PyGILState_Ensure)
    PYTHON(release, PyGILState_Release)
    PYTHON(save_thread, PyEval_SaveThread)
    PYTHON(clear_thread_state, PyThreadState_Clear)
    PYTHON(delete_thread_state, PyThreadState_Delete)
#undef PYTHON
    kept_thread_state_made = pthread_key_create(&kept_thread_state, hand_over_thread_state) == 0;
    Dl_info self;
    if (!dladdr((void *)&load_engine, &self) || self.dli_fname == NULL) {
        snprintf(engine_problem, sizeof engine_problem, "cannot locate the FMU's binary folder");
        return;
    }
    char path[4096];
    const char *slash = strrchr(self.dli_fname, '/');
    int folder = slash ? (int)(slash - self.dli_fname + 1) : 0;
    snprintf(path, sizeof path, "%.*s%s", folder, self.dli_fname, PYTHONFMU_ENGINE);
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (library == NULL) {
        snprintf(engine_problem, sizeof engine_problem, "cannot load %s: %s", path, dlerror());
        return;
    }
#define LOAD(field, name)                                                                   \
    if ((*(void **)&engine.field = dlsym(library, #name)) == NULL) {                        \
        snprintf(engine_problem, sizeof engine_problem, "%s lacks " #name, path);          \
        return;                                                                             \
    }
    LOAD(instantiate, fmi2Instantiate)
    LOAD(freeInstance, fmi2FreeInstance)
    LOAD(setDebugLogging, fmi2SetDebugLogging)
    LOAD(setupExperiment, fmi2SetupExperiment)
    LOAD(enterInitializationMode, fmi2EnterInitializationMode)
    LOAD(exitInitializationMode, fmi2ExitInitializationMode)
    LOAD(terminate, fmi2Terminate)
    LOAD(reset, fmi2Reset)
    LOAD(getReal, fmi2GetReal)
    LOAD(getInteger, fmi2GetInteger)
    LOAD(getBoolean, fmi2GetBoolean)
    LOAD(getString, fmi2GetString)
    LOAD(setReal, fmi2SetReal)
    LOAD(setInteger, fmi2SetInteger)
    LOAD(setBoolean, fmi2SetBoolean)
    LOAD(setString, fmi2SetString)
    LOAD(getFMUstate, fmi2GetFMUstate)
    LOAD(setFMUstate, fmi2SetFMUstate)
    LOAD(freeFMUstate, fmi2FreeFMUstate)
    LOAD(serializedFMUstateSize, fmi2SerializedFMUstateSize)
    LOAD(serializeFMUstate, fmi2SerializeFMUstate)
    LOAD(deSerializeFMUstate, fmi2DeSerializeFMUstate)
    LOAD(getDirectionalDerivative, fmi2GetDirectionalDerivative)
    LOAD(setRealInputDerivatives, fmi2SetRealInputDerivatives)
    LOAD(getRealOutputDerivatives, fmi2GetRealOutputDerivatives)
    LOAD(doStep, fmi2DoStep)
    LOAD(cancelStep, fmi2CancelStep)
#undef LOAD
}

/* The guard's own error messages. */
static fmi2Status guard_error(const Guard *guard, const char *format, ...) {
    char message[MESSAGE_SIZE];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    host_log(&guard->log, STATUS_ERROR, message);
    return fmi2Error;
}

/* Remember the worst status seen during the call, and keep the message if the host wants
   it, to pass on when pythonfmu has returned. */
static void guard_logger(fmi2ComponentEnvironment environment, fmi2String instance_name,
                         fmi2Status status, fmi2String category, fmi2String message, ...) {
    (void)instance_name;
    Guard *guard = (Guard *)environment;
    if (status > guard->worst) guard->worst = status;
    if (!host_log_wants(&guard->log, (Status)status, category)) return;
    if (guard->n_pending == PENDING_MESSAGES) {
        guard->n_dropped++;
        return;
    }
    int i = guard->n_pending++;
    guard->pending[i].status = status;
    snprintf(guard->pending[i].category, sizeof guard->pending[i].category, "%s",
             category ? category : "");
    snprintf(guard->pending[i].text, sizeof guard->pending[i].text, "%s", message ? message : "");
}

/* The opening of every call that has claimed the instance. */
static void enter(Guard *guard) {
    guard->outer = calling;
    calling = guard;
    guard->worst = fmi2OK;
    keep_python_thread_state();
    delete_ended_thread_states();
}

/* A call that found another on the instance not returned: refused, touching nothing. */
static fmi2Status overlapping(Guard *guard, const char *function) {
    host_log_overlap(&guard->log, &guard->call, function);
    return fmi2Error;
}

/* The end of every call: the messages kept during it go to the host (the instance still
   claimed, so a logger calling back is refused), then the call's status. */
static fmi2Status finish(Guard *guard, fmi2Status status) {
    for (int i = 0; i < guard->n_pending; i++)
        host_log_send(&guard->log, (Status)guard->pending[i].status, guard->pending[i].category,
                      guard->pending[i].text);
    if (guard->n_dropped) {
        char message[96];
        snprintf(message, sizeof message, "%d more messages of this call were dropped",
                 guard->n_dropped);
        host_log_send(&guard->log, STATUS_WARNING, "logStatusWarning", message);
    }
    guard->n_pending = guard->n_dropped = 0;
    calling = guard->outer;
    call_release(&guard->call);
    return status;
}

static fmi2Status refuse(Guard *guard, const char *function) {
    return guard_error(guard, "%s refused: this instance failed fatally; free it", function);
}

static fmi2Status settle(Guard *guard, fmi2Status status) {
    if (status > guard->worst) guard->worst = status;
    if (guard->worst == fmi2Fatal) guard->fatal = 1;
    return guard->worst;
}

#define CLOSE(status) return finish(guard, (status))


/* The adapter's way to log (runtime/adapter.py): straight to the instance this thread is
   calling, rather than through pythonfmu's log queue, which keeps about 190 bytes of every
   message it passes on. 0 if this thread is inside no call of this library. */
__attribute__((visibility("default"))) int fmu_guard_log(int status, const char *category,
                                                         const char *message) {
    if (calling == NULL) return 0;
    guard_logger(calling, NULL, (fmi2Status)status, category, message);
    return 1;
}

/* The opening of every call passed to pythonfmu: declares `guard`, returns for a missing
   instance, one that failed fatally, or one with another call not returned, and starts the
   call's worst status at fmi2OK. CLOSE(status) ends the call. */
#define GUARDED(c)                                                                          \
    Guard *guard = (Guard *)(c);                                                            \
    if (guard == NULL) return fmi2Error;                                                    \
    if (!call_claim(&guard->call)) return overlapping(guard, __func__);                     \
    enter(guard);                                                                           \
    if (guard->fatal) CLOSE(refuse(guard, __func__))

/* pythonfmu reads the arrays it is given without looking: NULL is refused here. */
#define REFUSE_NULL(function, n, a, b)                                                      \
    if ((n) > 0 && ((a) == NULL || (b) == NULL))                                            \
    CLOSE(guard_error(guard, "%s: %u values announced but an array is NULL; call ignored",  \
                      function, (unsigned)(n)))

/* Forward a get or set of values to pythonfmu, its arrays checked. */
#define FORWARD_VALUES(function, call)                                                      \
    GUARDED(c);                                                                             \
    REFUSE_NULL(function, nvr, vr, value);                                                  \
    CLOSE(settle(guard, engine.call(guard->engine, vr, nvr, value)))

/* Forward one call to pythonfmu and report the worst status seen during it. */
#define FORWARD(c, call)                                                                    \
    do {                                                                                    \
        GUARDED(c);                                                                         \
        CLOSE(settle(guard, engine.call));                                                  \
    } while (0)

/* ---- the Python's content (export/build.py, python_content_hash) ---- */

#define MAX_PYTHON_FILES 256

typedef struct {
    char *paths[MAX_PYTHON_FILES]; /* relative to the resources folder, '/' between parts */
    int count, overflow;
} PythonFiles;

static void find_python(const char *root, const char *relative, PythonFiles *files) {
    char folder[8192];
    snprintf(folder, sizeof folder, "%s%s%s", root, relative[0] ? "/" : "", relative);
    DIR *directory = opendir(folder);
    if (directory == NULL) return;
    struct dirent *entry;
    while ((entry = readdir(directory)) != NULL) {
        const char *name = entry->d_name;
        if (name[0] == '.' || strcmp(name, "__pycache__") == 0) continue;
        char path[8192];
        snprintf(path, sizeof path, "%s%s%s", relative, relative[0] ? "/" : "", name);
        size_t n = strlen(name);
        int folder_entry = entry->d_type == DT_DIR;
        if (entry->d_type == DT_UNKNOWN) { /* file systems that do not say, such as older XFS;
                                              opendir, not stat (GLIBC_2.33: glibc_floor.h) */
            char full[16384];
            snprintf(full, sizeof full, "%s/%s", root, path);
            DIR *inner = opendir(full);
            folder_entry = inner != NULL;
            if (inner) closedir(inner);
        }
        if (folder_entry) {
            find_python(root, path, files);
        } else if (n > 3 && strcmp(name + n - 3, ".py") == 0) {
            if (files->count == MAX_PYTHON_FILES) files->overflow = 1;
            else files->paths[files->count++] = strdup(path);
        }
    }
    closedir(directory);
}

static int by_bytes(const void *a, const void *b) {
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static uint64_t fnv1a(uint64_t hash, const unsigned char *bytes, size_t n) {
    for (size_t i = 0; i < n; i++) hash = (hash ^ bytes[i]) * 0x100000001b3ull;
    return hash;
}

/* FNV-1a 64 over each .py file under the folder, in byte order of its relative path:
   the path, a NUL, the content, a NUL. 0 with the hash, or 1 if a file cannot be read. */
static int python_content(const char *folder, uint64_t *hash) {
    PythonFiles files = {{0}, 0, 0};
    find_python(folder, "", &files);
    qsort(files.paths, (size_t)files.count, sizeof *files.paths, by_bytes);
    uint64_t h = 0xcbf29ce484222325ull;
    int failed = files.overflow;
    static const unsigned char nul = 0;
    for (int i = 0; i < files.count; i++) {
        char path[8192];
        snprintf(path, sizeof path, "%s/%s", folder, files.paths[i]);
        FILE *file = fopen(path, "rb");
        failed |= file == NULL;
        h = fnv1a(fnv1a(h, (const unsigned char *)files.paths[i], strlen(files.paths[i])), &nul,
                  1);
        unsigned char buffer[65536];
        size_t n;
        while (file && (n = fread(buffer, 1, sizeof buffer, file)) > 0) h = fnv1a(h, buffer, n);
        h = fnv1a(h, &nul, 1);
        if (file) fclose(file);
        free(files.paths[i]);
    }
    *hash = h;
    return failed;
}

/* 1, logged, when the resources folder's Python is not what the build wrote. */
static int python_content_problem(const HostLog *log, const char *resource_location) {
    char folder[4096], text[17];
    uint64_t hash = 0;
    if (uri_path(resource_location, folder, sizeof folder) == 0 &&
        python_content(folder, &hash) == 0) {
        snprintf(text, sizeof text, "%016" PRIx64, hash);
        if (strcmp(text, PYTHON_CONTENT) == 0) return 0;
    } else {
        snprintf(text, sizeof text, "(unreadable)");
    }
    char message[MESSAGE_SIZE];
    snprintf(message, sizeof message, "fmi2Instantiate: the Python in %.300s hashes to %s, not "
             "to %s as built: a copy edited after the build would share its module names with "
             "an unedited one in this process. Build the FMU again (fmu-components build) "
             "rather than editing it", resource_location, text, PYTHON_CONTENT);
    host_log(log, STATUS_ERROR, message);
    return 1;
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    HostLog log = fmi2_host_log(instanceName, functions);
    if (fmi2_instantiation_problem(&log, instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                   functions, FMU_NAME, FMU_GUID, 1u << fmi2CoSimulation))
        return NULL;
    pthread_once(&engine_once, load_engine);
    if (engine_problem[0]) {
        host_log(&log, STATUS_ERROR, engine_problem);
        return NULL;
    }
    Guard *guard = pool_take(fmuResourceLocation);
    int reused = guard != NULL;
    if (!reused && python_content_problem(&log, fmuResourceLocation)) return NULL;
    if (!reused) guard = calloc(1, sizeof *guard);
    if (guard == NULL) return NULL;
    free(guard->instance_name);
    guard->instance_name = strdup(instanceName);
    if (!reused) guard->resource_location = strdup(fmuResourceLocation);
    guard->log = log;
    guard->log.instance_name = guard->instance_name;
    guard->log.debug_logging = loggingOn;
    guard->engine_callbacks = *functions;
    guard->engine_callbacks.logger = guard_logger;
    guard->engine_callbacks.componentEnvironment = guard;
    guard->last_successful_time = 0.0;
    call_claim(&guard->call); /* a new instance, or a freed one: nobody else has it */
    enter(guard);
    if (reused) {
        settle(guard, engine.reset(guard->engine));
    } else {
        guard->engine = engine.instantiate(instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                           &guard->engine_callbacks, visible, fmi2True);
    }
    finish(guard, fmi2OK);
    if (guard->engine == NULL || guard->worst >= fmi2Error || guard->instance_name == NULL ||
        guard->resource_location == NULL) {
        /* A half-made instance is not freed through pythonfmu: it may be broken. */
        release(guard);
        return NULL;
    }
    return guard;
}

void fmi2FreeInstance(fmi2Component c) {
    Guard *guard = (Guard *)c;
    if (guard == NULL) return;
    if (!call_claim(&guard->call)) {
        overlapping(guard, __func__);
        return;
    }
    if (!guard->fatal) {
        host_log_forget(&guard->log);
        call_release(&guard->call);
        if (pool_put(guard)) return;
        call_claim(&guard->call);
        enter(guard);
        engine.freeInstance(guard->engine);
        finish(guard, fmi2OK);
    }
    release(guard);
}

/* Recorded here, not passed on: pythonfmu must keep logging everything. */
fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    GUARDED(c);
    char problem[MESSAGE_SIZE];
    if (host_log_set(&guard->log, "fmi2SetDebugLogging", loggingOn, nCategories, categories,
                     problem))
        CLOSE(guard_error(guard, "%s", problem));
    CLOSE(fmi2OK);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    GUARDED(c);
    fmi2Status status = settle(guard, engine.setupExperiment(guard->engine, toleranceDefined,
                                                             tolerance, startTime,
                                                             stopTimeDefined, stopTime));
    /* Only an accepted call sets the time: a refused one (out of sequence: fmi2Error) did
       nothing, so the last successful time stays, as in fmi2DoStep. */
    if (status <= fmi2Warning) guard->last_successful_time = startTime;
    CLOSE(status);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    FORWARD(c, enterInitializationMode(guard->engine));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    FORWARD(c, exitInitializationMode(guard->engine));
}

fmi2Status fmi2Terminate(fmi2Component c) { FORWARD(c, terminate(guard->engine)); }

fmi2Status fmi2Reset(fmi2Component c) { FORWARD(c, reset(guard->engine)); }

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    FORWARD_VALUES("fmi2GetReal", getReal);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    FORWARD_VALUES("fmi2GetInteger", getInteger);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    FORWARD_VALUES("fmi2GetBoolean", getBoolean);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    FORWARD_VALUES("fmi2GetString", getString);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    FORWARD_VALUES("fmi2SetReal", setReal);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    FORWARD_VALUES("fmi2SetInteger", setInteger);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    FORWARD_VALUES("fmi2SetBoolean", setBoolean);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    FORWARD_VALUES("fmi2SetString", setString);
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    GUARDED(c);
    REFUSE_NULL("fmi2GetFMUstate", 1, FMUstate, FMUstate);
    CLOSE(settle(guard, engine.getFMUstate(guard->engine, FMUstate)));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    GUARDED(c);
    REFUSE_NULL("fmi2SetFMUstate", 1, FMUstate, FMUstate);
    CLOSE(settle(guard, engine.setFMUstate(guard->engine, FMUstate)));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    GUARDED(c);
    if (FMUstate == NULL || *FMUstate == NULL) CLOSE(fmi2OK);
    fmi2Status status = settle(guard, engine.freeFMUstate(guard->engine, FMUstate));
    /* pythonfmu leaves the freed pointer in place: a host that passes it again would
       hand Python a freed object. */
    *FMUstate = NULL;
    CLOSE(status);
}

/* The serialized state is pythonfmu's bytes (the adapter's JSON) in the envelope. */
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    GUARDED(c);
    REFUSE_NULL("fmi2SerializedFMUstateSize", 1, FMUstate, size);
    fmi2Status status = settle(guard, engine.serializedFMUstateSize(guard->engine, FMUstate, size));
    if (status <= fmi2Warning) *size += ENVELOPE_OVERHEAD;
    CLOSE(status);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size) {
    GUARDED(c);
    REFUSE_NULL("fmi2SerializeFMUstate", 1, FMUstate, FMUstate);
    size_t length = 0;
    fmi2Status status = settle(guard, engine.serializedFMUstateSize(guard->engine, FMUstate,
                                                                    &length));
    if (status > fmi2Warning) CLOSE(status);
    if (serializedState == NULL || size < length + ENVELOPE_OVERHEAD)
        CLOSE(guard_error(guard, "fmi2SerializeFMUstate: the buffer holds %u bytes, the state "
                          "needs %u (fmi2SerializedFMUstateSize)", (unsigned)size,
                          (unsigned)(length + ENVELOPE_OVERHEAD)));
    unsigned char *payload = malloc(length ? length : 1);
    if (payload == NULL) CLOSE(guard_error(guard, "fmi2SerializeFMUstate: out of memory"));
    status = settle(guard, engine.serializeFMUstate(guard->engine, FMUstate,
                                                    (fmi2Byte *)payload, length));
    if (status <= fmi2Warning)
        envelope_write((unsigned char *)serializedState, FMU_NAME, FMU_GUID,
                       STATE_FORMAT_VERSION, payload, length);
    free(payload);
    CLOSE(status);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    GUARDED(c);
    REFUSE_NULL("fmi2DeSerializeFMUstate", 1, FMUstate, FMUstate);
    const unsigned char *payload;
    size_t length;
    char problem[MESSAGE_SIZE];
    if (envelope_read((const unsigned char *)serializedState, size, FMU_NAME, FMU_GUID,
                      STATE_FORMAT_VERSION, &payload, &length, problem, sizeof problem))
        CLOSE(guard_error(guard, "fmi2DeSerializeFMUstate: %s", problem));
    CLOSE(settle(guard, engine.deSerializeFMUstate(guard->engine, (const fmi2Byte *)payload,
                                                   length, FMUstate)));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    FORWARD(c, getDirectionalDerivative(guard->engine, vUnknown_ref, nUnknown, vKnown_ref,
                                        nKnown, dvKnown, dvUnknown));
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    FORWARD(c, setRealInputDerivatives(guard->engine, vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    FORWARD(c, getRealOutputDerivatives(guard->engine, vr, nvr, order, value));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    GUARDED(c);
    fmi2Status status = settle(guard, engine.doStep(guard->engine, currentCommunicationPoint,
                                                    communicationStepSize,
                                                    noSetFMUStatePriorToCurrentPoint));
    /* A completed step ends at t + h; a discarded one leaves the instance at t. A refused
       call (fmi2Error) did nothing, so the last successful time stays. */
    if (status <= fmi2Warning)
        guard->last_successful_time = currentCommunicationPoint + communicationStepSize;
    else if (status == fmi2Discard)
        guard->last_successful_time = currentCommunicationPoint;
    CLOSE(status);
}

fmi2Status fmi2CancelStep(fmi2Component c) { FORWARD(c, cancelStep(guard->engine)); }

static fmi2Status unsupported_status(fmi2Component c, const char *function) {
    GUARDED(c);
    CLOSE(guard_error(guard, "%s: steps run synchronously, there is no status to ask for",
                      function));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s, (void)value;
    return unsupported_status(c, __func__);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (s != fmi2LastSuccessfulTime) return unsupported_status(c, __func__);
    GUARDED(c);
    if (value == NULL) CLOSE(fmi2Error);
    *value = guard->last_successful_time;
    CLOSE(fmi2OK);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s, (void)value;
    return unsupported_status(c, __func__);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    if (s != fmi2Terminated) return unsupported_status(c, __func__);
    GUARDED(c);
    if (value == NULL) CLOSE(fmi2Error);
    *value = fmi2False; /* the FMU never asks to end the simulation */
    CLOSE(fmi2OK);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s, (void)value;
    return unsupported_status(c, __func__);
}
