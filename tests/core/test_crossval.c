/*
 * test_crossval.c — the evaluation protocols of affect/crossval.h on motion_synth observations
 * (knock and wave × 4 emotions × performers 1–4; the right hand and head by role with
 * velocities; 3-state HMMs).
 *
 * Checked: affect_stratified_folds gives stratified, disjoint, covering folds of sizes
 * differing by at most 1, the same for a seed and different for another, and the
 * cross-validation's folds are exactly those (per fold n_test, n_train and the class counts
 * of its confusion matrices); two runs give bit-identical results; every fold metric against
 * the definitions of crossval.h recomputed from the confusion matrices, the summaries (mean,
 * sample sd, pooled matrix and accuracy) likewise; a constructed leave-one-group-out case
 * with a class missing from a fold's training motions, its metrics worked out by hand;
 * leakage: a second run in which half of one fold's motions are replaced by garbage leaves
 * that fold's classifier untouched (the same C, sPCA and kNN parameters) and its confusion
 * matrices are exactly the predictions of a classifier trained here on the other folds'
 * motions alone, clean and garbage motions alike (a held-out motion reaching training would
 * change that classifier); the progress lines; every error message; and every allocation
 * failing in turn in a tiny cross-validation.
 */
#include <stdio.h>
#include <string.h>

#include "testutil.h"

#include "affect/crossval.h"
#include "util/rng.h"
#include "affect/synth.h"

#define N_ACTIONS 2
#define N_EMOTIONS 4
#define N_SEEDS 4
#define N_MOTIONS (N_ACTIONS * N_EMOTIONS * N_SEEDS)

static const char *const ACTIONS[N_ACTIONS] = {"knock", "wave"};
static const char *const EMOTIONS[N_EMOTIONS] = {"neutral", "happy", "sad", "angry"};
static const char *const JOINTS[] = {"right_hand", "head"};

/* ---- data ---- */

typedef struct dataset {
    affect_features *feat;
    uint32_t n, dim;
    double *x[N_MOTIONS];
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS], seed[N_MOTIONS], action[N_MOTIONS];
} dataset;

static void dataset_load(dataset *d)
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
                    opt.joints = JOINTS;
                    opt.n_joints = 2;
                    opt.velocity = true;
                    if (affect_features_create(&opt, m, &d->feat, &err))
                        fail_msg("features: %s", err.msg);
                    d->dim = affect_features_dim(d->feat);
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

static void cv_config(affect_cv_config *cfg, const affect_features *f)
{
    affect_cv_config_default(cfg);
    cfg->cls.hmm.dim = affect_features_dim(f);
    cfg->cls.hmm.n_states = 3;
    cfg->cls.hmm.n_mix = 1;
    cfg->cls.hmm.cov = AFFECT_HMM_FULL;
    cfg->cls.hmm.max_iter = 4;
    cfg->cls.descriptors = 0;
    cfg->cls.mirror = AFFECT_MIRROR_OFF;
    cfg->cls.spca_dims = 2;
    cfg->cls.knn_k = 3;
}

static affect_cv_result *run_ok(const affect_cv_config *cfg, const affect_features *f,
                                const affect_hmm_seq *seqs, const uint32_t *y, uint32_t n,
                                const char *const *labels, uint32_t C, const uint32_t *group,
                                uint32_t n_groups)
{
    affect_cv_result *r = NULL;
    affect_error err;
    if (affect_crossval(cfg, f, seqs, NULL, y, n, labels, C, group, n_groups, &r, &err))
        fail_msg("crossval: %s", err.msg);
    assert_non_null(r);
    return r;
}

static void run_fails(const affect_cv_config *cfg, const affect_features *f,
                      const affect_hmm_seq *seqs, const uint32_t *y, uint32_t n,
                      const char *const *labels, uint32_t C, const uint32_t *group,
                      uint32_t n_groups, const char *msg)
{
    affect_cv_result *r = (affect_cv_result *)seqs; /* must become NULL */
    affect_error err;
    affect_status st =
        affect_crossval(cfg, f, seqs, NULL, y, n, labels, C, group, n_groups, &r, &err);
    if (st == AFFECT_OK)
        fail_msg("cross-validation succeeded, expected \"%s\"", msg);
    assert_int_equal(st, AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, msg);
    assert_null(r);
}

/* ---- metrics, from the definitions of crossval.h ---- */

typedef struct metric3 {
    double acc, bal, f1;
} metric3;

static metric3 metrics_of(const uint32_t *cm, uint32_t C)
{
    uint32_t total = 0, correct = 0, nrec = 0, nf1 = 0;
    double rec = 0, f1 = 0;
    for (uint32_t k = 0; k < C; k++) {
        uint32_t tp = cm[k * C + k], fn = 0, fp = 0;
        for (uint32_t j = 0; j < C; j++) {
            if (j == k)
                continue;
            fn += cm[k * C + j];
            fp += cm[j * C + k];
        }
        total += tp + fn;
        correct += tp;
        if (tp + fn > 0) { /* present among the held-out motions */
            rec += (double)tp / (tp + fn);
            nrec++;
        }
        if (tp + fn > 0 || tp + fp > 0) { /* present or predicted */
            f1 += 2.0 * tp / (2.0 * tp + fp + fn);
            nf1++;
        }
    }
    metric3 m = {(double)correct / total, rec / nrec, f1 / nf1};
    return m;
}

