/*
 * test_monitor.c — stopping long calls and watching their progress (affect/monitor.h; issue 14,
 * item 3: "every call returns interrupted within 0.2 s of the interrupt, with no leak; and a
 * progress report a user can watch").
 *
 * Each long call of the core runs on an input that takes seconds uninterrupted, with a stop
 * hook that says true from a given moment on (a time, a number of polls, or the moment the
 * progress hook shows a given stage). Checked for each: the call returns AFFECT_ERR_INTERRUPTED
 * with the message "interrupted" (classifier training and cross-validation may put their
 * stage in front: "fold 1: training the HMM of class \"sad\": interrupted"), no output, no
 * block left allocated (a counting allocator, thread-safe, installed for the whole run), and
 * the latency from the moment the stop was due to the return: printed as wall time and as the
 * process's CPU time per working thread, the latter asserted ≤ LATENCY_MAX (0.2 s, the issue's
 * goal; the 2-core test machine is shared, so the wall time also measures the other processes:
 * it is only bounded by WALL_MAX); the hooks run only on the calling thread, also with worker
 * threads. Also printed: the polls, and the largest gap between two polls with the progress
 * shown around it (where a loop that does not poll would show). The calls: affect_hmm_train
 * (full covariances, 7 states × 4 mixtures, 78 dimensions), affect_dtw_distance on two 1000 fps
 * walks, affect_rmlr_cv (1 and 2 threads), affect_classifier_train (1 and 2 threads; stopped in
 * the class HMMs and as each pass of the Fisher scores starts), affect_crossval (1 and 2
 * threads).
 * Progress: an uninterrupted run shows only stages with done ≤ total, done never decreasing
 * within a stage, and ends on done == total. A monitor that never stops changes nothing: the
 * same bytes as with a NULL monitor (HMM, classifier, RMLR and cross-validation results, DTW).
 *
 * Usage: test_monitor [PATTERN] (cmocka's test filter, e.g. "*classifier*"). ctest runs it
 * with OPENBLAS_NUM_THREADS=1 (tests/CMakeLists.txt: worker threads that call a threaded
 * OpenBLAS wait on each other). Every test frees what it holds in its teardown, so a failed
 * assertion leaks nothing, and the sanitizer build (AFFECT_SANITIZE=ON) checks the process as
 * a whole.
 */
#define _POSIX_C_SOURCE 200809L /* clock_gettime */

#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <threads.h>
#include <time.h>

#include "testutil.h"

#include "affect/classifier.h"
#include "affect/crossval.h"
#include "affect/generate.h"
#include "affect/hmm_blob.h"
#include "affect/io.h"
#include "affect/laban.h"
#include "affect/skeleton.h"
#include "affect/monitor.h"
#include "affect/rmlr.h"
#include "util/rng.h"
#include "affect/synth.h"
#include "util/bytes.h"

/* Issue 14's goal: 0.2 s from the interrupt to the return (LATENCY_MAX, on CPU time per thread,
 * see check_stopped; WALL_MAX bounds the wall time on a loaded machine). The sanitizer build
 * runs about 3 times slower. */
#if defined(__SANITIZE_ADDRESS__)
#define AFFECT_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define AFFECT_TEST_ASAN 1
#endif
#endif
#ifdef AFFECT_TEST_ASAN
#define LATENCY_MAX 0.6
#define WALL_MAX 3.0
#else
#define LATENCY_MAX 0.2
#define WALL_MAX 1.0
#endif

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static double now_s(void)
{
    return clock_s(CLOCK_MONOTONIC);
}

/* CPU time of the whole process (every thread). */
static double cpu_s(void)
{
    return clock_s(CLOCK_PROCESS_CPUTIME_ID);
}

/* ---- a thread-safe counting allocator, installed once for the whole run ---- */

static atomic_long live_blocks;

static void *count_malloc(size_t n)
{
    void *p = malloc(n);
    if (p)
        atomic_fetch_add(&live_blocks, 1);
    return p;
}

static void *count_realloc(void *p, size_t n)
{
    if (!p)
        return count_malloc(n);
    return realloc(p, n);
}

static void count_free(void *p)
{
    if (p)
        atomic_fetch_sub(&live_blocks, 1);
    free(p);
}

static const affect_allocator COUNTING = {count_malloc, count_realloc, count_free};

/* ---- the hooks ---- */

typedef struct watch {
    /* when to stop (whichever comes first) */
    double stop_at;         /* clock time (0: never) */
    long stop_after;        /* polls (0: never) */
    const char *stop_stage; /* as the progress hook shows this stage (NULL: never) */
    double due, cpu_due;    /* when the stop became due (0: not yet), process CPU time then */
    /* what the hooks saw */
    thrd_t owner;
    bool off_owner; /* a hook ran on another thread */
    long polls;
    double start, first_poll, last_poll, cpu_last_poll, max_gap;
    char here[96], gap_at[200]; /* the progress at the last poll; around the largest gap */
    long shows;
    const char *stage; /* the last progress call */
    uint64_t done, total;
    char bad[256];    /* the first inconsistent progress call, if any */
    char stages[512]; /* the stages shown, in order (a stage again after another: again) */
} watch;

