/*
 * laban_series.c — Weight, Time, Space and Flow over a window sliding along a motion (see
 * affect/laban.h for the definitions and the window layout).
 *
 *     affect_laban_series_options so;
 *     affect_laban_series_options_default(&so);
 *     so.window = affect_laban_series_frames(1.0, m->fps);     (one second)
 *     so.combined = true;
 *     affect_laban_series *s;
 *     st = affect_laban_series_new(m, parts, 6, &opt, &so, &s, &err);
 *     while (!(st = affect_laban_series_next(s, &first, &last, values, &err)))
 *         … values[row · AFFECT_SERIES_N + AFFECT_SERIES_WEIGHT] …
 *     (st == AFFECT_ERR_RANGE: every window was given)
 *     affect_laban_series_free(s);
 *
 * How it works. The parts' velocity and acceleration are computed once over the whole motion
 * (affect_laban_kinematics_block in laban.c: the per-clip functions' bits), so a window is a
 * reduction of frames the per-clip values also reduce. Per frame t and part k the terms are
 *   point terms (frame t alone):      ‖v_k(t)‖² (Weight Q1), ‖a_k(t)‖ (Time Q1)
 *   step terms (frames t − 1 and t):  max(0, ‖v_k(t−1)‖ − ‖v_k(t)‖)·fps (Weight Q2),
 *                                     ‖v_k(t) − v_k(t−1)‖·fps (Time Q2), ‖a_k(t) − a_k(t−1)‖·fps
 *                                     (Flow), ‖p_k(t) − p_k(t−1)‖ (Space's path)
 * and a row's term is the sum over its parts in part order (one part alone: that part's term),
 * as laban.c sums them. A window [f, l] takes the point terms of f … l and the step terms of
 * f + 1 … l. Moving to the next window removes the frames that left and adds those that came:
 *   - a peak is the front of a monotone queue (indices ascending, values descending): an entering
 *     value pops the smaller ones at the back, the front pops once its frame has left; each frame
 *     enters and leaves once, so O(1) amortized per frame whatever the window;
 *   - a sum is kept as a double-double (hi + lo, with TwoSum's exact error of every addition in
 *     lo), so removing a term undoes its addition to within 2^-104 relative and a long motion
 *     does not drift; a count of the non-zero terms it holds makes a sum exactly 0 when nothing
 *     moved in the window (a still part is direct: Space 1, not max_ratio from a residue).
 * Each frame's step terms are computed once, when it enters, and kept in a ring of one window
 * (rows × 3 + parts doubles a frame) from which they are taken back, the same bits, when it
 * leaves; windows that do not overlap (hop ≥ window) are computed afresh and need no ring. The
 * positions for Space are the parts' centroids read from the motion as frames enter (m must
 * outlive the series), the last ones kept for the next frame's path step.
 */
#include "affect/laban.h"

#include <math.h>
#include <string.h>

#include "util/internal.h"

#define POLL_FRAMES 4096 /* the monitor is polled every this many frames of work */
#define MAX_ROWS 7       /* six parts and their combination */

void affect_laban_series_options_default(affect_laban_series_options *so)
{
    so->window = 0;
    so->hop = 1;
    so->weight = AFFECT_LABAN_Q1;
    so->time = AFFECT_LABAN_Q1;
    so->combined = false;
}

uint32_t affect_laban_series_frames(double seconds, double fps)
{
    double f = seconds * fps;
    if (!isfinite(f) || !(f >= 0.5))
        return 0;
    return f >= 4294967295.0 ? UINT32_MAX : (uint32_t)llround(f);
}

/* A running sum: hi + lo, the exact error of every addition to hi carried in lo. */
typedef struct dd_sum {
    double hi, lo;
    uint64_t nonzero; /* terms ≠ 0 it holds: none → exactly 0 */
} dd_sum;

static void dd_add(dd_sum *a, double x, int sign)
{
    if (x == 0)
        return;
    double y = sign > 0 ? x : -x;
    double s = a->hi + y;
    double bp = s - a->hi;
    double e = (a->hi - (s - bp)) + (y - bp);
    a->hi = s;
    a->lo += e;
    if (sign > 0) {
        a->nonzero++;
    } else if (--a->nonzero == 0) {
        a->hi = 0;
        a->lo = 0;
    }
}

static double dd_value(const dd_sum *a)
{
    return a->nonzero ? a->hi + a->lo : 0.0;
}

/* A monotone queue of (frame, value) in a ring of cap entries. */
typedef struct peak_queue {
    uint32_t *idx;
    double *val;
    uint32_t cap, head, count;
} peak_queue;

