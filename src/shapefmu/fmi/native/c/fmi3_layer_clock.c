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
 * are counted in the instance (clock_ticks), and where it stands on the ticks' grid (clock_position)
 * is counted from its steps by the sample grid's rule (sample_clock.c), the rule the model part's
 * samples follow: so a host at t0 = 1.7e9, whose times are 2.4e-7 s apart and drift as it adds its
 * steps, ticks the clock where the model samples; FMU states save both.
 */
#include <math.h>
#include <string.h>

#include "fmi3_layer.h"

/* The interval of the clock, 0 for an FMU without one (fmi3_clock.c, generated). */
extern const double fmi3_clock_interval;

int fmi3_clocked(void) { return fmi3_clock_interval > 0.0; }

static fmi3ValueReference clock_reference(const ModelInstance *inst) {
    return (fmi3ValueReference)(layer_of(inst)->n_variables + 1);
}

/* The instant of tick k as a host at t0 + k Ts computes it (for messages). */
static double tick_time(const ModelInstance *inst, double k) { return inst->start_time + k * fmi3_clock_interval; }

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
    const GridPosition *at = &inst->clock_position;
    if (inst->clock_ticks < (double)at->k + 1.0)
        return FAIL("fmi3DoStep: the clock 'sample' was not ticked at t = %.17g (enter Event Mode and call fmi3SetClock "
                    "at every tick t0 + k Ts, Ts = %g)", tick_time(inst, (double)at->k), fmi3_clock_interval);
    if (!isfinite(h) || !(h > 0.0)) return fmi3OK;  /* the layer's own checks answer it */
    const GridStep step = grid_step(at, fmi3_clock_interval, t, h);
    if (step.count > 1.0 || (step.count == 1.0 && step.since != 0.0))
        return FAIL("fmi3DoStep: the step from %.17g to %.17g passes the tick of the clock 'sample' at %.17g; end the "
                    "step there, enter Event Mode and tick the clock", t, t + h, tick_time(inst, (double)at->k + 1.0));
    return fmi3OK;
}

void fmi3_clock_after_step(ModelInstance *inst, double t, double h) {
    if (!layer_of(inst)->clocked || !(h > 0.0)) return;
    const GridStep step = grid_step(&inst->clock_position, fmi3_clock_interval, t, h);
    grid_take(&inst->clock_position, &step);
}

fmi3Status fmi3_clock_before_step_mode(ModelInstance *inst) {
    if (!layer_of(inst)->clocked || inst->clock_ticks >= (double)inst->clock_position.k + 1.0) return fmi3OK;
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
        const GridPosition *at = &inst->clock_position;
        if (at->since != 0.0)
            return FAIL("fmi3SetClock: the clock 'sample' ticks at t0 + k Ts (Ts = %g), not at t = %.17g: the steps "
                        "since t0 = %.17g add up to %.17g s after the tick at %.17g", fmi3_clock_interval, inst->time,
                        inst->start_time, at->since, tick_time(inst, (double)at->k));
        if (inst->clock_ticks < (double)at->k)
            return FAIL("fmi3SetClock: the ticks before t = %.17g were not taken (%.0f of %lld)", inst->time,
                        inst->clock_ticks, at->k);
        inst->clock_ticks = (double)at->k + 1.0;
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
