/*
 * bvh_write.c — BVH export of skeletal motions (see affect/io.h).
 *
 * Usage:
 *   affect_bvh_write_options o;  affect_bvh_write_options_default(&o);
 *   char *text; size_t len;
 *   affect_bvh_write(m, &o, &text, &len, &err);   // m->rot must be set
 *
 * Numbers are written by a fixed-point formatter (value × 10^precision rounded to an integer,
 * then its digits) rather than printf, which is what keeps export above 200 MB/s of text.
 * Values of 10^12 or more (never a pose in practice) fall back to "%.17g".
 */
#include "affect/io.h"
#include "affect/quat.h"
#include "affect/skeleton.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define FIXED_MAX 1e12
#define NUMBER_MAX_BYTES 32 /* the longest number either formatter writes, with its separator */

void affect_bvh_write_options_default(affect_bvh_write_options *opt)
{
    opt->order[0] = opt->order[1] = opt->order[2] = -1;
    opt->frame_time = 0;
    opt->precision = 6;
    opt->root_name = NULL;
    opt->monitor = NULL;
}

typedef struct out_buf {
    char *p;
    size_t len, cap;
} out_buf;

static bool reserve(out_buf *b, size_t more)
{
    if (b->cap - b->len >= more)
        return true;
    size_t cap = b->cap ? b->cap : 4096;
    while (cap - b->len < more) {
        if (cap > SIZE_MAX / 2)
            return false;
        cap *= 2;
    }
    char *p = affect_realloc(b->p, cap);
    if (!p)
        return false;
    b->p = p;
    b->cap = cap;
    return true;
}

/* Appends s; the caller has reserved the room. */
static void put(out_buf *b, const char *s, size_t n)
{
    memcpy(b->p + b->len, s, n);
    b->len += n;
}

static const double pow10_table[10] = {1, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9};

/* u = ip · 10^prec + fp. A constant divisor per precision lets the compiler divide by
 * multiplication (the run-time 64-bit division was a third of export time). */
static void split_fixed(uint64_t u, int prec, uint64_t *ip, uint64_t *fp)
{
#define SPLIT(p10)                                                                                 \
    do {                                                                                           \
        *ip = u / (p10);                                                                           \
        *fp = u - *ip * (p10);                                                                     \
    } while (0)
    switch (prec) {
    case 1:
        SPLIT(10u);
        break;
    case 2:
        SPLIT(100u);
        break;
    case 3:
        SPLIT(1000u);
        break;
    case 4:
        SPLIT(10000u);
        break;
    case 5:
        SPLIT(100000u);
        break;
    case 6:
        SPLIT(1000000u);
        break;
    case 7:
        SPLIT(10000000u);
        break;
    case 8:
        SPLIT(100000000u);
        break;
    default:
        SPLIT(1000000000u);
        break;
    }
#undef SPLIT
}

/* Writes v with prec decimals, trailing zeros (and a bare point) removed, "-0" as "0". At most
 * NUMBER_MAX_BYTES − 1 bytes; room reserved by the caller. */
static void put_number(out_buf *b, double v, int prec)
{
    char *o = b->p + b->len;
    if (!(fabs(v) < FIXED_MAX)) {
        int n = snprintf(o, NUMBER_MAX_BYTES, "%.17g", v);
        b->len += (size_t)n;
        return;
    }
    double scaled = fabs(v) * pow10_table[prec];
    uint64_t u = (uint64_t)(scaled + 0.5), ip, fp;
    split_fixed(u, prec, &ip, &fp);
    size_t n = 0;
    if (v < 0 && u != 0)
        o[n++] = '-';
    char digits[24];
    int nd = 0;
    do {
        digits[nd++] = (char)('0' + ip % 10);
        ip /= 10;
    } while (ip);
    while (nd)
        o[n++] = digits[--nd];
    if (fp) {
        int width = prec;
        while (fp % 10 == 0) {
            fp /= 10;
            width--;
        }
        o[n++] = '.';
        for (int k = width - 1; k >= 0; k--) {
            o[n + (size_t)k] = (char)('0' + fp % 10);
            fp /= 10;
        }
        n += (size_t)width;
    }
    b->len += n;
}

