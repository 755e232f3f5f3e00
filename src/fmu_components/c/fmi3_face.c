/*
 * The FMI 3.0 face of the native runtime: each FMI 3.0 function passes the host's arguments
 * to its core call (core.h), the same calls the FMI 2.0 face makes, and the status back.
 * What only FMI 3.0 has is answered here: the value counts of every get and set, the
 * logger's signature, the resource path, the adjoint derivatives (from the directional
 * ones), the outputs' time derivatives, and the functions of the variable types, clocks and
 * configuration the FMUs do not have.
 */
#include "core.h"
#include "fmi3Functions.h"
#include "instantiation.h"

static const Face FMI3 = {"fmi3",
                          {"Instantiated", "InitializationMode", "StepMode", "StepDiscarded",
                           "Terminated", "EventMode", "ContinuousTimeMode",
                           "IntermediateUpdateMode"},
                          1,
                          /* FMI 3.0.2 sections 3.2 and 4.2.5: from Continuous-Time Mode,
                             or from Step Mode with eventModeUsed; not in Event Mode */
                          CONTINUOUS_TIME_MODE | STEP_COMPLETE};

/* The core's status as FMI 3.0's (the same numbers). The host's handle is the core's
   Instance, passed on as it is. */
static inline fmi3Status fmi3_status(Status status) { return (fmi3Status)status; }

static void send_fmi3(const HostLog *log, Status status, const char *category,
                      const char *message) {
    ((fmi3LogMessageCallback)log->logger)(log->environment, (fmi3Status)status, category,
                                          message);
}

const char *fmi3GetVersion(void) { return fmi3Version; }

static fmi3Instance instantiate(const char *function, Interface type, fmi3String instanceName,
                                fmi3String instantiationToken, fmi3String resourcePath,
                                fmi3Boolean loggingOn, fmi3InstanceEnvironment environment,
                                fmi3LogMessageCallback logMessage) {
    HostLog log = {(HostLogger)logMessage, send_fmi3, environment, instanceName, 0, 0, {0}};
    InstantiationRequest request = {function, instanceName, 0, NULL, "instantiationToken",
                                    instantiationToken, "resourcePath", resourcePath, 0};
    if (instantiation_problem(&log, &request, MODEL_INFO.name, MODEL_INFO.guid)) return NULL;
    return core_instantiate(log, instanceName, type, &FMI3, loggingOn);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)visible;
    return instantiate(__func__, MODEL_EXCHANGE, instanceName, instantiationToken,
                       resourcePath, loggingOn, instanceEnvironment, logMessage);
}

/* The host's callback inside a step: it may read the outputs and set the inputs (the
   variables declared intermediateUpdate), and ask the step to return early. */
static int intermediate_update(Instance *instance, double t, int can_return_early) {
    fmi3Boolean early = false;
    fmi3Float64 early_time = t;
    ((fmi3IntermediateUpdateCallback)instance->intermediate_context)(
        instance->log.environment, t, true, true, true, can_return_early, &early, &early_time);
    return early;
}

/* eventModeUsed: a tyre's step that returned early at its contact asks for event handling;
   earlyReturnAllowed: steps return early there, or where the host asks in an intermediate
   update; intermediateUpdate: called at the integrator's internal steps inside a step.
   Every input and output is an intermediate variable, so the list asked for changes
   nothing. */
fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)visible, (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables;
    Instance *instance = instantiate(__func__, CO_SIMULATION, instanceName, instantiationToken,
                                     resourcePath, loggingOn, instanceEnvironment, logMessage);
    if (instance == NULL) return NULL;
    instance->event_mode_used = eventModeUsed;
    instance->early_return_allowed = earlyReturnAllowed;
    if (intermediateUpdate != NULL) {
        instance->intermediate_update = intermediate_update;
        instance->intermediate_context = (void *)intermediateUpdate;
    }
    return instance;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    HostLog log = {(HostLogger)logMessage, send_fmi3, instanceEnvironment, instanceName, 0, 0,
                   {0}};
    host_log(&log, STATUS_ERROR, "fmi3InstantiateScheduledExecution: this FMU offers Model "
             "Exchange and Co-Simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { core_free_instance(instance, __func__); }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    return fmi3_status(core_set_debug_logging(instance, __func__, loggingOn, nCategories,
                                              categories));
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    (void)stopTimeDefined, (void)stopTime;
    fmi3Status status = fmi3_status(core_setup_experiment(instance, __func__, toleranceDefined,
                                                          tolerance, startTime));
    if (status > fmi3Warning) return status;
    return fmi3_status(core_enter_initialization_mode(instance, __func__));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    return fmi3_status(core_exit_initialization_mode(instance, __func__));
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    return fmi3_status(core_terminate(instance, __func__));
}
fmi3Status fmi3Reset(fmi3Instance instance) {
    return fmi3_status(core_reset(instance, __func__));
}

/* --- values: Float64 variables and one Boolean parameter, all scalars -------------------- */

/* Every variable is a scalar: as many values as value references. */
static int counts_differ(fmi3Instance instance, const char *function, size_t nvr,
                         size_t nValues) {
    if (nvr == nValues) return 0;
    core_not_offered(instance, function, nvr > nValues ? "fewer values than value references "
                     "(every variable is a scalar); call ignored" : "more values than value "
                     "references (every variable is a scalar); call ignored");
    return 1;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Float64 values[], size_t nValues) {
    if (counts_differ(instance, __func__, nvr, nValues)) return fmi3Error;
    return fmi3_status(core_get_float64(instance, __func__, vr, nvr, values));
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues) {
    if (counts_differ(instance, __func__, nvr, nValues)) return fmi3Error;
    return fmi3_status(core_set_float64(instance, __func__, vr, nvr, values));
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          fmi3Boolean values[], size_t nValues) {
    if (counts_differ(instance, __func__, nvr, nValues)) return fmi3Error;
    int flag;
    fmi3Status status = fmi3_status(core_get_boolean(instance, __func__, vr, nvr, values, &flag));
    if (status <= fmi3Error && values != NULL && vr != NULL)
        for (size_t i = 0; i < nvr; i++) values[i] = flag != 0;
    return status;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues) {
    if (counts_differ(instance, __func__, nvr, nValues)) return fmi3Error;
    int last = nvr > 0 && values != NULL && values[nvr - 1];
    return fmi3_status(core_set_boolean(instance, __func__, vr, nvr, values, last));
}

