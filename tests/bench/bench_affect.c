/*
 * bench_affect.c — the emotion recognizer (affect/classifier.h, affect/crossval.h) on the real
 * corpus, on one core: training, evaluation throughput (Fisher scores under the class HMMs,
 * normalization, SVM, sPCA, kNN), the Fisher score alone, the whole 10-fold cross-validation,
 * and a breakdown of one fold's work by piece (class HMMs, Fisher scores, libsvm, sPCA + kNN).
 *
 * Usage:
 *     bench_affect [corpus directory] [--repeat N] [--cv-runs N] [--fold-runs N] [--fold K]
 *     AFFECT_BENCH_ONLY=bench_affect bash tests/bench/run.sh   # Release, one core, one thread
 * --repeat N fixes the passes per run of the evaluation kernels (default: calibrated);
 * --cv-runs and --fold-runs the runs of parts 2 and 3 (default 3); --fold K the fold of part 3.
 * The directory defaults to AFFECT_BENCH_CORPUS (${AFFECT_SHARED_DIR}/corpora/bandai-namco-1/
 * data, set by tests/bench/CMakeLists.txt). When it is absent the program says so and exits 0.
 * Run it with OPENBLAS_NUM_THREADS=1 (run.sh does): it prints OpenBLAS's configuration and
 * thread count, and warns when that count is not 1.
 *
 * Data set: the 44 motions sql/affect_eval.sql's eval_data selects from the demo database —
 * emotion angry, happy, sad or normal and content walk, run, dash, walk-back, walk-left,
 * walk-right, bow, bye, byebye or guide (11 per emotion: walk has two takes). Content and
 * emotion come from the file name as sql/import_bvh.sql derives them: the stem (name without
 * ".bvh") must look like dataset-%_%_%_% (SQL LIKE: "dataset-" then at least three '_'); the
 * content is the text between its first and second '_', the emotion the text between the
 * second and third. Motions are taken in stem order (the demo's row order; checked: the demo's
 * motions table lists them in that order) and the classes in byte order (angry, happy, normal,
 * sad), as affect_crossval orders its labels, so the folds are the SQL function's. The program
 * refuses (exit status 1) any other count than 44 motions, 11 per emotion.
 *
 * Configuration ("the full-body configuration"): affect_features with every joint of the
 * first motion, normalize, the automatic scale (the right arm's length: unit "arm"), no
 * velocity; affect_classifier_config_default with the HMM at 7 states × 4 mixtures, full
 * covariances, seed 7; the folds of affect_crossval with 10 folds and seed 7 (affect_crossval
 * in SQL seeds its folds with the HMM seed too).
 *
 * Measurements (clock_gettime(CLOCK_MONOTONIC); motions and observations are all in memory
 * before any timing):
 *  1. affect_classifier_train on all 44 motions (one call per run), then, with that
 *     classifier, passes over the 44 motions:
 *        eval (full)     affect_classifier_eval with ml_only = false: Fisher scores under the
 *                        4 class HMMs, z-scores, SVM, sPCA embedding, kNN — what
 *                        affect_classify and affect_crossval pay per motion;
 *        eval (ML only)  affect_classifier_eval with ml_only = true: the 4 forward passes;
 *        fisher (1 HMM)  affect_fisher_score of every motion under the first class HMM alone.
 *     As bench_laban: bench_measure (benchutil.h) — an untimed warm-up, 5 runs, the median run
 *     with the fastest and slowest; training one call per run, the passes calibrated so that a
 *     run takes about a second (or --repeat).
 *  2. affect_crossval (stratified 10-fold, seed 7) on the 44 motions, --cv-runs times (3;
 *     --threads N runs N folds at once; --cv-only measures this alone, as run.sh does a second
 *     time, unpinned, with --threads 2;
 *     no warm-up: a run trains 10 classifiers), median, fastest and slowest wall time against
 *     the goal of CV_GOAL_SECONDS, each run's CPU time next to it (CLOCK_PROCESS_CPUTIME_ID:
 *     less than the wall time when another process shared the core); the accuracies it
 *     reports; and from the progress callback the time of each fold in the median run.
 *  3. One typical fold — the fold whose time is the median of the median run's folds (or
 *     --fold K, 1-based) — done again by calling the pieces directly, in the classifier's
 *     order and with its arguments (classifier.c's affect_classifier_train and
 *     affect_classifier_eval), --fold-runs times (3), the median of each piece:
 *        class HMMs        affect_hmm_train for each of the 4 classes on its training motions;
 *        fisher (train)    affect_fisher_score of every training motion under the 4 HMMs;
 *        fisher (test)     the same for the held-out motions;
 *        z-scores          the normalization fitted on the training rows and applied to them
 *                          (a copy of classifier.c's fit_normalization, static there) and to
 *                          the held-out rows;
 *        libsvm select C   affect_svm_select_c over AFFECT_CLASSIFIER_C_GRID, 5 inner folds;
 *        libsvm train      affect_svm_train with that C;
 *        sPCA + kNN        affect_spca_fit, the training rows embedded, leave-one-out kNN
 *                          (the training report), and the held-out motions embedded and
 *                          classified;
 *        predictions       the SVM on the training rows (the training report) and on the
 *                          held-out rows.
 *     Both libsvm pieces compute the Gram matrix X Xᵀ of the training rows (affect_svm_gram,
 *     cblas_dsyrk), which is timed alone too: "gram" says how much of libsvm's share is BLAS.
 *     The library now streams: it adds the Gram matrix block by block (one class HMM's scores
 *     at a time), fits the SVM and sPCA in the dual and computes the scores a second time for
 *     the weights; these pieces do the same work on the whole n × D matrix at once, so the
 *     pieces' sum undercounts the library's second pass of Fisher scores.
 *     The pieces are checked against the library: affect_classifier_train and
 *     affect_classifier_eval on the same fold must give the same C, the same sPCA eigenvalues
 *     (to 1e-9 of the largest: the Gram matrix is summed in another order) and the same labels
 * (else exit status 1: the breakdown would not be the fold's work); the time of that (the whole
 * fold) is reported next to the sum of the pieces. Output: tables for people, then one line per
 * metric for scripts: BENCH <metric> <value> <unit> e.g. "BENCH affect_crossval_10fold 21.3 s".
 * Exit status 1 if a computation fails.
 */
#define _DEFAULT_SOURCE /* getloadavg */
#define _POSIX_C_SOURCE 200809L

#include "affect/classifier.h"
#include "affect/crossval.h"
#include "affect/features.h"
#include "affect/fisher.h"
#include "affect/hmm.h"
#include "affect/io.h"
#include "affect/motion.h"
#include "affect/spca.h"
#include "affect/svm.h"