static void watch_init(watch *w)
{
    memset(w, 0, sizeof *w);
    w->owner = thrd_current();
    w->start = now_s();
    snprintf(w->here, sizeof w->here, "the start");
}

static bool hook_stop(void *ctx)
{
    watch *w = ctx;
    double t = now_s(), cpu = cpu_s();
    if (!thrd_equal(thrd_current(), w->owner))
        w->off_owner = true;
    char here[96];
    snprintf(here, sizeof here, "%s %llu/%llu", w->stage ? w->stage : "no stage",
             (unsigned long long)w->done, (unsigned long long)w->total);
    if (w->polls > 0 && t - w->last_poll > w->max_gap) {
        w->max_gap = t - w->last_poll;
        snprintf(w->gap_at, sizeof w->gap_at, "from %s to %s", w->here, here);
    }
    memcpy(w->here, here, sizeof here);
    if (w->polls++ == 0)
        w->first_poll = t;
    if (w->due == 0 && w->stop_at > 0 && t >= w->stop_at) {
        w->due = w->stop_at;
        w->cpu_due = w->polls > 1 ? w->cpu_last_poll : cpu; /* at most one poll early */
    }
    if (w->due == 0 && w->stop_after > 0 && w->polls >= w->stop_after) {
        w->due = t;
        w->cpu_due = cpu;
    }
    w->last_poll = t;
    w->cpu_last_poll = cpu;
    return w->due != 0;
}

static void hook_progress(void *ctx, const char *stage, uint64_t done, uint64_t total)
{
    watch *w = ctx;
    if (!thrd_equal(thrd_current(), w->owner))
        w->off_owner = true;
    if (!w->bad[0] && (!stage || done > total))
        snprintf(w->bad, sizeof w->bad, "call %ld: stage \"%s\", done %llu > total %llu",
                 w->shows + 1, stage ? stage : "(null)", (unsigned long long)done,
                 (unsigned long long)total);
    if (!w->bad[0] && w->stage && stage && strcmp(stage, w->stage) == 0 && done < w->done &&
        total == w->total)
        snprintf(w->bad, sizeof w->bad,
                 "call %ld: stage \"%s\" went back from %llu to %llu (of %llu)", w->shows + 1,
                 stage, (unsigned long long)w->done, (unsigned long long)done,
                 (unsigned long long)total);
    if (stage && (!w->stage || strcmp(stage, w->stage) != 0)) {
        size_t len = strlen(w->stages);
        snprintf(w->stages + len, sizeof w->stages - len, "%s%s", len ? " | " : "", stage);
    }
    w->shows++;
    w->stage = stage;
    w->done = done;
    w->total = total;
    if (w->due == 0 && w->stop_stage && stage && strcmp(stage, w->stop_stage) == 0) {
        w->due = now_s();
        w->cpu_due = cpu_s();
    }
}

/* A monitor with both hooks on w. */
static void monitor_on(affect_monitor *mon, watch *w)
{
    affect_monitor_init(mon, hook_stop, hook_progress, w);
}

/* Checks an interrupted call: status and message (exact, or only its end when the call adds
 * its stage), the stop was due, the latency, the hooks stayed on the calling thread, nothing
 * is left allocated (base: the live blocks before the call). The latency is printed as wall
 * time from the moment the stop was due to the return, and as the process's CPU time over
 * that span; the assertion is on the CPU time per working thread (the 2 cores are shared, so
 * the wall time also measures the other processes), and on the wall time with a wide margin. */
static void check_stopped(const char *what, const watch *w, affect_status st,
                          const affect_error *err, double returned, double cpu_returned,
                          uint32_t threads, long base, bool exact_msg)
{
    if (st != AFFECT_ERR_INTERRUPTED)
        fail_msg("%s: status %d (%s), expected AFFECT_ERR_INTERRUPTED", what, (int)st, err->msg);
    if (exact_msg)
        assert_string_equal(err->msg, "interrupted");
    else {
        size_t len = strlen(err->msg), tail = strlen("interrupted");
        if (len < tail || strcmp(err->msg + len - tail, "interrupted") != 0)
            fail_msg("%s: message \"%s\" does not end with \"interrupted\"", what, err->msg);
    }
    if (w->due == 0)
        fail_msg("%s: the call returned interrupted before the stop was due", what);
    double wall = returned - w->due, cpu = (cpu_returned - w->cpu_due) / threads;
    printf("    %-58s %6.1f ms (CPU %6.1f ms/thread); %4ld polls from %.1f ms, largest gap "
           "%6.1f ms, %s\n",
           what, wall * 1e3, cpu * 1e3, w->polls, (w->first_poll - w->start) * 1e3,
           w->max_gap * 1e3, w->gap_at);
    if (!exact_msg)
        printf("      message: %s\n", err->msg);
    fflush(stdout);
    if (cpu > LATENCY_MAX)
        fail_msg("%s: %.3f s of CPU per thread after the stop was due (at most %.2f s)", what, cpu,
                 LATENCY_MAX);
    if (wall > WALL_MAX)
        fail_msg("%s: returned %.3f s after the stop was due (at most %.2f s)", what, wall,
                 WALL_MAX);
    if (w->off_owner)
        fail_msg("%s: a hook ran on a thread other than the caller's", what);
    long live = atomic_load(&live_blocks);
    if (live != base)
        fail_msg("%s: %ld blocks left allocated", what, live - base);
}

