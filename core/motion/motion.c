/*
 * motion.c — the motion model, its BLOB encoding and the editing operations
 * (see affect/motion.h and docs/FORMATS.md).
 *
 * BLOB layout, version 1 (all integers and floats little-endian):
 *   0  4  magic "AFMO"
 *   4  2  format version (1)
 *   6  2  flags (0; reserved)
 *   8  4  frame count T (1 .. 2^24)
 *  12  4  joint count J (1 .. 4096)
 *  16  8  frames per second (float64, finite, 0 < fps ≤ 100000)
 *  24  1  unit length U (0 .. 15)
 *  25  7  reserved, zero
 *  32  U  unit (ASCII [A-Za-z0-9_.-])
 *      then J × { 2-byte name length L (1 .. 1024), L bytes of UTF-8 name }
 *      then J × int32 parent index (−1 or 0 .. J−1, acyclic)
 *      then T × J × 3 float32 positions, frame-major
 * Version 2 is the same with flags (bit 0 skeleton, always set; bit 1 rotations) and,
 * after the positions:
 *      skeleton (bit 0): J × 32 bytes { 3 float64 rest offset, 1 channel count (0 .. 6),
 *                        6 channel types (AFFECT_CH_*, the first count distinct, the rest
 *                        zero), 1 joint flags (bit 0 End Site: a leaf without channels) }
 *      rotations (bit 1): T × J × 4 float32 unit quaternions (w, x, y, z), frame-major, then
 *                        T × K × 3 float32 local translations of the K joints that have a
 *                        position channel (in joint order), frame-major
 * The encoder writes version 1 for a motion without a skeleton (unchanged bytes) and version 2
 * otherwise. The decoder checks these in order: length ≥ header, magic, version, flags, sizes,
 * each name's length against the remaining bytes, the exact total length, names (no NUL,
 * valid UTF-8: no overlongs, surrogates or code points above U+10FFFF), unique names, parents,
 * finiteness, then the skeleton's channels and End Sites, offsets, quaternion norms
 * (within AFFECT_MOTION_QUAT_NORM_TOL of 1) and translations.
 */
#include "affect/motion.h"
#include "util/bytes.h"
#include "affect/quat.h"
#include "affect/skeleton.h"
#include "util/internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static double u64_to_double(uint64_t u)
{
    double d;
    memcpy(&d, &u, sizeof d);
    return d;
}

static uint64_t double_to_u64(double d)
{
    uint64_t u;
    memcpy(&u, &d, sizeof u);
    return u;
}

static bool host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

/* ---- construction ---- */

static affect_status check_sizes(uint32_t n_frames, uint32_t n_joints, double fps,
                                 affect_error *err)
{
    if (n_frames < 1 || n_frames > AFFECT_MOTION_MAX_FRAMES)
        return affect_fail(err, AFFECT_ERR_RANGE, "frame count %u out of range (1 .. %u)", n_frames,
                           AFFECT_MOTION_MAX_FRAMES);
    if (n_joints < 1 || n_joints > AFFECT_MOTION_MAX_JOINTS)
        return affect_fail(err, AFFECT_ERR_RANGE, "joint count %u out of range (1 .. %u)", n_joints,
                           AFFECT_MOTION_MAX_JOINTS);
    if (!(fps > 0.0) || !(fps <= AFFECT_MOTION_MAX_FPS))
        return affect_fail(err, AFFECT_ERR_RANGE, "frames per second %g out of range (0 .. %g]",
                           fps, AFFECT_MOTION_MAX_FPS);
    return AFFECT_OK;
}

/* affect_motion_create, with the positions left unset when zero is false (the caller writes
 * every sample: see affect_motion_add_skeleton_as). */
affect_status affect_motion_create_as(uint32_t n_frames, uint32_t n_joints, double fps, bool zero,
                                      affect_motion **out, affect_error *err)
{
    affect_status st = check_sizes(n_frames, n_joints, fps, err);
    if (st)
        return st;
    size_t n_pos;
    if (!affect_mul_size((size_t)n_frames * n_joints, 3, &n_pos))
        return affect_fail(err, AFFECT_ERR_RANGE, "motion too large");
    affect_motion *m = affect_calloc(1, sizeof *m);
    if (!m)
        return affect_nomem(err);
    m->n_frames = n_frames;
    m->n_joints = n_joints;
    m->fps = fps;
    m->names = affect_calloc(n_joints, sizeof *m->names);
    m->parents = affect_malloc_array(n_joints, sizeof *m->parents);
    m->pos =
        zero ? affect_calloc(n_pos, sizeof *m->pos) : affect_malloc_array(n_pos, sizeof *m->pos);
    if (!m->names || !m->parents)
        goto nomem;
    if (!m->pos) {
        affect_motion_free(m);
        return affect_nomem_of(err, n_pos, sizeof *m->pos, "the positions of %u frames x %u joints",
                               n_frames, n_joints);
    }
    for (uint32_t j = 0; j < n_joints; j++) {
        char name[16];
        int len = snprintf(name, sizeof name, "j%u", j);
        m->parents[j] = -1;
        m->names[j] = affect_strndup(name, (size_t)len);
        if (!m->names[j])
            goto nomem;
    }
    *out = m;
    return AFFECT_OK;
nomem:
    affect_motion_free(m);
    return affect_nomem(err);
}

affect_status affect_motion_create(uint32_t n_frames, uint32_t n_joints, double fps,
                                   affect_motion **out, affect_error *err)
{
    return affect_motion_create_as(n_frames, n_joints, fps, true, out, err);
}

void affect_motion_free(affect_motion *m)
{
    if (!m)
        return;
    if (m->names)
        for (uint32_t j = 0; j < m->n_joints; j++)
            affect_free(m->names[j]);
    affect_free(m->names);
    affect_free(m->parents);
    affect_free(m->pos);
    affect_motion_drop_skeleton(m);
    affect_free(m);
}

