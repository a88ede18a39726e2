/*
 * test_csv.c — CSV import and export (core/motion/csv.c): header styles, header detection, line
 * ends, byte order mark, quoting, blank lines, delimiters, every error message, exact round
 * trips of awkward floats and names, a 1000-frame × 27-joint round trip, and out-of-memory at
 * every allocation of a parse and a write.
 */
#include "testutil.h"

#include "affect/io.h"
#include "util/rng.h"
#include "util/strbuf.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- helpers ---- */

static affect_csv_options opts(char delimiter, int header)
{
    affect_csv_options o;
    affect_csv_options_default(&o);
    o.delimiter = delimiter;
    o.header = header;
    return o;
}

static affect_motion *parse_ok_len(const char *text, size_t len, const affect_csv_options *opt)
{
    affect_motion *m = NULL;
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_csv_parse(text, len, 30.0, opt, &m, &err);
    if (st != AFFECT_OK)
        fail_msg("parse failed (%d): %s", (int)st, err.msg);
    assert_non_null(m);
    return m;
}

static affect_motion *parse_ok(const char *text, const affect_csv_options *opt)
{
    return parse_ok_len(text, strlen(text), opt);
}

static void expect_error_len(const char *text, size_t len, double fps,
                             const affect_csv_options *opt, affect_status status, const char *msg)
{
    affect_motion *m = (affect_motion *)&m; /* must be reset to NULL */
    affect_error err;
    affect_error_clear(&err);
    affect_status st = affect_csv_parse(text, len, fps, opt, &m, &err);
    if (st == AFFECT_OK) {
        affect_motion_free(m);
        fail_msg("expected error \"%s\", parse succeeded", msg);
    }
    assert_null(m);
    assert_string_equal(err.msg, msg);
    assert_int_equal(err.status, status);
    assert_int_equal(st, status);
}

static void expect_error(const char *text, const affect_csv_options *opt, affect_status status,
                         const char *msg)
{
    expect_error_len(text, strlen(text), 30.0, opt, status, msg);
}

static void assert_names(const affect_motion *m, const char *const *names, uint32_t n)
{
    assert_int_equal(m->n_joints, n);
    for (uint32_t j = 0; j < n; j++)
        assert_string_equal(m->names[j], names[j]);
}

static void assert_values(const affect_motion *m, const float *v, size_t n)
{
    assert_int_equal((size_t)m->n_frames * m->n_joints * 3, n);
    for (size_t i = 0; i < n; i++)
        if (memcmp(&m->pos[i], &v[i], sizeof(float)) != 0)
            fail_msg("value %zu: got %.9g, expected %.9g", i, (double)m->pos[i], (double)v[i]);
}

static bool same_bits(const affect_motion *a, const affect_motion *b)
{
    size_t n = (size_t)a->n_frames * a->n_joints * 3;
    return a->n_frames == b->n_frames && a->n_joints == b->n_joints &&
           memcmp(a->pos, b->pos, n * sizeof(float)) == 0;
}

/* Writes m, parses the text back and checks names and bit-identical positions. */
static void assert_round_trip(const affect_motion *m)
{
    char *text = NULL;
    size_t len = 0;
    affect_error err;
    affect_status st = affect_csv_write(m, &text, &len, NULL, &err);
    if (st)
        fail_msg("write failed: %s", err.msg);
    assert_int_equal(strlen(text), len);
    assert_int_equal(text[len - 1], '\n');
    affect_motion *back = parse_ok_len(text, len, NULL);
    assert_int_equal(back->n_joints, m->n_joints);
    for (uint32_t j = 0; j < m->n_joints; j++)
        assert_string_equal(back->names[j], m->names[j]);
    if (!same_bits(back, m)) {
        size_t n = (size_t)m->n_frames * m->n_joints * 3;
        for (size_t i = 0; i < n; i++)
            if (memcmp(&back->pos[i], &m->pos[i], sizeof(float)) != 0)
                fail_msg("value %zu: wrote %a, read %a", i, (double)m->pos[i],
                         (double)back->pos[i]);
        fail_msg("frame or joint counts differ");
    }
    affect_motion_free(back);
    affect_free(text);
}

/* ---- header styles ---- */

