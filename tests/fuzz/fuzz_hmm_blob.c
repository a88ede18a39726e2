/*
 * fuzz_hmm_blob.c — libFuzzer target for the HMM model BLOB decoder (affect_hmm_blob_decode,
 * affect/hmm_blob.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_hmm_blob -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_hmm_blob>
 *
 * The input is the BLOB as is. Beyond "no crash, no leak, no undefined behaviour":
 *   - on failure: a non-OK status recorded with a non-empty message, and nothing handed out;
 *   - on success: encode(decode(x)) == x byte for byte (one encoding per model), and the model
 *     scores a short sequence of zeros without error or NaN.
 * The checksum makes random mutations fail early; the seed (tests/fixtures/hmm-v1.bin) and
 * libFuzzer's comparison tracing let it reach the later checks. A broken invariant aborts.
 */
#include "affect/hmm.h"
#include "affect/hmm_blob.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    affect_hmm *h = NULL;
    affect_features *f = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_hmm_blob_decode(data, size, &h, &f, &err);
    if (st != AFFECT_OK) {
        if (h || f || err.status != st || err.msg[0] == '\0')
            abort();
        return 0;
    }
    unsigned char *buf = NULL;
    size_t n = 0;
    if (affect_hmm_blob_encode(h, f, &buf, &n, &err) != AFFECT_OK || n != size ||
        memcmp(buf, data, size) != 0)
        abort();
    affect_free(buf);
    uint32_t dim = affect_hmm_get_config(h)->dim;
    if (dim <= 64) {
        double x[4 * 64] = {0};
        double ll = 0;
        st = affect_hmm_loglik(h, x, 4, &ll, &err);
        if (st == AFFECT_OK && isnan(ll))
            abort();
    }
    affect_hmm_free(h);
    affect_features_free(f);
    return 0;
}
