/*
 * test_hmm_blob.c — the model BLOB: layout, bit-identical round trips (encode(decode(x)) == x)
 * of built and trained models, every corruption refused with its message (each truncation,
 * a flipped byte in each section, bad header fields, non-finite values and bad contents behind
 * a valid checksum), the version-1 fixture, and allocation failure.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/hmm_blob.h"
#include "affect/synth.h"

enum { N = 3, M = 2, D = 6 };

/* The feature definition of the tiny model: the right hand and the hips of a synthetic wave
 * (dimension 6, fps 30, unit "arm"). */
static affect_features *tiny_features(void)
{
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_synth("wave", "happy", 1, NULL, &m, &err), AFFECT_OK);
    static const char *const joints[] = {"right_hand", "Hips"};
    affect_features_options opt;
    affect_features_options_default(&opt);
    opt.joints = joints;
    opt.n_joints = 2;
    affect_features *f = NULL;
    assert_int_equal(affect_features_create(&opt, m, &f, &err), AFFECT_OK);
    affect_motion_free(m);
    return f;
}

/* Parameters of the tiny model: dyadic probabilities, means i + j/10 + d/100, covariances
 * with a diagonal of 1 + i/10 + j/20 + d/100 and 0.1 next to it (diagonally dominant). */
typedef struct params {
    double start[N], trans[N * N], weights[N * M], means[N * M * D], full[N * M * D * D],
        diag[N * M * D];
} params;

static void tiny_params(params *p)
{
    static const double trans[N * N] = {0.75, 0.125, 0.125, 0.125, 0.75, 0.125, 0.25, 0.25, 0.5};
    static const double weights[N * M] = {0.625, 0.375, 0.5, 0.5, 0.25, 0.75};
    memset(p, 0, sizeof *p);
    p->start[0] = 1;
    memcpy(p->trans, trans, sizeof trans);
    memcpy(p->weights, weights, sizeof weights);
    for (int i = 0; i < N; i++)
        for (int j = 0; j < M; j++)
            for (int d = 0; d < D; d++) {
                int k = (i * M + j) * D + d;
                double v = 1 + 0.1 * i + 0.05 * j + 0.01 * d;
                p->means[k] = i + 0.1 * j + 0.01 * d;
                p->diag[k] = v;
                double *c = p->full + (size_t)(i * M + j) * D * D;
                c[d * D + d] = v;
                if (d + 1 < D)
                    c[d * D + d + 1] = c[(d + 1) * D + d] = 0.1;
            }
}

static const double tiny_loglik[3] = {-1234.5, -1100.25, -1099.875};

static affect_hmm *tiny_model(affect_hmm_cov cov)
{
    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    cfg.n_states = N;
    cfg.n_mix = M;
    cfg.dim = D;
    cfg.cov = cov;
    cfg.topology = AFFECT_HMM_ERGODIC;
    cfg.max_iter = 5;
    cfg.tol = 1e-3;
    cfg.reg = 1e-4;
    cfg.seed = 42;
    params p;
    tiny_params(&p);
    affect_hmm *h = NULL;
    affect_error err;
    affect_status st = affect_hmm_from_params(&cfg, p.start, p.trans, p.weights, p.means,
                                              cov == AFFECT_HMM_FULL ? p.full : p.diag, &h, &err);
    if (st)
        fail_msg("from_params: %s", err.msg);
    affect_hmm_report rep = {2, true, tiny_loglik, 1, 4, 400};
    assert_int_equal(affect_hmm_set_report(h, &rep, &err), AFFECT_OK);
    return h;
}

static unsigned char *encode(const affect_hmm *h, const affect_features *f, size_t *size)
{
    unsigned char *blob = NULL;
    affect_error err;
    affect_status st = affect_hmm_blob_encode(h, f, &blob, size, &err);
    if (st)
        fail_msg("encode: %s", err.msg);
    return blob;
}