/* Checks an uninterrupted run's progress: shown at all, consistent, ending on done == total. */
static void check_progress(const char *what, const watch *w)
{
    printf("    %-44s %ld progress calls; stages: %s\n", what, w->shows, w->stages);
    if (w->shows == 0)
        fail_msg("%s: the progress hook was never called", what);
    if (w->bad[0])
        fail_msg("%s: %s", what, w->bad);
    if (w->done != w->total)
        fail_msg("%s: the last progress call is stage \"%s\", %llu of %llu", what, w->stage,
                 (unsigned long long)w->done, (unsigned long long)w->total);
    if (w->off_owner)
        fail_msg("%s: a hook ran on a thread other than the caller's", what);
}

/* ---- data: motion_synth observations ---- */

#define N_ACTIONS 4
#define N_EMOTIONS 4
#define MAX_MOTIONS 128

static const char *const ACTIONS[N_ACTIONS] = {"knock", "wave", "walk", "bow"};
static const char *const EMOTIONS[N_EMOTIONS] = {"neutral", "happy", "sad", "angry"};
static const char *const JOINTS4[] = {"right_hand", "left_hand", "head", "chest"};

typedef struct dataset {
    affect_features *feat;
    uint32_t n;
    double *x[MAX_MOTIONS];
    affect_hmm_seq seqs[MAX_MOTIONS];
    uint32_t y[MAX_MOTIONS];
} dataset;

/* Every action × emotion × seeds 1 .. n_seeds; joints NULL = all 26 (78 dimensions). */
static void dataset_load(dataset *d, uint32_t n_seeds, const char *const *joints, uint32_t n_joints,
                         bool velocity)
{
    affect_error err;
    memset(d, 0, sizeof *d);
    for (uint32_t s = 1; s <= n_seeds; s++)
        for (uint32_t a = 0; a < N_ACTIONS; a++)
            for (uint32_t e = 0; e < N_EMOTIONS; e++) {
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
                assert_true(d->n < MAX_MOTIONS);
                uint32_t i = d->n++;
                if (affect_features_extract(d->feat, m, &d->x[i], &d->seqs[i].n_frames, NULL, &err))
                    fail_msg("extract: %s", err.msg);
                d->seqs[i].x = d->x[i];
                d->y[i] = e;
                affect_motion_free(m);
            }
}

static void dataset_free(dataset *d)
{
    for (uint32_t i = 0; i < d->n; i++)
        affect_free(d->x[i]);
    affect_features_free(d->feat);
    memset(d, 0, sizeof *d);
}

/* The big HMM: full covariances, 7 states × 4 mixtures, every iteration run. */
static void big_hmm_config(affect_hmm_config *cfg, const dataset *d)
{
    affect_hmm_config_default(cfg);
    cfg->dim = affect_features_dim(d->feat);
    cfg->n_states = 7;
    cfg->n_mix = 4;
    cfg->cov = AFFECT_HMM_FULL;
    cfg->max_iter = 200;
    cfg->tol = 0;
}

/* A classifier with full-covariance class HMMs (large Fisher scores), C by inner CV. */
static void big_classifier_config(affect_classifier_config *cfg, const dataset *d, uint32_t threads)
{
    affect_classifier_config_default(cfg);
    cfg->hmm.dim = affect_features_dim(d->feat);
    cfg->hmm.n_states = 5;
    cfg->hmm.n_mix = 2;
    cfg->hmm.cov = AFFECT_HMM_FULL;
    cfg->hmm.max_iter = 30;
    cfg->hmm.tol = 0;
    cfg->descriptors = 0;
    cfg->mirror = AFFECT_MIRROR_OFF;
    cfg->threads = threads;
}

/* n samples of p features, K classes (class k shifts features k, k + K, … by sep). */
static void rmlr_data(size_t n, size_t p, uint32_t K, uint64_t seed, double *x, uint32_t *y)
{
    affect_rng r;
    affect_rng_seed(&r, seed);
    for (size_t i = 0; i < n; i++) {
        y[i] = (uint32_t)(i % K);
        for (size_t j = 0; j < p; j++)
            x[i * p + j] = affect_rng_normal(&r) + (j % K == y[i] && j < 4 * K ? 0.8 : 0.0);
    }
}

static affect_motion *long_walk(const char *emotion, uint64_t seed, double fps)
{
    affect_synth_options opt;
    affect_synth_options_default(&opt);
    opt.fps = fps;
    affect_motion *m = NULL;
    affect_error err;
    if (affect_motion_synth("walk", emotion, seed, &opt, &m, &err))
        fail_msg("synth: %s", err.msg);
    return m;
}

