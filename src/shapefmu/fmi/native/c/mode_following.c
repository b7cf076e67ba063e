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

static MfSegment *segment_at(const ModeFollowing *mf, long long m) {
    return &mf->segments[(mf->head + m) & (mf->capacity - 1)];
}

/* Segment g's taps become the design taps (its old ones released): 0, or -1 (failure set). */
static int take_taps(ModeFollowing *mf, ModelInstance *inst, MfSegment *g, const MfTaps *taps) {
    const long long in_flight = mf->taps_in_flight - g->n_taps + taps->count;
    if (in_flight > MF_MAX_TAPS_IN_FLIGHT) {
        snprintf(mf->failure, sizeof mf->failure, "the designs in flight would hold %lld taps, more than the %lld "
                 "summed per sample (a new design at nearly every sample of a moving command): raise resolution",
                 in_flight, MF_MAX_TAPS_IN_FLIGHT);
        return -1;
    }
    MfTap *copy = model_allocate(inst, (size_t)taps->count, sizeof(MfTap));
    if (copy == NULL) return fail(mf, "out of memory for a design's taps");
    for (int i = 0; i < taps->count; i++) copy[i].delay = taps->delay[i], copy[i].weight = taps->weight[i];
    model_release(inst, g->taps);
    g->taps = copy, g->n_taps = taps->count, g->reach = copy[taps->count - 1].delay + 1;
    mf->taps_in_flight = in_flight;
    return 0;
}

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

/* A new open segment at the back with the design taps, starting at sample start after the command
 * base; the deque doubled when full. 0, or -1 (failure set). */
static int push_segment(ModeFollowing *mf, ModelInstance *inst, const MfTaps *taps, long long start, double base) {
    if (mf->count == mf->capacity) {
        MfSegment *grown = model_allocate(inst, 2 * (size_t)mf->capacity, sizeof(MfSegment));
        if (grown == NULL) return fail(mf, "out of memory for the designs in flight");
        for (long long m = 0; m < mf->count; m++) grown[m] = *segment_at(mf, m);
        model_release(inst, mf->segments);
        mf->segments = grown, mf->head = 0, mf->capacity *= 2;
    }
    MfSegment *g = segment_at(mf, mf->count);
    memset(g, 0, sizeof *g);
    g->start = start, g->base = base, g->end_value = base, g->open = 1;
    if (take_taps(mf, inst, g, taps) != 0) return -1;
    mf->count++;
    return 0;
}

/* The oldest segment folded into the base (or dropped). */
static void pop_segment(ModeFollowing *mf, ModelInstance *inst) {
    MfSegment *g = segment_at(mf, 0);
    mf->taps_in_flight -= g->n_taps;
    model_release(inst, g->taps);
    g->taps = NULL;
    mf->head = (mf->head + 1) & (mf->capacity - 1), mf->count--;
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
    mf->capacity = 4;
    mf->last = u0, mf->ring[0] = u0, mf->mask = 0;
    if (push_segment(mf, inst, &taps, 0, u0) != 0) return -1;
    return fit(mf, inst, segment_at(mf, 0)->reach);
}

void mf_free(ModeFollowing *mf, ModelInstance *inst) {
    while (mf->count > 0) pop_segment(mf, inst);
    model_release(inst, mf->ring);
    model_release(inst, mf->segments);
    mf->ring = NULL, mf->segments = NULL;
    mf->head = mf->capacity = mf->taps_in_flight = 0;
}

static int moved(const ModeFollowing *mf, double omega, double zeta) {
    return fabs(omega - mf->mode[0]) > mf->resolution * mf->mode[0] || fabs(zeta - mf->mode[1]) > mf->resolution;
}

/* ModeFollowingShaper._sum: the output at sample k with command u there. */
static double sum(const ModeFollowing *mf, long long k, double u) {
    double y = segment_at(mf, 0)->base;
    for (long long m = 0; m < mf->count; m++) {
        const MfSegment *g = segment_at(mf, m);
        for (long long i = 0; i < g->n_taps; i++) {
            const long long j = k - g->taps[i].delay;
            if (j < g->start) continue;
            const double value = j == k ? u : mf->ring[j & mf->mask];
            y += g->taps[i].weight * ((g->open || j <= g->end ? value : g->end_value) - g->base);
        }
    }
    return y;
}

