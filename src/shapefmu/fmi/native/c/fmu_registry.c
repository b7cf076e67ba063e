/* The liveness tag of instances (fmu_registry.h). */
#include <stdio.h>

#include "fmu_registry.h"

/* Arbitrary 64-bit patterns, unlikely as a pointer or a double an allocator leaves behind. */
#define LIVE_TAG 0x5348415045464d55ULL /* "SHAPEFMU" */
#define DEAD_TAG 0x4652454544464d55ULL /* "FREEDFMU" */

static unsigned long long *tag(const void *instance) { return (unsigned long long *)instance; }

int fmu_registry_add(const void *instance) {
    *tag(instance) = LIVE_TAG;
    return 0;
}

int fmu_registry_remove(const void *instance) {
    if (instance == NULL || *tag(instance) != LIVE_TAG) return 0;
    *tag(instance) = DEAD_TAG;
    return 1;
}

int fmu_registry_live(const void *instance, const char *function) {
    if (instance != NULL && *tag(instance) == LIVE_TAG) return 1;
    fprintf(stderr, "shapefmu FMU: %s called on an instance that is not live (already freed?)\n", function);
    return 0;
}