#define NO_GETTER(function, type)                                                          \
    fmi3Status function(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,  \
                        type values[], size_t nValues) {                                   \
        (void)values, (void)nValues;                                                       \
        return fmi3_status(                                                                \
            core_no_variable_of_type(instance, #function, nvr, vr, READABLE));             \
    }
#define NO_SETTER(function, type)                                                          \
    fmi3Status function(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,  \
                        const type values[], size_t nValues) {                             \
        (void)values, (void)nValues;                                                       \
        return fmi3_status(                                                                \
            core_no_variable_of_type(instance, #function, nvr, vr, SETTABLE));             \
    }
NO_GETTER(fmi3GetFloat32, fmi3Float32)
NO_GETTER(fmi3GetInt8, fmi3Int8)
NO_GETTER(fmi3GetUInt8, fmi3UInt8)
NO_GETTER(fmi3GetInt16, fmi3Int16)
NO_GETTER(fmi3GetUInt16, fmi3UInt16)
NO_GETTER(fmi3GetInt32, fmi3Int32)
NO_GETTER(fmi3GetUInt32, fmi3UInt32)
NO_GETTER(fmi3GetInt64, fmi3Int64)
NO_GETTER(fmi3GetUInt64, fmi3UInt64)
NO_GETTER(fmi3GetString, fmi3String)
NO_SETTER(fmi3SetFloat32, fmi3Float32)
NO_SETTER(fmi3SetInt8, fmi3Int8)
NO_SETTER(fmi3SetUInt8, fmi3UInt8)
NO_SETTER(fmi3SetInt16, fmi3Int16)
NO_SETTER(fmi3SetUInt16, fmi3UInt16)
NO_SETTER(fmi3SetInt32, fmi3Int32)
NO_SETTER(fmi3SetUInt32, fmi3UInt32)
NO_SETTER(fmi3SetInt64, fmi3Int64)
NO_SETTER(fmi3SetUInt64, fmi3UInt64)
NO_SETTER(fmi3SetString, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueSizes, (void)values, (void)nValues;
    return fmi3_status(core_no_variable_of_type(instance, __func__, nvr, vr, READABLE));
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueSizes, (void)values, (void)nValues;
    return fmi3_status(core_no_variable_of_type(instance, __func__, nvr, vr, SETTABLE));
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        fmi3Clock values[]) {
    (void)values;
    return fmi3_status(core_no_variable_of_type(instance, __func__, nvr, vr, READABLE));
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Clock values[]) {
    (void)values;
    return fmi3_status(core_no_variable_of_type(instance, __func__, nvr, vr, SETTABLE));
}

/* --- what the FMUs do not have: clocks, configuration, per-element dependencies ---------- */

#define NO_CLOCKS "the FMU has no clocks"
static fmi3Status no_clocks(fmi3Instance instance, const char *function) {
    return fmi3_status(core_not_offered(instance, function, NO_CLOCKS));
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t nvr, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)vr, (void)nvr, (void)intervals, (void)qualifiers;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions, (void)qualifiers;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               fmi3Float64 shifts[]) {
    (void)vr, (void)nvr, (void)shifts;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                size_t nvr, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[],
                                  size_t nvr, const fmi3Float64 intervals[]) {
    (void)vr, (void)nvr, (void)intervals;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                   size_t nvr, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[]) {
    (void)vr, (void)nvr, (void)shifts;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[],
                                size_t nvr, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)vr, (void)nvr, (void)counters, (void)resolutions;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return no_clocks(instance, __func__);
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    return no_clocks(instance, __func__);
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return fmi3_status(core_not_offered(instance, __func__, "the FMU has no structural "
                                        "parameters"));
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return fmi3_status(core_not_offered(instance, __func__, "the FMU has no structural "
                                        "parameters"));
}

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference, (void)nDependencies;
    return fmi3_status(core_not_offered(instance, __func__, "every variable is a scalar: the "
                                        "dependencies are the modelDescription's "
                                        "ModelStructure (providesPerElementDependencies is "
                                        "false)"));
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    return fmi3_status(core_not_offered(instance, __func__, "every variable is a scalar: the "
                                        "dependencies are the modelDescription's "
                                        "ModelStructure (providesPerElementDependencies is "
                                        "false)"));
}

/* --- FMU states -------------------------------------------------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return fmi3_status(core_get_state(instance, __func__, FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    return fmi3_status(core_set_state(instance, __func__, FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return fmi3_status(core_free_state(instance, __func__, FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState,
                                      size_t *size) {
    return fmi3_status(core_serialized_state_size(instance, __func__, FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size) {
    return fmi3_status(core_serialize_state(instance, __func__, FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState) {
    return fmi3_status(core_deserialize_state(instance, __func__, serializedState, size, FMUState));
}

/* --- derivatives ------------------------------------------------------------------------- */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity) {
    if (counts_differ(instance, __func__, nKnowns, nSeed) ||
        counts_differ(instance, __func__, nUnknowns, nSensitivity))
        return fmi3Error;
    return fmi3_status(core_get_directional_derivative(instance, __func__, unknowns, nUnknowns,
                                                       knowns, nKnowns, seed, sensitivity));
}

