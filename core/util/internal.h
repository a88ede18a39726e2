/*
 * internal.h — small helpers shared by the core's .c files (not part of the public API).
 */
#ifndef AFFECT_INTERNAL_H
#define AFFECT_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

/* FNV-1a hash of a NUL-terminated string (joint-name sets). */
static inline uint32_t affect_hash_name(const char *s)
{
    uint32_t h = 2166136261u;
    for (; *s; s++)
        h = (h ^ (unsigned char)*s) * 16777619u;
    return h;
}

/* One allocation for a workspace of several arrays: each part receives a pointer into one block
 * (count elements of elem bytes, each part 64-byte aligned within it). Returns the block (free
 * it with affect_free) or NULL on overflow or allocation failure (the slots are then unset). */
typedef struct affect_ws_part {
    void **slot;
    size_t count;
    size_t elem;
} affect_ws_part;

void *affect_ws_alloc(const affect_ws_part *parts, size_t n);

/* A parallel for over items 0 .. n − 1 (parallel.c): fn(ctx, i, err) on up to `threads` C11
 * threads, the items taken in increasing order from a shared counter. Each item must write
 * only its own outputs, so the results do not depend on the schedule. After a failure no
 * further item starts; the result is the status and error of the lowest-index failing item
 * (deterministic: every item below a failing one was taken, and runs to its end), or
 * AFFECT_OK. threads ≤ 1, or a thread that cannot be created, runs the items in the caller.
 * The allocator and the BLAS must be thread-safe (SQLite's and OpenBLAS's are). */
#include "affect/base.h"
#include "affect/monitor.h"
#include "affect/motion.h"
/* affect_motion_create and affect_motion_add_skeleton, with the positions (zero false), the
 * rotations and translations (fill false) allocated but not set: the caller must write every
 * sample before anyone reads them (core/motion/motion.c). A parser that fills a motion frame by
 * frame uses them so that the memory is first touched between its polls of the monitor. */
affect_status affect_motion_create_as(uint32_t n_frames, uint32_t n_joints, double fps, bool zero,
                                      affect_motion **out, affect_error *err);
affect_status affect_motion_add_skeleton_as(affect_motion *m, bool rotations, bool fill,
                                            affect_error *err);

typedef affect_status (*affect_item_fn)(void *ctx, uint32_t i, affect_error *err);
/* mon (may be NULL): when the calling thread has taken its last item it keeps asking mon's stop
 * hook (which only it may call) until the other threads are done. */
affect_status affect_parallel_for(uint32_t n, uint32_t threads, affect_item_fn fn, void *ctx,
                                  affect_monitor *mon, affect_error *err);

/* OpenBLAS on one thread during each BLAS or LAPACK call of the core (blas.c), so that results
 * do not depend on OpenBLAS's thread count: AFFECT_BLAS(cblas_dgemm(...)); or
 * AFFECT_BLAS(info = LAPACKE_dpotrf_work(...)); around every call (a test checks core/). */
void affect_blas_begin(void);
void affect_blas_end(void);
#define AFFECT_BLAS(call)                                                                          \
    do {                                                                                           \
        affect_blas_begin();                                                                       \
        call;                                                                                      \
        affect_blas_end();                                                                         \
    } while (0)

/* Eigen-decomposition of the symmetric n × n array G (rank.c): G is first symmetrized (each
 * pair replaced by its mean), then LAPACKE_dsyev_work runs in column-major form on it (the
 * same matrix) with the minimal workspace work (3n − 1 doubles), so nothing is allocated
 * outside ours; ev gets the eigenvalues in ascending order and row k of G the eigenvector of
 * ev[k]. Returns LAPACK's info (0 on success). */
int affect_sym_eigen(double *G, uint32_t n, double *ev, double *work);

/* The filtered velocity and acceleration of n parts (1 to 6) of a motion (laban.c), exactly as
 * affect_kinematics_compute gives them (to the bit), in one block (*block, affect_free it):
 * part k's velocity and acceleration at frame t are vel[k] + t·stride and acc[k] + t·stride
 * (3 doubles each). Checks opt (affect_laban_options) and that the motion has at least 4
 * frames (AFFECT_ERR_RANGE); polls opt->monitor. For laban_series.c. */
#include "affect/laban.h"
affect_status affect_laban_kinematics_block(const affect_motion *m, const affect_part *parts,
                                            uint32_t n, const affect_laban_options *opt,
                                            double **block, const double *vel[6],
                                            const double *acc[6], size_t *stride,
                                            affect_error *err);

#endif