static void queue_push(peak_queue *q, uint32_t t, double v)
{
    while (q->count > 0) {
        uint32_t back = (q->head + q->count - 1) % q->cap;
        if (q->val[back] > v)
            break;
        q->count--;
    }
    uint32_t at = (q->head + q->count) % q->cap;
    q->idx[at] = t;
    q->val[at] = v;
    q->count++;
}

static void queue_expire(peak_queue *q, uint32_t first)
{
    while (q->count > 0 && q->idx[q->head] < first) {
        q->head = (q->head + 1) % q->cap;
        q->count--;
    }
}

/* The peak, 0 when empty (the per-clip peaks start from 0). */
static double queue_front(const peak_queue *q)
{
    return q->count > 0 ? q->val[q->head] : 0.0;
}

struct affect_laban_series {
    const affect_motion *m;
    const affect_laban_options *opt;
    affect_laban_options opt_default; /* opt when the caller gave NULL */
    affect_laban_series_options so;
    affect_part parts[6];
    uint32_t n_parts, n_rows, n_windows, next_window, window;
    double fps;
    double *block; /* the kinematics */
    const double *vel[6], *acc[6];
    size_t stride;
    void *ws;                /* the queues' storage */
    peak_queue qw[MAX_ROWS]; /* Weight's peak (Q1: point terms; Q2: step terms) */
    peak_queue qt[MAX_ROWS]; /* Time Q1's peak */
    dd_sum time_sum[MAX_ROWS], flow_sum[MAX_ROWS], path[6];
    double pos[6][3]; /* the parts' positions at the frame added last */
    double *ring;     /* overlapping windows: each frame's step terms (RING_SLOTS doubles) at
                         row t mod window, read back when it leaves; NULL otherwise */
    uint32_t prev_first, prev_last;
    bool started;
    uint64_t work, next_poll;
};

/* Centroid of part k at frame t (laban.c's part_positions arithmetic). */
static void part_at(const affect_laban_series *s, uint32_t k, uint32_t t, double out[3])
{
    const affect_part *part = &s->parts[k];
    double c[3] = {0, 0, 0};
    for (uint32_t i = 0; i < part->n_joints; i++) {
        const float *p = affect_motion_at(s->m, t, (uint32_t)part->joints[i]);
        c[0] += p[0], c[1] += p[1], c[2] += p[2];
    }
    double inv = 1.0 / part->n_joints;
    for (int a = 0; a < 3; a++)
        out[a] = part->n_joints == 1 ? c[a] : c[a] * inv;
}

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static double dist3(const double *a, const double *b)
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm3(d);
}

/* Rows' parts: row r covers parts [lo, hi). */
static void row_parts(const affect_laban_series *s, uint32_t r, uint32_t *lo, uint32_t *hi)
{
    if (s->so.combined && r == 0) {
        *lo = 0;
        *hi = s->n_parts;
    } else {
        *lo = r - (s->so.combined ? 1 : 0);
        *hi = *lo + 1;
    }
}

/* The point terms of frame t into the queues. */
static void add_point(affect_laban_series *s, uint32_t t)
{
    bool weight = s->so.weight == AFFECT_LABAN_Q1, time = s->so.time == AFFECT_LABAN_Q1;
    if (!weight && !time)
        return;
    double ke[6], an[6];
    for (uint32_t k = 0; k < s->n_parts; k++) {
        const double *v = s->vel[k] + (size_t)t * s->stride, *a = s->acc[k] + (size_t)t * s->stride;
        ke[k] = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
        an[k] = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    }
    for (uint32_t r = 0; r < s->n_rows; r++) {
        uint32_t lo, hi;
        row_parts(s, r, &lo, &hi);
        double sw = 0, st = 0;
        for (uint32_t k = lo; k < hi; k++) {
            sw += ke[k];
            st += an[k];
        }
        if (weight)
            queue_push(&s->qw[r], t, sw);
        if (time)
            queue_push(&s->qt[r], t, st);
    }
}

/* Step-term slots per frame in the ring: three per row (deceleration, velocity change, jerk)
 * and one per part (its path step). */
#define RING_SLOTS(s) ((size_t)(s)->n_rows * 3 + (s)->n_parts)

/* Applies the step terms of one frame (terms: RING_SLOTS doubles) with sign 1 (the frame
 * enters; Weight Q2's queue gets it too) or −1 (it leaves). */
static void apply_steps(affect_laban_series *s, uint32_t t, const double *terms, int sign)
{
    for (uint32_t r = 0; r < s->n_rows; r++) {
        const double *rt = terms + (size_t)r * 3;
        if (sign > 0 && s->so.weight == AFFECT_LABAN_Q2)
            queue_push(&s->qw[r], t, rt[0]);
        if (s->so.time == AFFECT_LABAN_Q2)
            dd_add(&s->time_sum[r], rt[1], sign);
        dd_add(&s->flow_sum[r], rt[2], sign);
    }
    const double *path = terms + (size_t)s->n_rows * 3;
    for (uint32_t k = 0; k < s->n_parts; k++)
        dd_add(&s->path[k], path[k], sign);
}