#include <cblas.h>
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <time.h>

#define BENCH_NAME "bench_affect"
#include "benchutil.h"

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS "../shared/corpora/bandai-namco-1/data"
#endif

#define N_CLASSES 4u
#define EXPECTED_MOTIONS 44u
#define EXPECTED_PER_CLASS 11u
#define N_STATES 7u
#define N_MIX 4u
#define SEED 7u
#define CV_FOLDS 10u
#define CV_RUNS 3u
#define FOLD_RUNS 3u
#define MAX_RUNS 25u
#define CV_GOAL_SECONDS 30.0

/* The classes in byte order, as affect_train and affect_crossval order their labels. */
static const char *const emotions[N_CLASSES] = {"angry", "happy", "normal", "sad"};
static const char *const contents[] = {"walk",       "run", "dash", "walk-back", "walk-left",
                                       "walk-right", "bow", "bye",  "byebye",    "guide"};

typedef struct item {
    char *stem;
    uint32_t y;
    affect_motion *m;
    double *x; /* T × dim observations */
    uint32_t T;
} item;

typedef struct dataset {
    item *it;
    uint32_t n, cap;
    uint64_t frames;
    affect_features *feat;
    uint32_t dim;
    affect_hmm_seq *seqs;
    uint32_t *y;
    affect_classifier_config cfg;
} dataset;

/* Values the timed loops write so the compiler cannot drop their work. */
static volatile double g_sink;

/* ---- the data set ---- */

static int cmp_stem(const void *a, const void *b)
{
    return strcmp(((const item *)a)->stem, ((const item *)b)->stem);
}

static int lower(int c)
{
    return c >= 'A' && c <= 'Z' ? c - 'A' + 'a' : c;
}

/* Whether s starts (ends) with the ASCII text t, ignoring case as SQL's LIKE does. */
static bool starts_with(const char *s, const char *t)
{
    for (; *t; s++, t++)
        if (lower((unsigned char)*s) != lower((unsigned char)*t))
            return false;
    return true;
}

static bool ends_with(const char *s, const char *t)
{
    size_t n = strlen(s), k = strlen(t);
    return n >= k && starts_with(s + n - k, t);
}

/* The class of a file name as sql/import_bvh.sql and affect_eval.sql's eval_data see it:
 * UINT32_MAX when the name is not selected. */
static uint32_t class_of(const char *stem)
{
    if (!starts_with(stem, "dataset-"))
        return UINT32_MAX;
    unsigned underscores = 0;
    for (const char *p = stem + strlen("dataset-"); *p; p++)
        underscores += *p == '_';
    if (underscores < 3)
        return UINT32_MAX;
    const char *content = strchr(stem, '_') + 1;
    const char *emotion = strchr(content, '_') + 1;
    const char *end = strchr(emotion, '_');
    size_t content_len = (size_t)(emotion - 1 - content), emotion_len = (size_t)(end - emotion);
    bool known = false;
    for (size_t k = 0; k < sizeof contents / sizeof contents[0]; k++)
        known = known || (strlen(contents[k]) == content_len &&
                          memcmp(contents[k], content, content_len) == 0);
    if (!known)
        return UINT32_MAX;
    for (uint32_t k = 0; k < N_CLASSES; k++)
        if (strlen(emotions[k]) == emotion_len && memcmp(emotions[k], emotion, emotion_len) == 0)
            return k;
    return UINT32_MAX;
}

static void free_dataset(dataset *d)
{
    for (uint32_t i = 0; i < d->n; i++) {
        free(d->it[i].stem);
        affect_motion_free(d->it[i].m);
        affect_free(d->it[i].x);
    }
    free(d->it);
    free(d->seqs);
    free(d->y);
    affect_features_free(d->feat);
    memset(d, 0, sizeof *d);
}

/* The selected *.bvh of dir, sorted by stem and parsed; 1 when dir cannot be opened, 2 on any
 * other error (message printed). */
static int load_corpus(const char *dir, dataset *d)
{
    DIR *dh = opendir(dir);
    if (!dh)
        return 1;
    int rc = 0;
    struct dirent *de;
    while (!rc && (de = readdir(dh)) != NULL) {
        if (!ends_with(de->d_name, ".bvh"))
            continue;
        size_t len = strlen(de->d_name) - 4;
        char *stem = malloc(len + 1);
        if (!stem) {
            rc = 2;
            break;
        }
        memcpy(stem, de->d_name, len);
        stem[len] = '\0';
        uint32_t y = class_of(stem);
        if (y == UINT32_MAX) {
            free(stem);
            continue;
        }
        if (d->n == d->cap) {
            uint32_t cap = d->cap ? 2 * d->cap : 64;
            item *grown = realloc(d->it, cap * sizeof *grown);
            if (!grown) {
                free(stem);
                rc = 2;
                break;
            }
            d->it = grown;
            d->cap = cap;
        }
        d->it[d->n++] = (item){.stem = stem, .y = y};
    }
    closedir(dh);
    if (rc) {
        fprintf(stderr, "bench_affect: out of memory\n");
        return rc;
    }
    qsort(d->it, d->n, sizeof *d->it, cmp_stem);
    char path[4096];
    for (uint32_t i = 0; i < d->n; i++) {
        snprintf(path, sizeof path, "%s/%s.bvh", dir, d->it[i].stem);
        size_t len = 0;
        char *text = bench_read_file(path, &len);
        if (!text) {
            fprintf(stderr, "bench_affect: cannot read %s: %s\n", path, strerror(errno));
            return 2;
        }
        affect_error err;
        affect_status st = affect_bvh_parse(text, len, NULL, &d->it[i].m, &err);
        free(text);
        if (st) {
            fprintf(stderr, "bench_affect: %s.bvh: %s\n", d->it[i].stem, err.msg);
            return 2;
        }
        d->frames += d->it[i].m->n_frames;
    }
    return 0;
}