/* Every fold's metrics from its matrices, and the summaries, of the methods in mask. */
static void check_metrics_of(const affect_cv_result *r, uint32_t n_total, unsigned mask)
{
    uint32_t C = r->n_classes, F = r->n_folds;
    uint32_t tested = 0;
    for (uint32_t f = 0; f < F; f++) {
        const affect_cv_fold *fd = &r->folds[f];
        tested += fd->n_test;
        assert_int_equal(fd->n_train + fd->n_test, n_total);
        for (int m = 0; m < AFFECT_CV_METHODS; m++) {
            if (!(mask & (1u << m)))
                continue;
            uint32_t sum = 0;
            for (uint32_t e = 0; e < C * C; e++)
                sum += fd->confusion[m][e];
            assert_int_equal(sum, fd->n_test);
            metric3 want = metrics_of(fd->confusion[m], C);
            tu_assert_near(fd->accuracy[m], want.acc, 1e-15);
            tu_assert_near(fd->balanced[m], want.bal, 1e-15);
            tu_assert_near(fd->f1[m], want.f1, 1e-15);
        }
        for (uint32_t k = 0; k < C; k++) { /* the methods saw the same motions */
            uint32_t row[AFFECT_CV_METHODS] = {0}, first = UINT32_MAX;
            for (int m = 0; m < AFFECT_CV_METHODS; m++) {
                if (!(mask & (1u << m)))
                    continue;
                for (uint32_t j = 0; j < C; j++)
                    row[m] += fd->confusion[m][k * C + j];
                if (first == UINT32_MAX)
                    first = row[m];
                assert_int_equal(row[m], first);
            }
        }
    }
    assert_int_equal(tested, n_total);
    for (int m = 0; m < AFFECT_CV_METHODS; m++) {
        if (!(mask & (1u << m)))
            continue;
        double s[3] = {0}, q[3] = {0};
        for (uint32_t f = 0; f < F; f++) {
            s[0] += r->folds[f].accuracy[m];
            s[1] += r->folds[f].balanced[m];
            s[2] += r->folds[f].f1[m];
        }
        for (int t = 0; t < 3; t++)
            s[t] /= F;
        for (uint32_t f = 0; f < F; f++) {
            double v[3] = {r->folds[f].accuracy[m], r->folds[f].balanced[m], r->folds[f].f1[m]};
            for (int t = 0; t < 3; t++)
                q[t] += (v[t] - s[t]) * (v[t] - s[t]);
        }
        tu_assert_near(r->mean_accuracy[m], s[0], 1e-14);
        tu_assert_near(r->mean_balanced[m], s[1], 1e-14);
        tu_assert_near(r->mean_f1[m], s[2], 1e-14);
        tu_assert_near(r->sd_accuracy[m], sqrt(q[0] / (F - 1)), 1e-14);
        tu_assert_near(r->sd_balanced[m], sqrt(q[1] / (F - 1)), 1e-14);
        tu_assert_near(r->sd_f1[m], sqrt(q[2] / (F - 1)), 1e-14);
        uint32_t trace = 0, total = 0;
        for (uint32_t e = 0; e < C * C; e++) {
            uint32_t sum = 0;
            for (uint32_t f = 0; f < F; f++)
                sum += r->folds[f].confusion[m][e];
            assert_int_equal(r->pooled[m][e], sum);
            total += sum;
            trace += e % (C + 1) == 0 ? sum : 0;
        }
        assert_int_equal(total, n_total);
        tu_assert_near(r->pooled_accuracy[m], (double)trace / total, 1e-15);
    }
}

static void check_metrics(const affect_cv_result *r, uint32_t n_total)
{
    check_metrics_of(r, n_total, AFFECT_CV_RECOGNIZER_MASK);
}

/* Whether two results are bit-identical (folds, matrices, summaries). */
static bool same_results(const affect_cv_result *a, const affect_cv_result *b)
{
    if (a->n_classes != b->n_classes || a->n_folds != b->n_folds)
        return false;
    size_t cc = (size_t)a->n_classes * a->n_classes * sizeof(uint32_t);
    for (uint32_t f = 0; f < a->n_folds; f++) {
        const affect_cv_fold *x = &a->folds[f], *y = &b->folds[f];
        if (x->fold != y->fold || x->group != y->group || x->n_train != y->n_train ||
            x->n_test != y->n_test || memcmp(x->accuracy, y->accuracy, sizeof x->accuracy) ||
            memcmp(x->balanced, y->balanced, sizeof x->balanced) ||
            memcmp(x->f1, y->f1, sizeof x->f1) || memcmp(&x->svm_c, &y->svm_c, 8) ||
            memcmp(&x->spca_sigma, &y->spca_sigma, 8) || x->spca_dims != y->spca_dims ||
            x->knn_k != y->knn_k)
            return false;
        for (int m = 0; m < AFFECT_CV_METHODS; m++)
            if (memcmp(x->confusion[m], y->confusion[m], cc))
                return false;
        if (memcmp(x->fda_dims, y->fda_dims, sizeof x->fda_dims) ||
            memcmp(&x->fda_lambda, &y->fda_lambda, 8))
            return false;
    }
    for (int m = 0; m < AFFECT_CV_METHODS; m++)
        if (memcmp(a->pooled[m], b->pooled[m], cc))
            return false;
    return memcmp(a->mean_accuracy, b->mean_accuracy, sizeof a->mean_accuracy) == 0 &&
           memcmp(a->sd_accuracy, b->sd_accuracy, sizeof a->sd_accuracy) == 0 &&
           memcmp(a->mean_f1, b->mean_f1, sizeof a->mean_f1) == 0 &&
           memcmp(a->pooled_accuracy, b->pooled_accuracy, sizeof a->pooled_accuracy) == 0;
}

