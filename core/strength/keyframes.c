/*
 * keyframes.c — exact keyframe selection by dynamic programming (affect/keyframes.h).
 *
 * Memory: the curve's coordinate-major copy and prefix sums ((T + 1)(3D + 2) doubles), one row
 * of segment costs (T), the DP table and its back-pointers (q T each); sizes overflow-checked.
 * The costs are computed at most once each (O(T² D)), row by row as the DP needs them, and the
 * rows are cut where a lower bound proves the rest cannot be on the optimal path (see
 * keyframes_dp); the DP is O(q T²) at most.
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

/* The segment sums of this many ends b are held in registers while the coordinates are added
 * (a loop of a constant count that compilers unroll and vectorize; the same operations per
 * end, so the same bits). */
#define KEYFRAME_BLOCK 8u
/* The rounding of the prefix-sum costs and bounds is at most a few × eps × D × T³ × max|y|²
 * (the prefix sums of t·y_t are the largest terms); a bound prunes only when it clears the
 * threshold by KEYFRAME_PRUNE_SLACK × D × (T + 1)³ × max|y|², about 10⁴ times that. */
#define KEYFRAME_PRUNE_SLACK 1e-12

/* The prefix sums and coordinate-major copies of the curve that the costs are computed from:
 * yt (c × T), syt and styt (c × (T + 1): sums over frames 0 .. t − 1 at index t), sq (T + 1). */
typedef struct {
    const double *Y;
    uint32_t T, D;
    size_t T1, TP, T1P; /* T + 1; the rows of yt and of syt, styt: T and T + 1 padded */
    const double *sq, *nrm, *yt, *syt, *styt; /* nrm[t] = ‖y_t‖² */
} kf_sums;

/* The four sums of segments (a, b0 + j), j < KEYFRAME_BLOCK (see segment_costs), over the
 * coordinates in order, into out[0 .. 3][j]: a loop of constant count whose sums stay in
 * registers. Ends past T − 1 read the zero padding of the copies (their sums are not used). */
static inline void block_sums(const kf_sums *p, uint32_t a, uint32_t b0,
                              double out[4][KEYFRAME_BLOCK])
{
    double ysy[KEYFRAME_BLOCK] = {0}, tyd[KEYFRAME_BLOCK] = {0};
    double yd[KEYFRAME_BLOCK] = {0}, dd[KEYFRAME_BLOCK] = {0};
    const double *ya = p->Y + (size_t)a * p->D;
    double fa = (double)a;
    for (uint32_t c = 0; c < p->D; c++) {
        const double *syc = p->syt + c * p->T1P, *styc = p->styt + c * p->T1P;
        const double *y = p->yt + c * p->TP + b0, *sy = syc + b0, *sty = styc + b0;
        double yac = ya[c], sya = syc[a + 1], stya = styc[a + 1];
        for (uint32_t j = 0; j < KEYFRAME_BLOCK; j++) {
            double Sy = sy[j] - sya;
            double Sty = sty[j] - stya;
            double delta = y[j] - yac;
            ysy[j] += yac * Sy;
            tyd[j] += (Sty - fa * Sy) * delta;
            yd[j] += yac * delta;
            dd[j] += delta * delta;
        }
    }
    for (uint32_t j = 0; j < KEYFRAME_BLOCK; j++) {
        out[0][j] = ysy[j];
        out[1][j] = tyd[j];
        out[2][j] = yd[j];
        out[3][j] = dd[j];
    }
}

/* The costs of the segments (a, b) for b = lo .. hi − 1 (a + 2 ≤ lo, hi ≤ T) into cost[b]: for
 * every end, the four sums over the coordinates in order (Σ y_a·S_y, Σ (S_ty − a S_y)·Δ,
 * Σ y_a·Δ, Σ Δ², with S the sums over the frames inside), then Σ_t ‖y_t − y_a − s_t Δ‖²,
 * clamped at 0. Each end's value is the same bits whatever the range it is computed in. */
static void segment_costs(const kf_sums *p, uint32_t a, uint32_t lo, uint32_t hi, double *cost)
{
    double na = p->nrm[a];
    for (uint32_t b0 = lo; b0 < hi; b0 += KEYFRAME_BLOCK) {
        double acc[4][KEYFRAME_BLOCK];
        block_sums(p, a, b0, acc);
        uint32_t n = hi - b0 < KEYFRAME_BLOCK ? hi - b0 : KEYFRAME_BLOCK;
        for (uint32_t j = 0; j < n; j++) {
            uint32_t b = b0 + j;
            double m = (double)(b - a - 1); /* frames strictly inside */
            double L = (double)(b - a);
            /* Σ s_t = Σ_{k=1}^{L−1} k/L, Σ s_t² = Σ k²/L² */
            double s1 = (L - 1) / 2.0;
            double s2 = (L - 1) * (2 * L - 1) / (6.0 * L);
            double cross = acc[1][j] / L - s1 * acc[2][j];
            double e =
                p->sq[b] - p->sq[a + 1] + m * na - 2 * acc[0][j] - 2 * cross + acc[3][j] * s2;
            cost[b] = e > 0 ? e : 0;
        }
    }
}

