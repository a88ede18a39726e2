/*
 * fuzz_blob.c — libFuzzer target for the motion BLOB decoder (affect_motion_decode,
 * affect/motion.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_blob -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_blob>
 *
 * The input is the BLOB as is. Checks beyond "no crash, no leak, no undefined behaviour":
 *   - on failure: a status other than AFFECT_OK, recorded in the error with a non-empty
 *     message, and no motion handed out;
 *   - on success: the motion validates and encode(decode(x)) == x byte for byte. The format
 *     has exactly one encoding of each motion (reserved bytes zero, exact length, no padding),
 *     so any difference is a decoder that accepted something it should have refused or an
 *     encoder that lost information.
 * A broken invariant calls abort(), which libFuzzer reports as a crash with the input saved.
 *
 * Seed mode: compiled with -DAFFECT_FUZZ_WRITE_SEEDS (and without -fsanitize=fuzzer) this file
 * is instead a small program that writes the valid seed BLOBs of tests/fuzz/corpus/fuzz_blob:
 *     cc -std=c11 -DAFFECT_FUZZ_WRITE_SEEDS -Icore/include tests/fuzz/fuzz_blob.c
 *        core/src/[a-z]*.c -lm -o /tmp/write_seeds
 *     /tmp/write_seeds tests/fuzz/corpus/fuzz_blob
 */
#include "affect/motion.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef AFFECT_FUZZ_WRITE_SEEDS

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A failure is recorded with its status and a non-empty, NUL-terminated message. (Messages
 * may quote input text, joint names included, verbatim, so a line break in one is not an
 * error here.) */
static void check_error(affect_status st, const affect_error *err)
{
    if (st == AFFECT_OK || err->status != st || err->msg[0] == '\0' ||
        !memchr(err->msg, '\0', sizeof err->msg))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_motion_decode(data, size, &m, &err);
    if (st != AFFECT_OK) {
        if (m)
            abort();
        check_error(st, &err);
        return 0;
    }
    if (affect_motion_validate(m, &err) != AFFECT_OK)
        abort();
    size_t n = 0;
    if (!affect_motion_encoded_size(m, &n) || n != size)
        abort();
    unsigned char *buf = NULL;
    st = affect_motion_encode(m, &buf, &n, &err);
    if (st == AFFECT_OK && (n != size || memcmp(buf, data, size) != 0))
        abort();
    if (st != AFFECT_OK && st != AFFECT_ERR_NOMEM)
        abort();
    affect_free(buf);
    affect_motion_free(m);
    return 0;
}

#else /* AFFECT_FUZZ_WRITE_SEEDS */

static int write_seed(const char *dir, const char *name, const affect_motion *m)
{
    affect_error err;
    unsigned char *buf = NULL;
    size_t n = 0;
    if (affect_motion_validate(m, &err) || affect_motion_encode(m, &buf, &n, &err)) {
        fprintf(stderr, "%s: %s\n", name, err.msg);
        return 1;
    }
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    int rc = !f || fwrite(buf, 1, n, f) != n;
    if (f && fclose(f) != 0)
        rc = 1;
    if (rc)
        fprintf(stderr, "%s: cannot write\n", path);
    affect_free(buf);
    return rc;
}

/* Frame t, joint j, axis a: a smooth value with a little of everything float32 can hold. */
static float value(uint32_t t, uint32_t j, int a)
{
    return (float)(10.0 * j + 0.5 * t - 3.25 * a) + (a == 1 ? 0.1f : 0.0f);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s <output directory>\n", argv[0]);
        return 2;
    }
    const char *dir = argv[1];
    affect_error err;
    affect_motion *m = NULL;
    int rc = 0;

    /* 1 frame, 1 joint, default name, no unit */
    if (affect_motion_create(1, 1, 30.0, &m, &err))
        goto fail;
    rc |= write_seed(dir, "one_joint.blob", m);
    affect_motion_free(m);

    /* a 6-joint chain with an End Site, 4 frames at 30 fps, cm */
    static const char *const chain[6] = {"Hips", "Spine", "Chest", "Neck", "Head", "Head_end"};
    if (affect_motion_create(4, 6, 30.0, &m, &err) || affect_motion_set_unit(m, "cm", &err))
        goto fail;
    for (uint32_t j = 0; j < 6; j++) {
        if (affect_motion_set_name(m, j, chain[j], strlen(chain[j]), &err))
            goto fail;
        m->parents[j] = (int32_t)j - 1;
        for (uint32_t t = 0; t < 4; t++)
            for (int a = 0; a < 3; a++)
                affect_motion_at(m, t, j)[a] = value(t, j, a);
    }
    rc |= write_seed(dir, "chain_cm.blob", m);
    affect_motion_free(m);

    /* a branching skeleton whose parents do not precede their children, two roots, odd fps,
     * unit "m", UTF-8 names and edge-case floats (−0, subnormal, FLT_MAX) */
    static const char *const tree[5] = {"LeftHand", "Root", "LeftArm", "Caf\xC3\xA9", "Prop"};
    static const int32_t parents[5] = {2, -1, 1, 1, -1};
    if (affect_motion_create(3, 5, 119.88, &m, &err) || affect_motion_set_unit(m, "m", &err))
        goto fail;
    for (uint32_t j = 0; j < 5; j++) {
        if (affect_motion_set_name(m, j, tree[j], strlen(tree[j]), &err))
            goto fail;
        m->parents[j] = parents[j];
        for (uint32_t t = 0; t < 3; t++)
            for (int a = 0; a < 3; a++)
                affect_motion_at(m, t, j)[a] = value(t, j, a) / 100.0f;
    }
    affect_motion_at(m, 0, 4)[0] = -0.0f;
    affect_motion_at(m, 1, 4)[1] = 1e-45f;
    affect_motion_at(m, 2, 4)[2] = 3.4028235e38f;
    rc |= write_seed(dir, "tree_m.blob", m);
    affect_motion_free(m);
    return rc;
fail:
    fprintf(stderr, "%s\n", err.msg);
    affect_motion_free(m);
    return 1;
}

#endif
