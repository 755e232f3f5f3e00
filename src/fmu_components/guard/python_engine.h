/* pythonfmu's library (the engine, shipped beside the guard as PYTHONFMU_ENGINE) and the
   Python it needs: loaded once per process, with one Python thread state kept for each
   host thread that has none of its own. */
#ifndef PYTHON_ENGINE_H
#define PYTHON_ENGINE_H

#include "fmi2Functions.h"

/* The engine's FMI functions, looked up once per process (engine_load). */
typedef struct {
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
} Engine;

extern Engine engine;

/* Loads Python (for a C host) and the engine, once per process: NULL when they are there,
   else why not (a message for the host). */
const char *engine_load(void);

/* At the opening of every call into the engine, on the calling thread: keep a Python thread
   state for a host thread that has none, and delete those of threads that have ended. */
void python_thread_enter(void);

#endif
