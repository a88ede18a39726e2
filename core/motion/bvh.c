/*
 * bvh.c — Biovision Hierarchy (BVH) import with forward kinematics (see affect/io.h).
 *
 * Usage: see the block at the top of affect/io.h (compiled by the style/header-usage test).
 *
 * How it works:
 *   1. HIERARCHY: ROOT/JOINT blocks with OFFSET and CHANNELS, End Site blocks with OFFSET, read
 *      by a loop with an explicit stack (no recursion, so deep files cannot overflow the C
 *      stack). Several ROOTs are allowed. Keywords are matched case-insensitively; a joint's
 *      name is the rest of its line, and must be valid UTF-8. End Sites become joints named
 *      "<parent>_end"; a name that repeats an earlier one gets "_2", "_3", … appended.
 *   2. MOTION: "Frames: N", "Frame Time: t" (fps = 1/t, snapped to a whole number when
 *      within 1e-4 relative of one: 0.0333333 s means 30 fps), then N lines of exactly as many
 *      numbers as the channels declared (blank lines are skipped). N is checked against the
 *      text left before anything is allocated for the frames (two bytes per value and frame;
 *      a line end per frame when no joint has channels, since those frames take no other
 *      text) and frames × joints against opt->max_samples (AFFECT_MOTION_MAX_SAMPLES).
 *   3. Per frame, each joint's local translation is its OFFSET with each position channel
 *      replacing the component it names (the real corpus writes the OFFSET into the position
 *      channels of every joint; root position channels carry the global translation), and its
 *      local rotation is the product of the rotation channels in the order CHANNELS lists them
 *      (degrees). affect_fk_frame accumulates world rotations and positions in double.
 *   4. The motion keeps the skeleton (offsets, channels, End Sites) and every frame's local
 *      rotations (quaternions) and translations, so affect_bvh_write reproduces the file.
 * Numbers are read with affect_parse_double (locale-independent, no allocation).
 */
#include "affect/fk.h"
#include "affect/io.h"
#include "util/numparse.h"
#include "affect/quat.h"
#include "util/internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

enum { CH_XPOS, CH_YPOS, CH_ZPOS, CH_XROT, CH_YROT, CH_ZROT };

typedef struct bvh_joint {
    const char *name; /* points into the text, or NULL for an End Site */
    size_t name_len;
    int32_t parent;
    double offset[3];
    uint8_t n_channels;
    uint8_t channel[6];
    uint32_t first_value; /* index of this joint's first channel in a frame line */
} bvh_joint;

typedef struct parser {
    const char *p, *end;
    uint32_t line;
    affect_error *err;
    bvh_joint *joints;
    uint32_t n_joints, cap_joints;
    uint32_t n_values; /* channels per frame */
} parser;

static bool is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f';
}

/* Skips white space including newlines, counting lines. */
static void skip_ws(parser *ps)
{
    while (ps->p < ps->end && (is_space(*ps->p) || *ps->p == '\n')) {
        if (*ps->p == '\n')
            ps->line++;
        ps->p++;
    }
}

/* Next white-space-delimited token; len 0 at the end of the text. */
static const char *next_token(parser *ps, size_t *len)
{
    skip_ws(ps);
    const char *s = ps->p;
    while (ps->p < ps->end && !is_space(*ps->p) && *ps->p != '\n')
        ps->p++;
    *len = (size_t)(ps->p - s);
    return s;
}

static bool token_is(const char *tok, size_t len, const char *word)
{
    size_t n = strlen(word);
    if (len != n)
        return false;
    for (size_t i = 0; i < n; i++) {
        char a = tok[i], b = word[i];
        if (a >= 'A' && a <= 'Z')
            a = (char)(a - 'A' + 'a');
        if (b >= 'A' && b <= 'Z')
            b = (char)(b - 'A' + 'a');
        if (a != b)
            return false;
    }
    return true;
}

/* A token for a message: at most 40 bytes, control bytes written as \xNN. */
static void excerpt(const char *tok, size_t len, char out[168])
{
    static const char hex[] = "0123456789abcdef";
    size_t o = 0;
    for (size_t i = 0; i < len && i < 40; i++) {
        unsigned char c = (unsigned char)tok[i];
        if (c < 0x20 || c == 0x7f) {
            out[o++] = '\\';
            out[o++] = 'x';
            out[o++] = hex[c >> 4];
            out[o++] = hex[c & 15];
        } else {
            out[o++] = (char)c;
        }
    }
    out[o] = '\0';
}

