/* The input clock of the generic FMI 3.0 layer: an FMU built with --clock declares a periodic
 * time-based input clock "sample" (intervalVariability="constant", interval Ts, shift 0) and takes its
 * samples at its ticks, in Co-Simulation with Event Mode (FMI 3.0 sections 2.2.9 and 4.1.3).
 *
 * The model part is unchanged: it samples on the absolute grid t0 + k Ts (sample_clock.h), and the
 * ticks t0 + k Ts are that grid. A sample is taken with the inputs set at its instant, and its output
 * is read there (feed-through), which is what a clocked input and output mean at a tick. What the layer
 * adds is the protocol that makes a host run the FMU tick by tick, and refuses, with a message naming
 * the tick, a run that would be wrong: instantiation without Event Mode (FMI 3.0 asks for
 * eventModeUsed = fmi3True from hosts of FMUs with clocks), a step across a tick, a step or the
 * return to Step Mode while the clock was not ticked at the tick the FMU stands on, a tick off the
 * grid, and a Ts other than the interval the model description declares.
 *
 * fmi3_clock.c, generated for each FMI 3.0 build, gives the interval (0: no clock). The ticks taken
 * are counted in the instance (clock_ticks), which FMU states save.
 */
#include <math.h>
#include <string.h>

#include "fmi3_layer.h"

/* The interval of the clock, 0 for an FMU without one (fmi3_clock.c, generated). */
extern const double fmi3_clock_interval;

/* A tick t0 + k Ts counts as reached at tau when it is <= tau + CLOCK_TOLERANCE Ts: the rule of the
 * sample grid (sample_clock.h's SAMPLE_TOLERANCE), so ticks and samples are the same instants. */
#define CLOCK_TOLERANCE 1e-6

int fmi3_clocked(void) { return fmi3_clock_interval > 0.0; }

static fmi3ValueReference clock_reference(const ModelInstance *inst) {
    return (fmi3ValueReference)(layer_of(inst)->n_variables + 1);
}

/* The number of ticks at or before tau (K(tau) + 1 of the sample grid). */
static double ticks_until(const ModelInstance *inst, double tau) {
    const double ts = fmi3_clock_interval, t0 = inst->start_time, delta = CLOCK_TOLERANCE * ts;
    double k = floor((tau - t0) / ts + CLOCK_TOLERANCE);
    if (t0 + (k + 1.0) * ts <= tau + delta) k += 1.0;
    else if (t0 + k * ts > tau + delta) k -= 1.0;
    return k + 1.0;
}

static int on_tick(const ModelInstance *inst, double tau, double k) {
    return fabs(tau - (inst->start_time + k * fmi3_clock_interval)) <= CLOCK_TOLERANCE * fmi3_clock_interval;
}

fmi3Status fmi3_clock_start(ModelInstance *inst, const char *function) {
    if (!layer_of(inst)->clocked) return fmi3OK;
    const size_t period_slot = layer_of(inst)->period_slot;
    if (model_update(inst, function) != MODEL_OK) return fmi3Error;
    const double ts = inst->reals[period_slot];
    if (fabs(ts - fmi3_clock_interval) > 1e-12 * fmi3_clock_interval) {
        const char *name = "Ts";
        model_variable(inst, TYPE_REAL, period_slot, &name);
        return FAIL("%s: %s = %.17g, but this FMU's clock 'sample' ticks every %.17g s (its modelDescription.xml): "
                    "rebuild it with --clock for another sample period", function, name, ts, fmi3_clock_interval);
    }
    inst->mode = MODE_EVENT;  /* Co-Simulation with Event Mode starts in Event Mode: the tick at t0 */
    return fmi3OK;
}

fmi3Status fmi3_clock_before_step(ModelInstance *inst, double t, double h) {
    const double due = ticks_until(inst, t);
    if (inst->clock_ticks < due)
        return FAIL("fmi3DoStep: the clock 'sample' was not ticked at t = %.17g (enter Event Mode and call fmi3SetClock "
                    "at every tick t0 + k Ts, Ts = %g)", inst->start_time + (due - 1.0) * fmi3_clock_interval,
                    fmi3_clock_interval);
    const double next = inst->start_time + due * fmi3_clock_interval;
    if (t + h > next + CLOCK_TOLERANCE * fmi3_clock_interval)
        return FAIL("fmi3DoStep: the step from %.17g to %.17g passes the tick of the clock 'sample' at %.17g; end the "
                    "step there, enter Event Mode and tick the clock", t, t + h, next);
    return fmi3OK;
}

