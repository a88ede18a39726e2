/*
 * fuzz_motion_v2.c — libFuzzer target for skeletal motions (motion BLOB version 2, BVH export
 * and import; affect/motion.h, affect/io.h, affect/skeleton.h).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_motion_v2 -max_total_time=60 <a copy of
 * tests/fuzz/corpus/fuzz_motion_v2>
 *
 * Unlike fuzz_blob, which feeds raw bytes to the decoder (and so rarely gets past its checks
 * into a valid skeleton), this target reads the input as a recipe for a valid skeletal motion
 * and checks what is done with it. The recipe, byte by byte (a missing byte reads as 0):
 *   joint count 1 + b % 8, frame count 1 + b % 4, frame rate one of six;
 *   per generated joint i > 0 its parent b % (i + 1) − 1 (−1: another root) among the earlier
 *   ones, then a permutation of the joint indices (so parents need not precede children);
 *   per joint: a flags byte (bit 0: an End Site when it is a leaf with a parent and its parent
 *   has no End Site yet; bits 1–3: negative zero for a zero offset x, y, z), a channel count
 *   b % 7 and six bytes choosing a permutation of the six channel types (the first count are
 *   the joint's), the offset as three int16 / 64;
 *   per frame: a byte whose bit j negates joint j's quaternion (q and −q are one rotation),
 *   then per joint, in joint order, one int16 / 64 per channel in channel order: degrees for
 *   a rotation channel (the rotation is the product of the joint's channel rotations, so BVH
 *   can express it), the translation component for a position channel (the components no
 *   channel names are the offset's).
 * Seeds (tests/fuzz/corpus/fuzz_motion_v2): fixture_like.bin follows this recipe to build the
 * skeleton and frames of tests/fixtures/motion-v2.bin; two_roots.bin has two roots, a
 * two-rotation-channel joint and no position channel; one_joint.bin is the smallest motion;
 * random_96.bin and random_320.bin are bytes of Python's random.Random(20240501).
 * The positions are the forward kinematics (affect_motion_fk). Checks, each abort()ing:
 *   1. the motion validates; encode → decode gives every field back bit for bit (skeleton,
 *      rotations, translations, positions) and encode of that gives the same bytes, a
 *      version-2 BLOB with flags 3; the FK of the decoded motion is its positions;
 *   2. without its skeleton it encodes as version 1 and decodes to the same positions;
 *   3. affect_bvh_write → affect_bvh_parse succeeds and gives the same joints (by name: an
 *      End Site becomes "<parent>_end"), parents, channels, End Sites and offsets, the same
 *      local rotations (up to sign, 1e-4 per component), translations within 1e-5, and
 *      positions within 1e-4 + 1e-4 × the joint's reach (the sum of the translation lengths
 *      from its root down to it, the most a rotation error can be multiplied by);
 *   4. slice and resample keep the skeleton, give positions that are the FK of their
 *      rotations (within 1e-5 × (1 + reach)), validate and round-trip through the BLOB.
 */
#include "affect/io.h"
#include "affect/quat.h"
#include "affect/skeleton.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_J 8u

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct reader {
    const uint8_t *p;
    size_t n;
} reader;

static uint8_t rd8(reader *r)
{
    if (!r->n)
        return 0;
    r->n--;
    return *r->p++;
}

/* int16 / 64: multiples of 1/64 in [−512, 512), exact in float and in six decimals */
static double rdfix(reader *r)
{
    uint16_t lo = rd8(r), hi = rd8(r);
    return (int16_t)(uint16_t)(lo | (hi << 8)) / 64.0;
}

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "fuzz_motion_v2: check failed at line %d: %s\n", __LINE__, #cond);     \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

