/*
 * keyframes.c — exact keyframe selection by dynamic programming (affect/keyframes.h).
 *
 * Memory: prefix sums ((T + 1)(2D + 1) doubles), the segment costs (T² doubles, upper
 * triangle used), the DP table and its back-pointers (q T each); sizes overflow-checked.
 * The costs are computed once (O(T² D)); the DP is O(q T²).
 */
#include "affect/keyframes.h"

#include <math.h>
#include <string.h>

#include "util/internal.h"

#define MAX_CELLS ((size_t)1 << 28) /* T² cost table: refused above 2^28 cells (2 GiB) */

double affect_keyframes_error(const double *Y, uint32_t T, uint32_t D, const uint32_t *frames,
                              uint32_t n)
{
    double sse = 0;
    for (uint32_t k = 0; k + 1 < n; k++) {
        uint32_t a = frames[k], b = frames[k + 1];
        for (uint32_t t = a + 1; t < b; t++) {
            double s = (double)(t - a) / (double)(b - a);
            for (uint32_t c = 0; c < D; c++) {
                double ya = Y[(size_t)a * D + c], yb = Y[(size_t)b * D + c];
                double e = Y[(size_t)t * D + c] - (ya + s * (yb - ya));
                sse += e * e;
            }
        }
    }
    (void)T;
    return sse;
}

/* The segment sums are added in blocks of this many ends b: a loop of a constant count over
 * arrays that do not overlap, which compilers vectorize (the same operations per element, so
 * the same bits). */
#define KEYFRAME_BLOCK 8u

/* Adds coordinate c's terms to the four sums of n segment ends (see affect_keyframes_select):
 * y, sy, sty are the coordinate's values and prefix sums at those ends, ya, sya, stya at the
 * segment's start a (fa = a). */
static inline void segment_sums(const double *restrict y, const double *restrict sy,
                                const double *restrict sty, double ya, double sya, double stya,
                                double fa, double *restrict ysy, double *restrict tyd,
                                double *restrict yd, double *restrict dd, uint32_t n)
{
    for (uint32_t j = 0; j < n; j++) {
        double Sy = sy[j] - sya;
        double Sty = sty[j] - stya;
        double delta = y[j] - ya;
        ysy[j] += ya * Sy;
        tyd[j] += (Sty - fa * Sy) * delta;
        yd[j] += ya * delta;
        dd[j] += delta * delta;
    }
}

