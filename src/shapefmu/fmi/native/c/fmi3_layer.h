/* Shared by the two files of the generic FMI 3.0 layer only (fmi3_layer.c, fmi3_layer_me.c): the
 * layer's data of an instance, its value references, and the entry guards. Model parts include
 * model.h, not this.
 *
 * Value references. FMI 3.0 numbers variables, not values, and has arrays; the contract
 * (model.h) numbers values ("slots"). The layer lists the contract's variables by slot, Real,
 * Integer, Boolean, String, and makes one FMI 3.0 variable of each, except that the elements
 * base[1], base[2], ... of a parameter of one type become the array parameter base (in the order they come, even when
 * another array's elements come between them, as a Shaper's f[i] and zeta[i] do). Value reference 0 is
 * time, the independent variable; the k-th variable of that list has value reference k. A model
 * part's own "time" slot (the plants keep time in slot 0) is time, not another variable.
 * shapefmu.fmi.description.fmi3 numbers the modelDescription.xml the same way.
 */
#ifndef FMI3_LAYER_H
#define FMI3_LAYER_H

#include "fmi3Functions.h"
#include "layer_core.h"

typedef struct {
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log;
    size_t n_variables;   /* value references 1 .. n_variables */
    size_t *first;        /* n_variables + 1 offsets into slots: variable k's elements are */
    size_t *slots;        /* slots[first[k - 1] .. first[k] - 1] */
    ValueType *types;      /* of each variable */
    size_t *scalar;       /* of each variable: its slot if it has one element, else SIZE_MAX (the fast path) */
    size_t period_slot;   /* the sample period's slot (Ts_used, else Ts), for the clock; SIZE_MAX: none */
    int clocked;          /* a Co-Simulation instance of an FMU built with --clock */
} Fmi3Layer;

#define ENTER(instance, allowed, function) GUARD(instance, allowed, function, fmi3Error)
#define ENTER_ARRAY(pointer, count, function) GUARD_ARRAY(pointer, count, function, fmi3Error)
#define FAIL(...) ((fmi3Status)model_fail(inst, __VA_ARGS__))

static inline Fmi3Layer *layer_of(const ModelInstance *inst) { return (Fmi3Layer *)inst->layer; }

/* The slot of scalar variable vr of the given type; logs and returns 0 if vr is none (or time, or
 * an array). */
int fmi3_scalar_slot(ModelInstance *inst, fmi3ValueReference vr, ValueType type, size_t *slot, const char *function);

/* The input clock (fmi3_layer_clock.c): whether this build has one (Fmi3Layer.clocked says it for an
 * instance); its checks at the exit of initialisation (Ts is the declared interval; then Event Mode,
 * the tick at t0), before a step of a clocked instance and before the return to Step Mode (the tick
 * the FMU stands on was taken). */
int fmi3_clocked(void);
fmi3Status fmi3_clock_start(ModelInstance *inst, const char *function);
fmi3Status fmi3_clock_before_step(ModelInstance *inst, double t, double h);
/* After a step of a clocked instance: its position on the clock's grid moves with it. */
void fmi3_clock_after_step(ModelInstance *inst, double t, double h);
fmi3Status fmi3_clock_before_step_mode(ModelInstance *inst);

#endif
