/* runtime/scheduled_shaper.py's ModeFollowingShaper in C (mode_following.h), operation for
 * operation: the same designs on the grid (shaper_designs.c, grid_impulses' order of sums), the same
 * segments and ring of past commands, the same sum at each sample. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "mode_following.h"

#define PI 3.14159265358979323846

static int fail(ModeFollowing *mf, const char *why) {
    snprintf(mf->failure, sizeof mf->failure, "%s", why);
    return -1;
}

/* shaper_filter.py's grid_impulses: each impulse split onto the grid, summed per delay in the
 * order of the impulses, the zero weights dropped, sorted by delay. */
static void grid_taps(const double *times, const double *amplitudes, int count, double h, MfTaps *taps) {
    taps->count = 0;
    for (int i = 0; i < count; i++) {
        long k;
        const double alpha = grid_split(times[i], h, &k);
        const double parts[2] = {(1.0 - alpha) * amplitudes[i], alpha * amplitudes[i]};
        for (int p = 0; p < (alpha != 0.0 ? 2 : 1); p++) {
            int at = 0;
            while (at < taps->count && taps->delay[at] != k + p) at++;
            if (at == taps->count) taps->delay[taps->count] = k + p, taps->weight[taps->count++] = 0.0;
            taps->weight[at] = taps->weight[at] + parts[p];
        }
    }
    int kept = 0;
    for (int i = 0; i < taps->count; i++) {
        if (taps->weight[i] == 0.0) continue;
        const long long delay = taps->delay[i];
        const double weight = taps->weight[i];
        int at = kept++;
        for (; at > 0 && taps->delay[at - 1] > delay; at--)
            taps->delay[at] = taps->delay[at - 1], taps->weight[at] = taps->weight[at - 1];
        taps->delay[at] = delay, taps->weight[at] = weight;
    }
    taps->count = kept;
}

/* ModeFollowingShaper._taps: the design for (omega, zeta) on the grid, designed once per mode. */
static int design(ModeFollowing *mf, double omega, double zeta, MfTaps *taps) {
    if (mf->has_pending && mf->pending_mode[0] == omega && mf->pending_mode[1] == zeta) {
        *taps = mf->pending;
        return 0;
    }
    if (omega * sqrt(1.0 - zeta * zeta) >= PI / mf->h) {
        snprintf(mf->failure, sizeof mf->failure, "the mode omega = %g rad/s, zeta = %g lies at or above the Nyquist "
                 "frequency pi*fs = %g rad/s: sampled at fs = %g Hz no shaper can cancel it", omega, zeta, PI * mf->fs,
                 mf->fs);
        return -1;
    }
    double times[MF_MAX_IMPULSES], amplitudes[MF_MAX_IMPULSES], scratch[2 * MF_MAX_IMPULSES];
    const int count = design_closed_form(mf->kind, mf->order, 1, &omega, &zeta, times, amplitudes, MF_MAX_IMPULSES,
                                         scratch);
    if (count <= 0) return fail(mf, "the shaper's closed-form design failed");
    const double samples = times[count - 1] / mf->h + 2.0;
    if (!(samples <= MF_MAX_LENGTH)) {
        snprintf(mf->failure, sizeof mf->failure, "a shaper for omega = %g rad/s sampled at fs = %g Hz would be %.4g "
                 "samples long, more than the limit of 1,000,000 (shapefmu.runtime.limits.MAX_SAMPLED_LENGTH); use a "
                 "lower fs or a higher frequency", omega, mf->fs, samples);
        return -1;
    }
    grid_taps(times, amplitudes, count, mf->h, &mf->pending);
    if (mf->pending.count == 0) return fail(mf, "the shaper's design has no non-zero tap");
    mf->has_pending = 1, mf->pending_mode[0] = omega, mf->pending_mode[1] = zeta;
    *taps = mf->pending;
    return 0;
}