static void test_header_styles(void **state)
{
    (void)state;
    static const char *const texts[] = {
        "Head.x,Head.y,Head.z,Neck.x,Neck.y,Neck.z\n1,2,3,4,5,6\n",
        "Head_x,Head_y,Head_z,Neck_x,Neck_y,Neck_z\n1,2,3,4,5,6\n",
        "Head X,Head Y,Head Z,Neck X,Neck Y,Neck Z\n1,2,3,4,5,6\n",
        "Head:x,Head:y,Head:z,Neck:x,Neck:y,Neck:z\n1,2,3,4,5,6\n",
        "Head.X,Head.Y,Head.Z,Neck_x,Neck_Y,Neck_z\n1,2,3,4,5,6\n",
        "Head.x, Head.y ,Head.z\t,\tNeck:X,Neck:Y,Neck:Z\n1,2,3,4,5,6\n",
    };
    static const char *const names[] = {"Head", "Neck"};
    static const float v[] = {1, 2, 3, 4, 5, 6};
    for (size_t i = 0; i < sizeof texts / sizeof *texts; i++) {
        affect_motion *m = parse_ok(texts[i], NULL);
        assert_names(m, names, 2);
        assert_values(m, v, 6);
        assert_int_equal(m->n_frames, 1);
        assert_true(m->fps == 30.0);
        assert_int_equal(m->parents[0], -1);
        assert_int_equal(m->parents[1], -1);
        assert_string_equal(m->unit, "");
        affect_motion_free(m);
    }
}

static void test_header_last_separator(void **state)
{
    (void)state;
    affect_motion *m = parse_ok("Left_Hand.x,Left_Hand.y,Left_Hand.z,"
                                "a.b_x,a.b_y,a.b_z,"
                                "Left Arm:x,Left Arm:y,Left Arm:z,"
                                "c.x.x,c.x.y,c.x.z\n"
                                "0,0,0,0,0,0,0,0,0,0,0,0\n",
                                NULL);
    static const char *const names[] = {"Left_Hand", "a.b", "Left Arm", "c.x"};
    assert_names(m, names, 4);
    affect_motion_free(m);
}

/* ---- header presence ---- */

static void test_no_header(void **state)
{
    (void)state;
    affect_csv_options o = opts(',', 0);
    affect_motion *m = parse_ok("1,2,3,4,5,6\n-7.5,8e2,.5,5.,+1,-0\n", &o);
    static const char *const names[] = {"j0", "j1"};
    static const float v[] = {1, 2, 3, 4, 5, 6, -7.5f, 800, 0.5f, 5, 1, -0.0f};
    assert_names(m, names, 2);
    assert_int_equal(m->n_frames, 2);
    assert_values(m, v, 12);
    affect_motion_free(m);

    /* header = 0: a header-like first row is data, and not numbers */
    expect_error("a.x,a.y,a.z\n1,2,3\n", &o, AFFECT_ERR_FORMAT,
                 "row 1, column 1: \"a.x\" is not a number");
}

static void test_header_detection(void **state)
{
    (void)state;
    /* numbers only: data */
    affect_motion *m = parse_ok("1,2,3\n4,5,6\n", NULL);
    assert_string_equal(m->names[0], "j0");
    assert_int_equal(m->n_frames, 2);
    affect_motion_free(m);
    /* one field not a number: header */
    m = parse_ok("a.x,a.y,a.z\n4,5,6\n", NULL);
    assert_string_equal(m->names[0], "a");
    assert_int_equal(m->n_frames, 1);
    affect_motion_free(m);
    /* a number-like first row with a quoted number is still data */
    m = parse_ok("\"1\",2,3e0\n", NULL);
    static const float v[] = {1, 2, 3};
    assert_values(m, v, 3);
    affect_motion_free(m);
    /* an empty field does not make a header: the row is data with an empty value */
    expect_error("1,,3\n", NULL, AFFECT_ERR_FORMAT, "row 1, column 2: empty value");
    /* header = 1 forces the first row to be a header */
    affect_csv_options o = opts(',', 1);
    expect_error("1,2,3\n4,5,6\n", &o, AFFECT_ERR_FORMAT,
                 "row 1, column 1: \"1\" does not end in .x, .y or .z");
    m = parse_ok("x.x,x.y,x.z\n4,5,6\n", &o);
    assert_string_equal(m->names[0], "x");
    affect_motion_free(m);
}

/* ---- line ends, BOM, blank lines, quoting, delimiters ---- */