/* Counts, observations and the configuration; 0 or 1 (message printed). */
static int prepare(dataset *d)
{
    uint32_t per[N_CLASSES] = {0};
    for (uint32_t i = 0; i < d->n; i++)
        per[d->it[i].y]++;
    bool ok = d->n == EXPECTED_MOTIONS;
    for (uint32_t k = 0; k < N_CLASSES; k++)
        ok = ok && per[k] == EXPECTED_PER_CLASS;
    if (!ok) {
        fprintf(stderr,
                "bench_affect: expected %u motions, %u per emotion; found %u (angry %u, "
                "happy %u, normal %u, sad %u)\n",
                EXPECTED_MOTIONS, EXPECTED_PER_CLASS, d->n, per[0], per[1], per[2], per[3]);
        return 1;
    }
    affect_error err;
    affect_features_options fo;
    affect_features_options_default(&fo); /* every joint, normalize, automatic scale, no velocity */
    if (affect_features_create(&fo, d->it[0].m, &d->feat, &err)) {
        fprintf(stderr, "bench_affect: features: %s\n", err.msg);
        return 1;
    }
    d->dim = affect_features_dim(d->feat);
    d->seqs = malloc(d->n * sizeof *d->seqs);
    d->y = malloc(d->n * sizeof *d->y);
    if (!d->seqs || !d->y) {
        fprintf(stderr, "bench_affect: out of memory\n");
        return 1;
    }
    for (uint32_t i = 0; i < d->n; i++) {
        item *e = &d->it[i];
        if (e->m->fps != d->feat->fps || e->m->n_frames < N_STATES) {
            fprintf(stderr, "bench_affect: %s: %g fps (first motion %g), %u frames\n", e->stem,
                    e->m->fps, d->feat->fps, e->m->n_frames);
            return 1;
        }
        if (affect_features_extract(d->feat, e->m, &e->x, &e->T, NULL, &err)) {
            fprintf(stderr, "bench_affect: %s: %s\n", e->stem, err.msg);
            return 1;
        }
        d->seqs[i] = (affect_hmm_seq){e->x, e->T};
        d->y[i] = e->y;
    }
    affect_classifier_config_default(&d->cfg);
    d->cfg.hmm.n_states = N_STATES;
    d->cfg.hmm.n_mix = N_MIX;
    d->cfg.hmm.cov = AFFECT_HMM_FULL;
    d->cfg.hmm.max_iter = 50;
    d->cfg.hmm.seed = SEED;
    d->cfg.descriptors = 0; /* the thesis's configuration, as documented above */
    d->cfg.mirror = AFFECT_MIRROR_OFF;
    d->cfg.hmm.dim = d->dim;
    const char *msg = affect_classifier_config_check(&d->cfg);
    if (msg) {
        fprintf(stderr, "bench_affect: configuration: %s\n", msg);
        return 1;
    }
    return 0;
}

/* ---- small helpers ---- */

static double median_of(const double *v, uint32_t n, double *lo, double *hi)
{
    double s[MAX_RUNS];
    memcpy(s, v, n * sizeof *s);
    qsort(s, n, sizeof *s, cmp_double);
    if (lo)
        *lo = s[0];
    if (hi)
        *hi = s[n - 1];
    return s[n / 2];
}

static double peak_rss_mb(void)
{
    struct rusage ru;
    return getrusage(RUSAGE_SELF, &ru) == 0 ? (double)ru.ru_maxrss / 1024.0 : NAN;
}

static void print_load(const char *when)
{
    double la[3];
    if (getloadavg(la, 3) == 3)
        printf("load average %s: %.2f %.2f %.2f\n", when, la[0], la[1], la[2]);
}

/* ---- 1. training and evaluation throughput ---- */

typedef struct thr_ctx {
    const dataset *d;
    affect_classifier *c; /* the last one trained */
    double *fisher;       /* a Fisher score under one HMM */
    double *dec, *embed, loglik[N_CLASSES];
    uint32_t votes[N_CLASSES];
} thr_ctx;

static int pass_train(void *arg)
{
    thr_ctx *t = arg;
    affect_error err;
    affect_classifier_free(t->c);
    t->c = NULL;
    if (affect_classifier_train(&t->d->cfg, t->d->feat, t->d->seqs, NULL, t->d->y, t->d->n,
                                emotions, N_CLASSES, &t->c, &err)) {
        fprintf(stderr, "bench_affect: training on all motions: %s\n", err.msg);
        return 1;
    }
    return 0;
}

static int eval_pass(thr_ctx *t, bool ml_only)
{
    for (uint32_t i = 0; i < t->d->n; i++) {
        affect_classifier_out o = {
            .loglik = t->loglik, .decision = t->dec, .embed = t->embed, .votes = t->votes};
        affect_error err;
        if (affect_classifier_eval(t->c, t->d->seqs[i].x, t->d->seqs[i].n_frames, NULL, ml_only, &o,
                                   NULL, &err)) {
            fprintf(stderr, "bench_affect: eval of %s: %s\n", t->d->it[i].stem, err.msg);
            return 1;
        }
        g_sink += t->loglik[0] + o.svm + o.knn + o.ml;
    }
    return 0;
}

static int pass_eval(void *arg)
{
    return eval_pass(arg, false);
}

static int pass_eval_ml(void *arg)
{
    return eval_pass(arg, true);
}

static int pass_fisher(void *arg)
{
    thr_ctx *t = arg;
    const affect_classifier_config *cc = affect_classifier_get_config(t->c);
    for (uint32_t i = 0; i < t->d->n; i++) {
        affect_error err;
        double ll;
        if (affect_fisher_score(affect_classifier_hmm(t->c, 0), t->d->seqs[i].x,
                                t->d->seqs[i].n_frames, cc->groups, t->fisher, &ll, NULL, &err)) {
            fprintf(stderr, "bench_affect: Fisher score of %s: %s\n", t->d->it[i].stem, err.msg);
            return 1;
        }
        g_sink += ll + t->fisher[0];
    }
    return 0;
}

typedef struct thr_result {
    result train, eval, eval_ml, fisher;
    affect_classifier_report rep;
} thr_result;

static void thr_row(const char *name, const result *r, const dataset *d)
{
    double s = r->median / r->repeat;
    printf("%-16s %6u %9.3f %9.3f %9.3f %10.2f %10.0f %10.2f\n", name, r->repeat, r->median, r->min,
           r->max, d->n / s, (double)d->frames / s, s / d->n * 1e3);
}

