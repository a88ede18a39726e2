/*
 * crossval.c — k-fold and leave-one-group-out evaluation of the recognizer (see
 * affect/crossval.h).
 *
 * Usage: see the block at the top of affect/crossval.h (compiled by the style/header-usage test).
 *
 * How it works: the fold of every motion is fixed first (stratified folds, or its group), then
 * fold by fold the training motions are gathered (classes absent from them removed and the
 * others renumbered in order), a classifier is trained on them alone, and each held-out motion
 * is evaluated once (affect_classifier_eval gives all three labels); each functional method asked
 * trains its own affect_fda model on the same training motions and classifies the held-out
 * ones by 1-NN (affect_fda_classify). Nothing of a held-out
 * motion reaches training: the only shared inputs are the configuration and the feature
 * definition (tests/core/test_crossval.c checks this by corrupting the held-out motions).
 */
#include "affect/crossval.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <threads.h>

#define MAX_FOLDS 1024u

void affect_cv_config_default(affect_cv_config *cfg)
{
    memset(cfg, 0, sizeof *cfg);
    affect_classifier_config_default(&cfg->cls);
    cfg->folds = 10;
    cfg->seed = 1;
    cfg->threads = 1;
    cfg->methods = AFFECT_CV_RECOGNIZER_MASK;
    affect_fda_config_default(&cfg->fda);
}

static const char *const method_names[AFFECT_CV_METHODS] = {
    "ml", "svm", "knn", "fpca", "ffda", "fspca", "fspca_rbf", "fisomap"};

const char *affect_cv_method_name(unsigned m)
{
    return m < AFFECT_CV_METHODS ? method_names[m] : NULL;
}

void affect_cv_result_free(affect_cv_result *r)
{
    if (!r)
        return;
    for (uint32_t f = 0; r->folds && f < r->n_folds; f++)
        for (int m = 0; m < AFFECT_CV_METHODS; m++)
            affect_free(r->folds[f].confusion[m]);
    affect_free(r->folds);
    for (int m = 0; m < AFFECT_CV_METHODS; m++)
        affect_free(r->pooled[m]);
    affect_free(r);
}

/* Accuracy, balanced accuracy and macro-F1 of a confusion matrix (C × C). */
static void metrics(const uint32_t *cm, uint32_t C, double *acc, double *bal, double *f1)
{
    uint64_t total = 0, correct = 0;
    double rec_sum = 0.0, f1_sum = 0.0;
    uint32_t rec_n = 0, f1_n = 0;
    for (uint32_t k = 0; k < C; k++) {
        uint64_t row = 0, col = 0, tp = cm[(size_t)k * C + k];
        for (uint32_t j = 0; j < C; j++) {
            row += cm[(size_t)k * C + j];
            col += cm[(size_t)j * C + k];
        }
        total += row;
        correct += tp;
        if (row > 0) {
            rec_sum += (double)tp / (double)row;
            rec_n++;
        }
        if (row > 0 || col > 0) {
            f1_sum += 2.0 * (double)tp / (double)(row + col);
            f1_n++;
        }
    }
    *acc = total ? (double)correct / (double)total : NAN;
    *bal = rec_n ? rec_sum / rec_n : NAN;
    *f1 = f1_n ? f1_sum / f1_n : NAN;
}

/* Mean and sample standard deviation of v[0 .. n) (NaN entries skipped). */
static void mean_sd(const double *v, uint32_t n, double *mean, double *sd)
{
    double s = 0.0;
    uint32_t k = 0;
    for (uint32_t i = 0; i < n; i++)
        if (!isnan(v[i])) {
            s += v[i];
            k++;
        }
    *mean = k ? s / k : NAN;
    double q = 0.0;
    for (uint32_t i = 0; i < n; i++)
        if (!isnan(v[i]))
            q += (v[i] - *mean) * (v[i] - *mean);
    *sd = k > 1 ? sqrt(q / (k - 1)) : NAN;
}

/* Scratch of one fold. */
typedef struct fold_ws {
    affect_hmm_seq *seqs;
    double *desc;        /* the training motions' descriptors (NULL without) */
    uint32_t *y, *map;   /* map: class → index among the present classes, or UINT32_MAX */
    const char **labels; /* present classes' names */
    uint32_t *back;      /* present index → class */
} fold_ws;

