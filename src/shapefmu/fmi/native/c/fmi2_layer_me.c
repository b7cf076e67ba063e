/* Model Exchange functions and directional derivatives of the generic FMI 2.0 layer.
 *
 * The continuous states and their derivatives are Real variables at the value references the
 * model part declares (Fmi2ModelInfo.state_vr, derivative_vr); the layer checks the calls and their
 * arguments and asks the model part to recompute (model_update) or linearise
 * (model_partial_derivative). The models have no event indicators and no time events.
 */
#include <math.h>
#include <string.h>

#include "fmi2_layer.h"

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    REQUIRE(c, FMI2_EVENT_MODE | FMI2_CONTINUOUS_TIME, "fmi2EnterEventMode");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2EnterEventMode");
    inst->mode = FMI2_EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo) {
    REQUIRE(c, FMI2_EVENT_MODE, "fmi2NewDiscreteStates");
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
    REQUIRE(c, FMI2_EVENT_MODE, "fmi2EnterContinuousTimeMode");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2EnterContinuousTimeMode");
    inst->mode = FMI2_CONTINUOUS_TIME;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    REQUIRE(c, FMI2_CONTINUOUS_TIME, "fmi2CompletedIntegratorStep");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2CompletedIntegratorStep");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (enterEventMode == NULL || terminateSimulation == NULL)
        return fmi2_fail(inst, "fmi2CompletedIntegratorStep: NULL enterEventMode or terminateSimulation");
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    REQUIRE(c, FMI2_EVENT_MODE | FMI2_CONTINUOUS_TIME, "fmi2SetTime");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2SetTime");
    if (!isfinite(time)) return fmi2_fail(inst, "fmi2SetTime: time must be finite, got %g", time);
    inst->time = time;
    return fmi2OK;
}

/* The call's state count n is the model's. */
#define REQUIRE_STATES(n, function)                                                                 \
    if ((n) != (size_t)inst->info.n_states)                                                         \
    return fmi2_fail(inst, "%s: nx must be %d, got %zu", function, inst->info.n_states, (size_t)(n))

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t n) {
    REQUIRE(c, FMI2_CONTINUOUS_TIME, "fmi2SetContinuousStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2SetContinuousStates");
    REQUIRE_ARRAY(x, n, "fmi2SetContinuousStates");
    REQUIRE_STATES(n, "fmi2SetContinuousStates");
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i])) {
            const char *name = "?";
            model_variable(inst, FMI2_REAL, inst->info.state_vr + i, &name);
            return fmi2_fail(inst, "fmi2SetContinuousStates: state %s must be finite, got %g", name, x[i]);
        }
    memcpy(inst->reals + inst->info.state_vr, x, n * sizeof(double));
    model_states_changed(inst);
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t n) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetDerivatives");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetDerivatives");
    REQUIRE_ARRAY(derivatives, n, "fmi2GetDerivatives");
    REQUIRE_STATES(n, "fmi2GetDerivatives");
    if (inst->mode != FMI2_ERROR_STATE && model_update(inst, "fmi2GetDerivatives") != fmi2OK) return fmi2Error;
    if (n) memcpy(derivatives, inst->reals + inst->info.derivative_vr, n * sizeof(double));
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetEventIndicators");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetEventIndicators");
    (void)eventIndicators;
    if (ni != 0) return fmi2_fail(inst, "fmi2GetEventIndicators: the FMU has no event indicators, got ni = %zu", ni);
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t n) {
    REQUIRE(c, AFTER_INSTANTIATION, "fmi2GetContinuousStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetContinuousStates");
    REQUIRE_ARRAY(x, n, "fmi2GetContinuousStates");
    REQUIRE_STATES(n, "fmi2GetContinuousStates");
    if (n) memcpy(x, inst->reals + inst->info.state_vr, n * sizeof(double));
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t n) {
    REQUIRE(c, ANY_MODE, "fmi2GetNominalsOfContinuousStates");
    REQUIRE_TYPE(fmi2ModelExchange, "fmi2GetNominalsOfContinuousStates");
    REQUIRE_ARRAY(x_nominal, n, "fmi2GetNominalsOfContinuousStates");
    REQUIRE_STATES(n, "fmi2GetNominalsOfContinuousStates");
    if (n) memcpy(x_nominal, inst->info.state_nominal, n * sizeof(double));
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    REQUIRE(c, FMI2_INITIALIZATION | RUNNING | FMI2_TERMINATED, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(vUnknown_ref, nUnknown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(dvUnknown, nUnknown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(vKnown_ref, nKnown, "fmi2GetDirectionalDerivative");
    REQUIRE_ARRAY(dvKnown, nKnown, "fmi2GetDirectionalDerivative");
    for (size_t i = 0; i < nUnknown; i++) {
        double sum = 0.0;
        for (size_t j = 0; j < nKnown; j++) {
            double entry;
            if (model_partial_derivative(inst, vUnknown_ref[i], vKnown_ref[j], &entry, "fmi2GetDirectionalDerivative")
                != fmi2OK)
                return fmi2Error;
            sum += entry * dvKnown[j];
        }
        dvUnknown[i] = sum;
    }
    return fmi2OK;
}