fmi3Status fmi3_clock_before_step_mode(ModelInstance *inst) {
    if (!layer_of(inst)->clocked || inst->clock_ticks >= ticks_until(inst, inst->time)) return fmi3OK;
    return FAIL("fmi3EnterStepMode: t = %.17g is a tick of the clock 'sample', which was not set (fmi3SetClock) in "
                "this Event Mode", inst->time);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[]) {
    ENTER(instance, MODE_EVENT, "fmi3SetClock");
    ENTER_ARRAY(vr, nvr, "fmi3SetClock");
    ENTER_ARRAY(values, nvr, "fmi3SetClock");
    for (size_t i = 0; i < nvr; i++) {
        if (!layer_of(inst)->clocked || vr[i] != clock_reference(inst))
            return FAIL("fmi3SetClock: value reference %u is no clock of this FMU", (unsigned)vr[i]);
        if (!values[i]) continue;
        const double k = ticks_until(inst, inst->time) - 1.0;
        if (!on_tick(inst, inst->time, k))
            return FAIL("fmi3SetClock: the clock 'sample' ticks at t0 + k Ts (Ts = %g), not at t = %.17g",
                        fmi3_clock_interval, inst->time);
        if (inst->clock_ticks < k)
            return FAIL("fmi3SetClock: the ticks before t = %.17g were not taken (%.0f of %.0f)", inst->time,
                        inst->clock_ticks, k);
        inst->clock_ticks = k + 1.0;
    }
    return fmi3OK;
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[]) {
    ENTER(instance, ANY_MODE, "fmi3GetClock");
    (void)vr, (void)values;
    return nvr == 0 ? fmi3OK : FAIL("fmi3GetClock: this FMU has no output clock (its clock 'sample' is an input)");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    ENTER(instance, AFTER_INSTANTIATION, "fmi3GetIntervalDecimal");
    ENTER_ARRAY(vr, nvr, "fmi3GetIntervalDecimal");
    ENTER_ARRAY(intervals, nvr, "fmi3GetIntervalDecimal");
    ENTER_ARRAY(qualifiers, nvr, "fmi3GetIntervalDecimal");
    for (size_t i = 0; i < nvr; i++) {
        if (!layer_of(inst)->clocked || vr[i] != clock_reference(inst))
            return FAIL("fmi3GetIntervalDecimal: value reference %u is no clock of this FMU", (unsigned)vr[i]);
        intervals[i] = fmi3_clock_interval;
        qualifiers[i] = fmi3IntervalUnchanged;
    }
    return fmi3OK;
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 shifts[]) {
    ENTER(instance, AFTER_INSTANTIATION, "fmi3GetShiftDecimal");
    ENTER_ARRAY(vr, nvr, "fmi3GetShiftDecimal");
    ENTER_ARRAY(shifts, nvr, "fmi3GetShiftDecimal");
    for (size_t i = 0; i < nvr; i++) {
        if (!layer_of(inst)->clocked || vr[i] != clock_reference(inst))
            return FAIL("fmi3GetShiftDecimal: value reference %u is no clock of this FMU", (unsigned)vr[i]);
        shifts[i] = 0.0;
    }
    return fmi3OK;
}

/* The clock's interval and shift are constant and decimal: none of these applies. */
#define NOT_THIS_CLOCK(function)                                                                    \
    {                                                                                               \
        ENTER(instance, ANY_MODE, #function);                                                       \
        return FAIL(#function ": the clock 'sample' has a constant decimal interval and shift (none, "    \
                    "without --clock)");                                                            \
    }
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[],
                                   fmi3UInt64 r[], fmi3IntervalQualifier q[]) {
    (void)vr, (void)n, (void)c, (void)r, (void)q;
    NOT_THIS_CLOCK(fmi3GetIntervalFraction)
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[], fmi3UInt64 r[]) {
    (void)vr, (void)n, (void)c, (void)r;
    NOT_THIS_CLOCK(fmi3GetShiftFraction)
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 i[]) {
    (void)vr, (void)n, (void)i;
    NOT_THIS_CLOCK(fmi3SetIntervalDecimal)
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[],
                                   const fmi3UInt64 r[]) {
    (void)vr, (void)n, (void)c, (void)r;
    NOT_THIS_CLOCK(fmi3SetIntervalFraction)
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 s[]) {
    (void)vr, (void)n, (void)s;
    NOT_THIS_CLOCK(fmi3SetShiftDecimal)
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[],
                                const fmi3UInt64 r[]) {
    (void)vr, (void)n, (void)c, (void)r;
    NOT_THIS_CLOCK(fmi3SetShiftFraction)
}
