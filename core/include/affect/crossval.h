/*
 * affect/crossval.h — evaluation protocols for the recognizer (affect/classifier.h): stratified
 * k-fold cross-validation (seeded) and leave-one-group-out (a group per motion: its content,
 * or its performer), with maximum likelihood, Fisher + SVM and Fisher + sPCA + kNN scored on
 * the same folds.
 *
 * Usage:
 *     const affect_features *feat = ...;
 *     const affect_hmm_seq *seqs = ...;  const uint32_t *y = ...;  uint32_t n = ...;
 *     const char *const labels[4] = {"neutral", "happy", "sad", "angry"};
 *     affect_error err;
 *     affect_cv_config cfg;
 *     affect_cv_config_default(&cfg);                  // 10 folds
 *     cfg.cls.hmm.dim = affect_features_dim(feat);
 *     affect_cv_result *r = NULL;                      // group NULL: stratified k-fold
 *     if (affect_crossval(&cfg, feat, seqs, NULL, y, n, labels, 4, NULL, 0, &r, &err) != AFFECT_OK)
 *         puts(err.msg);
 *     else
 *         printf("svm accuracy %.3f\n", r->mean_accuracy[AFFECT_CV_SVM]);   // over the folds
 *     affect_cv_result_free(r);
 *
 * Per fold a classifier is trained on the training motions only (HMMs, normalization, SVM,
 * sPCA, and the optional grid search inside it) and every held-out motion is classified by the
 * three methods. A class missing from a fold's training motions (possible with
 * leave-one-group-out) is left out of that fold's classifier; its held-out motions then count
 * as errors. Folds: affect_stratified_folds (affect/svm.h) with the seed; groups: fold g holds
 * the motions of group g (groups numbered by the caller, 0 .. n_groups − 1; an empty group
 * gives no fold).
 *
 * Functional methods (cfg.methods bits AFFECT_CV_FPCA .. AFFECT_CV_FISOMAP): per fold a
 * functional model (affect_fda_train, cfg.fda with the method's own method and label kernel) is
 * trained on the same training motions (the same observation sequences; descriptors and the
 * recognizer's options play no part) and each held-out motion is classified by 1-NN in its
 * embedding (affect_fda_classify, k = 1) — the thesis's protocol (chapter 3). With no
 * recognizer method asked, no classifier is trained.
 *
 * Metrics per method and fold, over the fold's held-out motions: accuracy; balanced accuracy
 * = the mean recall over the classes present among them; macro-F1 = the mean of
 * F1 = 2 TP / (2 TP + FP + FN) over the classes present among them or predicted for them; the
 * confusion matrix (row = true class, column = predicted). The summary per method: the mean and
 * sample standard deviation (n − 1) of each metric over the folds, the pooled confusion matrix
 * and the pooled accuracy (correct / all motions).
 *
 * Threads: with threads > 1, that many C11 threads take the folds in turn (the folds are
 * independent; each result goes to its own slot and every fold computes exactly what it
 * computes alone, so the result is the same bytes whatever the thread count). The allocator
 * installed with affect_set_allocator and the BLAS must then be thread-safe (SQLite's and
 * OpenBLAS's are); libsvm's print function is set once per process (affect/svm.h).
 *
 * progress (may be NULL) receives one line per fold (with threads: in completion order, one
 * call at a time) ("fold 3/10: 40 training, 4 held out, svm 0.75, knn 0.75, ml 0.5, ffda 0.5":
 * the methods asked, the recognizer's first, then the functional ones in method order).
 */
#ifndef AFFECT_CROSSVAL_H
#define AFFECT_CROSSVAL_H

#include "affect/classifier.h"
#include "affect/fda.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The methods: the recognizer's three (affect/classifier.h) and the functional ones
 * (affect/fda.h: FSPCA with the linear and with the Gaussian-RBF label kernel), each scored by
 * 1-NN in its embedding. */
