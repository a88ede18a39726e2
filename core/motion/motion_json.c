/*
 * motion_json.c — motions as JSON text (see affect/io.h):
 *
 *     {"fps": 30, "unit": "cm", "joints": ["Hips", "Spine", ...], "parents": [-1, 0, ...],
 *      "frames": [[[x, y, z], ...one per joint], ...one per frame]}
 *
 * "fps", "joints" and "frames" are required; "parents" defaults to all −1 (skeleton unknown)
 * and "unit" to "" (unknown). Any other key is an error. The writer emits exactly this form
 * with no white space, "unit" left out when empty, fps as the shortest decimal that reads back
 * as the same double and coordinates as the shortest decimal that reads back as the same
 * float32, so to_json → from_json reproduces a motion bit for bit.
 *
 * Reading: affect_json_parse (whose "at byte N: …" syntax errors are passed through), then a
 * check of each key in the order fps, unit, joints, parents, frames (the counts of joints and
 * frames, and frames × joints, first, before the motion is allocated; and each frame's joint
 * count too when the text is too short for frames × joints); errors name the JSON path:
 *     expected an object at the top level, found array
 *     "frams": unknown key (expected fps, unit, joints, parents, frames)
 *     "fps": missing key (required: fps, joints, frames)
 *     fps: expected a positive number          fps: 200000 is above the limit of 100000
 *     unit: expected a string                  (other unit errors from affect_motion_set_unit)
 *     joints: expected a non-empty array       joints: 5000 joints (at most 4096)
 *     joints[2]: expected a non-empty string   joints[2]: contains a NUL character
 *     joints[2]: 2000 bytes long (at most 1024)
 *     parents: expected an array of 22 integers, found object
 *     parents: expected 22 integers, found 21
 *     parents[5]: expected an integer from -1 to 21
 *     frames: expected a non-empty array       frames: 20000000 frames (at most 16777216)
 *     frames: 1000000 frames x 22 joints is 22000000 samples, above the limit of 16777216
 *                                                (AFFECT_MOTION_MAX_SAMPLES; no option)
 *     frames[4]: expected an array of 22 joints, found number
 *     frames[4]: expected 22 joints, found 21
 *     frames[12][3]: expected an array of 3 numbers
 *     frames[0][1][2]: 1e+300 does not fit a 32-bit float
 * and finally affect_motion_validate's message (duplicate names, parent cycles). Status:
 * AFFECT_ERR_RANGE for limits (counts, fps, float range), AFFECT_ERR_FORMAT otherwise.
 */
#include "affect/io.h"
#include "util/json.h"
#include "util/strbuf.h"
#include "util/numparse.h"

#include <math.h>
#include <string.h>

#define KEYS_ACCEPTED "fps, unit, joints, parents, frames"
#define KEYS_REQUIRED "fps, joints, frames"

/* v as "%.15g" (or more digits if needed to read back as v), locale-independent, into a
 * buffer of at least 32 bytes: 200000, 1e+300, 0.1. */
static void format_number(char *buf, size_t size, double v)
{
    for (int prec = 15; prec <= 17; prec++) {
        int n = affect_format_g(buf, size, prec, v);
        double back = 0;
        if (affect_parse_double(buf, buf + n, &back) == buf + n && back == v)
            return;
    }
}

/* "array", "number", … for messages. */
static const char *type_name(const affect_json_node *n)
{
    return affect_json_type_name(n->type);
}

typedef struct members {
    const affect_json_node *fps, *unit, *joints, *parents, *frames;
} members;

