/*
 * csv.c — motions as CSV text: one row per frame, three columns (x, y, z) per joint
 * (see affect/io.h).
 *
 * Usage: see the block at the top of affect/io.h (compiled by the style/header-usage test).
 *
 * What CSV carries: joint names and positions only. It has no place for the skeleton
 * (parents), the frame rate or the unit, so the writer drops them and the reader takes fps
 * and the unit from its caller; every parsed motion has all parents −1.
 *
 * Reading, line by line:
 *   - Lines end in LF, CRLF or a lone CR; the last line needs no line end. A UTF-8 byte order
 *     mark at the very start is skipped. Lines holding only spaces and tabs are skipped, but
 *     they count in row numbers: "row N" is always the N-th line of the text.
 *   - Fields are separated by the delimiter (',' default, ';', tab or space) and spaces and
 *     tabs around a field are trimmed. With the tab delimiter, a run of tabs separates two
 *     fields; with the space delimiter, a run of spaces and tabs does (white-space separated
 *     columns). Either way such runs at the start or end of a line are ignored, and "Head X"
 *     is one header field with the tab delimiter (quote it with the space delimiter).
 *   - A field may be double-quoted (RFC 4180): "" inside quotes is one quote, and only spaces,
 *     tabs or the delimiter may follow the closing quote. A quoted field must close on its
 *     own line, except in a row that may be a header (opt->header ≠ 0), where a joint name
 *     may hold a line break; the writer quotes such names, and the line breaks count as
 *     lines in row numbers. A quote inside an unquoted field is an ordinary character.
 *   - Header: opt->header = 1 says the first non-blank row names the columns, 0 says there is
 *     none, −1 (default) decides: the first row is a header when one of its non-empty fields
 *     is not a number. A header field is "<joint><sep><axis>" where the LAST of '.', '_', ' '
 *     or ':' is the separator and the axis is one letter x, y or z in either case ("Head.x",
 *     "Left_Hand_X", "Head Y", "Neck:z"). Columns come in x, y, z triples of one joint name,
 *     which must be valid UTF-8. Without a header the joints are named j0, j1, ….
 *   - Data: every field is one number, the whole field ([+-]digits[.digits][e[+-]digits], read
 *     by affect_parse_double and rounded to float32), and every row has as many fields as the
 *     first row (with ',' or ';', a trailing delimiter makes an extra, empty field).
 *
 * Errors (row = 1-based line number, column = 1-based field number in its row):
 *     fps must be a positive number, got -1                    (AFFECT_ERR_INVALID)
 *     fps must be at most 100000, got 200000                   (AFFECT_ERR_INVALID)
 *     delimiter must be ',', ';', tab or space                 (AFFECT_ERR_INVALID)
 *     header must be -1 (detect), 0 (none) or 1 (first row), got 2   (AFFECT_ERR_INVALID)
 *     unit …                                  (affect_motion_set_unit's message, INVALID)
 *     text is NULL                                             (AFFECT_ERR_INVALID)
 *     no data rows
 *     row 1: the column count 7 is not a multiple of 3
 *     row 1: more than 12288 columns (3 per joint, at most 4096 joints)  (AFFECT_ERR_RANGE)
 *     row 1, column 4: "Hips" does not end in .x, .y or .z
 *     row 1, column 1: ".x" has no joint name before the axis
 *     row 1, column 4: expected "Neck.x" to start a joint, found "Neck.y"
 *     row 1, column 5: expected "Head.y" after "Head.x", found "Neck.x"
 *     row 1, column 7: the joint name is 1030 bytes long (at most 1024)
 *     row 1, column 1: the joint name contains a NUL byte
 *     row 1: joints 0 and 2 have the same name "Head"    (affect_motion_validate's message)
 *     row 7: expected 66 values, found 65
 *     row 3, column 2: "abc" is not a number
 *     row 3, column 2: empty value
 *     row 2, column 1: 1e40 does not fit a 32-bit float        (AFFECT_ERR_RANGE)
 *     row 3, column 2: the quoted field does not end on its line
 *     row 1, column 2: the quoted field is not closed          (header row, at the end of text)
 *     row 3, column 2: unexpected text after the closing quote
 *     row 9: more than 16777216 frames                          (AFFECT_ERR_RANGE)
 *     row 9: 8 frames x 3 joints is 24 samples, above the limit of 20 (option max_samples)
 *                                         (frames × joints above opt->max_samples, RANGE)
 * Quoted field text in messages is cut to 48 bytes. The status is AFFECT_ERR_FORMAT unless
 * noted, or AFFECT_ERR_NOMEM.
 *
 * How it works: one pass over the text. The first non-blank row is split into field
 * descriptors (pointers into the text, nothing copied); it becomes the header or the first
 * frame, and fixes the column count. Every later row is parsed straight into a growable float
 * array: affect_parse_double reads the number where it stands and the parser only checks that
 * a delimiter or the line end follows, so each byte is looked at about once and there is no
 * allocation per field or per row. The array grows geometrically (its first growth is
 * estimated from the length of the first data row and the bytes left, which for regular files
 * allocates once), every size is overflow-checked, and at the end the array is handed to the
 * motion without a copy and trimmed to its exact size.
 *
 * Writing: a header "name.x,name.y,name.z,…" (a name with a comma, quote, CR or LF, or
 * starting with a space, tab or byte order mark, is written as a quoted field with "" for its
 * quotes), then one line per frame with the shortest decimal that reads back as the same
 * float32 (affect_strbuf_float), '\n' after every line including the last. Parsing the output
 * gives back the same names and bit-identical positions.
 */