static void progress(const affect_cv_config *cfg, const affect_cv_fold *f, uint32_t n_folds)
{
    if (!cfg->progress)
        return;
    char line[512];
    int len = snprintf(line, sizeof line, "fold %u/%u: %u training, %u held out", f->fold + 1,
                       n_folds, f->n_train, f->n_test);
    static const unsigned order[AFFECT_CV_METHODS] = {
        AFFECT_CV_SVM,  AFFECT_CV_KNN,   AFFECT_CV_ML,        AFFECT_CV_FPCA,
        AFFECT_CV_FFDA, AFFECT_CV_FSPCA, AFFECT_CV_FSPCA_RBF, AFFECT_CV_FISOMAP};
    for (unsigned k = 0; k < AFFECT_CV_METHODS && len > 0 && (size_t)len < sizeof line; k++)
        if (cfg->methods & (1u << order[k]))
            len += snprintf(line + len, sizeof line - (size_t)len, ", %s %.3f",
                            method_names[order[k]], f->accuracy[order[k]]);
    cfg->progress(cfg->progress_ctx, line);
}

/* What every fold reads (shared, read-only while folds run). */
typedef struct run_ctx {
    const affect_cv_config *cfg;
    const affect_classifier_config *cls; /* cfg->cls with a silent child of its monitor */
    const affect_features *feat;
    uint32_t m; /* coordinates per frame (affect_features_dim) */
    const affect_hmm_seq *seqs;
    const double *desc;
    uint32_t ddim;
    const uint32_t *y;
    uint32_t n;
    const char *const *labels;
    uint32_t C;
    const uint32_t *fold_of;
    uint32_t k;
    affect_cv_result *r;
} run_ctx;

