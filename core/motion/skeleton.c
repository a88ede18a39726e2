/*
 * skeleton.c — forward kinematics from stored rotations, free links, bone-length variation,
 * the rigid projection and inverse kinematics (see affect/skeleton.h).
 *
 * Rigid projection, per frame: minimize Σ_k ‖p_k − q_k‖² (q the input) subject to
 * ‖p_j − p_parent(j)‖ = L_j on every bone. With the other bones fixed, moving bone j's
 * direction u moves its subtree S_j (the joints below it through bones) rigidly, and
 *   Σ_{k∈S_j} ‖p_par + L_j u + r_k − q_k‖² is least for u ∥ Σ_{k∈S_j} (q_k − r_k − p_par),
 * r_k = p_k − p_j: an exact block update. Each rigid part (a root or a free joint with its
 * subtree) also translates by its mean residual. Sweeps in parent-first order repeat until no
 * joint moves more than tolerance × body size; the objective never increases.
 *
 * Inverse kinematics uses Horn's closed form for the best-fit rotation (the eigenvector of the
 * largest eigenvalue of a symmetric 4×4 matrix, here by cyclic Jacobi rotations).
 */
#include "affect/skeleton.h"
#include "affect/quat.h"
#include "affect/roles.h"
#include "util/internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* two children whose best-fit rotation is undetermined to this relative eigenvalue gap are
 * treated as collinear */
#define IK_EIGEN_GAP_REL 1e-9
/* bones shorter than this × body size carry no direction */
#define BONE_MIN_REL 1e-9
#define JACOBI_MAX_SWEEPS 50
/* float steps either way that rounding a rigid joint may take to keep its bone's length */
#define ROUND_STEPS 1
/* rounds of the generalized Procrustes mean of a sibling group's rest offsets */
#define IK_SHAPE_ROUNDS 3
/* with siblings "auto", a sibling group whose best fit misses a position by more than this ×
 * body size gets position channels */
#define IK_SIBLING_TOL_REL 1e-3

void affect_rigid_options_default(affect_rigid_options *opt)
{
    opt->model = AFFECT_RIGID_BONES;
    opt->lengths = AFFECT_RIGID_MEDIAN;
    opt->reference = NULL;
    opt->max_sweeps = 200;
    opt->tolerance = 1e-9;
    opt->free_link = NULL;
    opt->monitor = NULL;
}

void affect_ik_options_default(affect_ik_options *opt)
{
    opt->rest_frame = 0;
    opt->siblings = AFFECT_IK_SIBLINGS_AUTO;
    opt->order[0] = 2, opt->order[1] = 0, opt->order[2] = 1;
    affect_rigid_options_default(&opt->rigid);
}

/* ---- small vector helpers ---- */

static void load3(const float *p, double v[3])
{
    v[0] = p[0], v[1] = p[1], v[2] = p[2];
}

static double norm3(const double v[3])
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static void qload(const float *p, double q[4])
{
    q[0] = p[0], q[1] = p[1], q[2] = p[2], q[3] = p[3];
}

static void qconj(const double q[4], double r[4])
{
    r[0] = q[0], r[1] = -q[1], r[2] = -q[2], r[3] = -q[3];
}

/* ---- topology ---- */

affect_status affect_motion_topo_order(const affect_motion *m, uint32_t *order, affect_error *err)
{
    uint32_t n = m->n_joints, head = 0, tail = 0;
    for (uint32_t j = 0; j < n; j++)
        if (m->parents[j] < 0)
            order[tail++] = j;
    /* breadth first: each pass appends the children of order[head] (O(J²) worst case is
     * avoided by a children table) */
    uint32_t *start = affect_calloc((size_t)n + 1, sizeof *start);
    uint32_t *list = affect_malloc_array(n ? n : 1, sizeof *list);
    if (!start || !list) {
        affect_free(start);
        affect_free(list);
        return affect_nomem(err);
    }
    for (uint32_t j = 0; j < n; j++)
        if (m->parents[j] >= 0)
            start[m->parents[j] + 1]++;
    for (uint32_t j = 0; j < n; j++)
        start[j + 1] += start[j];
    uint32_t *fill = affect_malloc_array(n ? n : 1, sizeof *fill);
    if (!fill) {
        affect_free(start);
        affect_free(list);
        return affect_nomem(err);
    }
    memcpy(fill, start, (size_t)n * sizeof *fill);
    for (uint32_t j = 0; j < n; j++)
        if (m->parents[j] >= 0)
            list[fill[m->parents[j]]++] = j;
    while (head < tail) {
        uint32_t j = order[head++];
        for (uint32_t k = start[j]; k < start[j + 1] && tail < n; k++)
            order[tail++] = list[k];
    }
    affect_free(fill);
    affect_free(start);
    affect_free(list);
    if (tail != n)
        return affect_fail(err, AFFECT_ERR_FORMAT, "the joints' parents do not form a tree");
    return AFFECT_OK;
}

/* Children table: the children of j are list[start[j] .. start[j + 1]). */
typedef struct children {
    uint32_t *start, *list;
} children;

static affect_status children_build(const affect_motion *m, children *c, affect_error *err)
{
    uint32_t n = m->n_joints;
    c->start = affect_calloc((size_t)n + 2, sizeof *c->start);
    c->list = affect_malloc_array(n ? n : 1, sizeof *c->list);
    if (!c->start || !c->list)
        return affect_nomem(err);
    for (uint32_t j = 0; j < n; j++)
        if (m->parents[j] >= 0)
            c->start[m->parents[j] + 2]++;
    for (uint32_t j = 0; j < n; j++)
        c->start[j + 2] += c->start[j + 1];
    for (uint32_t j = 0; j < n; j++)
        if (m->parents[j] >= 0)
            c->list[c->start[m->parents[j] + 1]++] = j;
    return AFFECT_OK;
}

static void children_free(children *c)
{
    affect_free(c->start);
    affect_free(c->list);
}

/* ---- forward kinematics ---- */

/* World positions of frame t from m's rotations into out (J × 3 doubles); wrot receives the
 * world rotations (J × 4). */