/* Builds the motion the recipe describes; NULL only when memory runs out. */
static affect_motion *build(reader *r)
{
    static const double rates[6] = {24, 25, 30, 60, 119.88, 1000};
    uint32_t nj = 1 + rd8(r) % MAX_J, nf = 1 + rd8(r) % 4;
    double fps = rates[rd8(r) % 6];
    int32_t gen_parent[MAX_J];
    uint32_t perm[MAX_J];
    for (uint32_t i = 0; i < nj; i++) {
        gen_parent[i] = i == 0 ? -1 : (int32_t)(rd8(r) % (i + 1)) - 1;
        perm[i] = i;
    }
    for (uint32_t i = nj; i-- > 1;) {
        uint32_t k = rd8(r) % (i + 1), tmp = perm[i];
        perm[i] = perm[k];
        perm[k] = tmp;
    }
    affect_motion *m = NULL;
    affect_error err;
    if (affect_motion_create(nf, nj, fps, &m, &err))
        return NULL;
    if (affect_motion_set_unit(m, "cm", &err) || affect_motion_add_skeleton(m, true, &err)) {
        affect_motion_free(m);
        return NULL;
    }
    for (uint32_t i = 0; i < nj; i++)
        m->parents[perm[i]] = gen_parent[i] < 0 ? -1 : (int32_t)perm[gen_parent[i]];
    bool has_child[MAX_J] = {false}, has_end[MAX_J] = {false};
    for (uint32_t j = 0; j < nj; j++)
        if (m->parents[j] >= 0)
            has_child[m->parents[j]] = true;
    for (uint32_t j = 0; j < nj; j++) {
        affect_skel_joint *s = &m->skel[j];
        uint8_t flags = rd8(r);
        int32_t p = m->parents[j];
        uint8_t n_ch = rd8(r) % 7;
        uint8_t types[6] = {0, 1, 2, 3, 4, 5};
        for (int i = 5; i >= 0; i--) {
            int k = rd8(r) % (i + 1);
            uint8_t tmp = types[i];
            types[i] = types[k];
            types[k] = tmp;
        }
        for (int a = 0; a < 3; a++) {
            s->offset[a] = rdfix(r);
            if (s->offset[a] == 0 && (flags & (2u << a)))
                s->offset[a] = -0.0;
        }
        if ((flags & 1) && p >= 0 && !has_child[j] && !has_end[p]) {
            s->flags = AFFECT_JOINT_END_SITE;
            has_end[p] = true;
            continue;
        }
        s->n_channels = n_ch;
        memcpy(s->channel, types, n_ch);
    }
    for (uint32_t t = 0; t < nf; t++) {
        uint8_t negate = rd8(r);
        for (uint32_t j = 0; j < nj; j++) {
            const affect_skel_joint *s = &m->skel[j];
            double q[4] = {1, 0, 0, 0}, tr[3] = {s->offset[0], s->offset[1], s->offset[2]};
            for (int c = 0; c < s->n_channels; c++) {
                double v = rdfix(r);
                if (s->channel[c] <= AFFECT_CH_ZPOS) {
                    tr[s->channel[c]] = v;
                } else {
                    double h = v * (3.14159265358979323846 / 360.0), a[4] = {cos(h), 0, 0, 0};
                    a[1 + s->channel[c] - AFFECT_CH_XROT] = sin(h);
                    affect_quat_mul(q, a, q);
                }
            }
            affect_quat_normalize(q);
            float *qo = m->rot + ((size_t)t * nj + j) * 4,
                  *to = m->trans + ((size_t)t * nj + j) * 3;
            for (int i = 0; i < 4; i++)
                qo[i] = (float)((negate >> j) & 1 ? -q[i] : q[i]);
            for (int a = 0; a < 3; a++)
                to[a] = (float)tr[a];
        }
    }
    for (uint32_t j = 0; j < nj; j++) {
        char name[16];
        int len = snprintf(name, sizeof name, "j%u", j);
        if (affect_motion_set_name(m, j, name, (size_t)len, &err)) {
            affect_motion_free(m);
            return NULL;
        }
    }
    if (affect_motion_fk(m, &err)) {
        CHECK(err.status == AFFECT_ERR_NOMEM);
        affect_motion_free(m);
        return NULL;
    }
    return m;
}

/* Largest distance from joint j's root to it along the translations it uses, over frames. */
static double reach(const affect_motion *m, uint32_t j)
{
    double total = 0;
    for (int32_t k = (int32_t)j; k >= 0; k = m->parents[k]) {
        double most = 0;
        for (uint32_t t = 0; t < m->n_frames; t++) {
            const float *tr = m->trans + ((size_t)t * m->n_joints + (uint32_t)k) * 3;
            const double *o = m->skel[k].offset;
            bool pos = affect_skel_has_position(&m->skel[k]);
            double len =
                pos ? sqrt((double)tr[0] * tr[0] + (double)tr[1] * tr[1] + (double)tr[2] * tr[2])
                    : sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
            most = len > most ? len : most;
        }
        total += most;
    }
    return total;
}

static double max_reach(const affect_motion *m)
{
    double most = 0;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        double r = reach(m, j);
        most = r > most ? r : most;
    }
    return most;
}

static void check_same(const affect_motion *a, const affect_motion *b)
{
    size_t nj = a->n_joints, n = (size_t)a->n_frames * nj;
    CHECK(a->n_frames == b->n_frames && a->n_joints == b->n_joints);
    CHECK(memcmp(&a->fps, &b->fps, sizeof a->fps) == 0 && strcmp(a->unit, b->unit) == 0);
    for (size_t j = 0; j < nj; j++)
        CHECK(strcmp(a->names[j], b->names[j]) == 0 && a->parents[j] == b->parents[j]);
    CHECK(memcmp(a->pos, b->pos, n * 3 * sizeof(float)) == 0);
    CHECK(a->skel && b->skel && memcmp(a->skel, b->skel, nj * sizeof *a->skel) == 0);
    CHECK(a->rot && b->rot && memcmp(a->rot, b->rot, n * 4 * sizeof(float)) == 0);
    CHECK(memcmp(a->trans, b->trans, n * 3 * sizeof(float)) == 0);
}