/* What a test holds, freed by the teardown, also when an assertion jumps out of the test. */
static struct {
    dataset d;
    affect_motion *a, *b;
    double *x;
    uint32_t *y;
    affect_hmm *h0, *h1;
    affect_classifier *c0, *c1;
    affect_cv_result *r0, *r1;
    affect_rmlr *m0, *m1;
    unsigned char *b0, *b1;
    affect_bw w0, w1;
} S;

static int teardown(void **state)
{
    (void)state;
    dataset_free(&S.d);
    affect_motion_free(S.a);
    affect_motion_free(S.b);
    free(S.x);
    free(S.y);
    affect_hmm_free(S.h0);
    affect_hmm_free(S.h1);
    affect_classifier_free(S.c0);
    affect_classifier_free(S.c1);
    affect_cv_result_free(S.r0);
    affect_cv_result_free(S.r1);
    affect_rmlr_free(S.m0);
    affect_rmlr_free(S.m1);
    affect_free(S.b0);
    affect_free(S.b1);
    affect_bw_free(&S.w0);
    affect_bw_free(&S.w1);
    memset(&S, 0, sizeof S);
    return 0;
}

/* ---- stopping ---- */

static void test_hmm_train_stops(void **state)
{
    (void)state;
    dataset *d = &S.d;
    dataset_load(d, 2, NULL, 0, false); /* 32 motions, 78 dimensions */
    affect_hmm_config cfg;
    big_hmm_config(&cfg, d);
    /* at a time (inside Baum–Welch), and after 1 and 3 polls (the initialisation) */
    const double at[] = {0.3, 0, 0};
    const long after[] = {0, 1, 3};
    const char *names[] = {"affect_hmm_train, stop at 0.3 s", "affect_hmm_train, after 1 poll",
                           "affect_hmm_train, after 3 polls"};
    for (int k = 0; k < 3; k++) {
        watch w;
        watch_init(&w);
        affect_monitor mon;
        monitor_on(&mon, &w);
        cfg.monitor = &mon;
        long base = atomic_load(&live_blocks);
        double t0 = now_s();
        w.stop_at = at[k] > 0 ? t0 + at[k] : 0;
        w.stop_after = after[k];
        affect_hmm *h = (affect_hmm *)&w; /* must become NULL */
        affect_error err;
        affect_error_clear(&err);
        affect_status st = affect_hmm_train(&cfg, d->seqs, d->n, &h, &err);
        double t1 = now_s(), c1 = cpu_s();
        assert_null(h);
        check_stopped(names[k], &w, st, &err, t1, c1, 1, base, true);
    }
}

static void test_dtw_stops(void **state)
{
    (void)state;
    affect_motion *a = S.a = long_walk("sad", 1, 1000), *b = S.b = long_walk("angry", 2, 1000);
    printf("    DTW over %u x %u frames\n", a->n_frames, b->n_frames);
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    long base = atomic_load(&live_blocks);
    double t0 = now_s(), dist = -1;
    w.stop_at = t0 + 0.3;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_dtw_distance(a, b, &dist, &mon, &err);
    double t1 = now_s(), c1 = cpu_s();
    check_stopped("affect_dtw_distance, stop at 0.3 s", &w, st, &err, t1, c1, 1, base, true);
}

/* The calls on one long motion (a walk at 20,000 fps, 123,140 frames): each polls as it reads
 * the frames, so it stops soon after the stop comes due, here at the second poll (10-20 ms in,
 * the calls run for 0.1 s to minutes uninterrupted). */
typedef enum one_call {
    ONE_LOGLIK,
    ONE_VITERBI,
    ONE_FISHER,
    ONE_LABAN,
    ONE_RIGID,
    ONE_IK,
    ONE_BVH_WRITE,
    ONE_BVH_PARSE,
    ONE_JSON_WRITE,
    ONE_JSON_PARSE,
    ONE_CSV_WRITE,
    ONE_CSV_PARSE,
    ONE_N
} one_call;

static const char *const ONE_NAMES[ONE_N] = {
    "affect_hmm_loglik",       "affect_hmm_viterbi",  "affect_fisher_score",
    "affect_laban_vector",     "affect_motion_rigid", "affect_motion_ik",
    "affect_bvh_write",        "affect_bvh_parse",    "affect_motion_to_json",
    "affect_motion_from_json", "affect_csv_write",    "affect_csv_parse"};