static void fk_frame(const affect_motion *m, const uint32_t *order, uint32_t t, double *wrot,
                     double *out)
{
    uint32_t nj = m->n_joints;
    for (uint32_t i = 0; i < nj; i++) {
        uint32_t j = order[i];
        const affect_skel_joint *s = &m->skel[j];
        double tr[3], q[4];
        if (affect_skel_has_position(s))
            load3(m->trans + ((size_t)t * nj + j) * 3, tr);
        else
            memcpy(tr, s->offset, sizeof tr);
        qload(m->rot + ((size_t)t * nj + j) * 4, q);
        affect_quat_normalize(q);
        int32_t p = m->parents[j];
        if (p < 0) {
            memcpy(wrot + (size_t)j * 4, q, sizeof q);
            memcpy(out + (size_t)j * 3, tr, sizeof tr);
        } else {
            double v[3];
            affect_quat_rotate(wrot + (size_t)p * 4, tr, v);
            for (int a = 0; a < 3; a++)
                out[(size_t)j * 3 + a] = out[(size_t)p * 3 + a] + v[a];
            affect_quat_mul(wrot + (size_t)p * 4, q, wrot + (size_t)j * 4);
        }
    }
}

/* Work arrays for fk_frame. */
typedef struct fk_work {
    uint32_t *order;
    double *wrot, *pos;
    void *block;
} fk_work;

static affect_status fk_work_alloc(const affect_motion *m, fk_work *w, affect_error *err)
{
    size_t n = m->n_joints;
    affect_ws_part parts[] = {{(void **)&w->order, n, sizeof *w->order},
                              {(void **)&w->wrot, n * 4, sizeof *w->wrot},
                              {(void **)&w->pos, n * 3, sizeof *w->pos}};
    w->block = affect_ws_alloc(parts, 3);
    if (!w->block)
        return affect_nomem(err);
    affect_status st = affect_motion_topo_order(m, w->order, err);
    if (st)
        affect_free(w->block);
    return st;
}

affect_status affect_motion_fk(affect_motion *m, affect_error *err)
{
    if (!m->rot || !m->skel)
        return affect_fail(err, AFFECT_ERR_INVALID, "the motion has no rotations");
    fk_work w;
    affect_status st = fk_work_alloc(m, &w, err);
    if (st)
        return st;
    size_t nv = (size_t)m->n_joints * 3;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        fk_frame(m, w.order, t, w.wrot, w.pos);
        float *o = affect_motion_at(m, t, 0);
        for (size_t i = 0; i < nv; i++)
            o[i] = (float)w.pos[i];
    }
    affect_free(w.block);
    return AFFECT_OK;
}

/* affect_motion_fk_error, polling mon (may be NULL) every few thousand frames. */
static affect_status fk_error(const affect_motion *m, double *max_dist, uint32_t *frame,
                              uint32_t *joint, affect_monitor *mon, affect_error *err)
{
    *max_dist = 0;
    *frame = *joint = 0;
    if (!m->rot || !m->skel)
        return affect_fail(err, AFFECT_ERR_INVALID, "the motion has no rotations");
    fk_work w;
    affect_status st = fk_work_alloc(m, &w, err);
    if (st)
        return st;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        if (t % 4096 == 0 && (st = affect_monitor_check(mon, err))) {
            affect_free(w.block);
            return st;
        }
        fk_frame(m, w.order, t, w.wrot, w.pos);
        for (uint32_t j = 0; j < m->n_joints; j++) {
            const float *p = affect_motion_at(m, t, j);
            double d[3] = {w.pos[j * 3] - p[0], w.pos[j * 3 + 1] - p[1], w.pos[j * 3 + 2] - p[2]};
            double dist = norm3(d);
            if (dist > *max_dist) {
                *max_dist = dist;
                *frame = t;
                *joint = j;
            }
        }
    }
    affect_free(w.block);
    return AFFECT_OK;
}

affect_status affect_motion_fk_error(const affect_motion *m, double *max_dist, uint32_t *frame,
                                     uint32_t *joint, affect_error *err)
{
    return fk_error(m, max_dist, frame, joint, NULL, err);
}

/* ---- bones ---- */

double affect_motion_body_size(const affect_motion *m)
{
    float lo[3], hi[3];
    for (int a = 0; a < 3; a++)
        lo[a] = hi[a] = m->pos[a];
    for (uint32_t j = 0; j < m->n_joints; j++)
        for (int a = 0; a < 3; a++) {
            float v = affect_motion_at(m, 0, j)[a];
            lo[a] = v < lo[a] ? v : lo[a];
            hi[a] = v > hi[a] ? v : hi[a];
        }
    double size = 0;
    for (int a = 0; a < 3; a++)
        size = fmax(size, (double)hi[a] - lo[a]);
    return size > 0 ? size : 1.0;
}

affect_status affect_motion_free_links(const affect_motion *m, bool *free_link, affect_error *err)
{
    uint32_t nj = m->n_joints;
    uint32_t *n_children = affect_calloc(nj, sizeof *n_children);
    if (!n_children)
        return affect_nomem(err);
    for (uint32_t j = 0; j < nj; j++)
        if (m->parents[j] >= 0)
            n_children[m->parents[j]]++;
    affect_roles roles;
    affect_roles_resolve(m, &roles);
    for (uint32_t j = 0; j < nj; j++) {
        free_link[j] = false;
        int32_t p = m->parents[j];
        if (p < 0)
            continue;
        if (m->parents[p] < 0 && n_children[p] == 1 &&
            (int32_t)j == roles.joint[AFFECT_ROLE_PELVIS]) {
            free_link[j] = true; /* a reference root above the pelvis */
            continue;
        }
        if (m->skel && m->rot && affect_skel_has_position(&m->skel[j])) {
            const double *o = m->skel[j].offset;
            double limit = AFFECT_FREE_LINK_REL * norm3(o);
            for (uint32_t t = 0; t < m->n_frames && !free_link[j]; t++) {
                const float *tr = m->trans + ((size_t)t * nj + j) * 3;
                double d[3] = {tr[0] - o[0], tr[1] - o[1], tr[2] - o[2]};
                free_link[j] = norm3(d) > limit;
            }
        }
    }
    affect_free(n_children);
    return AFFECT_OK;
}

