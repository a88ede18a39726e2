/*
 * test_strength.c — keyframes by curve simplification (affect/keyframes.h) and the emotion
 * strength model (affect/strength.h): the DP is optimal against brute force and exact when
 * q ≥ T; the regression fits a known smooth map; a model trained on synthetic motions of known
 * emotion intensity ranks unseen ones in order; synthesis and editing move the strength in the
 * order asked; determinism; the BLOB round trip and corruption; errors; out of memory.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "affect/keyframes.h"
#include "util/rng.h"
#include "affect/strength.h"
#include "affect/synth.h"

/* ---- keyframes ---- */

static double brute_best(const double *Y, uint32_t T, uint32_t D, uint32_t q, uint32_t *best)
{
    /* every choice of q − 2 interior frames among 1 .. T − 2 (bitmask enumeration) */
    double bestv = INFINITY;
    uint32_t fr[32];
    for (uint32_t mask = 0; mask < (1u << (T - 2)); mask++) {
        if ((uint32_t)__builtin_popcount(mask) != q - 2)
            continue;
        uint32_t k = 0;
        fr[k++] = 0;
        for (uint32_t t = 1; t + 1 < T; t++)
            if (mask & (1u << (t - 1)))
                fr[k++] = t;
        fr[k++] = T - 1;
        double e = affect_keyframes_error(Y, T, D, fr, q);
        if (e < bestv) {
            bestv = e;
            memcpy(best, fr, sizeof(uint32_t) * q);
        }
    }
    return bestv;
}

static void test_keyframes_optimal(void **state)
{
    (void)state;
    affect_rng r;
    affect_rng_seed(&r, 5);
    for (int trial = 0; trial < 40; trial++) {
        uint32_t T = 4 + (uint32_t)(affect_rng_uniform(&r) * 9); /* 4 .. 12 */
        uint32_t D = 1 + (uint32_t)(affect_rng_uniform(&r) * 4);
        uint32_t q = 2 + (uint32_t)(affect_rng_uniform(&r) * (T - 2));
        double Y[12 * 4];
        for (uint32_t k = 0; k < T * D; k++)
            Y[k] = 100 * affect_rng_normal(&r) + 50; /* offsets: the prefix sums cancel */
        uint32_t fr[12], best[12], n;
        double sse;
        affect_error err;
        assert_int_equal(affect_keyframes_select(Y, T, D, q, fr, &n, &sse, NULL, &err), AFFECT_OK);
        assert_int_equal(n, q);
        assert_int_equal(fr[0], 0);
        assert_int_equal(fr[q - 1], T - 1);
        for (uint32_t k = 1; k < q; k++)
            assert_true(fr[k] > fr[k - 1]);
        double bv = brute_best(Y, T, D, q, best);
        if (!(fabs(sse - bv) <= 1e-9 * (1 + bv)))
            fail_msg("T %u D %u q %u: DP %.12g, brute force %.12g", T, D, q, sse, bv);
    }
}

/* The least error by a plain DP over directly computed segment errors (no prefix sums, no
 * pruning): the reference for curves too long for brute force. */
static double plain_dp_best(const double *Y, uint32_t T, uint32_t D, uint32_t q)
{
    double *cost = malloc(sizeof(double) * T * T), *E = malloc(sizeof(double) * q * T);
    assert_non_null(cost);
    assert_non_null(E);
    for (uint32_t a = 0; a < T; a++)
        for (uint32_t b = a + 1; b < T; b++) {
            uint32_t fr[2] = {a, b};
            cost[a * T + b] = affect_keyframes_error(Y, T, D, fr, 2);
        }
    for (uint32_t b = 0; b < T; b++)
        E[b] = b == 0 ? 0 : INFINITY;
    for (uint32_t k = 1; k < q; k++)
        for (uint32_t b = 0; b < T; b++) {
            double best = INFINITY;
            for (uint32_t a = 0; a < b; a++)
                if (E[(k - 1) * T + a] + cost[a * T + b] < best)
                    best = E[(k - 1) * T + a] + cost[a * T + b];
            E[k * T + b] = best;
        }
    double v = E[(q - 1) * T + T - 1];
    free(cost);
    free(E);
    return v;
}

/* Longer curves, where the pruning of the DP (rows and ends that cannot be on the optimal
 * path) cuts most of the cost table: smooth motions with noise, a drifting random walk and
 * integer steps (many ties); the DP's error must be the plain DP's optimum. */
static void test_keyframes_pruned_optimal(void **state)
{
    (void)state;
    affect_rng r;
    affect_rng_seed(&r, 11);
    for (int trial = 0; trial < 12; trial++) {
        uint32_t T = 40 + (uint32_t)(affect_rng_uniform(&r) * 110); /* 40 .. 149 */
        uint32_t D = 1 + (uint32_t)(affect_rng_uniform(&r) * 6);
        uint32_t q = 2 + (uint32_t)(affect_rng_uniform(&r) * 20);
        double *Y = malloc(sizeof(double) * T * D);
        assert_non_null(Y);
        for (uint32_t t = 0; t < T; t++)
            for (uint32_t c = 0; c < D; c++) {
                double v;
                if (trial % 3 == 0)
                    v = 30 * sin(0.07 * t + c) + 0.5 * t + 0.1 * affect_rng_normal(&r);
                else if (trial % 3 == 1)
                    v = (t ? Y[(t - 1) * D + c] : 100) + affect_rng_normal(&r) + 0.2;
                else
                    v = (double)((t / 7 + c) % 4);
                Y[t * D + c] = v;
            }
        uint32_t fr[32], n;
        double sse;
        affect_error err;
        assert_int_equal(affect_keyframes_select(Y, T, D, q, fr, &n, &sse, NULL, &err), AFFECT_OK);
        assert_int_equal(n, q);
        double bv = plain_dp_best(Y, T, D, q);
        if (!(fabs(sse - bv) <= 1e-9 * (1 + bv)))
            fail_msg("T %u D %u q %u: DP %.12g, plain DP %.12g", T, D, q, sse, bv);
        free(Y);
    }
}