#include "affect/io.h"
#include "util/numparse.h"
#include "util/strbuf.h"

#include <math.h>
#include <string.h>

#define CSV_MAX_COLUMNS (3u * AFFECT_MOTION_MAX_JOINTS)
#define CSV_SHOWN_MAX 48     /* bytes of a field quoted in an error message */
#define CSV_FIRST_FRAMES 16u /* capacity, in frames, when nothing suggests better */

/* One field of a row. For a quoted field, p..p+n is the text between the quotes, still with
 * its "" pairs when escaped is set; otherwise the trimmed field. */
typedef struct csv_field {
    const char *p;
    size_t n;
    bool quoted;
    bool escaped;
} csv_field;

/* The reader polls the monitor every this many rows, the writer every this many frames. */
#define POLL_FRAMES 1024

typedef struct csv_parser {
    const char *p, *end;
    char delim;
    size_t row;       /* line number of the current row (its last line, for a header) */
    size_t first_row; /* line number where the first row starts */
    affect_error *err;
    affect_monitor *mon; /* the caller's (may be NULL) */

    csv_field *fields; /* the first row, split */
    size_t n_fields, cap_fields;
    char *unescaped; /* header fields with "" pairs, unescaped */

    size_t n_cols;
    uint32_t n_frames;
    float *pos; /* n_frames * n_cols values, capacity cap_pos */
    size_t cap_pos;
    size_t first_len;     /* bytes of the first data row and its line end; 0 until known */
    bool estimated;       /* the capacity has been sized from first_len */
    size_t header_row;    /* 0 when there is no header */
    uint64_t max_samples; /* frames × joints at most */
    affect_motion *m;
} csv_parser;

/* ---- small helpers ---- */

static bool is_blank(char c)
{
    return c == ' ' || c == '\t';
}

/* The delimiter; with the space delimiter, a tab too (white space separates fields). */
static bool is_delim(const csv_parser *ps, char c)
{
    return c == ps->delim || (ps->delim == ' ' && c == '\t');
}

/* Spaces and tabs that are trimmed around fields: both, except delimiters. */
static bool is_trim(const csv_parser *ps, char c)
{
    return is_blank(c) && !is_delim(ps, c);
}

/* Separators of joint name and axis in a header field. */
static bool is_separator(char c)
{
    return c == '.' || c == '_' || c == ' ' || c == ':';
}

/* True when q ends a field: the end of the text, a line end or the delimiter. */
static bool ends_field(const csv_parser *ps, const char *q)
{
    return q == ps->end || *q == '\n' || *q == '\r' || is_delim(ps, *q);
}

/* How many bytes of s (at most CSV_SHOWN_MAX) to quote in a message, not cutting a UTF-8
 * sequence. */
