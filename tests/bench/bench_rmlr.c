/*
 * bench_rmlr.c — the time of the cross-validated RMLR fit (affect_rmlr_cv, the fit behind
 * laban_salient) on the Laban vectors of real corpora, on one core, with the chosen model and
 * the largest KKT violation of its refit, so that a faster solver can be checked to choose the
 * same model.
 *
 * Usage:
 *     bench_rmlr [--corpus1 DIR] [--corpus2 DIR] [--runs N] [--threads N]
 *     AFFECT_BENCH_ONLY=bench_rmlr bash tests/bench/run.sh      # Release, pinned to CPU 0
 * DIR defaults to AFFECT_BENCH_CORPUS (bandai-namco-1) and AFFECT_BENCH_CORPUS2
 * (bandai-namco-2-dev), both set by tests/bench/CMakeLists.txt; an absent corpus is skipped
 * with a message (exit status 0). --runs N: timed fits of each data set (default 3; the
 * median is reported); --threads N: options.threads (default 1).
 *
 * Data sets (the vectors computed once, untimed, before any fit):
 *   bn1-44 (22 and 27 joints)  bandai-namco-1's 44 recordings of emotion angry, happy, normal or
 *             sad whose content is recorded in all four (the selection of bench_generate.c and
 *             sql/import_bvh.sql), in name order, labels the emotions (4 classes); at the BVH's
 *             27 joints (its 22 and 5 End Sites) and at 22 (affect_motion_select without
 *             Head_end, Hand_L_end, Hand_R_end, Toes_L_end, Toes_R_end), as bench_generate's
 *             ix27 and ix22;
 *   bn2-504 (27 joints)  all 504 recordings of bandai-namco-2-dev, labels the 7 styles (the
 *             third field of dataset-2_{content}_{style}_{take}.bvh).
 * Each motion: affect_bvh_parse with unit "cm", affect_laban_vector with the default options
 * and missing_null (as the laban virtual table: a component that cannot be computed is
 * missing), rounded to float32 as the laban table stores it; then affect_impute_column_means.
 * The fit: affect_rmlr_cv with laban_salient's options (defaults — 20 α, 100 λ — with seed 1,
 * 10 folds, lambda_min_ratio 0.01). Each run's wall time and process CPU time
 * (CLOCK_PROCESS_CPUTIME_ID: less than the wall time when another process shared the core).
 * After the runs: the chosen α, λ index, cross-validated error, the count of non-zero
 * coefficients, the FNV-1a hash of the model's encoding (equal hashes: the same model, byte
 * for byte), and the KKT check of the refit: with the model's own means and sds, g_kj =
 * (1/n) Σ_i z_ij (1{y_i = k} − p_ik); the largest |g_kj − λ(1−α)β_kj − λα sign β_kj| over the
 * non-zero coefficients and the largest |g_kj| − λα over the zero ones (≤ 0 when none
 * violates), relative to λ.
 * Output: a table, then one line per metric for scripts:
 *     BENCH rmlr_cv_<data set> <seconds> s
 * (the median CPU time with one thread; the median wall time with --threads N > 1, as
 * rmlr_cv_<data set>_threads).
 * Exit status 1 if a fit or a file fails.
 */
#define _POSIX_C_SOURCE 200809L

#include "affect/io.h"
#include "affect/laban.h"
#include "affect/motion.h"
#include "affect/rmlr.h"
#include "affect/roles.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "benchutil.h"
#include "util/bytes.h"

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS "../shared/corpora/bandai-namco-1/data"
#endif
#ifndef AFFECT_BENCH_CORPUS2
#define AFFECT_BENCH_CORPUS2 "../shared/corpora/bandai-namco-2-dev/data"
#endif

#define P AFFECT_LABAN_N
#define MAX_RUNS 20u
#define MAX_LABELS 16
#define MAX_FIELD 64

static const char *const end_sites[] = {"Head_end", "Hand_L_end", "Hand_R_end", "Toes_L_end",
                                        "Toes_R_end"};