/* The loops of every level the processor runs (plain C, SSE2, AVX2, AVX-512) give the same bits:
 * keyframes and error of random curves whose lengths leave partial blocks of ends, noisy, random
 * walks and integer steps (ties), compared with the plain C loops'. */
static void test_keyframes_levels(void **state)
{
    (void)state;
    affect_rng r;
    affect_rng_seed(&r, 23);
    int top = affect_keyframes_level();
    assert_true(top >= AFFECT_KEYFRAMES_LEVEL_SCALAR && top <= AFFECT_KEYFRAMES_LEVEL_AVX512);
    for (int trial = 0; trial < 30; trial++) {
        uint32_t T = 3 + (uint32_t)(affect_rng_uniform(&r) * 150); /* 3 .. 152 */
        uint32_t D = 1 + (uint32_t)(affect_rng_uniform(&r) * 10);
        uint32_t q = 2 + (uint32_t)(affect_rng_uniform(&r) * 16);
        double *Y = malloc(sizeof(double) * T * D);
        assert_non_null(Y);
        for (uint32_t t = 0; t < T; t++)
            for (uint32_t c = 0; c < D; c++)
                Y[t * D + c] = trial % 3 == 0 ? 40 * affect_rng_normal(&r)
                               : trial % 3 == 1
                                   ? (t ? Y[(t - 1) * D + c] : 0) + affect_rng_normal(&r)
                                   : (double)((t / 5 + c) % 3);
        uint32_t fr0[32], fr[32], n0, n;
        double sse0, sse;
        affect_error err;
        assert_int_equal(affect_keyframes_select_level(Y, T, D, q, fr0, &n0, &sse0,
                                                       AFFECT_KEYFRAMES_LEVEL_SCALAR, NULL, &err),
                         AFFECT_OK);
        for (int level = AFFECT_KEYFRAMES_LEVEL_BASE; level <= AFFECT_KEYFRAMES_LEVEL_AVX512;
             level++) {
            assert_int_equal(
                affect_keyframes_select_level(Y, T, D, q, fr, &n, &sse, level, NULL, &err),
                AFFECT_OK);
            assert_int_equal(n, n0);
            assert_memory_equal(fr, fr0, n * sizeof fr[0]);
            assert_memory_equal(&sse, &sse0, sizeof sse);
        }
        assert_int_equal(affect_keyframes_select(Y, T, D, q, fr, &n, &sse, NULL, &err), AFFECT_OK);
        assert_memory_equal(fr, fr0, n * sizeof fr[0]);
        free(Y);
    }
}

static void test_keyframes_exact(void **state)
{
    (void)state;
    double Y[5 * 2] = {1, 2, 3, 5, 8, 13, 21, 34, 55, 89};
    uint32_t fr[8], n;
    double sse = -1;
    affect_error err;
    assert_int_equal(affect_keyframes_select(Y, 5, 2, 5, fr, &n, &sse, NULL, &err), AFFECT_OK);
    assert_int_equal(n, 5);
    assert_true(sse == 0);
    for (uint32_t k = 0; k < 5; k++)
        assert_int_equal(fr[k], k);
    assert_int_equal(affect_keyframes_select(Y, 5, 2, 8, fr, &n, &sse, NULL, &err), AFFECT_OK);
    assert_int_equal(n, 5);
    /* a straight line needs 2 keyframes and has no error */
    double line[6] = {0, 1, 2, 3, 4, 5};
    assert_int_equal(affect_keyframes_select(line, 6, 1, 2, fr, &n, &sse, NULL, &err), AFFECT_OK);
    assert_true(sse < 1e-20);
    /* errors */
    assert_int_equal(affect_keyframes_select(Y, 5, 2, 1, fr, &n, &sse, NULL, &err),
                     AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "keyframes must be from 2 to 4096 (got 1)");
    assert_int_equal(affect_keyframes_select(Y, 0, 2, 3, fr, &n, &sse, NULL, &err),
                     AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "empty curve (0 frames of 2 values)");
}

/* ---- regression ---- */