void affect_motion_drop_skeleton(affect_motion *m)
{
    affect_free(m->skel);
    affect_free(m->rot);
    affect_free(m->trans);
    m->skel = NULL;
    m->rot = NULL;
    m->trans = NULL;
}

bool affect_skel_has_position(const affect_skel_joint *j)
{
    for (int c = 0; c < j->n_channels; c++)
        if (j->channel[c] <= AFFECT_CH_ZPOS)
            return true;
    return false;
}

/* affect_motion_add_skeleton, with the rotations and translations left unset when fill is false
 * (the caller writes every frame's: the BVH parser, whose frames then touch the memory as it
 * polls, instead of filling hundreds of megabytes before its first poll). */
affect_status affect_motion_add_skeleton_as(affect_motion *m, bool rotations, bool fill,
                                            affect_error *err)
{
    affect_motion_drop_skeleton(m);
    size_t n = (size_t)m->n_frames * m->n_joints; /* ≤ 2^36: no overflow below */
    m->skel = affect_calloc(m->n_joints, sizeof *m->skel);
    if (!m->skel)
        return affect_nomem(err);
    if (!rotations)
        return AFFECT_OK;
    m->rot = affect_malloc_array(n, 4 * sizeof *m->rot);
    m->trans = fill ? affect_calloc(n, 3 * sizeof *m->trans)
                    : affect_malloc_array(n, 3 * sizeof *m->trans);
    if (!m->rot || !m->trans) {
        bool rot = !m->rot;
        affect_motion_drop_skeleton(m);
        return affect_nomem_of(err, n, (rot ? 4 : 3) * sizeof(float),
                               "the %s of %u frames x %u joints",
                               rot ? "rotations" : "translations", m->n_frames, m->n_joints);
    }
    for (size_t i = 0; fill && i < n; i++) {
        float *q = m->rot + i * 4;
        q[0] = 1, q[1] = q[2] = q[3] = 0;
    }
    return AFFECT_OK;
}

affect_status affect_motion_add_skeleton(affect_motion *m, bool rotations, affect_error *err)
{
    return affect_motion_add_skeleton_as(m, rotations, true, err);
}

affect_status affect_motion_set_name(affect_motion *m, uint32_t j, const char *name, size_t len,
                                     affect_error *err)
{
    if (j >= m->n_joints)
        return affect_fail(err, AFFECT_ERR_RANGE, "joint %u out of range", j);
    if (len == 0 || len > AFFECT_MOTION_MAX_NAME)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "joint %u: name length %zu out of range (1 .. %u)", j, len,
                           AFFECT_MOTION_MAX_NAME);
    if (memchr(name, '\0', len))
        return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u: name contains a NUL byte", j);
    affect_status st = affect_utf8_check(err, AFFECT_ERR_FORMAT, name, len, "joint %u: name", j);
    if (st)
        return st;
    char *copy = affect_strndup(name, len);
    if (!copy)
        return affect_nomem(err);
    affect_free(m->names[j]);
    m->names[j] = copy;
    return AFFECT_OK;
}

static bool unit_char_ok(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '.' || c == '-';
}

static affect_status check_unit(const char *unit, size_t len, affect_error *err)
{
    if (len > AFFECT_MOTION_UNIT_MAX)
        return affect_fail(err, AFFECT_ERR_FORMAT, "unit is %zu bytes long (at most %u)", len,
                           AFFECT_MOTION_UNIT_MAX);
    for (size_t i = 0; i < len; i++)
        if (!unit_char_ok(unit[i]))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "unit has a character other than letters, digits, '_', '.', '-' "
                               "(byte %zu)",
                               i);
    return AFFECT_OK;
}

affect_status affect_motion_set_unit(affect_motion *m, const char *unit, affect_error *err)
{
    size_t len = unit ? strlen(unit) : 0;
    affect_status st = check_unit(unit, len, err);
    if (st)
        return st;
    if (len)
        memcpy(m->unit, unit, len);
    m->unit[len] = '\0';
    return AFFECT_OK;
}

static affect_status check_names_unique(const affect_motion *m, affect_error *err)
{
    uint32_t n = m->n_joints, cap = 16;
    while (cap < 2 * n)
        cap *= 2;
    int32_t *slots = affect_malloc_array(cap, sizeof *slots);
    if (!slots)
        return affect_nomem(err);
    for (uint32_t i = 0; i < cap; i++)
        slots[i] = -1;
    affect_status st = AFFECT_OK;
    for (uint32_t j = 0; j < n && !st; j++) {
        uint32_t h = affect_hash_name(m->names[j]) & (cap - 1);
        while (slots[h] >= 0) {
            if (strcmp(m->names[slots[h]], m->names[j]) == 0) {
                st = affect_fail(err, AFFECT_ERR_FORMAT,
                                 "joints %d and %u have the same name \"%.64s\"", slots[h], j,
                                 m->names[j]);
                break;
            }
            h = (h + 1) & (cap - 1);
        }
        if (!st)
            slots[h] = (int32_t)j;
    }
    affect_free(slots);
    return st;
}

static affect_status check_parents(const affect_motion *m, affect_error *err)
{
    uint32_t n = m->n_joints;
    for (uint32_t j = 0; j < n; j++) {
        int32_t p = m->parents[j];
        if (p < -1 || p >= (int32_t)n)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "joint %u: parent index %d out of range (-1 .. %u)", j, p, n - 1);
        if (p == (int32_t)j)
            return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u: is its own parent", j);
    }
    /* acyclic: walking up from any joint reaches a root within n steps */
    for (uint32_t j = 0; j < n; j++) {
        int32_t p = m->parents[j];
        uint32_t steps = 0;
        while (p >= 0 && steps <= n) {
            p = m->parents[p];
            steps++;
        }
        if (p >= 0)
            return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u: parent indices form a cycle", j);
    }
    return AFFECT_OK;
}