static void test_line_ends(void **state)
{
    (void)state;
    static const float v[] = {1, 2, 3, 4, 5, 6};
    static const char *const texts[] = {
        "a.x,a.y,a.z\r\n1,2,3\r\n4,5,6\r\n", "a.x,a.y,a.z\r1,2,3\r4,5,6\r",
        "a.x,a.y,a.z\n1,2,3\r\n4,5,6",   /* mixed, no final line end */
        "a.x,a.y,a.z\r\n1,2,3\r\n4,5,6", /* no final line end */
    };
    for (size_t i = 0; i < sizeof texts / sizeof *texts; i++) {
        affect_motion *m = parse_ok(texts[i], NULL);
        assert_string_equal(m->names[0], "a");
        assert_values(m, v, 6);
        affect_motion_free(m);
    }
    /* row numbers count CRLF, lone CR and LF as one line end each; "\r\r\n" is two */
    expect_error("a.x,a.y,a.z\r\n1,2,3\r\n1,2\r\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3: expected 3 values, found 2");
    expect_error("a.x,a.y,a.z\r1,2,3\r\r\n1,2\r\n", NULL, AFFECT_ERR_FORMAT,
                 "row 4: expected 3 values, found 2");
    expect_error("a.x,a.y,a.z\n1,2,3\n1,2", NULL, AFFECT_ERR_FORMAT,
                 "row 3: expected 3 values, found 2");
}

static void test_bom(void **state)
{
    (void)state;
    affect_motion *m = parse_ok("\xEF\xBB\xBFHead.x,Head.y,Head.z\n1,2,3\n", NULL);
    assert_string_equal(m->names[0], "Head");
    affect_motion_free(m);
    m = parse_ok("\xEF\xBB\xBF"
                 "1,2,3\n",
                 NULL);
    static const float v[] = {1, 2, 3};
    assert_values(m, v, 3);
    affect_motion_free(m);
    /* only at the very start */
    expect_error("1,2,3\n\xEF\xBB\xBF"
                 "1,2,3\n",
                 NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 1: \"\xEF\xBB\xBF"
                 "1\" is not a number");
}

static void test_blank_lines(void **state)
{
    (void)state;
    const char *text = "\n  \n a.x,a.y,a.z\n\n\t\n1,2,3\r\n \r\n4,5,6\n\n\n";
    affect_motion *m = parse_ok(text, NULL);
    static const float v[] = {1, 2, 3, 4, 5, 6};
    assert_string_equal(m->names[0], "a");
    assert_values(m, v, 6);
    affect_motion_free(m);
    /* blank lines count in row numbers */
    expect_error("\n\na.x,a.y,a.z\n\n1,2,3\n\n1,x,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 7, column 2: \"x\" is not a number");
    expect_error("\n\n1,2\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3: the column count 2 is not a multiple of 3");
}

static void test_quoted_fields(void **state)
{
    (void)state;
    const char *text = "\"a,b.x\",\"a,b.y\", \"a,b.z\" ,"
                       "\"q\"\"t.x\",\"q\"\"t.y\",\"q\"\"t.z\","
                       "\"\"\".x\",\"\"\".y\",\"\"\".z\"\n"
                       "\"1.5\", 2 ,\"3\",  \"-4\"\t,5,6,7,8,\"9\"\n";
    affect_motion *m = parse_ok(text, NULL);
    static const char *const names[] = {"a,b", "q\"t", "\""};
    static const float v[] = {1.5f, 2, 3, -4, 5, 6, 7, 8, 9};
    assert_names(m, names, 3);
    assert_values(m, v, 9);
    affect_motion_free(m);
    /* a quote inside an unquoted field is an ordinary character */
    m = parse_ok("a\"b.x,a\"b.y,a\"b.z\n0,0,0\n", NULL);
    assert_string_equal(m->names[0], "a\"b");
    affect_motion_free(m);
    /* a joint name with line breaks (CRLF, LF, CR) in a header spanning four lines; row
     * numbers go on counting lines */
    m = parse_ok("\"a\r\nb.x\",\"a\r\nb.y\",\"a\r\nb.z\",\"c\n\rd.x\",\"c\n\rd.y\",\"c\n\rd.z\"\n"
                 "1,2,3,4,5,6\n",
                 NULL);
    static const char *const broken[] = {"a\r\nb", "c\n\rd"};
    assert_names(m, broken, 2);
    affect_motion_free(m);
    expect_error("\"a\nb.x\",\"a\nb.y\",\"a\nb.z\"\n1,2,3\n1,2\n", NULL, AFFECT_ERR_FORMAT,
                 "row 6: expected 3 values, found 2");
    expect_error("\"a\nb.x\",\"a\nb.y\",\"a\nb.w\"\n1,2,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 3: \"a\\x0ab.w\" does not end in .x, .y or .z");
    /* quoted with the space delimiter: "Head X" as one field */
    affect_csv_options o = opts(' ', -1);
    m = parse_ok("\"Head X\" \"Head Y\" \"Head Z\"\n1 2 3\n", &o);
    assert_string_equal(m->names[0], "Head");
    affect_motion_free(m);
}

