/* A shaper re-designed for the mode it is given at each sample, with no jump in its output:
 * runtime/scheduled_shaper.py's ModeFollowingShaper in C, operation for operation (its module
 * docstring derives why each change of the command keeps the design in force when it was made,
 * and how the segments of changes under one design are summed and folded into the base). For the
 * model parts of the shapers that follow a moving mode (scheduled_part.c, tracked_shaper_part.c). */
#ifndef MODE_FOLLOWING_H
#define MODE_FOLLOWING_H

#include "model.h"
#include "shaper_designs.h"

/* Impulses of one single-mode closed-form design (zv_dn of order n <= 62 has n + 2), and its taps
 * on the grid: each impulse split onto two samples. */
#define MF_MAX_IMPULSES 64
#define MF_MAX_ORDER 62
#define MF_MAX_TAPS (2 * MF_MAX_IMPULSES)
/* runtime/limits.py's MAX_SAMPLED_LENGTH: the longest design, in samples. */
#define MF_MAX_LENGTH 1000000.0
/* Taps summed per sample over the designs in flight (16 bytes each; C only, the Python kernel keeps
 * any number): a new design at every sample of a moving command keeps a segment per sample in
 * flight, as many as the longest design spans. */
#define MF_MAX_TAPS_IN_FLIGHT 1000000LL
/* The ring of past commands: a power of two holding the longest design (MF_MAX_LENGTH + 2 samples). */
#define MF_MAX_RING (1LL << 20)

typedef struct {
    int count;
    long long delay[MF_MAX_TAPS];  /* increasing, weights non-zero */
    double weight[MF_MAX_TAPS];
} MfTaps;

typedef struct {
    long long delay;
    double weight;
} MfTap;

/* scheduled_shaper.py's CommandSegment: the changes of the command made under one design. */
typedef struct {
    MfTap *taps;  /* n_taps of them, increasing delays */
    long long n_taps, start, open, end, moved, reach;  /* open: its design is in force (end not yet set) */
    double base, end_value;
} MfSegment;

/* Plain data but for ring, segments and their taps (copied and saved by the functions below). */
typedef struct {
    ClosedFormKind kind;
    int order;
    double fs, h, resolution, mode[2], last;
    long long designs, k, mask;  /* ring of mask + 1 commands */
    long long head, count, capacity, taps_in_flight;  /* the m-th segment at segments[(head + m) & (capacity - 1)] */
    double *ring;
    MfSegment *segments;
    int has_pending;  /* the newest design, shared by the probe of a sample and the step that takes it */
    double pending_mode[2];
    MfTaps pending;
    char failure[240];  /* why the last call returned -1 */
} ModeFollowing;

/* Start designed for (omega rad/s, zeta), the command at rest at u0: 0, or -1 (mf->failure says why). */
int mf_start(ModeFollowing *mf, ModelInstance *inst, double fs, double omega, double zeta, ClosedFormKind kind,
             int order, double u0, double resolution);
void mf_free(ModeFollowing *mf, ModelInstance *inst);
/* Shape one command sample with the design for (omega, zeta), re-designed if it moved: 0 and *y
 * (y may be NULL: the sample taken, its sum left to mf_output), or -1 (mf->failure says why). */
int mf_step(ModeFollowing *mf, ModelInstance *inst, double command, double omega, double zeta, double *y);
/* What mf_step(command, omega, zeta) will give, without taking the sample (ModeFollowingShaper.output):
 * the output if the command holds plus the first tap of the design for the mode times the change.
 * 0 and *y, or -1 (mf->failure says why). */
int mf_output(ModeFollowing *mf, double command, double omega, double zeta, double *y);
/* dst becomes a copy of src (dst's buffers reused when large enough): 0, or -1 out of memory. */
int mf_copy(ModeFollowing *dst, const ModeFollowing *src, ModelInstance *inst);

/* An FMU state: the bytes mf_save writes (mf_bytes of them), and mf_restore reading them back at
 * *at (advanced) before end into a freed mf with the given build settings: 0, or -1 if they are
 * not a shaper a run reaches. */
size_t mf_bytes(const ModeFollowing *mf);
void mf_save(const ModeFollowing *mf, unsigned char *bytes);
int mf_restore(ModeFollowing *mf, ModelInstance *inst, const unsigned char **at, const unsigned char *end);

#endif