static const char *const emotions[] = {"angry", "happy", "normal", "sad"};

/* One data set: n vectors of P components, labels 0 .. K−1 (names in byte order). */
typedef struct dataset {
    const char *name;
    size_t n, cap;
    double *x;
    char **label_of; /* n: each row's label text, until labels are numbered */
    uint32_t *y;
    uint32_t K;
    char labels[MAX_LABELS][MAX_FIELD];
} dataset;

static void dataset_free(dataset *d)
{
    for (size_t i = 0; i < d->n; i++)
        free(d->label_of[i]);
    free(d->label_of);
    free(d->x);
    free(d->y);
    memset(d, 0, sizeof *d);
}

/* Field f (0-based) of a file stem split at '_', into out (NUL-terminated); false if absent. */
static bool field(const char *stem, int f, char *out, size_t size)
{
    const char *s = stem;
    for (int i = 0; i < f; i++) {
        s = strchr(s, '_');
        if (!s)
            return false;
        s++;
    }
    size_t len = strcspn(s, "_.");
    if (len == 0 || len >= size)
        return false;
    memcpy(out, s, len);
    out[len] = '\0';
    return true;
}

/* The Laban vector of m as the laban table stores it (float32, missing = NaN). */
static int laban(const affect_motion *m, const char *what, double *out)
{
    affect_laban_options o;
    affect_laban_options_default(&o);
    o.missing_null = true;
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    affect_error err;
    double v[P];
    if (affect_laban_vector(m, &roles, &o, v, &err)) {
        fprintf(stderr, "bench_rmlr: %s: %s\n", what, err.msg);
        return 1;
    }
    for (int j = 0; j < P; j++)
        out[j] = fabs(v[j]) <= FLT_MAX ? (double)(float)v[j] : NAN;
    return 0;
}

static int add_row(dataset *d, const char *label, const double *v)
{
    if (d->n == d->cap) {
        size_t cap = d->cap ? 2 * d->cap : 64;
        double *x = realloc(d->x, cap * P * sizeof *x);
        if (x)
            d->x = x;
        char **l = realloc(d->label_of, cap * sizeof *l);
        if (l)
            d->label_of = l;
        if (!x || !l)
            return 1;
        d->cap = cap;
    }
    d->label_of[d->n] = strdup(label);
    if (!d->label_of[d->n])
        return 1;
    memcpy(d->x + d->n * P, v, P * sizeof *v);
    d->n++;
    return 0;
}

static int cmp_label(const void *a, const void *b)
{
    return strcmp(a, b);
}

/* Numbers the labels in byte order and imputes the missing components. */
static int finish(dataset *d)
{
    d->K = 0;
    for (size_t i = 0; i < d->n; i++) {
        uint32_t k = 0;
        while (k < d->K && strcmp(d->labels[k], d->label_of[i]) != 0)
            k++;
        if (k == d->K) {
            if (d->K == MAX_LABELS)
                return 1;
            snprintf(d->labels[d->K++], MAX_FIELD, "%s", d->label_of[i]);
        }
    }
    qsort(d->labels, d->K, MAX_FIELD, cmp_label);
    d->y = malloc((d->n ? d->n : 1) * sizeof *d->y);
    if (!d->y)
        return 1;
    for (size_t i = 0; i < d->n; i++)
        for (uint32_t k = 0; k < d->K; k++)
            if (strcmp(d->labels[k], d->label_of[i]) == 0)
                d->y[i] = k;
    affect_impute_column_means(d->x, d->n, P);
    return 0;
}

static affect_motion *parse(const bench_text *t)
{
    affect_bvh_options bo = {.scale = 1, .unit = "cm"};
    affect_motion *m = NULL;
    affect_error err;
    if (affect_bvh_parse(t->text, t->len, &bo, &m, &err)) {
        fprintf(stderr, "bench_rmlr: %s: %s\n", t->name, err.msg);
        return NULL;
    }
    return m;
}

