/* What the hand-written FMI 3.0 test FMUs (typed_stair3.c, array_gain3.c) do alike: an instance is
 * one malloc'ed block, logging has nothing to switch, and Scheduled Execution, binaries, clocks,
 * dependency queries, directional and adjoint derivatives, configuration mode, clock intervals and
 * shifts, model partitions and output derivatives are not provided: each of those refuses through
 * the includer's refuse(instance, function, why), which logs and returns fmi3Error. */
#ifndef FMI3_COMMON_H
#define FMI3_COMMON_H

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String name, fmi3String token, fmi3String resources, fmi3Boolean visible,
                                               fmi3Boolean logging, fmi3InstanceEnvironment environment,
                                               fmi3LogMessageCallback log, fmi3ClockUpdateCallback clock,
                                               fmi3LockPreemptionCallback lock, fmi3UnlockPreemptionCallback unlock) {
    (void)name; (void)token; (void)resources; (void)visible; (void)logging; (void)environment; (void)log;
    (void)clock; (void)lock; (void)unlock;
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }
const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n, const fmi3String categories[]) {
    (void)on; (void)n; (void)categories;
    return instance == NULL ? fmi3Error : fmi3OK;
}

#define NOT_PROVIDED(function, ...) { __VA_ARGS__; return refuse(instance, #function, "not provided"); }
fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, size_t z[], fmi3Binary v[], size_t m)
    NOT_PROVIDED(fmi3GetBinary, (void)vr; (void)n; (void)z; (void)v; (void)m)
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const size_t z[], const fmi3Binary v[], size_t m)
    NOT_PROVIDED(fmi3SetBinary, (void)vr; (void)n; (void)z; (void)v; (void)m)
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Clock v[])
    NOT_PROVIDED(fmi3GetClock, (void)vr; (void)n; (void)v)
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Clock v[])
    NOT_PROVIDED(fmi3SetClock, (void)vr; (void)n; (void)v)
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr, size_t *n)
    NOT_PROVIDED(fmi3GetNumberOfVariableDependencies, (void)vr; (void)n)
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference d, size_t a[], fmi3ValueReference b[],
                                       size_t c[], fmi3DependencyKind k[], size_t n)
    NOT_PROVIDED(fmi3GetVariableDependencies, (void)d; (void)a; (void)b; (void)c; (void)k; (void)n)
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference u[], size_t nu, const fmi3ValueReference k[],
                                        size_t nk, const fmi3Float64 s[], size_t ns, fmi3Float64 r[], size_t nr)
    NOT_PROVIDED(fmi3GetDirectionalDerivative, (void)u; (void)nu; (void)k; (void)nk; (void)s; (void)ns; (void)r; (void)nr)
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference u[], size_t nu, const fmi3ValueReference k[],
                                    size_t nk, const fmi3Float64 s[], size_t ns, fmi3Float64 r[], size_t nr)
    NOT_PROVIDED(fmi3GetAdjointDerivative, (void)u; (void)nu; (void)k; (void)nk; (void)s; (void)ns; (void)r; (void)nr)
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) NOT_PROVIDED(fmi3EnterConfigurationMode, (void)0)
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) NOT_PROVIDED(fmi3ExitConfigurationMode, (void)0)
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 i[], fmi3IntervalQualifier q[])
    NOT_PROVIDED(fmi3GetIntervalDecimal, (void)vr; (void)n; (void)i; (void)q)
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[], fmi3UInt64 r[],
                                   fmi3IntervalQualifier q[])
    NOT_PROVIDED(fmi3GetIntervalFraction, (void)vr; (void)n; (void)c; (void)r; (void)q)
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 s[])
    NOT_PROVIDED(fmi3GetShiftDecimal, (void)vr; (void)n; (void)s)
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[], fmi3UInt64 r[])
    NOT_PROVIDED(fmi3GetShiftFraction, (void)vr; (void)n; (void)c; (void)r)
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 i[])
    NOT_PROVIDED(fmi3SetIntervalDecimal, (void)vr; (void)n; (void)i)
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[], const fmi3UInt64 r[])
    NOT_PROVIDED(fmi3SetIntervalFraction, (void)vr; (void)n; (void)c; (void)r)
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 s[])
    NOT_PROVIDED(fmi3SetShiftDecimal, (void)vr; (void)n; (void)s)
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[], const fmi3UInt64 r[])
    NOT_PROVIDED(fmi3SetShiftFraction, (void)vr; (void)n; (void)c; (void)r)
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference c, fmi3Float64 t)
    NOT_PROVIDED(fmi3ActivateModelPartition, (void)c; (void)t)
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Int32 o[],
                                    fmi3Float64 v[], size_t m)
    NOT_PROVIDED(fmi3GetOutputDerivatives, (void)vr; (void)n; (void)o; (void)v; (void)m)

#endif
