/*
 * test_blas_threads.c — the core's results do not depend on OpenBLAS's thread count (blas.c):
 * the same calls with OpenBLAS set to 1, 2 and 4 threads through its own API (threads above
 * the core count still split the work) give the same bytes — HMM training with full
 * covariances (dpotrf on 80 dimensions, the density dgemm panels, the scatter dsyrk), its
 * log-likelihood, Fisher scores (dsyrk, dpotrf, dpotri, dsymv, dsymm), sPCA (dsyrk, dgemm,
 * dsyev), the SVM's Gram matrix and the Laban vector (the 3 × 3 dsyev) — and each call leaves
 * the count the caller set. Two threads training at once under 4 BLAS threads also get the
 * reference bytes. Before blas.c every one of these groups but the Gram matrix differed.
 */
#include <string.h>
#include <threads.h>

#include "testutil.h"

#include "affect/fisher.h"
#include "affect/hmm.h"
#include "affect/laban.h"
#include "util/rng.h"
#include "affect/roles.h"
#include "affect/spca.h"
#include "affect/svm.h"
#include "affect/synth.h"

/* From OpenBLAS (cblas.h declares them; the core's include path is private). */
void openblas_set_num_threads(int num_threads);
int openblas_get_num_threads(void);

#define DIM 80u /* above the size from which OpenBLAS 0.3.21 splits dpotrf */
#define SEQS 4u
#define FRAMES 240u
#define SP_N 400u /* sPCA rows: Tᵀ X with 400-long sums was split */
#define SP_D 60u
#define SP_C 4u
#define HMM_LEN (9u + 6u * DIM + 6u * DIM * DIM) /* 3 states × 2 mixtures */

typedef struct results {
    double hmm[HMM_LEN]; /* transitions, means, covariances */
    size_t hmm_len;
    double loglik;
    double *fisher;
    size_t fisher_len;
    double spca[3 * SP_D + 3];
    size_t spca_len;
    double gram[64 * 64];
    double laban[AFFECT_LABAN_N];
} results;

static double *data; /* SEQS × FRAMES × DIM: a random 3-state walk through correlated clouds */
static double *sp_x; /* SP_N × SP_D */
static uint32_t sp_y[SP_N];

static void make_data(void)
{
    affect_rng r;
    affect_rng_seed(&r, 14);
    data = malloc((size_t)SEQS * FRAMES * DIM * sizeof *data);
    double mix[DIM * 4];
    for (size_t i = 0; i < sizeof mix / sizeof *mix; i++)
        mix[i] = affect_rng_normal(&r);
    for (uint32_t s = 0; s < SEQS; s++) {
        uint32_t state = 0;
        for (uint32_t t = 0; t < FRAMES; t++) {
            if (affect_rng_uniform(&r) < 0.05)
                state = (state + 1) % 3;
            double z[4];
            for (int k = 0; k < 4; k++)
                z[k] = affect_rng_normal(&r);
            double *x = data + ((size_t)s * FRAMES + t) * DIM;
            for (uint32_t d = 0; d < DIM; d++)
                x[d] = 3.0 * state * (d % 3 == state) + mix[d * 4] * z[0] + mix[d * 4 + 1] * z[1] +
                       0.5 * mix[d * 4 + 2] * z[2] + 0.3 * affect_rng_normal(&r);
        }
    }
    sp_x = malloc((size_t)SP_N * SP_D * sizeof *sp_x);
    for (uint32_t i = 0; i < SP_N; i++) {
        sp_y[i] = i % SP_C;
        for (uint32_t d = 0; d < SP_D; d++)
            sp_x[(size_t)i * SP_D + d] = affect_rng_normal(&r) + (d % SP_C == sp_y[i] ? 1.0 : 0.0);
    }
}

static affect_hmm *train(void)
{
    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    cfg.n_states = 3;
    cfg.n_mix = 2;
    cfg.dim = DIM;
    cfg.max_iter = 3;
    affect_hmm_seq seqs[SEQS];
    for (uint32_t s = 0; s < SEQS; s++)
        seqs[s] = (affect_hmm_seq){data + (size_t)s * FRAMES * DIM, FRAMES};
    affect_hmm *h = NULL;
    affect_error err;
    if (affect_hmm_train(&cfg, seqs, SEQS, &h, &err) != AFFECT_OK)
        fail_msg("affect_hmm_train: %s", err.msg);
    return h;
}

static size_t hmm_bytes(const affect_hmm *h, double *out)
{
    size_t n = 0, K = 3 * 2;
    memcpy(out + n, affect_hmm_transitions(h), 9 * sizeof *out), n += 9;
    memcpy(out + n, affect_hmm_means(h), K * DIM * sizeof *out), n += K * DIM;
    memcpy(out + n, affect_hmm_covariances(h), K * DIM * DIM * sizeof *out), n += K * DIM * DIM;
    return n;
}

