/*
 * keyframes.c — exact keyframe selection by dynamic programming (affect/keyframes.h).
 *
 * Memory: the curve's coordinate-major copy and prefix sums, padded by KEYFRAME_BLOCK, and a
 * frame-major copy of the prefix sums (about (T + 17)(5D + 2) doubles), one row of segment
 * costs (T), the DP table and its back-pointers (q T each); sizes overflow-checked.
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

/* Ends whose segment sums are held in registers at once, at most: the zero padding of the
 * coordinate-major copies past the last frame (see ROW_COSTS). */
#define KEYFRAME_BLOCK 16u
/* The rounding of the prefix-sum costs and bounds is at most a few × eps × D × T³ × max|y|²
 * (the prefix sums of t·y_t are the largest terms); a bound prunes only when it clears the
 * threshold by KEYFRAME_PRUNE_SLACK × D × (T + 1)³ × max|y|², about 10⁴ times that. */
#define KEYFRAME_PRUNE_SLACK 1e-12

/* The inner loops (the segment costs and the DP's relaxation) are written once with GCC's and
 * Clang's vector extension, whose operations are the scalar ones lane by lane (not contracted
 * into fused multiply-adds: the build is ISO C, -ffp-contract=off), so every lane gives the
 * bits of the scalar loop whatever the width. On x86-64 they are compiled three times, for
 * SSE2 (the build's baseline), AVX2 and AVX-512, and the widest the processor has is chosen at
 * run time; the results are the same bits on every processor. Other compilers get the scalar
 * loops, which tests compare with the lanes (AFFECT_KEYFRAMES_LEVEL_SCALAR). */
#if defined(__GNUC__) || defined(__clang__)
#define KEYFRAME_VECTOR 1
#else
#define KEYFRAME_VECTOR 0
#endif
#if KEYFRAME_VECTOR && defined(__x86_64__)
#define KEYFRAME_X86 1
#else
#define KEYFRAME_X86 0
#endif

/* The prefix sums and coordinate-major copies of the curve that the costs are computed from:
 * yt (c × T), syt and styt (c × (T + 1): sums over frames 0 .. t − 1 at index t), sq (T + 1,
 * padded), and the prefix sums frame-major in pf. */
typedef struct {
    const double *Y;
    uint32_t T, D;
    size_t T1, TP, T1P; /* T + 1; the rows of yt and of syt, styt: T and T + 1 padded */
    const double *sq, *nrm, *yt, *syt, *styt; /* nrm[t] = ‖y_t‖² */
    const double *pf; /* (T + 1) × 2D: frame t's syt then styt values (for residual_bound) */
    int level;        /* the loops that run: AFFECT_KEYFRAMES_LEVEL_… */
} kf_sums;

#if KEYFRAME_VECTOR
/* ROW_COSTS(NAME, VT, MT, W) defines NAME(p, a, lo, hi, cost, nv): the costs of the segments
 * (a, b) for b = lo .. hi − 1 (a + 2 ≤ lo, hi ≤ T) into cost[b], W nv ends at a time (W lanes
 * of type VT, MT their 64-bit integer lanes, nv vectors per sum; constants where inlined). For each
 * end, four sums over the coordinates in order: Σ y_a·S_y, Σ (S_ty − a S_y)·Δ, Σ y_a·Δ and Σ Δ²,
 * with S the sums over the frames inside and Δ = y_b − y_a; then Σ_t ‖y_t − y_a − s_t Δ‖² from
 * them, clamped at 0. Ends past T − 1 read the zero padding (their values are not stored). Each
 * end's value is the same bits whatever the range, W and nv. */