/* encode → decode → encode; the decoded motion in *back (NULL when memory ran out). */
static void check_blob(const affect_motion *m, affect_motion **back)
{
    affect_error err;
    unsigned char *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    *back = NULL;
    if (affect_motion_encode(m, &a, &na, &err) != AFFECT_OK) {
        CHECK(err.status == AFFECT_ERR_NOMEM);
        return;
    }
    CHECK(na >= 8 && memcmp(a, "AFMO\x02\x00", 6) == 0 && a[6] == 3 && a[7] == 0);
    affect_status st = affect_motion_decode(a, na, back, &err);
    if (st != AFFECT_OK) {
        if (st != AFFECT_ERR_NOMEM)
            fprintf(stderr, "decode of an encoded valid motion failed: %s\n", err.msg);
        CHECK(st == AFFECT_ERR_NOMEM);
        affect_free(a);
        return;
    }
    check_same(m, *back);
    if (affect_motion_encode(*back, &b, &nb, &err) == AFFECT_OK)
        CHECK(na == nb && memcmp(a, b, na) == 0);
    affect_free(a);
    affect_free(b);
}

/* Without its skeleton: version 1, same positions. */
static void check_v1(const affect_motion *m)
{
    affect_error err;
    affect_motion *c = NULL, *back = NULL;
    unsigned char *a = NULL;
    size_t na = 0;
    if (affect_motion_clone(m, &c, &err))
        return;
    affect_motion_drop_skeleton(c);
    if (affect_motion_encode(c, &a, &na, &err) == AFFECT_OK) {
        CHECK(memcmp(a, "AFMO\x01\x00\x00\x00", 8) == 0);
        if (affect_motion_decode(a, na, &back, &err) == AFFECT_OK) {
            CHECK(!back->skel && !back->rot && !back->trans);
            CHECK(memcmp(back->pos, m->pos, (size_t)m->n_frames * m->n_joints * 12) == 0);
        }
    }
    affect_free(a);
    affect_motion_free(back);
    affect_motion_free(c);
}

static int32_t find(const affect_motion *p, const char *name)
{
    return affect_motion_find_joint(p, name);
}

/* The name joint j of m has after a BVH round trip. */
static void bvh_name(const affect_motion *m, uint32_t j, char *out, size_t cap)
{
    if (m->skel[j].flags & AFFECT_JOINT_END_SITE)
        snprintf(out, cap, "%s_end", m->names[m->parents[j]]);
    else
        snprintf(out, cap, "%s", m->names[j]);
}

