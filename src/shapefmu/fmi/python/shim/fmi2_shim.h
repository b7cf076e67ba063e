/*
 * What the two halves of the FMU's C front end share: fmi2_shim.c (the FMI 2.0 entry points) and
 * python_runtime.c (libpython, the interpreter, pythonfmu's export library, the teardown).
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

/* Make libpython global, start the interpreter if nobody has, load the export library: 1 when
 * done (once per load of the front end; thread-safe), else 0 with the reason in why. */
int runtime_load(char* why, size_t why_size);

/* 1 while the process's interpreter can serve a call (it is initialised and not finalised). */
int runtime_alive(void);

#endif
