/*
 * test_bvh.c — BVH import: forward kinematics against hand-computed positions (6-channel
 * joints whose position channels replace the OFFSET, a non-ZXY rotation order, End Sites,
 * a 0-channel joint), header handling and every kind of error with its line number.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "affect/io.h"

/* Hips: 6 channels, ZXY. Chest: rotations in X Y Z order. Head: 6 channels with positions
 * first and rotations in Y Z X order. Arm: no channels. */
static const char small_bvh[] =
    "HIERARCHY\n"
    "ROOT Hips\n"
    "{\n"
    "  OFFSET 0 0 0\n"
    "  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n"
    "  JOINT Chest\n"
    "  {\n"
    "    OFFSET 0 10 0\n"
    "    CHANNELS 3 Xrotation Yrotation Zrotation\n"
    "    JOINT Head\n"
    "    {\n"
    "      OFFSET 0 5 0\n"
    "      CHANNELS 6 Xposition Yposition Zposition Yrotation Zrotation Xrotation\n"
    "      End Site\n"
    "      {\n"
    "        OFFSET 0 2 0\n"
    "      }\n"
    "    }\n"
    "    JOINT Arm\n"
    "    {\n"
    "      OFFSET 3 0 0\n"
    "      CHANNELS 0\n"
    "    }\n"
    "  }\n"
    "}\n"
    "MOTION\n"
    "Frames: 3\n"
    "Frame Time: 0.04\n"
    "1 2 3 0 0 0 0 0 0 0 5 0 0 0 0\n"
    "1 2 3 90 0 0 90 0 0 0 7 0 0 0 90\n"
    "0 0 0 0 0 0 90 90 0 0 5 0 0 0 0\n";

/* Expected world positions, worked by hand (see the comments in test_fk_by_hand). */
static const float expected[3][5][3] = {
    /* frame 0: identity rotations */
    {{1, 2, 3}, {1, 12, 3}, {1, 17, 3}, {1, 19, 3}, {4, 12, 3}},
    /* frame 1: Hips Rz(90); Chest Rx(90); Head translation (0,7,0) and Rx(90) */
    {{1, 2, 3}, {-9, 2, 3}, {-9, 2, 10}, {-7, 2, 10}, {-9, 5, 3}},
    /* frame 2: Chest Rx(90)·Ry(90) — in Y·X order the Arm would be at (0, 10, -3) */
    {{0, 0, 0}, {0, 10, 0}, {0, 10, 5}, {0, 10, 7}, {0, 13, 0}},
};

static affect_motion *parse_ok(const char *text)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_status st = affect_bvh_parse(text, strlen(text), NULL, &m, &err);
    if (st)
        fail_msg("unexpected error: %s", err.msg);
    return m;
}

static void test_fk_by_hand(void **state)
{
    affect_motion *m = parse_ok(small_bvh);
    assert_int_equal(m->n_frames, 3);
    assert_int_equal(m->n_joints, 5);
    tu_assert_near(m->fps, 25.0, 1e-9);
    const char *names[5] = {"Hips", "Chest", "Head", "Head_end", "Arm"};
    const int32_t parents[5] = {-1, 0, 1, 2, 1};
    for (int j = 0; j < 5; j++) {
        assert_string_equal(m->names[j], names[j]);
        assert_int_equal(m->parents[j], parents[j]);
    }
    for (uint32_t t = 0; t < 3; t++)
        for (uint32_t j = 0; j < 5; j++)
            for (int a = 0; a < 3; a++) {
                float got = affect_motion_at(m, t, j)[a];
                if (fabs(got - expected[t][j][a]) > 1e-5)
                    fail_msg("frame %u joint %s axis %d: got %g expected %g", t, names[j], a,
                             (double)got, (double)expected[t][j][a]);
            }
    affect_motion_free(m);
}