/* ---- progress ---- */

typedef struct lines {
    char text[16][160];
    uint32_t n;
} lines;

static void collect(void *ctx, const char *line)
{
    lines *l = ctx;
    assert_true(l->n < 16);
    assert_true(strlen(line) < sizeof l->text[0]);
    strcpy(l->text[l->n++], line);
}

/* ---- threads ---- */

static void test_threads(void **state)
{
    dataset *d = *state;
    affect_cv_config cfg;
    cv_config(&cfg, d->feat);
    cfg.folds = 4;
    cfg.seed = 5;
    lines progress = {0};
    cfg.progress = collect;
    cfg.progress_ctx = &progress;
    affect_cv_result *one =
        run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0);
    for (uint32_t t = 2; t <= 5; t += 3) { /* 2 threads, and more threads than folds */
        cfg.threads = t;
        progress.n = 0;
        affect_cv_result *many =
            run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0);
        assert_true(same_results(one, many));
        assert_int_equal(progress.n, 4); /* one line per fold, in completion order */
        affect_cv_result_free(many);
    }
    affect_cv_result_free(one);
    cfg.threads = 0;
    run_fails(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0,
              "threads must be from 1 to 64, got 0");
    /* an error in one fold stops them all: group 1 holds every class but 0, so its training
     * motions have one class */
    uint32_t group[N_MOTIONS];
    for (uint32_t i = 0; i < d->n; i++)
        group[i] = d->y[i] == 0 ? 0 : 1;
    cfg.threads = 2;
    cfg.progress = NULL;
    affect_cv_result *r = (affect_cv_result *)d;
    affect_error err;
    assert_int_equal(affect_crossval(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS, N_EMOTIONS,
                                     group, 2, &r, &err),
                     AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "fold 2: the training motions have fewer than 2 classes");
    assert_null(r);
}

/* ---- the fixture ---- */

static int setup(void **state)
{
    dataset *d = calloc(1, sizeof *d);
    if (!d)
        return -1;
    dataset_load(d);
    *state = d;
    return 0;
}

static int teardown(void **state)
{
    dataset_free(*state);
    free(*state);
    return 0;
}

/* ---- folds ---- */

static void test_stratified_folds(void **state)
{
    dataset *d = *state;
    affect_error err;
    uint32_t a[N_MOTIONS], b[N_MOTIONS], c[N_MOTIONS];
    /* unequal classes: drop some motions of classes 1 and 3 (32 → 27) */
    uint32_t y[N_MOTIONS], n = 0;
    for (uint32_t i = 0; i < d->n; i++)
        if (!((d->y[i] == 1 && d->seed[i] <= 2) ||
              (d->y[i] == 3 && d->seed[i] == 4 && d->action[i] == 0)))
            y[n++] = d->y[i];
    assert_int_equal(n, 27);
    uint32_t count[N_EMOTIONS] = {0};
    for (uint32_t i = 0; i < n; i++)
        count[y[i]]++;
    for (uint32_t k = 2; k <= 7; k++) {
        assert_int_equal(affect_stratified_folds(y, n, N_EMOTIONS, k, 1, a, &err), AFFECT_OK);
        assert_int_equal(affect_stratified_folds(y, n, N_EMOTIONS, k, 1, b, &err), AFFECT_OK);
        assert_int_equal(affect_stratified_folds(y, n, N_EMOTIONS, k, 2, c, &err), AFFECT_OK);
        assert_memory_equal(a, b, n * sizeof *a);     /* reproducible */
        assert_memory_not_equal(a, c, n * sizeof *a); /* another seed, other folds */
        uint32_t size[8] = {0}, per[8][N_EMOTIONS] = {{0}};
        for (uint32_t i = 0; i < n; i++) { /* one fold per motion: disjoint and covering */
            assert_true(a[i] < k);
            size[a[i]]++;
            per[a[i]][y[i]]++;
        }
        uint32_t lo = n, hi = 0;
        for (uint32_t f = 0; f < k; f++) {
            lo = size[f] < lo ? size[f] : lo;
            hi = size[f] > hi ? size[f] : hi;
            for (uint32_t e = 0; e < N_EMOTIONS; e++) /* stratified */
                assert_true(per[f][e] == count[e] / k || per[f][e] == (count[e] + k - 1) / k);
        }
        assert_true(lo >= 1 && hi - lo <= 1);
    }
    /* k beyond n is clamped to n: one motion per fold */
    assert_int_equal(affect_stratified_folds(y, 5, N_EMOTIONS, 10, 1, a, &err), AFFECT_OK);
    uint32_t seen[5] = {0};
    for (uint32_t i = 0; i < 5; i++) {
        assert_true(a[i] < 5);
        seen[a[i]]++;
    }
    for (uint32_t f = 0; f < 5; f++)
        assert_int_equal(seen[f], 1);
}

/* The cross-validation's folds are those of affect_stratified_folds with its seed, the same
 * run twice gives the same bits, and the metrics follow their definitions. */