#define ROW_COSTS(NAME, VT, MT, W)                                                                 \
    static inline __attribute__((always_inline)) void NAME(                                        \
        const kf_sums *p, uint32_t a, uint32_t lo, uint32_t hi, double *cost, uint32_t nv)         \
    {                                                                                              \
        const double *ya = p->Y + (size_t)a * p->D;                                                \
        double fa = (double)a, na = p->nrm[a], sqa = p->sq[a + 1];                                 \
        VT lane;                                                                                   \
        for (uint32_t j = 0; j < W; j++)                                                           \
            lane[j] = (double)j;                                                                   \
        for (uint32_t b0 = lo; b0 < hi; b0 += W * nv) {                                            \
            VT ysy[KEYFRAME_BLOCK / W] = {0}, tyd[KEYFRAME_BLOCK / W] = {0};                       \
            VT yd[KEYFRAME_BLOCK / W] = {0}, dd[KEYFRAME_BLOCK / W] = {0};                         \
            for (uint32_t c = 0; c < p->D; c++) {                                                  \
                const double *syc = p->syt + c * p->T1P, *styc = p->styt + c * p->T1P;             \
                const double *y = p->yt + c * p->TP + b0, *sy = syc + b0, *sty = styc + b0;        \
                double yac = ya[c], sya = syc[a + 1], stya = styc[a + 1];                          \
                for (uint32_t h = 0; h < nv; h++) {                                                \
                    VT vy, vsy, vsty; /* unaligned loads */                                        \
                    memcpy(&vy, y + W * h, sizeof vy);                                             \
                    memcpy(&vsy, sy + W * h, sizeof vsy);                                          \
                    memcpy(&vsty, sty + W * h, sizeof vsty);                                       \
                    VT Sy = vsy - sya, Sty = vsty - stya, delta = vy - yac;                        \
                    ysy[h] += yac * Sy;                                                            \
                    tyd[h] += (Sty - fa * Sy) * delta;                                             \
                    yd[h] += yac * delta;                                                          \
                    dd[h] += delta * delta;                                                        \
                }                                                                                  \
            }                                                                                      \
            for (uint32_t h = 0; h < nv && b0 + W * h < hi; h++) {                                 \
                uint32_t b = b0 + W * h, n = hi - b < W ? hi - b : W;                              \
                VT L = (double)(b - a) + lane, m = L - 1.0; /* m: frames strictly inside */        \
                VT sqb;                                                                            \
                memcpy(&sqb, p->sq + b, sizeof sqb);                                               \
                /* Σ s_t = Σ_{k=1}^{L−1} k/L = (L − 1) / 2, Σ s_t² = Σ k²/L² */         \
                VT s1 = (L - 1.0) / 2.0;                                                           \
                VT s2 = (L - 1.0) * (2.0 * L - 1.0) / (6.0 * L);                                   \
                VT cross = tyd[h] / L - s1 * yd[h];                                                \
                VT e = sqb - sqa + m * na - 2.0 * ysy[h] - 2.0 * cross + dd[h] * s2;               \
                e = (VT)((MT)e & (e > 0.0)); /* the mask's bits: all 1 or 0 */                     \
                memcpy(cost + b, &e, n * sizeof(double));                                          \
            }                                                                                      \
        }                                                                                          \
    }

/* RELAX(NAME, VT, MT, W) defines NAME(Ek, bk, cost, ep, a, lo, hi): for b = lo .. hi − 1, when
 * ep + cost[b] < Ek[b], Ek[b] takes it and bk[b] = a; W ends at a time in lanes of VT, MT the
 * matching 64-bit integer lanes (the comparison's mask). */
#define RELAX(NAME, VT, MT, W)                                                                     \
    static inline __attribute__((always_inline)) void NAME(double *Ek, uint64_t *bk,               \
                                                           const double *cost, double ep,          \
                                                           uint32_t a, uint32_t lo, uint32_t hi)   \
    {                                                                                              \
        uint32_t b = lo;                                                                           \
        MT av = {0};                                                                               \
        av += (long long)a;                                                                        \
        for (; b + W <= hi; b += W) {                                                              \
            VT c, e;                                                                               \
            MT k;                                                                                  \
            memcpy(&c, cost + b, sizeof c);                                                        \
            memcpy(&e, Ek + b, sizeof e);                                                          \
            memcpy(&k, bk + b, sizeof k);                                                          \
            VT v = ep + c;                                                                         \
            MT better = v < e;                                                                     \
            e = (VT)(((MT)v & better) | ((MT)e & ~better));                                        \
            k = (av & better) | (k & ~better);                                                     \
            memcpy(Ek + b, &e, sizeof e);                                                          \
            memcpy(bk + b, &k, sizeof k);                                                          \
        }                                                                                          \
        for (; b < hi; b++) {                                                                      \
            double v = ep + cost[b];                                                               \
            if (v < Ek[b]) {                                                                       \
                Ek[b] = v;                                                                         \
                bk[b] = a;                                                                         \
            }                                                                                      \
        }                                                                                          \
    }