static affect_status one_run(one_call k, const affect_motion *m, const affect_hmm *h,
                             const double *x, const affect_motion *sk, const char *text, size_t len,
                             affect_monitor *mon, affect_error *err)
{
    affect_status st = AFFECT_OK;
    double ll;
    char *out = NULL;
    size_t n = 0;
    affect_motion *r = NULL;
    switch (k) {
    case ONE_LOGLIK:
        return affect_hmm_loglik(h, x, m->n_frames, &ll, mon, err);
    case ONE_VITERBI: {
        int32_t *path = malloc(sizeof *path * m->n_frames);
        assert_non_null(path);
        st = affect_hmm_viterbi(h, x, m->n_frames, path, &ll, mon, err);
        free(path);
        return st;
    }
    case ONE_FISHER: {
        size_t D = affect_fisher_dim(affect_hmm_get_config(h), AFFECT_FISHER_ALL);
        double *f = malloc(sizeof *f * D);
        assert_non_null(f);
        st = affect_fisher_score(h, x, m->n_frames, AFFECT_FISHER_ALL, f, &ll, mon, err);
        free(f);
        return st;
    }
    case ONE_LABAN: {
        affect_laban_options lo;
        affect_laban_options_default(&lo);
        lo.monitor = mon;
        affect_roles roles;
        affect_roles_resolve(m, &roles);
        double v[AFFECT_LABAN_N];
        return affect_laban_vector(m, &roles, &lo, v, err);
    }
    case ONE_RIGID:
    case ONE_IK: {
        affect_ik_options io;
        affect_ik_options_default(&io);
        io.rigid.monitor = mon;
        st = k == ONE_RIGID ? affect_motion_rigid(m, &io.rigid, &r, err)
                            : affect_motion_ik(m, &io, &r, err);
        break;
    }
    case ONE_BVH_WRITE: {
        affect_bvh_write_options bo;
        affect_bvh_write_options_default(&bo);
        bo.monitor = mon;
        st = affect_bvh_write(sk, &bo, &out, &n, err);
        break;
    }
    case ONE_BVH_PARSE: {
        affect_bvh_options bo = {1.0, NULL, 0, mon};
        st = affect_bvh_parse(text, len, &bo, &r, err);
        break;
    }
    case ONE_JSON_WRITE:
        st = affect_motion_to_json(m, &out, &n, mon, err);
        break;
    case ONE_JSON_PARSE:
        st = affect_motion_from_json(text, len, &r, mon, err);
        break;
    case ONE_CSV_WRITE:
        st = affect_csv_write(m, &out, &n, mon, err);
        break;
    default: {
        affect_csv_options co;
        affect_csv_options_default(&co);
        co.monitor = mon;
        st = affect_csv_parse(text, len, m->fps, &co, &r, err);
    }
    }
    affect_free(out);
    affect_motion_free(r);
    return st;
}

static void test_one_motion_calls_stop(void **state)
{
    (void)state;
    dataset *d = &S.d;
    dataset_load(d, 1, NULL, 0, false); /* 16 motions, 78 dimensions: the model */
    affect_hmm_config cfg;
    big_hmm_config(&cfg, d);
    cfg.max_iter = 1;
    affect_error err;
    if (affect_hmm_train(&cfg, d->seqs, d->n, &S.h0, &err))
        fail_msg("train: %s", err.msg);
    affect_motion *walk = long_walk("sad", 1, 1000);
    S.a = walk;
    if (affect_motion_resample(walk, 20000, &S.b, &err))
        fail_msg("resample: %s", err.msg);
    const affect_motion *m = S.b;
    assert_int_equal(affect_features_dim(d->feat), 78);
    double *x = NULL; /* the positions as observations */
    uint32_t T = 0;
    if (affect_features_extract(d->feat, m, &x, &T, NULL, &err))
        fail_msg("extract: %s", err.msg);
    affect_motion *sk = NULL;
    if (affect_motion_ik(walk, NULL, &sk, &err))
        fail_msg("ik: %s", err.msg);
    affect_motion_free(S.a);
    S.a = NULL;
    if (affect_motion_resample(sk, 20000, &S.a, &err))
        fail_msg("resample: %s", err.msg);
    affect_motion_free(sk);
    printf("    %u frames x %u joints\n", m->n_frames, m->n_joints);
    for (int k = 0; k < ONE_N; k++) {
        char *text = NULL;
        size_t len = 0;
        if (k == ONE_BVH_PARSE)
            assert_int_equal(affect_bvh_write(S.a, NULL, &text, &len, &err), AFFECT_OK);
        else if (k == ONE_JSON_PARSE)
            assert_int_equal(affect_motion_to_json(m, &text, &len, NULL, &err), AFFECT_OK);
        else if (k == ONE_CSV_PARSE)
            assert_int_equal(affect_csv_write(m, &text, &len, NULL, &err), AFFECT_OK);
        watch w;
        watch_init(&w);
        affect_monitor mon;
        monitor_on(&mon, &w);
        w.stop_after = 2;
        long base = atomic_load(&live_blocks);
        affect_error_clear(&err);
        affect_status st = one_run((one_call)k, m, S.h0, x, S.a, text, len, &mon, &err);
        double t1 = now_s(), c1 = cpu_s();
        char name[64];
        snprintf(name, sizeof name, "%s, stop at the 2nd poll", ONE_NAMES[k]);
        check_stopped(name, &w, st, &err, t1, c1, 1, base, false);
        affect_free(text);
    }
    affect_free(x);
}

