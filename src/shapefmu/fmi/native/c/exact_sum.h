/* Python's math.fsum (exact_sum.c): the correctly rounded sum of x[0..n), which the design layer's
 * Python uses where a sum must not depend on its order (shaped_bang_bang, stos_curves). */
#ifndef EXACT_SUM_H
#define EXACT_SUM_H

/* The sum of the n finite doubles x, correctly rounded; at most a few dozen partials are kept. */
double exact_sum(const double *x, int n);

#endif
