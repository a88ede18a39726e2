/*
 * fuzz_blob.c — libFuzzer target for the motion BLOB decoder (affect_motion_decode,
 * affect/motion.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_blob -max_total_time=60 <a copy of tests/fuzz/corpus/fuzz_blob>
 *
 * The input is the BLOB as is, of either version: version 1 (positions only) or version 2 (a
 * skeleton part, flags bit 0, and rotations with translations, bit 1). Checks beyond "no
 * crash, no leak, no undefined behaviour":
 *   - on failure: a status other than AFFECT_OK, recorded in the error with a non-empty
 *     message of valid UTF-8 on one line, and no motion handed out;
 *   - on success: the motion validates and encode(decode(x)) == x byte for byte. The format
 *     has exactly one encoding of each motion (reserved bytes zero, exact length, no padding),
 *     so any difference is a decoder that accepted something it should have refused or an
 *     encoder that lost information. This covers version 2 too: the encoder writes version 2
 *     exactly when the motion has a skeleton, flags 1 or 3 as it has rotations, so a BLOB
 *     whose version or flags say otherwise must be refused.
 * A broken invariant calls abort(), which libFuzzer reports as a crash with the input saved.
 *
 * Seed mode: compiled with -DAFFECT_FUZZ_WRITE_SEEDS (and without -fsanitize=fuzzer) this file
 * is instead a small program that writes the valid seed BLOBs of tests/fuzz/corpus/fuzz_blob:
 *     cc -std=c11 -DAFFECT_FUZZ_WRITE_SEEDS -Icore/include -I/usr/include/libsvm
 *        -Icore tests/fuzz/fuzz_blob.c $(find core -name '*.c') -llapacke -lopenblas -lsvm -lm
 *        -o /tmp/write_seeds
 *     /tmp/write_seeds tests/fuzz/corpus/fuzz_blob
 * The version-2 seeds are v2_*.blob; fixture_v2.blob is a copy of tests/fixtures/motion-v2.bin
 * (cp tests/fixtures/motion-v2.bin tests/fuzz/corpus/fuzz_blob/fixture_v2.blob).
 */
#include "affect/motion.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef AFFECT_FUZZ_WRITE_SEEDS

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

