/*
 * bench_import.c — throughput of BVH import (affect_bvh_parse) and of motion BLOB decoding
 * (affect_motion_decode) over the real corpus, each next to the bound it cannot beat.
 *
 * Usage:
 *     bench_import [corpus directory] [--repeat N]
 *     bash tests/bench/run.sh            # Release build, pinned to one core, prints the results
 * The directory defaults to AFFECT_BENCH_CORPUS (${AFFECT_SHARED_DIR}/corpora/bandai-namco-1/
 * data, set by tests/bench/CMakeLists.txt); every *.bvh file in it is used. When it is absent
 * the program says so and exits 0, so a machine without the corpus is not a failure.
 *
 * How it measures: every file is read into memory first (disk and page cache are out of the
 * picture), parsed once to check it and to count frames, and each motion is encoded to a BLOB.
 * Then four kernels run, single-threaded, each over the whole data set repeated N times per run
 * (N chosen so that one run takes about a second, or --repeat), after one untimed warm-up
 * pass; 5 runs each, and the median run time is reported (with the fastest and slowest run):
 *     read floor   one pass over the BVH text counting newlines and summing bytes: the cost
 *                  of merely touching every byte, the floor for any text parser;
 *     bvh import   affect_bvh_parse of every file, including its allocations and forward
 *                  kinematics, and affect_motion_free;
 *     blob memcpy  memcpy of every BLOB into a buffer: the bound for decoding;
 *     blob decode  affect_motion_decode of every BLOB (validation included) and free.
 * Times come from clock_gettime(CLOCK_MONOTONIC). MB are 10^6 bytes. Output: a table for
 * people, then one line per metric for scripts:
 *     BENCH <metric> <value> <unit>
 * e.g. "BENCH bvh_import_text_throughput 123.4 MB/s". Exit status 1 if a file fails to parse
 * or decode (the benchmark never reports numbers for work that did not happen).
 */
#define _POSIX_C_SOURCE 200809L

#include "affect/io.h"
#include "affect/motion.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define BENCH_NAME "bench_import"
#include "benchutil.h"

#ifndef AFFECT_BENCH_CORPUS
#define AFFECT_BENCH_CORPUS "../shared/corpora/bandai-namco-1/data"
#endif

typedef struct item {
    bench_text file;     /* the BVH file: name, text, len (first: bench_load_items) */
    unsigned char *blob; /* its motion, encoded */
    size_t blob_len;
    uint32_t n_frames;
    uint32_t n_joints;
} item;

typedef struct corpus {
    item *items;
    size_t n, cap;
    size_t text_bytes, blob_bytes, max_blob;
    uint64_t frames;
} corpus;

/* Values the timed loops write so the compiler cannot drop their work. */
static volatile uint64_t g_sink;