static void test_bone_lengths_constant(void **state)
{
    /* a chain with rotations on every joint: all bone lengths stay those of the OFFSETs */
    static const char text[] =
        "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n"
        "CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation\n"
        "JOINT b\n{\nOFFSET 1 2 2\nCHANNELS 3 Zrotation Yrotation Xrotation\n"
        "JOINT c\n{\nOFFSET 0 4 3\nCHANNELS 3 Xrotation Zrotation Yrotation\n"
        "End Site\n{\nOFFSET 2 0 0\n}\n}\n}\n}\n"
        "MOTION\nFrames: 4\nFrame Time: 0.01\n"
        "0 0 0 0 0 0 0 0 0 0 0 0\n"
        "5 -3 2 10 20 30 40 50 60 70 80 90\n"
        "1 1 1 -170 33.5 12 1e1 -2.5e1 7 0.5 0.25 -180\n"
        "0 0 0 359 -359 180 90 90 90 -90 -90 -90\n";
    affect_motion *m = parse_ok(text);
    const double lengths[4] = {0, 3, 5, 2};
    for (uint32_t t = 0; t < m->n_frames; t++)
        for (uint32_t j = 1; j < 4; j++) {
            const float *p = affect_motion_at(m, t, j),
                        *q = affect_motion_at(m, t, (uint32_t)m->parents[j]);
            double d = sqrt(pow(p[0] - q[0], 2) + pow(p[1] - q[1], 2) + pow(p[2] - q[2], 2));
            tu_assert_near(d, lengths[j], 1e-5);
        }
    affect_motion_free(m);
}

static void test_options_and_header_forms(void **state)
{
    /* keywords in other cases, "Frames :" split tokens, CRLF, blank lines between frames,
     * a BOM, multiple roots, a name with a space, "{" on the name's line */
    static const char text[] = "\xEF\xBB\xBFhierarchy\r\nROOT My Root {\r\n offset 1 0 0\r\n"
                               " channels 3 xposition yposition zposition\r\n}\r\n"
                               "ROOT second\r\n{\r\nOFFSET 0 0 0\r\nCHANNELS 1 Yrotation\r\n"
                               "End Site\r\n{\r\nOFFSET 1 0 0\r\n}\r\n}\r\n"
                               "MOTION\r\nFrames : 2\r\nFrame Time : 0.5\r\n"
                               "1 2 3 90\r\n\r\n4 5 6 0\r\n\r\n";
    affect_motion *m = NULL;
    affect_error err;
    affect_bvh_options opt = {0.01, "m", 0, NULL};
    affect_status st = affect_bvh_parse(text, sizeof text - 1, &opt, &m, &err);
    if (st)
        fail_msg("%s", err.msg);
    assert_int_equal(m->n_joints, 3);
    assert_string_equal(m->names[0], "My Root");
    assert_string_equal(m->names[2], "second_end");
    assert_string_equal(m->unit, "m");
    tu_assert_near(m->fps, 2.0, 1e-12);
    tu_assert_near(affect_motion_at(m, 0, 0)[1], 0.02, 1e-7);
    /* Ry(90) maps (1,0,0) to (0,0,-1); scaled by 0.01 */
    tu_assert_near(affect_motion_at(m, 0, 2)[2], -0.01, 1e-7);
    tu_assert_near(affect_motion_at(m, 1, 2)[0], 0.01, 1e-7);
    affect_motion_free(m);
}

static void test_duplicate_names_get_suffixes(void **state)
{
    static const char text[] =
        "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\n"
        "JOINT a\n{\nOFFSET 1 0 0\nCHANNELS 0\nEnd Site\n{\nOFFSET 1 0 0\n}\n}\n"
        "JOINT a_end\n{\nOFFSET 0 1 0\nCHANNELS 0\n}\n}\n"
        "MOTION\nFrames: 1\nFrame Time: 1\n\n";
    affect_motion *m = parse_ok(text);
    assert_int_equal(m->n_joints, 4);
    assert_string_equal(m->names[0], "a");
    assert_string_equal(m->names[1], "a_2");
    assert_string_equal(m->names[2], "a_2_end");
    assert_string_equal(m->names[3], "a_end");
    affect_motion_free(m);
}

typedef struct error_case {
    const char *text;
    const char *message;
} error_case;