typedef double kf_v2 __attribute__((vector_size(16)));
typedef long long kf_m2 __attribute__((vector_size(16)));
ROW_COSTS(row_costs2, kf_v2, kf_m2, 2)
RELAX(relax2, kf_v2, kf_m2, 2)
#if KEYFRAME_X86
typedef double kf_v4 __attribute__((vector_size(32)));
typedef long long kf_m4 __attribute__((vector_size(32)));
typedef double kf_v8 __attribute__((vector_size(64)));
typedef long long kf_m8 __attribute__((vector_size(64)));
ROW_COSTS(row_costs4, kf_v4, kf_m4, 4)
RELAX(relax4, kf_v4, kf_m4, 4)
ROW_COSTS(row_costs8, kf_v8, kf_m8, 8)
RELAX(relax8, kf_v8, kf_m8, 8)

/* The AVX2 copies: 4 lanes, 8 ends at a time (the 16 registers hold 8 sums). */
__attribute__((target("avx2"))) static void costs_avx2(const kf_sums *p, uint32_t a, uint32_t lo,
                                                       uint32_t hi, double *cost)
{
    row_costs4(p, a, lo, hi, cost, 2);
}

__attribute__((target("avx2"))) static void relax_avx2(double *Ek, uint64_t *bk, const double *cost,
                                                       double ep, uint32_t a, uint32_t lo,
                                                       uint32_t hi)
{
    relax4(Ek, bk, cost, ep, a, lo, hi);
}

/* The AVX-512 copies: 8 lanes, 16 ends at a time. */
__attribute__((target("avx512f"))) static void costs_avx512(const kf_sums *p, uint32_t a,
                                                            uint32_t lo, uint32_t hi, double *cost)
{
    row_costs8(p, a, lo, hi, cost, 2);
}

__attribute__((target("avx512f"))) static void relax_avx512(double *Ek, uint64_t *bk,
                                                            const double *cost, double ep,
                                                            uint32_t a, uint32_t lo, uint32_t hi)
{
    relax8(Ek, bk, cost, ep, a, lo, hi);
}
#endif
#endif

int affect_keyframes_level(void)
{
#if KEYFRAME_X86
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f"))
        return AFFECT_KEYFRAMES_LEVEL_AVX512;
    if (__builtin_cpu_supports("avx2"))
        return AFFECT_KEYFRAMES_LEVEL_AVX2;
#endif
    return KEYFRAME_VECTOR ? AFFECT_KEYFRAMES_LEVEL_BASE : AFFECT_KEYFRAMES_LEVEL_SCALAR;
}

/* The plain C loops, one end at a time (AFFECT_KEYFRAMES_LEVEL_SCALAR; compilers without the
 * vector extension run only these): the same operations as the lanes of ROW_COSTS and RELAX. */
static void costs_scalar(const kf_sums *p, uint32_t a, uint32_t lo, uint32_t hi, double *cost)
{
    const double *ya = p->Y + (size_t)a * p->D;
    double fa = (double)a, na = p->nrm[a];
    for (uint32_t b = lo; b < hi; b++) {
        double ysy = 0, tyd = 0, yd = 0, dd = 0;
        for (uint32_t c = 0; c < p->D; c++) {
            const double *syc = p->syt + c * p->T1P, *styc = p->styt + c * p->T1P;
            double Sy = syc[b] - syc[a + 1], Sty = styc[b] - styc[a + 1];
            double delta = p->yt[c * p->TP + b] - ya[c];
            ysy += ya[c] * Sy;
            tyd += (Sty - fa * Sy) * delta;
            yd += ya[c] * delta;
            dd += delta * delta;
        }
        double L = (double)(b - a), m = L - 1.0;
        double s1 = (L - 1.0) / 2.0, s2 = (L - 1.0) * (2.0 * L - 1.0) / (6.0 * L);
        double cross = tyd / L - s1 * yd;
        double e = p->sq[b] - p->sq[a + 1] + m * na - 2.0 * ysy - 2.0 * cross + dd * s2;
        cost[b] = e > 0 ? e : 0;
    }
}

static void relax_scalar(double *Ek, uint64_t *bk, const double *cost, double ep, uint32_t a,
                         uint32_t lo, uint32_t hi)
{
    for (uint32_t b = lo; b < hi; b++) {
        double v = ep + cost[b];
        if (v < Ek[b]) {
            Ek[b] = v;
            bk[b] = a;
        }
    }
}