static void test_kfold(void **state)
{
    dataset *d = *state;
    affect_cv_config cfg;
    cv_config(&cfg, d->feat);
    cfg.folds = 4;
    cfg.seed = 7;
    cfg.cls.svm_c = 1.0;
    lines progress = {0};
    cfg.progress = collect;
    cfg.progress_ctx = &progress;
    affect_cv_result *r = run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0);
    assert_int_equal(r->n_classes, 4);
    assert_int_equal(r->n_folds, 4);
    uint32_t fold_of[N_MOTIONS], other[N_MOTIONS];
    affect_error err;
    assert_int_equal(affect_stratified_folds(d->y, d->n, N_EMOTIONS, 4, 7, fold_of, &err),
                     AFFECT_OK);
    assert_int_equal(affect_stratified_folds(d->y, d->n, N_EMOTIONS, 4, 8, other, &err), AFFECT_OK);
    assert_memory_not_equal(fold_of, other, sizeof fold_of);
    for (uint32_t f = 0; f < 4; f++) {
        const affect_cv_fold *fd = &r->folds[f];
        assert_int_equal(fd->fold, f);
        assert_int_equal(fd->group, -1);
        uint32_t per[N_EMOTIONS] = {0}, n_test = 0;
        for (uint32_t i = 0; i < d->n; i++)
            if (fold_of[i] == f) {
                per[d->y[i]]++;
                n_test++;
            }
        assert_int_equal(fd->n_test, n_test);
        assert_int_equal(fd->n_train, d->n - n_test);
        for (uint32_t k = 0; k < N_EMOTIONS; k++) {
            uint32_t row = 0;
            for (uint32_t j = 0; j < N_EMOTIONS; j++)
                row += fd->confusion[AFFECT_CV_SVM][k * N_EMOTIONS + j];
            assert_int_equal(row, per[k]);
        }
        assert_true(fd->svm_c == 1.0 && fd->spca_dims == 2 && fd->knn_k == 3 &&
                    fd->spca_sigma == 0.25);
        /* the progress line of the fold */
        char want[160];
        snprintf(want, sizeof want,
                 "fold %u/4: %u training, %u held out, svm %.3f, knn %.3f, "
                 "ml %.3f",
                 f + 1, fd->n_train, fd->n_test, fd->accuracy[AFFECT_CV_SVM],
                 fd->accuracy[AFFECT_CV_KNN], fd->accuracy[AFFECT_CV_ML]);
        assert_string_equal(progress.text[f], want);
    }
    assert_int_equal(progress.n, 4);
    assert_string_equal(progress.text[0],
                        "fold 1/4: 24 training, 8 held out, svm 1.000, knn 1.000, ml 1.000");
    check_metrics(r, d->n);
    printf("4-fold: svm %.3f, knn %.3f, ml %.3f\n", r->mean_accuracy[AFFECT_CV_SVM],
           r->mean_accuracy[AFFECT_CV_KNN], r->mean_accuracy[AFFECT_CV_ML]);
    assert_true(r->pooled_accuracy[AFFECT_CV_SVM] >= 0.9);

    /* the same again, without progress: the same bits */
    cfg.progress = NULL;
    affect_cv_result *r2 =
        run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0);
    assert_true(same_results(r, r2));
    affect_cv_result_free(r2);
    affect_cv_result_free(r);
}

/* ---- leakage ---- */

/* Predictions of a classifier trained on the motions outside fold F, for the motions of F
 * (seqs), added into cm (3 × C × C, the methods' matrices). */
static void direct_fold(const affect_cv_config *cfg, const dataset *d, const uint32_t *fold_of,
                        uint32_t F, const affect_hmm_seq *seqs, uint32_t cm[3][16], double *svm_c,
                        uint32_t *spca_dims)
{
    affect_hmm_seq tr[N_MOTIONS];
    uint32_t ty[N_MOTIONS], n = 0;
    for (uint32_t i = 0; i < d->n; i++)
        if (fold_of[i] != F) {
            tr[n] = d->seqs[i];
            ty[n++] = d->y[i];
        }
    affect_classifier *c = NULL;
    affect_error err;
    if (affect_classifier_train(&cfg->cls, d->feat, tr, NULL, ty, n, EMOTIONS, N_EMOTIONS, &c,
                                &err))
        fail_msg("train: %s", err.msg);
    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    *svm_c = rep.svm_c;
    *spca_dims = affect_spca_dims(affect_classifier_spca(c));
    memset(cm, 0, 3 * 16 * sizeof(uint32_t));
    for (uint32_t i = 0; i < d->n; i++) {
        if (fold_of[i] != F)
            continue;
        affect_classifier_out o = {0};
        if (affect_classifier_eval(c, seqs[i].x, seqs[i].n_frames, NULL, false, &o, NULL, &err))
            fail_msg("eval: %s", err.msg);
        cm[AFFECT_CV_ML][d->y[i] * N_EMOTIONS + o.ml]++;
        cm[AFFECT_CV_SVM][d->y[i] * N_EMOTIONS + o.svm]++;
        cm[AFFECT_CV_KNN][d->y[i] * N_EMOTIONS + o.knn]++;
    }
    affect_classifier_free(c);
}