static int bench_throughput(const dataset *d, unsigned repeat, thr_result *out)
{
    thr_ctx t = {.d = d};
    int rc = 1;
    size_t part = affect_fisher_dim(&d->cfg.hmm, d->cfg.groups);
    t.fisher = malloc(part * sizeof *t.fisher);
    t.dec = malloc(N_CLASSES * (N_CLASSES - 1) / 2 * sizeof *t.dec);
    t.embed = malloc(N_CLASSES * sizeof *t.embed); /* sPCA keeps at most C − 1 axes */
    if (!t.fisher || !t.dec || !t.embed) {
        fprintf(stderr, "bench_affect: out of memory\n");
        goto done;
    }
    printf("== 1. one classifier on all %u motions, then evaluation passes over them\n", d->n);
    if (bench_measure(pass_train, &t, 1, &out->train))
        goto done;
    affect_classifier_get_report(t.c, &out->rep);
    printf("trained: C = %g (inner 5-fold accuracy %.3f), sPCA %u axes; training accuracy: ML "
           "%.3f, SVM %.3f, kNN (leave-one-out) %.3f\n\n",
           out->rep.svm_c, out->rep.svm_cv_acc, affect_spca_dims(affect_classifier_spca(t.c)),
           out->rep.train_acc_ml, out->rep.train_acc_svm, out->rep.train_acc_knn);
    if (bench_measure(pass_eval, &t, repeat, &out->eval) ||
        bench_measure(pass_eval_ml, &t, repeat, &out->eval_ml) ||
        bench_measure(pass_fisher, &t, repeat, &out->fisher))
        goto done;
    printf("%-16s %6s %9s %9s %9s %10s %10s %10s\n", "kernel", "passes", "median", "fastest",
           "slowest", "motions/s", "frames/s", "ms/motion");
    printf("%-16s %6u %9.3f %9.3f %9.3f %10.4f %10s %10.1f\n", "train (44)", out->train.repeat,
           out->train.median, out->train.min, out->train.max, 1.0 / out->train.median, "-",
           out->train.median * 1e3);
    thr_row("eval (full)", &out->eval, d);
    thr_row("eval (ML only)", &out->eval_ml, d);
    thr_row("fisher (1 HMM)", &out->fisher, d);
    double ev = out->eval.median / out->eval.repeat, ml = out->eval_ml.median / out->eval_ml.repeat;
    double fi = out->fisher.median / out->fisher.repeat;
    printf("\ntrain: one call per run (motions/s = trainings/s); the passes: every motion "
           "once.\n4 Fisher scores (4 x fisher (1 HMM)) are %.1f%% of eval (full); the rest "
           "(normalization, SVM, sPCA, kNN) %.1f%%; eval (full) costs %.1fx eval (ML only)\n\n",
           100.0 * 4 * fi / ev, 100.0 * (ev - 4 * fi) / ev, ev / ml);
    rc = 0;
done:
    affect_classifier_free(t.c);
    free(t.fisher);
    free(t.dec);
    free(t.embed);
    return rc;
}

/* ---- 2. the whole cross-validation ---- */

typedef struct cv_clock {
    double start, *at; /* at[f]: when fold f ended */
    uint32_t n;
} cv_clock;

static void cv_progress(void *ctx, const char *line)
{
    (void)line;
    cv_clock *c = ctx;
    if (c->n < CV_FOLDS)
        c->at[c->n++] = now();
}

typedef struct cv_summary {
    double median, min, max, cpu; /* cpu: CPU seconds of the median run */
    double fold_s[CV_FOLDS];      /* the median run's folds */
    uint32_t typical;             /* 0-based: the fold of median time */
    double mean_acc[AFFECT_CV_METHODS], pooled_acc[AFFECT_CV_METHODS];
} cv_summary;

static int bench_crossval(const dataset *d, uint32_t runs, uint32_t threads, cv_summary *s)
{
    printf("== 2. affect_crossval: stratified %u-fold, seed %u, %u runs, %u thread%s\n", CV_FOLDS,
           SEED, runs, threads, threads == 1 ? "" : "s (folds in parallel)");
    double t[MAX_RUNS], cpu[MAX_RUNS], folds[MAX_RUNS][CV_FOLDS];
    affect_cv_result *res[MAX_RUNS] = {0};
    int rc = 1;
    for (uint32_t run = 0; run < runs; run++) {
        affect_cv_config cfg;
        affect_cv_config_default(&cfg);
        cfg.cls = d->cfg;
        cfg.folds = CV_FOLDS;
        cfg.seed = SEED;
        cfg.threads = threads;
        double at[CV_FOLDS];
        cv_clock clk = {.at = at};
        cfg.progress = cv_progress;
        cfg.progress_ctx = &clk;
        affect_error err;
        double c0 = cpu_now();
        clk.start = now();
        affect_status st = affect_crossval(&cfg, d->feat, d->seqs, NULL, d->y, d->n, emotions,
                                           N_CLASSES, NULL, 0, &res[run], &err);
        t[run] = now() - clk.start;
        cpu[run] = cpu_now() - c0;
        if (st) {
            fprintf(stderr, "bench_affect: affect_crossval: %s\n", err.msg);
            goto done;
        }
        if (clk.n != CV_FOLDS) {
            fprintf(stderr, "bench_affect: affect_crossval ran %u folds, expected %u\n", clk.n,
                    CV_FOLDS);
            goto done;
        }
        for (uint32_t f = 0; f < CV_FOLDS; f++)
            folds[run][f] = at[f] - (f ? at[f - 1] : clk.start);
        printf("run %u: %.2f s wall, %.2f s CPU (%.0f%% of the core)\n", run + 1, t[run], cpu[run],
               100.0 * cpu[run] / t[run]);
        fflush(stdout);
    }
    s->median = median_of(t, runs, &s->min, &s->max);
    uint32_t mr = 0;
    for (uint32_t run = 0; run < runs; run++)
        if (t[run] == s->median)
            mr = run;
    s->cpu = cpu[mr];
    memcpy(s->fold_s, folds[mr], sizeof s->fold_s);
    const affect_cv_result *r = res[mr];
    for (int m = 0; m < AFFECT_CV_RECOGNIZER_METHODS; m++) {
        s->mean_acc[m] = r->mean_accuracy[m];
        s->pooled_acc[m] = r->pooled_accuracy[m];
    }
    double sorted[CV_FOLDS];
    memcpy(sorted, s->fold_s, sizeof sorted);
    qsort(sorted, CV_FOLDS, sizeof *sorted, cmp_double);
    double typical_s = sorted[(CV_FOLDS - 1) / 2]; /* a fold's own time (lower median) */
    for (uint32_t f = 0; f < CV_FOLDS; f++)
        if (s->fold_s[f] == typical_s)
            s->typical = f;

    printf("\nwall time: median %.2f s (fastest %.2f, slowest %.2f; the median run used %.2f s "
           "of CPU); goal <= %.0f s: %s\n",
           s->median, s->min, s->max, s->cpu, CV_GOAL_SECONDS,
           s->median <= CV_GOAL_SECONDS ? "met" : "NOT met");
    printf("accuracy, mean +- sd over folds (pooled): ML %.3f +- %.3f (%.3f), Fisher + SVM "
           "%.3f +- %.3f (%.3f), Fisher + sPCA + kNN %.3f +- %.3f (%.3f)\n",
           r->mean_accuracy[AFFECT_CV_ML], r->sd_accuracy[AFFECT_CV_ML],
           r->pooled_accuracy[AFFECT_CV_ML], r->mean_accuracy[AFFECT_CV_SVM],
           r->sd_accuracy[AFFECT_CV_SVM], r->pooled_accuracy[AFFECT_CV_SVM],
           r->mean_accuracy[AFFECT_CV_KNN], r->sd_accuracy[AFFECT_CV_KNN],
           r->pooled_accuracy[AFFECT_CV_KNN]);
    printf("\nfolds of the median run:\n%-5s %6s %5s %8s %7s %6s %6s %6s\n", "fold", "train",
           "test", "seconds", "svm C", "ml", "svm", "knn");
    for (uint32_t f = 0; f < r->n_folds; f++) {
        const affect_cv_fold *fd = &r->folds[f];
        printf("%-5u %6u %5u %8.2f %7g %6.2f %6.2f %6.2f%s\n", fd->fold + 1, fd->n_train,
               fd->n_test, s->fold_s[f], fd->svm_c, fd->accuracy[AFFECT_CV_ML],
               fd->accuracy[AFFECT_CV_SVM], fd->accuracy[AFFECT_CV_KNN],
               f == s->typical ? "  <- typical (median time)" : "");
    }
    printf("\n");
    rc = 0;
done:
    for (uint32_t run = 0; run < runs; run++)
        affect_cv_result_free(res[run]);
    return rc;
}