/* Prefixes err's message with "fold 3: " (or "fold 3, motion 7: "), except out of memory. */
static affect_status fold_fail(affect_status st, uint32_t fold, uint32_t motion, const char *what,
                               affect_error *err)
{
    if (st == AFFECT_ERR_NOMEM)
        return st;
    char msg[AFFECT_ERROR_MSG_MAX];
    memcpy(msg, err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    if (motion == UINT32_MAX)
        return affect_fail(err, st, "fold %u: %s%s", fold + 1, what, msg);
    return affect_fail(err, st, "fold %u, motion %u: %s%s", fold + 1, motion, what, msg);
}

/* Functional method m on the fold's training motions (w, n_tr, present classes), each held-out
 * motion classified by 1-NN in the embedding. */
static affect_status run_functional(const run_ctx *rc, uint32_t fold, const fold_ws *w,
                                    uint32_t n_tr, uint32_t present, unsigned m, affect_cv_fold *f,
                                    affect_error *err)
{
    affect_fda_config fc = rc->cfg->fda;
    fc.monitor = rc->cls->hmm.monitor;
    fc.kernel = AFFECT_SPCA_LINEAR;
    switch (m) {
    case AFFECT_CV_FPCA:
        fc.method = AFFECT_FDA_FPCA;
        break;
    case AFFECT_CV_FFDA:
        fc.method = AFFECT_FDA_FFDA;
        break;
    case AFFECT_CV_FSPCA_RBF:
        fc.kernel = AFFECT_SPCA_RBF;
        fc.method = AFFECT_FDA_FSPCA;
        break;
    case AFFECT_CV_FSPCA:
        fc.method = AFFECT_FDA_FSPCA;
        break;
    default:
        fc.method = AFFECT_FDA_FISOMAP;
        break;
    }
    char what[32];
    snprintf(what, sizeof what, "%s: ", method_names[m]);
    affect_fda *model = NULL;
    affect_status st = affect_fda_train(&fc, rc->feat, w->seqs, n_tr, rc->m, w->y, w->labels,
                                        present, &model, err);
    if (st)
        return fold_fail(st, fold, UINT32_MAX, what, err);
    f->fda_dims[m] = affect_fda_dims(model);
    f->fda_lambda = affect_fda_get_config(model)->lambda;
    for (uint32_t i = 0; i < rc->n && st == AFFECT_OK; i++) {
        if (rc->fold_of[i] != fold)
            continue;
        uint32_t label = 0;
        st = affect_fda_classify(model, rc->seqs[i].x, rc->seqs[i].n_frames, 1, &label, NULL, err);
        if (st)
            st = fold_fail(st, fold, i, what, err);
        else
            f->confusion[m][(size_t)rc->y[i] * rc->C + w->back[label]]++;
    }
    affect_fda_free(model);
    return st;
}

/* The recognizer (ML, Fisher + SVM, Fisher + sPCA + kNN) on the fold's training motions. */
static affect_status run_recognizer(const run_ctx *rc, uint32_t fold, const fold_ws *w,
                                    uint32_t n_tr, uint32_t present, affect_cv_fold *f,
                                    affect_error *err)
{
    const affect_features *feat = rc->feat;
    const affect_hmm_seq *seqs = rc->seqs;
    const uint32_t *y = rc->y, *fold_of = rc->fold_of;
    uint32_t n = rc->n, C = rc->C;
    size_t dd = rc->ddim;
    affect_classifier *c = NULL;
    affect_status st = affect_classifier_train(rc->cls, feat, w->seqs, w->desc, w->y, n_tr,
                                               w->labels, present, &c, err);
    if (st)
        return fold_fail(st, fold, UINT32_MAX, "", err);
    const affect_classifier_config *cc = affect_classifier_get_config(c);
    affect_classifier_report rep;
    affect_classifier_get_report(c, &rep);
    f->svm_c = rep.svm_c;
    f->spca_dims = affect_spca_dims(affect_classifier_spca(c));
    f->spca_sigma = cc->spca_sigma;
    f->knn_k = cc->knn_k;
    for (uint32_t i = 0; i < n && st == AFFECT_OK; i++) {
        if (fold_of[i] != fold)
            continue;
        affect_classifier_out o = {0};
        st = affect_classifier_eval(c, seqs[i].x, seqs[i].n_frames, dd ? rc->desc + i * dd : NULL,
                                    false, &o, rc->cls->hmm.monitor, err);
        if (st) {
            st = fold_fail(st, fold, i, "", err);
            break;
        }
        uint32_t pred[3] = {o.ml, o.svm, o.knn};
        for (int m = 0; m < 3; m++)
            f->confusion[m][(size_t)y[i] * C + w->back[pred[m]]]++;
    }
    affect_classifier_free(c);
    return st;
}

/* Trains on the motions outside fold `fold` and scores the ones in it into f. */
static affect_status run_fold(const run_ctx *rc, uint32_t fold, fold_ws *w, affect_cv_fold *f,
                              affect_error *err)
{
    const affect_hmm_seq *seqs = rc->seqs;
    const uint32_t *y = rc->y, *fold_of = rc->fold_of;
    const char *const *labels = rc->labels;
    uint32_t n = rc->n, C = rc->C;
    uint32_t n_tr = 0, present = 0;
    for (uint32_t k = 0; k < C; k++)
        w->map[k] = UINT32_MAX;
    size_t dd = rc->ddim;
    for (uint32_t i = 0; i < n; i++)
        if (fold_of[i] != fold) {
            if (dd)
                memcpy(w->desc + n_tr * dd, rc->desc + i * dd, dd * sizeof *w->desc);
            w->seqs[n_tr] = seqs[i];
            w->y[n_tr++] = y[i];
            w->map[y[i]] = 0;
        }
    for (uint32_t k = 0; k < C; k++)
        if (w->map[k] == 0) {
            w->map[k] = present;
            w->back[present] = k;
            w->labels[present++] = labels[k];
        }
    for (uint32_t i = 0; i < n_tr; i++)
        w->y[i] = w->map[w->y[i]];
    f->n_train = n_tr;
    f->n_test = n - n_tr;
    if (present < 2)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "fold %u: the training motions have fewer than 2 classes", fold + 1);
    affect_status st = AFFECT_OK;
    for (unsigned m = AFFECT_CV_FPCA; m < AFFECT_CV_METHODS && st == AFFECT_OK; m++)
        if (rc->cfg->methods & (1u << m))
            st = run_functional(rc, fold, w, n_tr, present, m, f, err);
    if (st == AFFECT_OK && (rc->cfg->methods & AFFECT_CV_RECOGNIZER_MASK))
        st = run_recognizer(rc, fold, w, n_tr, present, f, err);
    if (st)
        return st;
    for (unsigned m = 0; m < AFFECT_CV_METHODS; m++) /* not asked: NaN (no motion counted) */
        metrics(f->confusion[m], C, &f->accuracy[m], &f->balanced[m], &f->f1[m]);
    return AFFECT_OK;
}