/* "line N: expected WHAT, found TOKEN" (or "found end of text"). */
static affect_status expected(parser *ps, const char *what, const char *tok, size_t len)
{
    if (len == 0)
        return affect_fail(ps->err, AFFECT_ERR_FORMAT, "line %u: expected %s, found end of text",
                           ps->line, what);
    char shown[168];
    excerpt(tok, len, shown);
    return affect_fail(ps->err, AFFECT_ERR_FORMAT, "line %u: expected %s, found %s", ps->line, what,
                       shown);
}

static affect_status expect_word(parser *ps, const char *word)
{
    size_t len;
    const char *tok = next_token(ps, &len);
    if (!token_is(tok, len, word))
        return expected(ps, word, tok, len);
    return AFFECT_OK;
}

static affect_status read_number(parser *ps, const char *what, double *v)
{
    size_t len;
    const char *tok = next_token(ps, &len);
    const char *after = len ? affect_parse_double(tok, tok + len, v) : NULL;
    if (!after || after != tok + len)
        return expected(ps, what, tok, len);
    return AFFECT_OK;
}

static affect_status add_joint(parser *ps, const char *name, size_t name_len, int32_t parent,
                               uint32_t *index)
{
    if (ps->n_joints >= AFFECT_MOTION_MAX_JOINTS)
        return affect_fail(ps->err, AFFECT_ERR_RANGE, "line %u: more than %u joints", ps->line,
                           AFFECT_MOTION_MAX_JOINTS);
    if (ps->n_joints == ps->cap_joints) {
        uint32_t cap = ps->cap_joints ? ps->cap_joints * 2 : 32;
        bvh_joint *j = affect_realloc(ps->joints, (size_t)cap * sizeof *j);
        if (!j)
            return affect_nomem(ps->err);
        ps->joints = j;
        ps->cap_joints = cap;
    }
    bvh_joint *j = &ps->joints[ps->n_joints];
    memset(j, 0, sizeof *j);
    j->name = name;
    j->name_len = name_len;
    j->parent = parent;
    *index = ps->n_joints++;
    return AFFECT_OK;
}

/* The joint name: the rest of the line, trimmed; a trailing "{" on the same line is left for
 * the caller to read as the opening brace. */
static affect_status read_name(parser *ps, const char **name, size_t *len)
{
    while (ps->p < ps->end && is_space(*ps->p))
        ps->p++;
    const char *s = ps->p;
    while (ps->p < ps->end && *ps->p != '\n')
        ps->p++;
    const char *e = ps->p;
    while (e > s && is_space(e[-1]))
        e--;
    if (e > s && e[-1] == '{') { /* "JOINT Hips {" */
        ps->p = e - 1;
        e--;
        while (e > s && is_space(e[-1]))
            e--;
    }
    if (e == s)
        return affect_fail(ps->err, AFFECT_ERR_FORMAT, "line %u: expected a joint name", ps->line);
    if ((size_t)(e - s) > AFFECT_MOTION_MAX_NAME - 8)
        return affect_fail(ps->err, AFFECT_ERR_FORMAT, "line %u: joint name longer than %u bytes",
                           ps->line, AFFECT_MOTION_MAX_NAME - 8);
    /* refused here: name_joints compares names as C strings, so an embedded NUL would make
     * "A\0x" and "A" collide for every "_N" suffix it tries (an endless loop) */
    if (memchr(s, '\0', (size_t)(e - s)))
        return affect_fail(ps->err, AFFECT_ERR_FORMAT, "line %u: joint name contains a NUL byte",
                           ps->line);
    affect_status st = affect_utf8_check(ps->err, AFFECT_ERR_FORMAT, s, (size_t)(e - s),
                                         "line %u: joint name", ps->line);
    if (st)
        return st;
    *name = s;
    *len = (size_t)(e - s);
    return AFFECT_OK;
}

static affect_status read_offset(parser *ps, bvh_joint *j)
{
    affect_status st = expect_word(ps, "OFFSET");
    for (int a = 0; a < 3 && !st; a++)
        st = read_number(ps, "a number", &j->offset[a]);
    return st;
}

