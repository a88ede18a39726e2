/*
 * bench_skeleton.c — skeletal motions on the real corpora: BVH export throughput next to BVH
 * import, inverse kinematics and the rigid projection in joint-frames per second, and the BVH
 * round trip's position error as a by-product.
 *
 * Usage:
 *     bench_skeleton [corpus directory ...] [--repeat N] [--only KERNEL]
 *     bash tests/bench/run.sh            # Release build, pinned to one core
 * The directories default to AFFECT_BENCH_CORPUS and AFFECT_BENCH_CORPUS2
 * (${AFFECT_SHARED_DIR}/corpora/bandai-namco-1/data and .../bandai-namco-2-dev/data, set by
 * tests/bench/CMakeLists.txt); every *.bvh file of each is used. A directory that is absent is
 * skipped with a message; when none is present the program says so and exits 0. --only runs
 * one kernel (import, export, reimport, rigid or ik), e.g. under perf or callgrind.
 *
 * How it measures, per corpus: every file is read into memory and parsed once with
 * affect_bvh_parse (the skeletal motion: skeleton, local rotations, translations, positions),
 * and a position-only copy of each is made (affect_motion_clone, affect_motion_drop_skeleton).
 * Before timing, every motion is exported once (affect_bvh_write, default options: each
 * joint's own channels, 6 decimals), the text re-imported and its positions compared with the
 * original import's, joint by joint (matched by name): the round trip's largest position
 * error. Each position-only copy also goes once through affect_motion_ik and
 * affect_motion_rigid, and the largest distances between their positions and the input's are
 * printed. Then five kernels run, single-threaded, each a pass over the whole corpus,
 * repeated so that one run takes about a second (or --repeat N), after an untimed warm-up
 * pass; 5 runs, the median run reported with the fastest and slowest (as bench_measure in
 * benchutil.h does):
 *     bvh import    affect_bvh_parse of every original file and affect_motion_free (MB/s of
 *                   the files' text);
 *     bvh export    affect_bvh_write of every skeletal motion and free of the text (MB/s of
 *                   the text written);
 *     re-import     affect_bvh_parse of the exported texts (MB/s of that text: import of the
 *                   exporter's number format, so export / re-import compares like with like);
 *     rigid         affect_motion_rigid of every position-only copy, default options, and
 *                   free (joint-frames/s);
 *     ik total      affect_motion_ik of every position-only copy, default options (the rigid
 *                   projection, the rest skeleton, the rotations, forward kinematics of the
 *                   result), and free.
 * A joint-frame is one joint in one frame; joints are all of the motion's joints (End Sites
 * and the fixed joint_Root included). Times come from clock_gettime(CLOCK_MONOTONIC); MB are
 * 10^6 bytes. Each row also shows its runs' CPU time over their wall time (cpu/wall,
 * CLOCK_PROCESS_CPUTIME_ID; well below 1 means the core was shared with other jobs and the
 * row's times are too long) and the rate computed from CPU time. Output: the machine, a table
 * per corpus, a goal line per goal ("met" or "NOT met", on wall time), then one line per
 * metric for scripts:
 *     BENCH <metric>.<corpus> <value> <unit>
 * Goals: export >= 200 MB/s of text written; IK total >= 1,000,000 joint-frames/s; both on
 * one core. Exit status 1 if any call fails (no numbers are reported for work that did not
 * happen).
 */
#define _GNU_SOURCE

#include "affect/io.h"
#include "affect/motion.h"
#include "affect/skeleton.h"

#include <errno.h>
#include <math.h>
#include <sched.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define BENCH_NAME "bench_skeleton"
#include "benchutil.h"

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS "../shared/corpora/bandai-namco-1/data"
#endif
#ifndef AFFECT_BENCH_CORPUS2
#define AFFECT_BENCH_CORPUS2 "../shared/corpora/bandai-namco-2-dev/data"
#endif
#ifndef AFFECT_BUILD_TYPE
#define AFFECT_BUILD_TYPE "unknown"
#endif
#ifndef AFFECT_COMPILE_FLAGS
#define AFFECT_COMPILE_FLAGS "unknown"
#endif

#define GOAL_EXPORT_MBS 200.0
#define GOAL_IK_JFS 1e6

