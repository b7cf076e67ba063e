/* Model Exchange, FMU states and directional derivatives of the generic FMI 3.0 layer, and the FMI 3.0
 * functions its FMUs do not provide.
 *
 * As in the FMI 2.0 layer (fmi2_layer_me.c), the core (layer_core.c, layer_state.c) does the work:
 * the models have no event indicators, no time events and no discrete states, so an event iteration
 * ends at once. Not provided, each logging why and returning fmi3Error: variables of other types than
 * Float64, Int32, Boolean and String (an empty request is fine), configuration mode, adjoint derivatives, model partitions, output derivatives and the dependency
 * queries (the ModelStructure of modelDescription.xml lists the dependencies).
 */
#include "fmi3_layer.h"

/* ---------------------------------------------------------------- Model Exchange */

#define REQUIRE_MODEL_EXCHANGE(function)                                                            \
    if (!inst->model_exchange) return FAIL("%s: only for Model Exchange instances", function)

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    ENTER(instance, MODE_EVENT | MODE_CONTINUOUS_TIME | MODE_STEP_COMPLETE, "fmi3EnterEventMode");
    if (!inst->model_exchange && !layer_of(inst)->clocked)
        return FAIL("fmi3EnterEventMode: this Co-Simulation FMU has no event mode (hasEventMode=\"false\"; build it "
                    "with --clock for one)");
    inst->mode = MODE_EVENT;
    return fmi3OK;
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    ENTER(instance, MODE_EVENT | MODE_CONTINUOUS_TIME, "fmi3EvaluateDiscreteStates");
    return fmi3OK;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate, fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged, fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime) {
    ENTER(instance, MODE_EVENT, "fmi3UpdateDiscreteStates");
    if (!discreteStatesNeedUpdate || !terminateSimulation || !nominalsOfContinuousStatesChanged
        || !valuesOfContinuousStatesChanged || !nextEventTimeDefined || !nextEventTime)
        return FAIL("fmi3UpdateDiscreteStates: NULL argument");
    *discreteStatesNeedUpdate = *terminateSimulation = *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = *nextEventTimeDefined = fmi3False;
    *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    ENTER(instance, MODE_EVENT, "fmi3EnterContinuousTimeMode");
    REQUIRE_MODEL_EXCHANGE("fmi3EnterContinuousTimeMode");
    inst->mode = MODE_CONTINUOUS_TIME;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    ENTER(instance, MODE_CONTINUOUS_TIME, "fmi3CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL)
        return FAIL("fmi3CompletedIntegratorStep: NULL enterEventMode or terminateSimulation");
    *enterEventMode = *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    ENTER(instance, MODE_EVENT | MODE_CONTINUOUS_TIME, "fmi3SetTime");
    REQUIRE_MODEL_EXCHANGE("fmi3SetTime");
    return (fmi3Status)core_set_time(inst, time, "fmi3SetTime");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t n) {
    ENTER(instance, MODE_CONTINUOUS_TIME | MODE_EVENT, "fmi3SetContinuousStates");
    return (fmi3Status)core_set_states(inst, x, n, "fmi3SetContinuousStates");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t n) {
    ENTER(instance, AFTER_INSTANTIATION, "fmi3GetContinuousStateDerivatives");
    return (fmi3Status)core_get_derivatives(inst, derivatives, n, "fmi3GetContinuousStateDerivatives");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t n) {
    ENTER(instance, ANY_MODE, "fmi3GetEventIndicators");
    (void)eventIndicators;
    return n == 0 ? fmi3OK : FAIL("fmi3GetEventIndicators: the FMU has no event indicators, got n = %zu", n);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t n) {
    ENTER(instance, AFTER_INSTANTIATION, "fmi3GetContinuousStates");
    return (fmi3Status)core_get_states(inst, x, n, "fmi3GetContinuousStates");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t n) {
    ENTER(instance, ANY_MODE, "fmi3GetNominalsOfContinuousStates");
    return (fmi3Status)core_get_nominals(inst, nominals, n, "fmi3GetNominalsOfContinuousStates");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n) {
    ENTER(instance, ANY_MODE, "fmi3GetNumberOfEventIndicators");
    if (n == NULL) return FAIL("fmi3GetNumberOfEventIndicators: NULL nEventIndicators");
    *n = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n) {
    ENTER(instance, ANY_MODE, "fmi3GetNumberOfContinuousStates");
    if (n == NULL) return FAIL("fmi3GetNumberOfContinuousStates: NULL nContinuousStates");
    *n = (size_t)inst->info.n_states;
    return fmi3OK;
}

/* Of scalar Float64 variables (states, inputs, derivatives, outputs): their slots, then the core. */
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    const char *function = "fmi3GetDirectionalDerivative";
    ENTER(instance, MODE_INITIALIZATION | RUNNING | MODE_TERMINATED, function);
    ENTER_ARRAY(unknowns, nUnknowns, function);
    ENTER_ARRAY(knowns, nKnowns, function);
    ENTER_ARRAY(seed, nSeed, function);
    ENTER_ARRAY(sensitivity, nSensitivity, function);
    if (nSeed != nKnowns || nSensitivity != nUnknowns)
        return FAIL("%s: nSeed (%zu) must equal nKnowns (%zu) and nSensitivity (%zu) nUnknowns (%zu): scalar variables only",
                    function, nSeed, nKnowns, nSensitivity, nUnknowns);
    unsigned int *slots = model_allocate(inst, nUnknowns + nKnowns, sizeof(unsigned int));
    if (nUnknowns + nKnowns > 0 && slots == NULL) return FAIL("%s: out of memory", function);
    fmi3Status status = fmi3OK;
    for (size_t i = 0; i < nUnknowns + nKnowns && status == fmi3OK; i++) {
        size_t slot;
        if (fmi3_scalar_slot(inst, i < nUnknowns ? unknowns[i] : knowns[i - nUnknowns], TYPE_REAL, &slot, function))
            slots[i] = (unsigned int)slot;
        else
            status = fmi3Error;
    }
    if (status == fmi3OK)
        status = (fmi3Status)core_directional_derivative(inst, slots, nUnknowns, slots + nUnknowns, nKnowns, seed,
                                                         sensitivity, function);
    model_release(inst, slots);
    return status;
}