static void test_delimiters(void **state)
{
    (void)state;
    static const float v[] = {1.5f, 2, 3, 4, 5, 6};
    static const char *const names[] = {"Head", "Neck"};

    affect_csv_options o = opts(';', -1);
    affect_motion *m = parse_ok("Head.x;Head.y;Head.z;Neck.x;Neck.y;Neck.z\n"
                                "1.5; 2 ;3;4;5;6\n",
                                &o);
    assert_names(m, names, 2);
    assert_values(m, v, 6);
    affect_motion_free(m);

    o = opts('\t', -1);
    m = parse_ok("Head X\tHead Y\tHead Z\tNeck X\tNeck Y\tNeck Z\n"
                 "1.5\t 2 \t3\t\t4\t5\t6\t\n",
                 &o);
    assert_names(m, names, 2);
    assert_values(m, v, 6);
    affect_motion_free(m);

    o = opts(' ', -1);
    m = parse_ok("  Head.x Head.y  Head.z\tNeck.x Neck.y Neck.z  \n"
                 "1.5   2 3 4\t 5 6 \n",
                 &o);
    assert_names(m, names, 2);
    assert_values(m, v, 6);
    affect_motion_free(m);

    /* with ',' a run of delimiters means empty fields */
    expect_error("1,,2,3\n", NULL, AFFECT_ERR_FORMAT, "row 1, column 2: empty value");
    /* the comma is no delimiter with ';' */
    o = opts(';', -1);
    expect_error("1;2;3\n1,5;2;3\n", &o, AFFECT_ERR_FORMAT,
                 "row 2, column 1: \"1,5\" is not a number");
}

static void test_unit_and_fps(void **state)
{
    (void)state;
    affect_csv_options o = opts(',', -1);
    o.unit = "cm";
    affect_motion *m = NULL;
    affect_error err;
    assert_int_equal(affect_csv_parse("1,2,3\n", 6, 120.0, &o, &m, &err), AFFECT_OK);
    assert_string_equal(m->unit, "cm");
    assert_true(m->fps == 120.0);
    affect_motion_free(m);
    o.unit = "";
    m = parse_ok("1,2,3\n", &o);
    assert_string_equal(m->unit, "");
    affect_motion_free(m);
    o.unit = "c m";
    expect_error("1,2,3\n", &o, AFFECT_ERR_INVALID,
                 "unit has a character other than letters, digits, '_', '.', '-' (byte 1)");
}

/* ---- errors ---- */

static void test_argument_errors(void **state)
{
    (void)state;
    const char *t = "1,2,3\n";
    expect_error_len(t, 6, -1.0, NULL, AFFECT_ERR_INVALID, "fps must be a positive number, got -1");
    expect_error_len(t, 6, 0.0, NULL, AFFECT_ERR_INVALID, "fps must be a positive number, got 0");
    expect_error_len(t, 6, NAN, NULL, AFFECT_ERR_INVALID, "fps must be a positive number, got nan");
    expect_error_len(t, 6, INFINITY, NULL, AFFECT_ERR_INVALID,
                     "fps must be a positive number, got inf");
    expect_error_len(t, 6, 2e5, NULL, AFFECT_ERR_INVALID, "fps must be at most 100000, got 200000");
    affect_csv_options o = opts('|', -1);
    expect_error(t, &o, AFFECT_ERR_INVALID, "delimiter must be ',', ';', tab or space");
    o = opts('.', -1);
    expect_error(t, &o, AFFECT_ERR_INVALID, "delimiter must be ',', ';', tab or space");
    o = opts(',', 2);
    expect_error(t, &o, AFFECT_ERR_INVALID,
                 "header must be -1 (detect), 0 (none) or 1 (first row), got 2");
    expect_error_len(NULL, 5, 30.0, NULL, AFFECT_ERR_INVALID, "text is NULL");
    expect_error_len(NULL, 0, 30.0, NULL, AFFECT_ERR_FORMAT, "no data rows");
}

