/*
 * test_classifier.c — the emotion recognizer (affect/classifier.h) on motion_synth
 * observations: 3 actions (knock, wave, bow) × 4 emotions × performers (seeds) 1–6, the hands,
 * head and chest by role with velocities (24 dimensions); trained on performers 1–4 (48
 * motions, 5 states, 1 mixture, 8 Baum–Welch iterations), tested on the unseen performers 5–6.
 *
 * Checked: SVM, kNN and ML recognition of the held-out performers (≥ 95 %); the normalization
 * (mean and population standard deviation of the raw Fisher scores of the training motions,
 * recomputed here from affect_fisher_score under the classifier's own HMMs); the evaluated
 * Fisher vector is exactly clip((raw − mean) / scale) and never exceeds score_clip although
 * the unclipped z-scores do; without z-scores nothing is clipped; an encode → decode round
 * trip evaluates bit-identically (decision values, log-likelihoods, embedding, Fisher vector,
 * votes) and re-encodes to the same bytes; two trainings give the same BLOB; every corrupted
 * byte, every truncation (with and without a recomputed checksum), wrong magic, version,
 * flags, class count, configuration and trailing bytes are refused with their messages;
 * every message of affect_classifier_config_check and of affect_classifier_train's argument
 * checks; the grid search (values from the lists, the best combination, grid_cv_acc, a
 * one-value grid equals the plain configuration); the salience rows against a brute-force
 * recomputation from the sPCA axes; and every allocation failing in turn in encode, decode,
 * eval and a tiny training with C and grid search (libsvm's own mallocs are not injectable).
 *
 * The 48-motion classifier is trained once, in the group setup.
 */
#include <float.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/classifier.h"
#include "affect/laban.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "util/quant.h"
#include "affect/synth.h"

#define N_ACTIONS 3
#define N_EMOTIONS 4
#define N_SEEDS 6
#define N_MOTIONS (N_ACTIONS * N_EMOTIONS * N_SEEDS)
#define TRAIN_SEEDS 4 /* performers 1 .. 4 train, 5 .. 6 are held out */

static const char *const ACTIONS[N_ACTIONS] = {"knock", "wave", "bow"};
static const char *const EMOTIONS[N_EMOTIONS] = {"neutral", "happy", "sad", "angry"};
static const char *const JOINTS4[] = {"right_hand", "left_hand", "head", "chest"};

static const char GROUPS_MSG[] =
    "groups must be a non-empty combination of start, transitions, weights, means, covariances";
static const char CHECKSUM_MSG[] = "classifier checksum mismatch: the BLOB is corrupt";
static const char MAGIC_MSG[] = "not a classifier (bad magic bytes at offset 0)";

/* ---- data ---- */

typedef struct dataset {
    affect_features *feat;
    uint32_t n;
    double *x[N_MOTIONS];
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS], seed[N_MOTIONS], action[N_MOTIONS];
} dataset;

/* Observations of every (action, emotion, seed) under a definition made from the first
 * motion with the given joints and velocity. */
static void dataset_load(dataset *d, const char *const *joints, uint32_t n_joints, bool velocity)
{
    affect_error err;
    memset(d, 0, sizeof *d);
    for (uint32_t a = 0; a < N_ACTIONS; a++)
        for (uint32_t e = 0; e < N_EMOTIONS; e++)
            for (uint32_t s = 1; s <= N_SEEDS; s++) {
                affect_motion *m = NULL;
                if (affect_motion_synth(ACTIONS[a], EMOTIONS[e], s, NULL, &m, &err))
                    fail_msg("synth: %s", err.msg);
                if (!d->feat) {
                    affect_features_options opt;
                    affect_features_options_default(&opt);
                    opt.joints = joints;
                    opt.n_joints = n_joints;
                    opt.velocity = velocity;
                    if (affect_features_create(&opt, m, &d->feat, &err))
                        fail_msg("features: %s", err.msg);
                }
                uint32_t i = d->n++;
                if (affect_features_extract(d->feat, m, &d->x[i], &d->seqs[i].n_frames, NULL, &err))
                    fail_msg("extract: %s", err.msg);
                d->seqs[i].x = d->x[i];
                d->y[i] = e;
                d->seed[i] = s;
                d->action[i] = a;
                affect_motion_free(m);
            }
}

static void dataset_free(dataset *d)
{
    for (uint32_t i = 0; i < d->n; i++)
        affect_free(d->x[i]);
    affect_features_free(d->feat);
}

/* The training part (seeds 1 .. TRAIN_SEEDS) into seqs / y; returns its size. */
static uint32_t training_part(const dataset *d, affect_hmm_seq *seqs, uint32_t *y)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < d->n; i++)
        if (d->seed[i] <= TRAIN_SEEDS) {
            seqs[n] = d->seqs[i];
            y[n++] = d->y[i];
        }
    return n;
}

static void main_config(affect_classifier_config *cfg, const affect_features *feat)
{
    affect_classifier_config_default(cfg);
    cfg->hmm.dim = affect_features_dim(feat);
    cfg->hmm.n_states = 5;
    cfg->hmm.n_mix = 1;
    cfg->hmm.cov = AFFECT_HMM_FULL;
    cfg->hmm.max_iter = 8;
    cfg->descriptors = 0;
    cfg->mirror = AFFECT_MIRROR_OFF;
}

static affect_classifier *train_ok(const affect_classifier_config *cfg, const affect_features *f,
                                   const affect_hmm_seq *seqs, const uint32_t *y, uint32_t n,
                                   const char *const *labels, uint32_t n_classes)
{
    affect_classifier *c = NULL;
    affect_error err;
    if (affect_classifier_train(cfg, f, seqs, NULL, y, n, labels, n_classes, &c, &err))
        fail_msg("train: %s", err.msg);
    assert_non_null(c);
    return c;
}

static void encode_ok(const affect_classifier *c, unsigned char **blob, size_t *size)
{
    affect_error err;
    if (affect_classifier_encode(c, blob, size, &err))
        fail_msg("encode: %s", err.msg);
}

/* Everything eval gives, in buffers of the right sizes. */
typedef struct eval_res {
    double loglik[N_EMOTIONS], decision[N_EMOTIONS * (N_EMOTIONS - 1) / 2], embed[8];
    uint32_t votes[N_EMOTIONS];
    double *fisher;
    affect_classifier_out o;
} eval_res;

static void eval_ok(const affect_classifier *c, const affect_hmm_seq *s, eval_res *r)
{
    affect_error err;
    assert_true(affect_classifier_n_classes(c) <= N_EMOTIONS);
    assert_true(affect_spca_dims(affect_classifier_spca(c)) <= 8);
    memset(r, 0, sizeof *r);
    r->fisher = malloc(affect_classifier_dim(c) * sizeof *r->fisher);
    assert_non_null(r->fisher);
    r->o.loglik = r->loglik;
    r->o.fisher = r->fisher;
    r->o.decision = r->decision;
    r->o.embed = r->embed;
    r->o.votes = r->votes;
    if (affect_classifier_eval(c, s->x, s->n_frames, NULL, false, &r->o, NULL, &err))
        fail_msg("eval: %s", err.msg);
}

/* The bytes of blob with its last 8 (the checksum) recomputed over the first size − 8. */
static void reseal(unsigned char *blob, size_t size)
{
    uint64_t sum = affect_fnv1a64(blob, size - 8);
    for (int i = 0; i < 8; i++)
        blob[size - 8 + (size_t)i] = (unsigned char)(sum >> (8 * i));
}

static void decode_fails(const unsigned char *blob, size_t size, affect_status st, const char *msg)
{
    affect_classifier *c = (affect_classifier *)blob; /* must become NULL */
    affect_error err;
    affect_error_clear(&err);
    affect_status got = affect_classifier_decode(blob, size, &c, &err);
    if (got != st || (msg && strcmp(err.msg, msg) != 0))
        fail_msg("decode of %zu bytes: status %d \"%s\", expected %d \"%s\"", size, got, err.msg,
                 st, msg ? msg : "(any)");
    assert_null(c);
}

/* ---- the shared fixture ---- */

typedef struct fixture {
    dataset d;
    affect_classifier *c; /* the main classifier (seeds 1 .. 4) */
    unsigned char *blob;
    size_t size;
    dataset small_d;          /* right hand only, no velocity */
    affect_classifier *small; /* 2 classes, 2 states, short sequences */
    unsigned char *small_blob;
    size_t small_size;
    affect_hmm_seq small_seqs[8];
    uint32_t small_y[8], small_n;
} fixture;

static const char *const SMALL_LABELS[2] = {"angry", "sad"};

/* The small set: wave, angry (class 0) and sad (class 1), seeds 1 .. n_seeds, frames
 * first .. first + frames − 1 of each (all motions start from the same pose: the first frames
 * hardly differ). */
static uint32_t small_part(const dataset *d, uint32_t n_seeds, uint32_t first, uint32_t frames,
                           affect_hmm_seq *seqs, uint32_t *y)
{
    uint32_t n = 0, dim = affect_features_dim(d->feat);
    for (uint32_t i = 0; i < d->n; i++)
        if (d->action[i] == 1 && d->seed[i] <= n_seeds && (d->y[i] == 3 || d->y[i] == 2)) {
            assert_true(first + frames <= d->seqs[i].n_frames);
            seqs[n].x = d->x[i] + (size_t)first * dim;
            seqs[n].n_frames = frames;
            y[n++] = d->y[i] == 3 ? 0 : 1;
        }
    return n;
}

static void small_config(affect_classifier_config *cfg, const affect_features *f)
{
    affect_classifier_config_default(cfg);
    cfg->hmm.dim = affect_features_dim(f);
    cfg->hmm.n_states = 2;
    cfg->hmm.n_mix = 1;
    cfg->hmm.cov = AFFECT_HMM_FULL;
    cfg->hmm.max_iter = 3;
    cfg->descriptors = 0;
    cfg->mirror = AFFECT_MIRROR_OFF;
    cfg->svm_c = 1.0;
    cfg->spca_dims = 1;
    cfg->knn_k = 1;
}