typedef struct item {
    bench_text file; /* the BVH file: name, text, len (first: bench_load_items) */
    char *out;       /* its export */
    size_t out_len;
    affect_motion *m;   /* skeletal, as imported */
    affect_motion *pos; /* position-only copy */
} item;

typedef struct corpus {
    const char *dir;
    char tag[128]; /* the corpus's name for BENCH lines */
    item *items;
    size_t n, cap;
    size_t text_bytes, out_bytes;
    uint64_t frames, joint_frames;
    uint32_t min_joints, max_joints;
    /* round trip: largest distance, where */
    double rt_max, rt_max_coord, rt_body;
    size_t rt_item;
    uint32_t rt_frame, rt_joint;
    /* by-products of IK: the largest distance between the rigid projection's positions and
     * the input's, between IK's and the rigid projection's, between IK's and the input's; the
     * input's largest bone-length variation */
    double rigid_max, ik_rigid_max, ik_max, bone_var;
    size_t rigid_item, ik_rigid_item, ik_item, bone_var_item;
    uint32_t ik_rigid_frame, ik_rigid_joint;
} corpus;

/* Values the timed loops write so the compiler cannot drop their work. */
static volatile uint64_t g_sink;

static void free_corpus(corpus *c)
{
    for (size_t i = 0; i < c->n; i++) {
        bench_free_text(&c->items[i].file);
        affect_free(c->items[i].out);
        affect_motion_free(c->items[i].m);
        affect_motion_free(c->items[i].pos);
    }
    free(c->items);
    c->items = NULL;
    c->n = c->cap = 0;
}

/* "…/bandai-namco-1/data" → "bandai-namco-1"; otherwise the last path component. */
static void corpus_tag(const char *dir, char *tag, size_t cap)
{
    char buf[4096];
    snprintf(buf, sizeof buf, "%s", dir);
    size_t n = strlen(buf);
    while (n > 1 && buf[n - 1] == '/')
        buf[--n] = '\0';
    char *last = strrchr(buf, '/');
    if (last && strcmp(last + 1, "data") == 0 && last != buf) {
        *last = '\0';
        last = strrchr(buf, '/');
    }
    const char *name = last ? last + 1 : buf;
    size_t k = strlen(name) < cap ? strlen(name) : cap - 1;
    memcpy(tag, name, k);
    tag[k] = '\0';
}

/* Reads every *.bvh of dir, sorted by name; 1 when dir cannot be opened, 2 on any other
 * error. */
static int load_corpus(const char *dir, corpus *c)
{
    void *items;
    int rc = bench_load_items(dir, ".bvh", sizeof *c->items, &items, &c->n, &c->text_bytes);
    c->items = items;
    c->cap = c->n;
    return rc;
}

/* Largest joint distance between a's and b's positions (joints matched by name). */
static int max_distance(const affect_motion *a, const affect_motion *b, double *dist, double *coord,
                        uint32_t *frame, uint32_t *joint, const char *what)
{
    *dist = *coord = 0;
    *frame = *joint = 0;
    if (a->n_frames != b->n_frames || a->n_joints != b->n_joints) {
        fprintf(stderr, "%s: %u frames x %u joints, expected %u x %u\n", what, b->n_frames,
                b->n_joints, a->n_frames, a->n_joints);
        return 1;
    }
    for (uint32_t j = 0; j < a->n_joints; j++) {
        int32_t k = affect_motion_find_joint(b, a->names[j]);
        if (k < 0) {
            fprintf(stderr, "%s: joint %s is missing\n", what, a->names[j]);
            return 1;
        }
        for (uint32_t t = 0; t < a->n_frames; t++) {
            const float *p = affect_motion_at(a, t, j), *q = affect_motion_at(b, t, (uint32_t)k);
            double d2 = 0;
            for (int x = 0; x < 3; x++) {
                double d = (double)q[x] - (double)p[x];
                d2 += d * d;
                if (fabs(d) > *coord)
                    *coord = fabs(d);
            }
            if (sqrt(d2) > *dist) {
                *dist = sqrt(d2);
                *frame = t;
                *joint = j;
            }
        }
    }
    return 0;
}