/* The costs of the segments (a, b), b = lo .. hi − 1 (a + 2 ≤ lo, hi ≤ T), into cost[b] (see
 * ROW_COSTS), by the loops of p->level. */
static void segment_costs(const kf_sums *p, uint32_t a, uint32_t lo, uint32_t hi, double *cost)
{
#if KEYFRAME_X86
    if (p->level == AFFECT_KEYFRAMES_LEVEL_AVX512) {
        costs_avx512(p, a, lo, hi, cost);
        return;
    }
    if (p->level == AFFECT_KEYFRAMES_LEVEL_AVX2) {
        costs_avx2(p, a, lo, hi, cost);
        return;
    }
#endif
#if KEYFRAME_VECTOR
    if (p->level == AFFECT_KEYFRAMES_LEVEL_BASE) {
        row_costs2(p, a, lo, hi, cost, 4); /* 8 ends: the 16 SSE2 registers hold 16 sums */
        return;
    }
#endif
    costs_scalar(p, a, lo, hi, cost);
}

/* The DP's relaxation of row a into E[k][b] (Ek) for b = lo .. hi − 1, ep = E[k − 1][a]: a
 * candidate ep + cost[b] below Ek[b] replaces it, and bk[b] = a (the first of equal minima
 * stays), by the loops of p->level. */
static void relax(const kf_sums *p, double *Ek, uint64_t *bk, const double *cost, double ep,
                  uint32_t a, uint32_t lo, uint32_t hi)
{
#if KEYFRAME_X86
    if (p->level == AFFECT_KEYFRAMES_LEVEL_AVX512) {
        relax_avx512(Ek, bk, cost, ep, a, lo, hi);
        return;
    }
    if (p->level == AFFECT_KEYFRAMES_LEVEL_AVX2) {
        relax_avx2(Ek, bk, cost, ep, a, lo, hi);
        return;
    }
#endif
#if KEYFRAME_VECTOR
    if (p->level == AFFECT_KEYFRAMES_LEVEL_BASE) {
        relax2(Ek, bk, cost, ep, a, lo, hi);
        return;
    }
#endif
    relax_scalar(Ek, bk, cost, ep, a, lo, hi);
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
    uint32_t D = p->D;
    const double *ya = p->Y + (size_t)a * D;
    const double *pe = p->pf + (size_t)e * 2 * D, *pa = p->pf + (size_t)(a + 1) * 2 * D;
    double n = (double)(e - a - 1), fa = (double)a, nn = n * (n + 1) / 2;
    /* four partial sums each (only whether the bound clears a threshold with a slack matters,
     * so their order is free) */
    double ys[4] = {0, 0, 0, 0}, g2[4] = {0, 0, 0, 0};
    uint32_t c = 0;
    for (; c + 4 <= D; c += 4)
        for (uint32_t j = 0; j < 4; j++) {
            double Sy = pe[c + j] - pa[c + j], Sty = pe[D + c + j] - pa[D + c + j];
            double g = Sty - fa * Sy - ya[c + j] * nn;
            ys[j] += ya[c + j] * Sy;
            g2[j] += g * g;
        }
    for (; c < D; c++) {
        double Sy = pe[c] - pa[c], Sty = pe[D + c] - pa[D + c];
        double g = Sty - fa * Sy - ya[c] * nn;
        ys[0] += ya[c] * Sy;
        g2[0] += g * g;
    }
    double ysum = (ys[0] + ys[1]) + (ys[2] + ys[3]), gsum = (g2[0] + g2[1]) + (g2[2] + g2[3]);
    double h = n * (n + 1) * (2 * n + 1) / 6;
    return p->sq[e] - p->sq[a + 1] - 2 * ysum + n * p->nrm[a] - gsum / h;
}

/* Searches of row_end stop when the answer is known to within this many ends (the costs are
 * computed that many at a time anyway). */
#define KEYFRAME_END_SLOP 8u

/* An end past which row a is cut: the first end e ≤ T whose residual_bound exceeds thr, or one at
 * most KEYFRAME_END_SLOP after it (T if none exceeds it). The bound grows with the end, so it is
 * found by galloping from guess (the previous row's end, as neighbouring rows' ends are close)
 * towards the answer, then bisection. Ends before the result are relaxed; every end from it on
 * has a bound above thr. */
