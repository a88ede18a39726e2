/*
 * bench_laban.c — throughput of the 27 Laban descriptors (affect_laban_vector) in frames per
 * second on one core, next to the bound it cannot beat (reading every position once), with a
 * breakdown of where the time goes.
 *
 * Usage:
 *     bench_laban [corpus directory] [--repeat N]
 *     bash tests/bench/run.sh            # Release build, pinned to one core, prints the results
 * The directory defaults to AFFECT_BENCH_CORPUS (${AFFECT_SHARED_DIR}/corpora/bandai-namco-1/
 * data, set by tests/bench/CMakeLists.txt); every *.bvh file in it is used. When it is absent
 * the program says so and measures only the synthetic data set (exit status 0).
 *
 * Two data sets, both built in memory before any timing:
 *     corpus     every *.bvh parsed once with affect_bvh_parse (27 joints: joint_Root, 21 body
 *                joints and 5 end sites; the hulls use the 26 that are not the pelvis's
 *                ancestors, as laban.c does);
 *     synthetic  one motion of at least SYNTH_MIN_FRAMES frames: affect_motion_synth clips
 *                (every action × emotion, seeds 1, 2, …, 30 fps) of the same 26-joint skeleton
 *                copied one after another into a motion made with affect_motion_create. The
 *                joins are jumps, which changes nothing for the cost.
 * Kernels, each a pass over a data set (every motion once):
 *     read bound      sum every float of every position (16 independent accumulators, so gcc
 *                     vectorises it without reassociation): the cost of merely reading the
 *                     input, the bound for any per-frame descriptor;
 *     laban vector    affect_laban_vector with the default options (3-D convex hull);
 *     vector (box)    the same with opt.hull_box = true (bounding box, no 3-D hull);
 * and the pieces of the vector, each the very public function affect_laban_vector calls, timed
 * separately with the same inputs:
 *     shaping         affect_laban_shape_shaping: the torso's vertical and sagittal
 *                     displacements and the largest horizontal hull area (every frame's area
 *                     bounded by its octagon, hulls only for frames that can beat the best);
 *     flow (hull)     affect_laban_shape_flow, default options: per frame, gather the body joints
 *                     into doubles and affect_hull3d_volume (the vector's Shape Flow);
 *     flow (box)      the same with hull_box: the per-frame gather and bounding box;
 *     directional x2  affect_laban_shape_directional for the left and right hand;
 * and, not part of the vector, the windowed Effort series (affect_laban_series_new and every
 * window by affect_laban_series_next: the six parts and their combination, a one-frame hop):
 *     series 1 s      one-second windows;
 *     series 10 s     ten-second windows (the cost does not grow with the window).
 * (affect_laban_shape_flow also resolves the roles, once per motion; the vector is given
 * them.) "effort + rest" is the vector's CPU time minus the pieces' (the
 * default: shaping, flow (hull), directional; box: shaping, flow (box), directional): the six
 * parts' kinematics filtered in one lockstep pass (internal to laban.c, so not timed alone),
 * the 21 Effort reductions, role look-ups, allocation.
 * How it measures: as bench_import — one untimed warm-up pass, then N passes per run (N chosen
 * so that a run takes about a second, or --repeat), 5 runs, the median run reported with the
 * fastest and slowest; clock_gettime(CLOCK_MONOTONIC). Each row also gives the median run's
 * process CPU time per frame ("cpu ns/fr") and "busy", CPU over wall time of the runs (below 1
 * when the process waited for its core). Output: a table per data set, then one line per
 * metric for scripts:
 *     BENCH <metric> <value> <unit>
 * e.g. "BENCH laban_vector_corpus 412345 frames/s". Exit status 1 if a computation fails.
 */
#define _POSIX_C_SOURCE 200809L

#include "affect/io.h"
#include "affect/laban.h"
#include "affect/motion.h"
#include "affect/roles.h"
#include "affect/synth.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define BENCH_NAME "bench_laban"
#include "benchutil.h"

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS "../shared/corpora/bandai-namco-1/data"
#endif