/* ---- 3. one fold, piece by piece ---- */

enum {
    P_HMM,
    P_FISHER_TRAIN,
    P_FISHER_TEST,
    P_ZSCORE,
    P_SELECT_C,
    P_SVM_TRAIN,
    P_SPCA_KNN,
    P_PREDICT,
    P_COUNT
};
static const char *const piece_names[P_COUNT] = {
    "class HMMs x4",   "fisher (train)", "fisher (test)", "z-scores",
    "libsvm select C", "libsvm train",   "sPCA + kNN",    "predictions"};
static const char *const piece_keys[P_COUNT] = {"hmm_train", "fisher_train", "fisher_test",
                                                "zscore",    "svm_select_c", "svm_train",
                                                "spca_knn",  "predict"};

/* What one fold's pieces produce (for the check against the library). */
typedef struct fold_out {
    double C, eig[N_CLASSES];
    uint32_t p, iters[N_CLASSES]; /* iters: Baum–Welch iterations of the class HMMs */
    uint32_t ml[EXPECTED_MOTIONS], svm[EXPECTED_MOTIONS], knn[EXPECTED_MOTIONS];
} fold_out;

/* A copy of classifier.c's fit_normalization (static there): per dimension divided by its
 * largest magnitude first, mean and population sd, constant dimensions centred only, z-scores
 * clipped to ±clip. */
static void fit_normalization(double *f, uint32_t n, size_t D, double clip, double *mean,
                              double *scale)
{
    for (size_t e = 0; e < D; e++) {
        double a = 0.0, mu = 0.0, var = 0.0;
        mean[e] = 0.0;
        scale[e] = 1.0;
        for (uint32_t i = 0; i < n; i++)
            if (fabs(f[(size_t)i * D + e]) > a)
                a = fabs(f[(size_t)i * D + e]);
        if (a == 0.0)
            continue;
        for (uint32_t i = 0; i < n; i++)
            mu += f[(size_t)i * D + e] / a;
        mu /= n;
        for (uint32_t i = 0; i < n; i++) {
            double v = f[(size_t)i * D + e] / a - mu;
            var += v * v;
        }
        double sd = sqrt(var / n), sc = sd * a;
        mean[e] = mu * a;
        if (sd > 0 && sc > 0 && isfinite(sc))
            scale[e] = sc;
        for (uint32_t i = 0; i < n; i++) { /* the library applies evaluation's formula */
            double z = (f[(size_t)i * D + e] - mean[e]) / scale[e];
            f[(size_t)i * D + e] = clip > 0 ? (z > clip ? clip : z < -clip ? -clip : z) : z;
        }
    }
}

/* Rows of Fisher scores of the listed motions under the HMMs into f (n × D), as classifier.c's
 * represent: infinite entries become ±DBL_MAX, NaN is an error. */
static int fisher_rows(const dataset *d, affect_hmm *const *h, const uint32_t *idx, uint32_t n,
                       size_t part, double *f, double *ll)
{
    size_t D = part * N_CLASSES;
    for (uint32_t i = 0; i < n; i++) {
        const affect_hmm_seq *s = &d->seqs[idx[i]];
        for (uint32_t k = 0; k < N_CLASSES; k++) {
            affect_error err;
            double *row = f + (size_t)i * D + k * part;
            if (affect_fisher_score(h[k], s->x, s->n_frames, d->cfg.groups, row,
                                    &ll[(size_t)i * N_CLASSES + k], NULL, &err)) {
                fprintf(stderr, "bench_affect: Fisher score of %s under class %s: %s\n",
                        d->it[idx[i]].stem, emotions[k], err.msg);
                return 1;
            }
            for (size_t e = 0; e < part; e++) {
                if (isnan(row[e])) {
                    fprintf(stderr, "bench_affect: %s: Fisher score entry %zu is NaN\n",
                            d->it[idx[i]].stem, e);
                    return 1;
                }
                if (isinf(row[e]))
                    row[e] = row[e] > 0 ? DBL_MAX : -DBL_MAX;
            }
        }
    }
    return 0;
}

static uint32_t argmax(const double *v, uint32_t n)
{
    uint32_t best = 0;
    for (uint32_t k = 1; k < n; k++)
        if (v[k] > v[best])
            best = k;
    return best;
}