static void test_structure_errors(void **state)
{
    (void)state;
    affect_csv_options o0 = opts(',', 0);
    expect_error("", NULL, AFFECT_ERR_FORMAT, "no data rows");
    expect_error("\n \r\n\t\n", NULL, AFFECT_ERR_FORMAT, "no data rows");
    expect_error("\xEF\xBB\xBF", NULL, AFFECT_ERR_FORMAT, "no data rows");
    expect_error("a.x,a.y,a.z\n\n", NULL, AFFECT_ERR_FORMAT, "no data rows");
    expect_error("1,2,3,4,5,6,7\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1: the column count 7 is not a multiple of 3");
    expect_error("1,2,3,4,5,6,7\n", &o0, AFFECT_ERR_FORMAT,
                 "row 1: the column count 7 is not a multiple of 3");
    expect_error("a.x,a.y,a.z,b.x,b.y,b.z,c.x\n1,2,3,4,5,6,7\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1: the column count 7 is not a multiple of 3");
    expect_error("a.x,a.y,a.z,Hips\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 4: \"Hips\" does not end in .x, .y or .z");
    expect_error("a.x,a.y,a.z,Hips.w\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 4: \"Hips.w\" does not end in .x, .y or .z");
    expect_error("a.x,a.y,a.z,Hips.xx\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 4: \"Hips.xx\" does not end in .x, .y or .z");
    expect_error("a.x,a.y,a.z,Hips.\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 4: \"Hips.\" does not end in .x, .y or .z");
    expect_error("a.x,a.y,a.z,,b.y\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 4: \"\" does not end in .x, .y or .z");
    expect_error("Hips.x,Hips.y,Hips.z,Head.x,Neck.x,Neck.y\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 5: expected \"Head.y\" after \"Head.x\", found \"Neck.x\"");
    expect_error("Head.x,Head.z,Head.y\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 2: expected \"Head.y\" after \"Head.x\", found \"Head.z\"");
    expect_error("Head_X,Head_Y,Neck_Z\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 3: expected \"Head_Z\" after \"Head_Y\", found \"Neck_Z\"");
    expect_error("Head.x,Head.y,Head.z,Neck.y,Neck.x,Neck.z\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 4: expected \"Neck.x\" to start a joint, found \"Neck.y\"");
    expect_error("Neck Z,Neck Y,Neck X\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 1: expected \"Neck X\" to start a joint, found \"Neck Z\"");
    expect_error(".x,.y,.z\n", NULL, AFFECT_ERR_FORMAT,
                 "row 1, column 1: \".x\" has no joint name before the axis");
    expect_error("\n\na.x,a.y,a.z,a.x,a.y,a.z\n1,2,3,4,5,6\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3: joints 0 and 1 have the same name \"a\"");
    expect_error_len("a\0b.x,a\0b.y,a\0b.z\n1,2,3\n", 24, 30.0, NULL, AFFECT_ERR_FORMAT,
                     "row 1, column 1: the joint name contains a NUL byte");
}

static void test_long_name_and_wide_rows(void **state)
{
    (void)state;
    /* a 1025-byte joint name, and one of exactly 1024 bytes */
    char *text = malloc(4 * 1040);
    assert_non_null(text);
    for (int len = 1024; len <= 1025; len++) {
        size_t o = 0;
        for (int a = 0; a < 3; a++) {
            memset(text + o, 'n', (size_t)len);
            o += (size_t)len;
            text[o++] = '.';
            text[o++] = "xyz"[a];
            text[o++] = a < 2 ? ',' : '\n';
        }
        memcpy(text + o, "1,2,3\n", 7);
        if (len == 1024) {
            affect_motion *m = parse_ok(text, NULL);
            assert_int_equal(strlen(m->names[0]), 1024);
            affect_motion_free(m);
        } else {
            expect_error(text, NULL, AFFECT_ERR_FORMAT,
                         "row 1, column 1: the joint name is 1025 bytes long (at most 1024)");
        }
    }
    free(text);

    /* 4096 joints are fine, 12289 columns are not */
    size_t cap = 12289 * 2 + 16;
    text = malloc(cap);
    assert_non_null(text);
    for (size_t n_cols = 12288; n_cols <= 12291; n_cols += 3) {
        size_t o = 0;
        for (size_t c = 0; c < n_cols; c++) {
            text[o++] = '0';
            text[o++] = c + 1 < n_cols ? ',' : '\n';
        }
        text[o] = '\0';
        if (n_cols == 12288) {
            affect_motion *m = parse_ok(text, NULL);
            assert_int_equal(m->n_joints, 4096);
            affect_motion_free(m);
        } else {
            expect_error(text, NULL, AFFECT_ERR_RANGE,
                         "row 1: more than 12288 columns (3 per joint, at most 4096 joints)");
        }
    }
    free(text);
}