/* A joint name with white space and braces replaced by '_'. */
static bool put_name(out_buf *b, const char *name)
{
    size_t n = strlen(name);
    if (!reserve(b, n + 2))
        return false;
    for (size_t i = 0; i < n; i++) {
        char c = name[i];
        b->p[b->len++] = (c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\v' ||
                          c == '\f' || c == '{' || c == '}')
                             ? '_'
                             : c;
    }
    return true;
}

static bool put_indent(out_buf *b, uint32_t depth, const char *s)
{
    size_t n = strlen(s);
    if (!reserve(b, depth + n))
        return false;
    for (uint32_t i = 0; i < depth; i++)
        b->p[b->len++] = '\t';
    put(b, s, n);
    return true;
}

static const char *const channel_names[AFFECT_CH_COUNT] = {"Xposition", "Yposition", "Zposition",
                                                           "Xrotation", "Yrotation", "Zrotation"};

/* The channels written for joint j: its own, or with rotations replaced by the order asked. */
static int joint_channels(const affect_skel_joint *s, const affect_bvh_write_options *opt,
                          uint8_t ch[6])
{
    int n = 0;
    bool rotates = false;
    for (int c = 0; c < s->n_channels; c++) {
        if (s->channel[c] <= AFFECT_CH_ZPOS || opt->order[0] < 0)
            ch[n++] = s->channel[c];
        rotates |= s->channel[c] >= AFFECT_CH_XROT;
    }
    if (rotates && opt->order[0] >= 0)
        for (int a = 0; a < 3; a++)
            ch[n++] = (uint8_t)(AFFECT_CH_XROT + opt->order[a]);
    return n;
}

typedef struct writer {
    const affect_motion *m;
    const affect_bvh_write_options *opt;
    out_buf b;
    uint32_t *seq; /* joints in file order */
    uint32_t n_seq;
    uint32_t *first_child, *next_sibling;
} writer;

static bool put_offset(writer *w, uint32_t depth, const double o[3])
{
    if (!put_indent(&w->b, depth, "OFFSET") || !reserve(&w->b, 3 * NUMBER_MAX_BYTES + 1))
        return false;
    for (int a = 0; a < 3; a++) {
        w->b.p[w->b.len++] = ' ';
        put_number(&w->b, o[a], w->opt->precision);
    }
    w->b.p[w->b.len++] = '\n';
    return true;
}

/* The hierarchy block of root r, depth first without recursion. */
static bool write_tree(writer *w, uint32_t r, bool first_root)
{
    const affect_motion *m = w->m;
    uint32_t j = r, depth = 0;
    for (;;) {
        const affect_skel_joint *s = &m->skel[j];
        if (s->flags & AFFECT_JOINT_END_SITE) {
            if (!put_indent(&w->b, depth, "End Site\n") || !put_indent(&w->b, depth, "{\n") ||
                !put_offset(w, depth + 1, s->offset) || !put_indent(&w->b, depth, "}\n"))
                return false;
        } else {
            if (!put_indent(&w->b, depth, j == r ? "ROOT " : "JOINT "))
                return false;
            const char *name =
                j == r && first_root && w->opt->root_name ? w->opt->root_name : m->names[j];
            if (!put_name(&w->b, name) || !reserve(&w->b, 1))
                return false;
            w->b.p[w->b.len++] = '\n';
            if (!put_indent(&w->b, depth, "{\n") || !put_offset(w, depth + 1, s->offset))
                return false;
            uint8_t ch[6];
            int n = joint_channels(s, w->opt, ch);
            char head[16];
            snprintf(head, sizeof head, "CHANNELS %d", n);
            if (!put_indent(&w->b, depth + 1, head) || !reserve(&w->b, 6 * 11 + 1))
                return false;
            for (int c = 0; c < n; c++) {
                w->b.p[w->b.len++] = ' ';
                put(&w->b, channel_names[ch[c]], 9);
            }
            w->b.p[w->b.len++] = '\n';
            w->seq[w->n_seq++] = j;
            if (w->first_child[j] != UINT32_MAX) { /* descend */
                j = w->first_child[j];
                depth++;
                continue;
            }
            if (!put_indent(&w->b, depth, "}\n"))
                return false;
        }
        /* climb until a joint with a next sibling, closing blocks */
        while (j != r && w->next_sibling[j] == UINT32_MAX) {
            j = (uint32_t)m->parents[j];
            depth--;
            if (!put_indent(&w->b, depth, "}\n"))
                return false;
        }
        if (j == r)
            return true;
        j = w->next_sibling[j];
    }
}