static void test_errors(void **state)
{
    static const error_case cases[] = {
        {"", "line 1: expected HIERARCHY, found end of text"},
        {"HIERARCH\n", "line 1: expected HIERARCHY, found HIERARCH"},
        {"HIERARCHY\nJOINT a\n", "line 2: expected ROOT, found JOINT"},
        {"HIERARCHY\nROOT\n{\n", "line 2: expected a joint name"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANELS 3 Xposition\n",
         "line 5: expected CHANNELS, found CHANELS"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 x 0\n", "line 4: expected a number, found x"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 7\n",
         "line 5: expected a channel count from 0 to 6, found 7"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Wrotation\n",
         "line 5: expected a channel name (Xposition … Zrotation), found Wrotation"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Xrotation\n",
         "line 5: channel Xrotation listed twice"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\nJOIN b\n",
         "line 6: expected JOINT, End Site or }, found JOIN"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\nEnd Sight\n",
         "line 6: expected Site, found Sight"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTON\n",
         "line 7: expected ROOT or MOTION, found MOTON"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 0\n",
         "line 8: expected a frame count from 1 to 16777216, found 0"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\n"
         "Frame Time: 0\n1\n",
         "line 9: frame time 0 out of range (> 0, at most 100000 fps)"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\n"
         "Frame Time: 0.1 junk\n1\n",
         "line 9: expected the end of the Frame Time line, found junk"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Yrotation\n}\nMOTION\n"
         "Frames: 2\nFrame Time: 0.1\n1 2\n3\n",
         "line 11: frame 1 has 1 values, expected 2"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Yrotation\n}\nMOTION\n"
         "Frames: 2\nFrame Time: 0.1\n1 2\n3 four\n",
         "line 11: value 2 of frame 1 is not a number: four"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Yrotation\n}\nMOTION\n"
         "Frames: 3\nFrame Time: 0.1\n1 2\n3 4\n5 6 7 8 9 10 11 12\n",
         "line 12: frame 2 has 8 values, expected 2"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Yrotation\n}\nMOTION\n"
         "Frames: 2\nFrame Time: 0.1\n1 2\n3 4\n5 6\n",
         "line 12: more frame lines than the 2 declared in Frames:"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 2 Xrotation Yrotation\n}\nMOTION\n"
         "Frames: 1000\nFrame Time: 0.1\n1 2\n3 4\n",
         "line 9: Frames: 1000 needs more text than the file has left"},
        {"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xposition\n}\nMOTION\n"
         "Frames: 1\nFrame Time: 0.1\n1e400\n",
         "line 10: value 1 of frame 0 is not a number: 1e400"},
        {"HIERARCHY\nROOT a\xFF"
         "b\n{\n", /* names are UTF-8 (Latin-1 here) */
         "line 2: joint name is not valid UTF-8 (byte 0xff at offset 1)"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        affect_motion *m = NULL;
        affect_error err;
        affect_status st = affect_bvh_parse(cases[i].text, strlen(cases[i].text), NULL, &m, &err);
        if (st == AFFECT_OK)
            fail_msg("case %zu parsed but should fail with: %s", i, cases[i].message);
        if (strcmp(err.msg, cases[i].message) != 0)
            fail_msg("case %zu:\n  got      %s\n  expected %s", i, err.msg, cases[i].message);
        assert_null(m);
    }
}

/* ---- sizes from the text (issue 14): "Frames:" against the text left, even when no joint
 * has channels, and frames × joints against max_samples, both before the frames are
 * allocated (a 160-byte file without channels made a 604 MB motion, ten joints 3.9 GB) ---- */

/* HIERARCHY with joints j0 … j(n−1), a chain, none with channels; then MOTION with the given
 * header lines and tail, into buf (malloc'd). */
static char *no_channels_bvh(unsigned n, const char *frames, const char *tail)
{
    size_t cap = 64 * (size_t)n + strlen(frames) + strlen(tail) + 64, len = 0;
    char *buf = malloc(cap);
    assert_non_null(buf);
    len += (size_t)snprintf(buf + len, cap - len, "HIERARCHY\n");
    for (unsigned j = 0; j < n; j++)
        len += (size_t)snprintf(buf + len, cap - len, "%s j%u\n{\nOFFSET 0 1 0\nCHANNELS 0\n",
                                j ? "JOINT" : "ROOT", j);
    for (unsigned j = 0; j < n; j++)
        len += (size_t)snprintf(buf + len, cap - len, "}\n");
    snprintf(buf + len, cap - len, "MOTION\nFrames: %s\nFrame Time: 0.01\n%s", frames, tail);
    return buf;
}

static void expect_bvh_error(const char *text, const affect_bvh_options *opt, affect_status status,
                             const char *message)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_status st = affect_bvh_parse(text, strlen(text), opt, &m, &err);
    if (st == AFFECT_OK)
        fail_msg("parsed %u frames x %u joints, expected: %s", m->n_frames, m->n_joints, message);
    assert_null(m);
    if (strcmp(err.msg, message) != 0)
        fail_msg("\n  got      %s\n  expected %s", err.msg, message);
    assert_int_equal(st, status);
}