affect_status affect_motion_set_parents(affect_motion *m, const int32_t *parents, affect_error *err)
{
    int32_t *old = m->parents;
    affect_motion probe = *m;
    probe.parents = (int32_t *)parents;
    affect_status st = check_parents(&probe, err);
    if (st)
        return st;
    memcpy(old, parents, (size_t)m->n_joints * sizeof *old);
    affect_motion_drop_skeleton(m);
    return AFFECT_OK;
}

/* True when a block of floats holds an infinity or NaN: the exponent bits all set. Written
 * without branches or early exits so the compiler vectorizes it (decode spends most of its
 * time here). */
static bool block_has_nonfinite(const float *v, size_t n)
{
    uint32_t bad = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t u;
        memcpy(&u, &v[i], sizeof u);
        bad |= (uint32_t)((u & 0x7f800000u) == 0x7f800000u);
    }
    return bad != 0;
}

static affect_status check_finite(const affect_motion *m, affect_error *err)
{
    size_t n = (size_t)m->n_frames * m->n_joints * 3, block = 4096;
    size_t start = 0;
    while (start < n && !block_has_nonfinite(m->pos + start, n - start < block ? n - start : block))
        start += block;
    for (size_t i = start; i < n; i++) {
        if (!isfinite(m->pos[i])) {
            size_t fj = i / 3;
            static const char axes[] = "xyz";
            return affect_fail(
                err, AFFECT_ERR_FORMAT, "non-finite coordinate at frame %zu, joint %zu (%.64s), %c",
                fj / m->n_joints, fj % m->n_joints, m->names[fj % m->n_joints], axes[i % 3]);
        }
    }
    return AFFECT_OK;
}

static const char *const channel_names[AFFECT_CH_COUNT] = {"Xposition", "Yposition", "Zposition",
                                                           "Xrotation", "Yrotation", "Zrotation"};

/* One joint of check_skeleton. */
static affect_status check_skeleton_joint(const affect_motion *m, uint32_t j, bool has_child,
                                          affect_error *err)
{
    const affect_skel_joint *s = &m->skel[j];
    if (s->n_channels > 6)
        return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u (%.64s): %u channels (at most 6)", j,
                           m->names[j], s->n_channels);
    unsigned seen = 0;
    for (int c = 0; c < s->n_channels; c++) {
        if (s->channel[c] >= AFFECT_CH_COUNT)
            return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u (%.64s): channel type %u unknown",
                               j, m->names[j], s->channel[c]);
        if (seen & (1u << s->channel[c]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u (%.64s): channel %s listed twice",
                               j, m->names[j], channel_names[s->channel[c]]);
        seen |= 1u << s->channel[c];
    }
    if (s->flags & ~AFFECT_JOINT_END_SITE)
        return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u (%.64s): unknown joint flags 0x%02x",
                           j, m->names[j], s->flags);
    if (s->flags & AFFECT_JOINT_END_SITE) {
        if (s->n_channels || m->parents[j] < 0)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "joint %u (%.64s): an End Site must have a parent and no channels",
                               j, m->names[j]);
        if (has_child)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "joint %u (%.64s): an End Site cannot have children", j,
                               m->names[j]);
    }
    for (int a = 0; a < 3; a++)
        if (!isfinite(s->offset[a]))
            return affect_fail(err, AFFECT_ERR_FORMAT, "joint %u (%.64s): non-finite offset", j,
                               m->names[j]);
    return AFFECT_OK;
}

/* Channels in range and distinct, End Sites leaves without channels, offsets finite. */
static affect_status check_skeleton(const affect_motion *m, affect_error *err)
{
    bool *has_child = affect_calloc(m->n_joints, sizeof *has_child);
    if (!has_child)
        return affect_nomem(err);
    for (uint32_t j = 0; j < m->n_joints; j++)
        if (m->parents[j] >= 0)
            has_child[m->parents[j]] = true;
    affect_status st = AFFECT_OK;
    for (uint32_t j = 0; j < m->n_joints && !st; j++)
        st = check_skeleton_joint(m, j, has_child[j], err);
    affect_free(has_child);
    return st;
}

/* The first rotation or translation that is not finite, or the first quaternion whose norm
 * is not within AFFECT_MOTION_QUAT_NORM_TOL of 1, as an error (the slow path of
 * check_rotations). */
static affect_status report_rotation(const affect_motion *m, affect_error *err)
{
    size_t n = (size_t)m->n_frames * m->n_joints;
    for (size_t i = 0; i < n; i++) {
        size_t t = i / m->n_joints, j = i % m->n_joints;
        for (int a = 0; a < 7; a++)
            if (!isfinite(a < 4 ? m->rot[i * 4 + a] : m->trans[i * 3 + a - 4]))
                return affect_fail(err, AFFECT_ERR_FORMAT,
                                   "non-finite %s at frame %zu, joint %zu (%.64s)",
                                   a < 4 ? "rotation" : "translation", t, j, m->names[j]);
        const float *q = m->rot + i * 4;
        double norm = sqrt((double)q[0] * q[0] + (double)q[1] * q[1] + (double)q[2] * q[2] +
                           (double)q[3] * q[3]);
        if (!(fabs(norm - 1) <= AFFECT_MOTION_QUAT_NORM_TOL))
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "rotation at frame %zu, joint %zu (%.64s) is not a unit quaternion "
                               "(norm %g)",
                               t, j, m->names[j], norm);
    }
    return AFFECT_OK;
}

