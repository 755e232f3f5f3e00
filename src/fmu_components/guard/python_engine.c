/*
 * pythonfmu's library (the engine) and the Python it runs in, for the guard (fmi2_guard.c):
 *
 *  - loads the Python shared library (PYTHON_LIBRARY) with global symbols when the host
 *    process has no Python of its own, so C hosts need no LD_PRELOAD;
 *  - loads the engine from the guard's own folder and looks its FMI functions up;
 *  - orders the engine's exit so that it does not corrupt the heap (finalize_engine_first);
 *  - keeps one Python thread state for each host thread that has none of its own (a C
 *    host's), rather than pythonfmu making and destroying one in every call, and deletes
 *    it after the thread has ended.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "python_engine.h"

#ifndef PYTHON_LIBRARY
#error "build with -DPYTHON_LIBRARY=\"libpython3.X.so.1.0\""
#endif
#ifndef PYTHONFMU_ENGINE
#error "build with -DPYTHONFMU_ENGINE=\"...\" (export/build.py, PYTHONFMU_ENGINE)"
#endif

Engine engine;

static pthread_once_t engine_once = PTHREAD_ONCE_INIT;
static char engine_problem[8192]; /* empty when the engine loaded */

/* The few functions of Python's C API the guard calls itself, looked up in the process (the
   guard does not link libpython). A thread state is opaque here. */
typedef struct {
    int (*is_initialized)(void);         /* Py_IsInitialized */
    void *(*this_thread_state)(void);    /* PyGILState_GetThisThreadState */
    int (*ensure)(void);                 /* PyGILState_Ensure */
    void (*release)(int);                /* PyGILState_Release */
    void *(*save_thread)(void);          /* PyEval_SaveThread */
    void (*clear_thread_state)(void *);  /* PyThreadState_Clear */
    void (*delete_thread_state)(void *); /* PyThreadState_Delete */
} PythonApi;
static PythonApi python;

typedef struct {
    const char *name;
    size_t offset; /* of the function pointer in its table */
} Symbol;

#define PYTHON_SYMBOL(field, name) {#name, offsetof(PythonApi, field)}
static const Symbol PYTHON_SYMBOLS[] = {
    PYTHON_SYMBOL(is_initialized, Py_IsInitialized),
    PYTHON_SYMBOL(this_thread_state, PyGILState_GetThisThreadState),
    PYTHON_SYMBOL(ensure, PyGILState_Ensure),
    PYTHON_SYMBOL(release, PyGILState_Release),
    PYTHON_SYMBOL(save_thread, PyEval_SaveThread),
    PYTHON_SYMBOL(clear_thread_state, PyThreadState_Clear),
    PYTHON_SYMBOL(delete_thread_state, PyThreadState_Delete),
};

#define ENGINE_SYMBOL(field, name) {#name, offsetof(Engine, field)}
static const Symbol ENGINE_SYMBOLS[] = {
    ENGINE_SYMBOL(instantiate, fmi2Instantiate),
    ENGINE_SYMBOL(freeInstance, fmi2FreeInstance),
    ENGINE_SYMBOL(setDebugLogging, fmi2SetDebugLogging),
    ENGINE_SYMBOL(setupExperiment, fmi2SetupExperiment),
    ENGINE_SYMBOL(enterInitializationMode, fmi2EnterInitializationMode),
    ENGINE_SYMBOL(exitInitializationMode, fmi2ExitInitializationMode),
    ENGINE_SYMBOL(terminate, fmi2Terminate),
    ENGINE_SYMBOL(reset, fmi2Reset),
    ENGINE_SYMBOL(getReal, fmi2GetReal),
    ENGINE_SYMBOL(getInteger, fmi2GetInteger),
    ENGINE_SYMBOL(getBoolean, fmi2GetBoolean),
    ENGINE_SYMBOL(getString, fmi2GetString),
    ENGINE_SYMBOL(setReal, fmi2SetReal),
    ENGINE_SYMBOL(setInteger, fmi2SetInteger),
    ENGINE_SYMBOL(setBoolean, fmi2SetBoolean),
    ENGINE_SYMBOL(setString, fmi2SetString),
    ENGINE_SYMBOL(getFMUstate, fmi2GetFMUstate),
    ENGINE_SYMBOL(setFMUstate, fmi2SetFMUstate),
    ENGINE_SYMBOL(freeFMUstate, fmi2FreeFMUstate),
    ENGINE_SYMBOL(serializedFMUstateSize, fmi2SerializedFMUstateSize),
    ENGINE_SYMBOL(serializeFMUstate, fmi2SerializeFMUstate),
    ENGINE_SYMBOL(deSerializeFMUstate, fmi2DeSerializeFMUstate),
    ENGINE_SYMBOL(getDirectionalDerivative, fmi2GetDirectionalDerivative),
    ENGINE_SYMBOL(setRealInputDerivatives, fmi2SetRealInputDerivatives),
    ENGINE_SYMBOL(getRealOutputDerivatives, fmi2GetRealOutputDerivatives),
    ENGINE_SYMBOL(doStep, fmi2DoStep),
    ENGINE_SYMBOL(cancelStep, fmi2CancelStep),
};