enum {
    AFFECT_CV_ML = 0,
    AFFECT_CV_SVM = 1,
    AFFECT_CV_KNN = 2,
    AFFECT_CV_FPCA = 3,
    AFFECT_CV_FFDA = 4,
    AFFECT_CV_FSPCA = 5,
    AFFECT_CV_FSPCA_RBF = 6,
    AFFECT_CV_FISOMAP = 7,
    AFFECT_CV_METHODS = 8,
    AFFECT_CV_RECOGNIZER_METHODS = 3 /* methods 0 .. 2 */
};
/* The recognizer's methods (a classifier is trained per fold only when one of them is asked). */
#define AFFECT_CV_RECOGNIZER_MASK 0x7u
#define AFFECT_CV_ALL_MASK 0xffu

typedef struct affect_cv_config {
    affect_classifier_config cls;
    uint32_t folds;   /* k of the stratified k-fold (default 10; ignored with groups) */
    uint64_t seed;    /* fold assignment (default 1) */
    uint32_t threads; /* folds run at once, each in its own thread (default 1, at most 64) */
    unsigned methods; /* bit m = method m (default AFFECT_CV_RECOGNIZER_MASK) */
    /* The functional methods' settings (affect_fda_config_default); method and kernel are
     * set per method, the monitor is cls.hmm.monitor's. */
    affect_fda_config fda;
    void (*progress)(void *ctx, const char *line);
    void *progress_ctx;
} affect_cv_config;

void affect_cv_config_default(affect_cv_config *cfg);

typedef struct affect_cv_fold {
    uint32_t fold; /* 0-based */
    int32_t group; /* the held-out group, or −1 (k-fold) */
    uint32_t n_train, n_test;
    double accuracy[AFFECT_CV_METHODS], balanced[AFFECT_CV_METHODS], f1[AFFECT_CV_METHODS];
    uint32_t *confusion[AFFECT_CV_METHODS]; /* n_classes × n_classes each */
    double svm_c, spca_sigma;               /* what the fold's classifier used */
    uint32_t spca_dims, knn_k;
    uint32_t fda_dims[AFFECT_CV_METHODS]; /* a functional method's embedding dimensions */
    double fda_lambda;                    /* the functional fits' λ (the first method's) */
} affect_cv_fold;

typedef struct affect_cv_result {
    uint32_t n_classes, n_folds;
    affect_cv_fold *folds;
    double mean_accuracy[AFFECT_CV_METHODS], sd_accuracy[AFFECT_CV_METHODS];
    double mean_balanced[AFFECT_CV_METHODS], sd_balanced[AFFECT_CV_METHODS];
    double mean_f1[AFFECT_CV_METHODS], sd_f1[AFFECT_CV_METHODS];
    double pooled_accuracy[AFFECT_CV_METHODS];
    uint32_t *pooled[AFFECT_CV_METHODS]; /* n_classes × n_classes */
} affect_cv_result;

/* The name of method m ("ml", "svm", "knn", "fpca", "ffda", "fspca", "fspca_rbf", "fisomap"),
 * or NULL when m is out of range. */
const char *affect_cv_method_name(unsigned m);

/* Runs the protocol on n sequences (class y[i] in 0 .. n_classes − 1 named labels[k]); group
 * NULL = stratified k-fold, else leave-one-group-out over group[i] in 0 .. n_groups − 1.
 * Errors (AFFECT_ERR_INVALID unless said): "need 2 to 64 classes, got 1", "no method asked",
 * "unknown method bits 0x100", the functional configuration's (affect_fda_config_check), "fold
 * 3: fisomap: <affect_fda_train's error>", "fold 3, motion 7: ffda: <its error>", the
 * classifier's, AFFECT_ERR_INTERRUPTED, AFFECT_ERR_NOMEM. */
affect_status affect_crossval(const affect_cv_config *cfg, const affect_features *feat,
                              const affect_hmm_seq *seqs, const double *desc, const uint32_t *y,
                              uint32_t n, const char *const *labels, uint32_t n_classes,
                              const uint32_t *group, uint32_t n_groups, affect_cv_result **out,
                              affect_error *err);
void affect_cv_result_free(affect_cv_result *r);

#ifdef __cplusplus
}
#endif

#endif