static double bone_length(const affect_motion *m, uint32_t t, uint32_t j)
{
    double a[3], b[3];
    load3(affect_motion_at(m, t, j), a);
    load3(affect_motion_at(m, t, (uint32_t)m->parents[j]), b);
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return norm3(d);
}

affect_status affect_motion_bone_variation(const affect_motion *m, double *variation,
                                           int32_t *worst, affect_error *err)
{
    *variation = 0;
    *worst = -1;
    bool *free_link = affect_malloc_array(m->n_joints, sizeof *free_link);
    if (!free_link)
        return affect_nomem(err);
    affect_status st = affect_motion_free_links(m, free_link, err);
    for (uint32_t j = 0; j < m->n_joints && !st; j++) {
        if (m->parents[j] < 0 || free_link[j])
            continue;
        double lo = INFINITY, hi = 0;
        for (uint32_t t = 0; t < m->n_frames; t++) {
            double l = bone_length(m, t, j);
            lo = fmin(lo, l);
            hi = fmax(hi, l);
        }
        double v = hi > 0 ? (hi - lo) / hi : 0;
        if (*worst < 0 || v > *variation) {
            *variation = v;
            *worst = (int32_t)j;
        }
    }
    affect_free(free_link);
    return st;
}

/* ---- rigid projection ---- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Median length of every bone of m into len (0 for roots); mon is polled per bone. */
static affect_status median_lengths(const affect_motion *m, double *len, affect_monitor *mon,
                                    affect_error *err)
{
    double *v = affect_malloc_array(m->n_frames, sizeof *v);
    if (!v)
        return affect_nomem(err);
    for (uint32_t j = 0; j < m->n_joints; j++) {
        affect_status st = affect_monitor_check(mon, err);
        if (st) {
            affect_free(v);
            return st;
        }
        len[j] = 0;
        if (m->parents[j] < 0)
            continue;
        for (uint32_t t = 0; t < m->n_frames; t++)
            v[t] = bone_length(m, t, j);
        qsort(v, m->n_frames, sizeof *v, cmp_double);
        uint32_t h = m->n_frames / 2;
        len[j] = m->n_frames % 2 ? v[h] : 0.5 * (v[h - 1] + v[h]);
    }
    affect_free(v);
    return AFFECT_OK;
}

/* The rigid parts: sub[start[j] .. start[j + 1]) lists j and the joints below it through bones
 * (not through free links), parents first. */
typedef struct subtrees {
    uint32_t *start, *list;
} subtrees;

static affect_status subtrees_build(const affect_motion *m, const children *ch,
                                    const bool *free_link, subtrees *s, affect_error *err)
{
    uint32_t n = m->n_joints;
    s->start = affect_malloc_array((size_t)n + 1, sizeof *s->start);
    s->list = NULL;
    uint32_t *stack = affect_malloc_array(n, sizeof *stack);
    size_t cap = (size_t)n * 4, used = 0;
    s->list = affect_malloc_array(cap, sizeof *s->list);
    affect_status st = AFFECT_OK;
    if (!s->start || !stack || !s->list) {
        st = affect_nomem(err);
        goto done;
    }
    for (uint32_t j = 0; j < n; j++) {
        s->start[j] = (uint32_t)used;
        uint32_t depth = 0;
        stack[depth++] = j;
        while (depth) {
            uint32_t k = stack[--depth];
            if (used == cap) {
                if (cap > UINT32_MAX / 2) {
                    st = affect_fail(err, AFFECT_ERR_RANGE, "skeleton too deep");
                    goto done;
                }
                uint32_t *grown = affect_realloc(s->list, cap * 2 * sizeof *grown);
                if (!grown) {
                    st = affect_nomem(err);
                    goto done;
                }
                s->list = grown;
                cap *= 2;
            }
            s->list[used++] = k;
            for (uint32_t c = ch->start[k + 1]; c-- > ch->start[k];) /* depth ≤ n */
                if (!free_link[ch->list[c]])
                    stack[depth++] = ch->list[c];
        }
    }
    s->start[n] = (uint32_t)used;
done:
    affect_free(stack);
    return st;
}

static void subtrees_free(subtrees *s)
{
    affect_free(s->start);
    affect_free(s->list);
}

typedef struct rigid_plan {
    uint32_t *order;
    bool *free_link;
    double *len;
    children ch;
    subtrees sub;
} rigid_plan;

static void rigid_plan_free(rigid_plan *p)
{
    affect_free(p->order);
    affect_free(p->free_link);
    affect_free(p->len);
    children_free(&p->ch);
    subtrees_free(&p->sub);
}

static affect_status same_joints(const affect_motion *a, const affect_motion *b, affect_error *err)
{
    if (a->n_joints != b->n_joints)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the reference motion has %u joints, the motion %u", b->n_joints,
                           a->n_joints);
    for (uint32_t j = 0; j < a->n_joints; j++)
        if (strcmp(a->names[j], b->names[j]) != 0 || a->parents[j] != b->parents[j])
            return affect_fail(err, AFFECT_ERR_INVALID,
                               "the reference motion's joint %u (%.64s) differs from the motion's "
                               "(%.64s) in name or parent",
                               j, b->names[j], a->names[j]);
    return AFFECT_OK;
}

static affect_status rigid_plan_make(const affect_motion *m, const affect_rigid_options *opt,
                                     rigid_plan *p, affect_error *err)
{
    memset(p, 0, sizeof *p);
    uint32_t n = m->n_joints;
    bool tree = n == 1;
    for (uint32_t j = 0; j < n; j++)
        tree |= m->parents[j] >= 0;
    if (!tree)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the motion has no skeleton: no joint has a parent (set parents when "
                           "importing, e.g. \"parents\" in JSON)");
    if (opt->lengths == AFFECT_RIGID_REFERENCE && !opt->reference)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "bone lengths from a reference need a reference motion");
    p->order = affect_malloc_array(n, sizeof *p->order);
    p->free_link = affect_malloc_array(n, sizeof *p->free_link);
    p->len = affect_malloc_array(n, sizeof *p->len);
    if (!p->order || !p->free_link || !p->len)
        return affect_nomem(err);
    affect_status st = affect_motion_topo_order(m, p->order, err);
    if (st)
        return st;
    if (opt->free_link)
        for (uint32_t j = 0; j < n; j++)
            p->free_link[j] = opt->free_link[j] && m->parents[j] >= 0;
    else if ((st = affect_motion_free_links(m, p->free_link, err)))
        return st;
    if (opt->lengths == AFFECT_RIGID_REFERENCE) {
        if ((st = same_joints(m, opt->reference, err)) ||
            (st = median_lengths(opt->reference, p->len, opt->monitor, err)))
            return st;
    } else if (opt->lengths == AFFECT_RIGID_FIRST) {
        for (uint32_t j = 0; j < n; j++)
            p->len[j] = m->parents[j] < 0 ? 0 : bone_length(m, 0, j);
    } else if ((st = median_lengths(m, p->len, opt->monitor, err))) {
        return st;
    }
    if ((st = children_build(m, &p->ch, err)))
        return st;
    return subtrees_build(m, &p->ch, p->free_link, &p->sub, err);
}