/* Parses each file once (checking it), makes its position-only copy, exports and re-imports
 * it (the round trip's error), and runs IK and the rigid projection once on the copy (their
 * distances to the input, and the input's bone-length variation). */
static int prepare(corpus *c)
{
    c->min_joints = UINT32_MAX;
    for (size_t i = 0; i < c->n; i++) {
        item *it = &c->items[i];
        affect_error err;
        affect_bvh_write_options wo;
        affect_bvh_write_options_default(&wo);
        if (affect_bvh_parse(it->file.text, it->file.len, NULL, &it->m, &err) ||
            affect_motion_clone(it->m, &it->pos, &err)) {
            fprintf(stderr, "%s: %s\n", it->file.name, err.msg);
            return 1;
        }
        if (!it->m->rot) {
            fprintf(stderr, "%s: the import kept no rotations\n", it->file.name);
            return 1;
        }
        affect_motion_drop_skeleton(it->pos);
        if (affect_bvh_write(it->m, &wo, &it->out, &it->out_len, &err)) {
            fprintf(stderr, "%s (export): %s\n", it->file.name, err.msg);
            return 1;
        }
        c->frames += it->m->n_frames;
        c->joint_frames += (uint64_t)it->m->n_frames * it->m->n_joints;
        c->out_bytes += it->out_len;
        if (it->m->n_joints < c->min_joints)
            c->min_joints = it->m->n_joints;
        if (it->m->n_joints > c->max_joints)
            c->max_joints = it->m->n_joints;

        affect_motion *back = NULL;
        if (affect_bvh_parse(it->out, it->out_len, NULL, &back, &err)) {
            fprintf(stderr, "%s (re-import of the export): %s\n", it->file.name, err.msg);
            return 1;
        }
        double d, coord;
        uint32_t t, j;
        int rc = max_distance(it->m, back, &d, &coord, &t, &j, it->file.name);
        affect_motion_free(back);
        if (rc)
            return 1;
        if (coord > c->rt_max_coord)
            c->rt_max_coord = coord;
        if (d > c->rt_max || i == 0) {
            c->rt_max = d;
            c->rt_item = i;
            c->rt_frame = t;
            c->rt_joint = j;
            c->rt_body = affect_motion_body_size(it->m);
        }

        affect_motion *ik = NULL, *rigid = NULL;
        affect_ik_options io;
        affect_ik_options_default(&io);
        double var;
        int32_t worst;
        if (affect_motion_ik(it->pos, &io, &ik, &err) ||
            affect_motion_rigid(it->pos, &io.rigid, &rigid, &err) ||
            affect_motion_bone_variation(it->pos, &var, &worst, &err)) {
            fprintf(stderr, "%s (IK): %s\n", it->file.name, err.msg);
            affect_motion_free(ik);
            affect_motion_free(rigid);
            return 1;
        }
        double d_ik, d_rigid, d_ik_rigid;
        rc = max_distance(it->pos, ik, &d_ik, &coord, &t, &j, it->file.name) ||
             max_distance(it->pos, rigid, &d_rigid, &coord, &t, &j, it->file.name) ||
             max_distance(rigid, ik, &d_ik_rigid, &coord, &t, &j, it->file.name);
        if (!rc && (d_ik_rigid > c->ik_rigid_max || i == 0)) {
            c->ik_rigid_max = d_ik_rigid;
            c->ik_rigid_item = i;
            c->ik_rigid_frame = t;
            c->ik_rigid_joint = j;
        }
        affect_motion_free(ik);
        affect_motion_free(rigid);
        if (rc)
            return 1;
        if (d_ik > c->ik_max || i == 0) {
            c->ik_max = d_ik;
            c->ik_item = i;
        }
        if (d_rigid > c->rigid_max || i == 0) {
            c->rigid_max = d_rigid;
            c->rigid_item = i;
        }
        if (var > c->bone_var || i == 0) {
            c->bone_var = var;
            c->bone_var_item = i;
        }
    }
    return 0;
}

/* ---- the kernels: one pass over the corpus; non-zero return = failure ---- */

