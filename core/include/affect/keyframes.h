/*
 * affect/keyframes.h — keyframes by curve simplification (SCIENCE.md §6, step 2): the q frames
 * of a curve (a motion's poses) through which interpolation reconstructs it with the least
 * squared error, chosen exactly by dynamic programming.
 *
 * Usage:
 *     const affect_motion *m = ...;
 *     affect_error err;
 *     uint32_t frames[AFFECT_KEYFRAMES_DEFAULT], n = 0;    // room for q keyframes
 *     double rms = 0;
 *     if (affect_motion_keyframes(m, AFFECT_KEYFRAMES_DEFAULT, frames, &n, &rms, NULL, &err)
 *         != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("%u keyframes, last %u, rms %g\n", n, frames[n - 1], rms);
 *
 * Interpolation: piecewise linear between consecutive keyframes. It is the one for which the
 * choice can be made exactly: the error of a segment depends only on its two end keyframes, so
 *     E(q, b) = min_a E(q − 1, a) + cost(a, b)
 * over frames a < b is an exact recursion (O(q T²) after the costs). A cubic spline through the
 * keyframes couples every segment to its neighbours' tangents, so no exact recursion exists for
 * it; the paper's greedy choice is not optimal for either. The first and the last frame are
 * always keyframes (so the interpolation spans the motion). Synthesis (affect/strength.h)
 * interpolates the keyframes with C¹ Hermite cubics, whose error on real motions measures within
 * a few per cent of the linear one it was chosen for.
 *
 * Costs: the squared error of segment (a, b) is computed in O(D) from prefix sums of ‖y_t‖²,
 * y_t and t·y_t: with Δ = y_b − y_a, L = b − a, s_t = (t − a)/L,
 *     Σ_t ‖y_t − y_a − s_t Δ‖² = Σ‖y_t − y_a‖² − 2 Σ s_t (y_t − y_a)·Δ + ‖Δ‖² Σ s_t²
 * (sums over a < t < b; rounding can make it slightly negative: clamped at 0).
 *
 * Speed: the costs of a start a are computed for many ends at once, in vector lanes (on x86-64
 * with SSE2, AVX2 or AVX-512, the widest the processor has, chosen at run time); each lane does
 * the scalar operations in the scalar order, so the keyframes and errors are the same bits on
 * every processor. Rows are cut where a lower bound of their costs proves they cannot be on the
 * optimal path (affect/keyframes.c).
 *
 * When q ≥ T every frame is a keyframe and the error is 0. Errors: q < 2 with T ≥ 2, sizes too
 * large, interrupted (the DP polls the monitor once per row).
 */
#ifndef AFFECT_KEYFRAMES_H
#define AFFECT_KEYFRAMES_H

#include "affect/base.h"
#include "affect/monitor.h"
#include "affect/motion.h"

#ifdef __cplusplus
extern "C" {
#endif

#define AFFECT_KEYFRAMES_DEFAULT 13u
#define AFFECT_KEYFRAMES_MAX 4096u

/* The keyframes of the T × D row-major curve Y: frames (min(q, T) entries, increasing, first 0
 * and last T − 1) and the total squared error of piecewise-linear interpolation through them
 * (sse, may be NULL). *n_out = min(q, T). */
affect_status affect_keyframes_select(const double *Y, uint32_t T, uint32_t D, uint32_t q,
                                      uint32_t *frames, uint32_t *n_out, double *sse,
                                      affect_monitor *mon, affect_error *err);

/* The loops of affect_keyframes_select (exposed for tests). */
#define AFFECT_KEYFRAMES_LEVEL_SCALAR                                                              \
    (-1)                                /* plain C, one end at a time (compilers without           \
                                           GCC's vector extension run only these) */
#define AFFECT_KEYFRAMES_LEVEL_BASE 0   /* 2-lane vectors: SSE2 on x86-64 */
#define AFFECT_KEYFRAMES_LEVEL_AVX2 1   /* x86-64 with AVX2 */
#define AFFECT_KEYFRAMES_LEVEL_AVX512 2 /* x86-64 with AVX-512F */

/* The widest level this processor runs (what affect_keyframes_select uses). */
int affect_keyframes_level(void);

/* affect_keyframes_select with its loops at most at max_level (AFFECT_KEYFRAMES_LEVEL_…; a
 * level above the processor's is lowered to it): the same results, for tests that compare the
 * levels. */
affect_status affect_keyframes_select_level(const double *Y, uint32_t T, uint32_t D, uint32_t q,
                                            uint32_t *frames, uint32_t *n_out, double *sse,
                                            int max_level, affect_monitor *mon, affect_error *err);

/* The squared error of piecewise-linear interpolation of Y through the given keyframes (for
 * tests and reports). */
double affect_keyframes_error(const double *Y, uint32_t T, uint32_t D, const uint32_t *frames,
                              uint32_t n);

/* The same on a motion's joint positions (D = 3 × joints). rms (may be NULL) is the root mean
 * square joint distance over every frame and joint, in the motion's unit. */
affect_status affect_motion_keyframes(const affect_motion *m, uint32_t q, uint32_t *frames,
                                      uint32_t *n_out, double *rms, affect_monitor *mon,
                                      affect_error *err);

#ifdef __cplusplus
}
#endif
#endif
