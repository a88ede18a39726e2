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

#include "internal.h"

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
    double *sq = NULL, *sy = NULL, *sty = NULL, *cost = NULL, *E = NULL;
    uint32_t *back = NULL;
    affect_ws_part parts[] = {
        {(void **)&sq, (size_t)T + 1, sizeof(double)},
        {(void **)&sy, ((size_t)T + 1) * D, sizeof(double)},
        {(void **)&sty, ((size_t)T + 1) * D, sizeof(double)},
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
    memset(sy, 0, sizeof(double) * D);
    memset(sty, 0, sizeof(double) * D);
    for (uint32_t t = 0; t < T; t++) {
        const double *y = Y + (size_t)t * D;
        double n2 = 0;
        for (uint32_t c = 0; c < D; c++) {
            n2 += y[c] * y[c];
            sy[(size_t)(t + 1) * D + c] = sy[(size_t)t * D + c] + y[c];
            sty[(size_t)(t + 1) * D + c] = sty[(size_t)t * D + c] + (double)t * y[c];
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
        for (uint32_t b = a + 2; b < T; b++) {
            const double *yb = Y + (size_t)b * D;
            double m = (double)(b - a - 1); /* frames strictly inside */
            double L = (double)(b - a);
            /* Σ s_t = Σ_{k=1}^{L−1} k/L, Σ s_t² = Σ k²/L² */
            double s1 = (L - 1) / 2.0;
            double s2 = (L - 1) * (2 * L - 1) / (6.0 * L);
            /* Σ s_t (y_t − y_a)·Δ = (Σ (t − a) y_t · Δ)/L − s1 y_a·Δ: the four sums are
             * accumulated apart (independent chains; no division in the loop) */
            const double *syb = sy + (size_t)b * D, *sya = sy + (size_t)(a + 1) * D;
            const double *styb = sty + (size_t)b * D, *stya = sty + (size_t)(a + 1) * D;
            double ySy = 0, tyd = 0, yd = 0, dd = 0, fa = (double)a;
            for (uint32_t c = 0; c < D; c++) {
                double Sy = syb[c] - sya[c];
                double Sty = styb[c] - stya[c];
                double delta = yb[c] - ya[c];
                ySy += ya[c] * Sy;
                tyd += (Sty - fa * Sy) * delta;
                yd += ya[c] * delta;
                dd += delta * delta;
            }
            double cross = tyd / L - s1 * yd;
            double e = sq[b] - sq[a + 1] + m * na - 2 * ySy - 2 * cross + dd * s2;
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