static void test_regression_smooth_map(void **state)
{
    (void)state;
    /* z(s) = (sin s, s², 1 − s/2) on 60 points, with a little noise */
    affect_strength s;
    memset(&s, 0, sizeof s);
    s.n_train = 60;
    s.pdim = 3;
    double r[60], z[180], zbar[3], pred[3];
    affect_rng g;
    affect_rng_seed(&g, 2);
    for (int i = 0; i < 60; i++) {
        r[i] = -2 + 4.0 * i / 59;
        z[3 * i] = sin(r[i]) + 0.01 * affect_rng_normal(&g);
        z[3 * i + 1] = r[i] * r[i] + 0.01 * affect_rng_normal(&g);
        z[3 * i + 2] = 1 - r[i] / 2 + 0.01 * affect_rng_normal(&g);
    }
    s.train_r = r;
    s.train_z = z;
    s.zbar = zbar;
    affect_error err;
    affect_strength_regression kinds[] = {AFFECT_STRENGTH_REG_KERNEL_RIDGE,
                                          AFFECT_STRENGTH_REG_LOCAL_LINEAR,
                                          AFFECT_STRENGTH_REG_AUTO};
    for (int k = 0; k < 3; k++) {
        assert_int_equal(affect_strength_fit_regression(&s, kinds[k], NULL, &err), AFFECT_OK);
        assert_true(s.cv_kernel_ridge < 0.02 * s.cv_constant);
        assert_true(s.cv_local_linear < 0.02 * s.cv_constant);
        for (double t = -1.5; t <= 1.5; t += 0.25) {
            affect_strength_predict(&s, t, pred);
            tu_assert_near(pred[0], sin(t), 0.03);
            tu_assert_near(pred[1], t * t, 0.05);
            tu_assert_near(pred[2], 1 - t / 2, 0.03);
        }
        if (kinds[k] == AFFECT_STRENGTH_REG_AUTO)
            assert_true(s.regression == (s.cv_kernel_ridge < s.cv_local_linear
                                             ? AFFECT_STRENGTH_REG_KERNEL_RIDGE
                                             : AFFECT_STRENGTH_REG_LOCAL_LINEAR));
        affect_free(s.alpha);
        s.alpha = NULL;
    }
}

/* ---- the model on synthetic motions ---- */

#define N_INT 3
static const double INTENSITY[N_INT] = {0.2, 0.8, 1.4};
static const char *const LEVELS[N_INT] = {"mild", "medium", "strong"};

typedef struct corpus {
    affect_motion *m[64];
    int32_t level[64];
    uint32_t group[64];
    uint32_t n;
} corpus;

static void make_corpus(corpus *c, uint64_t seed0, uint32_t seeds)
{
    static const char *const actions[] = {"knock", "wave"};
    c->n = 0;
    for (uint32_t a = 0; a < 2; a++)
        for (uint32_t l = 0; l < N_INT; l++)
            for (uint32_t k = 0; k < seeds; k++) {
                affect_synth_options so;
                affect_synth_options_default(&so);
                so.intensity = INTENSITY[l];
                affect_error err;
                assert_int_equal(
                    affect_motion_synth(actions[a], "angry", seed0 + k, &so, &c->m[c->n], &err),
                    AFFECT_OK);
                c->level[c->n] = (int32_t)l;
                c->group[c->n] = a;
                c->n++;
            }
}

static void free_corpus(corpus *c)
{
    for (uint32_t i = 0; i < c->n; i++)
        affect_motion_free(c->m[i]);
}

static double pair_accuracy(const affect_strength *s, const corpus *c, double *score)
{
    affect_error err;
    for (uint32_t i = 0; i < c->n; i++)
        assert_int_equal(affect_strength_score(s, c->m[i], &score[i], NULL, &err), AFFECT_OK);
    uint32_t right = 0, total = 0;
    for (uint32_t i = 0; i < c->n; i++)
        for (uint32_t j = 0; j < c->n; j++)
            if (c->level[i] > c->level[j] && c->group[i] == c->group[j]) {
                total++;
                right += score[i] > score[j];
            }
    return (double)right / total;
}

/* Training, ranking, determinism, the BLOB, then synthesis and editing (keyframes: both in the
 * order asked; both blocks: editing in order; the Laban vector alone and the Fisher
 * representation: a clear error). */
