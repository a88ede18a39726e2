/*
 * fuzz_strength_blob.c — libFuzzer target for the emotion-strength BLOB decoders: the strength
 * model (affect_strength_decode, magic AFST) and the ranker (affect_ranker_decode, magic AFRK)
 * of affect/strength.h and affect/rank.h.
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_strength_blob -max_total_time=60 <a copy of
 * tests/fuzz/corpus/fuzz_strength_blob>
 *
 * Each input goes to both decoders twice: as is, and as a copy whose last 8 bytes are
 * rewritten to the FNV-1a 64 of the rest (both formats end with that checksum), so mutations
 * reach the payload checks instead of stopping at the checksum.
 * Beyond "no crash, no leak, no undefined behaviour", for each decode:
 *   - on failure: AFFECT_ERR_FORMAT or AFFECT_ERR_NOMEM with a non-empty message, nothing
 *     handed out;
 *   - on success: encode(decode(x)) == x byte for byte; a strength model predicts features
 *     for a strength, and a ranker scores the zero vector (0 for one ranker) and puts it in one
 *     of its clusters.
 * Seeds (tests/fuzz/corpus/fuzz_strength_blob): copies of tests/fixtures/strength-v1.bin,
 * strength-v2.bin (Laban features), strength-v3.bin (Fisher features: a recognizer BLOB inside,
 * decoded by affect_classifier_decode) and ranker-v1.bin. A broken invariant aborts.
 */
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "affect/rank.h"
#include "affect/strength.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "check failed at line %d: %s\n", __LINE__, #cond);                     \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

static void check_failure(affect_status st, const affect_error *err)
{
    CHECK(st == AFFECT_ERR_FORMAT || st == AFFECT_ERR_NOMEM);
    CHECK(err->msg[0] != '\0');
}

static void check_strength(const uint8_t *data, size_t size)
{
    affect_strength *s = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_strength_decode(data, size, &s, &err);
    if (st != AFFECT_OK) {
        CHECK(s == NULL);
        check_failure(st, &err);
        return;
    }
    unsigned char *enc;
    size_t n;
    CHECK(affect_strength_encode(s, &enc, &n, &err) == AFFECT_OK);
    CHECK(n == size && memcmp(enc, data, n) == 0);
    affect_free(enc);
    double *z = malloc(sizeof(double) * s->pdim);
    if (z) {
        affect_strength_predict(s, 0.5, z); /* may overflow to ±inf on extreme values: no check */
        free(z);
    }
    affect_strength_free(s);
}

static void check_ranker(const uint8_t *data, size_t size)
{
    affect_ranker *r = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_ranker_decode(data, size, &r, &err);
    if (st != AFFECT_OK) {
        CHECK(r == NULL);
        check_failure(st, &err);
        return;
    }
    unsigned char *enc;
    size_t n;
    CHECK(affect_ranker_encode(r, &enc, &n, &err) == AFFECT_OK);
    CHECK(n == size && memcmp(enc, data, n) == 0);
    affect_free(enc);
    double *x = calloc(r->dim, sizeof(double));
    if (x) {
        double v = affect_ranker_score(r, x);
        CHECK(r->clusters > 1 || v == 0);
        CHECK(r->clusters < 1 || affect_ranker_cluster(r, x) < r->clusters);
        free(x);
    }
    affect_ranker_free(r);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check_strength(data, size);
    check_ranker(data, size);
    if (size < 8)
        return 0;
    uint8_t *copy = malloc(size);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    uint64_t h = affect_fnv1a64(copy, size - 8);
    for (int b = 0; b < 8; b++)
        copy[size - 8 + (size_t)b] = (uint8_t)(h >> (8 * b));
    check_strength(copy, size);
    check_ranker(copy, size);
    free(copy);
    return 0;
}