/* The Euler order used for a joint's rotation channels: those channels' axes, then the others
 * (whose angles are zero for a rotation made of the channels). */
static int rotation_order(const uint8_t *ch, int n, int order[3])
{
    int k = 0;
    unsigned seen = 0;
    for (int c = 0; c < n; c++)
        if (ch[c] >= AFFECT_CH_XROT) {
            order[k++] = ch[c] - AFFECT_CH_XROT;
            seen |= 1u << (ch[c] - AFFECT_CH_XROT);
        }
    int n_rot = k;
    for (int a = 0; a < 3; a++)
        if (!(seen & (1u << a)))
            order[k++] = a;
    return n_rot;
}

/* Angle (degrees) of the rotation q about axis a alone. */
static double axis_angle_deg(const double q[4], int a)
{
    return 2 * atan2(q[1 + a], q[0]) * (180.0 / 3.14159265358979323846);
}

static double unwrap_deg(double x, double ref)
{
    if (fabs(x - ref) < 180)
        return x;
    return x - 360.0 * floor((x - ref) / 360.0 + 0.5);
}

/* Euler angles of q for a joint with n_rot rotation channels (order[0 .. n_rot) their axes).
 * Three: affect_quat_to_euler_deg. Fewer: the rotation is R_a(α) (· R_b(β)), and the general
 * decomposition would spread rounding onto the missing axis (or pick the solution with a half
 * turn there, β beyond ±90°), so: α from the column b of R, which R_b leaves alone,
 * α = atan2(e · R[c][b], R[b][b]); then β is the angle of R_a(−α) · q about b. */
static void joint_euler(const double q[4], const int order[3], int n_rot, const double *prev,
                        double deg[3])
{
    if (n_rot == 3) {
        affect_quat_to_euler_deg(q, order, prev, deg);
        return;
    }
    int a = order[0];
    deg[1] = deg[2] = 0;
    if (n_rot == 1) {
        deg[0] = axis_angle_deg(q, a);
    } else {
        int b = order[1], c = order[2];
        double r[9], e = (b - a + 3) % 3 == 1 ? 1.0 : -1.0;
        affect_quat_to_matrix(q, r);
        double al = atan2(e * r[c * 3 + b], r[b * 3 + b]);
        double qa[4] = {cos(al / 2), 0, 0, 0}, rest[4];
        qa[1 + a] = -sin(al / 2); /* R_a(−α) */
        affect_quat_mul(qa, q, rest);
        deg[0] = al * (180.0 / 3.14159265358979323846);
        deg[1] = axis_angle_deg(rest, b);
    }
    for (int k = 0; k < n_rot; k++)
        deg[k] = prev ? unwrap_deg(deg[k], prev[k]) : unwrap_deg(deg[k], 0);
}

/* write_frames polls the monitor every this many frames */
#define POLL_FRAMES 1024

static affect_status write_frames(writer *w, affect_error *err)
{
    const affect_motion *m = w->m;
    uint32_t nj = m->n_joints;
    double *prev = affect_malloc_array((size_t)nj * 3, sizeof *prev);
    if (!prev)
        return affect_nomem(err);
    size_t per_frame = (size_t)w->n_seq * 6 * NUMBER_MAX_BYTES + 1;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        affect_status st =
            t % POLL_FRAMES == 0 ? affect_monitor_check(w->opt->monitor, err) : AFFECT_OK;
        if (st) {
            affect_free(prev);
            return st;
        }
        if (!reserve(&w->b, per_frame)) {
            affect_free(prev);
            return affect_nomem(err);
        }
        size_t line_start = w->b.len;
        for (uint32_t i = 0; i < w->n_seq; i++) {
            uint32_t j = w->seq[i];
            uint8_t ch[6];
            int n = joint_channels(&m->skel[j], w->opt, ch), order[3];
            int n_rot = rotation_order(ch, n, order);
            double deg[3] = {0, 0, 0};
            if (n_rot) {
                double q[4];
                const float *qf = m->rot + ((size_t)t * nj + j) * 4;
                q[0] = qf[0], q[1] = qf[1], q[2] = qf[2], q[3] = qf[3];
                affect_quat_normalize(q);
                joint_euler(q, order, n_rot, t ? prev + (size_t)j * 3 : NULL, deg);
                memcpy(prev + (size_t)j * 3, deg, sizeof deg);
            }
            const float *tr = m->trans + ((size_t)t * nj + j) * 3;
            for (int c = 0, r = 0; c < n; c++) {
                double v = ch[c] <= AFFECT_CH_ZPOS ? (double)tr[ch[c]] : deg[r++];
                put_number(&w->b, v, w->opt->precision);
                w->b.p[w->b.len++] = ' ';
            }
        }
        if (w->b.len > line_start)
            w->b.len--; /* the last separator */
        w->b.p[w->b.len++] = '\n';
    }
    affect_free(prev);
    return AFFECT_OK;
}

