/*
 * bench_strength.c — emotion strength (affect/strength.h, affect/rank.h) on the real corpora:
 * the time of the ranker, the regression, the whole training, and affect_strength per motion,
 * against the goals (ranker ≤ 50 ms with PCA-40 and ≤ 1 s without PCA, regression
 * ≤ 1 s, affect_strength ≤ 1 ms per motion) and the paper's MATLAB times (2.3–5.4 s, 64–152 s,
 * 491–915 s).
 *
 * Usage:
 *     bench_strength [--corpus1 DIR] [--corpus2 DIR]
 *     AFFECT_BENCH_ONLY=bench_strength bash tests/bench/run.sh   # Release, pinned to CPU 0
 * DIR defaults to AFFECT_BENCH_CORPUS / AFFECT_BENCH_CORPUS2 (set by tests/bench/CMakeLists.txt);
 * an absent corpus is skipped with a message (exit status 0).
 *
 * Data sets (BVH parsed once, untimed, unit cm): bn1-anger, bandai-namco-1's normal and angry
 * recordings of the ten contents recorded in every style (22); bn2-exhausted,
 * bandai-namco-2-dev's normal and exhausted recordings (144). The first half of each label in
 * name order trains (11 and 72 motions), the rest is scored.
 * Timed (process CPU time, median of 5 runs; the keyframe features, 13 keyframes, standardized,
 * which synthesis and editing need, except the last two columns):
 *   train PCA-40 / train no PCA  the whole affect_strength_train (features, PCA, ranker,
 *                                cross-validated regression);
 *   ranker PCA-40 / no PCA       affect_rank_fit alone on the model's training coordinates and
 *                                the pairs of the training labels (all ordered and similar
 *                                pairs) — the paper's "training the ranker";
 *   regression                   affect_strength_fit_regression alone (PCA-40 model: the grid
 *                                of 20 kernel ridge and 5 local linear fits × 5 folds);
 *   affect_strength              affect_strength_score per scored motion (normalization,
 *                                keyframe DP, features, projection), median over the motions;
 *   train default / affect_strength default   the same with strength_train's default options
 *                                (the Fisher representation of a recognizer trained inside
 *                                the model: its HMMs, Fisher scores and the ranker on them).
 * Then, below the table, the keyframe selection alone (affect_keyframes_select_level, 13
 * keyframes of the scored motions' joint positions; median over the motions of the mean of 3
 * calls) at every level this processor runs (plain C, then SSE2, AVX2, AVX-512 on x86-64):
 * what a processor without the wider ones gets.
 * Output: a table, then lines "BENCH strength_<what>_<data set> <seconds> s" for scripts.
 * Exit status 1 if a step fails.
 */
#define _POSIX_C_SOURCE 200809L
#include "benchutil.h"

#include "affect/io.h"
#include "affect/keyframes.h"
#include "affect/rank.h"
#include "affect/strength.h"

#include <math.h>
#include <stdint.h>

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS ""
#endif
#ifndef AFFECT_BENCH_CORPUS2
#define AFFECT_BENCH_CORPUS2 ""
#endif

#define N_RUNS 5

static const char *const TEN[] = {"walk", "run", "dash",   "walk-back", "walk-left", "walk-right",
                                  "bow",  "bye", "byebye", "guide",     NULL};

typedef struct dataset {
    const char *name;
    affect_motion **m;
    int32_t *level;
    bool *train;
    uint32_t n;
} dataset;

static int in_list(const char *s, const char *const *list)
{
    for (int k = 0; list[k]; k++)
        if (strcmp(s, list[k]) == 0)
            return 1;
    return 0;
}

/* Loads the recordings of dir whose style is lo or hi (and content in contents, if given). */
static int load(const char *dir, const char *lo, const char *hi, const char *const *contents,
                dataset *d)
{
    bench_text *texts;
    size_t n, bytes;
    if (bench_load_texts(dir, ".bvh", &texts, &n, &bytes))
        return 1;
    d->m = calloc(n, sizeof *d->m);
    d->level = calloc(n, sizeof *d->level);
    d->train = calloc(n, sizeof *d->train);
    d->n = 0;
    uint32_t seen[2] = {0, 0}, total[2] = {0, 0};
    int rc = 0;
    for (int pass = 0; pass < 2 && rc == 0; pass++)
        for (size_t i = 0; i < n; i++) {
            char name[256], *f[4] = {NULL, NULL, NULL, NULL};
            snprintf(name, sizeof name, "%s", texts[i].name);
            char *save = NULL, *tok = strtok_r(name, "_", &save);
            for (int k = 0; tok && k < 4; k++, tok = strtok_r(NULL, "_", &save))
                f[k] = tok;
            if (!f[2] || (contents && !in_list(f[1], contents)))
                continue;
            int lv = strcmp(f[2], lo) == 0 ? 0 : strcmp(f[2], hi) == 0 ? 1 : -1;
            if (lv < 0)
                continue;
            if (pass == 0) {
                total[lv]++;
                continue;
            }
            affect_bvh_options bo = {.scale = 1, .unit = "cm"};
            affect_error err;
            if (affect_bvh_parse(texts[i].text, texts[i].len, &bo, &d->m[d->n], &err)) {
                fprintf(stderr, "bench_strength: %s: %s\n", texts[i].name, err.msg);
                rc = 2;
                break;
            }
            d->level[d->n] = lv;
            d->train[d->n] = seen[lv]++ < total[lv] / 2;
            d->n++;
        }
    for (size_t i = 0; i < n; i++) {
        free(texts[i].name);
        free(texts[i].text);
    }
    free(texts);
    return rc;
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return v[n / 2];
}