static void rmlr_stops(uint32_t threads)
{
    enum { N = 600, PP = 120, K = 4 };
    double *x = S.x = malloc(sizeof(double) * N * PP);
    uint32_t *y = S.y = malloc(sizeof(uint32_t) * N);
    assert_non_null(x);
    assert_non_null(y);
    rmlr_data(N, PP, K, 7, x, y);
    affect_rmlr_options o;
    affect_rmlr_options_default(&o);
    o.threads = threads;
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    o.monitor = &mon;
    long base = atomic_load(&live_blocks);
    double t0 = now_s();
    w.stop_at = t0 + 0.3;
    affect_rmlr *m = (affect_rmlr *)&w;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_rmlr_cv(x, N, PP, y, K, &o, &m, &err);
    double t1 = now_s(), c1 = cpu_s();
    assert_null(m);
    char what[64];
    snprintf(what, sizeof what, "affect_rmlr_cv, %u thread%s, stop at 0.3 s", threads,
             threads > 1 ? "s" : "");
    check_stopped(what, &w, st, &err, t1, c1, threads, base, true);
}

static void test_rmlr_cv_stops_1(void **state)
{
    (void)state;
    rmlr_stops(1);
}

static void test_rmlr_cv_stops_2(void **state)
{
    (void)state;
    rmlr_stops(2);
}

static void classifier_stops(uint32_t threads)
{
    dataset *d = &S.d;
    dataset_load(d, 2, NULL, 0, false); /* 32 motions, 78 dimensions */
    affect_classifier_config cfg;
    big_classifier_config(&cfg, d, threads);
    /* in the class HMMs (at a time), and as each pass of the Fisher scores starts */
    const char *stages[] = {NULL, "Fisher scores, first pass", "Fisher scores, second pass"};
    for (int k = 0; k < 3; k++) {
        watch w;
        watch_init(&w);
        affect_monitor mon;
        monitor_on(&mon, &w);
        cfg.hmm.monitor = &mon;
        long base = atomic_load(&live_blocks);
        double t0 = now_s();
        w.stop_at = stages[k] ? 0 : t0 + 0.3;
        w.stop_stage = stages[k];
        affect_classifier *c = (affect_classifier *)&w;
        affect_error err;
        affect_error_clear(&err);
        affect_status st = affect_classifier_train(&cfg, d->feat, d->seqs, NULL, d->y, d->n,
                                                   EMOTIONS, N_EMOTIONS, &c, &err);
        double t1 = now_s(), c1 = cpu_s();
        assert_null(c);
        char what[96];
        snprintf(what, sizeof what, "affect_classifier_train, %u thread%s, %s", threads,
                 threads > 1 ? "s" : "", stages[k] ? stages[k] : "stop at 0.3 s");
        check_stopped(what, &w, st, &err, t1, c1, threads, base, false);
    }
}

static void test_classifier_train_stops_1(void **state)
{
    (void)state;
    classifier_stops(1);
}

static void test_classifier_train_stops_2(void **state)
{
    (void)state;
    classifier_stops(2);
}

static void crossval_stops(uint32_t threads)
{
    dataset *d = &S.d;
    dataset_load(d, 3, NULL, 0, false); /* 48 motions, 78 dimensions */
    affect_cv_config cfg;
    affect_cv_config_default(&cfg);
    big_classifier_config(&cfg.cls, d, 1);
    cfg.folds = 4;
    cfg.threads = threads;
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    cfg.cls.hmm.monitor = &mon;
    long base = atomic_load(&live_blocks);
    double t0 = now_s();
    w.stop_at = t0 + 0.3;
    affect_cv_result *r = (affect_cv_result *)&w;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_crossval(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS,
                                       N_EMOTIONS, NULL, 0, &r, &err);
    double t1 = now_s(), c1 = cpu_s();
    assert_null(r);
    char what[64];
    snprintf(what, sizeof what, "affect_crossval, %u thread%s, stop at 0.3 s", threads,
             threads > 1 ? "s" : "");
    check_stopped(what, &w, st, &err, t1, c1, threads, base, false);
}

static void test_crossval_stops_1(void **state)
{
    (void)state;
    crossval_stops(1);
}

static void test_crossval_stops_2(void **state)
{
    (void)state;
    crossval_stops(2);
}

/* ---- progress, and a monitor that never stops changes nothing ---- */

/* A small HMM (24 dimensions, full covariances) with and without a monitor. */
static void test_hmm_progress_and_determinism(void **state)
{
    (void)state;
    dataset *d = &S.d;
    dataset_load(d, 1, JOINTS4, 4, true);
    affect_hmm_config cfg;
    affect_hmm_config_default(&cfg);
    cfg.dim = affect_features_dim(d->feat);
    cfg.n_states = 5;
    cfg.n_mix = 2;
    cfg.max_iter = 15;
    affect_error err;
    if (affect_hmm_train(&cfg, d->seqs, d->n, &S.h0, &err))
        fail_msg("train: %s", err.msg);
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    cfg.monitor = &mon;
    if (affect_hmm_train(&cfg, d->seqs, d->n, &S.h1, &err))
        fail_msg("train with a monitor: %s", err.msg);
    check_progress("affect_hmm_train", &w);
    assert_string_equal(w.stage, "Baum-Welch iterations");
    assert_null(affect_hmm_get_config(S.h1)->monitor); /* the model keeps none */
    size_t n0 = 0, n1 = 0;
    if (affect_hmm_blob_encode(S.h0, d->feat, &S.b0, &n0, &err) ||
        affect_hmm_blob_encode(S.h1, d->feat, &S.b1, &n1, &err))
        fail_msg("encode: %s", err.msg);
    assert_int_equal(n0, n1);
    assert_memory_equal(S.b0, S.b1, n0);
}