affect_status affect_bvh_write(const affect_motion *m, const affect_bvh_write_options *opt,
                               char **out, size_t *len, affect_error *err)
{
    affect_bvh_write_options def;
    if (!opt) {
        affect_bvh_write_options_default(&def);
        opt = &def;
    }
    if (!m->skel || !m->rot)
        return affect_fail(err, AFFECT_ERR_INVALID, "the motion has no joint rotations");
    if (opt->precision < 1 || opt->precision > 9)
        return affect_fail(err, AFFECT_ERR_INVALID, "precision %d out of range (1 .. 9)",
                           opt->precision);
    double frame_time = opt->frame_time > 0 ? opt->frame_time : 1.0 / m->fps;
    if (!isfinite(frame_time) || frame_time <= 0)
        return affect_fail(err, AFFECT_ERR_INVALID, "frame time must be a positive number");
    if (opt->root_name) {
        size_t n = strlen(opt->root_name);
        if (n == 0 || n > AFFECT_MOTION_MAX_NAME)
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "root name length %zu out of range (1 .. %u)", n,
                               AFFECT_MOTION_MAX_NAME);
    }
    uint32_t nj = m->n_joints;
    writer w = {m, opt, {NULL, 0, 0}, NULL, 0, NULL, NULL};
    w.seq = affect_malloc_array(nj, sizeof *w.seq);
    w.first_child = affect_malloc_array(nj, sizeof *w.first_child);
    w.next_sibling = affect_malloc_array(nj, sizeof *w.next_sibling);
    affect_status st = AFFECT_OK;
    if (!w.seq || !w.first_child || !w.next_sibling) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t j = 0; j < nj; j++)
        w.first_child[j] = w.next_sibling[j] = UINT32_MAX;
    for (uint32_t j = nj; j-- > 0;) { /* children in joint order */
        int32_t p = m->parents[j];
        if (p >= 0) {
            w.next_sibling[j] = w.first_child[p];
            w.first_child[p] = j;
        }
    }
    if (!put_indent(&w.b, 0, "HIERARCHY\n")) {
        st = affect_nomem(err);
        goto done;
    }
    bool first = true;
    for (uint32_t r = 0; r < nj; r++) {
        if (m->parents[r] >= 0)
            continue;
        if (m->skel[r].flags & AFFECT_JOINT_END_SITE) {
            st = affect_fail(err, AFFECT_ERR_INVALID, "root joint %u is an End Site", r);
            goto done;
        }
        if (!write_tree(&w, r, first)) {
            st = affect_nomem(err);
            goto done;
        }
        first = false;
    }
    char head[96];
    int n = snprintf(head, sizeof head, "MOTION\nFrames: %u\nFrame Time: %.9g\n", m->n_frames,
                     frame_time);
    if (!reserve(&w.b, (size_t)n + 1)) {
        st = affect_nomem(err);
        goto done;
    }
    put(&w.b, head, (size_t)n);
    st = write_frames(&w, err);
    if (st)
        goto done;
    if (!reserve(&w.b, 1)) {
        st = affect_nomem(err);
        goto done;
    }
    w.b.p[w.b.len] = '\0';
    *out = w.b.p;
    *len = w.b.len;
    w.b.p = NULL;
done:
    affect_free(w.b.p);
    affect_free(w.seq);
    affect_free(w.first_child);
    affect_free(w.next_sibling);
    return st;
}