static affect_status read_members(const affect_json_doc *doc, const affect_json_node *root,
                                  members *mb, affect_error *err)
{
    static const char *const names[5] = {"fps", "unit", "joints", "parents", "frames"};
    const affect_json_node **slots[5] = {&mb->fps, &mb->unit, &mb->joints, &mb->parents,
                                         &mb->frames};
    memset(mb, 0, sizeof *mb);
    for (const affect_json_node *c = affect_json_first(doc, root); c;
         c = affect_json_next_sibling(doc, c)) {
        int k = 0;
        while (k < 5 &&
               !(c->key_len == strlen(names[k]) && memcmp(c->key, names[k], c->key_len) == 0))
            k++;
        if (k == 5) {
            char quoted[48];
            affect_json_quote(quoted, sizeof quoted, c->key, c->key_len);
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "%s: unknown key (expected " KEYS_ACCEPTED ")", quoted);
        }
        *slots[k] = c; /* the JSON reader has rejected duplicate keys */
    }
    const char *missing = !mb->fps ? "fps" : !mb->joints ? "joints" : !mb->frames ? "frames" : NULL;
    if (missing)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "\"%s\": missing key (required: " KEYS_REQUIRED ")", missing);
    return AFFECT_OK;
}

/* Checks fps and the shapes of joints and frames, before anything is allocated. */
static affect_status check_shape(const members *mb, affect_error *err)
{
    char num[40];
    if (mb->fps->type != AFFECT_JSON_NUMBER || !(mb->fps->num > 0))
        return affect_fail(err, AFFECT_ERR_FORMAT, "fps: expected a positive number");
    if (mb->fps->num > AFFECT_MOTION_MAX_FPS) {
        format_number(num, sizeof num, mb->fps->num);
        return affect_fail(err, AFFECT_ERR_RANGE, "fps: %s is above the limit of %u", num,
                           (unsigned)AFFECT_MOTION_MAX_FPS);
    }
    if (mb->unit && mb->unit->type != AFFECT_JSON_STRING)
        return affect_fail(err, AFFECT_ERR_FORMAT, "unit: expected a string");
    if (mb->joints->type != AFFECT_JSON_ARRAY || mb->joints->count == 0)
        return affect_fail(err, AFFECT_ERR_FORMAT, "joints: expected a non-empty array");
    if (mb->joints->count > AFFECT_MOTION_MAX_JOINTS)
        return affect_fail(err, AFFECT_ERR_RANGE, "joints: %u joints (at most %u)",
                           mb->joints->count, AFFECT_MOTION_MAX_JOINTS);
    if (mb->frames->type != AFFECT_JSON_ARRAY || mb->frames->count == 0)
        return affect_fail(err, AFFECT_ERR_FORMAT, "frames: expected a non-empty array");
    if (mb->frames->count > AFFECT_MOTION_MAX_FRAMES)
        return affect_fail(err, AFFECT_ERR_RANGE, "frames: %u frames (at most %u)",
                           mb->frames->count, AFFECT_MOTION_MAX_FRAMES);
    uint64_t samples = (uint64_t)mb->frames->count * mb->joints->count;
    if (samples > AFFECT_MOTION_MAX_SAMPLES)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "frames: %u frames x %u joints is %llu samples, above the limit of %u",
                           mb->frames->count, mb->joints->count, (unsigned long long)samples,
                           AFFECT_MOTION_MAX_SAMPLES);
    return AFFECT_OK;
}

/* Every frame an array of one entry per joint (the first that is not, as an error). */
static affect_status check_frame_counts(const affect_json_doc *doc, const members *mb,
                                        affect_error *err)
{
    uint32_t t = 0, n = mb->joints->count;
    for (const affect_json_node *f = affect_json_first(doc, mb->frames); f;
         f = affect_json_next_sibling(doc, f), t++) {
        if (f->type != AFFECT_JSON_ARRAY)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "frames[%u]: expected an array of %u joints, found %s", t, n,
                               type_name(f));
        if (f->count != n)
            return affect_fail(err, AFFECT_ERR_FORMAT, "frames[%u]: expected %u joints, found %u",
                               t, n, f->count);
    }
    return AFFECT_OK;
}