static void test_no_leakage(void **state)
{
    dataset *d = *state;
    affect_cv_config cfg;
    cv_config(&cfg, d->feat);
    cfg.folds = 4;
    cfg.seed = 3;
    cfg.cls.svm_c = 0; /* chosen by inner cross-validation: part of what must not change */
    cfg.cls.svm_folds = 3;
    const uint32_t F = 1;
    uint32_t fold_of[N_MOTIONS];
    affect_error err;
    assert_int_equal(affect_stratified_folds(d->y, d->n, N_EMOTIONS, 4, 3, fold_of, &err),
                     AFFECT_OK);

    /* the corrupted set: every other motion of fold F becomes noise of the same shape, 10 arm
     * lengths (and per second) wide */
    affect_hmm_seq bad[N_MOTIONS];
    double *noise[N_MOTIONS] = {0};
    affect_rng rng;
    affect_rng_seed(&rng, 99);
    uint32_t in_f = 0, replaced = 0;
    for (uint32_t i = 0; i < d->n; i++) {
        bad[i] = d->seqs[i];
        if (fold_of[i] != F || in_f++ % 2 != 0)
            continue;
        size_t len = (size_t)d->seqs[i].n_frames * d->dim;
        noise[i] = malloc(len * sizeof(double));
        assert_non_null(noise[i]);
        for (size_t e = 0; e < len; e++)
            noise[i][e] = 10 * affect_rng_normal(&rng);
        bad[i].x = noise[i];
        replaced++;
    }
    assert_true(replaced >= 3 && in_f - replaced >= 3);

    affect_cv_result *a = run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0);
    affect_cv_result *b = run_ok(&cfg, d->feat, bad, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0);
    check_metrics(a, d->n);
    check_metrics(b, d->n);
    /* fold F's classifier saw the same training motions in both runs */
    const affect_cv_fold *fa = &a->folds[F], *fb = &b->folds[F];
    assert_int_equal(fa->n_train, fb->n_train);
    assert_int_equal(fa->n_test, fb->n_test);
    assert_memory_equal(&fa->svm_c, &fb->svm_c, sizeof fa->svm_c);
    assert_memory_equal(&fa->spca_sigma, &fb->spca_sigma, sizeof fa->spca_sigma);
    assert_true(fa->spca_dims == fb->spca_dims && fa->knn_k == fb->knn_k);
    /* and its matrices are the predictions of a classifier trained here on the other folds
     * alone: of the clean motions in run a, of clean and garbage ones in run b */
    uint32_t cm[3][16];
    double c_direct;
    uint32_t dims_direct;
    direct_fold(&cfg, d, fold_of, F, d->seqs, cm, &c_direct, &dims_direct);
    assert_true(c_direct == fa->svm_c && dims_direct == fa->spca_dims);
    for (int m = 0; m < AFFECT_CV_RECOGNIZER_METHODS; m++)
        assert_memory_equal(fa->confusion[m], cm[m], sizeof cm[m]);
    direct_fold(&cfg, d, fold_of, F, bad, cm, &c_direct, &dims_direct);
    for (int m = 0; m < AFFECT_CV_RECOGNIZER_METHODS; m++)
        assert_memory_equal(fb->confusion[m], cm[m], sizeof cm[m]);
    /* the garbage is recognised as such: the clean run does better on fold F */
    assert_true(fb->accuracy[AFFECT_CV_SVM] < fa->accuracy[AFFECT_CV_SVM] ||
                fb->accuracy[AFFECT_CV_KNN] < fa->accuracy[AFFECT_CV_KNN] ||
                fb->accuracy[AFFECT_CV_ML] < fa->accuracy[AFFECT_CV_ML]);
    printf("fold %u: svm %.3f → %.3f, knn %.3f → %.3f, ml %.3f → %.3f with %u of %u motions "
           "replaced by noise\n",
           F + 1, fa->accuracy[1], fb->accuracy[1], fa->accuracy[2], fb->accuracy[2],
           fa->accuracy[0], fb->accuracy[0], replaced, in_f);
    affect_cv_result_free(a);
    affect_cv_result_free(b);
    for (uint32_t i = 0; i < d->n; i++)
        free(noise[i]);
}

/* ---- leave one group out ---- */

/* Three classes (neutral, sad, angry as 0, 1, 2) of the knock motions; group 0 holds every
 * sad motion and performer 1's other motions, group 1 the rest. Fold 1 trains without sad, so
 * its 4 sad motions are errors. */
