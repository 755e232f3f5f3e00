/* The FMI 2.0 Co-Simulation calls the hostile host makes, as a table: filled from an FMI 2.0
   binary's own functions, or from an FMI 3.0 binary's through fmi3_as_fmi2.c. */
#ifndef FMI2_TABLE_H
#define FMI2_TABLE_H

#include "fmi2Functions.h"

typedef struct {
    fmi2InstantiateTYPE *Instantiate;
    fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetDebugLoggingTYPE *SetDebugLogging;
    fmi2SetupExperimentTYPE *SetupExperiment;
    fmi2EnterInitializationModeTYPE *EnterInitializationMode;
    fmi2ExitInitializationModeTYPE *ExitInitializationMode;
    fmi2TerminateTYPE *Terminate;
    fmi2ResetTYPE *Reset;
    fmi2GetRealTYPE *GetReal;
    fmi2GetIntegerTYPE *GetInteger;
    fmi2GetBooleanTYPE *GetBoolean;
    fmi2GetStringTYPE *GetString;
    fmi2SetRealTYPE *SetReal;
    fmi2SetIntegerTYPE *SetInteger;
    fmi2SetBooleanTYPE *SetBoolean;
    fmi2SetStringTYPE *SetString;
    fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate;
    fmi2FreeFMUstateTYPE *FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *DeSerializeFMUstate;
    fmi2DoStepTYPE *DoStep;
    fmi2GetStatusTYPE *GetStatus;
    fmi2GetRealStatusTYPE *GetRealStatus;
} Fmi2Table;

/* Fills `table` with calls that go to the FMI 3.0 functions of `library`: 0 if one is
   missing. The FMI 2.0 arguments with no FMI 3.0 form are answered here, not passed on:
   an interface type other than Co-Simulation and Model Exchange, and missing callbacks,
   give NULL; fmi2GetStatus gives fmi2Error, fmi2GetRealStatus the last successful time
   that fmi3DoStep gave. */
int fmi3_as_fmi2(void *library, Fmi2Table *table);
/* The inputs and the output the intermediate update callback reads. */
void fmi3_as_fmi2_variables(const fmi2ValueReference inputs[2], fmi2ValueReference output);
/* How many intermediate updates the FMU has called back so far. */
unsigned long fmi3_as_fmi2_intermediate_updates(void);

#endif
