/* The liveness tag of instances, and the ring of retired ones (fmu_liveness.h). */
#include <stdio.h>
#include <stdlib.h>

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

static void *retired[FMU_RETIRED];
static size_t next_retired;

void fmu_retire(void *instance) {
    const size_t slot = __atomic_fetch_add(&next_retired, 1, __ATOMIC_RELAXED) % FMU_RETIRED;
    free(__atomic_exchange_n(&retired[slot], instance, __ATOMIC_ACQ_REL));
}

__attribute__((destructor)) static void release_retired(void) {
    for (size_t i = 0; i < FMU_RETIRED; i++) free(__atomic_exchange_n(&retired[i], NULL, __ATOMIC_ACQ_REL));
}

int fmu_is_live(const void *instance, const char *function) {
    if (instance != NULL && *tag(instance) == LIVE_TAG) return 1;
    fprintf(stderr, "shapefmu FMU: %s called on an instance that is not live (already freed?)\n", function);
    return 0;
}