static affect_status read_channels(parser *ps, uint32_t index)
{
    affect_status st = expect_word(ps, "CHANNELS");
    if (st)
        return st;
    size_t len;
    const char *tok = next_token(ps, &len);
    double n;
    const char *after = len ? affect_parse_double(tok, tok + len, &n) : NULL;
    if (!after || after != tok + len || n != floor(n) || n < 0 || n > 6)
        return expected(ps, "a channel count from 0 to 6", tok, len);
    static const char *const names[6] = {"Xposition", "Yposition", "Zposition",
                                         "Xrotation", "Yrotation", "Zrotation"};
    bvh_joint *j = &ps->joints[index];
    j->n_channels = (uint8_t)n;
    j->first_value = ps->n_values;
    unsigned seen = 0;
    for (int c = 0; c < j->n_channels; c++) {
        tok = next_token(ps, &len);
        int type = -1;
        for (int k = 0; k < 6 && type < 0; k++)
            if (token_is(tok, len, names[k]))
                type = k;
        if (type < 0)
            return expected(ps, "a channel name (Xposition … Zrotation)", tok, len);
        if (seen & (1u << type))
            return affect_fail(ps->err, AFFECT_ERR_FORMAT, "line %u: channel %s listed twice",
                               ps->line, names[type]);
        seen |= 1u << type;
        j->channel[c] = (uint8_t)type;
    }
    ps->n_values += j->n_channels;
    return AFFECT_OK;
}

/* A ROOT or JOINT block's head: name, "{", OFFSET and CHANNELS. */
static affect_status read_joint_head(parser *ps, int32_t parent, uint32_t *index)
{
    const char *name = NULL;
    size_t name_len = 0;
    affect_status st = read_name(ps, &name, &name_len);
    if (!st)
        st = add_joint(ps, name, name_len, parent, index);
    if (!st)
        st = expect_word(ps, "{");
    if (!st)
        st = read_offset(ps, &ps->joints[*index]);
    if (!st)
        st = read_channels(ps, *index);
    return st;
}

/* ROOT … up to and including its closing brace. */
static affect_status parse_root(parser *ps)
{
    int32_t stack[AFFECT_MOTION_MAX_JOINTS];
    uint32_t depth = 0, index;
    size_t len;
    affect_status st = read_joint_head(ps, -1, &index);
    if (st)
        return st;
    stack[depth++] = (int32_t)index;
    while (depth > 0) {
        const char *tok = next_token(ps, &len);
        int32_t parent = stack[depth - 1];
        if (token_is(tok, len, "JOINT")) {
            st = read_joint_head(ps, parent, &index);
            if (st)
                return st;
            stack[depth++] = (int32_t)index; /* depth ≤ joints ≤ the stack's size */
        } else if (token_is(tok, len, "End")) {
            st = expect_word(ps, "Site");
            if (!st)
                st = add_joint(ps, NULL, 0, parent, &index);
            if (!st)
                st = expect_word(ps, "{");
            if (!st)
                st = read_offset(ps, &ps->joints[index]);
            if (!st)
                st = expect_word(ps, "}");
            if (st)
                return st;
        } else if (token_is(tok, len, "}")) {
            depth--;
        } else {
            return expected(ps, "JOINT, End Site or }", tok, len);
        }
    }
    return AFFECT_OK;
}

/* Open-addressing set of the names given so far (indices into m->names). */
static bool name_taken(const affect_motion *m, const int32_t *slots, uint32_t mask,
                       const char *name, uint32_t *slot)
{
    uint32_t h = affect_hash_name(name) & mask;
    while (slots[h] >= 0) {
        if (strcmp(m->names[slots[h]], name) == 0)
            return true;
        h = (h + 1) & mask;
    }
    *slot = h;
    return false;
}

/* n, or less, so that s[0 .. n) does not end inside a UTF-8 sequence (s has more than n bytes,
 * all valid UTF-8): a name shortened for a suffix stays valid UTF-8. */
static size_t utf8_cut(const char *s, size_t n)
{
    while (n > 0 && ((unsigned char)s[n] & 0xC0) == 0x80)
        n--;
    return n;
}

