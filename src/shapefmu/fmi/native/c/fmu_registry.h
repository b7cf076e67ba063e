/* The process-wide registry of live instances of one native FMU (its shared library).
 *
 * Some hosts call an instance after they freed it: OMSimulator 3.0, after a failed initialisation,
 * terminates and frees its instances in one round and then runs the round again with the handles it
 * kept. Every entry point therefore asks whether its instance pointer is live before dereferencing
 * it. A pointer is live from fmu_registry_add (on instantiation) to fmu_registry_remove (on free).
 * The check first compares with the pointer last found live (one load: the hot path of doStep,
 * get and set), then scans the registry under a lock.
 */
#ifndef FMU_REGISTRY_H
#define FMU_REGISTRY_H

/* Register a new instance: 0, or -1 when the registry cannot grow (out of memory). */
int fmu_registry_add(const void *instance);

/* Unregister an instance: 1 if it was live, 0 if it was not (already freed or never made). */
int fmu_registry_remove(const void *instance);

/* 1 if instance is live; else 0, after one line on stderr naming function (the instance's logger
 * may be gone with it). */
int fmu_registry_live(const void *instance, const char *function);

#endif