#define SYNTH_MIN_FRAMES 100000u
#define SYNTH_FPS 30.0
#define TARGET_FRAMES_PER_SECOND 1e6

/* One motion and what the kernels need of it, resolved before timing. */
typedef struct entry {
    affect_motion *m;
    affect_roles roles;
    affect_part parts[6]; /* torso, head, left_hand, right_hand, left_foot, right_foot */
    int32_t *body;        /* the joints the hulls use */
    uint32_t n_body;
} entry;

typedef struct dataset {
    const char *name;
    entry *e;
    size_t n, cap;
    uint64_t frames;
    size_t pos_bytes;
    uint32_t max_joints;
} dataset;

/* Values the timed loops write so the compiler cannot drop their work. */
static volatile double g_sink;

static void free_dataset(dataset *d)
{
    for (size_t i = 0; i < d->n; i++) {
        affect_motion_free(d->e[i].m);
        free(d->e[i].body);
    }
    free(d->e);
    memset(d, 0, sizeof *d);
}

/* Adds a motion (taking ownership): resolves roles and parts, lists the body joints (every
 * joint but the pelvis's ancestors, as laban.c's hulls use). 0 or 1 (message printed). */
static int add_motion(dataset *d, affect_motion *m, const char *what)
{
    if (d->n == d->cap) {
        size_t cap = d->cap ? 2 * d->cap : 256;
        entry *grown = realloc(d->e, cap * sizeof *grown);
        if (!grown) {
            affect_motion_free(m);
            fprintf(stderr, "%s: out of memory\n", what);
            return 1;
        }
        d->e = grown;
        d->cap = cap;
    }
    entry *e = &d->e[d->n];
    memset(e, 0, sizeof *e);
    e->m = m;
    affect_roles_resolve(m, &e->roles);
    affect_error err;
    if (affect_parts_all(m, &e->roles, e->parts, &err)) {
        fprintf(stderr, "%s: %s\n", what, err.msg);
        affect_motion_free(m);
        return 1;
    }
    e->body = malloc(m->n_joints * sizeof *e->body);
    if (!e->body) {
        fprintf(stderr, "%s: out of memory\n", what);
        affect_motion_free(m);
        return 1;
    }
    int32_t pelvis = e->roles.joint[AFFECT_ROLE_PELVIS];
    for (uint32_t j = 0; j < m->n_joints; j++) {
        bool ancestor = false;
        for (int32_t p = pelvis >= 0 ? m->parents[pelvis] : -1, guard = 0;
             p >= 0 && guard <= (int32_t)m->n_joints; p = m->parents[p], guard++)
            if (p == (int32_t)j)
                ancestor = true;
        if (!ancestor)
            e->body[e->n_body++] = (int32_t)j;
    }
    d->n++;
    d->frames += m->n_frames;
    d->pos_bytes += (size_t)m->n_frames * m->n_joints * 3 * sizeof(float);
    if (m->n_joints > d->max_joints)
        d->max_joints = m->n_joints;
    return 0;
}

/* Every *.bvh of dir, parsed; 1 when dir cannot be opened, 2 on any other error. */
static int load_corpus(const char *dir, dataset *d)
{
    char **names;
    size_t n;
    int rc = bench_list_files(dir, ".bvh", &names, &n);
    if (rc == 1)
        return 1;
    char path[4096];
    for (size_t i = 0; i < n && !rc; i++) {
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        size_t len = 0;
        char *text = bench_read_file(path, &len);
        if (!text) {
            fprintf(stderr, "cannot read %s: %s\n", path, strerror(errno));
            rc = 2;
            break;
        }
        affect_motion *m = NULL;
        affect_error err;
        if (affect_bvh_parse(text, len, NULL, &m, &err)) {
            fprintf(stderr, "%s: %s\n", names[i], err.msg);
            rc = 2;
        } else if (add_motion(d, m, names[i])) {
            rc = 2;
        }
        free(text);
    }
    for (size_t i = 0; i < n; i++)
        free(names[i]);
    free(names);
    return rc;
}

/* One long motion: synthetic clips of every action × emotion with seeds 1, 2, …, copied one
 * after another until there are at least SYNTH_MIN_FRAMES frames. */