static long long reach_of(const MfTaps *taps) { return taps->delay[taps->count - 1] + 1; }

/* ModeFollowingShaper._fit: grow the ring to hold reach samples, the commands copied in order. */
static int fit(ModeFollowing *mf, ModelInstance *inst, long long reach) {
    const long long old = mf->mask + 1;
    long long size = old;
    if (size >= reach) return 0;
    while (size < reach) size *= 2;
    double *ring = model_allocate(inst, (size_t)size, sizeof(double));
    if (ring == NULL) return fail(mf, "out of memory for the ring of past commands");
    for (long long j = 0; j < size; j++) ring[j] = mf->last;
    for (long long j = mf->k - old > 0 ? mf->k - old : 0; j < mf->k; j++) ring[j & (size - 1)] = mf->ring[j & mf->mask];
    model_release(inst, mf->ring);
    mf->ring = ring, mf->mask = size - 1;
    return 0;
}

static void segment_start(MfSegment *segment, const MfTaps *taps, long long start, double base) {
    memset(segment, 0, sizeof *segment);
    segment->taps = *taps;
    segment->start = start, segment->base = base, segment->end_value = base;
    segment->open = 1;
    segment->reach = reach_of(taps);
}

int mf_start(ModeFollowing *mf, ModelInstance *inst, double fs, double omega, double zeta, ClosedFormKind kind,
             int order, double u0, double resolution) {
    memset(mf, 0, sizeof *mf);
    mf->fs = fs, mf->h = 1.0 / fs, mf->resolution = resolution, mf->kind = kind, mf->order = order;
    MfTaps taps;
    if (design(mf, omega, zeta, &taps) != 0) return -1;
    mf->mode[0] = omega, mf->mode[1] = zeta;
    mf->designs = 1;
    mf->segments = model_allocate(inst, 4, sizeof(MfSegment));
    mf->ring = model_allocate(inst, 1, sizeof(double));
    if (mf->segments == NULL || mf->ring == NULL) return fail(mf, "out of memory for the shaper");
    mf->capacity = 4, mf->count = 1;
    segment_start(&mf->segments[0], &taps, 0, u0);
    mf->last = u0, mf->ring[0] = u0, mf->mask = 0;
    return fit(mf, inst, mf->segments[0].reach);
}

void mf_free(ModeFollowing *mf, ModelInstance *inst) {
    model_release(inst, mf->ring);
    model_release(inst, mf->segments);
    mf->ring = NULL, mf->segments = NULL;
    mf->count = mf->capacity = 0;
}

static int moved(const ModeFollowing *mf, double omega, double zeta) {
    return fabs(omega - mf->mode[0]) > mf->resolution * mf->mode[0] || fabs(zeta - mf->mode[1]) > mf->resolution;
}

/* A new segment at the end, the array grown by doubling up to MF_MAX_SEGMENTS. */
static MfSegment *append(ModeFollowing *mf, ModelInstance *inst) {
    if (mf->count == mf->capacity) {
        if (mf->capacity >= MF_MAX_SEGMENTS) {
            snprintf(mf->failure, sizeof mf->failure, "the mode moved during a move more than %d times within one "
                     "shaper length: at most %d designs in flight (raise resolution)", MF_MAX_SEGMENTS, MF_MAX_SEGMENTS);
            return NULL;
        }
        MfSegment *grown = model_allocate(inst, 2 * (size_t)mf->capacity, sizeof(MfSegment));
        if (grown == NULL) {
            fail(mf, "out of memory for the designs in flight");
            return NULL;
        }
        memcpy(grown, mf->segments, (size_t)mf->count * sizeof(MfSegment));
        model_release(inst, mf->segments);
        mf->segments = grown, mf->capacity *= 2;
    }
    return &mf->segments[mf->count++];
}