static uint32_t row_end(const kf_sums *p, uint32_t a, double thr, uint32_t guess)
{
    uint32_t T = p->T, lo = a + 2, hi = T; /* bound(lo) may pass; the answer is in (lo, hi] */
    if (guess > lo && guess < T) {
        if (residual_bound(p, a, guess) > thr) {
            hi = guess;
            for (uint32_t step = 1; guess - lo > step; step *= 2) {
                if (residual_bound(p, a, guess - step) <= thr) {
                    lo = guess - step;
                    break;
                }
                hi = guess - step;
            }
        } else {
            lo = guess;
        }
    }
    if (hi == T) /* gallop up from lo */
        for (uint32_t step = 1; lo + step < T; step *= 2) {
            if (residual_bound(p, a, lo + step) > thr) {
                hi = lo + step;
                break;
            }
            lo += step;
        }
    while (hi - lo > KEYFRAME_END_SLOP) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (residual_bound(p, a, mid) > thr)
            hi = mid;
        else
            lo = mid;
    }
    return hi;
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
                                  uint64_t *back, double *cost, affect_monitor *mon,
                                  affect_error *err)
{
    uint32_t T = p->T;
    for (size_t i = 0; i < (size_t)q * T; i++) {
        E[i] = INFINITY;
        back[i] = 0;
    }
    E[0] = 0;           /* one keyframe: frame 0 */
    uint32_t guess = 0; /* the last row's end */
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
        uint32_t bend = row_end(p, a, U - emin + slack, guess);
        guess = bend;
        cost[a + 1] = 0;
        segment_costs(p, a, a + 2, bend, cost);
        for (uint32_t k = 1; k <= kmax; k++) {
            double ep = E[(size_t)(k - 1) * T + a];
            if (!(ep <= U))
                continue;
            relax(p, E + (size_t)k * T, back + (size_t)k * T, cost, ep, a, a + 1, bend);
        }
    }
    return AFFECT_OK;
}

affect_status affect_keyframes_select(const double *Y, uint32_t T, uint32_t D, uint32_t q,
                                      uint32_t *frames, uint32_t *n_out, double *sse,
                                      affect_monitor *mon, affect_error *err)
{
    return affect_keyframes_select_level(Y, T, D, q, frames, n_out, sse,
                                         AFFECT_KEYFRAMES_LEVEL_AVX512, mon, err);
}

affect_status affect_keyframes_select_level(const double *Y, uint32_t T, uint32_t D, uint32_t q,
                                            uint32_t *frames, uint32_t *n_out, double *sse,
                                            int max_level, affect_monitor *mon, affect_error *err)
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
    double *sq = NULL, *nrm = NULL, *yt = NULL, *syt = NULL, *styt = NULL, *pf = NULL;
    double *cost = NULL;
    double *E = NULL;
    uint64_t *back = NULL;
    affect_ws_part parts[] = {
        {(void **)&sq, T1P, sizeof(double)},
        {(void **)&nrm, T, sizeof(double)},
        {(void **)&yt, TP * D, sizeof(double)},
        {(void **)&syt, T1P * D, sizeof(double)},
        {(void **)&styt, T1P * D, sizeof(double)},
        {(void **)&pf, T1 * 2 * D, sizeof(double)},
        {(void **)&cost, T, sizeof(double)},
        {(void **)&E, (size_t)q * T, sizeof(double)},
        {(void **)&back, (size_t)q * T, sizeof(uint64_t)},
    };
    void *block = affect_ws_alloc(parts, sizeof parts / sizeof parts[0]);
    if (!block)
        return affect_nomem_of(err, (size_t)T * D, 5 * sizeof(double),
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
    for (uint32_t j = 0; j < KEYFRAME_BLOCK; j++)
        sq[T1 + j] = 0;
    for (size_t t = 0; t < T1; t++)
        for (uint32_t c = 0; c < D; c++) {
            pf[t * 2 * D + c] = syt[c * T1P + t];
            pf[t * 2 * D + D + c] = styt[c * T1P + t];
        }
    int level = affect_keyframes_level();
    if (max_level < level)
        level =
            max_level < AFFECT_KEYFRAMES_LEVEL_SCALAR ? AFFECT_KEYFRAMES_LEVEL_SCALAR : max_level;
    kf_sums p = {Y, T, D, T1, TP, T1P, sq, nrm, yt, syt, styt, pf, level};
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
