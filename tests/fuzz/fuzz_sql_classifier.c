/*
 * fuzz_sql_classifier.c — libFuzzer target for affect_generate's classifier option
 * (ext/fn_generate.c classify_source): a classifier BLOB given as hex text inside the options,
 * decoded and used to recognize the desired motion's emotion before generating.
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_sql_classifier -max_total_time=60 <a copy of
 * tests/fuzz/corpus/fuzz_sql_classifier>
 *
 * Input: the classifier BLOB. As in fuzz_classifier, its last 8 bytes are rewritten to the
 * FNV-1a 64 of the rest, so mutations get past the checksum; the result is hex-encoded and
 * passed on a fresh copy of fuzz_sql.h's fixtures as
 *     SELECT affect_generate_explain('ix', <motion 1>, 'sad', json_object('classifier', ?1,
 *            'components', json('["WeightAll"]'), 'method', 'hmm_nn', 'k', 1,
 *            'min_neighbours', 1, 'prefer_action', json('false'), 'states', 2))
 * (explicit components: no RMLR fit; the cheapest generation, one neighbour, two states: the
 * option is what is fuzzed, fuzz_sql_options covers the rest).
 * Seeds (tests/fuzz/corpus/fuzz_sql_classifier): the fixtures' own classifier (affect_train
 * over the 12 motions, version 2) and tests/fixtures/classifier-v1.bin.
 * Checks beyond "no crash, no leak, no undefined behaviour": the call fails with a message
 * starting "affect_generate_explain: " or returns valid JSON; when the core decodes the BLOB
 * and recognizes motion 1 with it (affect_classifier_observe and _eval), a successful
 * explanation names that label as "recognized", from "classifier"; when the core refuses the
 * BLOB, so does the call, with the core's message after "option \"classifier\": ".
 */
#include "fuzz_sql.h"

#include "affect/classifier.h"
#include "affect/hmm_blob.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* What the core makes of the BLOB on motion 1: 0 refused (msg), 1 label, 2 decoded but not
 * evaluated (the motion does not fit it, or out of memory). */
static int core_label(sqlite3 *db, const unsigned char *blob, size_t size, char *label, size_t cap,
                      char *msg, size_t msg_cap)
{
    affect_classifier *c = NULL;
    affect_error err;
    if (affect_classifier_decode(blob, size, &c, &err) != AFFECT_OK) {
        snprintf(msg, msg_cap, "%s", err.msg);
        return err.status == AFFECT_ERR_NOMEM ? 2 : 0;
    }
    sqlite3_stmt *st = fz_prepare(db, "SELECT motion FROM motions WHERE id = 1");
    affect_motion *m = NULL;
    double *x = NULL, *desc = NULL;
    uint32_t T = 0;
    int r = 2;
    if (sqlite3_step(st) == SQLITE_ROW &&
        affect_motion_decode(sqlite3_column_blob(st, 0), (size_t)sqlite3_column_bytes(st, 0), &m,
                             &err) == AFFECT_OK &&
        affect_classifier_observe(c, m, &x, &T, &desc, NULL, &err) == AFFECT_OK) {
        affect_classifier_out o = {0};
        if (affect_classifier_eval(c, x, T, desc, false, &o, NULL, &err) == AFFECT_OK) {
            snprintf(label, cap, "%s", affect_classifier_label(c, o.svm));
            r = 1;
        }
    }
    sqlite3_finalize(st);
    affect_free(x);
    affect_free(desc);
    affect_motion_free(m);
    affect_classifier_free(c);
    return r;
}

typedef struct result {
    sqlite3 *db;
    char recognized[256], from[32];
    bool got;
} result;

static void read_row(sqlite3_stmt *st, void *arg)
{
    result *r = arg;
    fz_check_json(r->db, st, 0);
    if (sqlite3_column_type(st, 0) != SQLITE_TEXT)
        return;
    sqlite3_stmt *q = fz_prepare(r->db, "SELECT json_extract(?1, '$.source.recognized'), "
                                        "json_extract(?1, '$.source.from')");
    sqlite3_bind_text(q, 1, (const char *)sqlite3_column_text(st, 0), sqlite3_column_bytes(st, 0),
                      SQLITE_TRANSIENT);
    if (sqlite3_step(q) == SQLITE_ROW) {
        const unsigned char *a = sqlite3_column_text(q, 0), *b = sqlite3_column_text(q, 1);
        snprintf(r->recognized, sizeof r->recognized, "%s", a ? (const char *)a : "");
        snprintf(r->from, sizeof r->from, "%s", b ? (const char *)b : "");
        r->got = true;
    }
    sqlite3_finalize(q);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size > 1 << 20)
        return 0;
    unsigned char *copy = malloc(size ? size : 1);
    char *hex = malloc(2 * size + 1);
    if (!copy || !hex) {
        free(copy);
        free(hex);
        return 0;
    }
    memcpy(copy, data, size);
    if (size >= 12) {
        uint64_t sum = affect_fnv1a64(copy, size - 8);
        for (int i = 0; i < 8; i++)
            copy[size - 8 + (size_t)i] = (unsigned char)(sum >> (8 * i));
    }
    for (size_t i = 0; i < size; i++)
        snprintf(hex + 2 * i, 3, "%02X", copy[i]);
    hex[2 * size] = '\0';

    sqlite3 *db = fz_open();
    char label[256] = "", msg[AFFECT_ERROR_MSG_MAX] = "";
    int core = core_label(db, copy, size, label, sizeof label, msg, sizeof msg);
    sqlite3_stmt *st = fz_prepare(
        db, "SELECT affect_generate_explain('ix', (SELECT motion FROM motions WHERE id = 1), "
            "'sad', json_object('classifier', ?1, 'components', json('[\"WeightAll\"]'), "
            "'method', 'hmm_nn', 'k', 1, 'min_neighbours', 1, 'prefer_action', json('false'), "
            "'states', 2))");
    sqlite3_bind_text(st, 1, hex, (int)(2 * size), SQLITE_STATIC);
    result r = {db, "", "", false};
    int rc = fz_step_all(db, st, "affect_generate_explain", read_row, &r);
    if (rc == SQLITE_DONE) {
        if (core == 0)
            fz_fail("the call accepted a classifier the core refuses (%s)", msg);
        if (!r.got || strcmp(r.from, "classifier") != 0)
            fz_fail("the explanation does not say the source came from the classifier");
        if (core == 1 && strcmp(r.recognized, label) != 0)
            fz_fail("the call recognized \"%s\", the core \"%s\"", r.recognized, label);
    } else if (rc == SQLITE_ERROR && core == 0) {
        const char *e = sqlite3_errmsg(db);
        static const char head[] = "affect_generate_explain: option \"classifier\": ";
        if (strncmp(e, head, sizeof head - 1) != 0 || strcmp(e + sizeof head - 1, msg) != 0)
            fz_fail("the core refuses the classifier with \"%s\", the call with \"%s\"", msg, e);
    }
    sqlite3_finalize(st);
    fz_close(db);
    free(copy);
    free(hex);
    return 0;
}