/* Shifts the joints of part j (j and its subtree) by d. */
static void shift_part(const subtrees *s, uint32_t j, const double d[3], double *p)
{
    for (uint32_t i = s->start[j]; i < s->start[j + 1]; i++) {
        double *x = p + (size_t)s->list[i] * 3;
        x[0] += d[0], x[1] += d[1], x[2] += d[2];
    }
}

/* One frame: q the input positions, p the output (J × 3 doubles). prev is the previous
 * frame's output or NULL (directions for bones whose input has none). */
static void rigid_frame(const affect_motion *m, const rigid_plan *pl,
                        const affect_rigid_options *opt, double size, const double *q,
                        const double *prev, double *p)
{
    uint32_t nj = m->n_joints;
    double min_len = BONE_MIN_REL * size;
    for (uint32_t i = 0; i < nj; i++) { /* start: the input's bone directions, chained */
        uint32_t j = pl->order[i];
        int32_t par = m->parents[j];
        double *x = p + (size_t)j * 3;
        if (par < 0 || pl->free_link[j]) {
            memcpy(x, q + (size_t)j * 3, 3 * sizeof *x);
            continue;
        }
        const double *xp = p + (size_t)par * 3;
        double d[3];
        for (int a = 0; a < 3; a++)
            d[a] = q[(size_t)j * 3 + a] - q[(size_t)par * 3 + a];
        double nd = norm3(d);
        if (nd <= min_len && prev) {
            for (int a = 0; a < 3; a++)
                d[a] = prev[(size_t)j * 3 + a] - prev[(size_t)par * 3 + a];
            nd = norm3(d);
        }
        if (nd <= min_len) {
            d[0] = 0, d[1] = 1, d[2] = 0;
            nd = 1;
        }
        for (int a = 0; a < 3; a++)
            x[a] = xp[a] + pl->len[j] * d[a] / nd;
    }
    double tol = opt->tolerance * size;
    for (uint32_t sweep = 0; sweep < opt->max_sweeps; sweep++) {
        double moved = 0;
        for (uint32_t i = 0; i < nj; i++) {
            uint32_t j = pl->order[i];
            int32_t par = m->parents[j];
            uint32_t s0 = pl->sub.start[j], s1 = pl->sub.start[j + 1];
            double c[3] = {0, 0, 0}, d[3];
            const double *xj = p + (size_t)j * 3;
            for (uint32_t k = s0; k < s1; k++) {
                uint32_t jk = pl->sub.list[k];
                for (int a = 0; a < 3; a++)
                    c[a] += q[(size_t)jk * 3 + a] - p[(size_t)jk * 3 + a];
            }
            if (par < 0 || pl->free_link[j]) { /* a rigid part's translation: its mean residual */
                for (int a = 0; a < 3; a++)
                    d[a] = c[a] / (double)(s1 - s0);
            } else {
                if (pl->len[j] <= min_len)
                    continue;
                const double *xp = p + (size_t)par * 3;
                for (int a = 0; a < 3; a++)
                    c[a] += (double)(s1 - s0) * (xj[a] - xp[a]);
                double nc = norm3(c);
                if (!(nc > 0))
                    continue;
                for (int a = 0; a < 3; a++)
                    d[a] = xp[a] + pl->len[j] * c[a] / nc - xj[a];
            }
            moved = fmax(moved, norm3(d));
            shift_part(&pl->sub, j, d, p);
        }
        if (moved <= tol)
            break;
    }
}

/* Rigid positions of every frame of m into out (T × J × 3 doubles). */
static affect_status rigid_positions(const affect_motion *m, const affect_rigid_options *opt,
                                     rigid_plan *pl, double *out, affect_error *err)
{
    affect_status st = rigid_plan_make(m, opt, pl, err);
    if (st)
        return st;
    size_t nv = (size_t)m->n_joints * 3;
    double *q = affect_malloc_array(nv, sizeof *q);
    if (!q)
        return affect_nomem(err);
    double size = affect_motion_body_size(m);
    for (uint32_t t = 0; t < m->n_frames; t++) {
        if ((st = affect_monitor_check(opt->monitor, err))) /* a frame is ~0.1 ms of work */
            break;
        const float *src = affect_motion_at(m, t, 0);
        for (size_t i = 0; i < nv; i++)
            q[i] = src[i];
        rigid_frame(m, pl, opt, size, q, t ? out + (t - 1) * nv : NULL, out + t * nv);
    }
    affect_free(q);
    return st;
}

/* Rounds one frame of rigid positions (doubles) to float32, parents first, choosing for every
 * bone's lower joint among the float neighbours of its exact position (the nearest float and
 * up to ROUND_STEPS steps either way on each axis) the one whose distance to the already rounded
 * parent is closest to the bone's length: rounding alone would leave length errors of a few float
 * steps (2e-6 relative on a 10 cm bone 1.7 m from the origin); the chosen joint moves at most
 * ROUND_STEPS float steps further than nearest rounding. */
