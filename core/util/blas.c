/*
 * blas.c — affect_blas_begin / affect_blas_end (internal.h): every BLAS and LAPACK call of the
 * core runs with OpenBLAS on one thread, so that no result depends on OpenBLAS's thread count.
 *
 * Usage (every call in core/; a test fails for a cblas_ or LAPACKE_ call outside the macro):
 *     AFFECT_BLAS(cblas_dgemm(CblasRowMajor, ...));
 *     AFFECT_BLAS(info = LAPACKE_dpotrf_work(LAPACK_COL_MAJOR, ...));
 *
 * Why. We promise the same bytes for the same inputs (statement-based replication relies on
 * it), and OpenBLAS splits a call's work by its thread count, which changes the order of the
 * sums: with OpenBLAS 0.3.21 on 1 and 2 (or 4) threads, dsymv and dgemv (partial sums per thread,
 * added at the end), dpotri and dsyev (they call them; even the 3 × 3 dsyev of laban.c), dpotrf
 * from m ≈ 78 and dgemm for some shapes (spca.c's Tᵀ X with 400-long sums) differ in the last
 * bits, so affect_train's BLOB, hmm_train's BLOB, hmm_loglik and affect_generate_explain
 * changed with OPENBLAS_NUM_THREADS. Our matrices are small and the core's own parallelism
 * (parallel.c, the `threads` options) is over independent items, so one BLAS thread per call
 * costs little: docs/BENCHMARKS.md ("BLAS threads") has the measurements.
 *
 * How. OpenBLAS 0.3.21 (Debian 12) has only a process-wide thread count
 * (openblas_set_num_threads), no per-thread one. A counter of the core's calls in progress,
 * under one mutex: the first to begin reads the host's count and, if it is
 * not 1, sets 1; the last to end sets the host's count back. So a host that changes the count
 * between our calls is honoured, and the host's own BLAS calls run on one thread only while one
 * of ours is running. What this cannot prevent: another thread of the host setting the count
 * while one of our calls runs (our call may then split its work, and the count we restore
 * replaces the host's). OpenBLAS's serial build has no threads to set; its OpenMP build also
 * runs on one thread once the count is 1 (not tested here: Debian links the pthread build by
 * default, and tests/core/test_blas_threads.c checks the build it runs with). A mutex that
 * cannot be created leaves OpenBLAS on one thread for good: the same bytes matter more.
 * Cost: two uncontended lock/unlock pairs and, for a host count above 1, two assignments
 * inside OpenBLAS, about 40 ns a call (dgemm panels of the HMM engine take tens of µs).
 */
#include <cblas.h>
#include <stdbool.h>
#include <threads.h>

#include "util/internal.h"

static once_flag blas_once = ONCE_FLAG_INIT;
static mtx_t blas_lock;
static bool blas_lock_ok;
static unsigned long blas_depth; /* the core's BLAS calls in progress */
static int blas_host;            /* the host's thread count, restored by the last to end */

static void blas_init(void)
{
    blas_lock_ok = mtx_init(&blas_lock, mtx_plain) == thrd_success;
}

void affect_blas_begin(void)
{
    call_once(&blas_once, blas_init);
    if (!blas_lock_ok) {
        openblas_set_num_threads(1);
        return;
    }
    mtx_lock(&blas_lock);
    if (blas_depth++ == 0) {
        blas_host = openblas_get_num_threads();
        if (blas_host != 1)
            openblas_set_num_threads(1);
    }
    mtx_unlock(&blas_lock);
}

void affect_blas_end(void)
{
    if (!blas_lock_ok)
        return;
    mtx_lock(&blas_lock);
    if (--blas_depth == 0 && blas_host != 1)
        openblas_set_num_threads(blas_host);
    mtx_unlock(&blas_lock);
}