/* Every computation once, with OpenBLAS set to `threads`; checks that each call leaves it so. */
static void run_all(int threads, results *res)
{
    openblas_set_num_threads(threads);
    int host = openblas_get_num_threads();
    affect_error err;

    affect_hmm *h = train();
    assert_int_equal(openblas_get_num_threads(), host);
    res->hmm_len = hmm_bytes(h, res->hmm);
    assert_int_equal(affect_hmm_loglik(h, data, FRAMES, &res->loglik, NULL, &err), AFFECT_OK);
    res->fisher_len = affect_fisher_dim(affect_hmm_get_config(h), AFFECT_FISHER_ALL);
    res->fisher = malloc(res->fisher_len * sizeof *res->fisher);
    assert_int_equal(affect_fisher_score(h, data + FRAMES * DIM, FRAMES, AFFECT_FISHER_ALL,
                                         res->fisher, NULL, NULL, &err),
                     AFFECT_OK);
    affect_hmm_free(h);
    assert_int_equal(openblas_get_num_threads(), host);

    affect_spca *s = NULL;
    assert_int_equal(
        affect_spca_fit(sp_x, SP_N, SP_D, sp_y, SP_C, AFFECT_SPCA_RBF, 0.25, 3, &s, &err),
        AFFECT_OK);
    uint32_t p = affect_spca_dims(s);
    memcpy(res->spca, affect_spca_axes(s), (size_t)p * SP_D * sizeof *res->spca);
    memcpy(res->spca + (size_t)p * SP_D, affect_spca_eigenvalues(s), p * sizeof *res->spca);
    res->spca_len = (size_t)p * SP_D + p;
    affect_spca_free(s);

    assert_int_equal(affect_svm_gram(sp_x, 64, SP_D, res->gram, &err), AFFECT_OK);

    affect_motion *m = NULL;
    assert_int_equal(affect_motion_synth("wave", "angry", 3, NULL, &m, &err), AFFECT_OK);
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    assert_int_equal(affect_laban_vector(m, &roles, NULL, res->laban, &err), AFFECT_OK);
    affect_motion_free(m);
    assert_int_equal(openblas_get_num_threads(), host);
}

static void assert_same(const double *a, const double *b, size_t n, const char *what, int t)
{
    for (size_t i = 0; i < n; i++)
        if (memcmp(a + i, b + i, sizeof *a) != 0)
            fail_msg("%s, entry %zu: %.17g with 1 BLAS thread, %.17g with %d", what, i, a[i], b[i],
                     t);
}

static void compare(const results *a, const results *b, int t)
{
    assert_int_equal(a->hmm_len, b->hmm_len);
    assert_same(a->hmm, b->hmm, a->hmm_len, "HMM parameters", t);
    assert_same(&a->loglik, &b->loglik, 1, "log-likelihood", t);
    assert_int_equal(a->fisher_len, b->fisher_len);
    assert_same(a->fisher, b->fisher, a->fisher_len, "Fisher score", t);
    assert_int_equal(a->spca_len, b->spca_len);
    assert_same(a->spca, b->spca, a->spca_len, "sPCA axes and eigenvalues", t);
    assert_same(a->gram, b->gram, 64 * 64, "SVM Gram matrix", t);
    assert_same(a->laban, b->laban, AFFECT_LABAN_N, "Laban vector", t);
}

static void test_thread_counts(void **state)
{
    (void)state;
    int host = openblas_get_num_threads();
    static results ref, other;
    run_all(1, &ref);
    const int counts[] = {2, 4};
    for (size_t i = 0; i < 2; i++) {
        run_all(counts[i], &other);
        compare(&ref, &other, counts[i]);
        free(other.fisher);
    }
    free(ref.fisher);
    openblas_set_num_threads(host);
}

/* Two threads training at once while the host has set 4 BLAS threads: the shared counter in
 * blas.c must keep OpenBLAS on one thread until both are done, then give the 4 back. */
typedef struct job {
    double out[HMM_LEN];
    size_t len;
} job;

static int train_job(void *arg)
{
    job *j = arg;
    for (int k = 0; k < 2; k++) {
        affect_hmm *h = train();
        j->len = hmm_bytes(h, j->out);
        affect_hmm_free(h);
    }
    return 0;
}

static void test_concurrent(void **state)
{
    (void)state;
    int host = openblas_get_num_threads();
    static results ref;
    run_all(1, &ref);
    free(ref.fisher);
    openblas_set_num_threads(4);
    static job jobs[2];
    thrd_t th[2];
    for (int i = 0; i < 2; i++)
        assert_int_equal(thrd_create(&th[i], train_job, &jobs[i]), thrd_success);
    for (int i = 0; i < 2; i++) {
        thrd_join(th[i], NULL);
        assert_int_equal(jobs[i].len, ref.hmm_len);
        assert_same(ref.hmm, jobs[i].out, ref.hmm_len, "HMM parameters (concurrent)", 4);
    }
    assert_int_equal(openblas_get_num_threads(), 4);
    openblas_set_num_threads(host);
}

int main(void)
{
    make_data();
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_counts),
        cmocka_unit_test(test_concurrent),
    };
    int rc = cmocka_run_group_tests(tests, NULL, NULL);
    free(data);
    free(sp_x);
    return rc;
}