static void test_value_errors(void **state)
{
    (void)state;
    affect_csv_options o0 = opts(',', 0);
    expect_error("a.x,a.y,a.z\n1,2,3\n1,abc,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3, column 2: \"abc\" is not a number");
    expect_error("a.x,a.y,a.z\n1,2,3\n1,,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3, column 2: empty value");
    expect_error("a.x,a.y,a.z\n1,2,3\n1,2,\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3, column 3: empty value");
    expect_error("a.x,a.y,a.z\n1,2,3\n1,\"\",3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3, column 2: empty value");
    expect_error("a.x,a.y,a.z\n1,2,3\n1,  ,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 3, column 2: empty value");
    expect_error("a.x,a.y,a.z\n1e40,2,3\n", NULL, AFFECT_ERR_RANGE,
                 "row 2, column 1: 1e40 does not fit a 32-bit float");
    expect_error("a.x,a.y,a.z\n1,-1e400,3\n", NULL, AFFECT_ERR_RANGE,
                 "row 2, column 2: -1e400 does not fit a 32-bit float");
    expect_error("a.x,a.y,a.z\n1,\"3.5e38\",3\n", NULL, AFFECT_ERR_RANGE,
                 "row 2, column 2: 3.5e38 does not fit a 32-bit float");
    expect_error("1e40,2,3\n", &o0, AFFECT_ERR_RANGE,
                 "row 1, column 1: 1e40 does not fit a 32-bit float");
    expect_error("1,2,3\n1.5x,2,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 1: \"1.5x\" is not a number");
    expect_error("1,2,3\n1,2 3,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: \"2 3\" is not a number");
    expect_error("1,2,3\n1,nan,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: \"nan\" is not a number");
    expect_error("1,2,3\n1,inf,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: \"inf\" is not a number");
    expect_error("1,2,3\n1,0x10,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: \"0x10\" is not a number");
    expect_error("1,2,3\n1,1e,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: \"1e\" is not a number");
    expect_error("1,2,3\n1,\"2\"\"\",3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: \"2\"\"\" is not a number");
    expect_error("1,2,3\n1,\"2,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: the quoted field does not end on its line");
    expect_error("1,\"2\n\",3\n1,2,3\n", &o0, AFFECT_ERR_FORMAT,
                 "row 1, column 2: the quoted field does not end on its line");
    expect_error("\n1,\"2\r\",3\n1,2,3\n", &o0, AFFECT_ERR_FORMAT,
                 "row 2, column 2: the quoted field does not end on its line");
    /* a row that may be a header can hold line breaks in quotes, but must close them */
    expect_error("\na.x,\"a.y,a.z\n1,2,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: the quoted field is not closed");
    expect_error("1,2,3\n1,\"2\"x,3\n", NULL, AFFECT_ERR_FORMAT,
                 "row 2, column 2: unexpected text after the closing quote");
    /* errors in extra columns are reported before the count only when malformed */
    expect_error("1,2,3\n1,2,3,x\n", NULL, AFFECT_ERR_FORMAT, "row 2: expected 3 values, found 4");
    expect_error("1,2,3\n1,2,3,\n", NULL, AFFECT_ERR_FORMAT, "row 2: expected 3 values, found 4");
    /* long field text is cut in messages */
    expect_error(
        "1,2,3\n1,aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa,3\n", NULL,
        AFFECT_ERR_FORMAT,
        "row 2, column 2: \"aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\" is not a number");
}

/* "row 7: expected 66 values, found 65": 22 joints, the 6th data row short by one. */
static void test_ragged_rows(void **state)
{
    (void)state;
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    for (int j = 0; j < 22; j++)
        for (int a = 0; a < 3; a++)
            affect_strbuf_printf(&sb, "%sJoint%d.%c", j || a ? "," : "", j, "xyz"[a]);
    affect_strbuf_putc(&sb, '\n');
    for (int r = 0; r < 6; r++) {
        int n = r == 5 ? 65 : 66;
        for (int c = 0; c < n; c++)
            affect_strbuf_printf(&sb, "%s%d.25", c ? "," : "", r * 100 + c);
        affect_strbuf_putc(&sb, '\n');
    }
    char *text;
    size_t len;
    assert_int_equal(affect_strbuf_finish(&sb, &text, &len, NULL), AFFECT_OK);
    expect_error(text, NULL, AFFECT_ERR_FORMAT, "row 7: expected 66 values, found 65");
    /* without the short row it parses */
    char *last = strrchr(text, '\n');
    *last = '\0';
    last = strrchr(text, '\n');
    last[1] = '\0';
    affect_motion *m = parse_ok(text, NULL);
    assert_int_equal(m->n_frames, 5);
    assert_int_equal(m->n_joints, 22);
    assert_string_equal(m->names[21], "Joint21");
    assert_true(affect_motion_at(m, 4, 21)[2] == 465.25f);
    affect_motion_free(m);
    affect_free(text);
}

/* ---- writing ---- */

static affect_motion *make_motion(uint32_t frames, uint32_t joints)
{
    affect_motion *m = NULL;
    assert_int_equal(affect_motion_create(frames, joints, 30.0, &m, NULL), AFFECT_OK);
    return m;
}

static void set_name(affect_motion *m, uint32_t j, const char *name)
{
    assert_int_equal(affect_motion_set_name(m, j, name, strlen(name), NULL), AFFECT_OK);
}

/* Frames × joints against opt->max_samples (AFFECT_MOTION_MAX_SAMPLES by default), checked
 * before each row is stored; the capacity is never sized beyond it. */
