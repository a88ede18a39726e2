/*
 * testutil.h — helpers shared by the core unit tests: reading files, building small motions,
 * and locating the real corpus (tests that need it skip when it is absent).
 */
#ifndef AFFECT_TESTUTIL_H
#define AFFECT_TESTUTIL_H

#include <math.h>
#include <setjmp.h>
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
#define tu_assert_near(a, b, tol)                                                              \
    do {                                                                                       \
        double tu_a_ = (double)(a), tu_b_ = (double)(b);                                       \
        if (!(fabs(tu_a_ - tu_b_) <= (tol)))                                                   \
            fail_msg("%s = %.9g, expected %.9g (tolerance %g)", #a, tu_a_, tu_b_, (double)(tol)); \
    } while (0)

#endif