/* Fills `table` with the symbols from `library` (RTLD_DEFAULT: the whole process): NULL,
   or the name of the first one missing. */
static const char *look_up(void *library, const Symbol *symbols, size_t n, void *table) {
    for (size_t i = 0; i < n; i++) {
        void *found = dlsym(library, symbols[i].name);
        if (found == NULL) return symbols[i].name;
        memcpy((char *)table + symbols[i].offset, &found, sizeof found);
    }
    return NULL;
}

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

void python_thread_enter(void) {
    keep_python_thread_state();
    delete_ended_thread_states();
}

/* Unloaded: no thread's end may call into this library any more. */
__attribute__((destructor)) static void forget_kept_thread_states(void) {
    if (kept_thread_state_made) pthread_key_delete(kept_thread_state);
}

int __cxa_atexit(void (*function)(void *), void *argument, void *library);

/* pythonfmu 0.7.0 keeps the object that owns its interpreter in a global std::shared_ptr.
   The engine's static constructor registers that pointer's destructor among the process's
   exit handlers while the engine loads; the loader's own exit handler (_dl_fini), which
   was registered before any library was loaded, runs after it and calls the engine's
   unload hook, whose finalizePythonInterpreter assigns to the destroyed pointer: a
   decrement on a freed block, which corrupts the heap at every exit of a process that
   made an instance ("corrupted double-linked list", now and then).
   Exit handlers run last registered, first run. finalizePythonInterpreter registered right
   after the engine has loaded therefore runs before that destructor: it empties the
   pointer (ending the interpreter if the engine started it: a C host's, as the destructor
   would have), and the destructor and the unload hook then find it empty and do nothing.
   It is registered with no library's handle, so that unloading the guard (fmpy does, in
   fmi2FreeInstance) does not run it early, which would end a C host's interpreter under
   the other Python FMUs it runs; and it stays callable until the exit because the engine
   is loaded RTLD_NODELETE. A function of no arguments registered as one of one is how
   glibc's atexit registers every function. Only the first load of an engine registers. */
static void finalize_engine_first(void *library) {
    void (*finalize)(void) = NULL;
    void *found = dlsym(library, "finalizePythonInterpreter");
    memcpy(&finalize, &found, sizeof found);
    if (finalize != NULL) __cxa_atexit((void (*)(void *))finalize, NULL, NULL);
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
    const char *missing = look_up(RTLD_DEFAULT, PYTHON_SYMBOLS,
                                  sizeof PYTHON_SYMBOLS / sizeof *PYTHON_SYMBOLS, &python);
    if (missing != NULL) {
        snprintf(engine_problem, sizeof engine_problem, "the Python library lacks %s", missing);
        return;
    }
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
    void *loaded_before = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NOLOAD);
    if (loaded_before) dlclose(loaded_before); /* only asked: the count stays as it was */
    else dlerror();                             /* and no error left for the host to read */
    void *library = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NODELETE);
    if (library == NULL) {
        snprintf(engine_problem, sizeof engine_problem, "cannot load %s: %s", path, dlerror());
        return;
    }
    if (loaded_before == NULL) finalize_engine_first(library);
    missing = look_up(library, ENGINE_SYMBOLS, sizeof ENGINE_SYMBOLS / sizeof *ENGINE_SYMBOLS,
                      &engine);
    if (missing != NULL)
        snprintf(engine_problem, sizeof engine_problem, "%s lacks %s", path, missing);
}

const char *engine_load(void) {
    pthread_once(&engine_once, load_engine);
    return engine_problem[0] ? engine_problem : NULL;
}