/* One fold by its pieces; t[P_*] receives the seconds, *gram_s one affect_svm_gram. */
static int fold_pieces(const dataset *d, const uint32_t *fold_of, uint32_t fold, double *t,
                       double *gram_s, fold_out *o)
{
    const affect_classifier_config *cfg = &d->cfg;
    uint32_t tr[EXPECTED_MOTIONS], te[EXPECTED_MOTIONS], n_tr = 0, n_te = 0;
    uint32_t ytr[EXPECTED_MOTIONS];
    for (uint32_t i = 0; i < d->n; i++) {
        if (fold_of[i] == fold) {
            te[n_te++] = i;
        } else {
            ytr[n_tr] = d->y[i];
            tr[n_tr++] = i;
        }
    }
    size_t part = affect_fisher_dim(&cfg->hmm, cfg->groups), D = part * N_CLASSES;
    affect_hmm *h[N_CLASSES] = {0};
    affect_hmm_seq mine[EXPECTED_MOTIONS];
    double *ftr = malloc((size_t)n_tr * D * sizeof *ftr);
    double *fte = malloc((size_t)n_te * D * sizeof *fte);
    double *mean = malloc(D * sizeof *mean), *scale = malloc(D * sizeof *scale);
    double *gram = malloc((size_t)n_tr * n_tr * sizeof *gram);
    double ll_tr[EXPECTED_MOTIONS * N_CLASSES], ll_te[EXPECTED_MOTIONS * N_CLASSES];
    double *ztr = NULL;
    affect_svm *svm = NULL;
    affect_spca *spca = NULL;
    affect_error err;
    int rc = 1;
    if (!ftr || !fte || !mean || !scale || !gram) {
        fprintf(stderr, "bench_affect: out of memory\n");
        goto done;
    }

    double t0 = now();
    for (uint32_t k = 0; k < N_CLASSES; k++) {
        uint32_t count = 0;
        for (uint32_t i = 0; i < n_tr; i++)
            if (ytr[i] == k)
                mine[count++] = d->seqs[tr[i]];
        if (affect_hmm_train(&cfg->hmm, mine, count, &h[k], &err)) {
            fprintf(stderr, "bench_affect: HMM of class %s: %s\n", emotions[k], err.msg);
            goto done;
        }
    }
    t[P_HMM] = now() - t0;
    for (uint32_t k = 0; k < N_CLASSES; k++) {
        affect_hmm_report rep;
        affect_hmm_get_report(h[k], &rep);
        o->iters[k] = rep.iterations;
    }

    t0 = now();
    if (fisher_rows(d, h, tr, n_tr, part, ftr, ll_tr))
        goto done;
    t[P_FISHER_TRAIN] = now() - t0;
    t0 = now();
    if (fisher_rows(d, h, te, n_te, part, fte, ll_te))
        goto done;
    t[P_FISHER_TEST] = now() - t0;

    t0 = now();
    fit_normalization(ftr, n_tr, D, cfg->score_clip, mean, scale);
    for (uint32_t i = 0; i < n_te; i++)
        for (size_t e = 0; e < D; e++) {
            double z = (fte[(size_t)i * D + e] - mean[e]) / scale[e], c = cfg->score_clip;
            fte[(size_t)i * D + e] = c > 0 ? (z > c ? c : z < -c ? -c : z) : z;
        }
    t[P_ZSCORE] = now() - t0;

    static const double grid[] = AFFECT_CLASSIFIER_C_GRID;
    double C, cv;
    t0 = now();
    if (affect_svm_select_c(ftr, n_tr, D, ytr, N_CLASSES, grid, sizeof grid / sizeof grid[0],
                            cfg->svm_folds, cfg->hmm.seed, &C, &cv, &err)) {
        fprintf(stderr, "bench_affect: affect_svm_select_c: %s\n", err.msg);
        goto done;
    }
    t[P_SELECT_C] = now() - t0;
    t0 = now();
    if (affect_svm_train(ftr, n_tr, D, ytr, N_CLASSES, C, &svm, &err)) {
        fprintf(stderr, "bench_affect: affect_svm_train: %s\n", err.msg);
        goto done;
    }
    t[P_SVM_TRAIN] = now() - t0;
    t0 = now();
    if (affect_svm_gram(ftr, n_tr, D, gram, &err)) {
        fprintf(stderr, "bench_affect: affect_svm_gram: %s\n", err.msg);
        goto done;
    }
    *gram_s = now() - t0;
    g_sink += gram[0];

    t0 = now();
    if (affect_spca_fit(ftr, n_tr, D, ytr, N_CLASSES, cfg->spca_kernel, cfg->spca_sigma,
                        cfg->spca_dims, &spca, &err)) {
        fprintf(stderr, "bench_affect: affect_spca_fit: %s\n", err.msg);
        goto done;
    }
    uint32_t p = affect_spca_dims(spca);
    ztr = malloc((size_t)n_tr * p * sizeof *ztr);
    if (!ztr) {
        fprintf(stderr, "bench_affect: out of memory\n");
        goto done;
    }
    affect_spca_embed_rows(spca, ftr, n_tr, ztr);
    {
        /* leave-one-out over the training coordinates, as classifier.c's loo_knn */
        double zo[EXPECTED_MOTIONS * N_CLASSES];
        uint32_t yo[EXPECTED_MOTIONS], hits = 0;
        for (uint32_t i = 0; i < n_tr; i++) {
            for (uint32_t j = 0, q = 0; j < n_tr; j++) {
                if (j == i)
                    continue;
                memcpy(zo + (size_t)q * p, ztr + (size_t)j * p, p * sizeof *zo);
                yo[q++] = ytr[j];
            }
            uint32_t label;
            if (affect_knn_classify(zo, yo, n_tr - 1, p, N_CLASSES, ztr + (size_t)i * p, cfg->knn_k,
                                    &label, NULL, &err)) {
                fprintf(stderr, "bench_affect: leave-one-out kNN: %s\n", err.msg);
                goto done;
            }
            hits += label == ytr[i];
        }
        g_sink += hits;
    }
    for (uint32_t i = 0; i < n_te; i++) {
        double z[N_CLASSES];
        affect_spca_embed(spca, fte + (size_t)i * D, z);
        if (affect_knn_classify(ztr, ytr, n_tr, p, N_CLASSES, z, cfg->knn_k, &o->knn[i], NULL,
                                &err)) {
            fprintf(stderr, "bench_affect: kNN: %s\n", err.msg);
            goto done;
        }
    }
    t[P_SPCA_KNN] = now() - t0;

    t0 = now();
    {
        uint32_t hits = 0;
        for (uint32_t i = 0; i < n_tr; i++)
            hits += affect_svm_predict(svm, ftr + (size_t)i * D, NULL) == ytr[i];
        g_sink += hits;
    }
    for (uint32_t i = 0; i < n_te; i++) {
        o->svm[i] = affect_svm_predict(svm, fte + (size_t)i * D, NULL);
        o->ml[i] = argmax(ll_te + (size_t)i * N_CLASSES, N_CLASSES);
    }
    t[P_PREDICT] = now() - t0;

    o->C = C;
    o->p = p;
    memcpy(o->eig, affect_spca_eigenvalues(spca), p * sizeof *o->eig);
    rc = 0;
done:
    for (uint32_t k = 0; k < N_CLASSES; k++)
        affect_hmm_free(h[k]);
    affect_svm_free(svm);
    affect_spca_free(spca);
    free(ftr);
    free(fte);
    free(mean);
    free(scale);
    free(gram);
    free(ztr);
    return rc;
}

