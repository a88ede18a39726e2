/*
 * fuzz_classifier.c — libFuzzer target for the classifier BLOB decoder
 * (affect_classifier_decode, affect/classifier.h), and through it the SVM and sPCA record
 * decoders and the embedded model BLOBs.
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_classifier -max_total_time=60 <a copy of
 * tests/fuzz/corpus/fuzz_classifier>
 *
 * The BLOB's trailing checksum would stop nearly every mutation at the first check, so the
 * target decodes a copy whose last 8 bytes are rewritten to the FNV-1a 64 of the rest: the
 * mutations reach the structure behind it (lengths, counts, the nested records). Beyond "no
 * crash, no leak, no undefined behaviour":
 *   - on failure: a non-OK status with a non-empty message;
 *   - on success: encode(decode(x)) == x byte for byte for today's versions (2, the float32
 *     storage, and 3, the compact storage; version 1 is re-encoded as version 2, which must then
 *     round-trip), and evaluating a short sequence of
 *     zeros either succeeds with labels in range or fails with a message.
 * The seeds are small classifiers trained on motion_synth (tests/fuzz/corpus/fuzz_classifier):
 * tiny-classifier.bin (version 1), tiny-classifier-v2.bin (version 2, with kinematic
 * descriptors and mirror images) and tiny-classifier-v3.bin (version 3, the compact storage:
 * the same options as tiny-classifier-v2.bin plus "storage": "compact").
 */
#include "affect/classifier.h"
#include "affect/hmm_blob.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    unsigned char *copy = malloc(size ? size : 1);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    if (size >= 12) {
        uint64_t sum = affect_fnv1a64(copy, size - 8);
        for (int i = 0; i < 8; i++)
            copy[size - 8 + (size_t)i] = (unsigned char)(sum >> (8 * i));
    }
    affect_classifier *c = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_classifier_decode(copy, size, &c, &err);
    if (st != AFFECT_OK) {
        if (c || err.status != st || err.msg[0] == '\0')
            abort();
        free(copy);
        return 0;
    }
    unsigned char *buf = NULL;
    size_t n = 0;
    if (affect_classifier_encode(c, &buf, &n, &err) != AFFECT_OK)
        abort();
    if (copy[4] >= 2) { /* today's versions (2: float32, 3: compact storage): the same bytes */
        if (n != size || memcmp(buf, copy, size) != 0)
            abort();
    } else { /* an older version is re-encoded as today's, which then round-trips */
        affect_classifier *again = NULL;
        unsigned char *buf2 = NULL;
        size_t n2 = 0;
        if (affect_classifier_decode(buf, n, &again, &err) != AFFECT_OK ||
            affect_classifier_encode(again, &buf2, &n2, &err) != AFFECT_OK || n2 != n ||
            memcmp(buf2, buf, n) != 0)
            abort();
        affect_free(buf2);
        affect_classifier_free(again);
    }
    affect_free(buf);
    uint32_t dim = affect_hmm_get_config(affect_classifier_hmm(c, 0))->dim;
    if (dim <= 64) {
        double x[3 * 64] = {0};
        affect_classifier_out o = {0};
        st = affect_classifier_eval(c, x, 3, NULL, false, &o, NULL, &err);
        uint32_t C = affect_classifier_n_classes(c);
        if (st == AFFECT_OK && (o.svm >= C || o.knn >= C || o.ml >= C))
            abort();
        if (st != AFFECT_OK && err.msg[0] == '\0')
            abort();
    }
    affect_classifier_free(c);
    free(copy);
    return 0;
}