static int shown(const char *s, size_t n)
{
    if (n <= CSV_SHOWN_MAX)
        return (int)n;
    n = CSV_SHOWN_MAX;
    while (n > 0 && ((unsigned char)s[n] & 0xC0) == 0x80)
        n--;
    return (int)n;
}

/* Whether s..s+n has the form of a number: [+-](digits[.digits] | .digits)[(e|E)[+-]digits]. */
static bool looks_numeric(const char *s, size_t n)
{
    const char *p = s, *end = s + n;
    size_t digits = 0;
    if (p < end && (*p == '+' || *p == '-'))
        p++;
    for (; p < end && *p >= '0' && *p <= '9'; p++)
        digits++;
    if (p < end && *p == '.')
        for (p++; p < end && *p >= '0' && *p <= '9'; p++)
            digits++;
    if (digits == 0)
        return false;
    if (p < end && (*p == 'e' || *p == 'E')) {
        p++;
        if (p < end && (*p == '+' || *p == '-'))
            p++;
        if (p == end || *p < '0' || *p > '9')
            return false;
        while (p < end && *p >= '0' && *p <= '9')
            p++;
    }
    return p == end;
}

/* ---- lines and fields ---- */

/* Consumes the line end at ps->p (LF, CRLF or CR), if any. */
static void end_line(csv_parser *ps)
{
    if (ps->p < ps->end && *ps->p == '\r') {
        ps->p++;
        if (ps->p < ps->end && *ps->p == '\n')
            ps->p++;
    } else if (ps->p < ps->end && *ps->p == '\n') {
        ps->p++;
    }
}

/* Moves to the first field of the next non-blank line, counting rows; false at the end. */
static bool next_row(csv_parser *ps)
{
    while (ps->p < ps->end) {
        ps->row++;
        const char *q = ps->p;
        while (q < ps->end && is_blank(*q))
            q++;
        ps->p = q;
        if (q < ps->end && *q != '\n' && *q != '\r')
            return true;
        end_line(ps);
    }
    return false;
}

/* After a field: true and ps->p at the next field when the delimiter follows, false at the
 * line end. With a blank delimiter, the whole run and a run ending the line are consumed. */
static bool next_field(csv_parser *ps)
{
    const char *q = ps->p;
    if (q == ps->end || !is_delim(ps, *q))
        return false;
    q++;
    if (is_blank(ps->delim)) {
        while (q < ps->end && is_blank(*q))
            q++;
        if (q == ps->end || *q == '\n' || *q == '\r') {
            ps->p = q;
            return false;
        }
    }
    ps->p = q;
    return true;
}

/* Splits the field at ps->p into *f and leaves ps->p at what ends it. A quoted field may
 * hold line ends (counted in ps->row) only when multiline is set. */
static affect_status scan_field(csv_parser *ps, size_t col, bool multiline, csv_field *f)
{
    const char *q = ps->p, *end = ps->end;
    const size_t row = ps->row;
    while (q < end && is_trim(ps, *q))
        q++;
    f->quoted = false;
    f->escaped = false;
    if (q < end && *q == '"') {
        const char *start = ++q;
        for (;;) {
            if (q == end && multiline)
                return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                                   "row %zu, column %zu: the quoted field is not closed", row, col);
            if (q == end || ((*q == '\n' || *q == '\r') && !multiline))
                return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                                   "row %zu, column %zu: the quoted field does not end on its line",
                                   row, col);
            if (*q == '\n' || *q == '\r') {
                if (*q == '\r' && q + 1 < end && q[1] == '\n')
                    q++;
                ps->row++;
            } else if (*q == '"') {
                if (q + 1 < end && q[1] == '"') {
                    f->escaped = true;
                    q += 2;
                    continue;
                }
                break;
            }
            q++;
        }
        f->p = start;
        f->n = (size_t)(q - start);
        f->quoted = true;
        q++;
        while (q < end && is_trim(ps, *q))
            q++;
        if (!ends_field(ps, q))
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu, column %zu: unexpected text after the closing quote", row,
                               col);
    } else {
        const char *start = q;
        while (!ends_field(ps, q))
            q++;
        const char *stop = q;
        while (stop > start && is_trim(ps, stop[-1]))
            stop--;
        f->p = start;
        f->n = (size_t)(stop - start);
    }
    ps->p = q;
    return AFFECT_OK;
}