/* Unit quaternions and finite translations. The fast pass is branch-free so it vectorises
 * (decode spends most of its time here): squared norms in float against the squared bounds
 * (a NaN or infinity fails both comparisons, so it also checks finiteness; float's 1e-7 is far
 * inside the 1e-3 tolerance), and the translations' exponent bits. */
static affect_status check_rotations(const affect_motion *m, affect_error *err)
{
    size_t n = (size_t)m->n_frames * m->n_joints;
    const float lo = (float)((1 - AFFECT_MOTION_QUAT_NORM_TOL) * (1 - AFFECT_MOTION_QUAT_NORM_TOL));
    const float hi = (float)((1 + AFFECT_MOTION_QUAT_NORM_TOL) * (1 + AFFECT_MOTION_QUAT_NORM_TOL));
    unsigned bad = 0;
    const float *q = m->rot;
    for (size_t i = 0; i < n; i++, q += 4) {
        float n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
        bad |= (unsigned)(n2 < lo) | (unsigned)(n2 > hi) | (unsigned)(n2 != n2);
    }
    if (bad || block_has_nonfinite(m->trans, n * 3))
        return report_rotation(m, err);
    return AFFECT_OK;
}

/* Every name 1 .. AFFECT_MOTION_MAX_NAME bytes of valid UTF-8 (the names of a motion built
 * through this API always are; a caller may have written m->names itself). */
static affect_status check_names(const affect_motion *m, affect_status status, affect_error *err)
{
    for (uint32_t j = 0; j < m->n_joints; j++) {
        size_t len = m->names[j] ? strlen(m->names[j]) : 0;
        if (len == 0 || len > AFFECT_MOTION_MAX_NAME)
            return affect_fail(err, status, "joint %u: name length %zu out of range (1 .. %u)", j,
                               len, AFFECT_MOTION_MAX_NAME);
        affect_status st = affect_utf8_check(err, status, m->names[j], len, "joint %u: name", j);
        if (st)
            return st;
    }
    return AFFECT_OK;
}

affect_status affect_motion_validate(const affect_motion *m, affect_error *err)
{
    affect_status st = check_sizes(m->n_frames, m->n_joints, m->fps, err);
    if (st)
        return st;
    st = check_unit(m->unit, strlen(m->unit), err);
    if (st)
        return st;
    st = check_names(m, AFFECT_ERR_FORMAT, err);
    if (st)
        return st;
    st = check_names_unique(m, err);
    if (st)
        return st;
    st = check_parents(m, err);
    if (st)
        return st;
    st = check_finite(m, err);
    if (st)
        return st;
    if ((m->rot || m->trans) && !(m->rot && m->trans && m->skel))
        return affect_fail(err, AFFECT_ERR_INVALID, "rotations without a skeleton or translations");
    if (m->skel)
        st = check_skeleton(m, err);
    if (!st && m->rot)
        st = check_rotations(m, err);
    return st;
}

/* Copies m's skeleton and the rotations of frames first .. first + c->n_frames − 1 into c. */
static affect_status copy_skeleton(const affect_motion *m, uint32_t first, affect_motion *c,
                                   affect_error *err)
{
    if (!m->skel)
        return AFFECT_OK;
    affect_status st = affect_motion_add_skeleton(c, m->rot != NULL, err);
    if (st)
        return st;
    memcpy(c->skel, m->skel, (size_t)m->n_joints * sizeof *c->skel);
    if (m->rot) {
        size_t per = m->n_joints, n = (size_t)c->n_frames * per;
        memcpy(c->rot, m->rot + (size_t)first * per * 4, n * 4 * sizeof *c->rot);
        memcpy(c->trans, m->trans + (size_t)first * per * 3, n * 3 * sizeof *c->trans);
    }
    return AFFECT_OK;
}

affect_status affect_motion_clone(const affect_motion *m, affect_motion **out, affect_error *err)
{
    affect_motion *c = NULL;
    affect_status st = affect_motion_create(m->n_frames, m->n_joints, m->fps, &c, err);
    if (st)
        return st;
    memcpy(c->unit, m->unit, sizeof c->unit);
    for (uint32_t j = 0; j < m->n_joints; j++) {
        st = affect_motion_set_name(c, j, m->names[j], strlen(m->names[j]), err);
        if (st) {
            affect_motion_free(c);
            return st;
        }
    }
    memcpy(c->parents, m->parents, (size_t)m->n_joints * sizeof *c->parents);
    memcpy(c->pos, m->pos, (size_t)m->n_frames * m->n_joints * 3 * sizeof *c->pos);
    st = copy_skeleton(m, 0, c, err);
    if (st) {
        affect_motion_free(c);
        return st;
    }
    *out = c;
    return AFFECT_OK;
}

int32_t affect_motion_find_joint(const affect_motion *m, const char *name)
{
    for (uint32_t j = 0; j < m->n_joints; j++)
        if (strcmp(m->names[j], name) == 0)
            return (int32_t)j;
    return -1;
}

double affect_motion_duration(const affect_motion *m)
{
    return (double)m->n_frames / m->fps;
}

void affect_motion_bbox(const affect_motion *m, float min[3], float max[3])
{
    for (int a = 0; a < 3; a++) {
        min[a] = m->pos[a];
        max[a] = m->pos[a];
    }
    size_t n = (size_t)m->n_frames * m->n_joints;
    for (size_t i = 0; i < n; i++)
        for (int a = 0; a < 3; a++) {
            float v = m->pos[i * 3 + a];
            if (v < min[a])
                min[a] = v;
            if (v > max[a])
                max[a] = v;
        }
}

/* ---- BLOB ---- */

/* Number of joints with a position channel (their translations are stored per frame). */
static uint32_t count_translated(const affect_motion *m)
{
    uint32_t k = 0;
    for (uint32_t j = 0; j < m->n_joints; j++)
        k += affect_skel_has_position(&m->skel[j]);
    return k;
}

