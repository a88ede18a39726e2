/*
 * test_motion.c — the motion model and its BLOB: encode/decode round trips, every corruption
 * rejected with its message, validation, slice, resample and select.
 */
#include <float.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"

/* 3 frames × 3 joints, a chain a → b → c, unit "cm", positions 100·t + 10·j + axis. */
static affect_motion *make_motion(void)
{
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(3, 3, 30.0, &m, &err), AFFECT_OK);
    const char *names[3] = {"a", "b", "c"};
    for (uint32_t j = 0; j < 3; j++) {
        assert_int_equal(affect_motion_set_name(m, j, names[j], 1, &err), AFFECT_OK);
        m->parents[j] = (int32_t)j - 1;
    }
    assert_int_equal(affect_motion_set_unit(m, "cm", &err), AFFECT_OK);
    for (uint32_t t = 0; t < 3; t++)
        for (uint32_t j = 0; j < 3; j++)
            for (int a = 0; a < 3; a++)
                affect_motion_at(m, t, j)[a] = (float)(100 * t + 10 * j + a);
    return m;
}

static void assert_same_motion(const affect_motion *a, const affect_motion *b)
{
    assert_int_equal(a->n_frames, b->n_frames);
    assert_int_equal(a->n_joints, b->n_joints);
    assert_memory_equal(&a->fps, &b->fps, sizeof a->fps);
    assert_string_equal(a->unit, b->unit);
    for (uint32_t j = 0; j < a->n_joints; j++) {
        assert_string_equal(a->names[j], b->names[j]);
        assert_int_equal(a->parents[j], b->parents[j]);
    }
    assert_memory_equal(a->pos, b->pos, (size_t)a->n_frames * a->n_joints * 3 * sizeof(float));
}

static void test_round_trip(void **state)
{
    affect_motion *m = make_motion(), *back = NULL;
    /* awkward values survive bit for bit */
    affect_motion_at(m, 1, 1)[0] = -0.0f;
    affect_motion_at(m, 1, 1)[1] = FLT_MIN / 4; /* denormal */
    affect_motion_at(m, 1, 1)[2] = FLT_MAX;
    unsigned char *blob;
    size_t size, expect_size;
    affect_error err;
    assert_int_equal(affect_motion_encode(m, &blob, &size, &err), AFFECT_OK);
    assert_true(affect_motion_encoded_size(m, &expect_size));
    assert_int_equal(size, expect_size);
    /* 32 header + 2 unit + 3 × (2 + 1) names + 3 × 4 parents + 27 × 4 positions */
    assert_int_equal(size, 32 + 2 + 9 + 12 + 108);
    assert_memory_equal(blob, "AFMO\x01\x00\x00\x00\x03\x00\x00\x00\x03\x00\x00\x00", 16);
    assert_int_equal(affect_motion_decode(blob, size, &back, &err), AFFECT_OK);
    assert_same_motion(m, back);
    /* encoding the decoded motion gives the same bytes */
    unsigned char *blob2;
    size_t size2;
    assert_int_equal(affect_motion_encode(back, &blob2, &size2, &err), AFFECT_OK);
    assert_int_equal(size, size2);
    assert_memory_equal(blob, blob2, size);
    affect_free(blob);
    affect_free(blob2);
    affect_motion_free(m);
    affect_motion_free(back);
}

static void put32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