static void test_max_samples(void **state)
{
    static const char text[] = "a.x,a.y,a.z,b.x,b.y,b.z\n1,2,3,4,5,6\n1,2,3,4,5,6\n"
                               "1,2,3,4,5,6\n1,2,3,4,5,6\n";
    affect_csv_options o = opts(',', -1);
    o.max_samples = 6;
    expect_error(text, &o, AFFECT_ERR_RANGE,
                 "row 5: 4 frames x 2 joints is 8 samples, above the limit of 6 (option "
                 "max_samples)");
    o.max_samples = 8;
    affect_motion *m = parse_ok(text, &o);
    assert_int_equal(m->n_frames, 4);
    affect_motion_free(m);
    o.max_samples = 0; /* the default */
    m = parse_ok(text, &o);
    assert_int_equal(m->n_frames, 4);
    affect_motion_free(m);
    /* without a header the first row is a frame too */
    o = opts(',', 0);
    o.max_samples = 1;
    expect_error("1,2,3,4,5,6\n", &o, AFFECT_ERR_RANGE,
                 "row 1: 1 frames x 2 joints is 2 samples, above the limit of 1 (option "
                 "max_samples)");
}

static void test_write_format(void **state)
{
    (void)state;
    affect_motion *m = make_motion(2, 2);
    set_name(m, 0, "Hips");
    set_name(m, 1, "a,\"b\"");
    static const float v[] = {0.1f, -0.0f, 1e-7f, 1, 2.5f, -3, 100, 1e10f, 0, 0, 0, 0};
    memcpy(m->pos, v, sizeof v);
    char *text;
    size_t len;
    affect_error err;
    assert_int_equal(affect_csv_write(m, &text, &len, NULL, &err), AFFECT_OK);
    assert_string_equal(text, "Hips.x,Hips.y,Hips.z,\"a,\"\"b\"\".x\",\"a,\"\"b\"\".y\","
                              "\"a,\"\"b\"\".z\"\n"
                              "0.1,-0,1e-07,1,2.5,-3\n"
                              "100,1e+10,0,0,0,0\n");
    assert_int_equal(len, strlen(text));
    affect_free(text);

    /* a non-finite value cannot be written */
    m->pos[4] = NAN;
    text = (char *)&text;
    assert_int_equal(affect_csv_write(m, &text, &len, NULL, &err), AFFECT_ERR_FORMAT);
    assert_null(text);
    assert_string_equal(err.msg, "non-finite coordinate at frame 0, joint 1 (a,\"b\"), y");
    affect_motion_free(m);
}

static void test_round_trip_awkward(void **state)
{
    (void)state;
    const float denormal = 1.4e-45f; /* the smallest, 2^-149 */
    const float values[] = {0.1f,
                            -0.0f,
                            1e-7f,
                            FLT_MAX,
                            -FLT_MAX,
                            FLT_MIN,
                            denormal,
                            -denormal,
                            0x1.fffffcp-127f,
                            1.0f / 3.0f,
                            16777215.0f,
                            123456.789f,
                            -2.5e-38f,
                            0.0f,
                            3.4028235e38f,
                            9.99999944e-11f,
                            1e38f,
                            7.0e-44f};
    const uint32_t n_values = sizeof values / sizeof *values; /* 18: six joints */
    affect_motion *m = make_motion(2, n_values / 3);
    static const char *const names[] = {"a,b",      "q\"t",     "line\nbreak",
                                        " leading", "Left Arm", "Kopf.x"};
    for (uint32_t j = 0; j < n_values / 3; j++)
        set_name(m, j, names[j]);
    memcpy(m->pos, values, sizeof values);
    for (uint32_t i = 0; i < n_values; i++)
        m->pos[n_values + i] = -values[n_values - 1 - i];
    assert_round_trip(m);
    /* carriage return and a name that starts with a byte order mark */
    set_name(m, 2, "cr\rlf\r\n");
    set_name(m, 0,
             "\xEF\xBB\xBF"
             "bom");
    assert_round_trip(m);
    affect_motion_free(m);
}

/* 1000 frames × 27 joints of random float32 bit patterns (every magnitude, both signs,
 * denormals) written and read back bit-identically. */