/* Frame t enters the window: its point terms into the queues and, unless it is the window's
 * first (step false), its step terms (from frame t − 1, the frame added just before: its
 * positions are in s->pos) into the sums, and into the ring for when it leaves. */
static void add_frame(affect_laban_series *s, uint32_t t, bool step)
{
    add_point(s, t);
    double fps = s->fps, dec[6], dv[6], da[6], pos[6][3];
    double local[MAX_ROWS * 3 + 6];
    double *terms = s->ring ? s->ring + (size_t)(t % s->window) * RING_SLOTS(s) : local;
    for (uint32_t k = 0; k < s->n_parts; k++) {
        part_at(s, k, t, pos[k]);
        if (!step)
            continue;
        const double *v1 = s->vel[k] + (size_t)t * s->stride, *v0 = v1 - s->stride;
        const double *a1 = s->acc[k] + (size_t)t * s->stride, *a0 = a1 - s->stride;
        double drop = (norm3(v0) - norm3(v1)) * fps;
        dec[k] = drop > 0 ? drop : 0;
        dv[k] = dist3(v1, v0) * fps;
        da[k] = dist3(a1, a0) * fps;
        terms[(size_t)s->n_rows * 3 + k] = dist3(pos[k], s->pos[k]);
    }
    memcpy(s->pos, pos, sizeof pos);
    if (!step)
        return;
    for (uint32_t r = 0; r < s->n_rows; r++) {
        uint32_t lo, hi;
        row_parts(s, r, &lo, &hi);
        double sd = 0, sv = 0, sa = 0;
        for (uint32_t k = lo; k < hi; k++) {
            sd += dec[k];
            sv += dv[k];
            sa += da[k];
        }
        terms[(size_t)r * 3] = sd;
        terms[(size_t)r * 3 + 1] = sv;
        terms[(size_t)r * 3 + 2] = sa;
    }
    apply_steps(s, t, terms, 1);
}

/* Frame t (≥ 1, in the ring) leaves: its step terms out of the sums. */
static void remove_frame(affect_laban_series *s, uint32_t t)
{
    apply_steps(s, t, s->ring + (size_t)(t % s->window) * RING_SLOTS(s), -1);
}

/* Counts frames of work and polls the monitor every POLL_FRAMES of them. */
static affect_status tick(affect_laban_series *s, affect_error *err)
{
    if (++s->work < s->next_poll)
        return AFFECT_OK;
    s->next_poll = s->work + POLL_FRAMES;
    return affect_monitor_check(s->opt->monitor, err);
}

static void reset(affect_laban_series *s)
{
    for (uint32_t r = 0; r < s->n_rows; r++) {
        s->qw[r].head = s->qw[r].count = 0;
        s->qt[r].head = s->qt[r].count = 0;
        memset(&s->time_sum[r], 0, sizeof s->time_sum[r]);
        memset(&s->flow_sum[r], 0, sizeof s->flow_sum[r]);
    }
    memset(s->path, 0, sizeof s->path);
}