static int k_import(const corpus *c)
{
    for (size_t i = 0; i < c->n; i++) {
        affect_motion *m = NULL;
        affect_error err;
        if (affect_bvh_parse(c->items[i].file.text, c->items[i].file.len, NULL, &m, &err)) {
            fprintf(stderr, "%s: %s\n", c->items[i].file.name, err.msg);
            return 1;
        }
        g_sink += m->n_frames;
        affect_motion_free(m);
    }
    return 0;
}

static int k_export(const corpus *c)
{
    affect_bvh_write_options wo;
    affect_bvh_write_options_default(&wo);
    for (size_t i = 0; i < c->n; i++) {
        char *text = NULL;
        size_t len = 0;
        affect_error err;
        if (affect_bvh_write(c->items[i].m, &wo, &text, &len, &err)) {
            fprintf(stderr, "%s (export): %s\n", c->items[i].file.name, err.msg);
            return 1;
        }
        g_sink += len + (unsigned char)text[len / 2];
        affect_free(text);
    }
    return 0;
}

static int k_reimport(const corpus *c)
{
    for (size_t i = 0; i < c->n; i++) {
        affect_motion *m = NULL;
        affect_error err;
        if (affect_bvh_parse(c->items[i].out, c->items[i].out_len, NULL, &m, &err)) {
            fprintf(stderr, "%s (re-import): %s\n", c->items[i].file.name, err.msg);
            return 1;
        }
        g_sink += m->n_frames;
        affect_motion_free(m);
    }
    return 0;
}

static int k_rigid(const corpus *c)
{
    affect_rigid_options ro;
    affect_rigid_options_default(&ro);
    for (size_t i = 0; i < c->n; i++) {
        affect_motion *r = NULL;
        affect_error err;
        if (affect_motion_rigid(c->items[i].pos, &ro, &r, &err)) {
            fprintf(stderr, "%s (rigid): %s\n", c->items[i].file.name, err.msg);
            return 1;
        }
        g_sink += r->n_frames;
        affect_motion_free(r);
    }
    return 0;
}

static int k_ik(const corpus *c)
{
    affect_ik_options io;
    affect_ik_options_default(&io);
    for (size_t i = 0; i < c->n; i++) {
        affect_motion *r = NULL;
        affect_error err;
        if (affect_motion_ik(c->items[i].pos, &io, &r, &err)) {
            fprintf(stderr, "%s (IK): %s\n", c->items[i].file.name, err.msg);
            return 1;
        }
        g_sink += r->n_frames;
        affect_motion_free(r);
    }
    return 0;
}

typedef int (*kernel_fn)(const corpus *c);

/* A kernel and its corpus, as bench_measure's pass argument. */
typedef struct kernel_run {
    kernel_fn fn;
    const corpus *c;
} kernel_run;

static int kernel_pass(void *arg)
{
    const kernel_run *k = arg;
    return k->fn(k->c);
}

/* bench_measure (benchutil.h: a warm-up pass, calibration when repeat is 0, RUNS runs of
 * repeat passes, wall and CPU time of each run). */
static int measure(const corpus *c, kernel_fn fn, unsigned repeat, result *tm)
{
    kernel_run k = {fn, c};
    return bench_measure(kernel_pass, &k, repeat, tm);
}

/* seconds per pass over the corpus: wall clock (the median run) and CPU time */
static double per_pass(const result *t)
{
    return t->median / t->repeat;
}

static double per_pass_cpu(const result *t)
{
    return t->cpu_median / t->repeat;
}

/* bytes > 0: a text kernel (MB/s); otherwise joint-frames/s by CPU time in the last column */
static void row(const char *name, const result *t, double bytes, double frames, double jf)
{
    double s = per_pass(t), sc = per_pass_cpu(t);
    printf("%-11s %6u %8.4f %8.4f %8.4f", name, t->repeat, t->median, t->min, t->max);
    if (bytes > 0)
        printf(" %8.1f", bytes / s / 1e6);
    else
        printf(" %8s", "");
    printf(" %9.0f %11.0f %7.1f %8.3f", frames / s, jf / s, s / jf * 1e9, t->busy);
    if (bytes > 0)
        printf(" %12.1f MB/s\n", bytes / sc / 1e6);
    else
        printf(" %12.0f jf/s\n", jf / sc);
}

/* After a goal line: a warning when the core was shared during the measurement (the verdict
 * is on wall time; says what CPU time gives). */