static int setup(void **state)
{
    fixture *fx = calloc(1, sizeof *fx);
    if (!fx)
        return -1;
    dataset_load(&fx->d, JOINTS4, 4, true);
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS];
    uint32_t n = training_part(&fx->d, seqs, y);
    affect_classifier_config cfg;
    main_config(&cfg, fx->d.feat);
    fx->c = train_ok(&cfg, fx->d.feat, seqs, y, n, EMOTIONS, N_EMOTIONS);
    encode_ok(fx->c, &fx->blob, &fx->size);

    static const char *const hand[] = {"right_hand"};
    dataset_load(&fx->small_d, hand, 1, false);
    fx->small_n = small_part(&fx->small_d, 3, 0, 30, fx->small_seqs, fx->small_y);
    small_config(&cfg, fx->small_d.feat);
    fx->small =
        train_ok(&cfg, fx->small_d.feat, fx->small_seqs, fx->small_y, fx->small_n, SMALL_LABELS, 2);
    encode_ok(fx->small, &fx->small_blob, &fx->small_size);
    *state = fx;
    return 0;
}

static int teardown(void **state)
{
    fixture *fx = *state;
    affect_classifier_free(fx->c);
    affect_free(fx->blob);
    affect_classifier_free(fx->small);
    affect_free(fx->small_blob);
    dataset_free(&fx->d);
    dataset_free(&fx->small_d);
    free(fx);
    return 0;
}

/* ---- recognition ---- */

static void test_recognition(void **state)
{
    fixture *fx = *state;
    const affect_classifier *c = fx->c;
    uint32_t hits[3] = {0}, n = 0;
    for (uint32_t i = 0; i < fx->d.n; i++) {
        if (fx->d.seed[i] <= TRAIN_SEEDS)
            continue;
        eval_res r;
        eval_ok(c, &fx->d.seqs[i], &r);
        hits[0] += r.o.svm == fx->d.y[i];
        hits[1] += r.o.knn == fx->d.y[i];
        hits[2] += r.o.ml == fx->d.y[i];
        /* the ML label is the argmax of the log-likelihoods, the kNN one has the most votes */
        for (uint32_t k = 0; k < N_EMOTIONS; k++) {
            assert_true(r.loglik[k] <= r.loglik[r.o.ml]);
            assert_true(r.votes[k] <= r.votes[r.o.knn]);
        }
        uint32_t votes = 0;
        for (uint32_t k = 0; k < N_EMOTIONS; k++)
            votes += r.votes[k];
        assert_int_equal(votes, affect_classifier_get_config(c)->knn_k);
        /* ml_only gives the same log-likelihoods and ML label */
        double ll[N_EMOTIONS];
        affect_classifier_out o = {0};
        o.loglik = ll;
        affect_error err;
        assert_int_equal(affect_classifier_eval(c, fx->d.seqs[i].x, fx->d.seqs[i].n_frames, NULL,
                                                true, &o, NULL, &err),
                         AFFECT_OK);
        assert_int_equal(o.ml, r.o.ml);
        assert_memory_equal(ll, r.loglik, sizeof ll);
        free(r.fisher);
        n++;
    }
    assert_int_equal(n, 24);
    printf("held-out performers: svm %u/24, knn %u/24, ml %u/24\n", hits[0], hits[1], hits[2]);
    assert_true(hits[0] >= 23); /* ≥ 95 % */
    assert_true(hits[1] >= 23);
    assert_true(hits[2] >= 23);

    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    static const double grid[] = AFFECT_CLASSIFIER_C_GRID;
    bool in_grid = false;
    for (size_t k = 0; k < sizeof grid / sizeof grid[0]; k++)
        in_grid = in_grid || rep.svm_c == grid[k];
    assert_true(in_grid);
    assert_true(rep.svm_cv_acc >= 0.9 && rep.svm_cv_acc <= 1.0);
    assert_true(isnan(rep.grid_cv_acc));
    assert_true(rep.train_acc_ml >= 0.95 && rep.train_acc_svm >= 0.95 && rep.train_acc_knn >= 0.9 &&
                rep.train_acc_knn <= 1.0);
    /* accuracies over 48 motions are multiples of 1/48 */
    assert_true(fabs(rep.train_acc_knn * 48 - round(rep.train_acc_knn * 48)) < 1e-9);

    /* views */
    assert_int_equal(affect_classifier_n_classes(c), 4);
    for (uint32_t k = 0; k < 4; k++)
        assert_string_equal(affect_classifier_label(c, k), EMOTIONS[k]);
    assert_null(affect_classifier_label(c, 4));
    assert_null(affect_classifier_hmm(c, 4));
    size_t part = 5 * 5 + 5 + 5 * 24 + 5 * 24 * 25 / 2;
    assert_int_equal(affect_classifier_part_dim(c), part);
    assert_int_equal(affect_classifier_dim(c), 4 * part);
    assert_int_equal(affect_classifier_n_train(c), 48);
    assert_int_equal(affect_spca_dims(affect_classifier_spca(c)), 3);
    assert_int_equal(affect_svm_dim(affect_classifier_svm(c)), 4 * part);
    assert_int_equal(affect_features_dim(affect_classifier_features(c)), 24);
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS];
    training_part(&fx->d, seqs, y);
    assert_memory_equal(affect_classifier_train_labels(c), y, 48 * sizeof *y);
}

/* The raw Fisher representation of s under the classifier's HMMs (infinities as ±DBL_MAX,
 * as affect/classifier.h's evaluation does). */
static void raw_fisher(const affect_classifier *c, const affect_hmm_seq *s, double *f)
{
    size_t part = affect_classifier_part_dim(c);
    unsigned groups = affect_classifier_get_config(c)->groups;
    affect_error err;
    for (uint32_t k = 0; k < affect_classifier_n_classes(c); k++) {
        double ll;
        if (affect_fisher_score(affect_classifier_hmm(c, k), s->x, s->n_frames, groups,
                                f + k * part, &ll, NULL, &err))
            fail_msg("fisher: %s", err.msg);
    }
    for (size_t e = 0; e < affect_classifier_dim(c); e++)
        if (isinf(f[e]))
            f[e] = f[e] > 0 ? DBL_MAX : -DBL_MAX;
}

static double clipped(double v, double limit)
{
    return limit > 0 && v > limit ? limit : limit > 0 && v < -limit ? -limit : v;
}

/* The normalization is the training motions' mean and population sd per dimension; the
 * evaluated vector is clip((raw − mean) / scale) exactly, bounded by score_clip, while the
 * unclipped z-scores of held-out motions go far beyond it. */
static void test_normalization_and_clipping(void **state)
{
    fixture *fx = *state;
    const affect_classifier *c = fx->c;
    size_t D = affect_classifier_dim(c);
    double clip = affect_classifier_get_config(c)->score_clip;
    assert_true(clip == 5.0);
    const double *mean = affect_classifier_norm_mean(c), *scale = affect_classifier_norm_scale(c);
    double *raw = malloc(48 * D * sizeof *raw);
    assert_non_null(raw);
    uint32_t n = 0;
    for (uint32_t i = 0; i < fx->d.n; i++)
        if (fx->d.seed[i] <= TRAIN_SEEDS)
            raw_fisher(c, &fx->d.seqs[i], raw + (size_t)n++ * D);
    assert_int_equal(n, 48);
    size_t constant = 0;
    for (size_t e = 0; e < D; e++) {
        double a = 0, mu = 0, var = 0;
        for (uint32_t i = 0; i < n; i++)
            a = fmax(a, fabs(raw[i * D + e]));
        if (a == 0) {
            assert_true(mean[e] == 0 && scale[e] == 1);
            constant++;
            continue;
        }
        for (uint32_t i = 0; i < n; i++)
            mu += raw[i * D + e] / a;
        mu /= n;
        for (uint32_t i = 0; i < n; i++)
            var += (raw[i * D + e] / a - mu) * (raw[i * D + e] / a - mu);
        double sd = sqrt(var / n);
        tu_assert_near(mean[e] / a, mu, 1e-12);
        if (sd == 0) {
            assert_true(scale[e] == 1.0);
            constant++;
        } else {
            tu_assert_near(scale[e] / (a * sd), 1.0, 1e-9);
        }
    }
    assert_true(constant < D / 2);
    free(raw);

    double *f = malloc(D * sizeof *f);
    assert_non_null(f);
    double max_z = 0;
    for (uint32_t i = 0; i < fx->d.n; i++) {
        if (fx->d.seed[i] <= TRAIN_SEEDS && i % 4 != 0)
            continue; /* the held-out motions and every 4th training one */
        eval_res r;
        eval_ok(c, &fx->d.seqs[i], &r);
        raw_fisher(c, &fx->d.seqs[i], f);
        for (size_t e = 0; e < D; e++) {
            double z = (f[e] - mean[e]) / scale[e];
            if (fabs(z) > max_z)
                max_z = fabs(z);
            double want = clipped(z, clip);
            if (memcmp(&want, &r.fisher[e], sizeof want) != 0)
                fail_msg("motion %u, entry %zu: %.17g, expected %.17g", i, e, r.fisher[e], want);
            assert_true(fabs(r.fisher[e]) <= clip);
        }
        free(r.fisher);
    }
    printf("largest unclipped |z|: %g\n", max_z);
    assert_true(max_z > 100 * clip); /* the limit matters */
    free(f);
}

/* Without z-scores the representation is the raw score, never clipped (training rows and
 * evaluated motions alike: the SVM's resubstitution accuracy is that of eval). */