static affect_status too_big(const csv_parser *ps, size_t col, const char *s, size_t n)
{
    return affect_fail(ps->err, AFFECT_ERR_RANGE,
                       "row %zu, column %zu: %.*s does not fit a 32-bit float", ps->row, col,
                       shown(s, n), s);
}

/* The value of a split field. */
static affect_status field_value(const csv_parser *ps, size_t col, const csv_field *f, float *out)
{
    if (f->n == 0)
        return affect_fail(ps->err, AFFECT_ERR_FORMAT, "row %zu, column %zu: empty value", ps->row,
                           col);
    double v = 0;
    const char *stop = f->p + f->n;
    if (!f->escaped && affect_parse_double(f->p, stop, &v) == stop) {
        float fv = (float)v;
        if (isinf(fv))
            return too_big(ps, col, f->p, f->n);
        *out = fv;
        return AFFECT_OK;
    }
    if (!f->escaped && looks_numeric(f->p, f->n)) /* beyond the double range: 1e400 */
        return too_big(ps, col, f->p, f->n);
    return affect_fail(ps->err, AFFECT_ERR_FORMAT, "row %zu, column %zu: \"%.*s\" is not a number",
                       ps->row, col, shown(f->p, f->n), f->p);
}

/* Reads the field at ps->p as a float. The fast path parses the number where it stands and
 * checks what follows; quoted fields and errors go through scan_field. */
static affect_status read_value(csv_parser *ps, size_t col, float *out)
{
    const char *q = ps->p, *end = ps->end;
    while (q < end && is_trim(ps, *q))
        q++;
    if (q < end && *q != '"') {
        double v;
        const char *after = affect_parse_double(q, end, &v);
        if (after) {
            const char *s = after;
            while (s < end && is_trim(ps, *s))
                s++;
            if (ends_field(ps, s)) {
                float fv = (float)v;
                if (isinf(fv))
                    return too_big(ps, col, q, (size_t)(after - q));
                *out = fv;
                ps->p = s;
                return AFFECT_OK;
            }
        }
    }
    csv_field f;
    affect_status st = scan_field(ps, col, false, &f);
    if (st)
        return st;
    return field_value(ps, col, &f, out);
}

/* ---- the first row ---- */

/* Splits the current row into ps->fields, leaving ps->p at its line end. Quoted fields may
 * span lines when the row can be a header (a joint name may hold a line break). */
static affect_status split_row(csv_parser *ps, bool multiline)
{
    ps->n_fields = 0;
    ps->first_row = ps->row;
    do {
        if (ps->n_fields == CSV_MAX_COLUMNS)
            return affect_fail(ps->err, AFFECT_ERR_RANGE,
                               "row %zu: more than %u columns (3 per joint, at most %u joints)",
                               ps->first_row, CSV_MAX_COLUMNS, AFFECT_MOTION_MAX_JOINTS);
        if (ps->n_fields == ps->cap_fields) {
            size_t cap = ps->cap_fields ? ps->cap_fields * 2 : 48;
            if (cap > CSV_MAX_COLUMNS)
                cap = CSV_MAX_COLUMNS;
            csv_field *grown = affect_realloc(ps->fields, cap * sizeof *grown);
            if (!grown)
                return affect_nomem(ps->err);
            ps->fields = grown;
            ps->cap_fields = cap;
        }
        affect_status st = scan_field(ps, ps->n_fields + 1, multiline, &ps->fields[ps->n_fields]);
        if (st)
            return st;
        ps->n_fields++;
    } while (next_field(ps));
    return AFFECT_OK;
}

/* Header detection: some non-empty field is not a number. */
static bool row_looks_like_header(const csv_parser *ps)
{
    for (size_t i = 0; i < ps->n_fields; i++) {
        const csv_field *f = &ps->fields[i];
        if (f->n && (f->escaped || !looks_numeric(f->p, f->n)))
            return true;
    }
    return false;
}