static void free_corpus(corpus *c)
{
    for (size_t i = 0; i < c->n; i++) {
        bench_free_text(&c->items[i].file);
        affect_free(c->items[i].blob);
    }
    free(c->items);
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

/* Parses each file once (checking it), counts frames and encodes its BLOB. */
static int prepare(corpus *c)
{
    for (size_t i = 0; i < c->n; i++) {
        item *it = &c->items[i];
        affect_motion *m = NULL;
        affect_error err;
        if (affect_bvh_parse(it->file.text, it->file.len, NULL, &m, &err) ||
            affect_motion_encode(m, &it->blob, &it->blob_len, &err)) {
            fprintf(stderr, "%s: %s\n", it->file.name, err.msg);
            affect_motion_free(m);
            return 1;
        }
        it->n_frames = m->n_frames;
        it->n_joints = m->n_joints;
        c->frames += m->n_frames;
        c->blob_bytes += it->blob_len;
        if (it->blob_len > c->max_blob)
            c->max_blob = it->blob_len;
        affect_motion_free(m);
    }
    return 0;
}

/* ---- the kernels: one pass over the data set; non-zero return = failure ---- */

typedef int (*kernel_fn)(const corpus *c, void *ctx);

static int k_read_floor(const corpus *c, void *ctx)
{
    (void)ctx;
    uint64_t total = 0;
    for (size_t i = 0; i < c->n; i++) {
        const unsigned char *p = (const unsigned char *)c->items[i].file.text;
        size_t n = c->items[i].file.len;
        uint64_t lines = 0, sum = 0;
        for (size_t k = 0; k < n; k++) {
            lines += p[k] == '\n';
            sum += p[k];
        }
        total += lines ^ sum;
    }
    g_sink += total;
    return 0;
}

static int k_bvh_import(const corpus *c, void *ctx)
{
    (void)ctx;
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

static int k_blob_memcpy(const corpus *c, void *ctx)
{
    unsigned char *dst = ctx;
    for (size_t i = 0; i < c->n; i++) {
        memcpy(dst, c->items[i].blob, c->items[i].blob_len);
        g_sink += dst[c->items[i].blob_len - 1];
    }
    return 0;
}

static int k_blob_decode(const corpus *c, void *ctx)
{
    (void)ctx;
    for (size_t i = 0; i < c->n; i++) {
        affect_motion *m = NULL;
        affect_error err;
        if (affect_motion_decode(c->items[i].blob, c->items[i].blob_len, &m, &err)) {
            fprintf(stderr, "%s (BLOB): %s\n", c->items[i].file.name, err.msg);
            return 1;
        }
        g_sink += m->n_frames;
        affect_motion_free(m);
    }
    return 0;
}

/* One kernel over the corpus, measured by bench_measure (benchutil.h). */
typedef struct pass_args {
    const corpus *c;
    kernel_fn fn;
    void *ctx;
} pass_args;

static int one_pass(void *arg)
{
    const pass_args *a = arg;
    return a->fn(a->c, a->ctx);
}

static int measure(const corpus *c, kernel_fn fn, void *ctx, unsigned repeat, result *r)
{
    pass_args a = {c, fn, ctx};
    return bench_measure(one_pass, &a, repeat, r);
}

static void row(const char *name, const result *r, double bytes, double frames, double motions)
{
    double s = r->median / r->repeat; /* seconds per pass over the data set */
    printf("%-13s %7u %9.4f %9.4f %9.4f %10.1f", name, r->repeat, r->median, r->min, r->max,
           bytes / s / 1e6);
    if (frames > 0)
        printf(" %12.0f %10.0f", frames / s, motions / s);
    printf("\n");
}

int main(int argc, char **argv)
{
    const char *dir = AFFECT_BENCH_CORPUS;
    unsigned repeat;
    if (bench_dir_args(argc, argv, &dir, &repeat))
        return 2;

    corpus c = {0};
    int rc = load_corpus(dir, &c);
    if (rc == 1) {
        printf("bench_import: corpus directory %s not found: nothing to measure\n", dir);
        return 0;
    }
    if (!rc && c.n == 0) {
        printf("bench_import: no .bvh files in %s: nothing to measure\n", dir);
        free_corpus(&c);
        return 0;
    }
    unsigned char *dst = NULL;
    if (!rc)
        rc = prepare(&c);
    if (!rc && !(dst = malloc(c.max_blob)))
        rc = 2;
    result floor_r, bvh_r, copy_r, dec_r;
    if (!rc)
        rc = measure(&c, k_read_floor, NULL, repeat, &floor_r) ||
             measure(&c, k_bvh_import, NULL, repeat, &bvh_r) ||
             measure(&c, k_blob_memcpy, dst, repeat, &copy_r) ||
             measure(&c, k_blob_decode, NULL, repeat, &dec_r);
    if (rc) {
        free(dst);
        free_corpus(&c);
        return 1;
    }

    double text = (double)c.text_bytes, blob = (double)c.blob_bytes;
    double frames = (double)c.frames, motions = (double)c.n;
    printf("corpus: %s\n", dir);
    printf("  %zu BVH files, %.2f MB of text, %llu frames; BLOBs %.2f MB\n", c.n, text / 1e6,
           (unsigned long long)c.frames, blob / 1e6);
    printf("  %d runs per kernel, each of 'passes' passes over the whole data set; times in "
           "seconds per run\n\n",
           RUNS);
    printf("%-13s %7s %9s %9s %9s %10s %12s %10s\n", "kernel", "passes", "median", "fastest",
           "slowest", "MB/s", "frames/s", "motions/s");
    row("read floor", &floor_r, text, 0, 0);
    row("bvh import", &bvh_r, text, frames, motions);
    row("blob memcpy", &copy_r, blob, 0, 0);
    row("blob decode", &dec_r, blob, frames, motions);

    double floor_s = floor_r.median / floor_r.repeat, bvh_s = bvh_r.median / bvh_r.repeat;
    double copy_s = copy_r.median / copy_r.repeat, dec_s = dec_r.median / dec_r.repeat;
    printf("\nbvh import runs at %.1f%% of the read floor's speed (%.1fx slower); "
           "blob decode at %.1f%% of memcpy's (%.1fx slower)\n",
           100.0 * floor_s / bvh_s, bvh_s / floor_s, 100.0 * copy_s / dec_s, dec_s / copy_s);
    printf("target: bvh import >= 100 MB/s of text on one core: %s\n\n",
           text / bvh_s / 1e6 >= 100.0 ? "met" : "NOT met");

    printf("BENCH read_floor_throughput %.1f MB/s\n", text / floor_s / 1e6);
    printf("BENCH bvh_import_text_throughput %.1f MB/s\n", text / bvh_s / 1e6);
    printf("BENCH bvh_import_frames %.0f frames/s\n", frames / bvh_s);
    printf("BENCH bvh_import_motions %.1f motions/s\n", motions / bvh_s);
    printf("BENCH bvh_import_vs_read_floor %.4f ratio\n", floor_s / bvh_s);
    printf("BENCH blob_memcpy_throughput %.1f MB/s\n", blob / copy_s / 1e6);
    printf("BENCH blob_decode_throughput %.1f MB/s\n", blob / dec_s / 1e6);
    printf("BENCH blob_decode_frames %.0f frames/s\n", frames / dec_s);
    printf("BENCH blob_decode_motions %.1f motions/s\n", motions / dec_s);
    printf("BENCH blob_decode_vs_memcpy %.4f ratio\n", copy_s / dec_s);
    free(dst);
    free_corpus(&c);
    return 0;
}