affect_status affect_keyframes_select(const double *Y, uint32_t T, uint32_t D, uint32_t q,
                                      uint32_t *frames, uint32_t *n_out, double *sse,
                                      affect_monitor *mon, affect_error *err)
{
    *n_out = 0;
    if (T == 0 || D == 0)
        return affect_fail(err, AFFECT_ERR_RANGE, "empty curve (%u frames of %u values)", T, D);
    if (q > AFFECT_KEYFRAMES_MAX)
        return affect_fail(err, AFFECT_ERR_RANGE, "keyframes must be from 2 to %u (got %u)",
                           AFFECT_KEYFRAMES_MAX, q);
    if (q >= T) {
        for (uint32_t t = 0; t < T; t++)
            frames[t] = t;
        *n_out = T;
        if (sse)
            *sse = 0;
        return AFFECT_OK;
    }
    if (q < 2)
        return affect_fail(err, AFFECT_ERR_RANGE, "keyframes must be from 2 to %u (got %u)",
                           AFFECT_KEYFRAMES_MAX, q);
    size_t cells;
    if (!affect_mul_size(T, T, &cells) || cells > MAX_CELLS)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "%u frames is too many for exact keyframe selection (at most 16384)", T);
    /* Coordinate-major copies (c × frames) of Y and of its prefix sums, so that the segment
     * costs of one start a are accumulated for every end b at once: each b's four sums still
     * run over the coordinates in order (the same bits as one b at a time), but the ends are
     * independent, so the loop over them is not bound by the latency of one chain. */
    size_t T1 = (size_t)T + 1;
    double *sq = NULL, *yt = NULL, *syt = NULL, *styt = NULL, *cost = NULL, *E = NULL;
    double *acc_ysy = NULL, *acc_tyd = NULL, *acc_yd = NULL, *acc_dd = NULL;
    uint32_t *back = NULL;
    affect_ws_part parts[] = {
        {(void **)&sq, T1, sizeof(double)},
        {(void **)&yt, (size_t)T * D, sizeof(double)},
        {(void **)&syt, T1 * D, sizeof(double)},
        {(void **)&styt, T1 * D, sizeof(double)},
        {(void **)&acc_ysy, T, sizeof(double)},
        {(void **)&acc_tyd, T, sizeof(double)},
        {(void **)&acc_yd, T, sizeof(double)},
        {(void **)&acc_dd, T, sizeof(double)},
        {(void **)&cost, cells, sizeof(double)},
        {(void **)&E, (size_t)q * T, sizeof(double)},
        {(void **)&back, (size_t)q * T, sizeof(uint32_t)},
    };
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return affect_nomem_of(err, cells, sizeof(double), "the %u x %u keyframe cost table", T, T);
    affect_status status = AFFECT_OK;
    /* prefix sums over frames 0 .. t − 1 at index t */
    sq[0] = 0;
    for (uint32_t c = 0; c < D; c++)
        syt[c * T1] = styt[c * T1] = 0;
    for (uint32_t t = 0; t < T; t++) {
        const double *y = Y + (size_t)t * D;
        double n2 = 0;
        for (uint32_t c = 0; c < D; c++) {
            n2 += y[c] * y[c];
            yt[(size_t)c * T + t] = y[c];
            syt[c * T1 + t + 1] = syt[c * T1 + t] + y[c];
            styt[c * T1 + t + 1] = styt[c * T1 + t] + (double)t * y[c];
        }
        sq[t + 1] = sq[t] + n2;
    }
    for (uint32_t a = 0; a < T; a++) {
        status = affect_monitor_check(mon, err);
        if (status != AFFECT_OK)
            goto cleanup;
        const double *ya = Y + (size_t)a * D;
        double na = 0;
        for (uint32_t c = 0; c < D; c++)
            na += ya[c] * ya[c];
        cost[(size_t)a * T + a] = 0;
        if (a + 1 < T)
            cost[(size_t)a * T + a + 1] = 0;
        if (a + 2 >= T)
            continue;
        /* Σ s_t (y_t − y_a)·Δ = (Σ (t − a) y_t · Δ)/L − s1 y_a·Δ: the four sums are
         * accumulated apart (no division in the loop), for the ends b = a + 2 .. T − 1 */
        uint32_t b0 = a + 2;
        size_t nb = T - b0;
        memset(acc_ysy + b0, 0, nb * sizeof(double));
        memset(acc_tyd + b0, 0, nb * sizeof(double));
        memset(acc_yd + b0, 0, nb * sizeof(double));
        memset(acc_dd + b0, 0, nb * sizeof(double));
        double fa = (double)a;
        for (uint32_t c = 0; c < D; c++) {
            const double *yc = yt + (size_t)c * T, *syc = syt + c * T1, *styc = styt + c * T1;
            double yac = ya[c], sya = syc[a + 1], stya = styc[a + 1];
            uint32_t b = b0;
            for (; b + KEYFRAME_BLOCK <= T; b += KEYFRAME_BLOCK)
                segment_sums(yc + b, syc + b, styc + b, yac, sya, stya, fa, acc_ysy + b,
                             acc_tyd + b, acc_yd + b, acc_dd + b, KEYFRAME_BLOCK);
            segment_sums(yc + b, syc + b, styc + b, yac, sya, stya, fa, acc_ysy + b, acc_tyd + b,
                         acc_yd + b, acc_dd + b, T - b);
        }
        for (uint32_t b = b0; b < T; b++) {
            double m = (double)(b - a - 1); /* frames strictly inside */
            double L = (double)(b - a);
            /* Σ s_t = Σ_{k=1}^{L−1} k/L, Σ s_t² = Σ k²/L² */
            double s1 = (L - 1) / 2.0;
            double s2 = (L - 1) * (2 * L - 1) / (6.0 * L);
            double cross = acc_tyd[b] / L - s1 * acc_yd[b];
            double e = sq[b] - sq[a + 1] + m * na - 2 * acc_ysy[b] - 2 * cross + acc_dd[b] * s2;
            cost[(size_t)a * T + b] = e > 0 ? e : 0;
        }
    }
    /* E[k][b]: least error of frames 0 .. b with k + 1 keyframes, the last at b */
    for (uint32_t b = 0; b < T; b++) {
        E[b] = b == 0 ? 0 : INFINITY; /* one keyframe: frame 0 */
        back[b] = 0;
    }
    for (uint32_t k = 1; k < q; k++) {
        status = affect_monitor_check(mon, err);
        if (status != AFFECT_OK)
            goto cleanup;
        double *Ek = E + (size_t)k * T, *Ep = E + (size_t)(k - 1) * T;
        uint32_t *bk = back + (size_t)k * T;
        for (uint32_t b = 0; b < T; b++) {
            if (b < k) {
                Ek[b] = INFINITY;
                bk[b] = 0;
                continue;
            }
            double best = INFINITY;
            uint32_t arg = k - 1;
            for (uint32_t a = k - 1; a < b; a++) {
                double v = Ep[a] + cost[(size_t)a * T + b];
                if (v < best) {
                    best = v;
                    arg = a;
                }
            }
            Ek[b] = best;
            bk[b] = arg;
        }
    }
    uint32_t b = T - 1;
    for (uint32_t k = q; k-- > 0;) {
        frames[k] = b;
        b = back[(size_t)k * T + b];
    }
    *n_out = q;
    if (sse)
        *sse = affect_keyframes_error(Y, T, D, frames, q); /* exact, not the prefix-sum value */
cleanup:
    affect_free(block);
    return status;
}

affect_status affect_motion_keyframes(const affect_motion *m, uint32_t q, uint32_t *frames,
                                      uint32_t *n_out, double *rms, affect_monitor *mon,
                                      affect_error *err)
{
    uint32_t T = m->n_frames, D;
    size_t n;
    if (!affect_mul_size((size_t)m->n_joints, 3, &n) || n > UINT32_MAX ||
        !affect_mul_size(n, T, &n))
        return affect_fail(err, AFFECT_ERR_RANGE, "motion too large");
    D = m->n_joints * 3;
    double *Y = affect_malloc_array(n, sizeof(double));
    if (!Y)
        return affect_nomem_of(err, n, sizeof(double), "the motion's positions");
    for (size_t k = 0; k < n; k++)
        Y[k] = m->pos[k];
    double sse = 0;
    affect_status st = affect_keyframes_select(Y, T, D, q, frames, n_out, &sse, mon, err);
    if (st == AFFECT_OK && rms)
        *rms = sqrt(sse / ((double)T * (double)m->n_joints));
    affect_free(Y);
    return st;
}