/* The same fold through the library (what affect_crossval's run_fold does); *secs its time. */
static int fold_library(const dataset *d, const uint32_t *fold_of, uint32_t fold, double *secs,
                        fold_out *o)
{
    affect_hmm_seq seqs[EXPECTED_MOTIONS];
    uint32_t y[EXPECTED_MOTIONS], n_tr = 0, n_te = 0;
    affect_classifier *c = NULL;
    affect_error err;
    int rc = 1;
    double t0 = now();
    for (uint32_t i = 0; i < d->n; i++)
        if (fold_of[i] != fold) {
            seqs[n_tr] = d->seqs[i];
            y[n_tr++] = d->y[i];
        }
    if (affect_classifier_train(&d->cfg, d->feat, seqs, NULL, y, n_tr, emotions, N_CLASSES, &c,
                                &err)) {
        fprintf(stderr, "bench_affect: affect_classifier_train: %s\n", err.msg);
        goto done;
    }
    for (uint32_t i = 0; i < d->n; i++) {
        if (fold_of[i] != fold)
            continue;
        affect_classifier_out out = {0};
        if (affect_classifier_eval(c, d->seqs[i].x, d->seqs[i].n_frames, NULL, false, &out, NULL,
                                   &err)) {
            fprintf(stderr, "bench_affect: affect_classifier_eval: %s\n", err.msg);
            goto done;
        }
        o->ml[n_te] = out.ml;
        o->svm[n_te] = out.svm;
        o->knn[n_te++] = out.knn;
    }
    *secs = now() - t0;
    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    o->C = rep.svm_c;
    o->p = affect_spca_dims(affect_classifier_spca(c));
    memcpy(o->eig, affect_spca_eigenvalues(affect_classifier_spca(c)), o->p * sizeof *o->eig);
    rc = 0;
done:
    affect_classifier_free(c);
    return rc;
}

typedef struct fold_summary {
    uint32_t fold, n_train, n_test;
    double piece[P_COUNT], gram, sum, whole;
} fold_summary;

static int bench_fold(const dataset *d, uint32_t fold, uint32_t runs, double cv_fold_s,
                      fold_summary *s)
{
    uint32_t fold_of[EXPECTED_MOTIONS];
    affect_error err;
    if (affect_stratified_folds(d->y, d->n, N_CLASSES, CV_FOLDS, SEED, fold_of, &err)) {
        fprintf(stderr, "bench_affect: folds: %s\n", err.msg);
        return 1;
    }
    s->fold = fold;
    s->n_test = 0;
    for (uint32_t i = 0; i < d->n; i++)
        s->n_test += fold_of[i] == fold;
    s->n_train = d->n - s->n_test;
    printf("== 3. fold %u (%u training, %u held out), piece by piece, %u runs\n", fold + 1,
           s->n_train, s->n_test, runs);
    double t[P_COUNT][MAX_RUNS], gram[MAX_RUNS], whole[MAX_RUNS], lo[P_COUNT], hi[P_COUNT];
    for (uint32_t run = 0; run < runs; run++) {
        double tt[P_COUNT] = {0};
        fold_out a, b;
        memset(&a, 0, sizeof a);
        memset(&b, 0, sizeof b);
        if (fold_pieces(d, fold_of, fold, tt, &gram[run], &a) ||
            fold_library(d, fold_of, fold, &whole[run], &b))
            return 1;
        for (int k = 0; k < P_COUNT; k++)
            t[k][run] = tt[k];
        bool same = a.C == b.C && a.p == b.p && memcmp(a.ml, b.ml, sizeof a.ml) == 0 &&
                    memcmp(a.svm, b.svm, sizeof a.svm) == 0 &&
                    memcmp(a.knn, b.knn, sizeof a.knn) == 0;
        for (uint32_t q = 0; same && q < a.p; q++) /* the library sums G block by block */
            same = fabs(a.eig[q] - b.eig[q]) <= 1e-9 * fabs(b.eig[0]);
        if (!same) {
            fprintf(stderr,
                    "bench_affect: the pieces do not reproduce the classifier on fold "
                    "%u (C %g vs %g, %u vs %u sPCA axes, or other labels)\n",
                    fold + 1, a.C, b.C, a.p, b.p);
            return 1;
        }
        if (run == 0) {
            printf("check: the pieces reproduce affect_classifier_train + eval on this fold (C "
                   "= %g, the same sPCA eigenvalues, the same ML, SVM and kNN labels)\n",
                   a.C);
            printf("Baum-Welch iterations of the class HMMs (max_iter %u):", d->cfg.hmm.max_iter);
            for (uint32_t k = 0; k < N_CLASSES; k++)
                printf(" %s %u", emotions[k], a.iters[k]);
            printf("\n");
        }
        fflush(stdout);
    }
    s->sum = 0;
    for (int k = 0; k < P_COUNT; k++) {
        s->piece[k] = median_of(t[k], runs, &lo[k], &hi[k]);
        s->sum += s->piece[k];
    }
    s->gram = median_of(gram, runs, NULL, NULL);
    double wlo, whi;
    s->whole = median_of(whole, runs, &wlo, &whi);
    printf("\n%-17s %9s %9s %9s %9s %9s\n", "piece", "median", "fastest", "slowest", "% pieces",
           "% fold");
    for (int k = 0; k < P_COUNT; k++) {
        printf("%-17s %9.3f %9.3f %9.3f %8.1f%% %8.1f%%\n", piece_names[k], s->piece[k], lo[k],
               hi[k], 100.0 * s->piece[k] / s->sum, 100.0 * s->piece[k] / s->whole);
        if (k == P_SVM_TRAIN)
            printf("%-17s %9.3f %9s %9s %8.1f%% %8.1f%%\n", "  gram (x2)", 2 * s->gram, "", "",
                   100.0 * 2 * s->gram / s->sum, 100.0 * 2 * s->gram / s->whole);
    }
    printf("%-17s %9.3f %9s %9s %8.1f%% %8.1f%%\n", "sum of pieces", s->sum, "", "", 100.0,
           100.0 * s->sum / s->whole);
    printf("%-17s %9.3f %9.3f %9.3f %9s %8.1f%%\n", "whole fold (lib)", s->whole, wlo, whi, "",
           100.0);
    double svm = s->piece[P_SELECT_C] + s->piece[P_SVM_TRAIN], rest = s->sum - svm;
    double fisher = s->piece[P_FISHER_TRAIN] + s->piece[P_FISHER_TEST];
    printf("\n\"gram (x2)\": one affect_svm_gram (cblas_dsyrk) of the training rows, which "
           "select C and train each compute once; it is inside the two libsvm rows.\n"
           "whole fold (lib): affect_classifier_train on the fold's training motions + "
           "affect_classifier_eval of its held-out motions; in the cross-validation runs above "
           "this fold took %.2f s.\n",
           cv_fold_s);
    printf("libsvm training (select C + train): %.3f s = %.1f%% of the pieces; the rest: %.3f s "
           "= %.1f%% (class HMMs %.1f%%, Fisher scores %.1f%%, sPCA + kNN %.1f%%, z-scores and "
           "predictions %.1f%%)\n\n",
           svm, 100.0 * svm / s->sum, rest, 100.0 * rest / s->sum, 100.0 * s->piece[P_HMM] / s->sum,
           100.0 * fisher / s->sum, 100.0 * s->piece[P_SPCA_KNN] / s->sum,
           100.0 * (s->piece[P_ZSCORE] + s->piece[P_PREDICT]) / s->sum);
    return 0;
}