static void shared_note(const result *t, bool met_by_cpu)
{
    if (t->busy < 0.95)
        printf("  warning: the process ran only %.0f%% of the wall time (the core was shared); by "
               "CPU time the goal is %s; rerun on an idle core\n",
               100 * t->busy, met_by_cpu ? "met" : "NOT met");
}

/* ---- the machine ---- */

static void print_machine(void)
{
    char model[256] = "unknown", line[512];
    int logical = 0;
    long cores = 0;
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (f) {
        while (fgets(line, sizeof line, f)) {
            char *colon = strchr(line, ':');
            if (!colon)
                continue;
            char *v = colon + 1;
            while (*v == ' ' || *v == '\t')
                v++;
            v[strcspn(v, "\n")] = '\0';
            if (strncmp(line, "model name", 10) == 0) {
                logical++;
                snprintf(model, sizeof model, "%s", v);
            } else if (strncmp(line, "cpu cores", 9) == 0) {
                cores = strtol(v, NULL, 10);
            }
        }
        fclose(f);
    }
    cpu_set_t set;
    int allowed = -1;
    if (sched_getaffinity(0, sizeof set, &set) == 0)
        allowed = CPU_COUNT(&set);
    printf("machine: cpu %s; %d logical CPUs in /proc/cpuinfo", model, logical);
    if (cores > 0)
        printf(" (%ld cores per package)", cores);
    printf(", %ld online; this process may run on %d\n", sysconf(_SC_NPROCESSORS_ONLN), allowed);
#ifdef __VERSION__
    printf("compiler: %s; build %s: %s\n", __VERSION__, AFFECT_BUILD_TYPE, AFFECT_COMPILE_FLAGS);
#endif
    printf("\n");
}

/* ---- one corpus ---- */

enum { K_IMPORT, K_EXPORT, K_REIMPORT, K_RIGID, K_IK, K_COUNT };
static const char *const kernel_names[K_COUNT] = {"import", "export", "reimport", "rigid", "ik"};
static const kernel_fn kernel_fns[K_COUNT] = {k_import, k_export, k_reimport, k_rigid, k_ik};

typedef struct verdict {
    bool have_export, have_ik;
    bool export_met, ik_met;
} verdict;