static void round_rigid_frame(const affect_motion *m, const rigid_plan *pl, const double *p,
                              float *o)
{
    for (uint32_t i = 0; i < m->n_joints; i++) {
        uint32_t j = pl->order[i];
        int32_t par = m->parents[j];
        const double *x = p + (size_t)j * 3;
        float *y = o + (size_t)j * 3;
        for (int a = 0; a < 3; a++)
            y[a] = (float)x[a];
        if (par < 0 || pl->free_link[j])
            continue;
        const float *yp = o + (size_t)par * 3;
        float cand[3][2 * ROUND_STEPS + 1], best[3];
        for (int a = 0; a < 3; a++) {
            cand[a][ROUND_STEPS] = y[a];
            for (int k = 1; k <= ROUND_STEPS; k++) {
                cand[a][ROUND_STEPS - k] = nextafterf(cand[a][ROUND_STEPS - k + 1], -INFINITY);
                cand[a][ROUND_STEPS + k] = nextafterf(cand[a][ROUND_STEPS + k - 1], INFINITY);
            }
        }
        double best_err = INFINITY, best_move = INFINITY;
        const int w = 2 * ROUND_STEPS + 1;
        for (int c = 0; c < w * w * w; c++) {
            float v[3] = {cand[0][c % w], cand[1][(c / w) % w], cand[2][c / (w * w)]};
            double d[3] = {(double)v[0] - yp[0], (double)v[1] - yp[1], (double)v[2] - yp[2]};
            double e = fabs(norm3(d) - pl->len[j]);
            double mv = fabs(v[0] - x[0]) + fabs(v[1] - x[1]) + fabs(v[2] - x[2]);
            if (e < best_err || (e == best_err && mv < best_move)) {
                best_err = e;
                best_move = mv;
                memcpy(best, v, sizeof best);
            }
        }
        memcpy(y, best, sizeof best);
    }
}

affect_status affect_motion_rigid(const affect_motion *m, const affect_rigid_options *opt,
                                  affect_motion **out, affect_error *err)
{
    affect_rigid_options def;
    if (!opt) {
        affect_rigid_options_default(&def);
        opt = &def;
    }
    if (opt->model == AFFECT_RIGID_SKELETON) {
        affect_ik_options io;
        affect_ik_options_default(&io);
        io.rigid = *opt;
        io.rigid.model = AFFECT_RIGID_BONES;
        return affect_motion_ik(m, &io, out, err);
    }
    size_t nv = (size_t)m->n_frames * m->n_joints * 3;
    double *pos = affect_malloc_array(nv, sizeof *pos);
    affect_motion *c = NULL;
    rigid_plan pl;
    memset(&pl, 0, sizeof pl);
    affect_status st = pos ? rigid_positions(m, opt, &pl, pos, err) : affect_nomem(err);
    if (!st)
        st = affect_motion_clone(m, &c, err);
    if (!st) {
        affect_motion_drop_skeleton(c);
        size_t per = (size_t)m->n_joints * 3;
        for (uint32_t t = 0; t < m->n_frames && !st; t++) {
            if (t % 256 == 0) /* a frame is ~5 µs of work */
                st = affect_monitor_check(opt->monitor, err);
            if (!st)
                round_rigid_frame(m, &pl, pos + t * per, c->pos + t * per);
        }
        if (st)
            affect_motion_free(c);
        else
            *out = c;
    }
    rigid_plan_free(&pl);
    affect_free(pos);
    return st;
}

/* ---- inverse kinematics ---- */

/* Eigenvalues (descending) and the eigenvector of the largest of a symmetric 4×4 matrix. */
static void sym4_top(double a[16], double lambda[4], double v0[4])
{
    double v[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    for (int sweep = 0; sweep < JACOBI_MAX_SWEEPS; sweep++) {
        double off = 0, diag = 0;
        for (int i = 0; i < 4; i++) {
            diag += a[i * 4 + i] * a[i * 4 + i];
            for (int j = i + 1; j < 4; j++)
                off += a[i * 4 + j] * a[i * 4 + j];
        }
        if (off <= 1e-30 * (diag + off) || off == 0)
            break;
        for (int p = 0; p < 3; p++)
            for (int q = p + 1; q < 4; q++) {
                double apq = a[p * 4 + q];
                if (apq == 0)
                    continue;
                double theta = (a[q * 4 + q] - a[p * 4 + p]) / (2 * apq);
                double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 4; k++) { /* A ← A J (columns p, q) */
                    double akp = a[k * 4 + p], akq = a[k * 4 + q];
                    a[k * 4 + p] = c * akp - s * akq;
                    a[k * 4 + q] = s * akp + c * akq;
                }
                for (int k = 0; k < 4; k++) { /* A ← Jᵀ A (rows p, q) */
                    double apk = a[p * 4 + k], aqk = a[q * 4 + k];
                    a[p * 4 + k] = c * apk - s * aqk;
                    a[q * 4 + k] = s * apk + c * aqk;
                }
                for (int k = 0; k < 4; k++) {
                    double vkp = v[k * 4 + p], vkq = v[k * 4 + q];
                    v[k * 4 + p] = c * vkp - s * vkq;
                    v[k * 4 + q] = s * vkp + c * vkq;
                }
            }
    }
    int idx[4] = {0, 1, 2, 3};
    for (int i = 0; i < 4; i++) /* sort indices by eigenvalue, descending */
        for (int j = i + 1; j < 4; j++)
            if (a[idx[j] * 5] > a[idx[i] * 5]) {
                int t = idx[i];
                idx[i] = idx[j];
                idx[j] = t;
            }
    for (int i = 0; i < 4; i++) {
        lambda[i] = a[idx[i] * 5];
        v0[i] = v[i * 4 + idx[0]];
    }
}

/* Best-fit rotation q with b_c ≈ q r_c q⁻¹ (Horn 1987); false when it is not determined (the
 * children collinear). */
static bool horn(const double *r, const double *b, uint32_t n, double q[4])
{
    double S[9] = {0};
    double scale = 0;
    for (uint32_t c = 0; c < n; c++) {
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                S[i * 3 + k] += r[c * 3 + i] * b[c * 3 + k];
        scale += norm3(r + c * 3) * norm3(b + c * 3);
    }
    double sxx = S[0], sxy = S[1], sxz = S[2], syx = S[3], syy = S[4], syz = S[5], szx = S[6],
           szy = S[7], szz = S[8];
    double N[16] = {sxx + syy + szz, syz - szy,       szx - sxz,        sxy - syx,
                    syz - szy,       sxx - syy - szz, sxy + syx,        szx + sxz,
                    szx - sxz,       sxy + syx,       -sxx + syy - szz, syz + szy,
                    sxy - syx,       szx + sxz,       syz + szy,        -sxx - syy + szz};
    double lambda[4];
    sym4_top(N, lambda, q);
    affect_quat_normalize(q);
    return lambda[0] - lambda[1] > IK_EIGEN_GAP_REL * scale;
}