static int build_synthetic(dataset *d, uint32_t *n_clips)
{
    affect_synth_options so;
    affect_synth_options_default(&so);
    so.fps = SYNTH_FPS;
    affect_motion **clips = NULL, *big = NULL;
    size_t n = 0, cap = 0;
    uint64_t total = 0;
    int rc = 1;
    affect_error err;
    for (uint64_t seed = 1; total < SYNTH_MIN_FRAMES; seed++) {
        for (int a = 0; affect_synth_actions[a] && total < SYNTH_MIN_FRAMES; a++) {
            for (int e = 0; affect_synth_emotions[e] && total < SYNTH_MIN_FRAMES; e++) {
                if (n == cap) {
                    cap = cap ? 2 * cap : 64;
                    affect_motion **grown = realloc(clips, cap * sizeof *grown);
                    if (!grown)
                        goto done;
                    clips = grown;
                }
                if (affect_motion_synth(affect_synth_actions[a], affect_synth_emotions[e], seed,
                                        &so, &clips[n], &err)) {
                    fprintf(stderr, "synth %s %s %llu: %s\n", affect_synth_actions[a],
                            affect_synth_emotions[e], (unsigned long long)seed, err.msg);
                    goto done;
                }
                total += clips[n++]->n_frames;
            }
        }
    }
    const affect_motion *first = clips[0];
    if (affect_motion_create((uint32_t)total, first->n_joints, first->fps, &big, &err) ||
        affect_motion_set_unit(big, first->unit, &err)) {
        fprintf(stderr, "synthetic motion: %s\n", err.msg);
        goto done;
    }
    for (uint32_t j = 0; j < first->n_joints; j++) {
        if (affect_motion_set_name(big, j, first->names[j], strlen(first->names[j]), &err)) {
            fprintf(stderr, "synthetic motion: %s\n", err.msg);
            goto done;
        }
        big->parents[j] = first->parents[j];
    }
    size_t at = 0;
    for (size_t i = 0; i < n; i++) {
        if (clips[i]->n_joints != first->n_joints) {
            fprintf(stderr, "synthetic clip %zu has %u joints, expected %u\n", i,
                    clips[i]->n_joints, first->n_joints);
            goto done;
        }
        size_t count = (size_t)clips[i]->n_frames * first->n_joints * 3;
        memcpy(big->pos + at, clips[i]->pos, count * sizeof *big->pos);
        at += count;
    }
    if (affect_motion_validate(big, &err)) {
        fprintf(stderr, "synthetic motion: %s\n", err.msg);
        goto done;
    }
    rc = add_motion(d, big, "synthetic motion");
    big = NULL;
    *n_clips = (uint32_t)n;
done:
    affect_motion_free(big);
    for (size_t i = 0; i < n; i++)
        affect_motion_free(clips[i]);
    free(clips);
    return rc;
}

/* ---- the kernels: one pass over the data set; non-zero return = failure ---- */

typedef int (*kernel_fn)(const dataset *d, void *ctx);

static int k_read(const dataset *d, void *ctx)
{
    (void)ctx;
    float acc[16] = {0};
    for (size_t i = 0; i < d->n; i++) {
        const affect_motion *m = d->e[i].m;
        const float *p = m->pos;
        size_t n = (size_t)m->n_frames * m->n_joints * 3, k = 0;
        for (; k + 16 <= n; k += 16)
            for (int a = 0; a < 16; a++)
                acc[a] += p[k + a];
        for (; k < n; k++)
            acc[0] += p[k];
    }
    double s = 0;
    for (int a = 0; a < 16; a++)
        s += acc[a];
    g_sink += s;
    return 0;
}

/* ctx: the affect_laban_options */
static int k_vector(const dataset *d, void *ctx)
{
    const affect_laban_options *opt = ctx;
    double out[AFFECT_LABAN_N];
    for (size_t i = 0; i < d->n; i++) {
        affect_error err;
        if (affect_laban_vector(d->e[i].m, &d->e[i].roles, opt, out, &err)) {
            fprintf(stderr, "laban vector of motion %zu: %s\n", i, err.msg);
            return 1;
        }
        g_sink += out[0] + out[AFFECT_LABAN_N - 1];
    }
    return 0;
}