static void check_model(affect_strength_feature_kind feat)
{
    corpus tr, te;
    make_corpus(&tr, 1, 4);
    make_corpus(&te, 101, 2);
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.pca_dims = 10;
    opt.features = feat;
    affect_strength *s, *s2;
    affect_error err;
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, tr.group,
                                           tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    assert_true(s->stats.converged);
    assert_true(s->pdim == 10);
    assert_int_equal(s->features, feat);
    if (feat == AFFECT_STRENGTH_FEAT_FISHER) {
        assert_non_null(s->fisher);
        assert_int_equal(affect_strength_rank_dim(s), affect_classifier_dim(s->fisher));
        assert_int_equal(affect_classifier_n_classes(s->fisher), N_INT);
        assert_false(s->cv_C); /* the sum of the pair losses, C as given */
    } else {
        assert_null(s->fisher);
        assert_int_equal(affect_strength_rank_dim(s), feat == AFFECT_STRENGTH_FEAT_KEYFRAMES ? 10u
                                                      : feat == AFFECT_STRENGTH_FEAT_LABAN   ? 27u
                                                                                             : 37u);
    }
    assert_true(feat == AFFECT_STRENGTH_FEAT_BOTH ? s->kf_weight > 0 : s->kf_weight == 0);
    assert_true(s->pca_variance > 0.5 && s->pca_variance <= 1);
    double score[64];
    double acc = pair_accuracy(s, &te, score);
    if (!(acc >= 0.9))
        fail_msg("held-out pair accuracy %g", acc);
    assert_true(s->level_strength[0] < s->level_strength[1]);
    assert_true(s->level_strength[1] < s->level_strength[2]);
    /* determinism: the same bytes twice */
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, tr.group,
                                           tr.n, LEVELS, N_INT, &opt, &s2, &err),
                     AFFECT_OK);
    unsigned char *b1, *b2;
    size_t n1, n2;
    assert_int_equal(affect_strength_encode(s, &b1, &n1, &err), AFFECT_OK);
    assert_int_equal(affect_strength_encode(s2, &b2, &n2, &err), AFFECT_OK);
    assert_int_equal(n1, n2);
    assert_memory_equal(b1, b2, n1);
    /* round trip: the same scores */
    affect_strength *back;
    assert_int_equal(affect_strength_decode(b1, n1, &back, &err), AFFECT_OK);
    double sc2[64];
    pair_accuracy(back, &te, sc2);
    for (uint32_t i = 0; i < te.n; i++)
        assert_true(sc2[i] == score[i]);
    unsigned char *b3;
    size_t n3;
    assert_int_equal(affect_strength_encode(back, &b3, &n3, &err), AFFECT_OK);
    assert_int_equal(n3, n1);
    assert_memory_equal(b3, b1, n1);
    /* corruption */
    for (size_t cut = 0; cut < n1; cut += n1 / 37 + 1) {
        affect_strength *bad;
        assert_true(affect_strength_decode(b1, cut, &bad, &err) == AFFECT_ERR_FORMAT);
    }
    b1[n1 / 2] ^= 0x10;
    affect_strength *bad;
    assert_int_equal(affect_strength_decode(b1, n1, &bad, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "strength model checksum mismatch: the BLOB is corrupt");
    /* synthesis (from a model of one action, as the paper fits its regression per action:
     * the mean of two actions is neither): strengths spread over the training range come out
     * in order */
    affect_strength *whole = s;
    if (feat == AFFECT_STRENGTH_FEAT_FISHER) { /* it edits, but cannot synthesize */
        affect_motion *m = NULL;
        assert_int_equal(affect_strength_synthesize(s, 0, true, &m, NULL, &err),
                         AFFECT_ERR_INVALID);
        assert_null(m);
        assert_true(strstr(err.msg, "the recognizer's Fisher representation") != NULL);
    }
    if (feat == AFFECT_STRENGTH_FEAT_LABAN) {
        affect_motion *m = NULL;
        assert_int_equal(affect_strength_synthesize(s, 0, true, &m, NULL, &err),
                         AFFECT_ERR_INVALID);
        assert_null(m);
        assert_true(strstr(err.msg, "the Laban vector alone") != NULL);
        assert_int_equal(affect_strength_edit(s, te.m[0], 0, true, &m, NULL, &err),
                         AFFECT_ERR_INVALID);
        assert_null(m);
        s = NULL;
        goto done;
    }
    affect_motion *knock[12];
    int32_t klev[12];
    for (uint32_t i = 0; i < 12; i++) {
        knock[i] = tr.m[i];
        klev[i] = tr.level[i];
    }
    assert_int_equal(affect_strength_train((const affect_motion *const *)knock, klev, NULL, 12,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    double lo = s->level_strength[0], hi = s->level_strength[2], prev = -INFINITY;
    if (feat == AFFECT_STRENGTH_FEAT_FISHER) { /* edits keep the motion's frames and joints */
        affect_motion *m;
        double got;
        assert_int_equal(affect_strength_edit(s, te.m[0], hi, true, &m, NULL, &err), AFFECT_OK);
        assert_int_equal(m->n_frames, te.m[0]->n_frames);
        assert_int_equal(m->n_joints, te.m[0]->n_joints);
        assert_int_equal(affect_strength_score(s, m, &got, NULL, &err), AFFECT_OK);
        double before;
        assert_int_equal(affect_strength_score(s, te.m[0], &before, NULL, &err), AFFECT_OK);
        if (!(fabs(got - hi) < fabs(before - hi)))
            fail_msg("edited toward %g: strength %g, %g before", hi, got, before);
        affect_motion_free(m);
    }
    for (int k = 0; feat == AFFECT_STRENGTH_FEAT_KEYFRAMES && k < 5; k++) {
        double target = lo + (hi - lo) * k / 4.0, got;
        affect_motion *m;
        assert_int_equal(affect_strength_synthesize(s, target, true, &m, NULL, &err), AFFECT_OK);
        assert_int_equal(m->n_joints, tr.m[0]->n_joints);
        assert_true(m->n_frames > 10);
        assert_int_equal(affect_strength_score(s, m, &got, NULL, &err), AFFECT_OK);
        if (!(got > prev))
            fail_msg("synthesized at %g: strength %g after %g", target, got, prev);
        prev = got;
        affect_motion_free(m);
    }
    /* editing: a held-out mild motion edited to three strengths, in order, near the targets */
    prev = -INFINITY;
    for (int k = 0; k < 3; k++) {
        double target = s->level_strength[k], got;
        affect_motion *m;
        assert_int_equal(affect_strength_edit(s, te.m[0], target, true, &m, NULL, &err), AFFECT_OK);
        assert_int_equal(affect_strength_score(s, m, &got, NULL, &err), AFFECT_OK);
        if (!(got > prev))
            fail_msg("edited to %g: strength %g after %g", target, got, prev);
        prev = got;
        affect_motion_free(m);
    }
done:
    affect_free(b1);
    affect_free(b2);
    affect_free(b3);
    affect_strength_free(whole);
    affect_strength_free(s);
    affect_strength_free(s2);
    affect_strength_free(back);
    free_corpus(&tr);
    free_corpus(&te);
}

static void test_model(void **state)
{
    (void)state;
    check_model(AFFECT_STRENGTH_FEAT_KEYFRAMES);
}

static void test_model_laban(void **state)
{
    (void)state;
    check_model(AFFECT_STRENGTH_FEAT_LABAN);
}

static void test_model_both(void **state)
{
    (void)state;
    check_model(AFFECT_STRENGTH_FEAT_BOTH);
}

static void test_model_fisher(void **state)
{
    (void)state;
    check_model(AFFECT_STRENGTH_FEAT_FISHER);
}

/* A Fisher model's recognizer is checked against the model: other class names than the levels
 * are refused; a level without motions is no class of the recognizer. */
static void test_fisher_checks(void **state)
{
    (void)state;
    corpus tr;
    make_corpus(&tr, 7, 2);
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.features = AFFECT_STRENGTH_FEAT_FISHER;
    affect_strength *s;
    affect_error err;
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    char *keep = s->level_names[1];
    s->level_names[1] = affect_strndup("average", 7);
    unsigned char *b;
    size_t n;
    assert_int_equal(affect_strength_encode(s, &b, &n, &err), AFFECT_OK);
    affect_strength *bad;
    assert_int_equal(affect_strength_decode(b, n, &bad, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg,
                        "the strength model's recognizer has other classes than its levels");
    affect_free(b);
    affect_free(s->level_names[1]);
    s->level_names[1] = keep;
    affect_strength_free(s);
    /* no "medium" motion: the recognizer's classes are mild and strong, and the model reads back */
    int32_t lv[64];
    for (uint32_t i = 0; i < tr.n; i++)
        lv[i] = tr.level[i] == 1 ? -1 : tr.level[i];
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, lv, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    assert_int_equal(affect_classifier_n_classes(s->fisher), 2);
    assert_string_equal(affect_classifier_label(s->fisher, 1), "strong");
    assert_int_equal(affect_strength_encode(s, &b, &n, &err), AFFECT_OK);
    affect_strength *back;
    assert_int_equal(affect_strength_decode(b, n, &back, &err), AFFECT_OK);
    double r1, r2;
    assert_int_equal(affect_strength_score(s, tr.m[0], &r1, NULL, &err), AFFECT_OK);
    assert_int_equal(affect_strength_score(back, tr.m[0], &r2, NULL, &err), AFFECT_OK);
    assert_true(r1 == r2);
    assert_true(s->level_strength[0] < s->level_strength[2] && s->level_count[1] == 0);
    affect_free(b);
    affect_strength_free(back);
    affect_strength_free(s);
    free_corpus(&tr);
}

/* The Laban ranker's C multiplies the mean pair loss: doubling every pair (the same data twice)
 * leaves the model as it is, where the sum form (keyframes) would halve the regularization. */
static void test_laban_mean_loss(void **state)
{
    (void)state;
    corpus tr;
    make_corpus(&tr, 1, 2);
    corpus two = tr;
    for (uint32_t i = 0; i < tr.n; i++) {
        two.m[tr.n + i] = tr.m[i];
        two.level[tr.n + i] = tr.level[i];
        two.group[tr.n + i] = tr.group[i];
    }
    two.n = 2 * tr.n;
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.features = AFFECT_STRENGTH_FEAT_LABAN;
    opt.pca_dims = 3;
    opt.keyframes = 4;
    opt.similar = false; /* the copies would add similar pairs of identical motions */
    opt.cv_C = false;    /* the copies would change the inner folds */
    affect_strength *a, *b;
    affect_error err;
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &a, &err),
                     AFFECT_OK);
    assert_int_equal(affect_strength_train((const affect_motion *const *)two.m, two.level, NULL,
                                           two.n, LEVELS, N_INT, &opt, &b, &err),
                     AFFECT_OK);
    /* 4 times the ordered pairs (every pair, its copies and the cross pairs): the same mean */
    assert_int_equal(b->stats.ordered, 4 * a->stats.ordered);
    for (uint32_t k = 0; k < AFFECT_LABAN_N; k++) {
        tu_assert_near(b->w[k], a->w[k], 1e-9 * (1 + fabs(a->w[k])));
        tu_assert_near(b->lab_mean[k], a->lab_mean[k], 1e-9 * (1 + fabs(a->lab_mean[k])));
    }
    assert_false(a->cv_C);
    assert_true(a->C == 1);
    affect_strength_free(a);
    affect_strength_free(b);
    free_corpus(&tr);
}

/* The inner cross-validation of C (the default with Laban features): a C of the grid, marked in
 * the model and its BLOB; a C given (cv_C false) is kept; keyframes never cross-validate. */
static void test_cv_C(void **state)
{
    (void)state;
    corpus tr;
    make_corpus(&tr, 1, 3);
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.features = AFFECT_STRENGTH_FEAT_LABAN;
    opt.pca_dims = 3;
    opt.keyframes = 4;
    affect_strength *s;
    affect_error err;
    assert_true(opt.cv_C);
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    assert_true(s->cv_C);
    assert_true(s->C == 0.01 || s->C == 0.1 || s->C == 1 || s->C == 10 || s->C == 100);
    unsigned char *b;
    size_t nb;
    affect_strength *back;
    assert_int_equal(affect_strength_encode(s, &b, &nb, &err), AFFECT_OK);
    assert_int_equal(affect_strength_decode(b, nb, &back, &err), AFFECT_OK);
    assert_true(back->cv_C && back->C == s->C);
    affect_free(b);
    affect_strength_free(back);
    affect_strength_free(s);
    opt.cv_C = false;
    opt.C = 0.5;
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    assert_false(s->cv_C);
    assert_true(s->C == 0.5);
    affect_strength_free(s);
    opt.cv_C = true;
    opt.features = AFFECT_STRENGTH_FEAT_KEYFRAMES;
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    assert_false(s->cv_C);
    assert_true(s->C == 0.5);
    affect_strength_free(s);
    free_corpus(&tr);
}

static void test_no_pca_and_options(void **state)
{
    (void)state;
    corpus tr;
    make_corpus(&tr, 1, 2);
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.pca_dims = 0;
    opt.keyframes = 6;
    opt.fraction = 0.5;
    opt.seed = 3;
    opt.regression = AFFECT_STRENGTH_REG_KERNEL_RIDGE;
    opt.relative = true;
    opt.features = AFFECT_STRENGTH_FEAT_BOTH; /* synthesis and editing need keyframes */
    affect_strength *s;
    affect_error err;
    assert_int_equal(affect_strength_train((const affect_motion *const *)tr.m, tr.level, NULL, tr.n,
                                           LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    assert_false(s->pca);
    assert_int_equal(s->pdim, s->dim);
    assert_int_equal(s->dim, 6u * 6u * tr.m[0]->n_joints);
    assert_int_equal(s->regression, AFFECT_STRENGTH_REG_KERNEL_RIDGE);
    unsigned char *b;
    size_t nb;
    affect_strength *back;
    assert_int_equal(affect_strength_encode(s, &b, &nb, &err), AFFECT_OK);
    assert_int_equal(affect_strength_decode(b, nb, &back, &err), AFFECT_OK);
    assert_true(back->relative && back->scale != NULL);
    assert_int_equal(back->root, s->root);
    affect_motion *m;
    assert_int_equal(affect_strength_synthesize(back, 0.0, false, &m, NULL, &err), AFFECT_OK);
    affect_motion_free(m);
    /* relative poses and standardized features are undone exactly: editing a training motion
     * to its own strength (no correction needed: it lands on it) gives it back */
    double r0;
    assert_int_equal(affect_strength_score(s, tr.m[0], &r0, NULL, &err), AFFECT_OK);
    assert_int_equal(affect_strength_edit(s, tr.m[0], r0, false, &m, NULL, &err), AFFECT_OK);
    assert_int_equal(m->n_frames, tr.m[0]->n_frames);
    if (!(tu_max_dist(m, tr.m[0]) < 1e-4))
        fail_msg("an edit to the motion's own strength moved it by %g", tu_max_dist(m, tr.m[0]));
    affect_motion_free(m);
    affect_free(b);
    affect_strength_free(back);
    affect_strength_free(s);
    free_corpus(&tr);
}

static void test_errors(void **state)
{
    (void)state;
    corpus tr;
    make_corpus(&tr, 1, 1);
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    affect_strength *s;
    affect_error err;
    const affect_motion *const *ms = (const affect_motion *const *)tr.m;
    opt.keyframes = 1;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "keyframes must be from 2 to 4096 (got 1)");
    affect_strength_options_default(&opt);
    opt.keyframes = 100000 / 10;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    affect_strength_options_default(&opt);
    opt.keyframes = 4000;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_RANGE);
    assert_true(strncmp(err.msg, "motion 0: ", 10) == 0);
    affect_strength_options_default(&opt);
    opt.C = 0;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "C must be finite and > 0 (got 0)");
    affect_strength_options_default(&opt);
    opt.descriptors = 4;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "descriptors must be a mask of 0 to 3 (got 4)");
    affect_strength_options_default(&opt);
    opt.features = AFFECT_STRENGTH_FEAT_KEYFRAMES; /* (Fisher features need every level) */
    int32_t one[6] = {0, 0, 0, -1, -1, -1};
    assert_int_equal(affect_strength_train(ms, one, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg,
                        "no ordered pairs: the motions need at least two different labels");
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, 1, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the order must have 2 to 64 labels (got 1)");
    opt.features = (affect_strength_feature_kind)4;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "features must be 0 to 3 (got 4)");
    /* the Laban vector scores a motion shorter than the keyframes (it needs none) */
    opt.features = AFFECT_STRENGTH_FEAT_LABAN;
    opt.pca_dims = 3;
    opt.keyframes = 5;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    affect_motion *shortl;
    double vl;
    assert_int_equal(affect_motion_slice(tr.m[0], 0, 2, &shortl, &err), AFFECT_OK);
    assert_int_equal(affect_strength_score(s, shortl, &vl, NULL, &err), AFFECT_OK);
    assert_true(isfinite(vl));
    affect_motion_free(shortl);
    affect_strength_free(s);
    /* another skeleton */
    opt.features = AFFECT_STRENGTH_FEAT_KEYFRAMES;
    assert_int_equal(affect_strength_train(ms, tr.level, NULL, tr.n, LEVELS, N_INT, &opt, &s, &err),
                     AFFECT_OK);
    affect_motion *other;
    assert_int_equal(affect_motion_create(20, 3, 30, &other, &err), AFFECT_OK);
    double v;
    assert_int_equal(affect_strength_score(s, other, &v, NULL, &err), AFFECT_ERR_INVALID);
    char expect[96];
    snprintf(expect, sizeof expect, "3 joints, the model has %u", tr.m[0]->n_joints);
    assert_string_equal(err.msg, expect);
    affect_motion *shortm;
    assert_int_equal(affect_motion_slice(tr.m[0], 0, 2, &shortm, &err), AFFECT_OK);
    assert_int_equal(affect_strength_score(s, shortm, &v, NULL, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "3 frames, fewer than the 5 keyframes");
    affect_motion *m;
    assert_int_equal(affect_strength_synthesize(s, NAN, true, &m, NULL, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the strength must be finite");
    affect_motion_free(other);
    affect_motion_free(shortm);
    affect_strength_free(s);
    free_corpus(&tr);
}

typedef struct oom_ctx {
    corpus tr;
    affect_strength *s;
    affect_motion *m;
    int what;
    unsigned char *blob; /* what 4: a Fisher model's BLOB */
    size_t size;
    affect_motion *m0; /* what 5: the motion edited */
} oom_ctx;

static affect_status oom_op(void *ctx, affect_error *err)
{
    oom_ctx *c = ctx;
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.pca_dims = 3;
    opt.keyframes = 4;
    opt.features = AFFECT_STRENGTH_FEAT_BOTH; /* the Laban and the keyframe paths */
    if (c->what == 0)
        return affect_strength_train((const affect_motion *const *)c->tr.m, c->tr.level, NULL,
                                     c->tr.n, LEVELS, N_INT, &opt, &c->s, err);
    if (c->what == 1)
        return affect_strength_synthesize(c->s, 0.5, true, &c->m, NULL, err);
    if (c->what == 2)
        return affect_strength_edit(c->s, c->tr.m[1], 0.5, true, &c->m, NULL, err);
    if (c->what == 3) { /* Fisher features: the recognizer's training */
        opt.features = AFFECT_STRENGTH_FEAT_FISHER;
        return affect_strength_train((const affect_motion *const *)c->tr.m, c->tr.level, NULL,
                                     c->tr.n, LEVELS, N_INT, &opt, &c->s, err);
    }
    if (c->what == 5) /* a Fisher model's edit (of a short slice: each step reads it again) */
        return affect_strength_edit(c->s, c->m0, c->s->level_strength[2], true, &c->m, NULL, err);
    /* a Fisher model decoded, then a motion scored */
    double r;
    affect_status st = affect_strength_decode(c->blob, c->size, &c->s, err);
    return st != AFFECT_OK ? st : affect_strength_score(c->s, c->tr.m[2], &r, NULL, err);
}

static void oom_finish(void *ctx, affect_status st)
{
    oom_ctx *c = ctx;
    (void)st;
    if (c->what == 0 || c->what == 3 || c->what == 4) {
        affect_strength_free(c->s);
        c->s = NULL;
    } else {
        affect_motion_free(c->m);
        c->m = NULL;
    }
}

static void test_out_of_memory(void **state)
{
    (void)state;
    oom_ctx c;
    memset(&c, 0, sizeof c);
    make_corpus(&c.tr, 1, 1);
    c.what = 0;
    long absorbed; /* affect_roles_resolve parses names on the fly when it cannot allocate */
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 10);
    affect_error err;
    affect_strength_options opt;
    affect_strength_options_default(&opt);
    opt.pca_dims = 3;
    opt.keyframes = 4;
    opt.features = AFFECT_STRENGTH_FEAT_BOTH;
    assert_int_equal(affect_strength_train((const affect_motion *const *)c.tr.m, c.tr.level, NULL,
                                           c.tr.n, LEVELS, N_INT, &opt, &c.s, &err),
                     AFFECT_OK);
    c.what = 1;
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 3);
    c.what = 2;
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 3);
    affect_strength_free(c.s);
    c.s = NULL;
    c.what = 3;
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 10);
    opt.features = AFFECT_STRENGTH_FEAT_FISHER;
    assert_int_equal(affect_strength_train((const affect_motion *const *)c.tr.m, c.tr.level, NULL,
                                           c.tr.n, LEVELS, N_INT, &opt, &c.s, &err),
                     AFFECT_OK);
    assert_int_equal(affect_strength_encode(c.s, &c.blob, &c.size, &err), AFFECT_OK);
    affect_strength_free(c.s);
    c.s = NULL;
    c.what = 4;
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 10);
    assert_int_equal(affect_strength_decode(c.blob, c.size, &c.s, &err), AFFECT_OK);
    assert_int_equal(affect_motion_slice(c.tr.m[0], 0, 12, &c.m0, &err), AFFECT_OK);
    c.what = 5;
    assert_true(tu_oom_sweep(oom_op, &c, oom_finish, &absorbed) > 10);
    affect_motion_free(c.m0);
    affect_strength_free(c.s);
    affect_free(c.blob);
    free_corpus(&c.tr);
}