bool affect_motion_encoded_size(const affect_motion *m, size_t *size)
{
    size_t total = AFFECT_MOTION_HEADER_SIZE + strlen(m->unit), n;
    if (check_names(m, AFFECT_ERR_INVALID, NULL))
        return false; /* a name the decoder would refuse */
    for (uint32_t j = 0; j < m->n_joints; j++)
        if (!affect_add_size(total, 2 + strlen(m->names[j]), &total))
            return false;
    if (!affect_add_size(total, (size_t)m->n_joints * 4, &total))
        return false;
    if (!affect_mul_size((size_t)m->n_frames * m->n_joints, 12, &n) ||
        !affect_add_size(total, n, &total))
        return false;
    if (m->skel && !affect_add_size(total, (size_t)m->n_joints * AFFECT_MOTION_JOINT_SIZE, &total))
        return false;
    if (m->skel && m->rot) {
        size_t per = (size_t)m->n_joints * 16 + (size_t)count_translated(m) * 12;
        if (!affect_mul_size(m->n_frames, per, &n) || !affect_add_size(total, n, &total))
            return false;
    }
    *size = total;
    return true;
}

/* n floats little-endian at p; returns the end. */
static unsigned char *put_floats(unsigned char *p, const float *v, size_t n)
{
    if (host_is_little_endian()) {
        memcpy(p, v, n * 4);
        return p + n * 4;
    }
    for (size_t i = 0; i < n; i++, p += 4) {
        uint32_t u;
        memcpy(&u, &v[i], 4);
        affect_put_u32(p, u);
    }
    return p;
}

/* n little-endian floats at p into v. */
static void get_floats(const unsigned char *p, float *v, size_t n)
{
    if (host_is_little_endian()) {
        memcpy(v, p, n * 4);
        return;
    }
    for (size_t i = 0; i < n; i++, p += 4) {
        uint32_t u = affect_get_u32(p);
        memcpy(&v[i], &u, 4);
    }
}

/* decoding polls the monitor after every this many values copied (4 MB) */
#define DECODE_POLL_VALUES ((size_t)1 << 20)

/* get_floats in slices, polling mon between them. */
static affect_status get_floats_polled(const unsigned char *p, float *v, size_t n,
                                       affect_monitor *mon, affect_error *err)
{
    for (size_t done = 0; done < n; done += DECODE_POLL_VALUES) {
        size_t k = n - done < DECODE_POLL_VALUES ? n - done : DECODE_POLL_VALUES;
        get_floats(p + done * 4, v + done, k);
        affect_status st = affect_monitor_check(mon, err);
        if (st)
            return st;
    }
    return AFFECT_OK;
}

void affect_motion_encode_into(const affect_motion *m, unsigned char *buf)
{
    unsigned char *p = buf;
    size_t unit_len = strlen(m->unit);
    unsigned flags =
        m->skel ? AFFECT_MOTION_FLAG_SKELETON | (m->rot ? AFFECT_MOTION_FLAG_ROTATIONS : 0) : 0;
    memcpy(p, AFFECT_MOTION_MAGIC, 4);
    affect_put_u16(p + 4, flags ? 2 : 1);
    affect_put_u16(p + 6, (uint16_t)flags);
    affect_put_u32(p + 8, m->n_frames);
    affect_put_u32(p + 12, m->n_joints);
    affect_put_u64(p + 16, double_to_u64(m->fps));
    p[24] = (unsigned char)unit_len;
    memset(p + 25, 0, 7);
    p += AFFECT_MOTION_HEADER_SIZE;
    memcpy(p, m->unit, unit_len);
    p += unit_len;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        size_t len = strlen(m->names[j]);
        affect_put_u16(p, (uint16_t)len);
        memcpy(p + 2, m->names[j], len);
        p += 2 + len;
    }
    for (uint32_t j = 0; j < m->n_joints; j++, p += 4)
        affect_put_u32(p, (uint32_t)m->parents[j]);
    size_t nj = m->n_joints, n = (size_t)m->n_frames * nj;
    p = put_floats(p, m->pos, n * 3);
    if (!m->skel)
        return;
    for (uint32_t j = 0; j < nj; j++, p += AFFECT_MOTION_JOINT_SIZE) {
        const affect_skel_joint *s = &m->skel[j];
        for (int a = 0; a < 3; a++)
            affect_put_u64(p + 8 * a, double_to_u64(s->offset[a]));
        p[24] = s->n_channels;
        for (int c = 0; c < 6; c++)
            p[25 + c] = c < s->n_channels ? s->channel[c] : 0;
        p[31] = s->flags;
    }
    if (!m->rot)
        return;
    p = put_floats(p, m->rot, n * 4);
    for (uint32_t t = 0; t < m->n_frames; t++)
        for (uint32_t j = 0; j < nj; j++)
            if (affect_skel_has_position(&m->skel[j]))
                p = put_floats(p, m->trans + ((size_t)t * nj + j) * 3, 3);
}

affect_status affect_motion_encode(const affect_motion *m, unsigned char **out, size_t *size,
                                   affect_error *err)
{
    size_t n;
    affect_status st = check_names(m, AFFECT_ERR_INVALID, err);
    if (st)
        return affect_prefix(err, "cannot encode the motion");
    if (!affect_motion_encoded_size(m, &n))
        return affect_fail(err, AFFECT_ERR_RANGE, "motion too large to encode");
    unsigned char *buf = affect_malloc(n);
    if (!buf)
        return affect_nomem(err);
    affect_motion_encode_into(m, buf);
    *out = buf;
    *size = n;
    return AFFECT_OK;
}

affect_status affect_motion_decode(const unsigned char *data, size_t size, affect_motion **out,
                                   affect_error *err)
{
    return affect_motion_decode_monitored(data, size, NULL, out, err);
}