/* 0: measured or skipped, 1: failure */
static int run_corpus(const char *dir, unsigned repeat, int only, verdict *v)
{
    corpus c;
    memset(&c, 0, sizeof c);
    c.dir = dir;
    corpus_tag(dir, c.tag, sizeof c.tag);
    int rc = load_corpus(dir, &c);
    if (rc == 1) {
        printf("bench_skeleton: corpus directory %s not found: skipped\n\n", dir);
        return 0;
    }
    if (!rc && c.n == 0) {
        printf("bench_skeleton: no .bvh files in %s: skipped\n\n", dir);
        free_corpus(&c);
        return 0;
    }
    double t0 = now();
    if (!rc)
        rc = prepare(&c);
    double prep_s = now() - t0;
    result r[K_COUNT];
    bool done[K_COUNT] = {false};
    for (int k = 0; k < K_COUNT && !rc; k++) {
        if (only >= 0 && k != only)
            continue;
        rc = measure(&c, kernel_fns[k], repeat, &r[k]);
        done[k] = !rc;
    }
    if (rc) {
        free_corpus(&c);
        return 1;
    }

    double text = (double)c.text_bytes, out = (double)c.out_bytes;
    double frames = (double)c.frames, jf = (double)c.joint_frames;
    printf("corpus %s: %s\n", c.tag, dir);
    printf("  %zu BVH files, %.2f MB of text, %llu frames, %u to %u joints, %.0f joint-frames; "
           "exported text %.2f MB (%.3f x the files)\n",
           c.n, text / 1e6, (unsigned long long)c.frames, c.min_joints, c.max_joints, jf, out / 1e6,
           out / text);
    printf("  (checks before timing: %.1f s)\n", prep_s);
    printf("  %d runs per kernel, each of 'passes' passes over the whole corpus; times in "
           "seconds per run (wall clock);\n  cpu/wall: the runs' CPU time over their wall time "
           "(below 1: the process waited, e.g. for other jobs on its core);\n  by CPU time: "
           "the rate from the median run's CPU time instead of its wall time\n\n",
           RUNS);
    printf("%-11s %6s %8s %8s %8s %8s %9s %11s %7s %8s %17s\n", "kernel", "passes", "median",
           "fastest", "slowest", "MB/s", "frames/s", "joint-fr/s", "ns/jf", "cpu/wall",
           "by CPU time");
    if (done[K_IMPORT])
        row("bvh import", &r[K_IMPORT], text, frames, jf);
    if (done[K_EXPORT])
        row("bvh export", &r[K_EXPORT], out, frames, jf);
    if (done[K_REIMPORT])
        row("re-import", &r[K_REIMPORT], out, frames, jf);
    if (done[K_RIGID])
        row("rigid", &r[K_RIGID], 0, frames, jf);
    if (done[K_IK])
        row("ik total", &r[K_IK], 0, frames, jf);
    if (done[K_RIGID] && done[K_IK])
        printf("\naffect_motion_rigid / IK total (time): %.2f\n",
               per_pass(&r[K_RIGID]) / per_pass(&r[K_IK]));
    printf("\n");

    const item *rt = &c.items[c.rt_item];
    printf("round trip (export with the stored rotations, 6 decimals, re-import): largest "
           "position error %.3g %s (largest coordinate error %.3g), %s frame %u joint %s; "
           "%.2g of that motion's body size\n",
           c.rt_max, rt->m->unit[0] ? rt->m->unit : "units", c.rt_max_coord, rt->file.name,
           c.rt_frame, rt->m->names[c.rt_joint], c.rt_max / c.rt_body);
    printf("IK (by-products, default options): the input's bones vary in length by up to "
           "%.3g%% (%s);\n  largest distance rigid projection - input %.3g (%s), IK - rigid "
           "projection %.3g (%s frame %u joint %s), IK - input %.3g (%s)\n",
           100 * c.bone_var, c.items[c.bone_var_item].file.name, c.rigid_max,
           c.items[c.rigid_item].file.name, c.ik_rigid_max, c.items[c.ik_rigid_item].file.name,
           c.ik_rigid_frame, c.items[c.ik_rigid_item].m->names[c.ik_rigid_joint], c.ik_max,
           c.items[c.ik_item].file.name);

    double exp_mbs = 0, imp_mbs = 0, ik_jfs = 0;
    if (done[K_EXPORT]) {
        exp_mbs = out / per_pass(&r[K_EXPORT]) / 1e6;
        v->have_export = true;
        v->export_met = exp_mbs >= GOAL_EXPORT_MBS;
    }
    if (done[K_IMPORT])
        imp_mbs = text / per_pass(&r[K_IMPORT]) / 1e6;
    if (done[K_EXPORT] && done[K_IMPORT])
        printf("export / import: %.2f (%.1f MB/s written / %.1f MB/s read)\n", exp_mbs / imp_mbs,
               exp_mbs, imp_mbs);
    if (done[K_EXPORT] && done[K_REIMPORT])
        printf("export / re-import of the exported text: %.2f\n",
               exp_mbs / (out / per_pass(&r[K_REIMPORT]) / 1e6));
    if (done[K_EXPORT]) {
        printf("goal: bvh export >= %.0f MB/s of text on one core [%s]: %s (%.1f MB/s; by CPU "
               "time %.1f MB/s, cpu/wall %.3f)\n",
               GOAL_EXPORT_MBS, c.tag, v->export_met ? "met" : "NOT met", exp_mbs,
               out / per_pass_cpu(&r[K_EXPORT]) / 1e6, r[K_EXPORT].busy);
        shared_note(&r[K_EXPORT], out / per_pass_cpu(&r[K_EXPORT]) / 1e6 >= GOAL_EXPORT_MBS);
    }
    if (done[K_IK]) {
        ik_jfs = jf / per_pass(&r[K_IK]);
        v->have_ik = true;
        v->ik_met = ik_jfs >= GOAL_IK_JFS;
        printf("goal: IK total >= %.0f joint-frames/s on one core [%s]: %s (%.0f joint-frames/s, "
               "%.2fx the goal; by CPU time %.0f, cpu/wall %.3f)\n",
               GOAL_IK_JFS, c.tag, v->ik_met ? "met" : "NOT met", ik_jfs, ik_jfs / GOAL_IK_JFS,
               jf / per_pass_cpu(&r[K_IK]), r[K_IK].busy);
        shared_note(&r[K_IK], jf / per_pass_cpu(&r[K_IK]) >= GOAL_IK_JFS);
    }
    printf("\n");

    if (done[K_IMPORT])
        printf("BENCH bvh_import_text_throughput.%s %.1f MB/s\n", c.tag, imp_mbs);
    if (done[K_EXPORT]) {
        printf("BENCH bvh_export_text_throughput.%s %.1f MB/s\n", c.tag, exp_mbs);
        printf("BENCH bvh_export_frames.%s %.0f frames/s\n", c.tag,
               frames / per_pass(&r[K_EXPORT]));
    }
    if (done[K_EXPORT] && done[K_IMPORT])
        printf("BENCH bvh_export_vs_import.%s %.4f ratio\n", c.tag, exp_mbs / imp_mbs);
    if (done[K_REIMPORT])
        printf("BENCH bvh_reimport_text_throughput.%s %.1f MB/s\n", c.tag,
               out / per_pass(&r[K_REIMPORT]) / 1e6);
    if (done[K_RIGID])
        printf("BENCH rigid_joint_frames.%s %.0f joint-frames/s\n", c.tag,
               jf / per_pass(&r[K_RIGID]));
    if (done[K_IK])
        printf("BENCH ik_joint_frames.%s %.0f joint-frames/s\n", c.tag, ik_jfs);
    for (int k = 0; k < K_COUNT; k++)
        if (done[k])
            printf("BENCH cpu_over_wall_%s.%s %.3f ratio\n", kernel_names[k], c.tag, r[k].busy);
    printf("BENCH bvh_roundtrip_max_position_error.%s %.6g %s\n", c.tag, c.rt_max,
           rt->m->unit[0] ? rt->m->unit : "units");
    printf("\n");
    free_corpus(&c);
    return 0;
}