/* affect_strength_score per scored motion (the mean of 3 calls), the median over them. */
static int score_time(const affect_strength *model, const dataset *d, double *out)
{
    double *per = malloc(sizeof(double) * d->n);
    int ns = 0;
    affect_error err;
    if (!per)
        return 1;
    for (uint32_t i = 0; i < d->n; i++) {
        if (d->train[i])
            continue;
        double s, c0 = cpu_now();
        for (int r = 0; r < 3; r++)
            if (affect_strength_score(model, d->m[i], &s, NULL, &err)) {
                fprintf(stderr, "bench_strength: score: %s\n", err.msg);
                free(per);
                return 1;
            }
        per[ns++] = (cpu_now() - c0) / 3;
    }
    *out = median(per, ns);
    free(per);
    return 0;
}

/* The keyframe selection alone at each level the processor runs: 13 keyframes of each scored
 * motion's joint positions (the mean of 3 calls), the median over the motions. */
static int keyframe_levels(const dataset *d)
{
    static const char *const level_names[] = {"scalar", "base", "avx2", "avx512"};
    double *per = malloc(sizeof(double) * d->n);
    if (!per)
        return 1;
    for (int level = AFFECT_KEYFRAMES_LEVEL_SCALAR; level <= affect_keyframes_level(); level++) {
        int ns = 0;
        for (uint32_t i = 0; i < d->n; i++) {
            if (d->train[i])
                continue;
            const affect_motion *m = d->m[i];
            size_t nv = (size_t)m->n_frames * m->n_joints * 3;
            double *Y = malloc(sizeof(double) * nv);
            uint32_t frames[AFFECT_KEYFRAMES_DEFAULT], nf;
            affect_error err;
            if (!Y) {
                free(per);
                return 1;
            }
            for (size_t k = 0; k < nv; k++)
                Y[k] = m->pos[k];
            double c0 = cpu_now();
            for (int r = 0; r < 3; r++)
                if (affect_keyframes_select_level(Y, m->n_frames, m->n_joints * 3,
                                                  AFFECT_KEYFRAMES_DEFAULT, frames, &nf, NULL,
                                                  level, NULL, &err)) {
                    fprintf(stderr, "bench_strength: keyframes: %s\n", err.msg);
                    free(Y);
                    free(per);
                    return 1;
                }
            per[ns++] = (cpu_now() - c0) / 3;
            free(Y);
        }
        printf("BENCH strength_keyframes_%s_%s %.6f s\n", level_names[level + 1], d->name,
               median(per, ns));
    }
    free(per);
    return 0;
}