/* Gives every joint its final name (End Sites: "<parent>_end"; repeats get "_2", "_3", …). */
static affect_status name_joints(parser *ps, affect_motion *m)
{
    char buf[AFFECT_MOTION_MAX_NAME + 1];
    uint32_t cap = 16;
    while (cap < 2 * ps->n_joints)
        cap *= 2;
    int32_t *slots = affect_malloc_array(cap, sizeof *slots);
    if (!slots)
        return affect_nomem(ps->err);
    for (uint32_t i = 0; i < cap; i++)
        slots[i] = -1;
    affect_status st = AFFECT_OK;
    for (uint32_t i = 0; i < ps->n_joints && !st; i++) {
        const bvh_joint *j = &ps->joints[i];
        size_t len;
        if (j->name) {
            len = j->name_len;
            memcpy(buf, j->name, len);
        } else {
            const char *pn = m->names[j->parent];
            len = strlen(pn);
            if (len > AFFECT_MOTION_MAX_NAME - 4)
                len = utf8_cut(pn, AFFECT_MOTION_MAX_NAME - 4);
            memcpy(buf, pn, len);
            memcpy(buf + len, "_end", 4);
            len += 4;
        }
        buf[len] = '\0';
        size_t base = len;
        if (base > AFFECT_MOTION_MAX_NAME - 12)
            base = utf8_cut(buf, AFFECT_MOTION_MAX_NAME - 12);
        uint32_t slot = 0;
        for (unsigned suffix = 2; name_taken(m, slots, cap - 1, buf, &slot); suffix++)
            len = base + (size_t)snprintf(buf + base, 12, "_%u", suffix);
        st = affect_motion_set_name(m, i, buf, len, ps->err);
        if (!st)
            slots[slot] = (int32_t)i;
    }
    affect_free(slots);
    return st;
}

static affect_status parse_motion_header(parser *ps, uint32_t *n_frames, double *frame_time)
{
    size_t len;
    const char *tok = next_token(ps, &len);
    if (token_is(tok, len, "Frames")) {
        affect_status st = expect_word(ps, ":");
        if (st)
            return st;
    } else if (!token_is(tok, len, "Frames:")) {
        return expected(ps, "Frames:", tok, len);
    }
    double n;
    tok = next_token(ps, &len);
    const char *after = len ? affect_parse_double(tok, tok + len, &n) : NULL;
    if (!after || after != tok + len || n != floor(n) || n < 1 || n > AFFECT_MOTION_MAX_FRAMES)
        return expected(ps, "a frame count from 1 to 16777216", tok, len);
    *n_frames = (uint32_t)n;
    affect_status st = expect_word(ps, "Frame");
    if (st)
        return st;
    tok = next_token(ps, &len);
    if (token_is(tok, len, "Time")) {
        st = expect_word(ps, ":");
        if (st)
            return st;
    } else if (!token_is(tok, len, "Time:")) {
        return expected(ps, "Time:", tok, len);
    }
    st = read_number(ps, "a frame time in seconds", frame_time);
    if (st)
        return st;
    if (!(*frame_time > 0) || 1.0 / *frame_time > AFFECT_MOTION_MAX_FPS)
        return affect_fail(ps->err, AFFECT_ERR_FORMAT,
                           "line %u: frame time %g out of range (> 0, at most %g fps)", ps->line,
                           *frame_time, AFFECT_MOTION_MAX_FPS);
    /* the rest of the Frame Time line must be empty */
    while (ps->p < ps->end && is_space(*ps->p))
        ps->p++;
    if (ps->p < ps->end && *ps->p != '\n') {
        tok = next_token(ps, &len);
        return expected(ps, "the end of the Frame Time line", tok, len);
    }
    return AFFECT_OK;
}

/* Local transforms of every joint for one frame of channel values. */
static void local_transforms(const parser *ps, const double *values, double scale, double *trans,
                             double *rot)
{
    static const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (uint32_t i = 0; i < ps->n_joints; i++) {
        const bvh_joint *j = &ps->joints[i];
        double *t = trans + (size_t)i * 3, *r = rot + (size_t)i * 9;
        t[0] = j->offset[0] * scale;
        t[1] = j->offset[1] * scale;
        t[2] = j->offset[2] * scale;
        /* the rotation channels in CHANNELS order, composed by one Euler-matrix build
         * (missing ones are zero-angle rotations, which are exact identities) */
        int order[3] = {0, 0, 0}, n_rot = 0;
        double deg[3] = {0, 0, 0};
        const double *v = values + j->first_value;
        for (int c = 0; c < j->n_channels; c++) {
            int type = j->channel[c];
            if (type <= CH_ZPOS) {
                t[type] = v[c] * scale;
            } else {
                order[n_rot] = type - CH_XROT;
                deg[n_rot++] = v[c];
            }
        }
        if (n_rot == 0)
            memcpy(r, identity, sizeof identity);
        else
            affect_euler_deg_to_matrix(order, deg, r);
    }
}