int main(int argc, char **argv)
{
    const char *dirs[64];
    int n_dirs = 0, only = -1;
    unsigned repeat = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) {
            if (bench_parse_count("--repeat", argv[++i], MAX_REPEAT, &repeat))
                return 2;
        } else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) {
            const char *k = argv[++i];
            for (int j = 0; j < K_COUNT; j++)
                if (strcmp(k, kernel_names[j]) == 0)
                    only = j;
            if (only < 0) {
                fprintf(stderr, "--only takes import, export, reimport, rigid or ik\n");
                return 2;
            }
        } else if (argv[i][0] == '-' || n_dirs == (int)(sizeof dirs / sizeof dirs[0])) {
            fprintf(stderr,
                    "usage: %s [corpus directory ...] [--repeat N] "
                    "[--only import|export|reimport|rigid|ik]\n",
                    argv[0]);
            return 2;
        } else {
            dirs[n_dirs++] = argv[i];
        }
    }
    if (n_dirs == 0) {
        dirs[n_dirs++] = AFFECT_BENCH_CORPUS;
        dirs[n_dirs++] = AFFECT_BENCH_CORPUS2;
    }

    print_machine();
    verdict all[64];
    memset(all, 0, sizeof all);
    for (int d = 0; d < n_dirs; d++)
        if (run_corpus(dirs[d], repeat, only, &all[d]))
            return 1;

    bool any_export = false, any_ik = false, export_met = true, ik_met = true;
    for (int d = 0; d < n_dirs; d++) {
        if (all[d].have_export) {
            any_export = true;
            export_met &= all[d].export_met;
        }
        if (all[d].have_ik) {
            any_ik = true;
            ik_met &= all[d].ik_met;
        }
    }
    if (!any_export && !any_ik) {
        printf("bench_skeleton: no corpus measured\n");
        return 0;
    }
    if (any_export)
        printf("GOAL bvh export >= %.0f MB/s on one core, every corpus: %s\n", GOAL_EXPORT_MBS,
               export_met ? "met" : "NOT met");
    if (any_ik)
        printf("GOAL IK >= %.0f joint-frames/s on one core, every corpus: %s\n", GOAL_IK_JFS,
               ik_met ? "met" : "NOT met");
    return 0;
}