static void test_leave_one_group_out(void **state)
{
    dataset *d = *state;
    static const char *const labels[] = {"neutral", "sad", "angry"};
    affect_hmm_seq seqs[N_MOTIONS];
    uint32_t y[N_MOTIONS], g[N_MOTIONS], n = 0;
    for (uint32_t i = 0; i < d->n; i++) {
        if (d->action[i] != 0 || d->y[i] == 1)
            continue;
        seqs[n] = d->seqs[i];
        y[n] = d->y[i] == 0 ? 0 : d->y[i] == 2 ? 1 : 2;
        g[n] = y[n] == 1 || d->seed[i] == 1 ? 0 : 2; /* group 1 is empty */
        n++;
    }
    assert_int_equal(n, 12);
    affect_cv_config cfg;
    cv_config(&cfg, d->feat);
    cfg.cls.svm_c = 1.0;
    lines progress = {0};
    cfg.progress = collect;
    cfg.progress_ctx = &progress;
    affect_cv_result *r = run_ok(&cfg, d->feat, seqs, y, n, labels, 3, g, 3);
    assert_int_equal(r->n_folds, 2); /* the empty group gives no fold */
    assert_int_equal(r->folds[0].fold, 0);
    assert_int_equal(r->folds[0].group, 0);
    assert_int_equal(r->folds[1].fold, 2);
    assert_int_equal(r->folds[1].group, 2);
    const affect_cv_fold *f0 = &r->folds[0];
    assert_int_equal(f0->n_test, 6); /* 4 sad, 1 neutral, 1 angry */
    assert_int_equal(f0->n_train, 6);
    assert_int_equal(r->folds[1].n_test, 6);
    /* fold 1's classifier knows two classes: one sPCA axis of the 2 asked */
    assert_int_equal(f0->spca_dims, 1);
    for (int m = 0; m < AFFECT_CV_RECOGNIZER_METHODS; m++) {
        const uint32_t *cm = f0->confusion[m];
        /* the sad row: 4 motions, none predicted sad; nothing else predicted sad either */
        assert_int_equal(cm[1 * 3 + 0] + cm[1 * 3 + 2], 4);
        assert_int_equal(cm[0 * 3 + 1] + cm[1 * 3 + 1] + cm[2 * 3 + 1], 0);
        assert_int_equal(cm[0 * 3 + 0] + cm[0 * 3 + 2], 1);
        assert_int_equal(cm[2 * 3 + 0] + cm[2 * 3 + 2], 1);
    }
    /* neutral and angry are recognised: the metrics by hand, with a = sad motions predicted
     * neutral (4 − a predicted angry): accuracy 2/6; balanced (1 + 0 + 1) / 3; F1 of neutral
     * 2·1 / (2·1 + a + 0) = 2 / (2 + a), of angry 2 / (2 + 4 − a), of sad 0 (present) */
    const uint32_t *cm = f0->confusion[AFFECT_CV_SVM];
    assert_int_equal(cm[0], 1);
    assert_int_equal(cm[8], 1);
    double a = cm[1 * 3 + 0];
    tu_assert_near(f0->accuracy[AFFECT_CV_SVM], 2.0 / 6.0, 1e-15);
    tu_assert_near(f0->balanced[AFFECT_CV_SVM], 2.0 / 3.0, 1e-15);
    tu_assert_near(f0->f1[AFFECT_CV_SVM], (2.0 / (2.0 + a) + 2.0 / (6.0 - a) + 0.0) / 3.0, 1e-15);
    /* fold 3: neutral and angry of performers 2 .. 4, all three classes trained */
    const affect_cv_fold *f2 = &r->folds[1];
    assert_true(f2->spca_dims == 2);
    for (uint32_t j = 0; j < 3; j++)
        assert_int_equal(f2->confusion[AFFECT_CV_SVM][1 * 3 + j], 0); /* no sad held out */
    check_metrics(r, n);
    assert_int_equal(progress.n, 2);
    assert_string_equal(progress.text[0],
                        "fold 1/3: 6 training, 6 held out, svm 0.333, knn 0.333, ml 0.333");
    assert_true(strncmp(progress.text[1], "fold 3/3: 6 training, 6 held out, svm ", 38) == 0);
    affect_cv_result_free(r);

    /* a fold whose training motions have one class: an error */
    for (uint32_t i = 0; i < n; i++)
        g[i] = y[i] == 1 ? 1 : 0; /* fold 1 trains on sad alone */
    run_fails(&cfg, d->feat, seqs, y, n, labels, 3, g, 2,
              "fold 1: the training motions have fewer than 2 classes");
}

/* ---- errors ---- */

static void test_errors(void **state)
{
    dataset *d = *state;
    affect_cv_config cfg;
    cv_config(&cfg, d->feat);
    cfg.cls.svm_c = 1.0;
    const affect_hmm_seq *s = d->seqs;
    uint32_t y[N_MOTIONS], g[N_MOTIONS];
    memcpy(y, d->y, sizeof y);
    for (uint32_t i = 0; i < d->n; i++)
        g[i] = d->seed[i] - 1;
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 1, NULL, 0, "need 2 to 64 classes, got 1");
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 65, NULL, 0, "need 2 to 64 classes, got 65");
    cfg.folds = 1;
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 4, NULL, 0, "folds must be at least 2");
    cfg.folds = 1025;
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 4, NULL, 0, "at most 1024 folds, got 1025");
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 4, g, 1025, "at most 1024 groups, got 1025");
    cfg.folds = 4;
    y[5] = 4;
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 4, NULL, 0,
              "motion 5: class or group out of range");
    y[5] = d->y[5];
    g[9] = 4;
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 4, g, 4,
              "motion 9: class or group out of range");
    cfg.cls.knn_k = 0;
    run_fails(&cfg, d->feat, s, y, d->n, EMOTIONS, 4, NULL, 0, "fold 1: knn_k must be at least 1");
    /* a fold's evaluation error names the fold and the motion */
    cv_config(&cfg, d->feat);
    cfg.cls.svm_c = 1.0;
    cfg.folds = 2;
    affect_hmm_seq bad[N_MOTIONS];
    memcpy(bad, s, sizeof bad);
    double *x = malloc((size_t)bad[3].n_frames * d->dim * sizeof *x);
    assert_non_null(x);
    memcpy(x, bad[3].x, (size_t)bad[3].n_frames * d->dim * sizeof *x);
    bad[3].x = x;
    uint32_t fold_of[N_MOTIONS];
    affect_error err;
    assert_int_equal(affect_stratified_folds(d->y, d->n, N_EMOTIONS, 2, 1, fold_of, &err),
                     AFFECT_OK);
    x[7] = NAN; /* training (the other fold) or evaluation (its own) fails */
    affect_cv_result *r = NULL;
    assert_int_equal(
        affect_crossval(&cfg, d->feat, bad, NULL, y, d->n, EMOTIONS, 4, NULL, 0, &r, &err),
        AFFECT_ERR_INVALID);
    assert_null(r);
    char prefix[64];
    if (fold_of[3] == 0)
        snprintf(prefix, sizeof prefix, "fold 1, motion 3: ");
    else
        snprintf(prefix, sizeof prefix, "fold 1: training the HMM of class \"neutral\": ");
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("\"%s\" does not start with \"%s\"", err.msg, prefix);
    free(x);
}

