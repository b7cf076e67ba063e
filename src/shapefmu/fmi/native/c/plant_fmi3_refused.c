/* The FMI 3.0 functions a plant FMU does not provide: variables of other types than Float64,
 * clocks, binaries, configuration mode, adjoint derivatives, model partitions and output
 * derivatives. Each logs why and returns fmi3Error (an empty request of a getter or setter is fine). */
#include "plant_fmi3.h"

/* The plant has Float64 variables only: every other getter and setter refuses a non-empty request. */
#define NO_VARIABLES(TYPE, CONST)                                                                   \
    fmi3Status fmi3Get##TYPE(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3##TYPE values[], size_t nValues) { \
        ENTER(instance, ANY_MODE, "fmi3Get" #TYPE);                                                 \
        (void)vr; (void)values; (void)nValues;                                                      \
        return nvr == 0 ? fmi3OK : fail(p, "fmi3Get" #TYPE ": this FMU has no " #TYPE " variables"); \
    }                                                                                               \
    fmi3Status fmi3Set##TYPE(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, CONST fmi3##TYPE values[], size_t nValues) { \
        ENTER(instance, ANY_MODE, "fmi3Set" #TYPE);                                                 \
        (void)vr; (void)values; (void)nValues;                                                      \
        return nvr == 0 ? fmi3OK : fail(p, "fmi3Set" #TYPE ": this FMU has no " #TYPE " variables"); \
    }
NO_VARIABLES(Float32, const)
NO_VARIABLES(Int8, const)
NO_VARIABLES(UInt8, const)
NO_VARIABLES(Int16, const)
NO_VARIABLES(UInt16, const)
NO_VARIABLES(Int32, const)
NO_VARIABLES(UInt32, const)
NO_VARIABLES(Int64, const)
NO_VARIABLES(UInt64, const)
NO_VARIABLES(Boolean, const)
NO_VARIABLES(String, const)

/* What the plant does not provide: clocks, binaries, configuration, adjoints, partitions. */
#define REFUSE(function, ...) { ENTER(instance, ANY_MODE, #function); __VA_ARGS__; return fail(p, #function ": not provided by the plant FMU"); }
fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t sizes[], fmi3Binary values[], size_t n)
    REFUSE(fmi3GetBinary, (void)vr; (void)nvr; (void)sizes; (void)values; (void)n)
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t sizes[], const fmi3Binary values[], size_t n)
    REFUSE(fmi3SetBinary, (void)vr; (void)nvr; (void)sizes; (void)values; (void)n)
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[])
    REFUSE(fmi3GetClock, (void)vr; (void)nvr; (void)values)
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[])
    REFUSE(fmi3SetClock, (void)vr; (void)nvr; (void)values)
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference vr, size_t *n)
    REFUSE(fmi3GetNumberOfVariableDependencies, (void)vr; (void)n)
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent, size_t a[], fmi3ValueReference b[],
                                       size_t c[], fmi3DependencyKind d[], size_t n)
    REFUSE(fmi3GetVariableDependencies, (void)dependent; (void)a; (void)b; (void)c; (void)d; (void)n)
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference u[], size_t nu, const fmi3ValueReference k[],
                                    size_t nk, const fmi3Float64 seed[], size_t ns, fmi3Float64 s[], size_t n)
    REFUSE(fmi3GetAdjointDerivative, (void)u; (void)nu; (void)k; (void)nk; (void)seed; (void)ns; (void)s; (void)n)
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) REFUSE(fmi3EnterConfigurationMode, (void)0)
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) REFUSE(fmi3ExitConfigurationMode, (void)0)
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 i[], fmi3IntervalQualifier q[])
    REFUSE(fmi3GetIntervalDecimal, (void)vr; (void)n; (void)i; (void)q)
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[], fmi3UInt64 r[],
                                   fmi3IntervalQualifier q[])
    REFUSE(fmi3GetIntervalFraction, (void)vr; (void)n; (void)c; (void)r; (void)q)
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3Float64 s[])
    REFUSE(fmi3GetShiftDecimal, (void)vr; (void)n; (void)s)
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, fmi3UInt64 c[], fmi3UInt64 r[])
    REFUSE(fmi3GetShiftFraction, (void)vr; (void)n; (void)c; (void)r)
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 i[])
    REFUSE(fmi3SetIntervalDecimal, (void)vr; (void)n; (void)i)
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[],
                                   const fmi3UInt64 r[])
    REFUSE(fmi3SetIntervalFraction, (void)vr; (void)n; (void)c; (void)r)
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3Float64 s[])
    REFUSE(fmi3SetShiftDecimal, (void)vr; (void)n; (void)s)
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t n, const fmi3UInt64 c[], const fmi3UInt64 r[])
    REFUSE(fmi3SetShiftFraction, (void)vr; (void)n; (void)c; (void)r)
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clock, fmi3Float64 time)
    REFUSE(fmi3ActivateModelPartition, (void)clock; (void)time)
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t n)
    REFUSE(fmi3GetOutputDerivatives, (void)vr; (void)nvr; (void)orders; (void)values; (void)n)

