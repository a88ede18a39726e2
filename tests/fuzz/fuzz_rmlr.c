/*
 * fuzz_rmlr.c — libFuzzer target for the stored RMLR fit: the decoder (affect_rmlr_decode,
 * affect/rmlr.h) and the path that reads a fit back from a laban index's cache
 * (ext/fn_generate.c stored_fit, used by laban_salient and affect_generate).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_rmlr -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_rmlr>
 *
 * The input is the encoded fit, version 2 (magic AFRL, length, checksum) or version 1 (no header:
 * a first byte 1; rmlr.h). A version-2 input whose length field fits is decoded twice: as is,
 * and as a copy whose checksum (at the length the header says, minus 8) is recomputed, so that
 * mutations reach the body past the checksum check (as fuzz_hmm_blob does); when the copy
 * differs from the input, the input must fail with the checksum message.
 * Checks beyond "no crash, no leak, no undefined behaviour":
 *   - on failure: AFFECT_ERR_FORMAT or AFFECT_ERR_NOMEM with a non-empty message starting
 *     "RMLR: ", and no fit handed out;
 *   - on success: the reader stopped within the input, and encoding the fit gives back exactly
 *     the bytes it read (one encoding per fit; for version 1, its body between version 2's
 *     20-byte header and 8-byte checksum); the accessors agree with the header (K ≥ 2,
 *     λ index < λ count, α and the CV error in [0, 1]); predicting the training means gives a
 *     class < K and probabilities in [0, 1] summing to 1 (then z = 0, so only the intercepts
 *     count); predicting other points gives a class < K;
 *   - when the fit has the shape of the fixtures' index (3 classes, 27 components, 12 rows;
 *     fuzz_sql.h), the input replaces the fit stored in the index (_info rows 'rmlr', its key
 *     kept) and laban_salient('ix') on a fresh connection must use it — succeed and report its
 *     α bit for bit — rather than refit.
 * Seeds (tests/fuzz/corpus/fuzz_rmlr): index_fit.bin, the fit laban_salient stored for the
 * fixtures' index in version 1 (= tests/fixtures/rmlr-v1.bin), index_fit_v2.bin the same in
 * version 2 (= tests/fixtures/rmlr-v2.bin); small_2x1.bin and flat_3x2.bin, written from their
 * fields in version 1 (K = 2, p = 1, one λ; K = 3, p = 2, a constant feature, not converged).
 */
#include "fuzz_sql.h"

#include "util/bytes.h"
#include "affect/hmm_blob.h" /* affect_fnv1a64 */
#include "affect/rmlr.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond))                                                                               \
            fz_fail("check failed at line %d: %s", __LINE__, #cond);                               \
    } while (0)

static void check_predict(const affect_rmlr *m)
{
    uint32_t K = affect_rmlr_n_classes(m);
    size_t p = affect_rmlr_n_features(m);
    double *x = malloc(p * sizeof *x), probs[256];
    if (!x)
        return;
    const double *mean = affect_rmlr_means(m), *sd = affect_rmlr_sds(m);
    memcpy(x, mean, p * sizeof *x);
    uint32_t k = affect_rmlr_predict(m, x, probs);
    CHECK(k < K);
    double sum = 0;
    for (uint32_t i = 0; i < K; i++) {
        CHECK(probs[i] >= 0 && probs[i] <= 1);
        sum += probs[i];
    }
    CHECK(fabs(sum - 1) <= 1e-9);
    for (size_t j = 0; j < p; j++)
        x[j] = mean[j] + sd[j];
    CHECK(affect_rmlr_predict(m, x, probs) < K);
    for (size_t j = 0; j < p; j++)
        x[j] = 0;
    CHECK(affect_rmlr_predict(m, x, NULL) < K);
    free(x);
}