/* Each corruption of a valid BLOB and the message it must give. */
static void test_corruptions(void **state)
{
    affect_motion *m = make_motion();
    unsigned char *good;
    size_t size;
    affect_error err;
    assert_int_equal(affect_motion_encode(m, &good, &size, &err), AFFECT_OK);
    unsigned char *b = malloc(size + 8);
    const size_t parents_off = 32 + 2 + 9, pos_off = parents_off + 12;
    struct {
        const char *what;
        size_t len;
        size_t at;    /* byte to change, or SIZE_MAX */
        uint32_t val; /* new 32-bit little-endian value at `at` (or a byte when small_write) */
        int small_write;
        const char *message;
    } cases[] = {
        {"empty", 0, SIZE_MAX, 0, 0, "truncated: 0 bytes is shorter than the 32-byte header"},
        {"short header", 31, SIZE_MAX, 0, 0,
         "truncated: 31 bytes is shorter than the 32-byte header"},
        {"magic", size, 0, 'X', 1, "not a motion (bad magic bytes at offset 0)"},
        {"version 0", size, 4, 0, 1, "unknown format version 0 (this build reads 1 .. 2)"},
        {"version 3", size, 4, 3, 1, "unknown format version 3 (this build reads 1 .. 2)"},
        {"flags", size, 6, 1, 1, "unknown flags 0x0001 (offset 6)"},
        {"zero frames", size, 8, 0, 0, "frame count 0 out of range (1 .. 16777216) (header)"},
        {"huge frames", size, 8, 0xFFFFFFFFu, 0,
         "frame count 4294967295 out of range (1 .. 16777216) (header)"},
        {"zero joints", size, 12, 0, 0, "joint count 0 out of range (1 .. 4096) (header)"},
        {"more frames than bytes", size, 8, 1000, 0,
         "truncated: 163 bytes, expected 36055 for 1000 frames x 3 joints"},
        {"fps NaN", size, 20, 0x7FF80000u, 0,
         "frames per second nan out of range (0 .. 100000] (header)"},
        {"fps negative", size, 20, 0xBFF00000u, 0,
         "frames per second -1 out of range (0 .. 100000] (header)"},
        {"reserved byte", size, 27, 1, 1, "reserved header byte 27 is not zero"},
        {"unit too long", size, 24, 16, 1, "truncated or bad unit (length 16 at offset 24)"},
        {"unit character", size, 32, '/', 1,
         "unit has a character other than letters, digits, '_', '.', '-' (byte 0)"},
        {"name length zero", size, 34, 0, 1,
         "joint 0: name length 0 out of range (1 .. 1024) at offset 34"},
        {"name runs past the end", 40, SIZE_MAX, 0, 0,
         "truncated in the name of joint 2 (offset 40)"},
        {"truncated positions", size - 1, SIZE_MAX, 0, 0,
         "truncated: 162 bytes, expected 163 for 3 frames x 3 joints"},
        {"trailing bytes", size + 4, SIZE_MAX, 0, 0,
         "trailing bytes: 167 bytes, expected 163 for 3 frames x 3 joints"},
        {"duplicate name", size, 39, 'a', 1, "joints 0 and 1 have the same name \"a\""},
        {"name with NUL", size, 36, 0, 1, "joint 0: name contains a NUL byte"},
        {"name not UTF-8", size, 36, 0xFF, 1,
         "joint 0: name is not valid UTF-8 (byte 0xff at offset 0)"},
        {"parent out of range", size, parents_off + 4, 7, 0,
         "joint 1: parent index 7 out of range (-1 .. 2)"},
        {"parent below -1", size, parents_off + 4, 0xFFFFFFFEu, 0,
         "joint 1: parent index -2 out of range (-1 .. 2)"},
        {"own parent", size, parents_off + 4, 1, 0, "joint 1: is its own parent"},
        {"cycle", size, parents_off, 2, 0, "joint 0: parent indices form a cycle"},
        {"NaN coordinate", size, pos_off + 4 * (3 * 4 + 1), 0x7FC00000u, 0,
         "non-finite coordinate at frame 1, joint 1 (b), y"},
        {"infinite coordinate", size, pos_off + 4 * 26, 0xFF800000u, 0,
         "non-finite coordinate at frame 2, joint 2 (c), z"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        memset(b, 0, size + 8);
        memcpy(b, good, size);
        if (cases[i].at != SIZE_MAX) {
            if (cases[i].small_write)
                b[cases[i].at] = (unsigned char)cases[i].val;
            else
                put32(b + cases[i].at, cases[i].val);
        }
        affect_motion *out = NULL;
        affect_status st = affect_motion_decode(b, cases[i].len, &out, &err);
        if (st == AFFECT_OK)
            fail_msg("case \"%s\" decoded but should fail", cases[i].what);
        assert_int_equal(st, AFFECT_ERR_FORMAT);
        if (strcmp(err.msg, cases[i].message) != 0)
            fail_msg("case \"%s\":\n  got      %s\n  expected %s", cases[i].what, err.msg,
                     cases[i].message);
        assert_null(out);
    }
    /* every truncation of the valid BLOB fails cleanly */
    for (size_t len = 0; len < size; len++) {
        affect_motion *out = NULL;
        assert_int_equal(affect_motion_decode(good, len, &out, &err), AFFECT_ERR_FORMAT);
    }
    free(b);
    affect_free(good);
    affect_motion_free(m);
}

static void test_validate(void **state)
{
    affect_motion *m = make_motion();
    affect_error err;
    assert_int_equal(affect_motion_validate(m, &err), AFFECT_OK);
    affect_motion_at(m, 2, 0)[0] = 1.0f / 0.0f;
    assert_int_equal(affect_motion_validate(m, &err), AFFECT_ERR_FORMAT);
    assert_string_equal(err.msg, "non-finite coordinate at frame 2, joint 0 (a), x");
    affect_motion_free(m);
    assert_int_equal(affect_motion_create(0, 1, 30, &m, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "frame count 0 out of range (1 .. 16777216)");
    assert_int_equal(affect_motion_create(1, 1, 0, &m, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "frames per second 0 out of range (0 .. 100000]");
    assert_int_equal(affect_motion_create(1, 5000, 30, &m, &err), AFFECT_ERR_RANGE);
    assert_int_equal(affect_motion_create(1, 2, 30, &m, &err), AFFECT_OK);
    assert_string_equal(m->names[1], "j1");
    assert_int_equal(affect_motion_set_unit(m, "c m", &err), AFFECT_ERR_FORMAT);
    assert_int_equal(affect_motion_set_name(m, 0, "x\0y", 3, &err), AFFECT_ERR_FORMAT);
    affect_motion_free(m);
}

static void test_slice(void **state)
{
    affect_motion *m = make_motion(), *s = NULL;
    affect_error err;
    assert_int_equal(affect_motion_slice(m, 1, 2, &s, &err), AFFECT_OK);
    assert_int_equal(s->n_frames, 2);
    assert_true(affect_motion_at(s, 0, 2)[1] == 121.0f);
    affect_motion_free(s);
    assert_int_equal(affect_motion_slice(m, -1, -1, &s, &err), AFFECT_OK);
    assert_int_equal(s->n_frames, 1);
    assert_true(affect_motion_at(s, 0, 0)[0] == 200.0f);
    affect_motion_free(s);
    assert_int_equal(affect_motion_slice(m, 2, 1, &s, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "last frame 1 is before first frame 2");
    assert_int_equal(affect_motion_slice(m, 0, 3, &s, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "last frame 3 out of range (the motion has 3 frames)");
    assert_int_equal(affect_motion_slice(m, -4, 1, &s, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "first frame -4 out of range (the motion has 3 frames)");
    affect_motion_free(m);
}

static void test_resample(void **state)
{
    affect_motion *m = make_motion(), *r = NULL;
    affect_error err;
    /* 30 → 60 fps: 3 frames spanning 2/30 s become 5, midpoints interpolated */
    assert_int_equal(affect_motion_resample(m, 60, &r, &err), AFFECT_OK);
    assert_int_equal(r->n_frames, 5);
    tu_assert_near(r->fps, 60, 0);
    tu_assert_near(affect_motion_at(r, 1, 1)[0], 60.0, 1e-5);
    tu_assert_near(affect_motion_at(r, 4, 2)[2], 222.0, 1e-5);
    affect_motion_free(r);
    /* 30 → 15 fps: frames 0 and 2 */
    assert_int_equal(affect_motion_resample(m, 15, &r, &err), AFFECT_OK);
    assert_int_equal(r->n_frames, 2);
    tu_assert_near(affect_motion_at(r, 1, 0)[0], 200.0, 1e-5);
    affect_motion_free(r);
    /* same rate: identical positions */
    assert_int_equal(affect_motion_resample(m, 30, &r, &err), AFFECT_OK);
    assert_memory_equal(r->pos, m->pos, 27 * sizeof(float));
    affect_motion_free(r);
    assert_int_equal(affect_motion_resample(m, -5, &r, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "frames per second -5 out of range (0 .. 100000]");
    affect_motion_free(m);
}

static void test_select(void **state)
{
    affect_motion *m = make_motion(), *s = NULL;
    affect_error err;
    const char *pick[2] = {"c", "a"};
    assert_int_equal(affect_motion_select(m, pick, 2, &s, &err), AFFECT_OK);
    assert_int_equal(s->n_joints, 2);
    assert_string_equal(s->names[0], "c");
    assert_int_equal(s->parents[0], 1); /* c's nearest selected ancestor is a, now index 1 */
    assert_int_equal(s->parents[1], -1);
    assert_true(affect_motion_at(s, 2, 0)[2] == 222.0f);
    assert_string_equal(s->unit, "cm");
    affect_motion_free(s);
    const char *bad[2] = {"a", "zz"};
    assert_int_equal(affect_motion_select(m, bad, 2, &s, &err), AFFECT_ERR_MISSING);
    assert_string_equal(err.msg, "no joint named \"zz\" (selection item 1)");
    const char *twice[2] = {"b", "b"};
    assert_int_equal(affect_motion_select(m, twice, 2, &s, &err), AFFECT_ERR_INVALID);
    assert_string_equal(err.msg, "joint \"b\" selected twice (items 0 and 1)");
    affect_motion_free(m);
}

static void test_bbox_duration(void **state)
{
    affect_motion *m = make_motion();
    float lo[3], hi[3];
    affect_motion_bbox(m, lo, hi);
    assert_true(lo[0] == 0 && lo[2] == 2 && hi[0] == 220 && hi[2] == 222);
    tu_assert_near(affect_motion_duration(m), 0.1, 1e-12);
    affect_motion_free(m);
}

/* A BLOB of each format version stays readable (tests/fixtures/README.md). */
static void test_fixture_v1(void **state)
{
    size_t len;
    char *data = tu_read_file(AFFECT_FIXTURES_DIR "/motion-v1.bin", &len);
    assert_non_null(data);
    affect_motion *m = NULL;
    affect_error err;
    if (affect_motion_decode((const unsigned char *)data, len, &m, &err))
        fail_msg("%s", err.msg);
    assert_int_equal(m->n_frames, 3);
    assert_int_equal(m->n_joints, 5);
    assert_string_equal(m->unit, "cm");
    assert_string_equal(m->names[3], "Head_end");
    assert_int_equal(m->parents[4], 1);
    tu_assert_near(m->fps, 25.0, 0);
    tu_assert_near(affect_motion_at(m, 1, 3)[0], -7.0, 1e-5);
    tu_assert_near(affect_motion_at(m, 1, 3)[2], 10.0, 1e-5);
    affect_motion_free(m);
    free(data);
}

/* ---- sizes (issue 14) ---- */

/* Resampling is bounded by AFFECT_MOTION_MAX_SAMPLES (or the input's size): a rate is no
 * size, and 2 frames of 4096 joints at 1 fps would become 409,604,096 samples at 100 kHz. */
static void test_resample_limit(void **state)
{
    affect_motion *m = NULL, *r = NULL;
    affect_error err;
    assert_int_equal(affect_motion_create(2, 4096, 1.0, &m, &err), AFFECT_OK);
    assert_int_equal(affect_motion_resample(m, 100000, &r, &err), AFFECT_ERR_RANGE);
    assert_string_equal(err.msg, "resampling to 100000 fps gives 100001 frames x 4096 joints = "
                                 "409604096 samples, above the limit of 16777216");
    assert_null(r);
    /* 4096 frames (16,777,216 samples, the limit) is fine */
    assert_int_equal(affect_motion_resample(m, 4095, &r, &err), AFFECT_OK);
    assert_int_equal(r->n_frames, 4096);
    affect_motion_free(r);
    affect_motion_free(m);
}

/* An allocator that refuses every request of refuse_from bytes or more. */
static size_t refuse_from;

static void *refusing_malloc(size_t n)
{
    return n >= refuse_from ? NULL : malloc(n);
}

static void *refusing_realloc(void *p, size_t n)
{
    return n >= refuse_from ? NULL : realloc(p, n);
}

static const affect_allocator refusing = {refusing_malloc, refusing_realloc, free};

/* A refused allocation of AFFECT_NOMEM_NAMED_MIN bytes or more says what it was for and how
 * large it was; a smaller one is the plain "out of memory" (SQLITE_NOMEM in the extension). */
static void test_large_requests(void **state)
{
    affect_error err;
    assert_int_equal(affect_nomem_of(&err, 560 * (size_t)667331, sizeof(double),
                                     "the %u x %u Fisher score matrix", 560u, 667331u),
                     AFFECT_ERR_NOMEM);
    assert_string_equal(err.msg, "cannot allocate the 560 x 667331 Fisher score matrix (2.8 GiB)");
    assert_true(affect_nomem_named(&err));
    assert_int_equal(affect_nomem_of(&err, AFFECT_NOMEM_NAMED_MIN, 1, "a block"), AFFECT_ERR_NOMEM);
    assert_string_equal(err.msg, "cannot allocate a block (16.0 MiB)");
    assert_int_equal(affect_nomem_of(&err, SIZE_MAX, 16, "too much"), AFFECT_ERR_NOMEM);
    assert_string_equal(err.msg, "cannot allocate too much (256.0 EiB)"); /* overflows size_t */
    assert_int_equal(affect_nomem_of(&err, AFFECT_NOMEM_NAMED_MIN - 1, 1, "a block"),
                     AFFECT_ERR_NOMEM);
    assert_string_equal(err.msg, "out of memory");
    assert_false(affect_nomem_named(&err));
    assert_int_equal(affect_nomem_of(NULL, 1, 1, "x"), AFFECT_ERR_NOMEM);

    /* a motion whose positions take 96 MiB, with every request of 16 MiB or more refused */
    affect_motion *m = NULL;
    refuse_from = AFFECT_NOMEM_NAMED_MIN;
    affect_set_allocator(&refusing);
    affect_status st = affect_motion_create(1u << 20, 8, 30.0, &m, &err);
    affect_set_allocator(NULL);
    assert_int_equal(st, AFFECT_ERR_NOMEM);
    assert_null(m);
    assert_string_equal(err.msg,
                        "cannot allocate the positions of 1048576 frames x 8 joints (96.0 MiB)");
    /* and a small one, with every request of 1 kB or more refused: the plain message */
    refuse_from = 1024;
    affect_set_allocator(&refusing);
    st = affect_motion_create(100, 8, 30.0, &m, &err);
    affect_set_allocator(NULL);
    assert_int_equal(st, AFFECT_ERR_NOMEM);
    assert_string_equal(err.msg, "out of memory");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip),     cmocka_unit_test(test_corruptions),
        cmocka_unit_test(test_validate),       cmocka_unit_test(test_slice),
        cmocka_unit_test(test_resample),       cmocka_unit_test(test_select),
        cmocka_unit_test(test_bbox_duration),  cmocka_unit_test(test_fixture_v1),
        cmocka_unit_test(test_resample_limit), cmocka_unit_test(test_large_requests),
    };
    return cmocka_run_group_tests_name("motion", tests, NULL, NULL);
}