typedef struct ik_work {
    double *g;           /* rigid positions, T × J × 3 */
    double *shape, *acc; /* a sibling group's mean shape and its running sum (J × 3 each) */
    uint32_t *kids;      /* a joint's bone children (J) */
    bool *moved;         /* joints placed by a translation channel: roots, free links, and
                            with AFFECT_IK_SIBLINGS_TRANSLATE the children of sibling groups */
    double *prevq;       /* previous frame's local rotation per joint, J × 4 */
    double *wrot, *fpos; /* this frame's world rotations (J × 4) and FK positions (J × 3) */
    double *r, *b;       /* rest and current child vectors of one joint (J × 3 each) */
} ik_work;

/* Local rotation of joint j at one frame from its bone children (see affect_motion_ik). */
static void ik_joint(const affect_motion *out, const rigid_plan *pl, const double *g, uint32_t j,
                     const double *wpar_inv, ik_work *w, double min_len, double q[4])
{
    uint32_t n = 0;
    for (uint32_t k = pl->ch.start[j]; k < pl->ch.start[j + 1]; k++) {
        uint32_t c = pl->ch.list[k];
        const double *o = out->skel[c].offset;
        if (pl->free_link[c] || norm3(o) <= min_len)
            continue;
        double v[3];
        for (int a = 0; a < 3; a++)
            v[a] = g[(size_t)c * 3 + a] - w->fpos[(size_t)j * 3 + a];
        affect_quat_rotate(wpar_inv, v, w->b + (size_t)n * 3);
        memcpy(w->r + (size_t)n * 3, o, 3 * sizeof *o);
        n++;
    }
    double *prev = w->prevq + (size_t)j * 4;
    if (n == 0) {
        q[0] = 1, q[1] = q[2] = q[3] = 0;
        return;
    }
    if (n >= 2 && horn(w->r, w->b, n, q)) {
        if (q[0] * prev[0] + q[1] * prev[1] + q[2] * prev[2] + q[3] * prev[3] < 0)
            for (int i = 0; i < 4; i++)
                q[i] = -q[i];
        return;
    }
    /* one child, or collinear children: the smallest turn from the previous frame's rotation */
    double rs[3] = {0, 0, 0}, bs[3] = {0, 0, 0}, rp[3], turn[4];
    for (uint32_t c = 0; c < n; c++)
        for (int a = 0; a < 3; a++) {
            rs[a] += w->r[c * 3 + a];
            bs[a] += w->b[c * 3 + a];
        }
    affect_quat_rotate(prev, rs, rp);
    if (norm3(rp) <= min_len || norm3(bs) <= min_len) {
        memcpy(q, prev, 4 * sizeof *q);
        return;
    }
    affect_quat_between(rp, bs, turn);
    affect_quat_mul(turn, prev, q);
    affect_quat_normalize(q);
}

/* The rest offsets of every joint's bone children when it has several: their mean shape over
 * the frames (generalized Procrustes: each frame's child vectors turned onto the current shape
 * by the best-fit rotation, averaged, rescaled to the bone lengths; a few rounds), turned to
 * the rest frame's orientation. One frame's configuration would fit the others badly wherever
 * the siblings' angles vary (positions averaged or synthesized rather than captured). */
static void ik_mean_shapes(const affect_motion *m, const rigid_plan *pl, const double *g,
                           double min_len, ik_work *w, affect_motion *out)
{
    uint32_t nj = m->n_joints;
    size_t nv = (size_t)nj * 3;
    for (uint32_t j = 0; j < nj; j++) {
        uint32_t n = 0;
        for (uint32_t k = pl->ch.start[j]; k < pl->ch.start[j + 1]; k++) {
            uint32_t c = pl->ch.list[k];
            if (!pl->free_link[c] && norm3(out->skel[c].offset) > min_len)
                w->kids[n++] = c;
        }
        if (n < 2)
            continue;
        for (uint32_t i = 0; i < n; i++)
            memcpy(w->shape + (size_t)i * 3, out->skel[w->kids[i]].offset, 3 * sizeof(double));
        for (int round = 0; round < IK_SHAPE_ROUNDS; round++) {
            memset(w->acc, 0, (size_t)n * 3 * sizeof *w->acc);
            uint32_t used = 0;
            for (uint32_t t = 0; t < m->n_frames; t++) {
                const double *gt = g + t * nv;
                for (uint32_t i = 0; i < n; i++)
                    for (int a = 0; a < 3; a++)
                        w->b[i * 3 + a] = gt[(size_t)w->kids[i] * 3 + a] - gt[(size_t)j * 3 + a];
                double q[4], inv[4], v[3];
                if (!horn(w->shape, w->b, n, q))
                    continue;
                qconj(q, inv);
                for (uint32_t i = 0; i < n; i++) {
                    affect_quat_rotate(inv, w->b + (size_t)i * 3, v);
                    for (int a = 0; a < 3; a++)
                        w->acc[i * 3 + a] += v[a];
                }
                used++;
            }
            if (!used)
                break;
            for (uint32_t i = 0; i < n; i++) {
                double len = norm3(out->skel[w->kids[i]].offset),
                       na = norm3(w->acc + (size_t)i * 3);
                if (na > 0)
                    for (int a = 0; a < 3; a++)
                        w->shape[i * 3 + a] = w->acc[i * 3 + a] * len / na;
            }
        }
        /* turn the shape onto the rest frame's configuration */
        double q[4];
        for (uint32_t i = 0; i < n; i++)
            memcpy(w->b + (size_t)i * 3, out->skel[w->kids[i]].offset, 3 * sizeof(double));
        if (!horn(w->shape, w->b, n, q))
            continue;
        for (uint32_t i = 0; i < n; i++)
            affect_quat_rotate(q, w->shape + (size_t)i * 3, out->skel[w->kids[i]].offset);
    }
}

