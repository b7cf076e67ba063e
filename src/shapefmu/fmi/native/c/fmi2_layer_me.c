/* Model Exchange functions, directional derivatives and FMU states of the generic FMI 2.0 layer.
 *
 * The continuous states and their derivatives are Real variables at the value references the
 * model part declares (ModelInfo.state_vr, derivative_vr); the core (layer_core.c) checks the
 * calls and their arguments and asks the model part to recompute (model_update) or linearise
 * (model_partial_derivative). The models have no event indicators and no time events. FMU states
 * are layer_state.c's.
 */
#include "fmi2_layer.h"

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    REQUIRE(c, MODE_EVENT | MODE_CONTINUOUS_TIME, "fmi2EnterEventMode");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2EnterEventMode");
    inst->mode = MODE_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    REQUIRE(c, MODE_EVENT, "fmi2NewDiscreteStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2NewDiscreteStates");
    REQUIRE_ARRAY(eventInfo, 1, "fmi2NewDiscreteStates");
    eventInfo->newDiscreteStatesNeeded = fmi2False;
    eventInfo->terminateSimulation = fmi2False;
    eventInfo->nominalsOfContinuousStatesChanged = fmi2False;
    eventInfo->valuesOfContinuousStatesChanged = fmi2False;
    eventInfo->nextEventTimeDefined = fmi2False;
    eventInfo->nextEventTime = 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    REQUIRE(c, MODE_EVENT, "fmi2EnterContinuousTimeMode");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2EnterContinuousTimeMode");
    inst->mode = MODE_CONTINUOUS_TIME;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    REQUIRE(c, MODE_CONTINUOUS_TIME, "fmi2CompletedIntegratorStep");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL)
        return model_fail(inst, "fmi2CompletedIntegratorStep: NULL enterEventMode or terminateSimulation");
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    REQUIRE(c, MODE_EVENT | MODE_CONTINUOUS_TIME, "fmi2SetTime");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2SetTime");
    return core_set_time(inst, time, "fmi2SetTime");
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    REQUIRE(c, MODE_CONTINUOUS_TIME, "fmi2SetContinuousStates");
    return core_set_states(inst, x, n, "fmi2SetContinuousStates");
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t n) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetDerivatives");
    return core_get_derivatives(inst, derivatives, n, "fmi2GetDerivatives");
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetEventIndicators");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetEventIndicators");
    (void)eventIndicators;
    if (ni != 0) return model_fail(inst, "fmi2GetEventIndicators: the FMU has no event indicators, got ni = %zu", ni);
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetContinuousStates");
    return core_get_states(inst, x, n, "fmi2GetContinuousStates");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t n) {
    REQUIRE(c, ANY_MODE, "fmi2GetNominalsOfContinuousStates");
    return core_get_nominals(inst, x_nominal, n, "fmi2GetNominalsOfContinuousStates");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    REQUIRE(c, MODE_INITIALIZATION | RUNNING | MODE_TERMINATED, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(vUnknown_ref, nUnknown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(dvUnknown, nUnknown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(vKnown_ref, nKnown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(dvKnown, nKnown, "fmi2GetDirectionalDerivative");
    return core_directional_derivative(inst, vUnknown_ref, nUnknown, vKnown_ref, nKnown, dvKnown, dvUnknown,
                                       "fmi2GetDirectionalDerivative");
}

/* ---------------------------------------------------------------- FMU states */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    REQUIRE(c, ANY_MODE & ~MODE_ERROR, "fmi2GetFMUstate");
    return core_get_state(inst, FMUstate, "fmi2GetFMUstate");
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate) {
    REQUIRE(c, ANY_MODE, "fmi2SetFMUstate");
    return core_set_state(inst, FMUstate, "fmi2SetFMUstate");
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate) {
    REQUIRE(c, ANY_MODE, "fmi2FreeFMUstate");
    return core_free_state(inst, FMUstate, "fmi2FreeFMUstate");
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size) {
    REQUIRE(c, ANY_MODE, "fmi2SerializedFMUstateSize");
    return core_serialized_size(inst, FMUstate, size, "fmi2SerializedFMUstateSize");
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size) {
    REQUIRE(c, ANY_MODE, "fmi2SerializeFMUstate");
    return core_serialize(inst, FMUstate, (unsigned char *)serializedState, size, "fmi2SerializeFMUstate");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate *FMUstate) {
    REQUIRE(c, ANY_MODE, "fmi2DeSerializeFMUstate");
    return core_deserialize(inst, (const unsigned char *)serializedState, size, FMUstate, "fmi2DeSerializeFMUstate");
}