/* ---------------------------------------------------------------- FMU states */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ENTER(instance, ANY_MODE & ~MODE_ERROR, "fmi3GetFMUState");
    return (fmi3Status)core_get_state(inst, FMUState, "fmi3GetFMUState");
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    ENTER(instance, ANY_MODE, "fmi3SetFMUState");
    return (fmi3Status)core_set_state(inst, FMUState, "fmi3SetFMUState");
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    ENTER(instance, ANY_MODE, "fmi3FreeFMUState");
    return (fmi3Status)core_free_state(inst, FMUState, "fmi3FreeFMUState");
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    ENTER(instance, ANY_MODE, "fmi3SerializedFMUStateSize");
    return (fmi3Status)core_serialized_size(inst, FMUState, size, "fmi3SerializedFMUStateSize");
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[], size_t size) {
    ENTER(instance, ANY_MODE, "fmi3SerializeFMUState");
    return (fmi3Status)core_serialize(inst, FMUState, serializedState, size, "fmi3SerializeFMUState");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size, fmi3FMUState *FMUState) {
    ENTER(instance, ANY_MODE, "fmi3DeserializeFMUState");
    return (fmi3Status)core_deserialize(inst, serializedState, size, FMUState, "fmi3DeserializeFMUState");
}

/* ---------------------------------------------------------------- not provided */

/* The types this FMU has no variables of: an empty request is fine, any other is refused. */
#define NO_VARIABLES(TYPE)                                                                          \
    fmi3Status fmi3Get##TYPE(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3##TYPE values[], size_t nValues) { \
        ENTER(instance, ANY_MODE, "fmi3Get" #TYPE);                                                 \
        (void)vr, (void)values, (void)nValues;                                                      \
        return nvr == 0 ? fmi3OK : FAIL("fmi3Get" #TYPE ": this FMU has no " #TYPE " variables");   \
    }                                                                                               \
    fmi3Status fmi3Set##TYPE(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3##TYPE values[], size_t nValues) { \
        ENTER(instance, ANY_MODE, "fmi3Set" #TYPE);                                                 \
        (void)vr, (void)values, (void)nValues;                                                      \
        return nvr == 0 ? fmi3OK : FAIL("fmi3Set" #TYPE ": this FMU has no " #TYPE " variables");   \
    }
NO_VARIABLES(Float32)
NO_VARIABLES(Int8)
NO_VARIABLES(UInt8)
NO_VARIABLES(Int16)
NO_VARIABLES(UInt16)
NO_VARIABLES(UInt32)
NO_VARIABLES(Int64)
NO_VARIABLES(UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t sizes[],
                         fmi3Binary values[], size_t nValues) {
    ENTER(instance, ANY_MODE, "fmi3GetBinary");
    (void)vr, (void)sizes, (void)values, (void)nValues;
    return nvr == 0 ? fmi3OK : FAIL("fmi3GetBinary: this FMU has no Binary variables");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t sizes[],
                         const fmi3Binary values[], size_t nValues) {
    ENTER(instance, ANY_MODE, "fmi3SetBinary");
    (void)vr, (void)sizes, (void)values, (void)nValues;
    return nvr == 0 ? fmi3OK : FAIL("fmi3SetBinary: this FMU has no Binary variables");
}

#define REFUSE(function, ...)                                                                       \
    {                                                                                               \
        ENTER(instance, ANY_MODE, #function);                                                       \
        __VA_ARGS__;                                                                                \
        return FAIL(#function ": not provided by this FMU");                                        \
    }
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr, size_t *n)
    REFUSE(fmi3GetNumberOfVariableDependencies, (void)vr, (void)n)
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t a[], fmi3ValueReference b[],
                                       size_t c[], fmi3DependencyKind d[], size_t n)
    REFUSE(fmi3GetVariableDependencies, (void)dependent, (void)a, (void)b, (void)c, (void)d, (void)n)
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference u[], size_t nu, const fmi3ValueReference k[],
                                    size_t nk, const fmi3Float64 seed[], size_t ns, fmi3Float64 s[], size_t n)
    REFUSE(fmi3GetAdjointDerivative, (void)u, (void)nu, (void)k, (void)nk, (void)seed, (void)ns, (void)s, (void)n)
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) REFUSE(fmi3EnterConfigurationMode, (void)0)
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) REFUSE(fmi3ExitConfigurationMode, (void)0)
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference, fmi3Float64 activationTime)
    REFUSE(fmi3ActivateModelPartition, (void)clockReference, (void)activationTime)
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues)
    REFUSE(fmi3GetOutputDerivatives, (void)vr, (void)nvr, (void)orders, (void)values, (void)nValues)