/* Offsets from the rest frame's rigid pose; leaves named "<parent>_end" become End Sites. */
static void ik_offsets(const affect_motion *m, const rigid_plan *pl, const double *rest,
                       affect_motion *out)
{
    for (uint32_t j = 0; j < m->n_joints; j++) {
        affect_skel_joint *s = &out->skel[j];
        int32_t p = m->parents[j];
        for (int a = 0; a < 3; a++)
            s->offset[a] = rest[(size_t)j * 3 + a] - (p >= 0 ? rest[(size_t)p * 3 + a] : 0);
        bool leaf = pl->ch.start[j] == pl->ch.start[j + 1];
        size_t lp = p >= 0 ? strlen(m->names[p]) : 0;
        if (leaf && p >= 0 && !pl->free_link[j] && strlen(m->names[j]) == lp + 4 &&
            strncmp(m->names[j], m->names[p], lp) == 0 && strcmp(m->names[j] + lp, "_end") == 0)
            s->flags = AFFECT_JOINT_END_SITE;
    }
}

/* The bone children of j (not free, offset longer than min_len) into w->kids; their count. */
static uint32_t bone_children(const rigid_plan *pl, const affect_motion *out, uint32_t j,
                              double min_len, uint32_t *kids)
{
    uint32_t n = 0;
    for (uint32_t k = pl->ch.start[j]; k < pl->ch.start[j + 1]; k++) {
        uint32_t c = pl->ch.list[k];
        if (!pl->free_link[c] && norm3(out->skel[c].offset) > min_len)
            kids[n++] = c;
    }
    return n;
}

/* Largest distance over the frames between a sibling group's rigid positions and its rest
 * offsets turned by the best-fit rotation (the shape is in w->shape). */
static double group_residual(const affect_motion *m, const double *g, uint32_t j, uint32_t n,
                             ik_work *w)
{
    size_t nv = (size_t)m->n_joints * 3;
    double worst = 0;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        const double *gt = g + t * nv;
        for (uint32_t i = 0; i < n; i++)
            for (int a = 0; a < 3; a++)
                w->b[i * 3 + a] = gt[(size_t)w->kids[i] * 3 + a] - gt[(size_t)j * 3 + a];
        double q[4], v[3];
        if (!horn(w->shape, w->b, n, q))
            continue;
        for (uint32_t i = 0; i < n; i++) {
            affect_quat_rotate(q, w->shape + (size_t)i * 3, v);
            for (int a = 0; a < 3; a++)
                v[a] -= w->b[i * 3 + a];
            worst = fmax(worst, norm3(v));
        }
    }
    return worst;
}

/* Which joints get position channels: roots and free links; the bone children of a joint
 * with several when asked (AFFECT_IK_SIBLINGS_TRANSLATE), or when rotations alone would miss
 * their positions by more than IK_SIBLING_TOL_REL of the body size (AFFECT_IK_SIBLINGS_AUTO).
 * End Sites never (they have no channels). */
static void ik_mark_moved(const affect_motion *m, const rigid_plan *pl,
                          const affect_ik_options *opt, const double *g, double min_len, ik_work *w,
                          const affect_motion *out)
{
    double tol = IK_SIBLING_TOL_REL * affect_motion_body_size(m);
    for (uint32_t j = 0; j < m->n_joints; j++)
        w->moved[j] = m->parents[j] < 0 || pl->free_link[j];
    if (opt->siblings == AFFECT_IK_SIBLINGS_ROTATE)
        return;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        uint32_t n = bone_children(pl, out, j, min_len, w->kids);
        if (n < 2)
            continue;
        if (opt->siblings == AFFECT_IK_SIBLINGS_AUTO) {
            for (uint32_t i = 0; i < n; i++)
                memcpy(w->shape + (size_t)i * 3, out->skel[w->kids[i]].offset, 3 * sizeof(double));
            if (group_residual(m, g, j, n, w) <= tol)
                continue;
        }
        for (uint32_t i = 0; i < n; i++)
            if (!(out->skel[w->kids[i]].flags & AFFECT_JOINT_END_SITE))
                w->moved[w->kids[i]] = true;
    }
}

/* Channels: position channels for the joints placed by translation, rotations for every joint
 * that is not an End Site. */
static void ik_channels(const affect_motion *m, const affect_ik_options *opt, const bool *moved,
                        affect_motion *out)
{
    for (uint32_t j = 0; j < m->n_joints; j++) {
        affect_skel_joint *s = &out->skel[j];
        if (s->flags & AFFECT_JOINT_END_SITE)
            continue;
        int c = 0;
        if (moved[j])
            for (int a = 0; a < 3; a++)
                s->channel[c++] = (uint8_t)(AFFECT_CH_XPOS + a);
        for (int a = 0; a < 3; a++)
            s->channel[c++] = (uint8_t)(AFFECT_CH_XROT + opt->order[a]);
        s->n_channels = (uint8_t)c;
    }
}

