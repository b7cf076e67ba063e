/* Closed-form impulse shapers designed in C (the native Shaper FMU re-designs them when its mode
 * parameters change before initialisation), and the mapping of impulses onto the sample grid.
 * The same formulas as runtime/impulse_formulas.py and runtime/shaper_designs.py. */
#ifndef SHAPER_DESIGNS_H
#define SHAPER_DESIGNS_H

typedef enum { KIND_ZV, KIND_ZVD, KIND_ZVDD, KIND_ZV_DN, KIND_MZV, KIND_NOT_CLOSED_FORM } ClosedFormKind;

/* The closed-form kind named kind, or KIND_NOT_CLOSED_FORM. */
ClosedFormKind closed_form_kind(const char *kind);

/* Impulses of one mode before merging: n + 2 for the ZV family (n the derivative order), 3 for MZV. */
int impulses_per_mode(ClosedFormKind kind, int n);

/* The shaper of kind for n_modes modes (omega rad/s, zeta), convolved over the modes, sorted and
 * with coincident impulses merged (shaper_designs.design_impulses). Writes at most capacity
 * impulses into times / amplitudes, using scratch (2 * capacity doubles); returns their count, or
 * -1 if the unmerged count exceeds capacity. */
int design_closed_form(ClosedFormKind kind, int n, int n_modes, const double *omega, const double *zeta,
                       double *times, double *amplitudes, int capacity, double *scratch);

/* Centroid-preserving split of an impulse at t onto the grid k ts (runtime/shaper_filter.py,
 * grid_impulses): weight (1 - alpha) at delay *k and alpha at *k + 1; returns alpha. */
double grid_split(double t, double ts, long *k);

#endif