static void fold_ws_free(fold_ws *w)
{
    affect_free(w->seqs);
    affect_free(w->desc);
    affect_free(w->y);
    affect_free(w->map);
    affect_free(w->back);
    affect_free(w->labels);
}

static bool fold_ws_alloc(fold_ws *w, uint32_t n, uint32_t n_classes, uint32_t ddim)
{
    w->desc = NULL;
    if (ddim && !(w->desc = affect_malloc_array((size_t)n * ddim, sizeof *w->desc)))
        return false;
    w->seqs = affect_malloc_array(n ? n : 1, sizeof *w->seqs);
    w->y = affect_malloc_array(n ? n : 1, sizeof *w->y);
    w->map = affect_malloc_array(n_classes, sizeof *w->map);
    w->back = affect_malloc_array(n_classes, sizeof *w->back);
    w->labels = affect_malloc_array(n_classes, sizeof *w->labels);
    return w->seqs && w->y && w->map && w->back && w->labels;
}

/* The parallel run: workers take the folds in order from a shared counter; each fold's
 * result lands in its own slot, so the output does not depend on the schedule. */
typedef struct worker {
    const run_ctx *rc;
    mtx_t *lock;
    uint32_t *next;        /* the next fold to take (under lock) */
    bool *stop;            /* set (under lock) by the first failure */
    uint32_t *finished;    /* workers that returned (under lock) */
    affect_status *status; /* per fold */
    affect_error *errs;    /* per fold */
    fold_ws w;
} worker;

static int worker_main(void *arg)
{
    worker *wk = arg;
    const run_ctx *rc = wk->rc;
    for (;;) {
        mtx_lock(wk->lock);
        uint32_t i = *wk->stop ? rc->r->n_folds : (*wk->next)++;
        if (i >= rc->r->n_folds)
            (*wk->finished)++;
        mtx_unlock(wk->lock);
        if (i >= rc->r->n_folds)
            return 0;
        affect_cv_fold *f = &rc->r->folds[i];
        wk->status[i] = run_fold(rc, f->fold, &wk->w, f, &wk->errs[i]);
        mtx_lock(wk->lock);
        if (wk->status[i] != AFFECT_OK) {
            *wk->stop = true;
        } else {
            progress(rc->cfg, f, rc->k); /* one line at a time, in completion order */
            affect_monitor_step(rc->cfg->cls.hmm.monitor);
        }
        mtx_unlock(wk->lock);
    }
}