static affect_status check_column_count(const csv_parser *ps)
{
    if (ps->n_fields % 3)
        return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                           "row %zu: the column count %zu is not a multiple of 3", ps->first_row,
                           ps->n_fields);
    return AFFECT_OK;
}

/* Replaces the "" pairs of escaped header fields by single quotes, in one buffer. */
static affect_status unescape_fields(csv_parser *ps)
{
    size_t total = 0;
    for (size_t i = 0; i < ps->n_fields; i++)
        if (ps->fields[i].escaped && !affect_add_size(total, ps->fields[i].n, &total))
            return affect_nomem(ps->err);
    if (total == 0)
        return AFFECT_OK;
    ps->unescaped = affect_malloc(total);
    if (!ps->unescaped)
        return affect_nomem(ps->err);
    char *o = ps->unescaped;
    for (size_t i = 0; i < ps->n_fields; i++) {
        csv_field *f = &ps->fields[i];
        if (!f->escaped)
            continue;
        char *start = o;
        for (size_t k = 0; k < f->n; k++) {
            *o++ = f->p[k];
            if (f->p[k] == '"')
                k++; /* the second quote of the pair */
        }
        f->p = start;
        f->n = (size_t)(o - start);
        f->escaped = false;
    }
    return AFFECT_OK;
}

/* A header field split at its last separator: the joint name is p..p+name_len, the
 * separator p[name_len] and the axis letter p[name_len + 1]. Returns the axis 0..2 or −1. */
static int split_header(const csv_field *f, size_t *name_len)
{
    size_t i = f->n; /* one past the last separator */
    while (i > 0 && !is_separator(f->p[i - 1]))
        i--;
    if (i == 0 || i != f->n - 1)
        return -1;
    *name_len = i - 1;
    char axis = (char)(f->p[i] | 0x20); /* lower case */
    return axis == 'x' ? 0 : axis == 'y' ? 1 : axis == 'z' ? 2 : -1;
}

/* Checks the header's x, y, z triples and creates the motion with its joint names. */
static affect_status read_header(csv_parser *ps, double fps)
{
    static const char lower[] = "xyz", upper[] = "XYZ";
    affect_status st = unescape_fields(ps);
    if (st)
        return st;
    const csv_field *fs = ps->fields;
    for (size_t i = 0; i < ps->n_fields; i++) {
        const csv_field *f = &fs[i];
        size_t col = i + 1, name_len = 0;
        int axis = split_header(f, &name_len);
        if (axis < 0)
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu, column %zu: \"%.*s\" does not end in .x, .y or .z",
                               ps->first_row, col, shown(f->p, f->n), f->p);
        if (name_len == 0)
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu, column %zu: \"%.*s\" has no joint name before the axis",
                               ps->first_row, col, shown(f->p, f->n), f->p);
        if (i % 3 == 0) {
            if (axis != 0) {
                bool up = f->p[f->n - 1] >= 'A' && f->p[f->n - 1] <= 'Z';
                return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                                   "row %zu, column %zu: expected \"%.*s%c%c\" to start a joint, "
                                   "found \"%.*s\"",
                                   ps->first_row, col, shown(f->p, name_len), f->p, f->p[name_len],
                                   up ? 'X' : 'x', shown(f->p, f->n), f->p);
            }
            continue;
        }
        const csv_field *x = &fs[i - i % 3], *prev = &fs[i - 1];
        size_t x_len = x->n - 2;
        if (axis != (int)(i % 3) || name_len != x_len || memcmp(f->p, x->p, x_len) != 0) {
            bool up = x->p[x->n - 1] == 'X';
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu, column %zu: expected \"%.*s%c%c\" after \"%.*s\", "
                               "found \"%.*s\"",
                               ps->first_row, col, shown(x->p, x_len), x->p, x->p[x_len],
                               (up ? upper : lower)[i % 3], shown(prev->p, prev->n), prev->p,
                               shown(f->p, f->n), f->p);
        }
    }
    st = check_column_count(ps);
    if (st)
        return st;
    /* The joint names: length, NUL and UTF-8 checks with the column, before creating anything. */
    for (size_t i = 0; i < ps->n_fields; i += 3) {
        size_t len = fs[i].n - 2;
        if (len > AFFECT_MOTION_MAX_NAME)
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu, column %zu: the joint name is %zu bytes long (at most %u)",
                               ps->first_row, i + 1, len, AFFECT_MOTION_MAX_NAME);
        if (memchr(fs[i].p, '\0', len))
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu, column %zu: the joint name contains a NUL byte",
                               ps->first_row, i + 1);
        st = affect_utf8_check(ps->err, AFFECT_ERR_FORMAT, fs[i].p, len,
                               "row %zu, column %zu: the joint name", ps->first_row, i + 1);
        if (st)
            return st;
    }
    ps->n_cols = ps->n_fields;
    ps->header_row = ps->first_row;
    st = affect_motion_create(1, (uint32_t)(ps->n_cols / 3), fps, &ps->m, ps->err);
    for (size_t i = 0; i < ps->n_cols && !st; i += 3)
        st = affect_motion_set_name(ps->m, (uint32_t)(i / 3), fs[i].p, fs[i].n - 2, ps->err);
    return st;
}