static void test_no_normalization(void **state)
{
    fixture *fx = *state;
    affect_classifier_config cfg;
    small_config(&cfg, fx->small_d.feat);
    cfg.zscore = false;
    affect_classifier *c =
        train_ok(&cfg, fx->small_d.feat, fx->small_seqs, fx->small_y, fx->small_n, SMALL_LABELS, 2);
    size_t D = affect_classifier_dim(c);
    const double *mean = affect_classifier_norm_mean(c), *scale = affect_classifier_norm_scale(c);
    for (size_t e = 0; e < D; e++)
        assert_true(mean[e] == 0 && scale[e] == 1);
    double *f = malloc(D * sizeof *f);
    assert_non_null(f);
    double big = 0;
    uint32_t hits = 0;
    for (uint32_t i = 0; i < fx->small_n; i++) {
        eval_res r;
        eval_ok(c, &fx->small_seqs[i], &r);
        raw_fisher(c, &fx->small_seqs[i], f);
        assert_memory_equal(f, r.fisher, D * sizeof *f);
        for (size_t e = 0; e < D; e++)
            big = fmax(big, fabs(f[e]));
        hits += r.o.svm == fx->small_y[i];
        free(r.fisher);
    }
    assert_true(big > cfg.score_clip);
    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    tu_assert_near(rep.train_acc_svm, (double)hits / fx->small_n, 1e-15);
    free(f);
    affect_classifier_free(c);
}

/* ---- binary form ---- */

static void test_round_trip(void **state)
{
    fixture *fx = *state;
    affect_classifier *c2 = NULL;
    affect_error err;
    if (affect_classifier_decode(fx->blob, fx->size, &c2, &err))
        fail_msg("decode: %s", err.msg);
    const affect_classifier *c = fx->c;
    size_t D = affect_classifier_dim(c);
    assert_int_equal(affect_classifier_dim(c2), D);
    assert_int_equal(affect_classifier_n_train(c2), 48);
    for (uint32_t k = 0; k < 4; k++)
        assert_string_equal(affect_classifier_label(c2, k), EMOTIONS[k]);
    assert_memory_equal(affect_classifier_norm_mean(c2), affect_classifier_norm_mean(c),
                        D * sizeof(double));
    assert_memory_equal(affect_classifier_norm_scale(c2), affect_classifier_norm_scale(c),
                        D * sizeof(double));
    assert_memory_equal(affect_classifier_train_labels(c2), affect_classifier_train_labels(c),
                        48 * sizeof(uint32_t));
    assert_memory_equal(affect_classifier_train_embed(c2), affect_classifier_train_embed(c),
                        48 * 3 * sizeof(double));
    affect_classifier_report r1, r2;
    affect_classifier_get_report(c, &r1);
    affect_classifier_get_report(c2, &r2);
    assert_memory_equal(&r1, &r2, sizeof r1);
    const affect_classifier_config *g1 = affect_classifier_get_config(c),
                                   *g2 = affect_classifier_get_config(c2);
    assert_memory_equal(&g1->hmm, &g2->hmm, sizeof g1->hmm);
    assert_true(g1->groups == g2->groups && g1->zscore == g2->zscore &&
                g1->score_clip == g2->score_clip && g1->svm_c == g2->svm_c &&
                g1->svm_folds == g2->svm_folds && g1->spca_dims == g2->spca_dims &&
                g1->spca_kernel == g2->spca_kernel && g1->spca_sigma == g2->spca_sigma &&
                g1->knn_k == g2->knn_k && g1->grid.n_dims == g2->grid.n_dims &&
                g1->grid.folds == g2->grid.folds);

    for (uint32_t i = 0; i < fx->d.n; i += 5) {
        eval_res a, b;
        eval_ok(c, &fx->d.seqs[i], &a);
        eval_ok(c2, &fx->d.seqs[i], &b);
        assert_memory_equal(a.loglik, b.loglik, sizeof a.loglik);
        assert_memory_equal(a.decision, b.decision, sizeof a.decision);
        assert_memory_equal(a.embed, b.embed, sizeof a.embed);
        assert_memory_equal(a.votes, b.votes, sizeof a.votes);
        assert_memory_equal(a.fisher, b.fisher, D * sizeof(double));
        assert_true(a.o.svm == b.o.svm && a.o.knn == b.o.knn && a.o.ml == b.o.ml);
        free(a.fisher);
        free(b.fisher);
    }
    unsigned char *again;
    size_t size;
    encode_ok(c2, &again, &size);
    assert_int_equal(size, fx->size);
    assert_memory_equal(again, fx->blob, size);
    affect_free(again);
    affect_classifier_free(c2);
}

static void test_determinism(void **state)
{
    fixture *fx = *state;
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS];
    uint32_t n = training_part(&fx->d, seqs, y);
    affect_classifier_config cfg;
    main_config(&cfg, fx->d.feat);
    affect_classifier *c = train_ok(&cfg, fx->d.feat, seqs, y, n, EMOTIONS, N_EMOTIONS);
    unsigned char *blob;
    size_t size;
    encode_ok(c, &blob, &size);
    assert_int_equal(size, fx->size);
    assert_memory_equal(blob, fx->blob, size);
    affect_free(blob);
    affect_classifier_free(c);
}

/* Training with the blocks of Fisher scores in slabs (issue 14: one block of 4,032 × 95,333
 * doubles is more than SQLite allocates at once): with slabs of one row and bands of one
 * column the classifier is the one of a single array (the normalization to the bit; the Gram
 * matrix from dsyrk and dgemm per slab may round differently, so the rest within 1e-9). */
static void test_slabs(void **state)
{
    fixture *fx = *state;
    affect_classifier_config cfg;
    small_config(&cfg, fx->small_d.feat);
    cfg.slab_bytes = 1; /* a row per slab, a column per band */
    affect_classifier *c =
        train_ok(&cfg, fx->small_d.feat, fx->small_seqs, fx->small_y, fx->small_n, SMALL_LABELS, 2);
    const affect_classifier *one = fx->small;
    size_t D = affect_classifier_dim(c);
    assert_int_equal(D, affect_classifier_dim(one));
    assert_memory_equal(affect_classifier_norm_mean(c), affect_classifier_norm_mean(one),
                        D * sizeof(double));
    assert_memory_equal(affect_classifier_norm_scale(c), affect_classifier_norm_scale(one),
                        D * sizeof(double));
    uint32_t n = affect_classifier_n_train(c), p = affect_spca_dims(affect_classifier_spca(c));
    assert_int_equal(n, fx->small_n);
    for (size_t e = 0; e < (size_t)n * p; e++)
        tu_assert_near(affect_classifier_train_embed(c)[e], affect_classifier_train_embed(one)[e],
                       1e-9);
    for (uint32_t i = 0; i < fx->small_n; i++) {
        eval_res a, b;
        eval_ok(c, &fx->small_seqs[i], &a);
        eval_ok(one, &fx->small_seqs[i], &b);
        assert_memory_equal(a.fisher, b.fisher, D * sizeof(double));
        assert_int_equal(a.o.svm, b.o.svm);
        assert_int_equal(a.o.knn, b.o.knn);
        tu_assert_near(a.decision[0], b.decision[0], 1e-9 * (1 + fabs(b.decision[0])));
        tu_assert_near(a.embed[0], b.embed[0], 1e-9 * (1 + fabs(b.embed[0])));
        free(a.fisher);
        free(b.fisher);
    }
    affect_classifier_free(c);
}

/* Every byte flipped (three ways) is caught: the magic by its check, the rest by the
 * checksum. */
static void test_corrupted_bytes(void **state)
{
    fixture *fx = *state;
    size_t size = fx->small_size;
    printf("small classifier BLOB: %zu bytes\n", size);
    assert_true(size < 8000);
    unsigned char *b = malloc(size);
    assert_non_null(b);
    static const unsigned char flips[] = {0x01, 0x80, 0xff};
    for (size_t i = 0; i < size; i++)
        for (size_t f = 0; f < sizeof flips; f++) {
            memcpy(b, fx->small_blob, size);
            b[i] ^= flips[f];
            decode_fails(b, size, AFFECT_ERR_FORMAT, i < 4 ? MAGIC_MSG : CHECKSUM_MSG);
        }
    free(b);
}

/* Every truncation fails: under 24 bytes as too short for the header, else by the checksum;
 * and with the checksum recomputed over the shortened body, with a format error (never a
 * crash, never a read outside the bytes: valgrind). */
static void test_truncations(void **state)
{
    fixture *fx = *state;
    size_t size = fx->small_size;
    unsigned char *b = malloc(size);
    assert_non_null(b);
    char msg[128];
    for (size_t len = 0; len < size; len++) {
        memcpy(b, fx->small_blob, len); /* a copy of exactly len bytes: valgrind sees overreads */
        unsigned char *exact = malloc(len ? len : 1);
        assert_non_null(exact);
        memcpy(exact, b, len);
        if (len < 24) {
            snprintf(msg, sizeof msg, "truncated: %zu bytes is shorter than the classifier header",
                     len);
            decode_fails(exact, len, AFFECT_ERR_FORMAT, msg);
        } else {
            decode_fails(exact, len, AFFECT_ERR_FORMAT, CHECKSUM_MSG);
        }
        free(exact);
    }
    /* resealed: the body cut at every length, a valid checksum appended */
    size_t body = size - 8;
    for (size_t len = 16; len < body; len++) {
        unsigned char *cut = malloc(len + 8);
        assert_non_null(cut);
        memcpy(cut, fx->small_blob, len);
        reseal(cut, len + 8);
        decode_fails(cut, len + 8, AFFECT_ERR_FORMAT, NULL);
        free(cut);
    }
    /* a few exact messages: labels "angry", "sad" end at 16 + 9 + 7 = 32; the configuration
     * (no grid lists) is 119 bytes */
    static const struct {
        size_t len;
        const char *msg;
    } cuts[] = {
        {16, "truncated in the labels (offset 16)"},
        {18, "truncated in the labels (offset 16)"},
        {25, "truncated in the labels (offset 25)"},
        {32, "truncated in the configuration (offset 32)"},
        {150, "truncated in the configuration (offset 143)"},
        {151, "truncated in the class HMMs (offset 151)"},
        {158, "truncated in the class HMMs (offset 151)"},
        {163, "truncated in the class HMMs (offset 159)"},
    };
    for (size_t k = 0; k < sizeof cuts / sizeof cuts[0]; k++) {
        unsigned char *cut = malloc(cuts[k].len + 8);
        assert_non_null(cut);
        memcpy(cut, fx->small_blob, cuts[k].len);
        reseal(cut, cuts[k].len + 8);
        decode_fails(cut, cuts[k].len + 8, AFFECT_ERR_FORMAT, cuts[k].msg);
        free(cut);
    }
    free(b);
}