/* ---- k beyond the motion count, and out of memory ---- */

typedef struct oom_ctx {
    const affect_cv_config *cfg;
    const dataset *d;
    const affect_hmm_seq *seqs;
    const uint32_t *y, *g;
    uint32_t n, n_groups;
    affect_cv_result *r;
    uint32_t classes; /* 0: 2 */
} oom_ctx;

static affect_status oom_cv(void *ctx, affect_error *err)
{
    oom_ctx *o = ctx;
    return affect_crossval(o->cfg, o->d->feat, o->seqs, NULL, o->y, o->n, EMOTIONS,
                           o->classes ? o->classes : 2, o->g, o->n_groups, &o->r, err);
}

static void oom_finish(void *ctx, affect_status st)
{
    oom_ctx *o = ctx;
    if (st == AFFECT_OK)
        assert_non_null(o->r);
    else
        assert_null(o->r);
    affect_cv_result_free(o->r);
    o->r = NULL;
}

static void test_small_and_out_of_memory(void **state)
{
    dataset *d = *state;
    /* neutral (0) and happy (1) waves of performers 1 .. 3, frames 30 .. 41 */
    affect_hmm_seq seqs[8];
    uint32_t y[8], g[8], n = 0;
    for (uint32_t i = 0; i < d->n; i++)
        if (d->action[i] == 1 && d->y[i] <= 1 && d->seed[i] <= 3) {
            seqs[n].x = d->x[i] + 30 * (size_t)d->dim;
            seqs[n].n_frames = 12;
            y[n] = d->y[i];
            g[n++] = d->seed[i] - 1;
        }
    assert_int_equal(n, 6);
    affect_cv_config cfg;
    cv_config(&cfg, d->feat);
    cfg.cls.hmm.n_states = 2;
    cfg.cls.hmm.max_iter = 2;
    cfg.cls.svm_c = 1.0;
    cfg.cls.spca_dims = 1;
    cfg.cls.knn_k = 1;
    cfg.folds = 10; /* clamped to the 6 motions: leave-one-out */
    affect_cv_result *r = run_ok(&cfg, d->feat, seqs, y, n, EMOTIONS, 2, NULL, 0);
    assert_int_equal(r->n_folds, 6);
    for (uint32_t f = 0; f < 6; f++)
        assert_true(r->folds[f].n_test == 1 && r->folds[f].n_train == 5);
    check_metrics(r, n);
    affect_cv_result_free(r);

    oom_ctx o = {&cfg, d, seqs, y, NULL, n, 0, NULL, 0};
    cfg.folds = 2;
    long k_fold = tu_oom_sweep(oom_cv, &o, oom_finish, NULL);
    o.g = g;
    o.n_groups = 3;
    long by_group = tu_oom_sweep(oom_cv, &o, oom_finish, NULL);
    printf("allocations: 2-fold %ld, 3 groups %ld\n", k_fold, by_group);
    assert_true(k_fold > 50 && by_group > 50);
}

/* ---- the functional methods (affect/fda.h) ---- */

static affect_fda_method fda_method_of(unsigned m, affect_spca_kernel *kernel)
{
    *kernel = m == AFFECT_CV_FSPCA_RBF ? AFFECT_SPCA_RBF : AFFECT_SPCA_LINEAR;
    return m == AFFECT_CV_FPCA                                ? AFFECT_FDA_FPCA
           : m == AFFECT_CV_FFDA                              ? AFFECT_FDA_FFDA
           : m == AFFECT_CV_FSPCA || m == AFFECT_CV_FSPCA_RBF ? AFFECT_FDA_FSPCA
                                                              : AFFECT_FDA_FISOMAP;
}

static void fda_cv_config(affect_cv_config *cfg, const affect_features *f)
{
    cv_config(cfg, f);
    cfg->methods = AFFECT_CV_ALL_MASK & ~AFFECT_CV_RECOGNIZER_MASK;
    cfg->fda.n_basis = 20;
    cfg->fda.dims = 2;
    cfg->fda.sigma = 0.5;
    cfg->fda.isomap_k = 5;
}