/* The cost of the one segment (a, b), a < b (cost: scratch of T): the same bits as in a row. */
static double cell_cost(const kf_sums *p, uint32_t a, uint32_t b, double *cost)
{
    if (b < a + 2)
        return 0;
    segment_costs(p, a, b, b + 1, cost);
    return cost[b];
}

/* A lower bound of the cost of every segment (a, b) with b ≥ e (a + 2 ≤ e ≤ T): the least
 * squared error of the frames a < t < e about any line through y_a, y_a + (t − a) v,
 *     Σ‖y_t − y_a‖² − ‖Σ (t − a)(y_t − y_a)‖² / Σ (t − a)²
 * (the segment's own line is one of them, and a longer segment has more frames inside). */
static double residual_bound(const kf_sums *p, uint32_t a, uint32_t e)
{
    const double *ya = p->Y + (size_t)a * p->D;
    double n = (double)(e - a - 1), fa = (double)a;
    double na = p->nrm[a], ysum = 0, g2 = 0;
    for (uint32_t c = 0; c < p->D; c++) {
        const double *syc = p->syt + c * p->T1P, *styc = p->styt + c * p->T1P;
        double Sy = syc[e] - syc[a + 1], Sty = styc[e] - styc[a + 1];
        double g = Sty - fa * Sy - ya[c] * (n * (n + 1) / 2);
        ysum += ya[c] * Sy;
        g2 += g * g;
    }
    double h = n * (n + 1) * (2 * n + 1) / 6;
    return p->sq[e] - p->sq[a + 1] - 2 * ysum + n * na - g2 / h;
}

/* The DP of affect_keyframes_select, the cost rows taken in order of their start a: E[k][·]
 * at a is final once the rows before a are relaxed, so each row is computed, relaxed into every
 * E[k][b], and dropped (no T² table). The candidates of each E[k][b] are still taken in
 * increasing a, with the same values, so the minima and their first arguments are those of
 * the DP over the whole table. Pruning by an upper bound U of the optimum (the error of a
 * feasible choice, summed as the DP sums it): a state E[k][a] > U cannot be on the optimal
 * path (costs are ≥ 0, so the sums along a path only grow), nor can a candidate whose value
 * exceeds U decide a state that is (it is larger than that state's minimum, so it breaks no
 * tie); such candidates are skipped: a row's states above U, and its ends past the first
 * whose residual_bound exceeds U − (the row's least state) by the slack. States the pruning
 * changes stay above U; every state at most the optimum — the path — keeps its value and its
 * back-pointer. */