#include "affect/quat.h"
#include "affect/skeleton.h"

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

    /* version 2 seeds on one skeleton: Hips (positions then ZXY) → Spine (XYZ) → Head (a lone
     * Yposition between Y, Z, X rotations) → Head_end (End Site), Arm (Zrotation) under Hips */
    static const char *const sk_names[5] = {"Hips", "Spine", "Head", "Head_end", "Arm"};
    static const int32_t sk_parents[5] = {-1, 0, 1, 2, 0};
    static const double sk_offsets[5][3] = {
        {1, 2, 3}, {0, 10, 0}, {0, 5, 0.5}, {0, 2, 0}, {-3, -0.0, 0.25}};
    static const uint8_t sk_n[5] = {6, 3, 4, 0, 1};
    static const uint8_t sk_ch[5][6] = {
        {AFFECT_CH_XPOS, AFFECT_CH_YPOS, AFFECT_CH_ZPOS, AFFECT_CH_ZROT, AFFECT_CH_XROT,
         AFFECT_CH_YROT},
        {AFFECT_CH_XROT, AFFECT_CH_YROT, AFFECT_CH_ZROT},
        {AFFECT_CH_YROT, AFFECT_CH_YPOS, AFFECT_CH_ZROT, AFFECT_CH_XROT},
        {0},
        {AFFECT_CH_ZROT}};
    for (int variant = 0; variant < 3; variant++) {
        /* 0: skeleton only (flags 1); 1: rotations (flags 3); 2: rotations, but no joint has
         * a position channel, so no translation is stored (K = 0) */
        if (affect_motion_create(3, 5, 25.0, &m, &err) || affect_motion_set_unit(m, "cm", &err) ||
            affect_motion_add_skeleton(m, variant > 0, &err))
            goto fail;
        for (uint32_t j = 0; j < 5; j++) {
            if (affect_motion_set_name(m, j, sk_names[j], strlen(sk_names[j]), &err))
                goto fail;
            m->parents[j] = sk_parents[j];
            affect_skel_joint *s = &m->skel[j];
            memcpy(s->offset, sk_offsets[j], sizeof s->offset);
            s->flags = j == 3 ? AFFECT_JOINT_END_SITE : 0;
            for (int c = 0; c < sk_n[j]; c++)
                if (variant < 2 || sk_ch[j][c] >= AFFECT_CH_XROT)
                    s->channel[s->n_channels++] = sk_ch[j][c];
            for (uint32_t t = 0; t < 3; t++)
                for (int a = 0; a < 3; a++)
                    affect_motion_at(m, t, j)[a] = value(t, j, a);
        }
        if (variant > 0) {
            for (uint32_t t = 0; t < 3; t++)
                for (uint32_t j = 0; j < 5; j++) {
                    const affect_skel_joint *s = &m->skel[j];
                    static const int zxy[3] = {2, 0, 1};
                    double deg[3] = {30.0 * t - 20 * j, 45.0 * j - 10 * t, j == 3 ? 0 : 7.5 * t};
                    double q[4] = {1, 0, 0, 0};
                    if (s->n_channels && j != 4)
                        affect_quat_from_euler_deg(zxy, deg, q);
                    float *qo = m->rot + ((size_t)t * 5 + j) * 4,
                          *to = m->trans + ((size_t)t * 5 + j) * 3;
                    for (int k = 0; k < 4; k++)
                        qo[k] = (float)q[k];
                    for (int a = 0; a < 3; a++)
                        to[a] = (float)s->offset[a] +
                                (affect_skel_has_position(s) ? (float)value(t, j, a) / 4 : 0.0f);
                }
            if (affect_motion_fk(m, &err))
                goto fail;
        }
        static const char *const files[3] = {"v2_skeleton_only.blob", "v2_rotations.blob",
                                             "v2_no_translations.blob"};
        rc |= write_seed(dir, files[variant], m);
        affect_motion_free(m);
    }

    /* version 2, one frame: two roots listed after their children, a root without channels
     * and a joint with two rotation channels */
    static const char *const pair[4] = {"Hand", "Arm", "Prop", "Prop_end"};
    static const int32_t pair_parents[4] = {1, -1, -1, 2};
    if (affect_motion_create(1, 4, 119.88, &m, &err) || affect_motion_add_skeleton(m, true, &err))
        goto fail;
    for (uint32_t j = 0; j < 4; j++) {
        if (affect_motion_set_name(m, j, pair[j], strlen(pair[j]), &err))
            goto fail;
        m->parents[j] = pair_parents[j];
        m->skel[j].offset[j % 3] = 1.5 + j;
    }
    m->skel[0].n_channels = 2;
    m->skel[0].channel[0] = AFFECT_CH_YROT;
    m->skel[0].channel[1] = AFFECT_CH_XROT;
    m->skel[1].n_channels = 3;
    m->skel[1].channel[0] = AFFECT_CH_ZPOS;
    m->skel[1].channel[1] = AFFECT_CH_XPOS;
    m->skel[1].channel[2] = AFFECT_CH_YPOS;
    m->skel[3].flags = AFFECT_JOINT_END_SITE;
    for (uint32_t j = 0; j < 4; j++)
        for (int a = 0; a < 3; a++)
            m->trans[j * 3 + a] = (float)m->skel[j].offset[a];
    m->trans[1 * 3 + 2] = -4.25f;
    m->rot[0] = 0.6f, m->rot[1] = 0.8f; /* Hand: Xrotation 106.26° */
    m->rot[4 * 2 + 0] = -1.0f;          /* Prop: −identity */
    if (affect_motion_fk(m, &err))
        goto fail;
    rc |= write_seed(dir, "v2_two_roots.blob", m);
    affect_motion_free(m);
    return rc;
fail:
    fprintf(stderr, "%s\n", err.msg);
    affect_motion_free(m);
    return 1;
}

#endif