/* ModeFollowingShaper._sum: the output at sample k with command u there. */
static double sum(const ModeFollowing *mf, long long k, double u) {
    double y = mf->segments[0].base;
    for (long long s = 0; s < mf->count; s++) {
        const MfSegment *segment = &mf->segments[s];
        for (int i = 0; i < segment->taps.count; i++) {
            const long long j = k - segment->taps.delay[i];
            if (j < segment->start) continue;
            const double value = j == k ? u : mf->ring[j & mf->mask];
            y += segment->taps.weight[i] * ((segment->open || j <= segment->end ? value : segment->end_value) - segment->base);
        }
    }
    return y;
}

int mf_step(ModeFollowing *mf, ModelInstance *inst, double command, double omega, double zeta, double *y) {
    const long long k = mf->k;
    MfSegment *current = &mf->segments[mf->count - 1];
    if (moved(mf, omega, zeta)) {
        MfTaps taps;
        if (design(mf, omega, zeta, &taps) != 0) return -1;
        mf->mode[0] = omega, mf->mode[1] = zeta;
        mf->designs++;
        if (current->moved) {  /* the changes made so far keep their design: a new segment begins here */
            current->open = 0, current->end = k - 1, current->end_value = mf->last;
            if ((current = append(mf, inst)) == NULL) return -1;
            segment_start(current, &taps, k, mf->last);
        } else {  /* no change commanded under the old design: nothing in flight depends on it */
            current->taps = taps, current->reach = reach_of(&taps);
        }
        if (fit(mf, inst, current->reach) != 0) return -1;
    }
    if (command != mf->last) current->moved = 1;
    mf->ring[k & mf->mask] = command;
    mf->last = command;
    long long folded = 0;  /* segments whose last change has reached their last impulse: into the base */
    while (mf->count - folded > 1 && k - (mf->segments[folded].reach - 1) >= mf->segments[folded].end) folded++;
    if (folded) {
        memmove(mf->segments, mf->segments + folded, (size_t)(mf->count - folded) * sizeof(MfSegment));
        mf->count -= folded;
    }
    if (y != NULL) *y = sum(mf, k, command);
    mf->k = k + 1;
    return 0;
}

int mf_output(ModeFollowing *mf, double command, double omega, double zeta, double *y) {
    const MfTaps *taps = &mf->segments[mf->count - 1].taps;
    MfTaps designed;
    if (moved(mf, omega, zeta)) {
        if (design(mf, omega, zeta, &designed) != 0) return -1;
        taps = &designed;
    }
    const double first = taps->delay[0] == 0 ? taps->weight[0] : 0.0;
    *y = sum(mf, mf->k, mf->last) + first * (command - mf->last);
    return 0;
}

int mf_copy(ModeFollowing *dst, const ModeFollowing *src, ModelInstance *inst) {
    double *ring = dst->ring;
    MfSegment *segments = dst->segments;
    long long capacity = dst->capacity;
    if (ring == NULL || dst->mask != src->mask) {
        model_release(inst, ring);
        ring = model_allocate(inst, (size_t)src->mask + 1, sizeof(double));
    }
    if (segments == NULL || capacity < src->count) {
        model_release(inst, segments);
        capacity = src->capacity;
        segments = model_allocate(inst, (size_t)capacity, sizeof(MfSegment));
    }
    *dst = *src;
    dst->ring = ring, dst->segments = segments, dst->capacity = capacity;
    if (ring == NULL || segments == NULL) {
        mf_free(dst, inst);
        return -1;
    }
    memcpy(ring, src->ring, ((size_t)src->mask + 1) * sizeof(double));
    memcpy(segments, src->segments, (size_t)src->count * sizeof(MfSegment));
    return 0;
}

/* ---------------------------------------------------------------- FMU state
 * A fixed header, then the ring and the segments. The design cache is not saved: a design is the
 * same numbers whenever it is made. */

typedef struct {
    double mode[2], last;
    long long designs, k, mask, count;
} MfHeader;

