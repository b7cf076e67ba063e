/* The liveness tag of instances (fmu_liveness.h). */
#include <stdio.h>

#include "fmu_liveness.h"

/* Arbitrary 64-bit patterns, unlikely as a pointer or a double an allocator leaves behind. */
#define LIVE_TAG 0x5348415045464d55ULL /* "SHAPEFMU" */
#define DEAD_TAG 0x4652454544464d55ULL /* "FREEDFMU" */

static unsigned long long *tag(const void *instance) { return (unsigned long long *)instance; }

void fmu_mark_live(void *instance) { *tag(instance) = LIVE_TAG; }

int fmu_mark_freed(const void *instance) {
    if (instance == NULL || *tag(instance) != LIVE_TAG) return 0;
    *tag(instance) = DEAD_TAG;
    return 1;
}

int fmu_is_live(const void *instance, const char *function) {
    if (instance != NULL && *tag(instance) == LIVE_TAG) return 1;
    fprintf(stderr, "shapefmu FMU: %s called on an instance that is not live (already freed?)\n", function);
    return 0;
}