affect_status affect_motion_decode_monitored(const unsigned char *data, size_t size,
                                             affect_monitor *mon, affect_motion **out,
                                             affect_error *err)
{
    if (size < AFFECT_MOTION_HEADER_SIZE)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated: %zu bytes is shorter than the %u-byte header", size,
                           AFFECT_MOTION_HEADER_SIZE);
    if (affect_check_magic(data, AFFECT_MOTION_MAGIC, NULL, "a motion", 0, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    uint16_t version = affect_get_u16(data + 4);
    if (affect_check_version(version, AFFECT_MOTION_VERSION, NULL, err) != AFFECT_OK)
        return AFFECT_ERR_FORMAT;
    uint16_t flags = affect_get_u16(data + 6);
    /* version 2 exists for the skeleton: without it the encoder writes version 1 */
    if (version == 1 ? flags != 0
                     : (flags & ~(AFFECT_MOTION_FLAG_SKELETON | AFFECT_MOTION_FLAG_ROTATIONS)) ||
                           !(flags & AFFECT_MOTION_FLAG_SKELETON))
        return affect_fail(err, AFFECT_ERR_FORMAT, "unknown flags 0x%04x (offset 6)", flags);
    uint32_t n_frames = affect_get_u32(data + 8), n_joints = affect_get_u32(data + 12);
    double fps = u64_to_double(affect_get_u64(data + 16));
    affect_error size_err;
    if (check_sizes(n_frames, n_joints, fps, &size_err))
        return affect_fail(err, AFFECT_ERR_FORMAT, "%s (header)", size_err.msg);
    affect_status st;
    size_t unit_len = data[24];
    for (int i = 25; i < 32; i++)
        if (data[i] != 0)
            return affect_fail(err, AFFECT_ERR_FORMAT, "reserved header byte %d is not zero", i);
    size_t off = AFFECT_MOTION_HEADER_SIZE;
    if (unit_len > AFFECT_MOTION_UNIT_MAX || size - off < unit_len)
        return affect_fail(err, AFFECT_ERR_FORMAT,
                           "truncated or bad unit (length %zu at offset 24)", unit_len);
    st = check_unit((const char *)data + off, unit_len, err);
    if (st)
        return st;
    size_t unit_off = off;
    off += unit_len;

    /* walk the name table to find where the parents start, checking each length */
    size_t names_off = off;
    for (uint32_t j = 0; j < n_joints; j++) {
        if (size - off < 2)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "truncated in the name of joint %u (offset %zu)", j, off);
        size_t len = affect_get_u16(data + off);
        if (len == 0 || len > AFFECT_MOTION_MAX_NAME)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "joint %u: name length %zu out of range (1 .. %u) at offset %zu", j,
                               len, AFFECT_MOTION_MAX_NAME, off);
        if (size - off - 2 < len)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "truncated in the name of joint %u (offset %zu)", j, off);
        off += 2 + len;
    }
    size_t n_vals = (size_t)n_frames * n_joints * 3; /* ≤ 2^24 · 2^12 · 3: no overflow */
    size_t expect = off + (size_t)n_joints * 4 + n_vals * 4;
    size_t skel_off = expect, n_translated = 0;
    if (flags & AFFECT_MOTION_FLAG_SKELETON) {
        if (size < skel_off || size - skel_off < (size_t)n_joints * AFFECT_MOTION_JOINT_SIZE)
            return affect_fail(err, AFFECT_ERR_FORMAT,
                               "truncated: %zu bytes, the skeleton part needs %zu from offset %zu",
                               size, (size_t)n_joints * AFFECT_MOTION_JOINT_SIZE, skel_off);
        for (uint32_t j = 0; j < n_joints; j++) {
            const unsigned char *q = data + skel_off + (size_t)j * AFFECT_MOTION_JOINT_SIZE;
            bool pos = false;
            for (int c = 0; c < q[24] && c < 6; c++)
                pos |= q[25 + c] <= AFFECT_CH_ZPOS;
            n_translated += pos;
        }
        expect += (size_t)n_joints * AFFECT_MOTION_JOINT_SIZE;
        if (flags & AFFECT_MOTION_FLAG_ROTATIONS) /* ≤ 2^36 · 28 bytes: no overflow */
            expect += (size_t)n_frames * ((size_t)n_joints * 16 + n_translated * 12);
    }
    if (size != expect)
        return affect_fail(
            err, AFFECT_ERR_FORMAT, "%s: %zu bytes, expected %zu for %u frames x %u joints",
            size < expect ? "truncated" : "trailing bytes", size, expect, n_frames, n_joints);

    /* positions, rotations and translations are all read below: not cleared first, so that the
     * memory is first touched between polls */
    affect_motion *m = NULL;
    st = affect_motion_create_as(n_frames, n_joints, fps, false, &m, err);
    if (st)
        return st;
    memcpy(m->unit, data + unit_off, unit_len);
    m->unit[unit_len] = '\0';
    off = names_off;
    for (uint32_t j = 0; j < n_joints; j++) {
        size_t len = affect_get_u16(data + off);
        st = affect_motion_set_name(m, j, (const char *)data + off + 2, len, err);
        if (st)
            goto fail;
        off += 2 + len;
    }
    for (uint32_t j = 0; j < n_joints; j++, off += 4)
        m->parents[j] = (int32_t)affect_get_u32(data + off);
    if ((st = get_floats_polled(data + off, m->pos, n_vals, mon, err)))
        goto fail;
    off += n_vals * 4;
    if (flags & AFFECT_MOTION_FLAG_SKELETON) {
        st = affect_motion_add_skeleton_as(m, (flags & AFFECT_MOTION_FLAG_ROTATIONS) != 0, false,
                                           err);
        if (st)
            goto fail;
        for (uint32_t j = 0; j < n_joints; j++, off += AFFECT_MOTION_JOINT_SIZE) {
            affect_skel_joint *s = &m->skel[j];
            for (int a = 0; a < 3; a++)
                s->offset[a] = u64_to_double(affect_get_u64(data + off + 8 * a));
            s->n_channels = data[off + 24];
            for (int c = 0; c < 6; c++) {
                s->channel[c] = data[off + 25 + c];
                if (c >= s->n_channels && s->channel[c] != 0) {
                    st = affect_fail(err, AFFECT_ERR_FORMAT,
                                     "joint %u: unused channel byte %d is not zero (offset %zu)", j,
                                     c, off + 25 + c);
                    goto fail;
                }
            }
            s->flags = data[off + 31];
        }
    }
    if (flags & AFFECT_MOTION_FLAG_ROTATIONS) {
        size_t nq = (size_t)n_frames * n_joints;
        if ((st = get_floats_polled(data + off, m->rot, nq * 4, mon, err)))
            goto fail;
        off += nq * 16;
        /* per joint once: stored translations, or the offset (as float) for every frame */
        float *rest = m->trans; /* frame 0's row holds each joint's fallback until it is read */
        uint8_t moving[AFFECT_MOTION_MAX_JOINTS];
        for (uint32_t j = 0; j < n_joints; j++) {
            const affect_skel_joint *s = &m->skel[j];
            moving[j] = s->n_channels <= 6 && affect_skel_has_position(s);
            for (int a = 0; a < 3; a++)
                rest[(size_t)j * 3 + a] = (float)s->offset[a];
        }
        for (uint32_t t = n_frames; t-- > 0;) { /* backwards: frame 0's fallbacks are read last */
            if (t % 4096 == 0 && (st = affect_monitor_check(mon, err)))
                goto fail;
            float *row = m->trans + (size_t)t * n_joints * 3;
            const unsigned char *src = data + off + (size_t)t * n_translated * 12;
            for (uint32_t j = 0; j < n_joints; j++) {
                if (moving[j]) {
                    get_floats(src, row + (size_t)j * 3, 3);
                    src += 12;
                } else if (t) {
                    memcpy(row + (size_t)j * 3, rest + (size_t)j * 3, 3 * sizeof *row);
                }
            }
        }
    }
    st = check_names_unique(m, err);
    if (!st)
        st = check_parents(m, err);
    if (!st)
        st = affect_monitor_check(mon, err);
    if (!st)
        st = check_finite(m, err);
    if (!st && m->skel)
        st = check_skeleton(m, err);
    if (!st)
        st = affect_monitor_check(mon, err);
    if (!st && m->rot)
        st = check_rotations(m, err);
    if (st)
        goto fail;
    *out = m;
    return AFFECT_OK;