/* ctx: the affect_laban_options */
static int k_shaping(const dataset *d, void *ctx)
{
    const affect_laban_options *opt = ctx;
    for (size_t i = 0; i < d->n; i++) {
        double v[3];
        affect_error err;
        if (affect_laban_shape_shaping(d->e[i].m, &d->e[i].roles, opt, v, &err)) {
            fprintf(stderr, "shape shaping of motion %zu: %s\n", i, err.msg);
            return 1;
        }
        g_sink += v[2];
    }
    return 0;
}

/* ctx: the affect_laban_options (default: the 3-D hull; hull_box: the bounding box) */
static int k_flow(const dataset *d, void *ctx)
{
    const affect_laban_options *opt = ctx;
    for (size_t i = 0; i < d->n; i++) {
        double v;
        affect_error err;
        if (affect_laban_shape_flow(d->e[i].m, opt, &v, &err)) {
            fprintf(stderr, "shape flow of motion %zu: %s\n", i, err.msg);
            return 1;
        }
        g_sink += v;
    }
    return 0;
}

static int k_directional(const dataset *d, void *ctx)
{
    const affect_laban_options *opt = ctx;
    for (size_t i = 0; i < d->n; i++) {
        for (int h = 2; h <= 3; h++) {
            double v;
            affect_error err;
            if (affect_laban_shape_directional(d->e[i].m, &d->e[i].parts[h], opt, &v, &err)) {
                fprintf(stderr, "shape directional of motion %zu: %s\n", i, err.msg);
                return 1;
            }
            g_sink += v;
        }
    }
    return 0;
}

/* ctx: the window in seconds (a double). The windowed Effort series of the six parts and their
 * combination, one-frame hop: every window computed and read (affect_laban_series_next). */
static int k_series(const dataset *d, void *ctx)
{
    const double *seconds = ctx;
    for (size_t i = 0; i < d->n; i++) {
        const affect_motion *m = d->e[i].m;
        affect_laban_series_options so;
        affect_laban_series_options_default(&so);
        so.window = affect_laban_series_frames(*seconds, m->fps);
        so.combined = true;
        affect_laban_series *s = NULL;
        affect_error err;
        if (affect_laban_series_new(m, d->e[i].parts, 6, NULL, &so, &s, &err)) {
            fprintf(stderr, "laban series of motion %zu: %s\n", i, err.msg);
            return 1;
        }
        double v[7 * AFFECT_SERIES_N], sum = 0;
        uint32_t first, last;
        affect_status st;
        while ((st = affect_laban_series_next(s, &first, &last, v, &err)) == AFFECT_OK)
            sum += v[0] + v[6 * AFFECT_SERIES_N + AFFECT_SERIES_FLOW];
        affect_laban_series_free(s);
        if (st != AFFECT_ERR_RANGE) {
            fprintf(stderr, "laban series of motion %zu: %s\n", i, err.msg);
            return 1;
        }
        g_sink += sum;
    }
    return 0;
}

/* One kernel over a data set, measured by bench_measure (benchutil.h). */
typedef struct pass_args {
    const dataset *d;
    kernel_fn fn;
    void *ctx;
} pass_args;

static int one_pass(void *arg)
{
    const pass_args *a = arg;
    return a->fn(a->d, a->ctx);
}

static int measure(const dataset *d, kernel_fn fn, void *ctx, unsigned repeat, result *r)
{
    pass_args a = {d, fn, ctx};
    return bench_measure(one_pass, &a, repeat, r);
}

enum {
    K_READ,
    K_VECTOR,
    K_BOX,
    K_SHAPING,
    K_FLOW,
    K_FLOWBOX,
    K_DIR,
    K_SERIES,
    K_SERIES10,
    K_COUNT
};

static const char *const kernel_names[K_COUNT] = {
    "read bound",   "laban vector",     "vector (box)", "  shaping",  "  flow (hull)",
    "  flow (box)", "  directional x2", "series 1 s",   "series 10 s"};