static affect_status run_parallel(const run_ctx *rc, affect_error *err)
{
    uint32_t nf = rc->r->n_folds, T = rc->cfg->threads < nf ? rc->cfg->threads : nf;
    worker *wk = affect_calloc(T, sizeof *wk);
    thrd_t *th = affect_calloc(T, sizeof *th);
    affect_status *status = affect_calloc(nf, sizeof *status);
    affect_error *errs = affect_calloc(nf, sizeof *errs);
    affect_status st = AFFECT_OK;
    mtx_t lock;
    uint32_t next = 0, started = 0, finished = 0;
    bool stop = false, have_lock = false;
    if (!wk || !th || !status || !errs) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t t = 0; t < T; t++)
        if (!fold_ws_alloc(&wk[t].w, rc->n, rc->C, rc->ddim)) {
            st = affect_nomem(err);
            goto done;
        }
    if (mtx_init(&lock, mtx_plain) != thrd_success) {
        st = affect_fail(err, AFFECT_ERR_RANGE, "cannot create a lock for the worker threads");
        goto done;
    }
    have_lock = true;
    for (uint32_t t = 0; t < T; t++) {
        wk[t] = (worker){rc, &lock, &next, &stop, &finished, status, errs, wk[t].w};
        if (thrd_create(&th[t], worker_main, &wk[t]) != thrd_success)
            break;
        started++;
    }
    if (started == 0) { /* no thread at all: run here */
        worker_main(&wk[0]);
    } else {
        /* the monitor asks only this thread: ask it while the folds run */
        affect_monitor *mon = rc->cfg->cls.hmm.monitor;
        for (bool all = false; mon && !all;) {
            (void)affect_monitor_stopped(mon);
            thrd_sleep(&(struct timespec){.tv_nsec = 2000000}, NULL);
            mtx_lock(&lock);
            all = finished == started;
            mtx_unlock(&lock);
        }
        for (uint32_t t = 0; t < started; t++)
            thrd_join(th[t], NULL);
        affect_monitor_flush(rc->cfg->cls.hmm.monitor);
    }
    for (uint32_t i = 0; i < nf; i++) /* the first failure in fold order */
        if (status[i] != AFFECT_OK) {
            *err = errs[i];
            st = status[i];
            break;
        }
    if (st == AFFECT_OK && next < nf && !stop) /* some threads failed to start: finish here */
        worker_main(&wk[0]);
done:
    if (have_lock)
        mtx_destroy(&lock);
    for (uint32_t t = 0; wk && t < T; t++)
        fold_ws_free(&wk[t].w);
    affect_free(wk);
    affect_free(th);
    affect_free(status);
    affect_free(errs);
    return st;
}

static void summarize(affect_cv_result *r)
{
    uint32_t C = r->n_classes;
    for (int m = 0; m < AFFECT_CV_METHODS; m++) {
        double acc[MAX_FOLDS], bal[MAX_FOLDS], f1[MAX_FOLDS];
        uint32_t nf = r->n_folds; /* ≤ MAX_FOLDS, checked by affect_crossval */
        for (uint32_t f = 0; f < nf; f++) {
            acc[f] = r->folds[f].accuracy[m];
            bal[f] = r->folds[f].balanced[m];
            f1[f] = r->folds[f].f1[m];
            for (size_t e = 0; e < (size_t)C * C; e++)
                r->pooled[m][e] += r->folds[f].confusion[m][e];
        }
        mean_sd(acc, nf, &r->mean_accuracy[m], &r->sd_accuracy[m]);
        mean_sd(bal, nf, &r->mean_balanced[m], &r->sd_balanced[m]);
        mean_sd(f1, nf, &r->mean_f1[m], &r->sd_f1[m]);
        double pb, pf;
        metrics(r->pooled[m], C, &r->pooled_accuracy[m], &pb, &pf);
    }
}