static uint32_t get32(const unsigned char *p)
{
    return (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
}

static void put32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put64(unsigned char *p, uint64_t v)
{
    for (int i = 0; i < 8; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void put_f64(unsigned char *p, double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    put64(p, u);
}

/* Rewrites the checksum of a BLOB that was changed on purpose. */
static void reseal(unsigned char *blob, size_t size)
{
    put64(blob + size - 8, affect_fnv1a64(blob, size - 8));
}

static void assert_same_model(const affect_hmm *a, const affect_hmm *b)
{
    const affect_hmm_config *ca = affect_hmm_get_config(a), *cb = affect_hmm_get_config(b);
    assert_int_equal(ca->n_states, cb->n_states);
    assert_int_equal(ca->n_mix, cb->n_mix);
    assert_int_equal(ca->dim, cb->dim);
    assert_int_equal(ca->cov, cb->cov);
    assert_int_equal(ca->topology, cb->topology);
    assert_int_equal(ca->max_jump, cb->max_jump);
    assert_int_equal(ca->learn_start, cb->learn_start);
    assert_int_equal(ca->max_iter, cb->max_iter);
    assert_memory_equal(&ca->tol, &cb->tol, sizeof ca->tol);
    assert_memory_equal(&ca->reg, &cb->reg, sizeof ca->reg);
    assert_true(ca->seed == cb->seed);
    size_t n = ca->n_states, m = ca->n_mix, d = ca->dim;
    size_t nc = ca->cov == AFFECT_HMM_FULL ? n * m * d * d : n * m * d;
    assert_memory_equal(affect_hmm_start(a), affect_hmm_start(b), n * sizeof(double));
    assert_memory_equal(affect_hmm_transitions(a), affect_hmm_transitions(b),
                        n * n * sizeof(double));
    assert_memory_equal(affect_hmm_weights(a), affect_hmm_weights(b), n * m * sizeof(double));
    assert_memory_equal(affect_hmm_means(a), affect_hmm_means(b), n * m * d * sizeof(double));
    assert_memory_equal(affect_hmm_covariances(a), affect_hmm_covariances(b), nc * sizeof(double));
    affect_hmm_report ra, rb;
    affect_hmm_get_report(a, &ra);
    affect_hmm_get_report(b, &rb);
    assert_int_equal(ra.iterations, rb.iterations);
    assert_int_equal(ra.converged, rb.converged);
    assert_int_equal(ra.reseeded, rb.reseeded);
    assert_int_equal(ra.n_sequences, rb.n_sequences);
    assert_true(ra.n_frames == rb.n_frames);
    assert_memory_equal(ra.loglik, rb.loglik, (ra.iterations + 1) * sizeof(double));
}

static void decode_ok(const unsigned char *blob, size_t size, affect_hmm **h, affect_features **f)
{
    affect_error err;
    affect_status st = affect_hmm_blob_decode(blob, size, h, f, &err);
    if (st)
        fail_msg("decode: %s", err.msg);
}

/* decode then encode gives the same bytes, and the same model */
static void check_round_trip(const affect_hmm *h, const affect_features *f)
{
    size_t size, size2;
    unsigned char *blob = encode(h, f, &size);
    affect_hmm *back = NULL;
    affect_features *fback = NULL;
    decode_ok(blob, size, &back, &fback);
    assert_same_model(h, back);
    assert_int_equal(fback->n_joints, f->n_joints);
    assert_string_equal(fback->skeleton[0], f->skeleton[0]);
    unsigned char *blob2 = encode(back, fback, &size2);
    assert_int_equal(size, size2);
    assert_memory_equal(blob, blob2, size);
    affect_free(blob);
    affect_free(blob2);
    affect_hmm_free(back);
    affect_features_free(fback);
}

static void test_layout_and_round_trip(void **state)
{
    affect_features *f = tiny_features();
    size_t f_len;
    assert_true(affect_features_encoded_size(f, &f_len));
    for (int c = 0; c < 2; c++) {
        affect_hmm_cov cov = c ? AFFECT_HMM_DIAG : AFFECT_HMM_FULL;
        affect_hmm *h = tiny_model(cov);
        size_t size;
        unsigned char *blob = encode(h, f, &size);
        size_t n_cov = cov == AFFECT_HMM_FULL ? N * M * D * D : N * M * D;
        size_t n_params = N + N * N + N * M + N * M * D + n_cov;
        assert_int_equal(size, 80 + f_len + 8 * 3 + 8 * n_params + 8);
        assert_memory_equal(blob,
                            "AFHM\x01\x00\x00\x00\x03\x00\x00\x00\x02\x00\x00\x00"
                            "\x06\x00\x00\x00",
                            20);
        assert_int_equal(blob[20], c);          /* covariance */
        assert_int_equal(blob[21], 0);          /* ergodic */
        assert_int_equal(blob[22], 0);          /* start: first state */
        assert_int_equal(blob[23], 1);          /* converged */
        assert_int_equal(get32(blob + 28), 5);  /* max_iter */
        assert_int_equal(get32(blob + 48), 42); /* seed */
        assert_int_equal(get32(blob + 56), 2);  /* iterations */
        assert_int_equal(get32(blob + 60), 1);  /* reseeded */
        assert_int_equal(get32(blob + 64), 4);  /* sequences */
        assert_int_equal(get32(blob + 68), f_len);
        assert_int_equal(get32(blob + 72), 400); /* frames */
        /* the first log-likelihood right after the feature definition */
        unsigned char ll[8];
        put_f64(ll, tiny_loglik[0]);
        assert_memory_equal(blob + 80 + f_len, ll, 8);
        uint64_t sum = 0;
        for (int i = 7; i >= 0; i--)
            sum = (sum << 8) | blob[size - 8 + i];
        assert_true(sum == affect_fnv1a64(blob, size - 8));
        check_round_trip(h, f);
        affect_free(blob);
        affect_hmm_free(h);
    }
    /* the definition's dimension must be the model's */
    affect_hmm *h = tiny_model(AFFECT_HMM_FULL);
    f->velocity = true;
    unsigned char *blob = NULL;
    size_t size;
    affect_error err;
    assert_int_equal(affect_hmm_blob_encode(h, f, &blob, &size, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the feature definition has 12 dimensions, the model 6");
    assert_null(blob);
    affect_hmm_free(h);
    affect_features_free(f);
}

/* A trained model survives the round trip bit for bit and scores the same. */
static void test_trained_round_trip(void **state)
{
    affect_features *f = NULL;
    affect_error err;
    affect_features_options opt;
    affect_features_options_default(&opt);
    static const char *const joints[] = {"right_hand", "left_hand", "head"};
    opt.joints = joints;
    opt.n_joints = 3;
    opt.velocity = true;
    affect_hmm_seq seqs[3];
    double *xs[3];
    for (int k = 0; k < 3; k++) {
        affect_motion *m = NULL;
        assert_int_equal(affect_motion_synth("knock", "angry", (uint64_t)k + 1, NULL, &m, &err),
                         AFFECT_OK);
        if (!f)
            assert_int_equal(affect_features_create(&opt, m, &f, &err), AFFECT_OK);
        uint32_t T;
        assert_int_equal(affect_features_extract(f, m, &xs[k], &T, NULL, &err), AFFECT_OK);
        seqs[k].x = xs[k];
        seqs[k].n_frames = T;
        affect_motion_free(m);
    }
    for (int c = 0; c < 2; c++) {
        affect_hmm_config cfg;
        affect_hmm_config_default(&cfg);
        cfg.n_states = 4;
        cfg.n_mix = 2;
        cfg.dim = affect_features_dim(f);
        cfg.max_iter = 4;
        cfg.cov = c ? AFFECT_HMM_DIAG : AFFECT_HMM_FULL;
        cfg.topology = c ? AFFECT_HMM_LEFT_RIGHT : AFFECT_HMM_ERGODIC;
        cfg.learn_start = c == 1;
        affect_hmm *h = NULL;
        if (affect_hmm_train(&cfg, seqs, 3, &h, &err))
            fail_msg("train: %s", err.msg);
        check_round_trip(h, f);
        size_t size;
        unsigned char *blob = encode(h, f, &size);
        affect_hmm *back = NULL;
        affect_features *fb = NULL;
        decode_ok(blob, size, &back, &fb);
        double a, b;
        assert_int_equal(affect_hmm_loglik(h, xs[0], seqs[0].n_frames, &a, NULL, &err), AFFECT_OK);
        assert_int_equal(affect_hmm_loglik(back, xs[0], seqs[0].n_frames, &b, NULL, &err),
                         AFFECT_OK);
        assert_memory_equal(&a, &b, sizeof a);
        affect_free(blob);
        affect_hmm_free(back);
        affect_features_free(fb);
        affect_hmm_free(h);
    }
    for (int k = 0; k < 3; k++)
        affect_free(xs[k]);
    affect_features_free(f);
}

static void expect_error(const unsigned char *blob, size_t size, const char *msg)
{
    affect_hmm *h = NULL;
    affect_features *f = NULL;
    affect_error err;
    affect_status st = affect_hmm_blob_decode(blob, size, &h, &f, &err);
    if (st == AFFECT_OK)
        fail_msg("decoding %zu bytes succeeded, expected \"%s\"", size, msg ? msg : "an error");
    assert_int_equal(st, AFFECT_ERR_FORMAT);
    assert_null(h);
    assert_null(f);
    if (msg && strcmp(err.msg, msg) != 0)
        fail_msg("expected \"%s\", got \"%s\"", msg, err.msg);
}

static void test_corruptions(void **state)
{
    affect_features *f = tiny_features();
    affect_hmm *h = tiny_model(AFFECT_HMM_FULL);
    size_t size, f_len;
    unsigned char *blob = encode(h, f, &size);
    assert_true(affect_features_encoded_size(f, &f_len));
    unsigned char *c = malloc(size + 8);
    char msg[200];

    /* every truncation */
    for (size_t n = 0; n < size; n++) {
        if (n < 80)
            snprintf(msg, sizeof msg, "truncated: %zu bytes is shorter than the 80-byte header", n);
        else
            snprintf(msg, sizeof msg,
                     "truncated: %zu bytes, expected %zu for 3 states x 2 mixtures x 6 dimensions",
                     n, size);
        expect_error(blob, n, msg);
    }
    memcpy(c, blob, size);
    c[size] = 0;
    snprintf(msg, sizeof msg,
             "trailing bytes: %zu bytes, expected %zu for 3 states x 2 mixtures x 6 dimensions",
             size + 1, size);
    expect_error(c, size + 1, msg);

#define CORRUPT(stmt, msg)                                                                         \
    do {                                                                                           \
        memcpy(c, blob, size);                                                                     \
        stmt;                                                                                      \
        expect_error(c, size, msg);                                                                \
    } while (0)
    /* the header, checked in order */
    CORRUPT(c[0] = 'X', "not a model (bad magic bytes at offset 0)");
    CORRUPT(c[4] = 0, "unknown format version 0 (this build reads 1 .. 1)");
    CORRUPT(c[4] = 2, "unknown format version 2 (this build reads 1 .. 1)");
    CORRUPT(c[6] = 1, "unknown flags 0x0001 (offset 6)");
    CORRUPT(put32(c + 8, 0), "state count 0 out of range (1 .. 256)");
    CORRUPT(put32(c + 8, 257), "state count 257 out of range (1 .. 256)");
    CORRUPT(put32(c + 12, 65), "mixture count 65 out of range (1 .. 64)");
    CORRUPT(put32(c + 16, 0), "dimension 0 out of range (1 .. 4096)");
    CORRUPT(c[20] = 2, "byte 20 must be 0 or 1, got 2");
    CORRUPT(c[23] = 7, "byte 23 must be 0 or 1, got 7");
    CORRUPT(put32(c + 56, 6), "6 iterations exceed max_iter 5 (offset 56)");
    snprintf(msg, sizeof msg,
             "truncated: %zu bytes, expected %zu for 4 states x 2 mixtures x 6 dimensions", size,
             size + 8 * (1 + 7 + 2 + 12 + 2 * 36));
    CORRUPT(put32(c + 8, 4), msg);
    CORRUPT(put32(c + 68, 0xffffffffu), NULL);
    if (sizeof(size_t) == 4) /* 256 × 64 × 4096² doubles do not fit 32 bits */
        CORRUPT(put32(c + 8, 256); put32(c + 12, 64);
                put32(c + 16, 4096), "sizes in the header overflow");
    else
        CORRUPT(put32(c + 8, 256); put32(c + 12, 64); put32(c + 16, 4096), NULL);

    /* a flipped byte in each section: the checksum catches it */
    const size_t ll = 80 + f_len, start = ll + 3 * 8, trans = start + N * 8,
                 weights = trans + N * N * 8, means = weights + N * M * 8,
                 covs = means + N * M * D * 8;
    const size_t at[] = {32 /* tol */,
                         40 /* reg */,
                         48 /* seed */,
                         60 /* reseeded */,
                         72 /* frames */,
                         80 /* features */,
                         80 + f_len - 1,
                         ll,
                         start,
                         trans + 17,
                         weights + 3,
                         means + 100,
                         covs,
                         covs + 1000,
                         size - 9,
                         size - 8 /* the checksum itself */,
                         size - 1};
    for (size_t i = 0; i < sizeof at / sizeof at[0]; i++)
        CORRUPT(c[at[i]] ^= 0x10, "model checksum mismatch: the BLOB is corrupt");
    CORRUPT(c[23] ^= 1, "model checksum mismatch: the BLOB is corrupt"); /* converged */
    CORRUPT(c[22] ^= 1, "model checksum mismatch: the BLOB is corrupt"); /* start */
    /* and every single-byte change anywhere is refused */
    for (size_t i = 0; i < size; i++)
        CORRUPT(c[i] ^= 0x01, NULL);

    /* behind a valid checksum: the contents */
    memcpy(c, blob, size);
    put_f64(c + trans + 8, NAN);
    reseal(c, size);
    snprintf(msg, sizeof msg, "non-finite value in the transitions (offset %zu)", trans + 8);
    expect_error(c, size, msg);
    memcpy(c, blob, size);
    put_f64(c + ll + 16, -INFINITY);
    reseal(c, size);
    snprintf(msg, sizeof msg, "non-finite value in the log-likelihoods (offset %zu)", ll + 16);
    expect_error(c, size, msg);
    memcpy(c, blob, size);
    put_f64(c + covs + 8 * (N * M * D * D - 1), INFINITY);
    reseal(c, size);
    snprintf(msg, sizeof msg, "non-finite value in the covariances (offset %zu)",
             covs + 8 * (N * M * D * D - 1));
    expect_error(c, size, msg);
    /* the feature definition: its flags (velocity doubles the dimension), a bad up axis */
    CORRUPT(c[81] |= 4;
            reseal(c, size), "the feature definition gives 12 dimensions, the header 6");
    CORRUPT(c[80] = 5;
            reseal(c, size), "feature definition at offset 80: up axis 5 out of range (0 .. 2)");
    /* the configuration and the parameters, as the HMM engine checks them */
    memcpy(c, blob, size);
    put_f64(c + 32, -1.0);
    reseal(c, size);
    expect_error(c, size, "bad configuration: tol must be a finite number, 0 or more");
    memcpy(c, blob, size);
    put_f64(c + trans, 0.5); /* the first row sums to 0.75 */
    reseal(c, size);
    expect_error(c, size, "bad parameters: transition row 0 sums to 0.75, not 1");
    memcpy(c, blob, size);
    put_f64(c + covs, -3.0); /* not positive definite */
    reseal(c, size);
    expect_error(c, size,
                 "bad parameters: covariance of state 0, mixture 0 is not positive definite");
#undef CORRUPT
    free(c);
    affect_free(blob);
    affect_hmm_free(h);
    affect_features_free(f);
}

/* tests/fixtures/hmm-v1.bin: the tiny full-covariance model, written by version 1. It must
 * keep decoding (readers accept every older version); today's encoder writes it again. */
static void test_fixture(void **state)
{
    size_t len;
    unsigned char *data = (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/hmm-v1.bin", &len);
    affect_features *f = tiny_features();
    affect_hmm *h = tiny_model(AFFECT_HMM_FULL);
    size_t size;
    unsigned char *blob = encode(h, f, &size);
    if (getenv("AFFECT_WRITE_FIXTURES")) { /* regenerate: AFFECT_WRITE_FIXTURES=1 test_hmm_blob */
        FILE *out = fopen(AFFECT_FIXTURES_DIR "/hmm-v1.bin", "wb");
        assert_non_null(out);
        assert_int_equal(fwrite(blob, 1, size, out), size);
        fclose(out);
        free(data);
        data = (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/hmm-v1.bin", &len);
    }
    assert_non_null(data);
    affect_hmm *back = NULL;
    affect_features *fb = NULL;
    decode_ok(data, len, &back, &fb);
    assert_same_model(h, back);
    assert_int_equal(fb->n_joints, 2);
    assert_string_equal(fb->joints[0], "right_hand");
    assert_string_equal(fb->skeleton[0], "Hand_R");
    assert_string_equal(fb->skeleton[1], "Hips");
    assert_true(fb->fps == 30.0);
    assert_string_equal(fb->unit, "arm");
    assert_int_equal(len, size);
    assert_memory_equal(data, blob, size);
    free(data);
    affect_free(blob);
    affect_hmm_free(back);
    affect_features_free(fb);
    affect_hmm_free(h);
    affect_features_free(f);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    const affect_hmm *h;
    const affect_features *f;
    const unsigned char *blob;
    size_t size;
    unsigned char *out;
    affect_hmm *model;
    affect_features *feat;
} oom_ctx;

static affect_status oom_encode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    size_t size;
    c->out = NULL;
    return affect_hmm_blob_encode(c->h, c->f, &c->out, &size, err);
}

static void oom_encode_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    if (!st)
        assert_memory_equal(c->out, c->blob, c->size);
    affect_free(c->out);
}

static affect_status oom_decode(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    c->model = NULL;
    c->feat = NULL;
    return affect_hmm_blob_decode(c->blob, c->size, &c->model, &c->feat, err);
}

static void oom_decode_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    if (st) {
        assert_null(c->model);
        assert_null(c->feat);
    }
    affect_hmm_free(c->model);
    affect_features_free(c->feat);
}

static void test_out_of_memory(void **state)
{
    affect_features *f = tiny_features();
    affect_hmm *h = tiny_model(AFFECT_HMM_FULL);
    size_t size;
    unsigned char *blob = encode(h, f, &size);
    oom_ctx c = {h, f, blob, size, NULL, NULL, NULL};
    assert_int_equal(tu_oom_sweep(oom_encode, &c, oom_encode_finish, NULL), 1);
    assert_true(tu_oom_sweep(oom_decode, &c, oom_decode_finish, NULL) >= 10);
    affect_free(blob);
    affect_hmm_free(h);
    affect_features_free(f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_layout_and_round_trip), cmocka_unit_test(test_trained_round_trip),
        cmocka_unit_test(test_corruptions),           cmocka_unit_test(test_fixture),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