/* Header fields and the configuration, each with a valid checksum. */
static void test_bad_fields(void **state)
{
    fixture *fx = *state;
    size_t size = fx->small_size;
    unsigned char *b = malloc(size + 1);
    assert_non_null(b);
    /* the layout: labels at 16 ("angry" 16..24, "sad" 25..31), configuration from 32:
     * groups 32, zscore 36, score_clip 37, svm_c 45, svm_folds 53, spca_dims 57, kernel 61,
     * sigma 62, knn_k 70, descriptors 74, descriptor_weight 78, mirror 86, grid counts
     * 87 .. 102 */
    static const struct {
        size_t off;
        unsigned char value;
        const char *msg;
    } cases[] = {
        {0, 'X', MAGIC_MSG},
        {4, 4, "unknown format version 4 (this build reads 1 .. 3)"},
        {4, 0, "unknown format version 0 (this build reads 1 .. 3)"},
        {8, 1, "unknown classifier flags 1 (offset 8)"},
        {12, 1, "invalid class count 1 (offset 12)"},
        {12, 65, "invalid class count 65 (offset 12)"},
        {16, 0, "invalid label (offset 20)"},                     /* label length 0 */
        {21, 0, "invalid label (offset 25)"},                     /* a NUL inside "angry" */
        {36, 2, "invalid configuration (offset 151)"},            /* zscore 2 */
        {61, 7, "invalid configuration (offset 151)"},            /* kernel 7 */
        {86, 2, "invalid configuration (offset 151)"},            /* mirror 2 */
        {87, 200, "truncated in the configuration (offset 103)"}, /* 200 grid dims > 128 */
        {74, 4,
         "invalid configuration: descriptors must be a combination of kinematics and "
         "laban"},
        {85, 0xff, "invalid configuration: descriptor_weight must be a positive finite number"},
        {70, 0, "invalid configuration: knn_k must be at least 1"},
        {53, 1, "invalid configuration: svm_folds must be at least 2"},
        {32, 0,
         "invalid configuration: "
         "groups must be a non-empty combination of start, "
         "transitions, weights, means, covariances"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        memcpy(b, fx->small_blob, size);
        if (cases[k].off == 70 || cases[k].off == 53 || cases[k].off == 32)
            memset(b + cases[k].off, 0, 4); /* a whole u32 field */
        b[cases[k].off] = cases[k].value;
        if (cases[k].off == 16)
            memset(b + 16, 0, 4);
        reseal(b, size);
        decode_fails(b, size, AFFECT_ERR_FORMAT, cases[k].msg);
    }
    /* one byte more before the checksum */
    memcpy(b, fx->small_blob, size - 8);
    b[size - 8] = 0;
    reseal(b, size + 1);
    char msg[128];
    snprintf(msg, sizeof msg, "1 unexpected bytes after the training set (offset %zu)", size - 8);
    decode_fails(b, size + 1, AFFECT_ERR_FORMAT, msg);
    /* the magic is checked before the checksum, the length before both */
    memcpy(b, fx->small_blob, size);
    memcpy(b, "AFHM", 4);
    decode_fails(b, size, AFFECT_ERR_FORMAT, MAGIC_MSG);
    decode_fails(fx->small_blob, 23, AFFECT_ERR_FORMAT,
                 "truncated: 23 bytes is shorter than the classifier header");
    decode_fails(fx->blob, 0, AFFECT_ERR_FORMAT,
                 "truncated: 0 bytes is shorter than the classifier header");
    free(b);
}

/* ---- configuration and argument errors ---- */

static void check_msg(const affect_classifier_config *cfg, const char *msg)
{
    const char *got = affect_classifier_config_check(cfg);
    if (!msg) {
        if (got)
            fail_msg("unexpected \"%s\"", got);
        return;
    }
    if (!got)
        fail_msg("no message, expected \"%s\"", msg);
    assert_string_equal(got, msg);
}

static void test_config_check(void **state)
{
    (void)state;
    affect_classifier_config def, c;
    affect_classifier_config_default(&def);
    /* the defaults of the header */
    assert_true(def.groups == AFFECT_FISHER_ALL && def.zscore && def.score_clip == 5.0 &&
                def.svm_c == 0.0 && def.svm_folds == 5 && def.spca_dims == 3 &&
                def.spca_kernel == AFFECT_SPCA_RBF && def.spca_sigma == 0.25 && def.knn_k == 5 &&
                def.grid.folds == 5 && def.grid.n_dims == 0 && def.grid.n_sigma == 0 &&
                def.grid.n_k == 0);
    /* the measured best, not the thesis's */
    assert_true(def.hmm.n_states == 5 && def.hmm.n_mix == 1 && def.hmm.cov == AFFECT_HMM_DIAG &&
                def.hmm.max_iter == 20 && def.descriptors == AFFECT_DESC_KINEMATICS &&
                def.descriptor_weight == 0.1 && def.mirror == AFFECT_MIRROR_AUTO);
    affect_features_options fo;
    affect_classifier_features_default(&fo);
    assert_true(fo.frame == AFFECT_FEATURES_FRAME_BODY && !fo.velocity && !fo.root);
    check_msg(&def, "observation dimension must be between 1 and 4096"); /* dim unset */
    def.hmm.dim = 24;
    check_msg(&def, NULL);
#define CASE(stmt, msg)                                                                            \
    do {                                                                                           \
        c = def;                                                                                   \
        stmt;                                                                                      \
        check_msg(&c, msg);                                                                        \
    } while (0)
    CASE(c.groups = 0, GROUPS_MSG);
    CASE(c.groups = 32, GROUPS_MSG);
    CASE(c.groups = AFFECT_FISHER_MEANS, NULL);
    const char *svm_c = "svm_c must be a positive finite number, or 0 to choose it by "
                        "cross-validation";
    CASE(c.svm_c = -1, svm_c);
    CASE(c.svm_c = NAN, svm_c);
    CASE(c.svm_c = INFINITY, svm_c);
    CASE(c.svm_c = 0.5, NULL);
    const char *clip = "score_clip must be a finite number, 0 or more (0: no limit)";
    CASE(c.score_clip = -0.1, clip);
    CASE(c.score_clip = NAN, clip);
    CASE(c.score_clip = INFINITY, clip);
    CASE(c.score_clip = 0, NULL);
    CASE(c.svm_folds = 1, "svm_folds must be at least 2");
    CASE(c.spca_dims = 0, "spca_dims must be at least 1");
    CASE(c.spca_kernel = (affect_spca_kernel)7, "spca_kernel must be linear or rbf");
    CASE(c.spca_kernel = AFFECT_SPCA_LINEAR, NULL);
    const char *sigma = "spca_sigma must be a positive finite number";
    CASE(c.spca_sigma = 0, sigma);
    CASE(c.spca_sigma = NAN, sigma);
    CASE(c.spca_sigma = INFINITY, sigma);
    CASE(c.knn_k = 0, "knn_k must be at least 1");
    const char *lists = "grid lists must have at most 128 values";
    CASE(c.grid.n_dims = 129, lists);
    CASE(c.grid.n_sigma = 129, lists);
    CASE(c.grid.n_k = 129, lists);
    CASE(c.grid.folds = 1, "grid folds must be at least 2");
    CASE((c.grid.n_dims = 2, c.grid.dims[0] = 1, c.grid.dims[1] = 0),
         "grid spca_dims must be whole numbers of at least 1");
    CASE((c.grid.n_sigma = 1, c.grid.sigma[0] = -1),
         "grid spca_sigma must be positive finite numbers");
    CASE((c.grid.n_sigma = 1, c.grid.sigma[0] = NAN),
         "grid spca_sigma must be positive finite numbers");
    CASE((c.grid.n_k = 1, c.grid.k[0] = 0), "grid knn_k must be whole numbers of at least 1");
    c = def;
    c.grid.n_dims = c.grid.n_sigma = c.grid.n_k = 128;
    for (uint32_t i = 0; i < 128; i++) {
        c.grid.dims[i] = c.grid.k[i] = i + 1;
        c.grid.sigma[i] = 0.25 * (i + 1);
    }
    check_msg(&c, NULL);
    CASE(c.hmm.n_states = 0, "states must be between 1 and 256");
    CASE(c.hmm.n_mix = 65, "mixtures must be between 1 and 64");
#undef CASE
}

static void train_fails(const affect_classifier_config *cfg, const affect_features *f,
                        const affect_hmm_seq *seqs, const uint32_t *y, uint32_t n,
                        const char *const *labels, uint32_t n_classes, const char *msg)
{
    affect_classifier *c = (affect_classifier *)seqs; /* must become NULL */
    affect_error err;
    affect_status st =
        affect_classifier_train(cfg, f, seqs, NULL, y, n, labels, n_classes, &c, &err);
    if (st == AFFECT_OK)
        fail_msg("training succeeded, expected \"%s\"", msg);
    assert_int_equal(st, AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, msg);
    assert_null(c);
}

static void test_train_errors(void **state)
{
    fixture *fx = *state;
    const affect_features *f = fx->small_d.feat;
    affect_classifier_config cfg;
    small_config(&cfg, f);
    const affect_hmm_seq *s = fx->small_seqs;
    uint32_t n = fx->small_n;
    static const char *const three[] = {"angry", "sad", "x"};
    train_fails(&cfg, f, s, fx->small_y, n, three, 3, "class \"x\" has no training motion");
    static const char *const x_first[] = {"x", "angry", "sad"};
    uint32_t shifted[8];
    for (uint32_t i = 0; i < n; i++)
        shifted[i] = fx->small_y[i] + 1;
    train_fails(&cfg, f, s, shifted, n, x_first, 3, "class \"x\" has no training motion");
    train_fails(&cfg, f, s, fx->small_y, n, SMALL_LABELS, 1, "need 2 to 64 classes, got 1");
    train_fails(&cfg, f, s, fx->small_y, n, SMALL_LABELS, 65, "need 2 to 64 classes, got 65");
    train_fails(&cfg, f, s, shifted, n, SMALL_LABELS, 2, "motion 0: class 2 of 2 classes");
    affect_classifier_config bad = cfg;
    bad.hmm.dim = 24;
    train_fails(&bad, f, s, fx->small_y, n, SMALL_LABELS, 2,
                "the HMM dimension 24 is not the feature dimension 3");
    bad = cfg;
    bad.knn_k = 0;
    train_fails(&bad, f, s, fx->small_y, n, SMALL_LABELS, 2, "knn_k must be at least 1");
    bad = cfg;
    bad.hmm.n_states = 40; /* sequences of 30 frames */
    affect_classifier *c = NULL;
    affect_error err;
    assert_int_equal(
        affect_classifier_train(&bad, f, s, NULL, fx->small_y, n, SMALL_LABELS, 2, &c, &err),
        AFFECT_ERR_INVALID);
    assert_null(c);
    const char *prefix = "training the HMM of class \"angry\": ";
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("unexpected \"%s\"", err.msg);
}

/* ---- appended descriptors ---- */

/* Descriptors that carry the class decide when the sequences cannot: every motion gets the
 * same observations, class 0 descriptors near (1, 0), class 1 near (0, 1). Without them the
 * SVM cannot be right on both classes; with them it is, and the block's factor ω keeps two
 * descriptors audible next to the Fisher block. The configuration survives the binary form,
 * and evaluation asks for the descriptors. */
static void test_descriptors(void **state)
{
    fixture *fx = *state;
    const affect_features *f = fx->small_d.feat;
    uint32_t n = fx->small_n;
    affect_hmm_seq same[8];
    double desc[8 * AFFECT_SUMMARY_N];
    uint32_t dd = affect_descriptors_dim(AFFECT_DESC_KINEMATICS);
    assert_int_equal(dd, AFFECT_SUMMARY_N);
    assert_int_equal(affect_descriptors_dim(AFFECT_DESC_ALL), AFFECT_SUMMARY_N + AFFECT_LABAN_N);
    assert_int_equal(affect_descriptors_dim(4), 0);
    for (uint32_t i = 0; i < n; i++) {
        same[i] = fx->small_seqs[0];
        for (uint32_t e = 0; e < dd; e++)
            desc[i * dd + e] = (e == fx->small_y[i] ? 1.0 : 0.0) + 0.01 * i + 0.001 * e;
    }
    affect_classifier_config cfg;
    small_config(&cfg, f);
    cfg.descriptors = AFFECT_DESC_KINEMATICS;
    cfg.descriptor_weight = 0.5;
    affect_classifier *c = NULL;
    affect_error err;
    assert_int_equal(
        affect_classifier_train(&cfg, f, same, NULL, fx->small_y, n, SMALL_LABELS, 2, &c, &err),
        AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the configuration appends descriptors but none were given");
    desc[3] = NAN;
    assert_int_equal(
        affect_classifier_train(&cfg, f, same, desc, fx->small_y, n, SMALL_LABELS, 2, &c, &err),
        AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "motion 0: descriptor 3 is not finite");
    desc[3] = 0.003;
    assert_int_equal(
        affect_classifier_train(&cfg, f, same, desc, fx->small_y, n, SMALL_LABELS, 2, &c, &err),
        AFFECT_OK);
    assert_int_equal(affect_classifier_dim(c), 2 * affect_classifier_part_dim(c) + dd);
    unsigned char *blob;
    size_t size;
    assert_int_equal(affect_classifier_encode(c, &blob, &size, &err), AFFECT_OK);
    affect_classifier *d = NULL;
    assert_int_equal(affect_classifier_decode(blob, size, &d, &err), AFFECT_OK);
    assert_int_equal(affect_classifier_get_config(d)->descriptors, AFFECT_DESC_KINEMATICS);
    assert_true(affect_classifier_get_config(d)->descriptor_weight == 0.5);
    for (uint32_t i = 0; i < n; i++) {
        affect_classifier_out o = {0};
        assert_int_equal(affect_classifier_eval(d, same[i].x, same[i].n_frames, desc + i * dd,
                                                false, &o, NULL, &err),
                         AFFECT_OK);
        assert_int_equal(o.svm, fx->small_y[i]);
    }
    affect_classifier_out o = {0};
    assert_int_equal(
        affect_classifier_eval(d, same[0].x, same[0].n_frames, NULL, false, &o, NULL, &err),
        AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the classifier appends descriptors but none were given");
    free(blob);
    affect_classifier_free(c);
    affect_classifier_free(d);
    /* mirror images need a partner for every observed joint: the right hand alone has none */
    small_config(&cfg, f);
    cfg.mirror = AFFECT_MIRROR_ON;
    assert_int_equal(affect_classifier_train(&cfg, f, fx->small_seqs, NULL, fx->small_y, n,
                                             SMALL_LABELS, 2, &c, &err),
                     AFFECT_ERR_INVALID);
    assert_non_null(strstr(err.msg, "has no mirror partner"));
    /* without descriptors the identical sequences carry no label information */
    small_config(&cfg, f);
    assert_int_equal(
        affect_classifier_train(&cfg, f, same, NULL, fx->small_y, n, SMALL_LABELS, 2, &c, &err),
        AFFECT_ERR_INVALID);
    assert_non_null(strstr(err.msg, "no label information"));
}

/* tests/fixtures/classifier-v1.bin: the SQL spec's small classifier (angry and sad waves, the
 * right hand, 2 states, frames 30 .. 49 of motion_synth seeds 1 .. 3) written by version 1
 * (commit bd15fd4). Today's decoder reads it as a classifier without descriptors or mirror
 * images, and its re-encoding (version 2) predicts the same. */
static void test_fixture_v1(void **state)
{
    fixture *fx = *state;
    size_t len;
    unsigned char *data =
        (unsigned char *)tu_read_file(AFFECT_FIXTURES_DIR "/classifier-v1.bin", &len);
    assert_non_null(data);
    assert_memory_equal(data, "AFCL\x01\0\0\0", 8);
    affect_classifier *c = NULL, *d = NULL;
    affect_error err;
    assert_int_equal(affect_classifier_decode(data, len, &c, &err), AFFECT_OK);
    const affect_classifier_config *cfg = affect_classifier_get_config(c);
    assert_int_equal(cfg->descriptors, 0);
    assert_true(cfg->descriptor_weight == 1.0 && cfg->mirror == AFFECT_MIRROR_OFF);
    assert_int_equal(affect_classifier_n_classes(c), 2);
    assert_string_equal(affect_classifier_label(c, 0), "angry");
    assert_int_equal(affect_classifier_features(c)->frame, AFFECT_FEATURES_FRAME_FIRST);
    unsigned char *blob;
    size_t size;
    assert_int_equal(affect_classifier_encode(c, &blob, &size, &err), AFFECT_OK);
    assert_int_equal(blob[4], 2);
    assert_int_equal(affect_classifier_decode(blob, size, &d, &err), AFFECT_OK);
    for (uint32_t i = 0; i < fx->small_n; i++) {
        affect_classifier_out a = {0}, b = {0};
        double da[1], db[1];
        a.decision = da;
        b.decision = db;
        const affect_hmm_seq *q = &fx->small_seqs[i];
        assert_int_equal(affect_classifier_eval(c, q->x, q->n_frames, NULL, false, &a, NULL, &err),
                         AFFECT_OK);
        assert_int_equal(affect_classifier_eval(d, q->x, q->n_frames, NULL, false, &b, NULL, &err),
                         AFFECT_OK);
        assert_true(a.svm == b.svm && a.knn == b.knn && a.ml == b.ml && da[0] == db[0]);
    }
    free(blob);
    free(data);
    affect_classifier_free(c);
    affect_classifier_free(d);
}

/* A fixture's bytes (of the expected length and version byte) and its decoded classifier. */
static affect_classifier *decode_fixture(const char *path, size_t expect_len, unsigned char version,
                                         unsigned char **data, size_t *len)
{
    *data = (unsigned char *)tu_read_file(path, len);
    assert_non_null(*data);
    assert_int_equal(*len, expect_len);
    assert_memory_equal(*data, "AFCL", 4);
    assert_int_equal((*data)[4], version);
    affect_classifier *c = NULL;
    affect_error err;
    if (affect_classifier_decode(*data, *len, &c, &err))
        fail_msg("decode %s: %s", path, err.msg);
    return c;
}

/* Today's encoder writes exactly data's len bytes for c. */
static void assert_reencodes(const affect_classifier *c, const unsigned char *data, size_t len)
{
    unsigned char *blob;
    size_t size;
    encode_ok(c, &blob, &size);
    assert_int_equal(size, len);
    assert_memory_equal(blob, data, len);
    affect_free(blob);
}

/* tests/fixtures/classifier-v2.bin: the same small classifier written by version 2 (commit
 * 59e045b: float32 SVM weights, SVM record version 2, and float32 sPCA axes, record flag 1).
 * Today's decoder reads it and evaluates the test's small set with it (finite decision values,
 * labels in range), and today's encoder writes its bytes again (a model this small keeps the
 * float32 storage). */
static void test_fixture_v2(void **state)
{
    fixture *fx = *state;
    size_t len;
    unsigned char *data;
    affect_classifier *c =
        decode_fixture(AFFECT_FIXTURES_DIR "/classifier-v2.bin", 2418, 2, &data, &len);
    affect_error err;
    const affect_classifier_config *cfg = affect_classifier_get_config(c);
    assert_int_equal(cfg->descriptors, 0);
    assert_true(cfg->mirror == AFFECT_MIRROR_OFF);
    assert_int_equal(affect_classifier_n_classes(c), 2);
    assert_string_equal(affect_classifier_label(c, 1), "sad");
    assert_int_equal(affect_classifier_n_train(c), 6);
    for (uint32_t i = 0; i < fx->small_n; i++) {
        affect_classifier_out a = {0};
        double da[1];
        a.decision = da;
        const affect_hmm_seq *q = &fx->small_seqs[i];
        assert_int_equal(affect_classifier_eval(c, q->x, q->n_frames, NULL, false, &a, NULL, &err),
                         AFFECT_OK);
        assert_true(isfinite(da[0]));
        assert_true(a.svm < 2 && a.knn < 2 && a.ml < 2);
    }
    assert_reencodes(c, data, len);
    free(data);
    affect_classifier_free(c);
}

/* ---- the compact storage (version 3) ---- */

/* How far the compact storage may move a decision value on this test problem, relative to the
 * largest magnitude among the float32 model's decision values (measured: 1.9 %; docs/FORMATS.md
 * gives the thesis configuration's). */
#define COMPACT_DECISION_TOL 0.05
/* The same for the sPCA coordinates (measured: 0.6 %). */
#define COMPACT_EMBED_TOL 0.05
/* The same for the 64 dimensions of the small classifier (classifier-v3.bin; measured: 12.5 %:
 * one block of 64 values, whose rounding errors do not average out — why "auto" keeps the
 * float32 storage below AFFECT_CLASSIFIER_COMPACT_DIM dimensions). */
#define COMPACT_TINY_DECISION_TOL 0.25

static uint64_t le64_at(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 0; i < 8; i++)
        v |= (uint64_t)p[i] << (8 * i);
    return v;
}

/* Offsets in a version-3 BLOB of the 4-emotion classifier (no grid lists): the first class
 * HMM's form byte, the dimension field, the SVM record. */
static void v3_offsets(const unsigned char *b, size_t *hmm0, size_t *dim_at, size_t *svm_at)
{
    size_t o = 16;
    for (int k = 0; k < N_EMOTIONS; k++)
        o += 4 + ((size_t)b[o] | (size_t)b[o + 1] << 8);
    o += 119; /* the configuration */
    *hmm0 = o;
    for (int k = 0; k < N_EMOTIONS; k++)
        o += 9 + (size_t)le64_at(b + o + 1);
    *dim_at = o;
    *svm_at = o + 8 + 6 * (size_t)le64_at(b + o);
}

/* The 4-emotion classifier trained with "storage": "compact" next to the same training with the
 * default (auto: float32 at this D): a version-3 BLOB, smaller; the mean and scale are the
 * float32 model's rounded to 24-bit floats; every held-out and training motion gets the same
 * SVM, kNN and ML labels, decision values and coordinates within the named tolerances; the
 * compact model decodes to itself to the bit (every output of eval) and re-encodes to the same
 * bytes; a second training gives the same bytes; corruptions of its new fields are refused with
 * their messages. */
static void test_compact(void **state)
{
    fixture *fx = *state;
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS];
    uint32_t n = training_part(&fx->d, seqs, y);
    affect_classifier_config cfg;
    main_config(&cfg, fx->d.feat);
    cfg.storage = AFFECT_STORAGE_COMPACT;
    affect_classifier *q = train_ok(&cfg, fx->d.feat, seqs, y, n, EMOTIONS, N_EMOTIONS);
    const affect_classifier *f = fx->c;
    assert_int_equal(affect_classifier_get_config(f)->storage, AFFECT_STORAGE_FLOAT32);
    assert_int_equal(affect_classifier_get_config(q)->storage, AFFECT_STORAGE_COMPACT);
    size_t D = affect_classifier_dim(q);
    assert_true(D < AFFECT_CLASSIFIER_COMPACT_DIM); /* auto chose float32 for fx->c */
    for (size_t e = 0; e < D; e++) {
        assert_true(affect_classifier_norm_mean(q)[e] ==
                    affect_f24_round(affect_classifier_norm_mean(f)[e]));
        assert_true(affect_classifier_norm_scale(q)[e] ==
                    affect_f24_round(affect_classifier_norm_scale(f)[e]));
    }
    unsigned char *blob, *again;
    size_t size, size2;
    encode_ok(q, &blob, &size);
    assert_memory_equal(blob, "AFCL\x03\0\0\0", 8);
    printf("compact BLOB: %zu bytes, float32: %zu bytes\n", size, fx->size);
    assert_true(size < fx->size);
    affect_classifier *d = NULL;
    affect_error err;
    if (affect_classifier_decode(blob, size, &d, &err))
        fail_msg("decode: %s", err.msg);
    assert_int_equal(affect_classifier_get_config(d)->storage, AFFECT_STORAGE_COMPACT);
    double max_dec = 0, max_ddec = 0, max_emb = 0, max_demb = 0;
    for (uint32_t i = 0; i < fx->d.n; i++) {
        eval_res a, b, c;
        eval_ok(f, &fx->d.seqs[i], &a);
        eval_ok(q, &fx->d.seqs[i], &b);
        eval_ok(d, &fx->d.seqs[i], &c);
        /* the decoded model is the trained one */
        assert_memory_equal(b.decision, c.decision, sizeof b.decision);
        assert_memory_equal(b.embed, c.embed, sizeof b.embed);
        assert_memory_equal(b.loglik, c.loglik, sizeof b.loglik);
        assert_memory_equal(b.votes, c.votes, sizeof b.votes);
        assert_memory_equal(b.fisher, c.fisher, D * sizeof(double));
        /* the same decisions as the float32 model */
        assert_int_equal(a.o.svm, b.o.svm);
        assert_int_equal(a.o.knn, b.o.knn);
        assert_int_equal(a.o.ml, b.o.ml);
        assert_memory_equal(a.loglik, b.loglik, sizeof a.loglik);
        for (size_t p = 0; p < N_EMOTIONS * (N_EMOTIONS - 1) / 2; p++) {
            max_dec = fmax(max_dec, fabs(a.decision[p]));
            max_ddec = fmax(max_ddec, fabs(a.decision[p] - b.decision[p]));
        }
        for (size_t p = 0; p < 3; p++) {
            max_emb = fmax(max_emb, fabs(a.embed[p]));
            max_demb = fmax(max_demb, fabs(a.embed[p] - b.embed[p]));
        }
        free(a.fisher);
        free(b.fisher);
        free(c.fisher);
    }
    printf("compact storage: decision values move by %.3g of the largest (%.3g), coordinates by "
           "%.3g (%.3g)\n",
           max_ddec / max_dec, max_dec, max_demb / max_emb, max_emb);
    assert_true(max_ddec <= COMPACT_DECISION_TOL * max_dec);
    assert_true(max_demb <= COMPACT_EMBED_TOL * max_emb);
    encode_ok(d, &again, &size2);
    assert_int_equal(size2, size);
    assert_memory_equal(again, blob, size);
    affect_free(again);
    affect_classifier *q2 = train_ok(&cfg, fx->d.feat, seqs, y, n, EMOTIONS, N_EMOTIONS);
    encode_ok(q2, &again, &size2);
    assert_int_equal(size2, size);
    assert_memory_equal(again, blob, size);
    affect_free(again);
    affect_classifier_free(q2);

    /* corruptions, each resealed */
    size_t hmm0, dim_at, svm_at;
    v3_offsets(blob, &hmm0, &dim_at, &svm_at);
    assert_int_equal(blob[hmm0], 1); /* full covariances: triangles */
    assert_int_equal(le64_at(blob + dim_at), D);
    assert_int_equal(blob[svm_at], 3);
    unsigned char *b = malloc(size);
    assert_non_null(b);
    char msg[160];
    memcpy(b, blob, size);
    b[hmm0] = 2;
    reseal(b, size);
    snprintf(msg, sizeof msg, "invalid form 2 of the HMM of class \"neutral\" (offset %zu)", hmm0);
    decode_fails(b, size, AFFECT_ERR_FORMAT, msg);
    memcpy(b, blob, size);
    b[hmm0] = 0; /* the triangles read as a whole model BLOB */
    reseal(b, size);
    decode_fails(b, size, AFFECT_ERR_FORMAT, NULL);
    memcpy(b, blob, size);
    b[hmm0 + 9 + 20] = 1; /* the model says diagonal: no triangles */
    reseal(b, size);
    decode_fails(b, size, AFFECT_ERR_FORMAT,
                 "the HMM of class \"neutral\": not a model BLOB with full covariances in "
                 "triangles");
    memcpy(b, blob, size);
    b[dim_at + 8 + 3 * D + 2] = 0x80; /* the first scale: −0 */
    b[dim_at + 8 + 3 * D + 1] = 0;
    b[dim_at + 8 + 3 * D] = 0;
    reseal(b, size);
    snprintf(msg, sizeof msg, "invalid normalization (offset %zu)", svm_at);
    decode_fails(b, size, AFFECT_ERR_FORMAT, msg);
    memcpy(b, blob, size);
    b[dim_at + 8 + 2] = 0x7f; /* the first mean: an exponent of all ones (inf or NaN) */
    b[dim_at + 8 + 1] |= 0xf0;
    reseal(b, size);
    decode_fails(b, size, AFFECT_ERR_FORMAT, msg);
    /* the SVM's first weight vector: its first scale negative, its first code −8 */
    uint32_t l = affect_svm_total_sv(affect_classifier_svm(q));
    size_t w0 = svm_at + 1 + 4 + 8 + 8 + 4 + 4 + 16 + 4 + 16 + 4 + 4 * (size_t)l + 4 +
                8 * 3 * (size_t)l + 4 + 8 * 6 + 4;
    size_t codes0 = w0 + 4 * ((D + 63) / 64);
    memcpy(b, blob, size);
    b[w0 + 3] ^= 0x80;
    reseal(b, size);
    snprintf(msg, sizeof msg, "SVM: weight vector 0 is not a canonical 4-bit form (offset %zu)",
             w0);
    decode_fails(b, size, AFFECT_ERR_FORMAT, msg);
    memcpy(b, blob, size);
    b[codes0] = (unsigned char)((b[codes0] & 0xf0) | 0x08);
    reseal(b, size);
    snprintf(msg, sizeof msg, "SVM: weight vector 0 is not a canonical 4-bit form (offset %zu)",
             codes0);
    decode_fails(b, size, AFFECT_ERR_FORMAT, msg);
    free(b);
    affect_free(blob);
    affect_classifier_free(d);
    affect_classifier_free(q);
}

/* tests/fixtures/classifier-v3.bin: the small classifier of classifier-v2.bin trained with
 * "storage": "compact" (version 3, commit 71d367f). Today's decoder reads it as the compact
 * storage; it gives the SVM, kNN and ML labels of classifier-v2.bin on the test's small set
 * (decision values within COMPACT_TINY_DECISION_TOL), and today's encoder writes its bytes
 * again. */
static void test_fixture_v3(void **state)
{
    fixture *fx = *state;
    size_t len, len2;
    unsigned char *data, *v2;
    affect_classifier *c =
        decode_fixture(AFFECT_FIXTURES_DIR "/classifier-v3.bin", 1500, 3, &data, &len);
    affect_classifier *f =
        decode_fixture(AFFECT_FIXTURES_DIR "/classifier-v2.bin", 2418, 2, &v2, &len2);
    affect_error err;
    assert_int_equal(affect_classifier_get_config(c)->storage, AFFECT_STORAGE_COMPACT);
    assert_int_equal(affect_classifier_get_config(f)->storage, AFFECT_STORAGE_FLOAT32);
    double max_dec = 0, max_ddec = 0;
    for (uint32_t i = 0; i < fx->small_n; i++) {
        affect_classifier_out a = {0}, b = {0};
        double da[1], db[1];
        a.decision = da;
        b.decision = db;
        const affect_hmm_seq *q = &fx->small_seqs[i];
        assert_int_equal(affect_classifier_eval(c, q->x, q->n_frames, NULL, false, &a, NULL, &err),
                         AFFECT_OK);
        assert_int_equal(affect_classifier_eval(f, q->x, q->n_frames, NULL, false, &b, NULL, &err),
                         AFFECT_OK);
        assert_true(a.svm == b.svm && a.knn == b.knn && a.ml == b.ml);
        max_dec = fmax(max_dec, fabs(db[0]));
        max_ddec = fmax(max_ddec, fabs(da[0] - db[0]));
    }
    printf("classifier-v3.bin: decision values move by %.3g of the largest (%.3g)\n",
           max_ddec / max_dec, max_dec);
    assert_true(max_ddec <= COMPACT_TINY_DECISION_TOL * max_dec);
    assert_reencodes(c, data, len);
    free(data);
    free(v2);
    affect_classifier_free(c);
    affect_classifier_free(f);
}

/* ---- grid search ---- */

static bool in_u32(uint32_t v, const uint32_t *list, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++)
        if (list[i] == v)
            return true;
    return false;
}