affect_status affect_laban_series_new(const affect_motion *m, const affect_part *parts, uint32_t n,
                                      const affect_laban_options *opt,
                                      const affect_laban_series_options *so,
                                      affect_laban_series **out, affect_error *err)
{
    *out = NULL;
    if (so->window < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "the window must be at least 2 frames, got %u",
                           so->window);
    if (so->hop < 1)
        return affect_fail(err, AFFECT_ERR_INVALID, "the hop must be at least 1 frame, got 0");
    if ((so->weight != AFFECT_LABAN_Q1 && so->weight != AFFECT_LABAN_Q2) ||
        (so->time != AFFECT_LABAN_Q1 && so->time != AFFECT_LABAN_Q2))
        return affect_fail(err, AFFECT_ERR_INVALID, "unknown Weight or Time method");
    if (n < 1 || n > 6)
        return affect_fail(err, AFFECT_ERR_INVALID, "the Laban series needs 1 to 6 parts, got %u",
                           n);
    affect_laban_series *s = affect_calloc(1, sizeof *s);
    if (!s)
        return affect_nomem(err);
    s->m = m;
    if (!opt) {
        affect_laban_options_default(&s->opt_default);
        opt = &s->opt_default;
    }
    s->opt = opt;
    s->so = *so;
    memcpy(s->parts, parts, n * sizeof *parts);
    s->n_parts = n;
    s->n_rows = n + (so->combined ? 1 : 0);
    s->fps = m->fps;
    affect_status st =
        affect_laban_kinematics_block(m, parts, n, opt, &s->block, s->vel, s->acc, &s->stride, err);
    if (st)
        goto fail;
    uint32_t T = m->n_frames;
    s->window = so->window < T ? so->window : T;
    s->n_windows = so->window < T ? (T - so->window) / so->hop + 1 : 1;
    affect_ws_part ws[4 * MAX_ROWS + 1];
    size_t n_ws = 0;
    for (uint32_t r = 0; r < s->n_rows; r++) {
        s->qw[r].cap = s->qt[r].cap = s->window;
        ws[n_ws++] = (affect_ws_part){(void **)&s->qw[r].idx, s->window, sizeof(uint32_t)};
        ws[n_ws++] = (affect_ws_part){(void **)&s->qw[r].val, s->window, sizeof(double)};
        ws[n_ws++] = (affect_ws_part){(void **)&s->qt[r].idx, s->window, sizeof(uint32_t)};
        ws[n_ws++] = (affect_ws_part){(void **)&s->qt[r].val, s->window, sizeof(double)};
    }
    if (s->n_windows > 1 && so->hop < s->window) {
        size_t slots;
        if (!affect_mul_size(s->window, RING_SLOTS(s), &slots)) {
            st = affect_fail(err, AFFECT_ERR_RANGE, "window too long");
            goto fail;
        }
        ws[n_ws++] = (affect_ws_part){(void **)&s->ring, slots, sizeof(double)};
    }
    s->ws = affect_ws_alloc(ws, n_ws);
    if (!s->ws) {
        st = affect_nomem(err);
        goto fail;
    }
    s->next_poll = POLL_FRAMES;
    *out = s;
    return AFFECT_OK;
fail:
    affect_laban_series_free(s);
    return st;
}

uint32_t affect_laban_series_windows(const affect_laban_series *s)
{
    return s->n_windows;
}

uint32_t affect_laban_series_rows(const affect_laban_series *s)
{
    return s->n_rows;
}

affect_status affect_laban_series_next(affect_laban_series *s, uint32_t *first, uint32_t *last,
                                       double *values, affect_error *err)
{
    if (s->next_window >= s->n_windows)
        return affect_fail(err, AFFECT_ERR_RANGE, "no window left (the series has %u)",
                           s->n_windows);
    affect_status st;
    uint32_t f = s->next_window * s->so.hop, l = f + s->window - 1;
    if (!s->started || f > s->prev_last) {
        reset(s);
        for (uint32_t t = f; t <= l; t++) {
            add_frame(s, t, t > f);
            if ((st = tick(s, err)))
                return st;
        }
    } else {
        for (uint32_t t = s->prev_first + 1; t <= f; t++) {
            remove_frame(s, t);
            if ((st = tick(s, err)))
                return st;
        }
        for (uint32_t r = 0; r < s->n_rows; r++) {
            queue_expire(&s->qw[r], s->so.weight == AFFECT_LABAN_Q1 ? f : f + 1);
            queue_expire(&s->qt[r], f);
        }
        for (uint32_t t = s->prev_last + 1; t <= l; t++) {
            add_frame(s, t, true);
            if ((st = tick(s, err)))
                return st;
        }
    }
    s->started = true;
    s->prev_first = f;
    s->prev_last = l;
    s->next_window++;

    double ratio[6];
    for (uint32_t k = 0; k < s->n_parts; k++) {
        double path = dd_value(&s->path[k]), p0[3], p1[3];
        part_at(s, k, f, p0);
        part_at(s, k, l, p1);
        double disp = dist3(p1, p0);
        ratio[k] = path > 0 ? path / fmax(disp, path / s->opt->max_ratio) : 1.0;
    }
    double duration = (double)(l - f + 1) / s->fps;
    for (uint32_t r = 0; r < s->n_rows; r++) {
        uint32_t lo, hi;
        row_parts(s, r, &lo, &hi);
        double *row = values + (size_t)r * AFFECT_SERIES_N;
        row[AFFECT_SERIES_WEIGHT] = queue_front(&s->qw[r]);
        if (s->so.time == AFFECT_LABAN_Q1) {
            row[AFFECT_SERIES_TIME] = queue_front(&s->qt[r]);
        } else {
            double v = dd_value(&s->time_sum[r]);
            row[AFFECT_SERIES_TIME] = s->opt->time_per_second ? v / duration : v;
        }
        double mean = 0;
        for (uint32_t k = lo; k < hi; k++)
            mean += ratio[k];
        row[AFFECT_SERIES_SPACE] = mean / (hi - lo);
        row[AFFECT_SERIES_FLOW] = dd_value(&s->flow_sum[r]);
    }
    *first = f;
    *last = l;
    return AFFECT_OK;
}

void affect_laban_series_free(affect_laban_series *s)
{
    if (!s)
        return;
    affect_free(s->block);
    affect_free(s->ws);
    affect_free(s);
}