/* Stores frame f's local rotations (as quaternions) and translations in m. */
static void keep_rotations(affect_motion *m, uint32_t f, const double *trans, const double *rot)
{
    size_t base = (size_t)f * m->n_joints;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        double q[4];
        affect_quat_from_matrix(rot + (size_t)j * 9, q);
        float *qo = m->rot + (base + j) * 4, *to = m->trans + (base + j) * 3;
        for (int a = 0; a < 4; a++)
            qo[a] = (float)q[a];
        for (int a = 0; a < 3; a++)
            to[a] = (float)trans[(size_t)j * 3 + a];
    }
}

/* The skeleton part of m: offsets (scaled), channels, End Sites. */
static void keep_skeleton(const parser *ps, affect_motion *m, double scale)
{
    for (uint32_t i = 0; i < ps->n_joints; i++) {
        const bvh_joint *j = &ps->joints[i];
        affect_skel_joint *s = &m->skel[i];
        for (int a = 0; a < 3; a++)
            s->offset[a] = j->offset[a] * scale;
        s->n_channels = j->n_channels;
        memcpy(s->channel, j->channel, sizeof s->channel);
        s->flags = j->name ? 0 : AFFECT_JOINT_END_SITE;
    }
}

/* Reads the frame lines and runs forward kinematics into m. */
/* parse_frames polls the monitor every this many frames */
#define POLL_FRAMES 1024

static affect_status parse_frames(parser *ps, affect_motion *m, double scale, affect_monitor *mon)
{
    uint32_t nv = ps->n_values, nj = ps->n_joints;
    double *values = affect_malloc_array(nv ? nv : 1, sizeof *values);
    double *trans = affect_malloc_array(nj, 3 * sizeof *trans);
    double *rot = affect_malloc_array(nj, 9 * sizeof *rot);
    double *scratch = affect_malloc_array(nj, 12 * sizeof *scratch);
    int32_t *parents = affect_malloc_array(nj, sizeof *parents);
    affect_status st = AFFECT_OK;
    if (!values || !trans || !rot || !scratch || !parents) {
        st = affect_nomem(ps->err);
        goto done;
    }
    for (uint32_t i = 0; i < nj; i++)
        parents[i] = ps->joints[i].parent;
    if (ps->p < ps->end && *ps->p == '\n') { /* end of the Frame Time line */
        ps->p++;
        ps->line++;
    }
    for (uint32_t f = 0; f < m->n_frames; f++) {
        if (f % POLL_FRAMES == 0 && (st = affect_monitor_check(mon, ps->err)))
            goto done;
        if (nv > 0) {
            /* skip blank lines */
            for (;;) {
                const char *q = ps->p;
                while (q < ps->end && is_space(*q))
                    q++;
                if (q < ps->end && *q == '\n') {
                    ps->p = q + 1;
                    ps->line++;
                    continue;
                }
                ps->p = q;
                break;
            }
            if (ps->p >= ps->end) {
                st = affect_fail(ps->err, AFFECT_ERR_FORMAT,
                                 "line %u: expected %u frames, found %u", ps->line, m->n_frames, f);
                goto done;
            }
            uint32_t k = 0;
            while (ps->p < ps->end && *ps->p != '\n') {
                const char *s = ps->p;
                double v;
                const char *after = affect_parse_double(s, ps->end, &v);
                if (!after || (after < ps->end && !is_space(*after) && *after != '\n')) {
                    const char *e = s;
                    while (e < ps->end && !is_space(*e) && *e != '\n')
                        e++;
                    char shown[168];
                    excerpt(s, (size_t)(e - s), shown);
                    st = affect_fail(ps->err, AFFECT_ERR_FORMAT,
                                     "line %u: value %u of frame %u is not a number: %s", ps->line,
                                     k + 1, f, shown);
                    goto done;
                }
                if (k < nv)
                    values[k] = v;
                k++;
                ps->p = after;
                while (ps->p < ps->end && is_space(*ps->p))
                    ps->p++;
            }
            if (k != nv) {
                st =
                    affect_fail(ps->err, AFFECT_ERR_FORMAT,
                                "line %u: frame %u has %u values, expected %u", ps->line, f, k, nv);
                goto done;
            }
            if (ps->p < ps->end) {
                ps->p++;
                ps->line++;
            }
        }
        local_transforms(ps, values, scale, trans, rot);
        affect_fk_frame(nj, parents, trans, rot, scratch, affect_motion_at(m, f, 0));
        keep_rotations(m, f, trans, rot);
    }
    skip_ws(ps);
    if (ps->p < ps->end)
        st = affect_fail(ps->err, AFFECT_ERR_FORMAT,
                         "line %u: more frame lines than the %u declared in Frames:", ps->line,
                         m->n_frames);
done:
    affect_free(values);
    affect_free(trans);
    affect_free(rot);
    affect_free(scratch);
    affect_free(parents);
    return st;
}