static void test_grid(void **state)
{
    fixture *fx = *state;
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS];
    uint32_t n = training_part(&fx->d, seqs, y);
    affect_classifier_config cfg;
    main_config(&cfg, fx->d.feat);
    cfg.svm_c = 1.0; /* no inner search for C: the grid alone */
    cfg.hmm.max_iter = 4;
    cfg.grid.n_dims = 2;
    cfg.grid.dims[0] = 1;
    cfg.grid.dims[1] = 2;
    cfg.grid.n_sigma = 2;
    cfg.grid.sigma[0] = 0.5;
    cfg.grid.sigma[1] = 2.0;
    /* k = 47 votes with (nearly) the whole inner training set: about chance; k = 1 is far
     * better, so the search must not keep the first combination */
    cfg.grid.n_k = 2;
    cfg.grid.k[0] = 47;
    cfg.grid.k[1] = 1;
    cfg.grid.folds = 4;
    affect_classifier *c = train_ok(&cfg, fx->d.feat, seqs, y, n, EMOTIONS, N_EMOTIONS);
    const affect_classifier_config *got = affect_classifier_get_config(c);
    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    printf("grid: dims %u, sigma %g, k %u, inner accuracy %g\n", got->spca_dims, got->spca_sigma,
           got->knn_k, rep.grid_cv_acc);
    assert_true(in_u32(got->spca_dims, cfg.grid.dims, 2));
    assert_true(got->spca_sigma == 0.5 || got->spca_sigma == 2.0);
    assert_int_equal(got->knn_k, 1);
    assert_int_equal(affect_spca_dims(affect_classifier_spca(c)), got->spca_dims);
    assert_true(affect_spca_sigma(affect_classifier_spca(c)) == got->spca_sigma);
    assert_true(rep.grid_cv_acc >= 0.9 && rep.grid_cv_acc <= 1.0);
    assert_true(fabs(rep.grid_cv_acc * n - round(rep.grid_cv_acc * n)) < 1e-9);
    assert_true(isnan(rep.svm_cv_acc) && rep.svm_c == 1.0);
    /* the chosen values and the lists survive the round trip */
    unsigned char *blob;
    size_t size;
    encode_ok(c, &blob, &size);
    affect_classifier *c2 = NULL;
    affect_error err;
    assert_int_equal(affect_classifier_decode(blob, size, &c2, &err), AFFECT_OK);
    const affect_classifier_config *g2 = affect_classifier_get_config(c2);
    assert_true(g2->knn_k == 1 && g2->spca_dims == got->spca_dims &&
                g2->spca_sigma == got->spca_sigma && g2->grid.n_k == 2 && g2->grid.k[0] == 47 &&
                g2->grid.sigma[1] == 2.0 && g2->grid.folds == 4);
    affect_classifier_report rep2;
    affect_classifier_get_report(c2, &rep2);
    assert_true(rep2.grid_cv_acc == rep.grid_cv_acc);
    affect_classifier_free(c2);
    affect_free(blob);
    affect_classifier_free(c);

    /* a grid of one value per list is the plain configuration with those values */
    affect_classifier_config one;
    small_config(&one, fx->small_d.feat);
    one.grid.n_dims = 1;
    one.grid.dims[0] = 1;
    one.grid.n_sigma = 1;
    one.grid.sigma[0] = 1.5;
    one.grid.n_k = 1;
    one.grid.k[0] = 3;
    one.grid.folds = 2;
    affect_classifier_config plain;
    small_config(&plain, fx->small_d.feat);
    plain.spca_sigma = 1.5;
    plain.knn_k = 3;
    affect_classifier *a =
        train_ok(&one, fx->small_d.feat, fx->small_seqs, fx->small_y, fx->small_n, SMALL_LABELS, 2);
    affect_classifier *b = train_ok(&plain, fx->small_d.feat, fx->small_seqs, fx->small_y,
                                    fx->small_n, SMALL_LABELS, 2);
    affect_classifier_report ra, rb;
    affect_classifier_get_report(a, &ra);
    affect_classifier_get_report(b, &rb);
    assert_true(!isnan(ra.grid_cv_acc) && isnan(rb.grid_cv_acc));
    assert_true(affect_classifier_get_config(a)->knn_k == 3 &&
                affect_classifier_get_config(a)->spca_sigma == 1.5);
    assert_memory_equal(affect_classifier_train_embed(a), affect_classifier_train_embed(b),
                        fx->small_n * sizeof(double));
    for (uint32_t i = 0; i < fx->small_n; i++) {
        eval_res ea, eb;
        eval_ok(a, &fx->small_seqs[i], &ea);
        eval_ok(b, &fx->small_seqs[i], &eb);
        assert_memory_equal(ea.embed, eb.embed, sizeof(double));
        assert_memory_equal(ea.votes, eb.votes, 2 * sizeof(uint32_t));
        assert_int_equal(ea.o.knn, eb.o.knn);
        free(ea.fisher);
        free(eb.fisher);
    }
    affect_classifier_free(a);
    affect_classifier_free(b);
}

