/*
 * bench_fda.c — the functional analysis (affect/fda.h, thesis chapter 3) on bandai-namco-1's 44
 * angry/happy/normal/sad motions of the ten contents recorded in every style: training time of
 * each method (FPCA, FFDA, FSPCA linear and RBF, F-Isomap, and FPCA with λ by GCV), and the
 * time to embed one unseen motion (the B-spline fit and the projection).
 *
 * Usage:
 *     bench_fda [corpus dir] [--joints all|thesis]
 *     bash tests/bench/run.sh            # Release build, pinned to one core
 * The corpus defaults to AFFECT_BENCH_CORPUS (../shared/corpora/bandai-namco-1/data); when it is
 * absent the program says so and exits 0.
 *
 * Observations as fda_train's defaults: body-frame joint positions of every joint (22, m = 66),
 * 200 cubic B-splines, λ = 1e-10, 3 dimensions; with --joints thesis the evaluation's options
 * (docs/EVALUATION.md): the thesis's seven joints (pelvis, chest, head, hands, feet) with
 * velocities (m = 42). Each training is timed by bench_measure (an untimed warm-up, then 5 runs,
 * the median reported with its process CPU time); embedding: every one of the 44 motions
 * embedded by a model trained on all of them, per motion. The goals (issue 15): FPCA and FSPCA
 * ≤ 0.1 s, FFDA ≤ 1 s, embedding ≤ 1 ms.
 * Output: a table for people, then one line per metric for scripts:
 *     BENCH <metric> <value> <unit>
 */
#define _POSIX_C_SOURCE 200809L

#include <stdbool.h>
#include <stdint.h>

#include "affect/fda.h"
#include "affect/io.h"
#include "benchutil.h"

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS ""
#endif

static const char *const emotions[4] = {"angry", "happy", "normal", "sad"};
static const char *const contents[10] = {"walk",       "run", "dash", "walk-back", "walk-left",
                                         "walk-right", "bow", "bye",  "byebye",    "guide"};

typedef struct bench {
    affect_fda_config cfg;
    affect_features *feat;
    affect_hmm_seq seqs[64];
    uint32_t y[64], n, m;
    affect_fda *model;
} bench;

/* The class of "dataset-1_<content>_<emotion>_<id>.bvh", or −1. */
static int class_of(const char *name)
{
    char content[64], emotion[64];
    if (sscanf(name, "dataset-1_%63[^_]_%63[^_]_", content, emotion) != 2)
        return -1;
    bool known = false;
    for (int k = 0; k < 10; k++)
        known = known || strcmp(content, contents[k]) == 0;
    for (int k = 0; known && k < 4; k++)
        if (strcmp(emotion, emotions[k]) == 0)
            return k;
    return -1;
}

static int pass_train(void *arg)
{
    bench *b = arg;
    affect_error err;
    affect_fda *f = NULL;
    if (affect_fda_train(&b->cfg, b->feat, b->seqs, b->n, b->m, b->y, emotions, 4, &f, &err)) {
        fprintf(stderr, "bench_fda: train: %s\n", err.msg);
        return 1;
    }
    affect_fda_free(b->model);
    b->model = f;
    return 0;
}

static int pass_embed(void *arg)
{
    bench *b = arg;
    double z[AFFECT_FDA_MAX_DIMS];
    affect_error err;
    for (uint32_t i = 0; i < b->n; i++)
        if (affect_fda_embed(b->model, b->seqs[i].x, b->seqs[i].n_frames, z, &err)) {
            fprintf(stderr, "bench_fda: embed: %s\n", err.msg);
            return 1;
        }
    return 0;
}