static void small_classifier_config(affect_classifier_config *cfg, const dataset *d,
                                    uint32_t threads)
{
    affect_classifier_config_default(cfg);
    cfg->hmm.dim = affect_features_dim(d->feat);
    cfg->hmm.n_states = 4;
    cfg->hmm.n_mix = 1;
    cfg->hmm.cov = AFFECT_HMM_FULL;
    cfg->hmm.max_iter = 6;
    cfg->descriptors = 0;
    cfg->mirror = AFFECT_MIRROR_OFF;
    cfg->threads = threads;
}

static void classifier_progress(uint32_t threads)
{
    dataset *d = &S.d;
    dataset_load(d, 2, JOINTS4, 4, true);
    affect_classifier_config cfg;
    small_classifier_config(&cfg, d, 1);
    affect_error err;
    if (affect_classifier_train(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS, N_EMOTIONS,
                                &S.c0, &err))
        fail_msg("train: %s", err.msg);
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    cfg.hmm.monitor = &mon;
    cfg.threads = threads;
    if (affect_classifier_train(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS, N_EMOTIONS,
                                &S.c1, &err))
        fail_msg("train with a monitor: %s", err.msg);
    char what[64];
    snprintf(what, sizeof what, "affect_classifier_train, %u thread%s", threads,
             threads > 1 ? "s" : "");
    check_progress(what, &w);
    assert_null(affect_classifier_get_config(S.c1)->hmm.monitor);
    size_t n0 = 0, n1 = 0;
    if (affect_classifier_encode(S.c0, &S.b0, &n0, &err) ||
        affect_classifier_encode(S.c1, &S.b1, &n1, &err))
        fail_msg("encode: %s", err.msg);
    assert_int_equal(n0, n1);
    assert_memory_equal(S.b0, S.b1, n0);
}

static void test_classifier_progress_and_determinism_1(void **state)
{
    (void)state;
    classifier_progress(1);
}

static void test_classifier_progress_and_determinism_2(void **state)
{
    (void)state;
    classifier_progress(2);
}

/* Every field of two cross-validation results. */
static void assert_cv_equal(const affect_cv_result *a, const affect_cv_result *b)
{
    assert_int_equal(a->n_classes, b->n_classes);
    assert_int_equal(a->n_folds, b->n_folds);
    size_t C = a->n_classes;
    for (int k = 0; k < AFFECT_CV_RECOGNIZER_METHODS; k++) {
        assert_memory_equal(&a->mean_accuracy[k], &b->mean_accuracy[k], sizeof(double));
        assert_memory_equal(&a->sd_accuracy[k], &b->sd_accuracy[k], sizeof(double));
        assert_memory_equal(&a->mean_balanced[k], &b->mean_balanced[k], sizeof(double));
        assert_memory_equal(&a->mean_f1[k], &b->mean_f1[k], sizeof(double));
        assert_memory_equal(&a->pooled_accuracy[k], &b->pooled_accuracy[k], sizeof(double));
        assert_memory_equal(a->pooled[k], b->pooled[k], C * C * sizeof(uint32_t));
    }
    for (uint32_t f = 0; f < a->n_folds; f++) {
        const affect_cv_fold *x = &a->folds[f], *y = &b->folds[f];
        assert_int_equal(x->n_train, y->n_train);
        assert_int_equal(x->n_test, y->n_test);
        assert_memory_equal(x->accuracy, y->accuracy, sizeof x->accuracy);
        assert_memory_equal(&x->svm_c, &y->svm_c, sizeof(double));
        for (int k = 0; k < AFFECT_CV_RECOGNIZER_METHODS; k++)
            assert_memory_equal(x->confusion[k], y->confusion[k], C * C * sizeof(uint32_t));
    }
}

static void crossval_progress(uint32_t threads)
{
    dataset *d = &S.d;
    dataset_load(d, 3, JOINTS4, 4, true);
    affect_cv_config cfg;
    affect_cv_config_default(&cfg);
    small_classifier_config(&cfg.cls, d, 1);
    cfg.folds = 3;
    affect_error err;
    if (affect_crossval(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0,
                        &S.r0, &err))
        fail_msg("crossval: %s", err.msg);
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    cfg.cls.hmm.monitor = &mon;
    cfg.threads = threads;
    if (affect_crossval(&cfg, d->feat, d->seqs, NULL, d->y, d->n, EMOTIONS, N_EMOTIONS, NULL, 0,
                        &S.r1, &err))
        fail_msg("crossval with a monitor: %s", err.msg);
    char what[64];
    snprintf(what, sizeof what, "affect_crossval, %u thread%s", threads, threads > 1 ? "s" : "");
    check_progress(what, &w);
    assert_cv_equal(S.r0, S.r1);
}

static void test_crossval_progress_and_determinism_1(void **state)
{
    (void)state;
    crossval_progress(1);
}

static void test_crossval_progress_and_determinism_2(void **state)
{
    (void)state;
    crossval_progress(2);
}