affect_status affect_crossval(const affect_cv_config *cfg, const affect_features *feat,
                              const affect_hmm_seq *seqs, const double *desc, const uint32_t *y,
                              uint32_t n, const char *const *labels, uint32_t n_classes,
                              const uint32_t *group, uint32_t n_groups, affect_cv_result **out,
                              affect_error *err)
{
    *out = NULL;
    if (n_classes < 2 || n_classes > AFFECT_CLASSIFIER_MAX_CLASSES)
        return affect_fail(err, AFFECT_ERR_INVALID, "need 2 to %u classes, got %u",
                           AFFECT_CLASSIFIER_MAX_CLASSES, n_classes);
    if (!(cfg->methods & AFFECT_CV_ALL_MASK))
        return affect_fail(err, AFFECT_ERR_INVALID, "no method asked");
    if (cfg->methods & ~AFFECT_CV_ALL_MASK)
        return affect_fail(err, AFFECT_ERR_INVALID, "unknown method bits 0x%x",
                           cfg->methods & ~AFFECT_CV_ALL_MASK);
    if (cfg->methods & ~AFFECT_CV_RECOGNIZER_MASK) {
        const char *msg = affect_fda_config_check(&cfg->fda);
        if (msg)
            return affect_fail(err, AFFECT_ERR_INVALID, "%s", msg);
    }
    if (cfg->threads < 1 || cfg->threads > 64)
        return affect_fail(err, AFFECT_ERR_INVALID, "threads must be from 1 to 64, got %u",
                           cfg->threads);
    if (!group && cfg->folds < 2)
        return affect_fail(err, AFFECT_ERR_INVALID, "folds must be at least 2");
    if (group && n_groups > MAX_FOLDS)
        return affect_fail(err, AFFECT_ERR_INVALID, "at most %u groups, got %u", MAX_FOLDS,
                           n_groups);
    if (!group && cfg->folds > MAX_FOLDS)
        return affect_fail(err, AFFECT_ERR_INVALID, "at most %u folds, got %u", MAX_FOLDS,
                           cfg->folds);
    for (uint32_t i = 0; i < n; i++)
        if (y[i] >= n_classes || (group && group[i] >= n_groups))
            return affect_fail(err, AFFECT_ERR_INVALID, "motion %u: class or group out of range",
                               i);
    uint32_t ddim = cfg->cls.descriptors ? affect_descriptors_dim(cfg->cls.descriptors) : 0;
    if (ddim && !desc)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the configuration appends descriptors but none were given");
    uint32_t *fold_of = affect_malloc_array(n ? n : 1, sizeof *fold_of);
    affect_cv_result *r = affect_calloc(1, sizeof *r);
    fold_ws w = {0};
    affect_status st = AFFECT_OK;
    if (!fold_ws_alloc(&w, n, n_classes, ddim) || !fold_of || !r) {
        st = affect_nomem(err);
        goto done;
    }
    r->n_classes = n_classes;
    uint32_t k = cfg->folds;
    if (group) {
        memcpy(fold_of, group, n * sizeof *fold_of);
        k = n_groups;
    } else {
        if (k > n)
            k = n;
        if ((st = affect_stratified_folds(y, n, n_classes, k, cfg->seed, fold_of, err)))
            goto done;
    }
    r->folds = affect_calloc(k ? k : 1, sizeof *r->folds);
    for (int m = 0; m < AFFECT_CV_METHODS; m++)
        r->pooled[m] = affect_calloc((size_t)n_classes * n_classes, sizeof(uint32_t));
    bool pooled = true;
    for (int m = 0; m < AFFECT_CV_METHODS; m++)
        pooled = pooled && r->pooled[m];
    if (!r->folds || !pooled) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t fold = 0; fold < k; fold++) {
        bool any = false;
        for (uint32_t i = 0; i < n && !any; i++)
            any = fold_of[i] == fold;
        if (!any)
            continue; /* an empty group */
        affect_cv_fold *f = &r->folds[r->n_folds++];
        f->fold = fold;
        f->group = group ? (int32_t)fold : -1;
        for (int m = 0; m < AFFECT_CV_METHODS; m++) {
            f->confusion[m] = affect_calloc((size_t)n_classes * n_classes, sizeof(uint32_t));
            if (!f->confusion[m]) {
                st = affect_nomem(err);
                goto done;
            }
        }
    }
    affect_classifier_config cls = cfg->cls;
    affect_monitor child;
    cls.hmm.monitor = affect_monitor_child(&child, cfg->cls.hmm.monitor);
    run_ctx rc = {cfg,  &cls,   feat,      feat ? affect_features_dim(feat) : cfg->cls.hmm.dim,
                  seqs, desc,   ddim,      y,
                  n,    labels, n_classes, fold_of,
                  k,    r};
    affect_monitor_report(cfg->cls.hmm.monitor, "folds", 0, r->n_folds);
    if (cfg->threads > 1 && r->n_folds > 1) {
        st = run_parallel(&rc, err);
    } else {
        for (uint32_t i = 0; i < r->n_folds && st == AFFECT_OK; i++)
            if ((st = run_fold(&rc, r->folds[i].fold, &w, &r->folds[i], err)) == AFFECT_OK) {
                progress(cfg, &r->folds[i], k);
                affect_monitor_step(cfg->cls.hmm.monitor);
            }
    }
    if (st)
        goto done;
    summarize(r);
done:
    affect_free(fold_of);
    fold_ws_free(&w);
    if (st) {
        affect_cv_result_free(r);
        return st;
    }
    *out = r;
    return AFFECT_OK;
}