/* bn1-44 at 27 (d27) and 22 joints (d22). 1: no corpus, 2: error. */
static int load_bn1(const char *dir, dataset *d27, dataset *d22)
{
    bench_text *t;
    size_t n, bytes;
    int rc = bench_load_texts(dir, ".bvh", &t, &n, &bytes);
    if (rc)
        return rc;
    /* the contents recorded in all four emotions */
    char contents[256][MAX_FIELD];
    unsigned mask[256];
    size_t n_contents = 0;
    for (size_t i = 0; i < n; i++) {
        char c[MAX_FIELD], e[MAX_FIELD];
        if (!field(t[i].name, 1, c, sizeof c) || !field(t[i].name, 2, e, sizeof e))
            continue;
        for (unsigned k = 0; k < 4; k++) {
            if (strcmp(e, emotions[k]) != 0)
                continue;
            size_t ci = 0;
            while (ci < n_contents && strcmp(contents[ci], c) != 0)
                ci++;
            if (ci == n_contents && n_contents < 256) {
                snprintf(contents[n_contents], MAX_FIELD, "%s", c);
                mask[n_contents++] = 0;
            }
            if (ci < n_contents)
                mask[ci] |= 1u << k;
        }
    }
    for (size_t i = 0; i < n && !rc; i++) {
        char c[MAX_FIELD], e[MAX_FIELD];
        if (!field(t[i].name, 1, c, sizeof c) || !field(t[i].name, 2, e, sizeof e))
            continue;
        bool emotion = false, shared = false;
        for (unsigned k = 0; k < 4; k++)
            emotion = emotion || strcmp(e, emotions[k]) == 0;
        for (size_t ci = 0; ci < n_contents; ci++)
            shared = shared || (strcmp(contents[ci], c) == 0 && mask[ci] == 15u);
        if (!emotion || !shared)
            continue;
        affect_motion *m = parse(&t[i]), *m22 = NULL;
        double v[P];
        affect_error err;
        if (!m) {
            rc = 2;
            continue;
        }
        /* the 22 joints: every joint but the End Sites, in the BVH's order */
        const char *keep[64];
        uint32_t nk = 0;
        for (uint32_t j = 0; j < m->n_joints && nk < 64; j++) {
            bool end = false;
            for (size_t s = 0; s < sizeof end_sites / sizeof *end_sites; s++)
                end = end || strcmp(m->names[j], end_sites[s]) == 0;
            if (!end)
                keep[nk++] = m->names[j];
        }
        if (affect_motion_select(m, keep, nk, &m22, &err)) {
            fprintf(stderr, "bench_rmlr: %s: %s\n", t[i].name, err.msg);
            rc = 2;
        } else if (laban(m, t[i].name, v) || add_row(d27, e, v) || laban(m22, t[i].name, v) ||
                   add_row(d22, e, v)) {
            rc = 2;
        }
        affect_motion_free(m);
        affect_motion_free(m22);
    }
    for (size_t i = 0; i < n; i++) {
        free(t[i].name);
        free(t[i].text);
    }
    free(t);
    if (!rc && (finish(d27) || finish(d22)))
        rc = 2;
    return rc;
}

/* bn2-504 at 27 joints, labels the styles. 1: no corpus, 2: error. */
static int load_bn2(const char *dir, dataset *d)
{
    bench_text *t;
    size_t n, bytes;
    int rc = bench_load_texts(dir, ".bvh", &t, &n, &bytes);
    if (rc)
        return rc;
    for (size_t i = 0; i < n && !rc; i++) {
        char style[MAX_FIELD];
        double v[P];
        if (!field(t[i].name, 2, style, sizeof style)) {
            fprintf(stderr, "bench_rmlr: %s: no style in the name\n", t[i].name);
            rc = 2;
            continue;
        }
        affect_motion *m = parse(&t[i]);
        if (!m || laban(m, t[i].name, v) || add_row(d, style, v))
            rc = 2;
        affect_motion_free(m);
    }
    for (size_t i = 0; i < n; i++) {
        free(t[i].name);
        free(t[i].text);
    }
    free(t);
    if (!rc && finish(d))
        rc = 2;
    return rc;
}