int mf_step(ModeFollowing *mf, ModelInstance *inst, double command, double omega, double zeta, double *y) {
    const long long k = mf->k;
    if (moved(mf, omega, zeta)) {
        MfTaps taps;
        if (design(mf, omega, zeta, &taps) != 0) return -1;
        mf->mode[0] = omega, mf->mode[1] = zeta;
        mf->designs++;
        MfSegment *current = segment_at(mf, mf->count - 1);
        if (current->moved) {  /* the changes made so far keep their design: a new segment begins here */
            current->open = 0, current->end = k - 1, current->end_value = mf->last;
            if (push_segment(mf, inst, &taps, k, mf->last) != 0) return -1;
        } else if (take_taps(mf, inst, current, &taps) != 0) {  /* nothing in flight depends on the old design */
            return -1;
        }
        if (fit(mf, inst, segment_at(mf, mf->count - 1)->reach) != 0) return -1;
    }
    if (command != mf->last) segment_at(mf, mf->count - 1)->moved = 1;
    mf->ring[k & mf->mask] = command;
    mf->last = command;
    /* a segment whose last change has reached its last impulse is folded into the base */
    while (mf->count > 1 && k - (segment_at(mf, 0)->reach - 1) >= segment_at(mf, 0)->end) pop_segment(mf, inst);
    if (y != NULL) *y = sum(mf, k, command);
    mf->k = k + 1;
    return 0;
}

int mf_output(ModeFollowing *mf, double command, double omega, double zeta, double *y) {
    const MfSegment *current = segment_at(mf, mf->count - 1);
    double first = current->taps[0].delay == 0 ? current->taps[0].weight : 0.0;
    if (moved(mf, omega, zeta)) {
        MfTaps taps;
        if (design(mf, omega, zeta, &taps) != 0) return -1;
        first = taps.delay[0] == 0 ? taps.weight[0] : 0.0;
    }
    *y = sum(mf, mf->k, mf->last) + first * (command - mf->last);
    return 0;
}

int mf_copy(ModeFollowing *dst, const ModeFollowing *src, ModelInstance *inst) {
    while (dst->count > 0) pop_segment(dst, inst);
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
    dst->head = dst->count = dst->taps_in_flight = 0;
    if (ring == NULL || segments == NULL) {
        mf_free(dst, inst);
        return -1;
    }
    memcpy(dst->ring, src->ring, ((size_t)src->mask + 1) * sizeof(double));
    for (long long m = 0; m < src->count; m++) {
        const MfSegment *g = segment_at(src, m);
        MfSegment *copy = &dst->segments[m];
        *copy = *g;
        copy->taps = model_allocate(inst, (size_t)g->n_taps, sizeof(MfTap));
        if (copy->taps == NULL) {
            mf_free(dst, inst);
            return -1;
        }
        memcpy(copy->taps, g->taps, (size_t)g->n_taps * sizeof(MfTap));
        dst->count = m + 1, dst->taps_in_flight += g->n_taps;
    }
    return 0;
}

/* ---------------------------------------------------------------- FMU state
 * A fixed header, the ring, then each segment in flight: its scalars and its taps. The design
 * cache is not saved: a design is the same numbers whenever it is made. */

typedef struct {
    double mode[2], last;
    long long designs, k, mask, count;
} MfHeader;

size_t mf_bytes(const ModeFollowing *mf) {
    return sizeof(MfHeader) + ((size_t)mf->mask + 1) * sizeof(double) + (size_t)mf->count * sizeof(MfSegment)
           + (size_t)mf->taps_in_flight * sizeof(MfTap);
}

void mf_save(const ModeFollowing *mf, unsigned char *bytes) {
    MfHeader header;
    memset(&header, 0, sizeof header);
    header.mode[0] = mf->mode[0], header.mode[1] = mf->mode[1], header.last = mf->last;
    header.designs = mf->designs, header.k = mf->k, header.mask = mf->mask, header.count = mf->count;
    memcpy(bytes, &header, sizeof header);
    unsigned char *at = bytes + sizeof header;
    memcpy(at, mf->ring, ((size_t)mf->mask + 1) * sizeof(double));
    at += ((size_t)mf->mask + 1) * sizeof(double);
    for (long long m = 0; m < mf->count; m++) {
        MfSegment g = *segment_at(mf, m);
        const MfTap *taps = g.taps;
        g.taps = NULL;
        memcpy(at, &g, sizeof g);
        memcpy(at + sizeof g, taps, (size_t)g.n_taps * sizeof(MfTap));
        at += sizeof g + (size_t)g.n_taps * sizeof(MfTap);
    }
}