static affect_status keyframes_dp(const kf_sums *p, uint32_t q, double U, double slack, double *E,
                                  uint32_t *back, double *cost, affect_monitor *mon,
                                  affect_error *err)
{
    uint32_t T = p->T;
    for (size_t i = 0; i < (size_t)q * T; i++) {
        E[i] = INFINITY;
        back[i] = 0;
    }
    E[0] = 0; /* one keyframe: frame 0 */
    for (uint32_t a = 0; a + 1 < T; a++) {
        affect_status st = affect_monitor_check(mon, err);
        if (st != AFFECT_OK)
            return st;
        double emin = INFINITY;
        uint32_t kmax = a + 1 < q - 1 ? a + 1 : q - 1; /* E[k − 1][a] with k − 1 ≤ a */
        for (uint32_t k = 1; k <= kmax; k++)
            if (E[(size_t)(k - 1) * T + a] <= U && E[(size_t)(k - 1) * T + a] < emin)
                emin = E[(size_t)(k - 1) * T + a];
        if (!(emin <= U))
            continue;
        /* ends a + 1 .. bend − 1, bend the first end whose bound exceeds U − emin by the
         * slack (the bound grows with the end: galloping, then bisection) */
        double thr = U - emin + slack;
        uint32_t lo = a + 2, hi = T; /* bound(lo) may pass, the answer is in (lo, hi] */
        for (uint32_t step = 1; lo + step < T; step *= 2) {
            if (residual_bound(p, a, lo + step) > thr) {
                hi = lo + step;
                break;
            }
            lo += step;
        }
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            if (residual_bound(p, a, mid) > thr)
                hi = mid;
            else
                lo = mid;
        }
        uint32_t bend = hi;
        cost[a + 1] = 0;
        segment_costs(p, a, a + 2, bend, cost);
        for (uint32_t k = 1; k <= kmax; k++) {
            double ep = E[(size_t)(k - 1) * T + a];
            if (!(ep <= U))
                continue;
            double *Ek = E + (size_t)k * T;
            uint32_t *bk = back + (size_t)k * T;
            for (uint32_t b = a + 1; b < bend; b++) {
                double v = ep + cost[b];
                if (v < Ek[b]) {
                    Ek[b] = v;
                    bk[b] = a;
                }
            }
        }
    }
    return AFFECT_OK;
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
     * costs of one start a are accumulated for a chunk of ends b at once: each b's four sums
     * still run over the coordinates in order (the same bits as one b at a time), but the ends
     * are independent, so the loop over them is not bound by the latency of one chain. */
    size_t T1 = (size_t)T + 1, TP = (size_t)T + KEYFRAME_BLOCK, T1P = T1 + KEYFRAME_BLOCK;
    double *sq = NULL, *nrm = NULL, *yt = NULL, *syt = NULL, *styt = NULL, *cost = NULL;
    double *E = NULL;
    uint32_t *back = NULL;
    affect_ws_part parts[] = {
        {(void **)&sq, T1, sizeof(double)},
        {(void **)&nrm, T, sizeof(double)},
        {(void **)&yt, TP * D, sizeof(double)},
        {(void **)&syt, T1P * D, sizeof(double)},
        {(void **)&styt, T1P * D, sizeof(double)},
        {(void **)&cost, T, sizeof(double)},
        {(void **)&E, (size_t)q * T, sizeof(double)},
        {(void **)&back, (size_t)q * T, sizeof(uint32_t)},
    };
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return affect_nomem_of(err, (size_t)T * D, 3 * sizeof(double),
                               "the %u x %u keyframe prefix sums", T, D);
    affect_status status = AFFECT_OK;
    /* prefix sums over frames 0 .. t − 1 at index t */
    sq[0] = 0;
    double ymax = 0;
    for (uint32_t c = 0; c < D; c++)
        syt[c * T1P] = styt[c * T1P] = 0;
    for (uint32_t t = 0; t < T; t++) {
        const double *y = Y + (size_t)t * D;
        double n2 = 0;
        for (uint32_t c = 0; c < D; c++) {
            n2 += y[c] * y[c];
            yt[c * TP + t] = y[c];
            syt[c * T1P + t + 1] = syt[c * T1P + t] + y[c];
            styt[c * T1P + t + 1] = styt[c * T1P + t] + (double)t * y[c];
            ymax = fmax(ymax, fabs(y[c]));
        }
        nrm[t] = n2;
        sq[t + 1] = sq[t] + n2;
    }
    for (uint32_t c = 0; c < D; c++) /* the padding past the last frame */
        for (uint32_t j = 0; j < KEYFRAME_BLOCK; j++) {
            yt[c * TP + T + j] = 0;
            syt[c * T1P + T1 + j] = styt[c * T1P + T1 + j] = 0;
        }
    kf_sums p = {Y, T, D, T1, TP, T1P, sq, nrm, yt, syt, styt};
    /* U: the error of evenly spaced keyframes, their costs summed in order from 0 as the DP
     * sums a path's (so the DP's optimum is at most U). (A local search that moved each
     * keyframe to its best frame between its neighbours brought U near the optimum but cost
     * more than the rows it pruned.) */
    for (uint32_t k = 0; k < q; k++)
        frames[k] = (uint32_t)(((uint64_t)k * (T - 1)) / (q - 1));
    double U = 0;
    for (uint32_t k = 1; k < q; k++)
        U = U + cell_cost(&p, frames[k - 1], frames[k], cost);
    double fT = (double)T + 1;
    double slack = KEYFRAME_PRUNE_SLACK * (double)D * fT * fT * fT * ymax * ymax;
    if (!isfinite(U) || !isfinite(slack))
        U = INFINITY;
    status = keyframes_dp(&p, q, U, slack, E, back, cost, mon, err);
    /* the optimum is at most U by construction; should rounding ever say otherwise, the DP
     * runs again without pruning */
    if (status == AFFECT_OK && !(E[(size_t)(q - 1) * T + T - 1] <= U) && isfinite(U))
        status = keyframes_dp(&p, q, INFINITY, slack, E, back, cost, mon, err);
    if (status != AFFECT_OK)
        goto cleanup;
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