fail:
    affect_motion_free(m);
    return st;
}

/* ---- editing ---- */

/* New motion with m's joints (names, parents, unit) and n_frames frames at fps. */
static affect_status like(const affect_motion *m, uint32_t n_frames, double fps,
                          affect_motion **out, affect_error *err)
{
    affect_motion *c = NULL;
    affect_status st = affect_motion_create(n_frames, m->n_joints, fps, &c, err);
    if (st)
        return st;
    memcpy(c->unit, m->unit, sizeof c->unit);
    memcpy(c->parents, m->parents, (size_t)m->n_joints * sizeof *c->parents);
    for (uint32_t j = 0; j < m->n_joints && !st; j++)
        st = affect_motion_set_name(c, j, m->names[j], strlen(m->names[j]), err);
    if (st) {
        affect_motion_free(c);
        return st;
    }
    *out = c;
    return AFFECT_OK;
}

/* The two source frames around position src (in source frames) and the weight of the second. */
static void resample_source(uint32_t n_frames, double src, uint32_t *i0, uint32_t *i1, double *w)
{
    *i0 = (uint32_t)floor(src);
    if (*i0 >= n_frames - 1)
        *i0 = n_frames - 1;
    *w = src - *i0;
    *i1 = *i0 + 1 < n_frames ? *i0 + 1 : *i0;
    if (*i1 == *i0)
        *w = 0.0;
}

affect_status affect_motion_slice(const affect_motion *m, int64_t first, int64_t last,
                                  affect_motion **out, affect_error *err)
{
    int64_t n = m->n_frames;
    int64_t f = first < 0 ? n + first : first;
    int64_t l = last < 0 ? n + last : last;
    if (f < 0 || f >= n)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "first frame %lld out of range (the motion has %lld frames)",
                           (long long)first, (long long)n);
    if (l < 0 || l >= n)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "last frame %lld out of range (the motion has %lld frames)",
                           (long long)last, (long long)n);
    if (l < f)
        return affect_fail(err, AFFECT_ERR_RANGE, "last frame %lld is before first frame %lld",
                           (long long)last, (long long)first);
    affect_motion *c = NULL;
    affect_status st = like(m, (uint32_t)(l - f + 1), m->fps, &c, err);
    if (st)
        return st;
    size_t per = (size_t)m->n_joints * 3;
    memcpy(c->pos, m->pos + (size_t)f * per, (size_t)(l - f + 1) * per * sizeof *c->pos);
    st = copy_skeleton(m, (uint32_t)f, c, err);
    if (st) {
        affect_motion_free(c);
        return st;
    }
    *out = c;
    return AFFECT_OK;
}

/* Rotations and translations of c (c->n_frames frames at c->fps) interpolated from m's, then
 * the positions by forward kinematics. */