static void test_rmlr_progress_and_determinism(void **state)
{
    (void)state;
    enum { N = 90, PP = 12, K = 3 };
    double x[N * PP];
    uint32_t y[N];
    rmlr_data(N, PP, K, 3, x, y);
    affect_rmlr_options o;
    affect_rmlr_options_default(&o);
    o.n_lambda = 30;
    o.folds = 5;
    affect_error err;
    if (affect_rmlr_cv(x, N, PP, y, K, &o, &S.m0, &err))
        fail_msg("rmlr: %s", err.msg);
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    o.monitor = &mon;
    o.threads = 2;
    if (affect_rmlr_cv(x, N, PP, y, K, &o, &S.m1, &err))
        fail_msg("rmlr with a monitor: %s", err.msg);
    check_progress("affect_rmlr_cv, 2 threads", &w);
    affect_bw_init(&S.w0);
    affect_bw_init(&S.w1);
    affect_rmlr_encode(S.m0, &S.w0);
    affect_rmlr_encode(S.m1, &S.w1);
    assert_false(S.w0.failed || S.w1.failed);
    assert_int_equal(S.w0.len, S.w1.len);
    assert_memory_equal(S.w0.data, S.w1.data, S.w0.len);
}

static void test_dtw_determinism(void **state)
{
    (void)state;
    affect_motion *a = S.a = long_walk("sad", 1, 30), *b = S.b = long_walk("angry", 2, 30);
    double d0 = -1, d1 = -2;
    affect_error err;
    watch w;
    watch_init(&w);
    affect_monitor mon;
    monitor_on(&mon, &w);
    if (affect_dtw_distance(a, b, &d0, NULL, &err) || affect_dtw_distance(a, b, &d1, &mon, &err))
        fail_msg("dtw: %s", err.msg);
    assert_memory_equal(&d0, &d1, sizeof d0);
}

/* A monitor without hooks, or a NULL one, never stops anything. */
static void test_monitor_basics(void **state)
{
    (void)state;
    affect_error err;
    affect_error_clear(&err);
    assert_false(affect_monitor_stopped(NULL));
    assert_int_equal(affect_monitor_check(NULL, &err), AFFECT_OK);
    affect_monitor_report(NULL, "x", 1, 2);
    affect_monitor_step(NULL);
    affect_monitor mon;
    affect_monitor_init(&mon, NULL, NULL, NULL);
    affect_monitor_report(&mon, "x", 1, 2);
    thrd_sleep(&(struct timespec){.tv_nsec = (AFFECT_MONITOR_POLL_MS + 5) * 1000000L}, NULL);
    assert_false(affect_monitor_stopped(&mon));
    /* once stopped, every later question says so without asking the hook again */
    watch w;
    watch_init(&w);
    w.stop_after = 1;
    monitor_on(&mon, &w);
    thrd_sleep(&(struct timespec){.tv_nsec = (AFFECT_MONITOR_POLL_MS + 5) * 1000000L}, NULL);
    assert_int_equal(affect_monitor_check(&mon, &err), AFFECT_ERR_INTERRUPTED);
    assert_string_equal(err.msg, "interrupted");
    assert_true(affect_monitor_stopped(&mon));
    assert_int_equal(w.polls, 1);
}

int main(int argc, char **argv)
{
    if (argc > 1)
        cmocka_set_test_filter(argv[1]); /* e.g. "*classifier*" */
    affect_set_allocator(&COUNTING);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test_teardown(test_monitor_basics, teardown),
        cmocka_unit_test_teardown(test_hmm_train_stops, teardown),
        cmocka_unit_test_teardown(test_dtw_stops, teardown),
        cmocka_unit_test_teardown(test_one_motion_calls_stop, teardown),
        cmocka_unit_test_teardown(test_rmlr_cv_stops_1, teardown),
        cmocka_unit_test_teardown(test_rmlr_cv_stops_2, teardown),
        cmocka_unit_test_teardown(test_classifier_train_stops_1, teardown),
        cmocka_unit_test_teardown(test_classifier_train_stops_2, teardown),
        cmocka_unit_test_teardown(test_crossval_stops_1, teardown),
        cmocka_unit_test_teardown(test_crossval_stops_2, teardown),
        cmocka_unit_test_teardown(test_hmm_progress_and_determinism, teardown),
        cmocka_unit_test_teardown(test_classifier_progress_and_determinism_1, teardown),
        cmocka_unit_test_teardown(test_classifier_progress_and_determinism_2, teardown),
        cmocka_unit_test_teardown(test_crossval_progress_and_determinism_1, teardown),
        cmocka_unit_test_teardown(test_crossval_progress_and_determinism_2, teardown),
        cmocka_unit_test_teardown(test_rmlr_progress_and_determinism, teardown),
        cmocka_unit_test_teardown(test_dtw_determinism, teardown),
    };
    int failed = cmocka_run_group_tests(tests, NULL, NULL);
    long live = atomic_load(&live_blocks);
    if (live != 0) {
        printf("%ld blocks of the library left allocated at exit\n", live);
        failed++;
    }
    return failed;
}
