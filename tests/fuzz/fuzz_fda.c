/*
 * fuzz_fda.c — libFuzzer target for the functional-model BLOB decoder (affect_fda_decode,
 * affect/fda.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_fda -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_fda>
 *
 * Each input is decoded twice: as is, and as a copy whose last 8 bytes are rewritten to the
 * FNV-1a 64 of the rest (the checksum's place and algorithm, core/functional/fda.c), so that
 * mutations reach the header checks, the feature definition, the class names, the labels and the
 * arrays. Beyond "no crash, no leak, no undefined behaviour", for each decode:
 *   - on failure: a non-OK status recorded with a non-empty message, and nothing handed out;
 *   - on success: encode(decode(x)) == x byte for byte, and the model embeds a short constant
 *     series without error or NaN (when the series is not too large);
 * and between the two: when the input's checksum is wrong the raw decode fails, with
 * "functional model checksum mismatch: the BLOB is corrupt" whenever the fixed copy decodes.
 * Seeds (tests/fuzz/corpus/fuzz_fda): fda-v1.bin, fda-v2.bin and fda-v3.bin, copies of the
 * fixtures. A broken invariant aborts.
 */
#include "affect/fda.h"
#include "affect/hmm_blob.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static affect_status check_decode(const uint8_t *data, size_t size, affect_error *err)
{
    affect_fda *f = NULL;
    affect_error_clear(err);
    affect_status st = affect_fda_decode(data, size, &f, err);
    if (st != AFFECT_OK) {
        if (f || err->status != st || err->msg[0] == '\0')
            abort();
        return st;
    }
    unsigned char *buf = NULL;
    size_t n = 0;
    if (affect_fda_encode(f, &buf, &n, err) != AFFECT_OK || n != size ||
        memcmp(buf, data, size) != 0)
        abort();
    affect_free(buf);
    uint32_t m = affect_fda_coords(f);
    if (m <= 64) {
        double x[3 * 64], z[AFFECT_FDA_MAX_DIMS];
        for (int i = 0; i < 3 * 64; i++)
            x[i] = 0.25;
        affect_error e2;
        if (affect_fda_embed(f, x, 3, z, &e2) == AFFECT_OK)
            for (uint32_t r = 0; r < affect_fda_dims(f); r++)
                if (isnan(z[r]))
                    abort();
    }
    affect_fda_free(f);
    return AFFECT_OK;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    affect_error err;
    if (size < 8) {
        check_decode(data, size, &err);
        return 0;
    }
    uint8_t *copy = malloc(size);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    uint64_t sum = affect_fnv1a64(copy, size - 8);
    for (int i = 0; i < 8; i++)
        copy[size - 8 + (size_t)i] = (uint8_t)(sum >> (8 * i));
    affect_status fixed = check_decode(copy, size, &err);
    if (memcmp(copy, data, size) != 0) {
        affect_status raw = check_decode(data, size, &err);
        if (raw == AFFECT_OK)
            abort();
        if (fixed == AFFECT_OK &&
            strcmp(err.msg, "functional model checksum mismatch: the BLOB is corrupt") != 0) {
            fprintf(stderr, "the checksum-fixed copy decodes, the input fails with: %s\n", err.msg);
            abort();
        }
    }
    free(copy);
    return 0;
}