static void test_frames_need_text(void **state)
{
    /* the 160-byte file: one joint and an End Site, no channels */
    static const char tiny[] = "HIERARCHY\nROOT Hips\n{\n  OFFSET 0 0 0\n  CHANNELS 0\n"
                               "  End Site\n  {\n    OFFSET 0 10 0\n  }\n}\nMOTION\n"
                               "Frames: 16777216\nFrame Time: 0.0083333\n";
    expect_bvh_error(tiny, NULL, AFFECT_ERR_FORMAT,
                     "line 13: Frames: 16777216 needs more text than the file has left");
    char *ten = no_channels_bvh(10, "16777216", "");
    assert_true(strlen(ten) < 476);
    expect_bvh_error(ten, NULL, AFFECT_ERR_FORMAT,
                     "line 54: Frames: 16777216 needs more text than the file has left");
    free(ten);
    /* one (empty) line per frame; the last may lack its line end */
    for (unsigned frames = 1; frames <= 5; frames++) {
        char count[16];
        snprintf(count, sizeof count, "%u", frames);
        char *text = no_channels_bvh(10, count, "\n\n\n");
        if (frames <= 4) {
            affect_motion *m = parse_ok(text);
            assert_int_equal(m->n_frames, frames);
            assert_int_equal(m->n_joints, 10);
            tu_assert_near(affect_motion_at(m, frames - 1, 9)[1], 10.0, 0);
            affect_motion_free(m);
        } else {
            expect_bvh_error(text, NULL, AFFECT_ERR_FORMAT,
                             "line 54: Frames: 5 needs more text than the file has left");
        }
        free(text);
    }
}

static void test_max_samples(void **state)
{
    /* the option lowers or raises the limit on frames × joints */
    char *text = no_channels_bvh(10, "3", "\n\n\n");
    affect_bvh_options opt = {1.0, NULL, 20, NULL};
    expect_bvh_error(text, &opt, AFFECT_ERR_RANGE,
                     "line 54: 3 frames x 10 joints is 30 samples, above the limit of 20 "
                     "(option max_samples)");
    opt.max_samples = 30;
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_bvh_parse(text, strlen(text), &opt, &m, &err), AFFECT_OK);
    assert_int_equal(m->n_frames, 3);
    affect_motion_free(m);
    free(text);

    /* the default, AFFECT_MOTION_MAX_SAMPLES: 4096 roots of one joint and 4097 frames (one
     * line end each) are refused before anything is allocated for them */
    size_t cap = 4096 * 48 + 4097 + 64, len = 0;
    char *big = malloc(cap);
    assert_non_null(big);
    len += (size_t)snprintf(big + len, cap - len, "HIERARCHY\n");
    for (unsigned j = 0; j < 4096; j++)
        len +=
            (size_t)snprintf(big + len, cap - len, "ROOT r%u\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\n", j);
    len += (size_t)snprintf(big + len, cap - len, "MOTION\nFrames: 4097\nFrame Time: 0.01\n");
    memset(big + len, '\n', 4097);
    big[len + 4097] = '\0';
    assert_int_equal(AFFECT_MOTION_MAX_SAMPLES, 16777216);
    expect_bvh_error(big, NULL, AFFECT_ERR_RANGE,
                     "line 20484: 4097 frames x 4096 joints is 16781312 samples, above the limit "
                     "of 16777216 (option max_samples)");
    free(big);
}

/* ---- out of memory: every allocation of a parse fails in turn (tu_oom_sweep) ---- */

static affect_status parse_small(void *ctx, affect_error *err)
{
    affect_motion **m = ctx;
    *m = NULL;
    return affect_bvh_parse(small_bvh, strlen(small_bvh), NULL, m, err);
}

static void free_parsed(void *ctx, affect_status st)
{
    affect_motion **m = ctx;
    if (st != AFFECT_OK)
        assert_null(*m);
    affect_motion_free(*m);
}

static void test_out_of_memory(void **state)
{
    affect_motion *m;
    assert_true(tu_oom_sweep(parse_small, &m, free_parsed, NULL) >= 5);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fk_by_hand),
        cmocka_unit_test(test_bone_lengths_constant),
        cmocka_unit_test(test_options_and_header_forms),
        cmocka_unit_test(test_duplicate_names_get_suffixes),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_frames_need_text),
        cmocka_unit_test(test_max_samples),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests_name("bvh", tests, NULL, NULL);
}