/* The stored-fit path: the input in place of the index's fit, then laban_salient. */
static void check_stored(const uint8_t *data, size_t size, const affect_rmlr *m)
{
    sqlite3 *db = fz_open();
    sqlite3_stmt *st = fz_prepare(db, "UPDATE ix_info SET value = ?1 WHERE key = 'rmlr'");
    sqlite3_bind_blob(st, 1, data, (int)size, SQLITE_STATIC);
    CHECK(sqlite3_step(st) == SQLITE_DONE && sqlite3_changes(db) == 1);
    sqlite3_finalize(st);
    st = fz_prepare(db, "SELECT laban_salient('ix'), json_extract(laban_salient('ix'), "
                        "'$.alpha')");
    int rc = sqlite3_step(st);
    if (rc == SQLITE_ROW) {
        fz_check_json(db, st, 0);
        CHECK(sqlite3_column_type(st, 1) != SQLITE_NULL);
        double alpha = sqlite3_column_double(st, 1);
        if (alpha != affect_rmlr_alpha(m))
            fz_fail("laban_salient reports alpha %.17g, the stored fit has %.17g (refitted?)",
                    alpha, affect_rmlr_alpha(m));
    } else if (rc != SQLITE_NOMEM) {
        fz_fail("laban_salient on a valid stored fit failed (%d): %s", rc, sqlite3_errmsg(db));
    }
    sqlite3_finalize(st);
    fz_close(db);
}

/* Decodes the input and checks the invariants above; the decoder's status. */
static affect_status check_one(const uint8_t *data, size_t size, affect_error *errp)
{
    affect_br r;
    affect_br_init(&r, data, size);
    static char sentinel;
    affect_rmlr *m = (affect_rmlr *)(void *)&sentinel; /* the decoder must reset it */
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_rmlr_decode(&r, &m, &err);
    *errp = err;
    if (st != AFFECT_OK) {
        CHECK(m == NULL);
        CHECK(st == AFFECT_ERR_FORMAT || st == AFFECT_ERR_NOMEM);
        CHECK(err.status == st && err.msg[0] != '\0');
        CHECK(st == AFFECT_ERR_NOMEM || strncmp(err.msg, "RMLR: ", 6) == 0);
        return st;
    }
    CHECK(m != NULL && r.off <= size);
    affect_bw w;
    affect_bw_init(&w);
    affect_rmlr_encode(m, &w);
    if (!w.failed) {
        if (data[0] == 1) /* version 1: the same body */
            CHECK(w.len == r.off - 1 + 28 && memcmp(w.data + 20, data + 1, r.off - 1) == 0);
        else
            CHECK(w.len == r.off && memcmp(w.data, data, r.off) == 0);
    }
    affect_bw_free(&w);

    uint32_t K = affect_rmlr_n_classes(m), count = 0;
    const double *lambdas = affect_rmlr_lambdas(m, &count);
    CHECK(K >= 2 && K <= 256 && affect_rmlr_n_features(m) >= 1);
    CHECK(affect_rmlr_n_train(m) >= K && count >= 1 && affect_rmlr_lambda_index(m) < count);
    CHECK(affect_rmlr_lambda(m) == lambdas[affect_rmlr_lambda_index(m)]);
    CHECK(affect_rmlr_alpha(m) >= 0 && affect_rmlr_alpha(m) <= 1);
    CHECK(affect_rmlr_cv_error(m) >= 0 && affect_rmlr_cv_error(m) <= 1);
    check_predict(m);
    if (K == 3 && affect_rmlr_n_features(m) == 27 && affect_rmlr_n_train(m) == 12 &&
        size <= 1 << 20)
        check_stored(data, size, m);
    affect_rmlr_free(m);
    return AFFECT_OK;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    affect_error err, err_fixed;
    affect_status raw = check_one(data, size, &err);
    /* version 2 with its checksum recomputed where the length field puts it */
    if (size < 20 || memcmp(data, AFFECT_RMLR_MAGIC, 4) != 0)
        return 0;
    uint64_t total = 0;
    for (int i = 0; i < 8; i++)
        total |= (uint64_t)data[12 + i] << (8 * i);
    if (total < 28 || total > size)
        return 0;
    uint8_t *copy = malloc(size);
    if (!copy)
        return 0;
    memcpy(copy, data, size);
    uint64_t sum = affect_fnv1a64(copy, (size_t)total - 8);
    for (int i = 0; i < 8; i++)
        copy[total - 8 + (size_t)i] = (uint8_t)(sum >> (8 * i));
    affect_status fixed = check_one(copy, size, &err_fixed);
    if (memcmp(copy, data, size) != 0) { /* the input's checksum was wrong */
        CHECK(raw != AFFECT_OK);
        if (fixed == AFFECT_OK && strncmp(err.msg, "RMLR: checksum mismatch", 23) != 0)
            fz_fail("the checksum-fixed copy decodes, the input fails with: %s", err.msg);
    }
    free(copy);
    return 0;
}
