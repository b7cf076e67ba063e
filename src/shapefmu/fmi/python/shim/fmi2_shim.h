/*
 * What the parts of the FMU's C front end share: fmi2_shim.c (the FMI 2.0 entry points and the
 * instance's state machine), fmu_states.c (the FMU state entry points) and python_runtime.c
 * (libpython, the interpreter, pythonfmu's export library, the teardown).
 *
 * The FMI 2.0 types come from the standard's own headers (fmi2FunctionTypes.h, fmi2TypesPlatform.h,
 * BSD-licensed), which the native FMUs use too: the builder compiles with -I on
 * shapefmu/fmi/native/c and records them beside these sources.
 */
#ifndef SHAPEFMU_FMI2_SHIM_H
#define SHAPEFMU_FMI2_SHIM_H

#include <stddef.h>

#include "fmi2FunctionTypes.h"

/* The export library's entry points, filled in by runtime_load. */
typedef struct {
    fmi2InstantiateTYPE* Instantiate;
    fmi2FreeInstanceTYPE* FreeInstance;
    fmi2SetupExperimentTYPE* SetupExperiment;
    fmi2EnterInitializationModeTYPE* EnterInitializationMode;
    fmi2ExitInitializationModeTYPE* ExitInitializationMode;
    fmi2TerminateTYPE* Terminate;
    fmi2ResetTYPE* Reset;
    fmi2GetRealTYPE* GetReal;
    fmi2GetIntegerTYPE* GetInteger;
    fmi2GetBooleanTYPE* GetBoolean;
    fmi2GetStringTYPE* GetString;
    fmi2SetRealTYPE* SetReal;
    fmi2SetIntegerTYPE* SetInteger;
    fmi2SetBooleanTYPE* SetBoolean;
    fmi2SetStringTYPE* SetString;
    fmi2GetFMUstateTYPE* GetFMUstate;
    fmi2SetFMUstateTYPE* SetFMUstate;
    fmi2FreeFMUstateTYPE* FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE* SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE* SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE* DeSerializeFMUstate;
    fmi2DoStepTYPE* DoStep;
} Inner;

extern Inner inner;

/* The instance's state in the FMI 2.0 co-simulation state machine (FMI 2.0.x, 4.2.4), as the
 * native FMUs name them. ERROR_STATE: an initialisation call or fmi2Reset answered fmi2Error. */
typedef enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION = 1 << 1,
    STEP_COMPLETE = 1 << 2,
    TERMINATED = 1 << 3,
    ERROR_STATE = 1 << 4
} Mode;

#define ANY_MODE (INSTANTIATED | INITIALIZATION | STEP_COMPLETE | TERMINATED | ERROR_STATE)

/* One live instance: the export library's instance, the host's callbacks, and ours. */
typedef struct {
    fmi2Component component;
    fmi2CallbackFunctions host;
    fmi2CallbackFunctions ours;
    fmi2Boolean logging_on;
    int error_logged; /* set by our logger when the slave logs fmi2Error or worse */
    int fatal;        /* the export library answered fmi2Fatal: its instance is released */
    Mode mode;
    char name[256];
} Shim;

/* What the host holds as its fmi2Component. fmi2FreeInstance frees the Shim and keeps this small
 * handle with shim = NULL for the life of the process, so that a host calling on an instance it
 * has freed (OMSimulator does, see fmi2_shim.c, 6.) is refused instead of reading freed memory. */
typedef struct {
    Shim* shim;
} Handle;

/* The live instance behind c if `function` may be called on it in one of the `allowed` modes;
 * else NULL, the refusal logged, and *refusal the status to return. */
Shim* admit(fmi2Component c, int allowed, const char* function, fmi2Status* refusal);

/* The status of a forwarded call: fmi2Error if the slave logged an error during it. */
fmi2Status merge(Shim* s, fmi2Status status);

/* Log message through the host's logger with fmi2Error; returns fmi2Error. */
fmi2Status refuse(Shim* s, const char* message);

#define BEGIN(c, allowed)                                                   \
    fmi2Status refusal_;                                                    \
    Shim* s = admit((c), (allowed), __func__, &refusal_);                   \
    if (s == NULL) return refusal_

/* Make libpython global, start the interpreter if nobody has, load the export library: 1 when
 * done (once per load of the front end; thread-safe), else 0 with the reason in why. */
int runtime_load(char* why, size_t why_size);

/* 1 while the process's interpreter can serve a call (it is initialised and not finalised). */
int runtime_alive(void);

#endif