static void check_bvh(const affect_motion *m)
{
    affect_error err;
    char *text = NULL;
    size_t len = 0;
    if (affect_bvh_write(m, NULL, &text, &len, &err) != AFFECT_OK) {
        if (err.status != AFFECT_ERR_NOMEM)
            fprintf(stderr, "affect_bvh_write failed: %s\n", err.msg);
        CHECK(err.status == AFFECT_ERR_NOMEM);
        return;
    }
    affect_motion *p = NULL;
    affect_bvh_options opt = {1.0, "cm", 0, NULL};
    affect_status st = affect_bvh_parse(text, len, &opt, &p, &err);
    if (st != AFFECT_OK) {
        if (st != AFFECT_ERR_NOMEM)
            fprintf(stderr, "the written BVH does not parse: %s\n%s", err.msg, text);
        CHECK(st == AFFECT_ERR_NOMEM);
        affect_free(text);
        return;
    }
    uint32_t nj = m->n_joints;
    CHECK(p->n_joints == nj && p->n_frames == m->n_frames && p->skel && p->rot);
    int32_t map[MAX_J];
    char name[64];
    for (uint32_t j = 0; j < nj; j++) {
        bvh_name(m, j, name, sizeof name);
        map[j] = find(p, name);
        CHECK(map[j] >= 0);
    }
    bool bad = false;
    for (uint32_t j = 0; j < nj; j++) {
        uint32_t k = (uint32_t)map[j];
        const affect_skel_joint *a = &m->skel[j], *b = &p->skel[k];
        int32_t pa = m->parents[j];
        CHECK(pa < 0 ? p->parents[k] < 0 : p->parents[k] == map[pa]);
        CHECK(a->n_channels == b->n_channels && memcmp(a->channel, b->channel, 6) == 0);
        CHECK(a->flags == b->flags);
        for (int i = 0; i < 3; i++)
            CHECK(fabs(a->offset[i] - b->offset[i]) <= 1e-9);
        double tol = 1e-4 + 1e-4 * reach(m, j);
        for (uint32_t t = 0; t < m->n_frames; t++) {
            const float *qa = m->rot + ((size_t)t * nj + j) * 4,
                        *qb = p->rot + ((size_t)t * nj + k) * 4;
            double dp = 0, dm = 0;
            for (int i = 0; i < 4; i++) {
                dp = fmax(dp, fabs((double)qa[i] - qb[i]));
                dm = fmax(dm, fabs((double)qa[i] + qb[i]));
            }
            const float *ta = m->trans + ((size_t)t * nj + j) * 3,
                        *tb = p->trans + ((size_t)t * nj + k) * 3;
            const float *xa = affect_motion_at(m, t, j), *xb = affect_motion_at(p, t, k);
            double dt = 0, dx = 0;
            for (int i = 0; i < 3; i++) {
                dt = fmax(dt, fabs((double)ta[i] - tb[i]));
                dx = fmax(dx, fabs((double)xa[i] - xb[i]));
            }
            if (fmin(dp, dm) > 1e-4 || dt > 1e-5 || dx > tol) {
                fprintf(stderr,
                        "frame %u joint %u (%s): rotation (%.9g %.9g %.9g %.9g) came back as "
                        "(%.9g %.9g %.9g %.9g); translation off by %g, position off by %g "
                        "(tolerance %g)\n",
                        t, j, m->names[j], qa[0], qa[1], qa[2], qa[3], qb[0], qb[1], qb[2], qb[3],
                        dt, dx, tol);
                bad = true;
            }
        }
    }
    if (bad)
        fprintf(stderr, "%s", text);
    CHECK(!bad);
    affect_free(text);
    affect_motion_free(p);
}

/* An edited motion: skeleton kept, positions the FK of its rotations, valid, round-trips. */
static void check_edited(const affect_motion *src, const affect_motion *e)
{
    affect_error err;
    CHECK(e->skel && e->rot && e->trans);
    CHECK(memcmp(e->skel, src->skel, (size_t)src->n_joints * sizeof *e->skel) == 0);
    CHECK(affect_motion_validate(e, &err) == AFFECT_OK);
    double fk;
    uint32_t ft, fj;
    if (affect_motion_fk_error(e, &fk, &ft, &fj, &err) == AFFECT_OK) {
        double tol = 1e-5 * (1 + max_reach(src));
        if (fk > tol)
            fprintf(stderr, "positions leave the FK by %g (tolerance %g) at frame %u joint %u\n",
                    fk, tol, ft, fj);
        CHECK(fk <= tol);
    }
    affect_motion *back = NULL;
    check_blob(e, &back);
    affect_motion_free(back);
}

static void check_edits(const affect_motion *m, reader *r)
{
    affect_error err;
    affect_motion *e = NULL;
    int64_t first = rd8(r) % m->n_frames;
    int64_t last = first + rd8(r) % (m->n_frames - first);
    if (affect_motion_slice(m, first, last, &e, &err) == AFFECT_OK) {
        CHECK(e->n_frames == (uint32_t)(last - first + 1));
        size_t nj = m->n_joints, n = (size_t)e->n_frames * nj;
        CHECK(memcmp(e->rot, m->rot + (size_t)first * nj * 4, n * 16) == 0);
        CHECK(memcmp(e->trans, m->trans + (size_t)first * nj * 3, n * 12) == 0);
        CHECK(memcmp(e->pos, m->pos + (size_t)first * nj * 3, n * 12) == 0);
        check_edited(m, e);
        affect_motion_free(e);
    }
    static const double factors[4] = {0.5, 1.0, 1.5, 2.5};
    double fps = m->fps * factors[rd8(r) % 4];
    if (affect_motion_resample(m, fps, &e, &err) == AFFECT_OK) {
        check_edited(m, e);
        affect_motion_free(e);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader r = {data, size};
    affect_motion *m = build(&r);
    if (!m)
        return 0;
    affect_error err;
    CHECK(affect_motion_validate(m, &err) == AFFECT_OK);
    affect_motion *back = NULL;
    check_blob(m, &back);
    if (back) {
        double fk;
        uint32_t ft, fj;
        if (affect_motion_fk_error(back, &fk, &ft, &fj, &err) == AFFECT_OK)
            CHECK(fk <= 1e-6 * (1 + max_reach(m)));
        affect_motion_free(back);
    }
    check_v1(m);
    check_bvh(m);
    check_edits(m, &r);
    affect_motion_free(m);
    return 0;
}
