/* The model of TypedStair, shared by its FMI 2.0 (typed_stair.c) and FMI 3.0 (typed_stair3.c)
 * wrappers: the whole state is plain data (an FMU state is a copy of it), and compute() sets every
 * output from the inputs, the parameters and the time (see typed_stair.c for the closed forms). */
#ifndef TYPED_STAIR_MODEL_H
#define TYPED_STAIR_MODEL_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#define TEXT 256

enum { VR_X_IN = 0, VR_X_OUT, VR_PERIOD, VR_STOP_AT, VR_LEVEL, VR_DER_LEVEL, N_REAL };
enum { VR_INCREMENT = 0, VR_N_IN, VR_COUNTER, VR_N_OUT, VR_MODE, VR_E_IN, VR_E_OUT, N_INTEGER };
enum { VR_NEGATE = 0, VR_B_IN, VR_B_OUT, N_BOOLEAN };
enum { VR_LABEL = 0, VR_S_IN, VR_S_OUT, N_STRING };

typedef struct {
    double real[N_REAL];
    int integer[N_INTEGER];
    int boolean[N_BOOLEAN];
    char string[N_STRING][TEXT];
    double time;
    int terminated;
    int initialized;
} State;

static const double EPS = 1e-9;

/* Number of period boundaries j * period (j >= 1) reached at time t. */
static inline long boundaries(const State *s, double t) { return (long)floor(t / s->real[VR_PERIOD] + EPS); }

static inline void compute(State *s) {
    const int sign = s->integer[VR_MODE] == 1 ? 1 : -1;
    s->integer[VR_COUNTER] = sign * s->integer[VR_INCREMENT] * (int)boundaries(s, s->time);
    s->real[VR_X_OUT] = s->real[VR_X_IN] + s->integer[VR_COUNTER];
    s->real[VR_DER_LEVEL] = s->real[VR_X_IN];
    s->integer[VR_N_OUT] = 2 * s->integer[VR_N_IN] + s->integer[VR_COUNTER];
    s->integer[VR_E_OUT] = 3 - s->integer[VR_E_IN];
    s->boolean[VR_B_OUT] = s->boolean[VR_B_IN] != s->boolean[VR_NEGATE];
    snprintf(s->string[VR_S_OUT], TEXT, "%.120s:%.120s", s->string[VR_LABEL], s->string[VR_S_IN]);
}

static inline void start_values(State *s) {
    memset(s, 0, sizeof *s);
    s->real[VR_PERIOD] = 1.0;
    s->real[VR_STOP_AT] = 1e300;
    s->integer[VR_INCREMENT] = 1;
    s->integer[VR_MODE] = 1;
    s->integer[VR_E_IN] = 1;
    strcpy(s->string[VR_LABEL], "stair");
    compute(s);
}

static inline int reached(const State *s, double t) { return t >= s->real[VR_STOP_AT] - EPS * fmax(1.0, fabs(t)); }

#endif
