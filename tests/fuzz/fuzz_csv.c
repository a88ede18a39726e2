/*
 * fuzz_csv.c — libFuzzer target for the CSV importer (affect_csv_parse, affect/io.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_csv -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_csv>
 *
 * Input layout: byte 0 chooses the options, the rest is the CSV text (not NUL-terminated):
 *     bits 0–1  delimiter: 0 ',', 1 ';', 2 tab, 3 space
 *     bits 2–3  header:    0 detect (−1), 1 none (0), 2 first row (1), 3 detect (−1)
 *     bit  4    unit:      0 none, 1 "cm"
 * The frame rate is always 30. Checks beyond "no crash, no leak, no undefined behaviour":
 *   - on failure: a status other than AFFECT_OK, recorded in the error with a non-empty
 *     message of valid UTF-8 on one line, and no motion handed out;
 *   - on success: the motion validates, and affect_csv_write → affect_csv_parse (',' and a
 *     header row) gives back a motion whose BLOB is byte-identical (io.h promises exact text
 *     round trips: same names, bit-identical positions).
 * A broken invariant calls abort(), which libFuzzer reports as a crash with the input saved.
 */
#include "affect/io.h"

#include <stdlib.h>
#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A failure is recorded with its status and a non-empty, NUL-terminated message: one line of
 * valid UTF-8 whatever it quotes of the input (affect_fail escapes control bytes and bytes
 * that are not UTF-8 as \xNN). */
static void check_error(affect_status st, const affect_error *err)
{
    if (st == AFFECT_OK || err->status != st || err->msg[0] == '\0' ||
        !memchr(err->msg, '\0', sizeof err->msg))
        abort();
    size_t len = strlen(err->msg);
    if (!affect_utf8_valid(err->msg, len))
        abort();
    for (size_t i = 0; i < len; i++)
        if ((unsigned char)err->msg[i] < 0x20 || err->msg[i] == 0x7f)
            abort();
}

/* True when both motions encode to the same bytes; allocation failure counts as equal. */
static bool same_blob(const affect_motion *a, const affect_motion *b)
{
    affect_error err;
    unsigned char *ea = NULL, *eb = NULL;
    size_t na = 0, nb = 0;
    bool same = true;
    if (affect_motion_encode(a, &ea, &na, &err) == AFFECT_OK &&
        affect_motion_encode(b, &eb, &nb, &err) == AFFECT_OK)
        same = na == nb && memcmp(ea, eb, na) == 0;
    affect_free(ea);
    affect_free(eb);
    return same;
}

static void check_round_trip(const affect_motion *m, const char *unit)
{
    affect_error err;
    char *text = NULL;
    size_t len = 0;
    affect_motion *back = NULL;
    affect_status st = affect_csv_write(m, &text, &len, NULL, &err);
    if (st == AFFECT_ERR_NOMEM)
        return;
    if (st != AFFECT_OK)
        abort();
    affect_csv_options opt;
    affect_csv_options_default(&opt);
    opt.header = 1;
    opt.unit = unit;
    st = affect_csv_parse(text, len, 30.0, &opt, &back, &err);
    if (st != AFFECT_OK && st != AFFECT_ERR_NOMEM)
        abort();
    if (st == AFFECT_OK && !same_blob(m, back))
        abort();
    affect_motion_free(back);
    affect_free(text);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const char delimiters[4] = {',', ';', '\t', ' '};
    static const int headers[4] = {-1, 0, 1, -1};
    if (size < 1)
        return 0;
    affect_csv_options opt;
    affect_csv_options_default(&opt);
    opt.delimiter = delimiters[data[0] & 3];
    opt.header = headers[(data[0] >> 2) & 3];
    opt.unit = (data[0] & 16) ? "cm" : NULL;

    affect_motion *m = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_csv_parse((const char *)data + 1, size - 1, 30.0, &opt, &m, &err);
    if (st != AFFECT_OK) {
        if (m)
            abort();
        check_error(st, &err);
        return 0;
    }
    if (affect_motion_validate(m, &err) != AFFECT_OK)
        abort();
    check_round_trip(m, opt.unit);
    affect_motion_free(m);
    return 0;
}
