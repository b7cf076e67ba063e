/* The model of TypedStair, shared by its FMI 2.0 (typed_stair.c) and FMI 3.0 (typed_stair3.c)
 * wrappers: the whole state is plain data (an FMU state is a copy of it), and compute() sets every
 * output from the inputs, the parameters and the time (see typed_stair.c for the closed forms).
 *
 * Exporter behaviours, each chosen at compile time so one model gives the FMUs that behave as other
 * tools' FMUs do (tests/support/c_fmus.py builds them; tests/test_cosim_exporters.py runs them):
 *   QUIRK_PROVISIONAL    a Co-Simulation step with noSetFMUStatePriorToCurrentPoint = false may be
 *                        discarded (FMI 2.0 sec. 4.2.2, FMI 3.0 sec. 4.2.1), so the FMU keeps its last
 *                        confirmed state: such a step starts again from it, and only a step called
 *                        with true confirms the state reached (the OSP quarter-truck Wheel does this);
 *   QUIRK_RESET_IN_SETUP fmi2SetupExperiment resets every variable to its start value (a 20-sim
 *                        export does): values set before it are lost.
 * Always, as the standards require: in Model Exchange, discrete inputs (r_in, n_in, e_in, b_in, s_in
 * and the FMI 3.0 integers) can be set only in initialization mode and event mode (FMI 2.0 sec.
 * 3.2.3, FMI 3.0 sec. 3.2.2); a set in continuous-time mode is refused with fmi2Error/fmi3Error. */
#ifndef TYPED_STAIR_MODEL_H
#define TYPED_STAIR_MODEL_H

#include <math.h>
#include <stdio.h>
#include <string.h>

#define TEXT 256

enum { VR_X_IN = 0, VR_X_OUT, VR_PERIOD, VR_STOP_AT, VR_LEVEL, VR_DER_LEVEL, VR_R_IN, VR_R_OUT, N_REAL };
/* steps and provisional_steps count the Co-Simulation steps taken and those called with
 * noSetFMUStatePriorToCurrentPoint = false (part of the state: a rolled-back step is not counted). */
enum { VR_INCREMENT = 0, VR_N_IN, VR_COUNTER, VR_N_OUT, VR_MODE, VR_E_IN, VR_E_OUT, VR_STEPS, VR_PROVISIONAL, N_INTEGER };
enum { VR_NEGATE = 0, VR_B_IN, VR_B_OUT, N_BOOLEAN };
enum { VR_LABEL = 0, VR_S_IN, VR_S_OUT, N_STRING };

/* The FMI 3.0 integer types besides Int32 (typed_stair3.c): wide_out[i] = wide_in[i], as bit patterns. */
enum { W_INT8 = 0, W_UINT8, W_INT16, W_UINT16, W_UINT32, W_INT64, W_UINT64, N_WIDE };

typedef struct {
    double real[N_REAL];
    int integer[N_INTEGER];
    unsigned long long wide_in[N_WIDE];
    unsigned long long wide_out[N_WIDE];
    int boolean[N_BOOLEAN];
    char string[N_STRING][TEXT];
    double time;
    double committed_level;  /* QUIRK_PROVISIONAL: the level at the last confirmed point */
    int terminated;
    int initialized;
} State;

/* The FMI state machine as far as TypedStair checks it (FMI 2.0 sec. 3.2.3 and 4.2.4, FMI 3.0 sec. 3.2
 * and 4.2): discrete inputs of a Model Exchange instance wait for event mode. */
enum { INSTANTIATED, INITIALIZATION, EVENT, CONTINUOUS, STEPPING };

static const double EPS = 1e-9;

/* Number of period boundaries j * period (j >= 1) reached at time t. */
static inline long boundaries(const State *s, double t) { return (long)floor(t / s->real[VR_PERIOD] + EPS); }

static inline void compute(State *s) {
    const int sign = s->integer[VR_MODE] == 1 ? 1 : -1;
    s->integer[VR_COUNTER] = sign * s->integer[VR_INCREMENT] * (int)boundaries(s, s->time);
    s->real[VR_X_OUT] = s->real[VR_X_IN] + s->integer[VR_COUNTER];
    s->real[VR_DER_LEVEL] = s->real[VR_X_IN];
    s->real[VR_R_OUT] = s->real[VR_R_IN] + s->integer[VR_COUNTER];
    s->integer[VR_N_OUT] = 2 * s->integer[VR_N_IN] + s->integer[VR_COUNTER];
    s->integer[VR_E_OUT] = 3 - s->integer[VR_E_IN];
    s->boolean[VR_B_OUT] = s->boolean[VR_B_IN] != s->boolean[VR_NEGATE];
    snprintf(s->string[VR_S_OUT], TEXT, "%.120s:%.120s", s->string[VR_LABEL], s->string[VR_S_IN]);
    memcpy(s->wide_out, s->wide_in, sizeof s->wide_out);
}

/* One Co-Simulation step's start: count it, and under QUIRK_PROVISIONAL pick the state it starts from. */
static inline void begin_step(State *s, int no_set_prior) {
    s->integer[VR_STEPS] += 1;
    if (!no_set_prior) s->integer[VR_PROVISIONAL] += 1;
#ifdef QUIRK_PROVISIONAL
    if (no_set_prior)
        s->committed_level = s->real[VR_LEVEL];  /* no rollback before t: the state at t is final */
    else
        s->real[VR_LEVEL] = s->committed_level;  /* this step may be discarded: start again from the last confirmed state */
#endif
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

/* Leaving initialisation: the start state is confirmed. */
static inline void initialized(State *s) {
    s->initialized = 1;
    s->committed_level = s->real[VR_LEVEL];
    compute(s);
}

static inline int reached(const State *s, double t) { return t >= s->real[VR_STOP_AT] - EPS * fmax(1.0, fabs(t)); }

#endif
