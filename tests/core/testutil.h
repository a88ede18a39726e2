/*
 * testutil.h — helpers shared by the core unit tests: reading files, building small motions,
 * locating the real corpus (tests that need it skip when it is absent), checking the SVG
 * documents the writers emit, and out-of-memory fault injection.
 */
#ifndef AFFECT_TESTUTIL_H
#define AFFECT_TESTUTIL_H

#include <math.h>
#include <setjmp.h>
#include <stdbool.h>
#include <stdlib.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "affect/motion.h"

/* Reads a whole file into a NUL-terminated malloc'd buffer; NULL if it cannot be read. */
char *tu_read_file(const char *path, size_t *len);

/* Directory of the real corpus's BVH files, or NULL (with a message on stdout saying the
 * tests that need it are skipped) when ../shared is absent. */
const char *tu_corpus_dir(void);

/* Asserts that two floats agree within an absolute tolerance, printing both on failure. */
#define tu_assert_near(a, b, tol)                                                                  \
    do {                                                                                           \
        double tu_a_ = (double)(a), tu_b_ = (double)(b);                                           \
        if (!(fabs(tu_a_ - tu_b_) <= (tol)))                                                       \
            fail_msg("%s = %.9g, expected %.9g (tolerance %g)", #a, tu_a_, tu_b_, (double)(tol));  \
    } while (0)

/* Largest Euclidean distance between the positions of two motions of the same size, over every
 * frame and joint. */
double tu_max_dist(const affect_motion *a, const affect_motion *b);

/* ---- text and SVG ---- */

/* Number of non-overlapping occurrences of needle (not empty) in s. */
size_t tu_count(const char *s, const char *needle);

/* Fails the test unless s is a well-formed standalone SVG document of len bytes as our
 * writers emit it: strlen(s) == len; it starts with
 * `<svg xmlns="http://www.w3.org/2000/svg" width="` and ends with "</svg>\n"; no "nan" or
 * "inf" in any case; valid UTF-8; tag names of ASCII letters starting lowercase (camelCase
 * such as animateTransform; under 20), followed
 * by a space, newline, '/' or '>'; every tag closed by '>' with balanced double quotes, no
 * '<' anywhere inside it and no '>' inside a quoted attribute; no stray '>' in text; only
 * the five predefined entities; tags properly nested (at most 64 deep) under one root
 * element that ends the document. */
void tu_assert_svg_well_formed(const char *s, size_t len);

/* ---- out of memory ----
 * A counting allocator, installed with affect_set_allocator, that fails exactly the fail_at-th
 * call to malloc or realloc (counted together from 1; 0 = never fails) and counts the blocks
 * it hands out that are not yet freed. It is a pass-through to the C library otherwise, and
 * once its failing call is past it never fails again, so one left installed by an assertion
 * that jumped out of a test is harmless (the next tu_oom_install replaces it). */

/* Installs the counting allocator with both counters at zero. */
void tu_oom_install(long fail_at);
/* Restores the C library's allocator; the counters keep their values. */
void tu_oom_remove(void);
/* Blocks allocated and not yet freed since tu_oom_install (a realloc moves a block, it does
 * not add one). */
long tu_oom_outstanding(void);
/* Calls to malloc and realloc since tu_oom_install, the failing one included. */
long tu_oom_calls(void);

/* The operation under test: runs once and leaves what it produced in ctx. */
typedef affect_status (*tu_oom_op)(void *ctx, affect_error *err);
/* Checks one run's result (st is AFFECT_OK or AFFECT_ERR_NOMEM) and frees what the run
 * produced; it runs with the counting allocator still installed, so its frees are counted. */
typedef void (*tu_oom_finish)(void *ctx, affect_status st);

/* Runs op(ctx) with allocation n failing, for n = 1, 2, … until a run makes fewer than n
 * allocations (so none failed), calling finish(ctx, status) (when not NULL) after every run.
 * Fails the test, naming n, unless
 *   - every run, once finished, leaves no block outstanding;
 *   - every run that returns an error returns AFFECT_ERR_NOMEM with the error record
 *     {AFFECT_ERR_NOMEM, "out of memory"}, and really reached allocation n;
 *   - the last run, in which no allocation failed, succeeds, within 100000 runs.
 * A run that succeeds although allocation n failed (the operation absorbed the failure, say a
 * shrinking realloc that keeps the larger block) fails the test when absorbed is NULL;
 * otherwise the sweep goes on and *absorbed receives how many runs did so. Returns the number
 * of allocations of the operation, each of which failed in one run; the allocator is the C
 * library's again on return. */
long tu_oom_sweep(tu_oom_op op, void *ctx, tu_oom_finish finish, long *absorbed);

#endif