/* The adjoint: sensitivity_j = sum_i seed_i d(unknown_i)/d(known_j), one directional
   derivative per known (the FMUs have at most a few). */
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity) {
    if (counts_differ(instance, __func__, nUnknowns, nSeed) ||
        counts_differ(instance, __func__, nKnowns, nSensitivity))
        return fmi3Error;
    if ((nUnknowns && (unknowns == NULL || seed == NULL)) ||
        (nKnowns && (knowns == NULL || sensitivity == NULL)))
        return fmi3_status(core_not_offered(instance, __func__, "an array is NULL; call ignored"));
    fmi3Status worst = fmi3OK;
    double column[MODEL_VARIABLES], one = 1.0;
    if (nUnknowns > MODEL_VARIABLES)
        return fmi3_status(core_not_offered(instance, __func__, "more unknowns than the FMU has "
                                            "variables; call ignored"));
    for (size_t j = 0; j < nKnowns; j++) {
        fmi3Status status = fmi3_status(core_get_directional_derivative(
            instance, __func__, unknowns, nUnknowns, &knowns[j], 1, &one, column));
        if (status > fmi3Warning) return status;
        if (status > worst) worst = status;
        double sum = 0.0;
        for (size_t i = 0; i < nUnknowns; i++) sum += seed[i] * column[i];
        sensitivity[j] = sum;
    }
    return worst;
}

/* --- model exchange ---------------------------------------------------------------------- */

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    return fmi3_status(core_enter_event_mode(instance, __func__));
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    fmi3Status status = fmi3_status(core_update_discrete_states(instance, __func__));
    if (status != fmi3OK) return status;
    /* FMI 3.0: NULL for what the host does not want to know */
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = false;
    if (terminateSimulation) *terminateSimulation = false;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = false;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = false;
    if (nextEventTimeDefined) *nextEventTimeDefined = false;
    if (nextEventTime) *nextEventTime = 0.0;
    return status;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return fmi3_status(core_enter_continuous_time_mode(instance, __func__));
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    fmi3Status status = fmi3_status(core_completed_integrator_step(instance, __func__));
    if (status == fmi3OK) {
        if (enterEventMode) *enterEventMode = false;
        if (terminateSimulation) *terminateSimulation = false;
    }
    return status;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    return fmi3_status(core_set_time(instance, __func__, time));
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    return fmi3_status(core_set_continuous_states(instance, __func__, continuousStates,
                                                  nContinuousStates));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    return fmi3_status(core_get_derivatives(instance, __func__, derivatives, nContinuousStates));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators) {
    return fmi3_status(core_get_event_indicators(instance, __func__, eventIndicators,
                                                 nEventIndicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    return fmi3_status(core_get_continuous_states(instance, __func__, continuousStates,
                                                  nContinuousStates));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    return fmi3_status(core_get_nominals(instance, __func__, nominals, nContinuousStates));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    if (nEventIndicators == NULL)
        return fmi3_status(core_not_offered(instance, __func__, "the place for the number is "
                                            "NULL"));
    *nEventIndicators = MODEL_EVENT_INDICATORS;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    if (nContinuousStates == NULL)
        return fmi3_status(core_not_offered(instance, __func__, "the place for the number is "
                                            "NULL"));
    *nContinuousStates = MODEL_CONTINUOUS;
    return fmi3OK;
}

/* --- co-simulation ----------------------------------------------------------------------- */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return fmi3_status(core_enter_step_mode(instance, __func__));
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[],
                                    size_t nvr, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    if (counts_differ(instance, __func__, nvr, nValues)) return fmi3Error;
    return fmi3_status(core_output_derivatives(instance, __func__, vr, nvr, orders, values));
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    const Instance *core = instance;
    fmi3Status status = fmi3_status(core_do_step(instance, __func__, currentCommunicationPoint,
                                                 communicationStepSize));
    if (status > fmi3Discard) return status;
    if (eventHandlingNeeded)
        *eventHandlingNeeded = core->returned_early == RETURNED_AT_CONTACT &&
                               core->event_mode_used;
    if (terminateSimulation) *terminateSimulation = false;
    if (earlyReturn) *earlyReturn = core->returned_early != 0;
    if (lastSuccessfulTime) *lastSuccessfulTime = core->s.last_successful_time;
    return status;
}
