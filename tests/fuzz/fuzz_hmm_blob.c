/*
 * fuzz_hmm_blob.c — libFuzzer target for the HMM model BLOB decoder (affect_hmm_blob_decode,
 * affect/hmm_blob.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_hmm_blob -max_total_time=60 <a copy of
 * tests/fuzz/corpus/fuzz_hmm_blob>
 *
 * Each input is decoded twice: as is, and as a copy whose last 8 bytes are rewritten to the
 * FNV-1a 64 of the rest (the checksum's place and algorithm, core/hmm/hmm_blob.c). Raw
 * mutations almost never keep the checksum right, so the decoder used to stop them at that
 * check (20 corpus files after 60 s, 22 after 3 minutes); the fixed copy takes them on to the
 * payload: the feature definition, the log-likelihoods, the parameters and
 * affect_hmm_from_params (149 corpus files after 60 s).
 * Beyond "no crash, no leak, no undefined behaviour", for each decode:
 *   - on failure: a non-OK status recorded with a non-empty message, and nothing handed out;
 *   - on success: encode(decode(x)) == x byte for byte (one encoding per model), and the model
 *     scores a short sequence of zeros without error or NaN;
 * and between the two: when the input's checksum is wrong (the copy differs) the raw decode
 * fails, and when the fixed copy decodes, the raw one fails at the checksum precisely — with
 * "model checksum mismatch: the BLOB is corrupt" — since everything before it is the same.
 * Seed (tests/fuzz/corpus/fuzz_hmm_blob): tiny-model.bin, a copy of tests/fixtures/hmm-v1.bin.
 * A broken invariant aborts.
 */
#include "affect/hmm.h"
#include "affect/hmm_blob.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Decodes data and checks the outcome; returns the status (the message in *err). */
static affect_status check_decode(const uint8_t *data, size_t size, affect_error *err)
{
    affect_hmm *h = NULL;
    affect_features *f = NULL;
    affect_error_clear(err);
    affect_status st = affect_hmm_blob_decode(data, size, &h, &f, err);
    if (st != AFFECT_OK) {
        if (h || f || err->status != st || err->msg[0] == '\0')
            abort();
        return st;
    }
    unsigned char *buf = NULL;
    size_t n = 0;
    if (affect_hmm_blob_encode(h, f, &buf, &n, err) != AFFECT_OK || n != size ||
        memcmp(buf, data, size) != 0)
        abort();
    affect_free(buf);
    uint32_t dim = affect_hmm_get_config(h)->dim;
    if (dim <= 64) {
        double x[4 * 64] = {0};
        double ll = 0;
        affect_error e2;
        if (affect_hmm_loglik(h, x, 4, &ll, NULL, &e2) == AFFECT_OK && isnan(ll))
            abort();
    }
    affect_hmm_free(h);
    affect_features_free(f);
    return AFFECT_OK;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    affect_error err;
    if (size < 8) { /* no room for a checksum: decoded as is only */
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
    if (memcmp(copy, data, size) != 0) { /* the input's checksum is wrong */
        affect_status raw = check_decode(data, size, &err);
        if (raw == AFFECT_OK)
            abort();
        if (fixed == AFFECT_OK &&
            strcmp(err.msg, "model checksum mismatch: the BLOB is corrupt") != 0) {
            fprintf(stderr, "the checksum-fixed copy decodes, the input fails with: %s\n", err.msg);
            abort();
        }
    }
    free(copy);
    return 0;
}