/* ---- the frames ---- */

/* Makes room for n_frames frames. The first time the length of the first data row is known,
 * the capacity is sized for the rest of the text; otherwise it doubles. */
static affect_status reserve_frames(csv_parser *ps, size_t n_frames)
{
    size_t need, cap, bytes;
    if (!affect_mul_size(n_frames, ps->n_cols, &need))
        return affect_nomem(ps->err);
    if (need <= ps->cap_pos)
        return AFFECT_OK;
    size_t frames = CSV_FIRST_FRAMES;
    if (ps->first_len && !ps->estimated) {
        frames = n_frames + (size_t)(ps->end - ps->p) / ps->first_len + 1;
        ps->estimated = true;
    } else if (ps->cap_pos) {
        frames = ps->cap_pos / ps->n_cols;
        frames = frames <= SIZE_MAX / 2 ? frames * 2 : SIZE_MAX;
    }
    if (frames > AFFECT_MOTION_MAX_FRAMES)
        frames = AFFECT_MOTION_MAX_FRAMES;
    size_t joints = ps->n_cols / 3 ? ps->n_cols / 3 : 1;
    if (frames > ps->max_samples / joints) /* more would be refused by check_samples */
        frames = (size_t)(ps->max_samples / joints);
    if (!affect_mul_size(frames, ps->n_cols, &cap) || cap < need)
        cap = need;
    if (!affect_mul_size(cap, sizeof *ps->pos, &bytes))
        return affect_nomem(ps->err);
    float *grown = affect_realloc(ps->pos, bytes);
    if (!grown)
        return affect_nomem(ps->err);
    ps->pos = grown;
    ps->cap_pos = cap;
    return AFFECT_OK;
}

/* n_frames frames of the parser's joints against the limit on frames × joints; the error
 * names the current row. */
static affect_status check_samples(const csv_parser *ps, size_t n_frames)
{
    size_t joints = ps->n_cols / 3;
    if ((uint64_t)n_frames * joints <= ps->max_samples)
        return AFFECT_OK;
    return affect_fail(ps->err, AFFECT_ERR_RANGE,
                       "row %zu: %zu frames x %zu joints is %llu samples, above the limit of %llu "
                       "(option max_samples)",
                       ps->row, n_frames, joints, (unsigned long long)n_frames * joints,
                       (unsigned long long)ps->max_samples);
}

/* The first row as frame 0 (no header): its split fields hold the values. */
static affect_status read_first_frame(csv_parser *ps, double fps)
{
    affect_status st = reserve_frames(ps, 1);
    for (size_t i = 0; i < ps->n_fields && !st; i++)
        st = field_value(ps, i + 1, &ps->fields[i], &ps->pos[i]);
    if (!st)
        st = check_column_count(ps);
    if (!st)
        st = check_samples(ps, 1);
    if (!st)
        st = affect_motion_create(1, (uint32_t)(ps->n_cols / 3), fps, &ps->m, ps->err);
    if (!st)
        ps->n_frames = 1;
    return st;
}