static void test_fixture_v1(void **state)
{
    (void)state;
    size_t n;
    char *data = tu_read_file(AFFECT_FIXTURES_DIR "/strength-v1.bin", &n);
    assert_non_null(data);
    affect_strength *s;
    affect_error err;
    assert_int_equal(affect_strength_decode((const unsigned char *)data, n, &s, &err), AFFECT_OK);
    assert_int_equal(s->n_joints, 26);
    assert_int_equal(s->keyframes, 3);
    assert_int_equal(s->dim, 468);
    assert_int_equal(s->pdim, 2);
    assert_true(s->pca);
    assert_int_equal(s->n_train, 3);
    assert_int_equal(s->n_levels, 3);
    assert_string_equal(s->level_names[1], "0.8");
    assert_int_equal(s->regression, AFFECT_STRENGTH_REG_KERNEL_RIDGE);
    assert_int_equal(s->stats.ordered, 3);
    assert_int_equal(s->stats.correct, 3);
    assert_true(s->level_strength[0] < s->level_strength[1] &&
                s->level_strength[1] < s->level_strength[2]);
    unsigned char *enc;
    size_t ne;
    assert_int_equal(affect_strength_encode(s, &enc, &ne, &err), AFFECT_OK);
    assert_int_equal(ne, n);
    assert_memory_equal(enc, data, n);
    /* the training motions score as stored (the wave of seed 1 at intensity 1.4) */
    affect_synth_options so;
    affect_synth_options_default(&so);
    so.intensity = 1.4;
    affect_motion *m;
    assert_int_equal(affect_motion_synth("wave", "angry", 1, &so, &m, &err), AFFECT_OK);
    double r;
    assert_int_equal(affect_strength_score(s, m, &r, NULL, &err), AFFECT_OK);
    tu_assert_near(r, s->level_strength[2], 1e-9);
    affect_motion_free(m);
    affect_free(enc);
    affect_strength_free(s);
    free(data);
}

