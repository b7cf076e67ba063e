/* The registry of live instances (fmu_registry.h): an array of pointers behind a lock, and the
 * pointer last found live, which is always NULL or live (fmu_registry_remove clears it under the
 * lock before the instance's memory is released). A call on an instance after its fmi2FreeInstance
 * returned therefore never matches it; a call racing with the free of its own instance is the
 * host's error and is not guarded. The array is freed when the last instance goes, so a process
 * that frees its instances leaks nothing. */
#include <stdio.h>
#include <stdlib.h>

#include "fmu_registry.h"

#ifdef _WIN32
#include <windows.h>
static SRWLOCK lock = SRWLOCK_INIT;
#define LOCK() AcquireSRWLockExclusive(&lock)
#define UNLOCK() ReleaseSRWLockExclusive(&lock)
#else
#include <pthread.h>
static pthread_mutex_t lock = PTHREAD_MUTEX_INITIALIZER;
#define LOCK() pthread_mutex_lock(&lock)
#define UNLOCK() pthread_mutex_unlock(&lock)
#endif

/* The last-found pointer is read without the lock: an atomic load (relaxed is enough: a call made
 * after the free returned is ordered after it by the host, and coherence then shows it the cleared
 * value or a newer one). */
#if defined(__GNUC__) || defined(__clang__)
#define LOAD(p) __atomic_load_n(&(p), __ATOMIC_RELAXED)
#define STORE(p, v) __atomic_store_n(&(p), (v), __ATOMIC_RELAXED)
#else /* MSVC: aligned pointer loads and stores are atomic, volatile keeps them */
#define LOAD(p) (*(const void *volatile *)&(p))
#define STORE(p, v) (*(const void *volatile *)&(p) = (v))
#endif

static const void **live;
static size_t n_live, capacity;
static const void *last_found;

static size_t find(const void *instance) {
    size_t i = 0;
    while (i < n_live && live[i] != instance) i++;
    return i;
}

int fmu_registry_add(const void *instance) {
    int result = 0;
    LOCK();
    if (n_live == capacity) {
        const size_t grown = capacity ? 2 * capacity : 8;
        const void **bigger = realloc((void *)live, grown * sizeof *live);
        if (bigger == NULL) result = -1;
        else live = bigger, capacity = grown;
    }
    if (result == 0) live[n_live++] = instance;
    UNLOCK();
    return result;
}

int fmu_registry_remove(const void *instance) {
    LOCK();
    const size_t i = find(instance);
    const int was_live = i < n_live;
    if (was_live) live[i] = live[--n_live];
    if (LOAD(last_found) == instance) STORE(last_found, NULL);
    if (n_live == 0) {
        free((void *)live);
        live = NULL;
        capacity = 0;
    }
    UNLOCK();
    return was_live;
}

int fmu_registry_live(const void *instance, const char *function) {
    if (instance != NULL && instance == LOAD(last_found)) return 1;
    LOCK();
    const int found = instance != NULL && find(instance) < n_live;
    if (found) STORE(last_found, instance);
    UNLOCK();
    if (!found) {
        fprintf(stderr, "shapefmu FMU: %s called on an instance that is not live (already freed?)\n", function);
        fflush(stderr);
    }
    return found;
}