size_t mf_bytes(const ModeFollowing *mf) {
    return sizeof(MfHeader) + ((size_t)mf->mask + 1) * sizeof(double) + (size_t)mf->count * sizeof(MfSegment);
}

void mf_save(const ModeFollowing *mf, unsigned char *bytes) {
    MfHeader header;
    memset(&header, 0, sizeof header);
    header.mode[0] = mf->mode[0], header.mode[1] = mf->mode[1], header.last = mf->last;
    header.designs = mf->designs, header.k = mf->k, header.mask = mf->mask, header.count = mf->count;
    memcpy(bytes, &header, sizeof header);
    memcpy(bytes + sizeof header, mf->ring, ((size_t)mf->mask + 1) * sizeof(double));
    memcpy(bytes + sizeof header + ((size_t)mf->mask + 1) * sizeof(double), mf->segments,
           (size_t)mf->count * sizeof(MfSegment));
}

/* A segment a run makes: taps at increasing delays below the ring's size, finite numbers; only the
 * last one open. */
static int segment_valid(const MfSegment *segment, int last, long long k, long long ring) {
    const MfTaps *taps = &segment->taps;
    if (taps->count < 1 || taps->count > MF_MAX_TAPS || segment->open != last || (segment->moved != 0 && segment->moved != 1)
        || segment->start < 0 || segment->start > k || !isfinite(segment->base) || !isfinite(segment->end_value)
        || (!segment->open && (segment->end < segment->start - 1 || segment->end >= k)))
        return 0;
    for (int i = 0; i < taps->count; i++)
        if (taps->delay[i] < (i ? taps->delay[i - 1] + 1 : 0) || !isfinite(taps->weight[i]) || taps->weight[i] == 0.0)
            return 0;
    return segment->reach == reach_of(taps) && segment->reach <= ring;
}

int mf_restore(ModeFollowing *mf, ModelInstance *inst, const unsigned char **at, const unsigned char *end) {
    MfHeader header;
    if ((size_t)(end - *at) < sizeof header) return -1;
    memcpy(&header, *at, sizeof header);
    const long long ring = header.mask + 1;
    if (ring < 1 || ring > MF_MAX_RING || (ring & header.mask) != 0 || header.count < 1 || header.count > MF_MAX_SEGMENTS
        || header.k < 0 || header.designs < 1 || !(header.mode[0] > 0.0 && header.mode[0] < INFINITY)
        || !(header.mode[1] >= 0.0 && header.mode[1] < 1.0) || !isfinite(header.last))
        return -1;
    const size_t bytes = sizeof header + (size_t)ring * sizeof(double) + (size_t)header.count * sizeof(MfSegment);
    if ((size_t)(end - *at) < bytes) return -1;
    mf->ring = model_allocate(inst, (size_t)ring, sizeof(double));
    mf->segments = model_allocate(inst, (size_t)header.count, sizeof(MfSegment));
    if (mf->ring == NULL || mf->segments == NULL) {
        mf_free(mf, inst);
        return -1;
    }
    memcpy(mf->ring, *at + sizeof header, (size_t)ring * sizeof(double));
    memcpy(mf->segments, *at + sizeof header + (size_t)ring * sizeof(double), (size_t)header.count * sizeof(MfSegment));
    mf->mask = header.mask, mf->count = mf->capacity = header.count;
    for (long long s = 0; s < header.count; s++)
        if (!segment_valid(&mf->segments[s], s == header.count - 1, header.k, ring)) {
            mf_free(mf, inst);
            return -1;
        }
    for (long long j = 0; j < ring; j++)
        if (!isfinite(mf->ring[j])) {
            mf_free(mf, inst);
            return -1;
        }
    mf->mode[0] = header.mode[0], mf->mode[1] = header.mode[1], mf->last = header.last;
    mf->designs = header.designs, mf->k = header.k, mf->has_pending = 0;
    *at += bytes;
    return 0;
}