/* Every remaining row, parsed straight into ps->pos. */
static affect_status read_frames(csv_parser *ps)
{
    const size_t n_cols = ps->n_cols;
    while (next_row(ps)) {
        const char *row_start = ps->p;
        if (ps->n_frames == AFFECT_MOTION_MAX_FRAMES)
            return affect_fail(ps->err, AFFECT_ERR_RANGE, "row %zu: more than %u frames", ps->row,
                               AFFECT_MOTION_MAX_FRAMES);
        affect_status st = check_samples(ps, (size_t)ps->n_frames + 1);
        if (!st && ps->n_frames % POLL_FRAMES == 0)
            st = affect_monitor_check(ps->mon, ps->err);
        if (st)
            return st;
        st = reserve_frames(ps, (size_t)ps->n_frames + 1);
        if (st)
            return st;
        float *dst = ps->pos + (size_t)ps->n_frames * n_cols;
        size_t col = 0;
        do {
            col++;
            if (col <= n_cols) {
                st = read_value(ps, col, &dst[col - 1]);
            } else {
                csv_field extra;
                st = scan_field(ps, col, false, &extra);
            }
            if (st)
                return st;
        } while (next_field(ps));
        if (col != n_cols)
            return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                               "row %zu: expected %zu values, found %zu", ps->row, n_cols, col);
        end_line(ps);
        if (!ps->first_len)
            ps->first_len = (size_t)(ps->p - row_start);
        ps->n_frames++;
    }
    return AFFECT_OK;
}

/* Hands the positions to the motion, sets the unit and validates. */
static affect_status finish(csv_parser *ps, const char *unit)
{
    affect_motion *m = ps->m;
    affect_free(m->pos);
    m->pos = ps->pos;
    m->n_frames = ps->n_frames;
    ps->pos = NULL;
    memcpy(m->unit, unit, sizeof m->unit);
    affect_status st = affect_motion_validate(m, ps->err);
    if (st && st != AFFECT_ERR_NOMEM && ps->header_row && ps->err) {
        /* A duplicate name: say which row holds the names. */
        char msg[AFFECT_ERROR_MSG_MAX];
        memcpy(msg, ps->err->msg, sizeof msg);
        affect_fail(ps->err, st, "row %zu: %s", ps->header_row, msg);
    }
    if (st)
        return st;
    /* Trim the spare capacity; if that fails the larger block is kept, which is harmless. */
    size_t used = (size_t)ps->n_frames * ps->n_cols;
    if (ps->cap_pos > used) {
        float *trimmed = affect_realloc(m->pos, used * sizeof *m->pos);
        if (trimmed)
            m->pos = trimmed;
    }
    return AFFECT_OK;
}

/* ---- public ---- */

void affect_csv_options_default(affect_csv_options *opt)
{
    opt->delimiter = ',';
    opt->header = -1;
    opt->unit = NULL;
    opt->max_samples = 0;
    opt->monitor = NULL;
}

/* Checks the arguments; the unit is checked by setting it on a probe motion. */
static affect_status check_arguments(const char *text, size_t len, double fps,
                                     const affect_csv_options *opt, affect_motion *probe,
                                     affect_error *err)
{
    if (!text && len)
        return affect_fail(err, AFFECT_ERR_INVALID, "text is NULL");
    if (!(fps > 0.0) || !isfinite(fps))
        return affect_fail(err, AFFECT_ERR_INVALID, "fps must be a positive number, got %g", fps);
    if (fps > AFFECT_MOTION_MAX_FPS)
        return affect_fail(err, AFFECT_ERR_INVALID, "fps must be at most %g, got %g",
                           AFFECT_MOTION_MAX_FPS, fps);
    char d = opt->delimiter;
    if (d != ',' && d != ';' && d != '\t' && d != ' ')
        return affect_fail(err, AFFECT_ERR_INVALID, "delimiter must be ',', ';', tab or space");
    if (opt->header < -1 || opt->header > 1)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "header must be -1 (detect), 0 (none) or 1 (first row), got %d",
                           opt->header);
    affect_error unit_err;
    if (affect_motion_set_unit(probe, opt->unit, &unit_err))
        return affect_fail(err, AFFECT_ERR_INVALID, "%s", unit_err.msg);
    return AFFECT_OK;
}