affect_status affect_motion_ik(const affect_motion *m, const affect_ik_options *opt,
                               affect_motion **out, affect_error *err)
{
    affect_ik_options def;
    if (!opt) {
        affect_ik_options_default(&def);
        opt = &def;
    }
    if (opt->rest_frame >= m->n_frames)
        return affect_fail(err, AFFECT_ERR_RANGE,
                           "rest frame %u out of range (the motion has %u frames)", opt->rest_frame,
                           m->n_frames);
    uint32_t nj = m->n_joints;
    size_t nv = (size_t)nj * 3;
    ik_work w = {0};
    affect_motion *c = NULL;
    rigid_plan pl;
    memset(&pl, 0, sizeof pl);
    void *block = NULL;
    affect_ws_part parts[] = {{(void **)&w.prevq, (size_t)nj * 4, sizeof(double)},
                              {(void **)&w.wrot, (size_t)nj * 4, sizeof(double)},
                              {(void **)&w.fpos, nv, sizeof(double)},
                              {(void **)&w.r, nv, sizeof(double)},
                              {(void **)&w.b, nv, sizeof(double)},
                              {(void **)&w.shape, nv, sizeof(double)},
                              {(void **)&w.acc, nv, sizeof(double)},
                              {(void **)&w.kids, nj, sizeof(uint32_t)},
                              {(void **)&w.moved, nj, sizeof(bool)}};
    affect_status st;
    w.g = affect_malloc_array((size_t)m->n_frames * nv, sizeof *w.g);
    block = affect_ws_alloc(parts, 9);
    if (!w.g || !block) {
        st = affect_nomem(err);
        goto done;
    }
    if ((st = rigid_positions(m, &opt->rigid, &pl, w.g, err)) ||
        (st = affect_motion_clone(m, &c, err)) || (st = affect_motion_add_skeleton(c, true, err)))
        goto done;
    double min_len = BONE_MIN_REL * affect_motion_body_size(m);
    ik_offsets(m, &pl, w.g + (size_t)opt->rest_frame * nv, c);
    if ((st = affect_monitor_check(opt->rigid.monitor, err)))
        goto done;
    ik_mean_shapes(m, &pl, w.g, min_len, &w, c);
    if ((st = affect_monitor_check(opt->rigid.monitor, err)))
        goto done;
    ik_mark_moved(m, &pl, opt, w.g, min_len, &w, c);
    if ((st = affect_monitor_check(opt->rigid.monitor, err)))
        goto done;
    ik_channels(m, opt, w.moved, c);
    for (uint32_t j = 0; j < nj; j++)
        w.prevq[j * 4] = 1, w.prevq[j * 4 + 1] = w.prevq[j * 4 + 2] = w.prevq[j * 4 + 3] = 0;
    for (uint32_t t = 0; t < m->n_frames; t++) {
        if ((st = affect_monitor_check(opt->rigid.monitor, err)))
            goto done;
        const double *g = w.g + t * nv;
        for (uint32_t i = 0; i < nj; i++) {
            uint32_t j = pl.order[i];
            int32_t p = m->parents[j];
            double inv[4] = {1, 0, 0, 0}, q[4];
            float *tr = c->trans + ((size_t)t * nj + j) * 3;
            if (p >= 0)
                qconj(w.wrot + (size_t)p * 4, inv);
            if (p < 0 || w.moved[j]) { /* translated: its own rigid position */
                double v[3];
                for (int a = 0; a < 3; a++) {
                    w.fpos[(size_t)j * 3 + a] = g[(size_t)j * 3 + a];
                    v[a] = g[(size_t)j * 3 + a] - (p >= 0 ? w.fpos[(size_t)p * 3 + a] : 0);
                }
                affect_quat_rotate(inv, v, v);
                for (int a = 0; a < 3; a++)
                    tr[a] = (float)v[a];
            } else {
                double v[3];
                affect_quat_rotate(w.wrot + (size_t)p * 4, c->skel[j].offset, v);
                for (int a = 0; a < 3; a++) {
                    w.fpos[(size_t)j * 3 + a] = w.fpos[(size_t)p * 3 + a] + v[a];
                    tr[a] = (float)c->skel[j].offset[a];
                }
            }
            ik_joint(c, &pl, g, j, inv, &w, min_len, q);
            memcpy(w.prevq + (size_t)j * 4, q, sizeof q);
            float *qo = c->rot + ((size_t)t * nj + j) * 4;
            for (int a = 0; a < 4; a++)
                qo[a] = (float)q[a];
            if (p >= 0)
                affect_quat_mul(w.wrot + (size_t)p * 4, q, w.wrot + (size_t)j * 4);
            else
                memcpy(w.wrot + (size_t)j * 4, q, sizeof q);
        }
    }
    if ((st = affect_monitor_check(opt->rigid.monitor, err)) || (st = affect_motion_fk(c, err)))
        goto done;
    *out = c;
    c = NULL;
done:
    affect_motion_free(c);
    rigid_plan_free(&pl);
    affect_free(w.g);
    affect_free(block);
    return st;
}

affect_status affect_motion_skeletal(const affect_motion *m, affect_rotation_source source,
                                     const affect_ik_options *opt, affect_motion **made,
                                     affect_error *err)
{
    *made = NULL;
    if (m->rot && source != AFFECT_ROTATIONS_IK) {
        double dist;
        uint32_t frame, joint;
        affect_status st = fk_error(m, &dist, &frame, &joint, opt ? opt->rigid.monitor : NULL, err);
        if (st)
            return st;
        if (dist <= AFFECT_STORED_FK_TOL_REL * affect_motion_body_size(m))
            return AFFECT_OK;
        return affect_fail(
            err, AFFECT_ERR_INVALID,
            "the stored rotations do not reproduce the positions (joint %u \"%.64s\", "
            "frame %u: %g apart); use {\"rotations\":\"ik\"} to rebuild them",
            joint, m->names[joint], frame, dist);
    }
    if (source == AFFECT_ROTATIONS_STORED)
        return affect_fail(err, AFFECT_ERR_INVALID,
                           "the motion has no stored rotations (it was not imported from BVH); use "
                           "{\"rotations\":\"auto\"} or \"ik\"");
    return affect_motion_ik(m, opt, made, err);
}

/* ---- angles ---- */

void affect_motion_joint_angles(const affect_motion *m, uint32_t t, uint32_t j, const int order[3],
                                const double *prev, double q[4], double deg[3], double *speed)
{
    uint32_t nj = m->n_joints;
    qload(m->rot + ((size_t)t * nj + j) * 4, q);
    affect_quat_normalize(q);
    affect_quat_to_euler_deg(q, order, prev, deg);
    uint32_t a = t > 0 ? t - 1 : t, b = t + 1 < m->n_frames ? t + 1 : t;
    if (a == b) {
        *speed = 0;
        return;
    }
    double qa[4], qb[4], inv[4], d[4];
    qload(m->rot + ((size_t)a * nj + j) * 4, qa);
    qload(m->rot + ((size_t)b * nj + j) * 4, qb);
    affect_quat_normalize(qa);
    affect_quat_normalize(qb);
    qconj(qa, inv);
    affect_quat_mul(inv, qb, d);
    *speed = affect_quat_angle(d) * m->fps / (double)(b - a);
}