static affect_status read_unit(affect_motion *m, const affect_json_node *unit, affect_error *err)
{
    if (!unit)
        return AFFECT_OK;
    size_t nul = strlen(unit->str);
    if (nul != unit->str_len)
        return affect_fail(err, AFFECT_ERR_FORMAT, "unit: contains a NUL character");
    return affect_motion_set_unit(m, unit->str, err);
}

static affect_status read_names(const affect_json_doc *doc, affect_motion *m,
                                const affect_json_node *joints, affect_error *err)
{
    uint32_t j = 0;
    for (const affect_json_node *c = affect_json_first(doc, joints); c;
         c = affect_json_next_sibling(doc, c), j++) {
        if (c->type != AFFECT_JSON_STRING || c->str_len == 0)
            return affect_fail(err, AFFECT_ERR_FORMAT, "joints[%u]: expected a non-empty string",
                               j);
        if (memchr(c->str, '\0', c->str_len))
            return affect_fail(err, AFFECT_ERR_FORMAT, "joints[%u]: contains a NUL character", j);
        if (c->str_len > AFFECT_MOTION_MAX_NAME)
            return affect_fail(err, AFFECT_ERR_RANGE, "joints[%u]: %zu bytes long (at most %u)", j,
                               c->str_len, AFFECT_MOTION_MAX_NAME);
        affect_status st = affect_motion_set_name(m, j, c->str, c->str_len, err);
        if (st)
            return st;
    }
    return AFFECT_OK;
}

static affect_status read_parents(const affect_json_doc *doc, affect_motion *m,
                                  const affect_json_node *parents, affect_error *err)
{
    uint32_t n = m->n_joints;
    if (!parents)
        return AFFECT_OK;
    if (parents->type != AFFECT_JSON_ARRAY)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "parents: expected an array of %u integers, found %s", n,
                           type_name(parents));
    if (parents->count != n)
        return affect_fail(err, AFFECT_ERR_FORMAT, "parents: expected %u integers, found %u", n,
                           parents->count);
    uint32_t j = 0;
    for (const affect_json_node *c = affect_json_first(doc, parents); c;
         c = affect_json_next_sibling(doc, c), j++) {
        if (c->type != AFFECT_JSON_NUMBER || !(c->num >= -1.0) || !(c->num <= (double)n - 1) ||
            c->num != floor(c->num))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "parents[%u]: expected an integer from -1 to %u", j, n - 1);
        m->parents[j] = (int32_t)c->num;
    }
    return AFFECT_OK;
}

static affect_status read_frames(const affect_json_doc *doc, affect_motion *m,
                                 const affect_json_node *frames, affect_error *err)
{
    uint32_t t = 0, n = m->n_joints;
    for (const affect_json_node *f = affect_json_first(doc, frames); f;
         f = affect_json_next_sibling(doc, f), t++) {
        if (f->type != AFFECT_JSON_ARRAY)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "frames[%u]: expected an array of %u joints, found %s", t, n,
                               type_name(f));
        if (f->count != n)
            return affect_fail(err, AFFECT_ERR_FORMAT, "frames[%u]: expected %u joints, found %u",
                               t, n, f->count);
        uint32_t j = 0;
        for (const affect_json_node *pt = affect_json_first(doc, f); pt;
             pt = affect_json_next_sibling(doc, pt), j++) {
            const affect_json_node *c = affect_json_first(doc, pt);
            bool ok = pt->type == AFFECT_JSON_ARRAY && pt->count == 3;
            for (const affect_json_node *x = c; ok && x; x = affect_json_next_sibling(doc, x))
                ok = x->type == AFFECT_JSON_NUMBER;
            if (!ok)
                return affect_fail(err, AFFECT_ERR_FORMAT,
                                   "frames[%u][%u]: expected an array of 3 numbers", t, j);
            float *dst = affect_motion_at(m, t, j);
            for (int a = 0; a < 3; a++, c = affect_json_next_sibling(doc, c)) {
                float v = (float)c->num;
                if (isinf(v)) {
                    char num[40];
                    format_number(num, sizeof num, c->num);
                    return affect_fail(err, AFFECT_ERR_RANGE,
                                       "frames[%u][%u][%d]: %s does not fit a 32-bit float", t, j,
                                       a, num);
                }
                dst[a] = v;
            }
        }
    }
    return AFFECT_OK;
}