int main(int argc, char **argv)
{
    const char *dir = AFFECT_BENCH_CORPUS;
    uint32_t cv_runs = CV_RUNS, fold_runs = FOLD_RUNS, fold = 0, repeat = 0, threads = 1;
    bool cv_only = false;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) {
            if (bench_parse_count("--repeat", argv[++i], MAX_REPEAT, &repeat))
                return 2;
        } else if (strcmp(argv[i], "--cv-runs") == 0 && i + 1 < argc) {
            if (bench_parse_count("--cv-runs", argv[++i], MAX_RUNS, &cv_runs))
                return 2;
        } else if (strcmp(argv[i], "--fold-runs") == 0 && i + 1 < argc) {
            if (bench_parse_count("--fold-runs", argv[++i], MAX_RUNS, &fold_runs))
                return 2;
        } else if (strcmp(argv[i], "--fold") == 0 && i + 1 < argc) {
            if (bench_parse_count("--fold", argv[++i], CV_FOLDS, &fold))
                return 2;
        } else if (strcmp(argv[i], "--threads") == 0 && i + 1 < argc) {
            if (bench_parse_count("--threads", argv[++i], 64, &threads))
                return 2;
        } else if (strcmp(argv[i], "--cv-only") == 0) {
            cv_only = true;
        } else if (argv[i][0] == '-') {
            fprintf(stderr,
                    "usage: %s [corpus directory] [--repeat N] [--cv-runs N] "
                    "[--fold-runs N] [--fold K] [--threads N] [--cv-only]\n",
                    argv[0]);
            return 2;
        } else {
            dir = argv[i];
        }
    }

    dataset d = {0};
    int lc = load_corpus(dir, &d);
    if (lc == 1) {
        printf("bench_affect: corpus directory %s not found: skipped (nothing measured)\n", dir);
        return 0;
    }
    int rc = 1;
    if (lc || prepare(&d))
        goto done;

    int blas_threads = openblas_get_num_threads();
    print_load("at start");
    printf("openblas: %s; %d thread%s%s\n", openblas_get_config(), blas_threads,
           blas_threads == 1 ? "" : "s",
           blas_threads == 1 ? ""
                             : " (WARNING: set OPENBLAS_NUM_THREADS=1 for single-core numbers)");
    size_t part = affect_fisher_dim(&d.cfg.hmm, d.cfg.groups);
    printf("data set: %s\n  %u motions (angry, happy, normal, sad: 11 each), %llu frames at %g "
           "fps, %u joints -> %u dimensions (unit %s, no velocity)\n",
           dir, d.n, (unsigned long long)d.frames, d.feat->fps, d.feat->n_joints, d.dim,
           d.feat->unit);
    printf("  HMM %u states x %u mixtures, full covariances, seed %u; Fisher score %zu entries "
           "per class HMM, %zu in all\n\n",
           N_STATES, N_MIX, SEED, part, part * N_CLASSES);
    fflush(stdout);

    cv_summary cs = {0};
    if (cv_only) { /* the cross-validation alone (run.sh: unpinned, with --threads 2) */
        if (bench_crossval(&d, cv_runs, threads, &cs))
            goto done;
        printf("BENCH affect_crossval_10fold_threads%u %.2f s\n", threads, cs.median);
        printf("BENCH affect_crossval_10fold_threads%u_cpu %.2f s\n", threads, cs.cpu);
        rc = 0;
        goto done;
    }
    thr_result tr;
    if (bench_throughput(&d, repeat, &tr))
        goto done;
    fflush(stdout);
    if (bench_crossval(&d, cv_runs, threads, &cs))
        goto done;
    fflush(stdout);
    uint32_t f0 = fold ? fold - 1 : cs.typical;
    fold_summary fs;
    if (bench_fold(&d, f0, fold_runs, cs.fold_s[f0], &fs))
        goto done;

    double ev = tr.eval.median / tr.eval.repeat, evml = tr.eval_ml.median / tr.eval_ml.repeat;
    double fi = tr.fisher.median / tr.fisher.repeat, frames = (double)d.frames;
    printf("BENCH affect_train_44 %.3f s\n", tr.train.median);
    printf("BENCH affect_eval_full %.3f motions/s\n", d.n / ev);
    printf("BENCH affect_eval_full_frames %.0f frames/s\n", frames / ev);
    printf("BENCH affect_eval_ml_only %.3f motions/s\n", d.n / evml);
    printf("BENCH affect_eval_ml_only_frames %.0f frames/s\n", frames / evml);
    printf("BENCH fisher_score_1hmm %.3f motions/s\n", d.n / fi);
    printf("BENCH fisher_score_1hmm_frames %.0f frames/s\n", frames / fi);
    printf("BENCH affect_crossval_10fold %.2f s\n", cs.median);
    printf("BENCH affect_crossval_10fold_fastest %.2f s\n", cs.min);
    printf("BENCH affect_crossval_10fold_slowest %.2f s\n", cs.max);
    printf("BENCH affect_crossval_10fold_cpu %.2f s\n", cs.cpu);
    static const char *const methods[AFFECT_CV_METHODS] = {"ml", "svm", "knn"};
    for (int m = 0; m < AFFECT_CV_RECOGNIZER_METHODS; m++)
        printf("BENCH affect_crossval_accuracy_%s %.4f ratio\n", methods[m], cs.mean_acc[m]);
    for (int k = 0; k < P_COUNT; k++)
        printf("BENCH fold_%s %.3f s\n", piece_keys[k], fs.piece[k]);
    printf("BENCH fold_svm_gram %.3f s\n", fs.gram);
    printf("BENCH fold_pieces_sum %.3f s\n", fs.sum);
    printf("BENCH fold_whole %.3f s\n", fs.whole);
    double svm = fs.piece[P_SELECT_C] + fs.piece[P_SVM_TRAIN];
    printf("BENCH fold_libsvm_share %.4f ratio\n", svm / fs.sum);
    printf("BENCH fold_rest_share %.4f ratio\n", (fs.sum - svm) / fs.sum);
    printf("BENCH peak_rss %.1f MB\n", peak_rss_mb());
    print_load("at end");
    rc = 0;
done:
    free_dataset(&d);
    return rc;
}