static const char *const kernel_keys[K_COUNT] = {
    "read_bound",     "laban_vector", "laban_vector_box", "shape_shaping",   "shape_flow",
    "shape_flow_box", "directional2", "laban_series_1s",  "laban_series_10s"};

/* Seconds per pass over the data set: wall clock (the median run) and that run's process CPU
 * time (which leaves out the time the process waited for its core on a shared machine). */
static double per_pass(const result *r)
{
    return r->median / r->repeat;
}

static double cpu_per_pass(const result *r)
{
    return r->cpu_median / r->repeat;
}

static void row(const char *name, const result *r, double frames, double vector_s)
{
    double s = per_pass(r);
    printf("%-17s %7u %9.4f %9.4f %9.4f %13.0f %10.1f %8.1f%% %10.1f %5.2f\n", name, r->repeat,
           r->median, r->min, r->max, frames / s, s / frames * 1e9, 100.0 * s / vector_s,
           cpu_per_pass(r) / frames * 1e9, r->busy);
}

/* Measures and reports one data set; key names it in the BENCH lines. */
static int run_dataset(const dataset *d, const char *key, unsigned repeat)
{
    affect_laban_options def, box;
    double one_second = 1.0, ten_seconds = 10.0;
    affect_laban_options_default(&def);
    box = def;
    box.hull_box = true;
    struct {
        kernel_fn fn;
        void *ctx;
    } k[K_COUNT] = {{k_read, NULL},        {k_vector, &def},        {k_vector, &box},
                    {k_shaping, &def},     {k_flow, &def},          {k_flow, &box},
                    {k_directional, &def}, {k_series, &one_second}, {k_series, &ten_seconds}};
    result r[K_COUNT];
    for (int i = 0; i < K_COUNT; i++)
        if (measure(d, k[i].fn, k[i].ctx, repeat, &r[i]))
            return 1;

    /* the remainders from CPU times: the kernels run one after another, and on a shared
     * machine their wall-clock times are taken under different loads */
    double frames = (double)d->frames;
    double vec_s = per_pass(&r[K_VECTOR]), read_s = per_pass(&r[K_READ]);
    double shape_cpu = cpu_per_pass(&r[K_SHAPING]) + cpu_per_pass(&r[K_DIR]);
    double other_s = cpu_per_pass(&r[K_VECTOR]) - shape_cpu - cpu_per_pass(&r[K_FLOW]);
    double other_box_s = cpu_per_pass(&r[K_BOX]) - shape_cpu - cpu_per_pass(&r[K_FLOWBOX]);

    printf("%-17s %7s %9s %9s %9s %13s %10s %9s %10s %5s\n", "kernel", "passes", "median",
           "fastest", "slowest", "frames/s", "ns/frame", "% vector", "cpu ns/fr", "busy");
    for (int i = 0; i < K_COUNT; i++)
        row(kernel_names[i], &r[i], frames, vec_s);
    printf("%-17s %7s %9s %9s %9s %13s %10s %9s %10.1f\n", "  effort+rest", "", "", "", "", "", "",
           "", other_s / frames * 1e9);
    printf("%-17s %7s %9s %9s %9s %13s %10s %9s %10.1f\n", "  effort+rest box", "", "", "", "", "",
           "", "", other_box_s / frames * 1e9);
    printf("\nread bound: %.1f MB/s; laban vector runs at %.2f%% of its speed (%.0fx slower), "
           "vector (box) at %.2f%% (%.0fx slower)\n",
           (double)d->pos_bytes / read_s / 1e6, 100.0 * read_s / vec_s, vec_s / read_s,
           100.0 * read_s / per_pass(&r[K_BOX]), per_pass(&r[K_BOX]) / read_s);
    double fps = frames / vec_s, fps_box = frames / per_pass(&r[K_BOX]);
    printf("target: >= 1,000,000 frames/s on one core: default %s (%.0f frames/s, %.2fx %s); "
           "box %s (%.0f frames/s, %.2fx %s)\n\n",
           fps >= TARGET_FRAMES_PER_SECOND ? "met" : "NOT met", fps,
           fps >= TARGET_FRAMES_PER_SECOND ? fps / TARGET_FRAMES_PER_SECOND
                                           : TARGET_FRAMES_PER_SECOND / fps,
           fps >= TARGET_FRAMES_PER_SECOND ? "above" : "short",
           fps_box >= TARGET_FRAMES_PER_SECOND ? "met" : "NOT met", fps_box,
           fps_box >= TARGET_FRAMES_PER_SECOND ? fps_box / TARGET_FRAMES_PER_SECOND
                                               : TARGET_FRAMES_PER_SECOND / fps_box,
           fps_box >= TARGET_FRAMES_PER_SECOND ? "above" : "short");

    for (int i = 0; i < K_COUNT; i++)
        printf("BENCH %s_%s %.0f frames/s\n", kernel_keys[i], key, frames / per_pass(&r[i]));
    for (int i = K_VECTOR; i < K_COUNT; i++)
        printf("BENCH %s_%s_time %.1f ns/frame\n", kernel_keys[i], key,
               per_pass(&r[i]) / frames * 1e9);
    for (int i = K_VECTOR; i < K_COUNT; i++)
        printf("BENCH %s_%s_cpu_time %.1f ns/frame\n", kernel_keys[i], key,
               cpu_per_pass(&r[i]) / frames * 1e9);
    printf("BENCH effort_rest_%s_cpu_time %.1f ns/frame\n", key, other_s / frames * 1e9);
    printf("BENCH effort_rest_box_%s_cpu_time %.1f ns/frame\n", key, other_box_s / frames * 1e9);
    printf("BENCH read_bound_%s_throughput %.1f MB/s\n", key, (double)d->pos_bytes / read_s / 1e6);
    printf("BENCH laban_vector_%s_vs_read_bound %.6f ratio\n", key, read_s / vec_s);
    printf("BENCH laban_vector_box_%s_vs_read_bound %.6f ratio\n", key,
           read_s / per_pass(&r[K_BOX]));
    printf("\n");
    return 0;
}

