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
 *
 * A freed instance's struct is not released at once but retired (fmu_retire): kept, with its dead
 * tag, while the next FMU_RETIRED instances of this library are freed. The allocator therefore cannot
 * give its address to a new instance soon after, and a call through the stale handle still finds the
 * dead tag rather than a stranger's live one (a host that frees, instantiates again, then calls the
 * old handle). The structs still retired when the library is unloaded are released then.
 */
#ifndef FMU_LIVENESS_H
#define FMU_LIVENESS_H

/* Mark a new instance live (its first member is the tag). */
void fmu_mark_live(void *instance);

/* Mark an instance freed, just before its memory is released: 1 if it was live, 0 if it was not
 * (already freed or never made). */
int fmu_mark_freed(const void *instance);

/* 1 if instance is live; else 0, after one line on stderr naming function (the instance's logger
 * may be gone with it). */
int fmu_is_live(const void *instance, const char *function);

/* Hand a freed instance's struct (marked freed, allocated with malloc) to the retired ring, which
 * releases it with free() FMU_RETIRED frees later; thread-safe. */
#define FMU_RETIRED 256
void fmu_retire(void *instance);

#endif