/* The largest KKT violations of m's refit on d, relative to λ: *nz over the non-zero
 * coefficients, *zero over the zero ones (|g| − λα; ≤ 0 when none violates). */
static int kkt(const dataset *d, const affect_rmlr *m, double *nz, double *zero)
{
    uint32_t K = d->K;
    const double *mean = affect_rmlr_means(m), *sd = affect_rmlr_sds(m);
    const double *beta = affect_rmlr_beta(m);
    double lam = affect_rmlr_lambda(m), alpha = affect_rmlr_alpha(m);
    double *z = malloc(d->n * P * sizeof *z), *pr = malloc(d->n * K * sizeof *pr);
    if (!z || !pr) {
        free(z);
        free(pr);
        return 1;
    }
    for (size_t i = 0; i < d->n; i++) {
        for (size_t j = 0; j < P; j++)
            z[i * P + j] = sd[j] > 0 ? (d->x[i * P + j] - mean[j]) / sd[j] : 0;
        affect_rmlr_predict(m, d->x + i * P, pr + i * K);
    }
    *nz = 0;
    *zero = -INFINITY;
    for (uint32_t k = 0; k < K; k++)
        for (size_t j = 0; j < P; j++) {
            double g = 0, b = beta[k * P + j];
            for (size_t i = 0; i < d->n; i++)
                g += z[i * P + j] * ((d->y[i] == k) - pr[i * K + k]);
            g /= (double)d->n;
            if (sd[j] == 0)
                continue;
            if (b != 0) {
                double v = fabs(g - lam * (1 - alpha) * b - lam * alpha * (b > 0 ? 1 : -1));
                if (v / lam > *nz)
                    *nz = v / lam;
            } else if ((fabs(g) - lam * alpha) / lam > *zero) {
                *zero = (fabs(g) - lam * alpha) / lam;
            }
        }
    free(z);
    free(pr);
    return 0;
}

static uint64_t fnv1a(const unsigned char *p, size_t n)
{
    uint64_t h = 14695981039346656037u;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211u;
    }
    return h;
}

static int bench(const dataset *d, unsigned runs, uint32_t threads, double *cpu_median)
{
    affect_rmlr_options o;
    affect_rmlr_options_default(&o);
    o.seed = 1;
    o.folds = 10;
    o.lambda_min_ratio = 0.01;
    o.threads = threads;
    double wall[MAX_RUNS], cpu[MAX_RUNS];
    affect_rmlr *m = NULL;
    for (unsigned r = 0; r < runs; r++) {
        affect_error err;
        affect_rmlr_free(m);
        m = NULL;
        double t0 = now(), c0 = cpu_now();
        if (affect_rmlr_cv(d->x, d->n, P, d->y, d->K, &o, &m, &err)) {
            fprintf(stderr, "bench_rmlr: %s: %s\n", d->name, err.msg);
            return 1;
        }
        cpu[r] = cpu_now() - c0;
        wall[r] = now() - t0;
    }
    bench_summary sw = bench_summarize(wall, runs), sc = bench_summarize(cpu, runs);
    size_t nonzero = 0;
    const double *beta = affect_rmlr_beta(m);
    for (size_t i = 0; i < (size_t)d->K * P; i++)
        nonzero += beta[i] != 0;
    affect_bw w;
    affect_bw_init(&w);
    affect_rmlr_encode(m, &w);
    double v_nz = 0, v_zero = 0;
    int rc = w.failed || kkt(d, m, &v_nz, &v_zero);
    if (!rc)
        printf("%-16s %4zu %2u %2u  %7.3f %7.3f %7.3f  %7.3f  %5.2f %3u %6.4f %4zu  %016llx  "
               "%8.1e %9.1e\n",
               d->name, d->n, d->K, threads, sw.median, sw.min, sw.max, sc.median,
               affect_rmlr_alpha(m), affect_rmlr_lambda_index(m), affect_rmlr_cv_error(m), nonzero,
               (unsigned long long)fnv1a(w.data, w.len), v_nz, v_zero);
    fflush(stdout);
    *cpu_median = threads > 1 ? sw.median : sc.median;
    affect_bw_free(&w);
    affect_rmlr_free(m);
    return rc;
}