static affect_status resample_rotations(const affect_motion *m, affect_motion *c, affect_error *err)
{
    affect_status st = affect_motion_add_skeleton(c, true, err);
    if (st)
        return st;
    uint32_t nj = m->n_joints;
    memcpy(c->skel, m->skel, (size_t)nj * sizeof *c->skel);
    for (uint32_t k = 0; k < c->n_frames; k++) {
        double src = (double)k * m->fps / c->fps, w;
        uint32_t i0, i1;
        resample_source(m->n_frames, src, &i0, &i1, &w);
        for (uint32_t j = 0; j < nj; j++) {
            const float *qa = m->rot + ((size_t)i0 * nj + j) * 4,
                        *qb = m->rot + ((size_t)i1 * nj + j) * 4;
            double a[4] = {qa[0], qa[1], qa[2], qa[3]}, b[4] = {qb[0], qb[1], qb[2], qb[3]}, r[4];
            affect_quat_slerp(a, b, w, r);
            float *qo = c->rot + ((size_t)k * nj + j) * 4;
            for (int i = 0; i < 4; i++)
                qo[i] = (float)r[i];
            const float *ta = m->trans + ((size_t)i0 * nj + j) * 3,
                        *tb = m->trans + ((size_t)i1 * nj + j) * 3;
            float *to = c->trans + ((size_t)k * nj + j) * 3;
            for (int i = 0; i < 3; i++)
                to[i] = (float)((1.0 - w) * ta[i] + w * tb[i]);
        }
    }
    return affect_motion_fk(c, err);
}

affect_status affect_motion_resample(const affect_motion *m, double fps, affect_motion **out,
                                     affect_error *err)
{
    if (!(fps > 0.0) || !(fps <= AFFECT_MOTION_MAX_FPS))
        return affect_fail(err, AFFECT_ERR_RANGE, "frames per second %g out of range (0 .. %g]",
                           fps, AFFECT_MOTION_MAX_FPS);
    double span = (double)(m->n_frames - 1) / m->fps; /* seconds from first to last frame */
    double frames = floor(span * fps + 1e-9) + 1.0;
    if (frames > AFFECT_MOTION_MAX_FRAMES)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "resampling to %g fps gives %.0f frames (at most %u)", fps, frames,
                           AFFECT_MOTION_MAX_FRAMES);
    /* a rate is no size: the result may not exceed the importers' limit, or the input's size */
    double samples = frames * m->n_joints, input = (double)m->n_frames * m->n_joints;
    double limit = input > AFFECT_MOTION_MAX_SAMPLES ? input : AFFECT_MOTION_MAX_SAMPLES;
    if (samples > limit)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "resampling to %g fps gives %.0f frames x %u joints = %.0f samples, "
                           "above the limit of %.0f",
                           fps, frames, m->n_joints, samples, limit);
    affect_motion *c = NULL;
    affect_status st = like(m, (uint32_t)frames, fps, &c, err);
    if (st)
        return st;
    if (m->rot) {
        st = resample_rotations(m, c, err);
        if (st) {
            affect_motion_free(c);
            return st;
        }
        *out = c;
        return AFFECT_OK;
    }
    size_t per = (size_t)m->n_joints * 3;
    for (uint32_t k = 0; k < c->n_frames; k++) {
        double src = (double)k * m->fps / fps, w; /* position in source frames */
        uint32_t i0, i1;
        resample_source(m->n_frames, src, &i0, &i1, &w);
        const float *a = m->pos + (size_t)i0 * per, *b = m->pos + (size_t)i1 * per;
        float *o = c->pos + (size_t)k * per;
        for (size_t i = 0; i < per; i++)
            o[i] = (float)((1.0 - w) * a[i] + w * b[i]);
    }
    *out = c;
    return AFFECT_OK;
}

affect_status affect_motion_select(const affect_motion *m, const char *const *names,
                                   uint32_t n_names, affect_motion **out, affect_error *err)
{
    if (n_names == 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "no joints selected");
    int32_t *src = affect_malloc_array(n_names, sizeof *src);
    int32_t *map = affect_malloc_array(m->n_joints, sizeof *map); /* source joint → new index */
    affect_motion *c = NULL;
    affect_status st = AFFECT_OK;
    if (!src || !map) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t j = 0; j < m->n_joints; j++)
        map[j] = -1;
    for (uint32_t i = 0; i < n_names; i++) {
        src[i] = affect_motion_find_joint(m, names[i]);
        if (src[i] < 0) {
            st = affect_fail(err, AFFECT_ERR_MISSING,
                             "no joint named \"%.64s\" (selection item %u)", names[i], i);
            goto done;
        }
        if (map[src[i]] >= 0) {
            st = affect_fail(err, AFFECT_ERR_INVALID,
                             "joint \"%.64s\" selected twice (items %d and %u)", names[i],
                             map[src[i]], i);
            goto done;
        }
        map[src[i]] = (int32_t)i;
    }
    st = affect_motion_create(m->n_frames, n_names, m->fps, &c, err);
    if (st)
        goto done;
    memcpy(c->unit, m->unit, sizeof c->unit);
    for (uint32_t i = 0; i < n_names; i++) {
        st = affect_motion_set_name(c, i, m->names[src[i]], strlen(m->names[src[i]]), err);
        if (st)
            goto done;
        int32_t p = m->parents[src[i]];
        uint32_t guard = 0;
        while (p >= 0 && map[p] < 0 && guard++ <= m->n_joints)
            p = m->parents[p];
        c->parents[i] = p >= 0 ? map[p] : -1;
    }
    for (uint32_t t = 0; t < m->n_frames; t++)
        for (uint32_t i = 0; i < n_names; i++)
            memcpy(affect_motion_at(c, t, i), affect_motion_at(m, t, (uint32_t)src[i]),
                   3 * sizeof(float));
    *out = c;
    c = NULL;
done:
    affect_motion_free(c);
    affect_free(src);
    affect_free(map);
    return st;
}