int main(int argc, char **argv)
{
    const char *dir = AFFECT_BENCH_CORPUS;
    unsigned repeat;
    if (bench_dir_args(argc, argv, &dir, &repeat))
        return 2;

    printf("%d runs per kernel, each of 'passes' passes over the data set; times in seconds "
           "per run;\nframes/s and ns/frame per pass; %% vector = share of the default laban "
           "vector's time\n\n",
           RUNS);
    int rc = 0;
    dataset corpus = {.name = "corpus"}, synth = {.name = "synthetic"};
    int lc = load_corpus(dir, &corpus);
    if (lc == 1) {
        printf("bench_laban: corpus directory %s not found: measuring the synthetic motion "
               "only\n\n",
               dir);
    } else if (lc == 0 && corpus.n == 0) {
        printf("bench_laban: no .bvh files in %s: measuring the synthetic motion only\n\n", dir);
    } else if (lc) {
        rc = 1;
    } else {
        const entry *e0 = &corpus.e[0];
        printf("== data set: corpus %s\n", dir);
        printf("  %zu motions, %llu frames, %u joints (hulls over %u body joints), positions "
               "%.2f MB\n\n",
               corpus.n, (unsigned long long)corpus.frames, e0->m->n_joints, e0->n_body,
               (double)corpus.pos_bytes / 1e6);
        rc = run_dataset(&corpus, "corpus", repeat);
    }
    free_dataset(&corpus);

    uint32_t clips = 0;
    if (!rc && build_synthetic(&synth, &clips))
        rc = 1;
    if (!rc) {
        const entry *e0 = &synth.e[0];
        printf("== data set: synthetic\n");
        printf("  1 motion of %llu frames (%u motion_synth clips at %.0f fps), %u joints (hulls "
               "over %u body joints), positions %.2f MB\n\n",
               (unsigned long long)synth.frames, clips, SYNTH_FPS, e0->m->n_joints, e0->n_body,
               (double)synth.pos_bytes / 1e6);
        rc = run_dataset(&synth, "synthetic", repeat);
    }
    free_dataset(&synth);
    return rc;
}