int main(int argc, char **argv)
{
    const char *dir1 = AFFECT_BENCH_CORPUS, *dir2 = AFFECT_BENCH_CORPUS2;
    unsigned runs = 3;
    uint32_t threads = 1;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--corpus1") == 0 && i + 1 < argc) {
            dir1 = argv[++i];
        } else if (strcmp(argv[i], "--corpus2") == 0 && i + 1 < argc) {
            dir2 = argv[++i];
        } else if ((strcmp(argv[i], "--runs") == 0 || strcmp(argv[i], "--threads") == 0) &&
                   i + 1 < argc) {
            char *end;
            unsigned long v = strtoul(argv[i + 1], &end, 10);
            if (*end || v < 1 || v > (strcmp(argv[i], "--runs") == 0 ? MAX_RUNS : 64)) {
                fprintf(stderr, "bench_rmlr: bad %s %s\n", argv[i], argv[i + 1]);
                return 2;
            }
            if (strcmp(argv[i], "--runs") == 0)
                runs = (unsigned)v;
            else
                threads = (uint32_t)v;
            i++;
        } else {
            fprintf(stderr, "usage: %s [--corpus1 DIR] [--corpus2 DIR] [--runs N] [--threads N]\n",
                    argv[0]);
            return 2;
        }
    }
    dataset d27 = {.name = "bn1-44 (27 j)"}, d22 = {.name = "bn1-44 (22 j)"};
    dataset d504 = {.name = "bn2-504 (27 j)"};
    int rc1 = load_bn1(dir1, &d27, &d22), rc2 = load_bn2(dir2, &d504), rc = 0;
    if (rc1 == 1)
        printf("bench_rmlr: %s cannot be opened: bn1-44 skipped\n", dir1);
    if (rc2 == 1)
        printf("bench_rmlr: %s cannot be opened: bn2-504 skipped\n", dir2);
    if (rc1 == 2 || rc2 == 2) {
        rc = 1;
        goto done;
    }
    printf("affect_rmlr_cv: 20 alpha x 100 lambda (ratio 0.01), 10 folds, seed 1; %u run%s per "
           "data set; seconds\n",
           runs, runs == 1 ? "" : "s");
    printf("%-16s %4s %2s %2s  %7s %7s %7s  %7s  %5s %3s %6s %4s  %-16s  %8s %9s\n", "data set",
           "n", "K", "th", "wall", "fastest", "slowest", "cpu", "alpha", "l_i", "cv err", "nz",
           "encoding FNV-1a", "KKT nz/λ", "KKT 0/λ");
    dataset *sets[3] = {&d22, &d27, &d504};
    const char *keys[3] = {"bn1_44_22j", "bn1_44_27j", "bn2_504_27j"};
    double cpu[3] = {-1, -1, -1};
    for (int s = 0; s < 3 && !rc; s++)
        if (sets[s]->n > 0)
            rc = bench(sets[s], runs, threads, &cpu[s]);
    for (int s = 0; s < 3 && !rc; s++)
        if (cpu[s] >= 0)
            printf("BENCH rmlr_cv_%s%s %.3f s\n", keys[s], threads > 1 ? "_threads" : "",
                   cpu[s]); /* CPU time with 1 thread, wall time with more */
done:
    dataset_free(&d22);
    dataset_free(&d27);
    dataset_free(&d504);
    return rc;
}
