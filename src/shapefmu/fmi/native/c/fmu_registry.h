/* Whether an instance pointer is a live instance of a native FMU.
 *
 * Some hosts call an instance after they freed it: OMSimulator 3.0, after a failed initialisation,
 * terminates and frees its instances in one round and then runs the round again with the handles it
 * kept. Every entry point therefore asks whether its instance is live before using it. Each instance
 * struct begins with a tag (unsigned long long live_tag), set to a live value on instantiation and
 * overwritten on free just before the memory is released; a freed chunk then holds the dead value or
 * the allocator's own bookkeeping, never the live value, unless it was reused for a new instance.
 * The tag lives in the instance, not in a table of this library: ecos loads one copy of an FMU's
 * library per instance and calls an instance through another copy's functions, so a per-library
 * table would refuse live instances there.
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