static void test_round_trip_large(void **state)
{
    (void)state;
    affect_motion *m = make_motion(1000, 27);
    affect_rng rng;
    affect_rng_seed(&rng, 20240611);
    for (uint32_t j = 0; j < 27; j++) {
        char name[32];
        snprintf(name, sizeof name, "Joint_%02u", j);
        set_name(m, j, name);
    }
    size_t n = (size_t)1000 * 27 * 3;
    for (size_t i = 0; i < n; i++) {
        float f;
        do {
            uint32_t bits = (uint32_t)(affect_rng_next(&rng) >> 32);
            memcpy(&f, &bits, sizeof f);
        } while (!isfinite(f));
        /* half the values in the realistic range of a capture in cm */
        m->pos[i] = (i & 1) ? f : (float)affect_rng_range(&rng, -200.0, 200.0);
    }
    assert_round_trip(m);
    affect_motion_free(m);
}

/* ---- out of memory ---- */

/* a header with escapes and enough frames to grow the position array several times */
typedef struct csv_oom {
    const char *text;
    size_t len;
    affect_csv_options opts;
    affect_motion *m; /* parse output, or the motion to write */
    char *out;        /* write output */
    size_t out_len;
} csv_oom;

static affect_status oom_parse(void *ctx, affect_error *err)
{
    csv_oom *c = ctx;
    c->m = NULL;
    return affect_csv_parse(c->text, c->len, 30.0, &c->opts, &c->m, err);
}

static void oom_parse_finish(void *ctx, affect_status st)
{
    csv_oom *c = ctx;
    if (st != AFFECT_OK) {
        assert_null(c->m);
        return;
    }
    assert_int_equal(c->m->n_frames, 240);
    assert_string_equal(c->m->names[0], "q\"t");
    assert_true(affect_motion_at(c->m, 239, 0)[0] == 239.0f);
    assert_true(affect_motion_at(c->m, 239, 1)[2] == 6.123456f);
    assert_true(affect_motion_at(c->m, 0, 0)[1] == 2.123456f);
    affect_motion_free(c->m);
    c->m = NULL;
}

static affect_status oom_write(void *ctx, affect_error *err)
{
    csv_oom *c = ctx;
    c->out = NULL;
    return affect_csv_write(c->m, &c->out, &c->out_len, NULL, err);
}

static void oom_write_finish(void *ctx, affect_status st)
{
    csv_oom *c = ctx;
    if (st != AFFECT_OK) {
        assert_null(c->out);
        return;
    }
    assert_int_equal(c->out_len, strlen(c->out));
    affect_free(c->out); /* through the counting allocator, which counts it */
}

static void test_out_of_memory(void **state)
{
    (void)state;
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "\"q\"\"t.x\",\"q\"\"t.y\",\"q\"\"t.z\",b.x,b.y,b.z\n");
    /* long first lines, then short ones: the capacity estimated from the first data row is
     * too small, so the array also doubles, and is trimmed at the end */
    for (int r = 0; r < 40; r++)
        affect_strbuf_printf(&sb, "%d.123456,2.123456,3.123456,4.123456,5.123456,6.123456\n", r);
    for (int r = 40; r < 240; r++)
        affect_strbuf_printf(&sb, "%d,2,3,4,5,6.123456\n", r);
    char *text;
    size_t len;
    assert_int_equal(affect_strbuf_finish(&sb, &text, &len, NULL), AFFECT_OK);

    csv_oom c = {.text = text, .len = len, .opts = opts(',', -1)};
    c.opts.unit = "cm";
    long absorbed;
    long failures = tu_oom_sweep(oom_parse, &c, oom_parse_finish, &absorbed);
    /* fields, motion parts, names, positions were all failed in turn */
    assert_true(failures >= 5 && failures < 1000);
    /* only the final trim may fail harmlessly (the motion keeps its larger block) */
    assert_int_equal(absorbed, 1);

    /* the writer too */
    c.m = parse_ok_len(text, len, NULL);
    failures = tu_oom_sweep(oom_write, &c, oom_write_finish, NULL);
    assert_true(failures < 1000);
    affect_motion_free(c.m);
    affect_free(text);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_header_styles),
        cmocka_unit_test(test_header_last_separator),
        cmocka_unit_test(test_no_header),
        cmocka_unit_test(test_header_detection),
        cmocka_unit_test(test_line_ends),
        cmocka_unit_test(test_bom),
        cmocka_unit_test(test_blank_lines),
        cmocka_unit_test(test_quoted_fields),
        cmocka_unit_test(test_delimiters),
        cmocka_unit_test(test_unit_and_fps),
        cmocka_unit_test(test_argument_errors),
        cmocka_unit_test(test_structure_errors),
        cmocka_unit_test(test_long_name_and_wide_rows),
        cmocka_unit_test(test_value_errors),
        cmocka_unit_test(test_ragged_rows),
        cmocka_unit_test(test_max_samples),
        cmocka_unit_test(test_write_format),
        cmocka_unit_test(test_round_trip_awkward),
        cmocka_unit_test(test_round_trip_large),
        cmocka_unit_test(test_out_of_memory),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