affect_status affect_motion_from_json(const char *text, size_t len, affect_motion **out,
                                      affect_monitor *mon, affect_error *err)
{
    *out = NULL;
    affect_json_doc *doc = NULL;
    affect_motion *m = NULL;
    affect_status st = affect_json_parse(text, len, &doc, mon, err);
    if (st)
        return st;
    const affect_json_node *root = affect_json_root(doc);
    members mb;
    if (root->type != AFFECT_JSON_OBJECT) {
        st = affect_fail(err, AFFECT_ERR_FORMAT, "expected an object at the top level, found %s",
                         type_name(root));
        goto done;
    }
    st = read_members(doc, root, &mb, err);
    if (!st)
        st = check_shape(&mb, err);
    /* every joint of every frame takes at least a byte of the text: more frames × joints than
     * that means a frame with fewer joints, reported before allocating for the counts (which
     * could ask for far more than the document holds); otherwise in the order of the keys */
    if (!st && (uint64_t)mb.frames->count * mb.joints->count > len)
        st = check_frame_counts(doc, &mb, err);
    if (!st)
        st = affect_motion_create(mb.frames->count, mb.joints->count, mb.fps->num, &m, err);
    if (!st)
        st = read_unit(m, mb.unit, err);
    if (!st)
        st = read_names(doc, m, mb.joints, err);
    if (!st)
        st = read_parents(doc, m, mb.parents, err);
    if (!st)
        st = read_frames(doc, m, mb.frames, err);
    if (!st)
        st = affect_motion_validate(m, err);
    if (!st) {
        *out = m;
        m = NULL;
    }
done:
    affect_motion_free(m);
    affect_json_free(doc);
    return st;
}

/* The writer polls the monitor every this many frames. */
#define POLL_FRAMES 1024

affect_status affect_motion_to_json(const affect_motion *m, char **out, size_t *len,
                                    affect_monitor *mon, affect_error *err)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"fps\":");
    affect_strbuf_double(&sb, m->fps);
    if (m->unit[0]) {
        affect_strbuf_puts(&sb, ",\"unit\":");
        affect_strbuf_json_string(&sb, m->unit);
    }
    affect_strbuf_puts(&sb, ",\"joints\":[");
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (j)
            affect_strbuf_putc(&sb, ',');
        affect_strbuf_json_string(&sb, m->names[j]);
    }
    affect_strbuf_puts(&sb, "],\"parents\":[");
    for (uint32_t j = 0; j < m->n_joints; j++) {
        if (j)
            affect_strbuf_putc(&sb, ',');
        affect_strbuf_int(&sb, m->parents[j]);
    }
    affect_strbuf_puts(&sb, "],\"frames\":[");
    for (uint32_t t = 0; t < m->n_frames && !sb.failed; t++) {
        if (t % POLL_FRAMES == 0 && affect_monitor_stopped(mon)) {
            affect_strbuf_free(&sb);
            return affect_monitor_check(mon, err);
        }
        affect_strbuf_puts(&sb, t ? ",[" : "[");
        const float *p = affect_motion_at(m, t, 0);
        for (uint32_t j = 0; j < m->n_joints; j++, p += 3) {
            affect_strbuf_puts(&sb, j ? ",[" : "[");
            affect_strbuf_float(&sb, p[0]);
            affect_strbuf_putc(&sb, ',');
            affect_strbuf_float(&sb, p[1]);
            affect_strbuf_putc(&sb, ',');
            affect_strbuf_float(&sb, p[2]);
            affect_strbuf_putc(&sb, ']');
        }
        affect_strbuf_putc(&sb, ']');
    }
    affect_strbuf_puts(&sb, "]}");
    return affect_strbuf_finish(&sb, out, len, err);
}
