/*
 * The FMI 2.0 face of the native runtime: each FMI 2.0 function passes the host's arguments
 * to its core call (core.h) and the status back. What only FMI 2.0 has (the status
 * inquiries, the event info struct, the file URI of the resources) is answered here.
 */
#include <stdbool.h>

#include "core.h"
#include "fmi2_host.h"

static const Face FMI2 = {"fmi2",
                          {"Instantiated", "InitializationMode", "StepComplete", "StepFailed",
                           "Terminated", "EventMode", "ContinuousTimeMode",
                           "IntermediateUpdateMode"},
                          0,
                          /* FMI 2.0.4 table 3.2.3: Event Mode again, or Continuous-Time */
                          EVENT_MODE | CONTINUOUS_TIME_MODE};

/* The core's status as FMI 2.0's (the same numbers). The host's handle is the core's
   Instance, passed on as it is. */
static inline fmi2Status fmi2_status(Status status) { return (fmi2Status)status; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    (void)visible;
    HostLog log;
    if (fmi2_instantiation_refused(&log, instanceName, fmuType, fmuGUID, fmuResourceLocation,
                                   functions, MODEL_INFO.name, MODEL_INFO.guid,
                                   1u << fmi2CoSimulation | 1u << fmi2ModelExchange))
        return NULL;
    return core_instantiate(log, instanceName, (Interface)fmuType, &FMI2, loggingOn);
}

void fmi2FreeInstance(fmi2Component c) { core_free_instance(c, __func__); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    return fmi2_status(core_set_debug_logging(c, __func__, loggingOn, nCategories, categories));
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime) {
    (void)stopTimeDefined, (void)stopTime;
    return fmi2_status(core_setup_experiment(c, __func__, toleranceDefined, tolerance, startTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return fmi2_status(core_enter_initialization_mode(c, __func__));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return fmi2_status(core_exit_initialization_mode(c, __func__));
}

fmi2Status fmi2Terminate(fmi2Component c) { return fmi2_status(core_terminate(c, __func__)); }
fmi2Status fmi2Reset(fmi2Component c) { return fmi2_status(core_reset(c, __func__)); }

/* --- values ----------------------------------------------------------------------------- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    return fmi2_status(core_get_float64(c, __func__, vr, nvr, value));
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    return fmi2_status(core_set_float64(c, __func__, vr, nvr, value));
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    int flag;
    fmi2Status status = fmi2_status(core_get_boolean(c, __func__, vr, nvr, value, &flag));
    if (status <= fmi2Error && value != NULL && vr != NULL)
        for (size_t i = 0; i < nvr; i++) value[i] = flag ? fmi2True : fmi2False;
    return status;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    int last = nvr > 0 && value != NULL && value[nvr - 1] != fmi2False;
    return fmi2_status(core_set_boolean(c, __func__, vr, nvr, value, last));
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    (void)value;
    return fmi2_status(core_no_variable_of_type(c, __func__, nvr, vr, READABLE));
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    (void)value;
    return fmi2_status(core_no_variable_of_type(c, __func__, nvr, vr, READABLE));
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    (void)value;
    return fmi2_status(core_no_variable_of_type(c, __func__, nvr, vr, SETTABLE));
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    (void)value;
    return fmi2_status(core_no_variable_of_type(c, __func__, nvr, vr, SETTABLE));
}

/* --- co-simulation ------------------------------------------------------------------------- */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return fmi2_status(core_not_offered(c, __func__, "the FMU holds the rate input over a step "
                                        "and takes no input derivatives (canInterpolateInputs is "
                                        "false)"));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[],
                                        fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return fmi2_status(core_not_offered(c, __func__, "maxOutputDerivativeOrder is 0"));
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    return fmi2_status(core_not_offered(c, __func__, "steps run synchronously; there is none to "
                                        "cancel"));
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    return fmi2_status(core_do_step(c, __func__, currentCommunicationPoint, communicationStepSize));
}

static fmi2Status no_status(fmi2Component c, const char *function) {
    return fmi2_status(core_not_offered(c, function, "steps run synchronously, there is no status "
                                        "to ask for"));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s, (void)value;
    return no_status(c, __func__);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    if (s != fmi2LastSuccessfulTime) return no_status(c, __func__);
    return fmi2_status(core_last_successful_time(c, __func__, value));
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s, (void)value;
    return no_status(c, __func__);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    if (s != fmi2Terminated) return no_status(c, __func__);
    double time; /* the call's checks are the last successful time's */
    fmi2Status status = fmi2_status(core_last_successful_time(c, __func__, value ? &time : NULL));
    if (status == fmi2OK) *value = fmi2False; /* the FMU never asks to end the simulation */
    return status;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s, (void)value;
    return no_status(c, __func__);
}

/* --- model exchange ------------------------------------------------------------------------ */

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    return fmi2_status(core_enter_event_mode(c, __func__));
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    if (eventInfo == NULL) return fmi2_status(core_not_offered(c, __func__, "eventInfo is NULL"));
    fmi2Status status = fmi2_status(core_update_discrete_states(c, __func__));
    if (status == fmi2OK) {
        eventInfo->newDiscreteStatesNeeded = fmi2False;
        eventInfo->terminateSimulation = fmi2False;
        eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
        eventInfo->valuesOfContinuousStatesChanged = fmi2False;
        eventInfo->nextEventTimeDefined = fmi2False;
        eventInfo->nextEventTime = 0.0;
    }
    return status;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    return fmi2_status(core_enter_continuous_time_mode(c, __func__));
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    fmi2Status status = fmi2_status(core_completed_integrator_step(c, __func__));
    if (status == fmi2OK) {
        if (enterEventMode) *enterEventMode = fmi2False;
        if (terminateSimulation) *terminateSimulation = fmi2False;
    }
    return status;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    return fmi2_status(core_set_time(c, __func__, time));
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    return fmi2_status(core_set_continuous_states(c, __func__, x, nx));
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    return fmi2_status(core_get_derivatives(c, __func__, derivatives, nx));
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    return fmi2_status(core_get_event_indicators(c, __func__, eventIndicators, ni));
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    return fmi2_status(core_get_continuous_states(c, __func__, x, nx));
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    return fmi2_status(core_get_nominals(c, __func__, x_nominal, nx));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[]) {
    return fmi2_status(core_get_directional_derivative(c, __func__, vUnknown_ref, nUnknown,
                                                       vKnown_ref, nKnown, dvKnown, dvUnknown));
}

/* --- FMU states ------------------------------------------------------------------------------ */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    return fmi2_status(core_get_state(c, __func__, FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    return fmi2_status(core_set_state(c, __func__, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    return fmi2_status(core_free_state(c, __func__, FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    return fmi2_status(core_serialized_state_size(c, __func__, FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size) {
    return fmi2_status(core_serialize_state(c, __func__, FMUstate,
                                            (unsigned char *)serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate) {
    return fmi2_status(core_deserialize_state(c, __func__, (const unsigned char *)serializedState,
                                              size, FMUstate));
}