static int bench_set(dataset *d)
{
    static const char *const names[] = {"low", "high"};
    affect_motion **tm = malloc(sizeof *tm * d->n);
    int32_t *tl = malloc(sizeof *tl * d->n);
    uint32_t nt = 0;
    for (uint32_t i = 0; i < d->n; i++)
        if (d->train[i]) {
            tm[nt] = d->m[i];
            tl[nt++] = d->level[i];
        }
    affect_error err;
    affect_strength *model[2] = {NULL, NULL};
    double t_train[2], t_rank[2], t_reg = 0, t_score = 0;
    uint32_t dims[2];
    for (int v = 0; v < 2; v++) {
        affect_strength_options so;
        affect_strength_options_default(&so);
        so.pca_dims = v == 0 ? 40 : 0;
        so.features = AFFECT_STRENGTH_FEAT_KEYFRAMES; /* the keyframe path (the default ranks by
                                                         the Fisher representation) */
        double runs[N_RUNS];
        for (int r = 0; r < N_RUNS; r++) {
            affect_strength_free(model[v]);
            model[v] = NULL;
            double c0 = cpu_now();
            if (affect_strength_train((const affect_motion *const *)tm, tl, NULL, nt, names, 2, &so,
                                      &model[v], &err)) {
                fprintf(stderr, "bench_strength: %s: %s\n", d->name, err.msg);
                return 1;
            }
            runs[r] = cpu_now() - c0;
        }
        t_train[v] = median(runs, N_RUNS);
        dims[v] = model[v]->pdim;
        /* the ranker alone, on the model's training coordinates */
        affect_rank_pair *pairs;
        size_t np;
        if (affect_rank_pairs(tl, NULL, nt, true, 1.0, 0, &pairs, &np, &err))
            return 1;
        double *w = malloc(sizeof(double) * model[v]->pdim);
        affect_rank_options ro;
        affect_rank_options_default(&ro);
        for (int r = 0; r < N_RUNS; r++) {
            double c0 = cpu_now();
            if (affect_rank_fit(model[v]->train_z, nt, model[v]->pdim, pairs, np, &ro, w, NULL,
                                &err)) {
                fprintf(stderr, "bench_strength: ranker: %s\n", err.msg);
                return 1;
            }
            runs[r] = cpu_now() - c0;
        }
        t_rank[v] = median(runs, N_RUNS);
        free(w);
        affect_free(pairs);
    }
    double runs[N_RUNS];
    for (int r = 0; r < N_RUNS; r++) {
        double c0 = cpu_now();
        if (affect_strength_fit_regression(model[0], AFFECT_STRENGTH_REG_AUTO, NULL, &err)) {
            fprintf(stderr, "bench_strength: regression: %s\n", err.msg);
            return 1;
        }
        runs[r] = cpu_now() - c0;
    }
    t_reg = median(runs, N_RUNS);
    if (score_time(model[0], d, &t_score))
        return 1;
    /* the default model (the Fisher representation): trained and scored likewise */
    affect_strength *def = NULL;
    double t_train_def, t_score_def;
    {
        affect_strength_options so;
        affect_strength_options_default(&so);
        for (int r = 0; r < N_RUNS; r++) {
            affect_strength_free(def);
            def = NULL;
            double c0 = cpu_now();
            if (affect_strength_train((const affect_motion *const *)tm, tl, NULL, nt, names, 2, &so,
                                      &def, &err)) {
                fprintf(stderr, "bench_strength: %s: default: %s\n", d->name, err.msg);
                return 1;
            }
            runs[r] = cpu_now() - c0;
        }
        t_train_def = median(runs, N_RUNS);
    }
    if (score_time(def, d, &t_score_def))
        return 1;
    affect_strength_free(def);
    uint32_t frames = 0;
    for (uint32_t i = 0; i < d->n; i++)
        frames = d->m[i]->n_frames > frames ? d->m[i]->n_frames : frames;
    printf("| %s | %u | %u | %u, %u | %.4f | %.4f | %.4f | %.4f | %.4f | %.5f | %.4f | %.5f |\n",
           d->name, nt, d->n - nt, dims[0], dims[1], t_train[0], t_train[1], t_rank[0], t_rank[1],
           t_reg, t_score, t_train_def, t_score_def);
    printf("BENCH strength_train_pca40_%s %.6f s\n", d->name, t_train[0]);
    printf("BENCH strength_train_nopca_%s %.6f s\n", d->name, t_train[1]);
    printf("BENCH strength_ranker_pca40_%s %.6f s\n", d->name, t_rank[0]);
    printf("BENCH strength_ranker_nopca_%s %.6f s\n", d->name, t_rank[1]);
    printf("BENCH strength_regression_%s %.6f s\n", d->name, t_reg);
    printf("BENCH strength_score_%s %.6f s\n", d->name, t_score);
    printf("BENCH strength_train_default_%s %.6f s\n", d->name, t_train_def);
    printf("BENCH strength_score_default_%s %.6f s\n", d->name, t_score_def);
    free(tm);
    free(tl);
    affect_strength_free(model[0]);
    affect_strength_free(model[1]);
    return 0;
}

int main(int argc, char **argv)
{
    const char *c1 = AFFECT_BENCH_CORPUS, *c2 = AFFECT_BENCH_CORPUS2;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (strcmp(argv[i], "--corpus1") == 0)
            c1 = argv[i + 1];
        else if (strcmp(argv[i], "--corpus2") == 0)
            c2 = argv[i + 1];
    }
    printf(
        "| data set | train | scored | dims (PCA-40, none) | train PCA-40 (s) | train no PCA (s) "
        "| ranker PCA-40 (s) | ranker no PCA (s) | regression (s) | affect_strength (s) "
        "| train default (s) | affect_strength default (s) |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    dataset d1 = {.name = "bn1-anger"}, d2 = {.name = "bn2-exhausted"};
    int rc = load(c1, "normal", "angry", TEN, &d1);
    if (rc == 1)
        printf("bench_strength: %s absent: bn1-anger skipped\n", c1);
    else if (rc || bench_set(&d1))
        return 1;
    rc = load(c2, "normal", "exhausted", NULL, &d2);
    if (rc == 1)
        printf("bench_strength: %s absent: bn2-exhausted skipped\n", c2);
    else if (rc || bench_set(&d2))
        return 1;
    if ((d1.n && keyframe_levels(&d1)) || (d2.n && keyframe_levels(&d2)))
        return 1;
    for (uint32_t i = 0; i < d1.n; i++)
        affect_motion_free(d1.m[i]);
    for (uint32_t i = 0; i < d2.n; i++)
        affect_motion_free(d2.m[i]);
    free(d1.m);
    free(d1.level);
    free(d1.train);
    free(d2.m);
    free(d2.level);
    free(d2.train);
    return 0;
}