static void test_functional(void **state)
{
    dataset *d = *state;
    affect_cv_config cfg;
    fda_cv_config(&cfg, d->feat);
    uint32_t g[N_MOTIONS];
    for (uint32_t i = 0; i < d->n; i++)
        g[i] = d->seed[i] - 1;
    affect_cv_result *r = run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, g, N_SEEDS);
    assert_int_equal(r->n_folds, N_SEEDS);
    /* each fold, each method: affect_fda_train on the other performers, 1-NN classification */
    for (uint32_t f = 0; f < r->n_folds; f++) {
        const affect_cv_fold *fd = &r->folds[f];
        affect_hmm_seq tr[N_MOTIONS];
        uint32_t ytr[N_MOTIONS], n_tr = 0;
        for (uint32_t i = 0; i < d->n; i++)
            if (g[i] != fd->fold) {
                tr[n_tr] = d->seqs[i];
                ytr[n_tr++] = d->y[i];
            }
        assert_int_equal(fd->n_train, n_tr);
        for (unsigned m = 0; m < AFFECT_CV_METHODS; m++) {
            uint32_t want[N_EMOTIONS * N_EMOTIONS] = {0}, sum = 0;
            for (uint32_t e = 0; e < N_EMOTIONS * N_EMOTIONS; e++)
                sum += fd->confusion[m][e];
            if (m < AFFECT_CV_RECOGNIZER_METHODS) { /* not asked: nothing counted */
                assert_int_equal(sum, 0);
                assert_true(isnan(fd->accuracy[m]));
                continue;
            }
            affect_fda_config fc = cfg.fda;
            fc.method = fda_method_of(m, &fc.kernel);
            affect_fda *model = NULL;
            affect_error err;
            if (affect_fda_train(&fc, d->feat, tr, n_tr, d->dim, ytr, EMOTIONS, N_EMOTIONS, &model,
                                 &err))
                fail_msg("fda_train: %s", err.msg);
            assert_int_equal(fd->fda_dims[m], affect_fda_dims(model));
            for (uint32_t i = 0; i < d->n; i++) {
                if (g[i] != fd->fold)
                    continue;
                uint32_t label;
                assert_int_equal(affect_fda_classify(model, d->seqs[i].x, d->seqs[i].n_frames, 1,
                                                     &label, NULL, &err),
                                 AFFECT_OK);
                want[d->y[i] * N_EMOTIONS + label]++;
            }
            affect_fda_free(model);
            assert_memory_equal(fd->confusion[m], want, sizeof want);
            assert_int_equal(sum, fd->n_test);
        }
    }
    check_metrics_of(r, d->n, cfg.methods);
    /* two threads: the same bits */
    cfg.threads = 2;
    affect_cv_result *r2 = run_ok(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, g, N_SEEDS);
    assert_true(same_results(r, r2));
    affect_cv_result_free(r2);
    affect_cv_result_free(r);

    /* errors */
    cfg.threads = 1;
    cfg.methods = 0;
    run_fails(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, g, N_SEEDS, "no method asked");
    cfg.methods = 0x1ff;
    run_fails(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, g, N_SEEDS,
              "unknown method bits 0x100");
    cfg.methods = 1u << AFFECT_CV_FFDA;
    cfg.fda.dims = 0;
    run_fails(&cfg, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, g, N_SEEDS,
              "dims must be from 1 to 64");
    cfg.fda.dims = 2;
    cfg.methods = 1u << AFFECT_CV_FISOMAP;
    cfg.fda.lambda = 0; /* more coefficients than frames: a fold's training fails */
    cfg.fda.n_basis = 4000;
    affect_error err;
    r = NULL;
    assert_int_not_equal(affect_crossval(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS, 4, g,
                                         N_SEEDS, &r, &err),
                         AFFECT_OK);
    assert_null(r);
    const char *prefix = "fold 1: fisomap: motion 0: the fit is singular";
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("\"%s\" does not start with \"%s\"", err.msg, prefix);
    /* the recognizer's methods are still unchanged by the functional ones next to them */
    affect_cv_config both;
    cv_config(&both, d->feat);
    both.cls.svm_c = 1.0;
    both.folds = 4;
    affect_cv_result *a = run_ok(&both, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, NULL, 0);
    both.methods |= 1u << AFFECT_CV_FFDA;
    both.fda.n_basis = 20;
    affect_cv_result *b = run_ok(&both, d->feat, d->seqs, d->y, d->n, EMOTIONS, 4, NULL, 0);
    for (unsigned m = 0; m < AFFECT_CV_RECOGNIZER_METHODS; m++)
        assert_memory_equal(a->pooled[m], b->pooled[m], 16 * sizeof(uint32_t));
    assert_false(isnan(b->mean_accuracy[AFFECT_CV_FFDA]));
    assert_true(isnan(a->mean_accuracy[AFFECT_CV_FFDA]));
    affect_cv_result_free(a);
    affect_cv_result_free(b);

    /* out of memory: FPCA and FFDA, leave one performer out on 3 performers' waves */
    affect_hmm_seq seqs[24];
    uint32_t y[24], g3[24], n = 0;
    for (uint32_t i = 0; i < d->n; i++)
        if (d->action[i] == 1 && d->seed[i] <= 3) {
            seqs[n] = d->seqs[i];
            y[n] = d->y[i];
            g3[n++] = d->seed[i] - 1;
        }
    fda_cv_config(&cfg, d->feat);
    cfg.methods = (1u << AFFECT_CV_FPCA) | (1u << AFFECT_CV_FFDA);
    cfg.fda.n_basis = 8;
    oom_ctx o = {&cfg, d, seqs, y, g3, n, 3, NULL, 4};
    long allocs = tu_oom_sweep(oom_cv, &o, oom_finish, NULL);
    printf("allocations: functional, 3 groups %ld\n", allocs);
    assert_true(allocs > 50);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_stratified_folds), cmocka_unit_test(test_kfold),
        cmocka_unit_test(test_no_leakage),       cmocka_unit_test(test_leave_one_group_out),
        cmocka_unit_test(test_errors),           cmocka_unit_test(test_small_and_out_of_memory),
        cmocka_unit_test(test_threads),          cmocka_unit_test(test_functional),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