int main(int argc, char **argv)
{
    const char *dir = AFFECT_BENCH_CORPUS;
    bool thesis = false;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--joints") == 0 && i + 1 < argc)
            thesis = strcmp(argv[++i], "thesis") == 0;
        else
            dir = argv[i];
    }
    bench_text *files;
    size_t count, bytes;
    if (!*dir || bench_load_texts(dir, ".bvh", &files, &count, &bytes) == 1) {
        printf("bench_fda: skipped: the corpus (%s) is absent\n", *dir ? dir : "not configured");
        return 0;
    }
    static bench b;
    affect_motion *first = NULL;
    affect_error err;
    int rc = 1;
    affect_motion *ms[64];
    uint32_t nm = 0;
    for (size_t i = 0; i < count; i++) {
        int y = class_of(files[i].name);
        if (y >= 0 && nm < 64) {
            if (affect_bvh_parse(files[i].text, files[i].len, NULL, &ms[nm], &err)) {
                fprintf(stderr, "bench_fda: %s: %s\n", files[i].name, err.msg);
                return 1;
            }
            b.y[nm++] = (uint32_t)y;
        }
        free(files[i].name);
        free(files[i].text);
    }
    free(files);
    if (nm != 44) {
        fprintf(stderr, "bench_fda: expected 44 motions, found %u\n", nm);
        return 1;
    }
    first = ms[0];
    affect_features_options fo;
    affect_features_options_default(&fo);
    fo.frame = AFFECT_FEATURES_FRAME_BODY;
    static const char *const seven[] = {"pelvis",     "chest",     "head",      "left_hand",
                                        "right_hand", "left_foot", "right_foot"};
    if (thesis) {
        fo.joints = seven;
        fo.n_joints = 7;
        fo.velocity = true;
    }
    if (affect_features_create(&fo, first, &b.feat, &err)) {
        fprintf(stderr, "bench_fda: features: %s\n", err.msg);
        return 1;
    }
    b.m = affect_features_dim(b.feat);
    b.n = nm;
    uint64_t frames = 0;
    for (uint32_t i = 0; i < nm; i++) {
        double *x;
        uint32_t T;
        if (affect_features_extract(b.feat, ms[i], &x, &T, NULL, &err)) {
            fprintf(stderr, "bench_fda: %s\n", err.msg);
            return 1;
        }
        b.seqs[i] = (affect_hmm_seq){x, T};
        frames += T;
    }
    printf("bench_fda: %u motions, %llu frames, m = %u coordinates (%s), OPENBLAS_NUM_THREADS=%s\n",
           nm, (unsigned long long)frames, b.m, thesis ? "7 joints with velocities" : "every joint",
           getenv("OPENBLAS_NUM_THREADS") ? getenv("OPENBLAS_NUM_THREADS") : "(unset)");
    printf("\n| method | training, median (CPU) | goal | embedding one motion | goal |\n");
    printf("|---|---|---|---|---|\n");
    struct {
        const char *name, *key;
        affect_fda_method method;
        affect_spca_kernel kernel;
        bool gcv;
        double goal;
    } rows[] = {
        {"FPCA", "fpca", AFFECT_FDA_FPCA, AFFECT_SPCA_LINEAR, false, 0.1},
        {"FFDA", "ffda", AFFECT_FDA_FFDA, AFFECT_SPCA_LINEAR, false, 1.0},
        {"FSPCA linear", "fspca_linear", AFFECT_FDA_FSPCA, AFFECT_SPCA_LINEAR, false, 0.1},
        {"FSPCA RBF (σ 0.5)", "fspca_rbf", AFFECT_FDA_FSPCA, AFFECT_SPCA_RBF, false, 0.1},
        {"F-Isomap (k 7)", "fisomap", AFFECT_FDA_FISOMAP, AFFECT_SPCA_LINEAR, false, 0},
        {"FPCA, λ by GCV", "fpca_gcv", AFFECT_FDA_FPCA, AFFECT_SPCA_LINEAR, true, 0},
    };
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
        affect_fda_config_default(&b.cfg);
        b.cfg.method = rows[r].method;
        b.cfg.kernel = rows[r].kernel;
        b.cfg.sigma = 0.5;
        b.cfg.gcv = rows[r].gcv;
        result tr, em;
        if (bench_measure(pass_train, &b, 1, &tr) || bench_measure(pass_embed, &b, 0, &em))
            goto done;
        double per = em.cpu_median / (em.repeat * (double)b.n);
        char goal[32] = "–";
        if (rows[r].goal > 0)
            snprintf(goal, sizeof goal, "≤ %g s", rows[r].goal);
        printf("| %s | %.4f s (%.4f s) | %s | %.3f ms | ≤ 1 ms |\n", rows[r].name, tr.median,
               tr.cpu_median, goal, per * 1e3);
        printf("BENCH fda_train_%s %.6f s\n", rows[r].key, tr.cpu_median);
        printf("BENCH fda_embed_%s %.6f ms\n", rows[r].key, per * 1e3);
        if (rows[r].gcv)
            printf("(GCV chose λ = %g)\n", affect_fda_get_config(b.model)->lambda);
        fflush(stdout);
    }
    rc = 0;
done:
    affect_fda_free(b.model);
    for (uint32_t i = 0; i < nm; i++) {
        affect_free((void *)b.seqs[i].x);
        affect_motion_free(ms[i]);
    }
    affect_features_free(b.feat);
    return rc;
}
