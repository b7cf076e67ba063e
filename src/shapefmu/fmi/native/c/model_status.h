/* The status a model part's hooks return (fmi2_model.h): FMI 2.0's fmi2Status, whose values FMI 3.0's
 * fmi3Status repeats (OK 0, Warning 1, Discard 2, Error 3, Fatal 4). The FMI 2.0 layer has it from
 * the standard's fmi2FunctionTypes.h, included first; a model part and the FMI 3.0 layer, compiled
 * without FMI 2.0's headers (an FMI 3.0 FMU's sources/ holds none), have the same enumeration from
 * here. */
#ifndef MODEL_STATUS_H
#define MODEL_STATUS_H

#ifndef fmi2FunctionTypes_h
typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
#endif

#endif