/* Frame Time is usually written with six or seven digits (0.0333333 for 30 fps): a rate within
 * 1e-4 relative of a whole number is taken to be that number. */
static double snap_fps(double fps)
{
    double whole = floor(fps + 0.5);
    return whole >= 1 && fabs(fps - whole) <= 1e-4 * fps ? whole : fps;
}

affect_status affect_bvh_parse(const char *text, size_t len, const affect_bvh_options *opt,
                               affect_motion **out, affect_error *err)
{
    double scale = opt && opt->scale != 0 ? opt->scale : 1.0;
    if (!isfinite(scale) || scale <= 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "scale must be a positive number, got %g",
                           scale);
    parser ps = {text, text + len, 1, err, NULL, 0, 0, 0};
    affect_motion *m = NULL;
    affect_status st;
    size_t tlen;
    const char *tok;

    if (len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) /* UTF-8 byte order mark */
        ps.p += 3;
    st = expect_word(&ps, "HIERARCHY");
    if (st)
        goto done;
    tok = next_token(&ps, &tlen);
    if (!token_is(tok, tlen, "ROOT")) {
        st = expected(&ps, "ROOT", tok, tlen);
        goto done;
    }
    for (;;) {
        st = parse_root(&ps);
        if (st)
            goto done;
        tok = next_token(&ps, &tlen);
        if (token_is(tok, tlen, "MOTION"))
            break;
        if (!token_is(tok, tlen, "ROOT")) {
            st = expected(&ps, "ROOT or MOTION", tok, tlen);
            goto done;
        }
    }
    uint32_t n_frames = 0;
    double frame_time = 0;
    st = parse_motion_header(&ps, &n_frames, &frame_time);
    if (st)
        goto done;
    /* refuse impossible counts before allocating for them: a frame line needs at least two
     * bytes per value, and a frame without values (no joint has channels) still its line end
     * (the last line may lack one) */
    uint64_t left = (uint64_t)(ps.end - ps.p); /* after the Frame Time line's end */
    if (left > 0 && *ps.p == '\n')
        left--;
    if (ps.n_values > 0 ? (uint64_t)n_frames * ps.n_values > left / 2 + ps.n_values
                        : n_frames > left + 1) {
        st = affect_fail(err, AFFECT_ERR_FORMAT,
                         "line %u: Frames: %u needs more text than the file has left", ps.line,
                         n_frames);
        goto done;
    }
    uint64_t max_samples = opt && opt->max_samples ? opt->max_samples : AFFECT_MOTION_MAX_SAMPLES;
    if ((uint64_t)n_frames * ps.n_joints > max_samples) {
        st = affect_fail(err, AFFECT_ERR_RANGE,
                         "line %u: %u frames x %u joints is %llu samples, above the limit of %llu "
                         "(option max_samples)",
                         ps.line, n_frames, ps.n_joints, (unsigned long long)n_frames * ps.n_joints,
                         (unsigned long long)max_samples);
        goto done;
    }
    /* every frame line sets all positions, rotations and translations (parse_frames) */
    st = affect_motion_create_as(n_frames, ps.n_joints, snap_fps(1.0 / frame_time), false, &m, err);
    if (st)
        goto done;
    for (uint32_t i = 0; i < ps.n_joints; i++)
        m->parents[i] = ps.joints[i].parent;
    st = name_joints(&ps, m);
    if (!st)
        st = affect_motion_add_skeleton_as(m, true, false, err);
    if (!st)
        keep_skeleton(&ps, m, scale);
    if (!st && opt && opt->unit)
        st = affect_motion_set_unit(m, opt->unit, err);
    if (!st)
        st = parse_frames(&ps, m, scale, opt ? opt->monitor : NULL);
    if (!st)
        st = affect_motion_validate(m, err);
    if (st)
        goto done;
    *out = m;
    m = NULL;
done:
    affect_motion_free(m);
    affect_free(ps.joints);
    return st;
}