/* ---- salience ---- */

typedef struct cov_entry {
    uint32_t r, s;
    double w;
} cov_entry;

static void test_salience(void **state)
{
    fixture *fx = *state;
    const affect_classifier *c = fx->c;
    const affect_classifier_config *cfg = affect_classifier_get_config(c);
    uint32_t N = cfg->hmm.n_states, M = cfg->hmm.n_mix, m = cfg->hmm.dim, C = 4;
    uint32_t per = m * (m + 1) / 2;
    affect_salience_row *rows = NULL;
    size_t n_rows = 0;
    affect_error err;
    assert_int_equal(affect_classifier_salience(c, 7, &rows, &n_rows, &err), AFFECT_OK);
    assert_int_equal(n_rows, (size_t)C * N * M);
    /* brute force: for every covariance entry the largest |axis coefficient| */
    const double *U = affect_spca_axes(affect_classifier_spca(c));
    uint32_t p = affect_spca_dims(affect_classifier_spca(c));
    size_t D = affect_classifier_dim(c), part = affect_classifier_part_dim(c);
    cov_entry *list = malloc(per * sizeof *list);
    assert_non_null(list);
    for (size_t q = 0; q < n_rows; q++) {
        const affect_salience_row *row = &rows[q];
        assert_int_equal(row->cls, q / (N * M));
        assert_int_equal(row->state, q / M % N);
        assert_int_equal(row->mix, q % M);
        assert_int_equal(row->n_top, 7);
        uint32_t cnt = 0;
        for (size_t e = 0; e < part; e++) {
            affect_fisher_entry fe;
            assert_int_equal(affect_fisher_describe(&cfg->hmm, cfg->groups, e, &fe, &err),
                             AFFECT_OK);
            if (fe.group != AFFECT_FISHER_COVS || fe.state != row->state || fe.other != row->mix)
                continue;
            double w = 0;
            for (uint32_t a = 0; a < p; a++)
                w = fmax(w, fabs(U[(size_t)a * D + row->cls * part + e]));
            /* insertion keeping the earlier entry first among equal weights */
            uint32_t pos = cnt++;
            while (pos > 0 && w > list[pos - 1].w) {
                list[pos] = list[pos - 1];
                pos--;
            }
            list[pos] = (cov_entry){fe.r, fe.s, w};
        }
        assert_int_equal(cnt, per);
        assert_true(row->weight >= 0);
        assert_true(row->weight == list[0].w);
        for (uint32_t t = 0; t < row->n_top; t++) {
            assert_true(row->top[t].weight >= 0);
            assert_true(row->top[t].r <= row->top[t].s && row->top[t].s < m);
            if (t)
                assert_true(row->top[t].weight <= row->top[t - 1].weight);
            if (row->top[t].r != list[t].r || row->top[t].s != list[t].s ||
                row->top[t].weight != list[t].w)
                fail_msg("row %zu, top %u: (%u, %u) %g, expected (%u, %u) %g", q, t, row->top[t].r,
                         row->top[t].s, row->top[t].weight, list[t].r, list[t].s, list[t].w);
        }
    }
    free(list);
    assert_true(rows[0].weight > 0);
    affect_free(rows);

    /* top limits */
    rows = (affect_salience_row *)fx;
    assert_int_equal(affect_classifier_salience(c, 0, &rows, &n_rows, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "top must be between 1 and 32");
    assert_null(rows);
    assert_int_equal(affect_classifier_salience(c, 33, &rows, &n_rows, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "top must be between 1 and 32");
    assert_int_equal(affect_classifier_salience(c, 32, &rows, &n_rows, &err), AFFECT_OK);
    assert_int_equal(rows[0].n_top, 32);
    affect_free(rows);
    /* the small model: 6 covariance entries per component, fewer than top */
    assert_int_equal(affect_classifier_salience(fx->small, 10, &rows, &n_rows, &err), AFFECT_OK);
    assert_int_equal(n_rows, 2 * 2 * 1);
    for (size_t q = 0; q < n_rows; q++)
        assert_int_equal(rows[q].n_top, 6);
    affect_free(rows);

    /* without the covariance group */
    affect_classifier_config cfg2;
    small_config(&cfg2, fx->small_d.feat);
    cfg2.groups = AFFECT_FISHER_MEANS | AFFECT_FISHER_TRANS;
    affect_classifier *nc = train_ok(&cfg2, fx->small_d.feat, fx->small_seqs, fx->small_y,
                                     fx->small_n, SMALL_LABELS, 2);
    assert_int_equal(affect_classifier_part_dim(nc), 4 + 6);
    assert_int_equal(affect_classifier_salience(nc, 5, &rows, &n_rows, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "the classifier has no covariance scores (trained without the "
                                 "covariances group)");
    assert_null(rows);
    assert_int_equal(n_rows, 0);
    affect_classifier_free(nc);
}

/* ---- out of memory ---- */

typedef struct oom_ctx {
    fixture *fx;
    const affect_classifier_config *cfg;
    const affect_hmm_seq *seqs;
    const uint32_t *y;
    uint32_t n;
    affect_classifier *c;
    unsigned char *blob;
    size_t size;
    eval_res r;
} oom_ctx;

static affect_status oom_train(void *ctx, affect_error *err)
{
    oom_ctx *o = ctx;
    return affect_classifier_train(o->cfg, o->fx->small_d.feat, o->seqs, NULL, o->y, o->n,
                                   SMALL_LABELS, 2, &o->c, err);
}

static affect_status oom_decode(void *ctx, affect_error *err)
{
    oom_ctx *o = ctx;
    return affect_classifier_decode(o->fx->small_blob, o->fx->small_size, &o->c, err);
}

/* The compact storage's BLOB (o->blob): its triangles and 24-bit values. */
static affect_status oom_decode_compact(void *ctx, affect_error *err)
{
    oom_ctx *o = ctx;
    return affect_classifier_decode(o->blob, o->size, &o->c, err);
}

static void oom_finish_classifier(void *ctx, affect_status st)
{
    oom_ctx *o = ctx;
    if (st == AFFECT_OK)
        assert_non_null(o->c);
    else
        assert_null(o->c);
    affect_classifier_free(o->c);
    o->c = NULL;
}

static affect_status oom_encode(void *ctx, affect_error *err)
{
    oom_ctx *o = ctx;
    return affect_classifier_encode(o->fx->small, &o->blob, &o->size, err);
}

static void oom_finish_encode(void *ctx, affect_status st)
{
    oom_ctx *o = ctx;
    if (st == AFFECT_OK) {
        assert_int_equal(o->size, o->fx->small_size);
        assert_memory_equal(o->blob, o->fx->small_blob, o->size);
    } else {
        assert_null(o->blob);
    }
    affect_free(o->blob);
    o->blob = NULL;
}

static affect_status oom_eval(void *ctx, affect_error *err)
{
    oom_ctx *o = ctx;
    const affect_hmm_seq *s = &o->fx->small_seqs[1];
    affect_classifier_out out = {0}; /* nothing wanted: eval allocates its own buffers */
    return affect_classifier_eval(o->fx->small, s->x, s->n_frames, NULL, false, &out, NULL, err);
}

static void test_out_of_memory(void **state)
{
    fixture *fx = *state;
    oom_ctx o = {0};
    o.fx = fx;
    long n_enc = tu_oom_sweep(oom_encode, &o, oom_finish_encode, NULL);
    long n_dec = tu_oom_sweep(oom_decode, &o, oom_finish_classifier, NULL);
    long n_eval = tu_oom_sweep(oom_eval, &o, NULL, NULL);
    assert_true(n_enc >= 1 && n_dec >= 10 && n_eval >= 2);

    /* a tiny training: 2 motions per class of 12 frames, 2 states, 2 iterations; C chosen by
     * inner cross-validation and a grid search, so that every stage allocates */
    affect_hmm_seq seqs[8];
    uint32_t y[8];
    uint32_t n = small_part(&fx->small_d, 2, 30, 12, seqs, y);
    assert_int_equal(n, 4);
    affect_classifier_config cfg;
    small_config(&cfg, fx->small_d.feat);
    cfg.hmm.max_iter = 2;
    cfg.svm_c = 0;
    cfg.svm_folds = 2;
    cfg.grid.n_dims = 1;
    cfg.grid.dims[0] = 1;
    cfg.grid.n_k = 2;
    cfg.grid.k[0] = 1;
    cfg.grid.k[1] = 3;
    cfg.grid.folds = 2;
    o.cfg = &cfg;
    o.seqs = seqs;
    o.y = y;
    o.n = n;
    long n_train = tu_oom_sweep(oom_train, &o, oom_finish_classifier, NULL);
    printf("allocations: encode %ld, decode %ld, eval %ld, training %ld\n", n_enc, n_dec, n_eval,
           n_train);
    assert_true(n_train > 20);
    /* the same training with the compact storage (make_compact allocates), and its decoding */
    cfg.storage = AFFECT_STORAGE_COMPACT;
    long n_compact = tu_oom_sweep(oom_train, &o, oom_finish_classifier, NULL);
    affect_error err;
    assert_int_equal(oom_train(&o, &err), AFFECT_OK);
    encode_ok(o.c, &o.blob, &o.size);
    assert_int_equal(o.blob[4], 3);
    affect_classifier_free(o.c);
    o.c = NULL;
    long n_dec3 = tu_oom_sweep(oom_decode_compact, &o, oom_finish_classifier, NULL);
    affect_free(o.blob);
    printf("allocations: compact training %ld, its decoding %ld\n", n_compact, n_dec3);
    assert_true(n_compact > n_train && n_dec3 >= 10);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_recognition),      cmocka_unit_test(test_normalization_and_clipping),
        cmocka_unit_test(test_no_normalization), cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_determinism),      cmocka_unit_test(test_corrupted_bytes),
        cmocka_unit_test(test_truncations),      cmocka_unit_test(test_descriptors),
        cmocka_unit_test(test_fixture_v1),       cmocka_unit_test(test_fixture_v2),
        cmocka_unit_test(test_compact),          cmocka_unit_test(test_fixture_v3),
        cmocka_unit_test(test_bad_fields),       cmocka_unit_test(test_config_check),
        cmocka_unit_test(test_train_errors),     cmocka_unit_test(test_grid),
        cmocka_unit_test(test_salience),         cmocka_unit_test(test_slabs),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