/* A segment a run makes (the m-th of count at sample k, with a ring of ring samples): its taps are
 * read and checked by taps_valid. Only the last one open. */
static int segment_valid(const MfSegment *g, int last, long long k, long long ring) {
    return g->n_taps >= 1 && g->n_taps <= MF_MAX_TAPS && g->open == last && (g->moved == 0 || g->moved == 1)
           && g->start >= 0 && g->start <= k && (g->open || (g->end >= g->start - 1 && g->end < k))
           && isfinite(g->base) && isfinite(g->end_value) && g->reach >= 1 && g->reach <= ring;
}

/* Taps at increasing delays from 0, finite non-zero weights, the last one reach - 1. */
static int taps_valid(const MfTap *taps, long long n, long long reach) {
    for (long long i = 0; i < n; i++)
        if (taps[i].delay < (i ? taps[i - 1].delay + 1 : 0) || !isfinite(taps[i].weight) || taps[i].weight == 0.0)
            return 0;
    return taps[n - 1].delay + 1 == reach;
}

int mf_restore(ModeFollowing *mf, ModelInstance *inst, const unsigned char **at, const unsigned char *end) {
    MfHeader header;
    if ((size_t)(end - *at) < sizeof header) return -1;
    memcpy(&header, *at, sizeof header);
    const long long ring = header.mask + 1;
    if (ring < 1 || ring > MF_MAX_RING || (ring & header.mask) != 0 || header.count < 1
        || header.count > MF_MAX_TAPS_IN_FLIGHT || header.k < 0 || header.designs < 1
        || !(header.mode[0] > 0.0 && header.mode[0] < INFINITY) || !(header.mode[1] >= 0.0 && header.mode[1] < 1.0)
        || !isfinite(header.last)
        || ((size_t)(end - *at) - sizeof header) / sizeof(double) < (size_t)ring
        || ((size_t)(end - *at) - sizeof header - (size_t)ring * sizeof(double)) / sizeof(MfSegment) < (size_t)header.count)
        return -1;
    const unsigned char *from = *at + sizeof header;
    mf->ring = model_allocate(inst, (size_t)ring, sizeof(double));
    for (mf->capacity = 4; mf->capacity < header.count; mf->capacity *= 2) {}
    mf->segments = model_allocate(inst, (size_t)mf->capacity, sizeof(MfSegment));
    mf->head = mf->count = mf->taps_in_flight = 0;
    if (mf->ring == NULL || mf->segments == NULL) goto refused;
    mf->mask = header.mask;
    memcpy(mf->ring, from, (size_t)ring * sizeof(double));
    from += (size_t)ring * sizeof(double);
    for (long long j = 0; j < ring; j++)
        if (!isfinite(mf->ring[j])) goto refused;
    for (long long m = 0; m < header.count; m++) {
        MfSegment g;
        if ((size_t)(end - from) < sizeof g) goto refused;
        memcpy(&g, from, sizeof g);
        from += sizeof g;
        if (!segment_valid(&g, m == header.count - 1, header.k, ring) || (size_t)(end - from) < (size_t)g.n_taps * sizeof(MfTap)
            || mf->taps_in_flight + g.n_taps > MF_MAX_TAPS_IN_FLIGHT)
            goto refused;
        g.taps = model_allocate(inst, (size_t)g.n_taps, sizeof(MfTap));
        if (g.taps == NULL) goto refused;
        memcpy(g.taps, from, (size_t)g.n_taps * sizeof(MfTap));
        from += (size_t)g.n_taps * sizeof(MfTap);
        mf->segments[m] = g, mf->count = m + 1, mf->taps_in_flight += g.n_taps;
        if (!taps_valid(g.taps, g.n_taps, g.reach)) goto refused;
    }
    mf->mode[0] = header.mode[0], mf->mode[1] = header.mode[1], mf->last = header.last;
    mf->designs = header.designs, mf->k = header.k, mf->has_pending = 0;
    *at = from;
    return 0;
refused:
    mf_free(mf, inst);
    return -1;
}