/* A fixture's bytes (*n of them; free them) and its decoded model. */
static char *decode_fixture(const char *path, size_t *n, affect_strength **s)
{
    char *data = tu_read_file(path, n);
    assert_non_null(data);
    affect_error err;
    assert_int_equal(affect_strength_decode((const unsigned char *)data, *n, s, &err), AFFECT_OK);
    return data;
}

/* The end of a fixture's test (frees s and data): today's encoder writes the fixture's bytes;
 * the angry wave of seed 1 at intensity 1.4 (reduced to the joints keep, when given) scores the
 * stored strength of its level (the third); and the fixture's flags under a header of version
 * older are refused (checksum recomputed). */
static void check_fixture_tail(affect_strength *s, char *data, size_t n, const char *const *keep,
                               uint32_t n_keep, unsigned char older)
{
    affect_error err;
    unsigned char *enc;
    size_t ne;
    assert_int_equal(affect_strength_encode(s, &enc, &ne, &err), AFFECT_OK);
    assert_int_equal(ne, n);
    assert_memory_equal(enc, data, n);
    affect_synth_options so;
    affect_synth_options_default(&so);
    so.intensity = 1.4;
    affect_motion *m, *sel = NULL;
    assert_int_equal(affect_motion_synth("wave", "angry", 1, &so, &m, &err), AFFECT_OK);
    if (keep)
        assert_int_equal(affect_motion_select(m, keep, n_keep, &sel, &err), AFFECT_OK);
    double r;
    assert_int_equal(affect_strength_score(s, sel ? sel : m, &r, NULL, &err), AFFECT_OK);
    tu_assert_near(r, s->level_strength[2], 1e-9);
    enc[4] = older;
    uint64_t h = affect_fnv1a64(enc, ne - 8);
    for (int k = 0; k < 8; k++)
        enc[ne - 8 + (size_t)k] = (unsigned char)(h >> (8 * k));
    affect_strength *bad;
    assert_int_equal(affect_strength_decode(enc, ne, &bad, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "reserved strength model fields are not valid");
    affect_motion_free(sel);
    affect_motion_free(m);
    affect_free(enc);
    affect_strength_free(s);
    free(data);
}

/* Version 2: both feature blocks (flags 61: PCA, standardized, Laban, both, C cross-validated). */
static void test_fixture_v2(void **state)
{
    (void)state;
    size_t n;
    affect_strength *s;
    char *data = decode_fixture(AFFECT_FIXTURES_DIR "/strength-v2.bin", &n, &s);
    assert_int_equal(s->features, AFFECT_STRENGTH_FEAT_BOTH);
    assert_int_equal(s->pdim, 2);
    assert_int_equal(affect_strength_rank_dim(s), 2 + AFFECT_LABAN_N);
    assert_true(s->kf_weight > 0 && s->scale != NULL && s->pca && s->cv_C);
    assert_int_equal(s->n_train, 3);
    assert_int_equal(s->stats.ordered, 3);
    assert_int_equal(s->stats.correct, 3);
    for (uint32_t k = 0; k < AFFECT_LABAN_N; k++)
        assert_true(s->lab_sd[k] > 0);
    /* the wave of intensity 1.4 scores its level's stored strength; a flag of version 2 in a
     * version-1 header is rejected */
    check_fixture_tail(s, data, n, NULL, 0, 1);
}

/* Version 3: Fisher features (flags 69: PCA, standardized, Fisher), the recognizer without
 * descriptors, nine joints of the synthetic skeleton. */
static void test_fixture_v3(void **state)
{
    (void)state;
    size_t n;
    affect_strength *s;
    char *data = decode_fixture(AFFECT_FIXTURES_DIR "/strength-v3.bin", &n, &s);
    assert_int_equal(s->features, AFFECT_STRENGTH_FEAT_FISHER);
    assert_non_null(s->fisher);
    assert_int_equal(affect_classifier_get_config(s->fisher)->descriptors, 0);
    assert_int_equal(affect_strength_rank_dim(s), 900);
    assert_true(s->scale != NULL && s->pca && !s->cv_C);
    assert_int_equal(s->n_joints, 9);
    assert_int_equal(s->n_train, 3);
    assert_int_equal(s->stats.correct, 3);
    /* the wave of intensity 1.4 (the same nine joints) scores its level's stored strength; the
     * Fisher flag in a version-2 header is rejected */
    static const char *const keep[] = {"Hips",       "Chest",  "Head",       "Shoulder_L", "Hand_L",
                                       "Shoulder_R", "Hand_R", "UpperLeg_L", "UpperLeg_R"};
    check_fixture_tail(s, data, n, keep, 9, 2);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_keyframes_optimal),
        cmocka_unit_test(test_keyframes_pruned_optimal),
        cmocka_unit_test(test_keyframes_levels),
        cmocka_unit_test(test_keyframes_exact),
        cmocka_unit_test(test_regression_smooth_map),
        cmocka_unit_test(test_model),
        cmocka_unit_test(test_no_pca_and_options),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_out_of_memory),
        cmocka_unit_test(test_fixture_v1),
        cmocka_unit_test(test_model_laban),
        cmocka_unit_test(test_model_both),
        cmocka_unit_test(test_model_fisher),
        cmocka_unit_test(test_fisher_checks),
        cmocka_unit_test(test_laban_mean_loss),
        cmocka_unit_test(test_fixture_v2),
        cmocka_unit_test(test_fixture_v3),
        cmocka_unit_test(test_cv_C),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
