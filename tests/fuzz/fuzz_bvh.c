/*
 * fuzz_bvh.c — libFuzzer target for the BVH importer (affect_bvh_parse, affect/io.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_bvh -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_bvh>
 *
 * The input is the BVH text as is (not NUL-terminated: the parser must stay inside len). Checks
 * beyond "no crash, no leak, no undefined behaviour":
 *   - on failure the error record holds a non-empty message (one line of valid UTF-8) and a
 *     status that is not AFFECT_OK;
 *   - on success the motion passes affect_motion_validate, and its BLOB decodes back to a
 *     motion with the same bytes (the importer only produces motions the decoder accepts).
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

/* encode → decode → encode gives the same bytes. */
static void check_blob(const affect_motion *m)
{
    affect_error err;
    unsigned char *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    affect_motion *back = NULL;
    if (affect_motion_encode(m, &a, &na, &err) == AFFECT_OK) {
        affect_status st = affect_motion_decode(a, na, &back, &err);
        if (st == AFFECT_ERR_NOMEM)
            goto done;
        if (st != AFFECT_OK)
            abort();
        if (affect_motion_encode(back, &b, &nb, &err) == AFFECT_OK &&
            (na != nb || memcmp(a, b, na) != 0))
            abort();
    }
done:
    affect_free(a);
    affect_free(b);
    affect_motion_free(back);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_bvh_parse((const char *)data, size, NULL, &m, &err);
    if (st != AFFECT_OK) {
        if (m)
            abort(); /* a failed parse hands nothing out */
        check_error(st, &err);
        return 0;
    }
    if (affect_motion_validate(m, &err) != AFFECT_OK)
        abort();
    check_blob(m);
    affect_motion_free(m);
    return 0;
}
