/*
 * The FMU state entry points of the front end (fmi2_shim.c has the others): fmi2GetFMUstate,
 * fmi2SetFMUstate, fmi2FreeFMUstate and the serialisation.
 *
 * A state saved by the export library holds the slave's variables, time and phase, not the front
 * end's state machine (fmi2_shim.c, 6.). FMI 2.0 has fmi2SetFMUstate bring back the FMU as it was
 * when the state was saved, so the host gets a Saved: the export library's state and the mode it
 * was taken in, which fmi2SetFMUstate restores. Serialised, a state is the 8-byte header "SFMU",
 * the mode, three zero bytes, then the export library's bytes; fmi2DeSerializeFMUstate refuses
 * bytes without it. No state is saved in the error state (there is nothing sound to save), so the
 * error state is never restored. The checks the export library would crash on are made here too: a
 * NULL state or buffer, a buffer smaller than fmi2SerializedFMUstateSize, and a state this front end
 * did not save (another FMU's, or a pointer that is no state): a Saved carries a mark and the GUID of
 * its FMU, and one without them is refused with fmi2Error rather than handed to the export library.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2_shim.h"

#define EXPORT __attribute__((visibility("default")))

#define HEADER_SIZE 8
static const char MAGIC[4] = {'S', 'F', 'M', 'U'};

#define SAVED_MAGIC 0x53464d5553746174ULL /* "SFMUStat" */

typedef struct {
    unsigned long long magic;
    const char* guid;   /* this FMU's SHIM_GUID: the address of the string in this library */
    fmi2FMUstate inner; /* the export library's state */
    Mode mode;
} Saved;

/* state as a Saved of this FMU, or NULL. */
static Saved* ours(fmi2FMUstate state)
{
    Saved* saved = (Saved*)state;
    return saved != NULL && saved->magic == SAVED_MAGIC && saved->guid == SHIM_GUID && saved->inner != NULL ? saved : NULL;
}

static Saved* new_saved(void)
{
    Saved* saved = (Saved*)calloc(1, sizeof(Saved));
    if (saved != NULL) {
        saved->magic = SAVED_MAGIC;
        saved->guid = SHIM_GUID;
    }
    return saved;
}

EXPORT fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Saved* saved;
    fmi2Status status;
    BEGIN(c, ANY_MODE & ~ERROR_STATE);
    if (state == NULL) return refuse(s, "fmi2GetFMUstate: NULL state pointer");
    /* FMI 2.0: a non-NULL *state is a state of this instance to update. */
    saved = (Saved*)*state;
    if (saved == NULL) {
        saved = new_saved();
        if (saved == NULL) return refuse(s, "fmi2GetFMUstate: out of memory");
    } else if (ours(saved) == NULL) {
        return refuse(s, "fmi2GetFMUstate: *FMUstate is neither NULL nor a state of this FMU");
    } else {
        inner.FreeFMUstate(s->component, &saved->inner);
        saved->inner = NULL;
    }
    status = merge(s, inner.GetFMUstate(s->component, &saved->inner));
    if (saved->inner == NULL) {
        free(saved);
        *state = NULL;
        return status > fmi2Warning ? status : refuse(s, "fmi2GetFMUstate: the FMU returned no state");
    }
    saved->mode = s->mode;
    *state = saved;
    return status;
}

EXPORT fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    Saved* saved = ours(state);
    fmi2Status status;
    BEGIN(c, ANY_MODE);
    if (saved == NULL) return refuse(s, "fmi2SetFMUstate: NULL, or not a state of this FMU");
    status = merge(s, inner.SetFMUstate(s->component, saved->inner));
    if (status <= fmi2Warning) s->mode = saved->mode;
    return status;
}

EXPORT fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate* state)
{
    Saved* saved;
    fmi2Status status = fmi2OK;
    BEGIN(c, ANY_MODE);
    if (state == NULL || *state == NULL) return fmi2OK;
    saved = ours(*state);
    if (saved == NULL) return refuse(s, "fmi2FreeFMUstate: not a state of this FMU");
    status = merge(s, inner.FreeFMUstate(s->component, &saved->inner));
    saved->magic = 0;
    free(saved);
    *state = NULL;
    return status;
}

EXPORT fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t* size)
{
    Saved* saved = ours(state);
    fmi2Status status;
    BEGIN(c, ANY_MODE);
    if (saved == NULL || size == NULL) {
        return refuse(s, "fmi2SerializedFMUstateSize: NULL size, or a state that is none of this FMU");
    }
    status = merge(s, inner.SerializedFMUstateSize(s->component, saved->inner, size));
    if (status <= fmi2Warning) *size += HEADER_SIZE;
    return status;
}

EXPORT fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte serializedState[], size_t size)
{
    Saved* saved = ours(state);
    size_t needed = 0;
    fmi2Status status;
    BEGIN(c, ANY_MODE);
    if (saved == NULL || serializedState == NULL) {
        return refuse(s, "fmi2SerializeFMUstate: NULL buffer, or a state that is none of this FMU");
    }
    status = inner.SerializedFMUstateSize(s->component, saved->inner, &needed);
    if (status > fmi2Warning) return merge(s, status);
    if (size < needed + HEADER_SIZE) return refuse(s, "fmi2SerializeFMUstate: buffer smaller than fmi2SerializedFMUstateSize");
    memcpy(serializedState, MAGIC, sizeof(MAGIC));
    memset(serializedState + sizeof(MAGIC), 0, HEADER_SIZE - sizeof(MAGIC));
    serializedState[sizeof(MAGIC)] = (fmi2Byte)saved->mode;
    return merge(s, inner.SerializeFMUstate(s->component, saved->inner, serializedState + HEADER_SIZE, needed));
}

/* The mode recorded in a serialised state's header, or 0 if the bytes do not start with one. */
static Mode header_mode(const fmi2Byte bytes[], size_t size)
{
    static const char zeros[HEADER_SIZE - sizeof(MAGIC) - 1] = {0};
    Mode mode;
    if (size < HEADER_SIZE || memcmp(bytes, MAGIC, sizeof(MAGIC)) != 0) return (Mode)0;
    if (memcmp(bytes + sizeof(MAGIC) + 1, zeros, sizeof(zeros)) != 0) return (Mode)0;
    mode = (Mode)(unsigned char)bytes[sizeof(MAGIC)];
    return mode == INSTANTIATED || mode == INITIALIZATION || mode == STEP_COMPLETE || mode == TERMINATED ? mode : (Mode)0;
}

EXPORT fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size, fmi2FMUstate* state)
{
    Saved* saved;
    fmi2Status status;
    Mode mode;
    BEGIN(c, ANY_MODE);
    if (serializedState == NULL || state == NULL) return refuse(s, "fmi2DeSerializeFMUstate: NULL buffer or state");
    mode = header_mode(serializedState, size);
    if (mode == 0) {
        return refuse(s, "fmi2DeSerializeFMUstate: these bytes are not a state written by fmi2SerializeFMUstate of "
            "this FMU (no SFMU header)");
    }
    saved = new_saved();
    if (saved == NULL) return refuse(s, "fmi2DeSerializeFMUstate: out of memory");
    status = merge(s, inner.DeSerializeFMUstate(s->component, serializedState + HEADER_SIZE, size - HEADER_SIZE,
        &saved->inner));
    if (saved->inner == NULL) {
        free(saved);
        return status > fmi2Warning ? status : refuse(s, "fmi2DeSerializeFMUstate: the FMU returned no state");
    }
    saved->mode = mode;
    *state = saved;
    return status;
}
