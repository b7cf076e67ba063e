/* Python's math.fsum in C (exact_sum.h): Shewchuk's exact partials, rounded once, as CPython's
 * mathmodule.c does it (finite inputs only: the callers' are). */
#include <math.h>

#include "exact_sum.h"

double exact_sum(const double *x, int n) {
    double partials[128];
    int used = 0;
    for (int k = 0; k < n; k++) {
        double value = x[k];
        int i = 0;
        for (int j = 0; j < used; j++) {
            double y = partials[j];
            if (fabs(value) < fabs(y)) {
                const double swap = value;
                value = y, y = swap;
            }
            const double hi = value + y, lo = y - (hi - value);
            if (lo != 0.0) partials[i++] = lo;
            value = hi;
        }
        used = i;
        partials[used++] = value;
    }
    double hi = 0.0;
    if (used > 0) {
        double lo = 0.0;
        hi = partials[--used];
        while (used > 0) {
            const double value = hi, y = partials[--used];
            hi = value + y;
            lo = y - (hi - value);
            if (lo != 0.0) break;
        }
        if (used > 0 && ((lo < 0.0 && partials[used - 1] < 0.0) || (lo > 0.0 && partials[used - 1] > 0.0))) {
            const double y = lo * 2.0, value = hi + y;
            if (y == value - hi) hi = value;
        }
    }
    return hi;
}