affect_status affect_csv_parse(const char *text, size_t len, double fps,
                               const affect_csv_options *opt, affect_motion **out,
                               affect_error *err)
{
    affect_csv_options defaults;
    affect_motion probe;
    *out = NULL;
    if (!opt) {
        affect_csv_options_default(&defaults);
        opt = &defaults;
    }
    memset(&probe, 0, sizeof probe);
    affect_status st = check_arguments(text, len, fps, opt, &probe, err);
    if (st)
        return st;
    if (!text)
        text = "";

    csv_parser ps;
    memset(&ps, 0, sizeof ps);
    ps.p = text;
    ps.end = text + len;
    ps.delim = opt->delimiter;
    ps.max_samples = opt->max_samples ? opt->max_samples : AFFECT_MOTION_MAX_SAMPLES;
    ps.err = err;
    ps.mon = opt->monitor;
    if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0)
        ps.p += 3;

    if (!next_row(&ps)) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "no data rows");
        goto cleanup;
    }
    const char *row_text = ps.p;
    st = split_row(&ps, opt->header != 0);
    if (st)
        goto cleanup;
    end_line(&ps);
    bool header = opt->header == 1 || (opt->header == -1 && row_looks_like_header(&ps));
    ps.n_cols = ps.n_fields;
    if (!header)
        ps.first_len = (size_t)(ps.p - row_text);
    st = header ? read_header(&ps, fps) : read_first_frame(&ps, fps);
    if (st)
        goto cleanup;
    st = read_frames(&ps);
    if (st)
        goto cleanup;
    if (ps.n_frames == 0) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "no data rows");
        goto cleanup;
    }
    st = finish(&ps, probe.unit);
    if (st)
        goto cleanup;
    *out = ps.m;
    ps.m = NULL;

cleanup:
    affect_motion_free(ps.m);
    affect_free(ps.pos);
    affect_free(ps.fields);
    affect_free(ps.unescaped);
    return st;
}

/* Whether a joint name must be written as a quoted field to read back unchanged. */
static bool needs_quotes(const char *name, bool first)
{
    if (is_blank(name[0]) || (first && strncmp(name, "\xEF\xBB\xBF", 3) == 0))
        return true;
    return strpbrk(name, ",\"\r\n") != NULL;
}

static void put_header_field(affect_strbuf *sb, const char *name, char axis, bool first)
{
    if (!needs_quotes(name, first)) {
        affect_strbuf_puts(sb, name);
        affect_strbuf_putc(sb, '.');
        affect_strbuf_putc(sb, axis);
        return;
    }
    affect_strbuf_putc(sb, '"');
    for (const char *p = name; *p; p++) {
        if (*p == '"')
            affect_strbuf_putc(sb, '"');
        affect_strbuf_putc(sb, *p);
    }
    affect_strbuf_putc(sb, '.');
    affect_strbuf_putc(sb, axis);
    affect_strbuf_putc(sb, '"');
}

affect_status affect_csv_write(const affect_motion *m, char **out, size_t *len, affect_monitor *mon,
                               affect_error *err)
{
    *out = NULL;
    if (len)
        *len = 0;
    affect_status st = affect_motion_validate(m, err);
    if (st)
        return st;
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    for (uint32_t j = 0; j < m->n_joints; j++)
        for (int a = 0; a < 3; a++) {
            if (j || a)
                affect_strbuf_putc(&sb, ',');
            put_header_field(&sb, m->names[j], "xyz"[a], j == 0 && a == 0);
        }
    affect_strbuf_putc(&sb, '\n');
    const size_t n_cols = (size_t)m->n_joints * 3;
    for (uint32_t t = 0; t < m->n_frames && !sb.failed; t++) {
        if (t % POLL_FRAMES == 0 && affect_monitor_stopped(mon)) {
            affect_strbuf_free(&sb);
            return affect_monitor_check(mon, err);
        }
        const float *row = affect_motion_at(m, t, 0);
        for (size_t c = 0; c < n_cols; c++) {
            if (c)
                affect_strbuf_putc(&sb, ',');
            affect_strbuf_float(&sb, row[c]);
        }
        affect_strbuf_putc(&sb, '\n');
    }
    return affect_strbuf_finish(&sb, out, len, err);
}
