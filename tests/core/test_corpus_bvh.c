/*
 * test_corpus_bvh.c — BVH round trips on every file of both real corpora (../shared/corpora:
 * bandai-namco-1, 174 files, and bandai-namco-2-dev, 504 files):
 *   - with stored rotations: BVH → motion → BVH → motion reproduces every position within
 *     1e-4 of the unit (cm);
 *   - through inverse kinematics: a position-only copy → BVH → motion equals the rigid
 *     projection of the copy within 0.5 % of the body height with rotation channels only
 *     (position channels on joint_Root and Hips alone), and the rigid projection keeps
 *     every bone's length within the float32 resolution at its distance from the origin.
 * Prints the largest errors found. Skips with a message when ../shared is absent.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#include "testutil.h"
#include "affect/io.h"
#include "affect/skeleton.h"

#define STORED_TOL 1e-4  /* cm */
#define IK_TOL_REL 0.005 /* of the body height */

/* Vertical extent (y up) of the first frame. */
static double height(const affect_motion *m)
{
    double lo = INFINITY, hi = -INFINITY;
    for (uint32_t j = 0; j < m->n_joints; j++) {
        lo = fmin(lo, affect_motion_at(m, 0, j)[1]);
        hi = fmax(hi, affect_motion_at(m, 0, j)[1]);
    }
    return hi - lo;
}

/* The largest bone-length variation that float32 positions allow: a few float steps at the
 * largest coordinate over the shortest bone longer than 1 % of the body. */
static double float_bound(const affect_motion *m)
{
    double big = 0, shortest = INFINITY, h = height(m);
    for (size_t i = 0; i < (size_t)m->n_frames * m->n_joints * 3; i++)
        big = fmax(big, fabs(m->pos[i]));
    for (uint32_t j = 0; j < m->n_joints; j++) {
        int32_t p = m->parents[j];
        if (p < 0)
            continue;
        const float *a = affect_motion_at(m, 0, j), *b = affect_motion_at(m, 0, (uint32_t)p);
        double l = sqrt(pow(a[0] - b[0], 2) + pow(a[1] - b[1], 2) + pow(a[2] - b[2], 2));
        if (l > 0.01 * h)
            shortest = fmin(shortest, l);
    }
    return fmax(1e-6, 4 * big * 0x1p-23 / shortest);
}

typedef struct totals {
    size_t files;
    double stored, ik_rel, rigid_var, rigid_excess;
    char worst_stored[256], worst_ik[256];
} totals;

static void check_file(const char *path, const char *name, totals *tot)
{
    size_t len;
    char *text = tu_read_file(path, &len);
    assert_non_null(text);
    affect_motion *m = NULL, *back = NULL, *pos = NULL, *ik = NULL, *rigid = NULL, *back2 = NULL;
    affect_error err;
    if (affect_bvh_parse(text, len, NULL, &m, &err))
        fail_msg("%s: %s", name, err.msg);
    char *out = NULL, *out2 = NULL;
    size_t n, n2;
    assert_int_equal(affect_bvh_write(m, NULL, &out, &n, &err), AFFECT_OK);
    if (affect_bvh_parse(out, n, NULL, &back, &err))
        fail_msg("%s: the exported BVH does not parse: %s", name, err.msg);
    double d = tu_max_dist(back, m);
    if (d > tot->stored) {
        tot->stored = d;
        snprintf(tot->worst_stored, sizeof tot->worst_stored, "%s", name);
    }
    if (d > STORED_TOL)
        fail_msg("%s: re-imported positions differ by %g cm", name, d);
    /* position-only copy through IK */
    assert_int_equal(affect_motion_clone(m, &pos, NULL), AFFECT_OK);
    affect_motion_drop_skeleton(pos);
    assert_int_equal(affect_motion_rigid(pos, NULL, &rigid, &err), AFFECT_OK);
    assert_int_equal(affect_motion_ik(pos, NULL, &ik, &err), AFFECT_OK);
    /* captured motion: a rotation-only skeleton below joint_Root and Hips (siblings "auto") */
    uint32_t translated = 0;
    for (uint32_t j = 0; j < ik->n_joints; j++)
        translated += affect_skel_has_position(&ik->skel[j]);
    if (translated != 2)
        fail_msg("%s: %u joints with position channels after IK, expected 2", name, translated);
    assert_int_equal(affect_bvh_write(ik, NULL, &out2, &n2, &err), AFFECT_OK);
    assert_int_equal(affect_bvh_parse(out2, n2, NULL, &back2, &err), AFFECT_OK);
    double rel = tu_max_dist(back2, rigid) / height(m);
    if (rel > tot->ik_rel) {
        tot->ik_rel = rel;
        snprintf(tot->worst_ik, sizeof tot->worst_ik, "%s", name);
    }
    if (rel > IK_TOL_REL)
        fail_msg("%s: IK export differs from the rigid projection by %g of the height", name, rel);
    double var;
    int32_t worst;
    assert_int_equal(affect_motion_bone_variation(rigid, &var, &worst, NULL), AFFECT_OK);
    tot->rigid_var = fmax(tot->rigid_var, var);
    tot->rigid_excess = fmax(tot->rigid_excess, var / float_bound(m));
    if (var > float_bound(m))
        fail_msg("%s: rigid bone %s varies by %g (float32 bound %g)", name, rigid->names[worst],
                 var, float_bound(m));
    tot->files++;
    affect_free(out);
    affect_free(out2);
    affect_motion_free(m);
    affect_motion_free(back);
    affect_motion_free(back2);
    affect_motion_free(pos);
    affect_motion_free(ik);
    affect_motion_free(rigid);
    free(text);
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

static void check_corpus(const char *dir, size_t expected, totals *tot)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    char *files[1024];
    size_t n_files = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n_files < 1024) {
        size_t len = strlen(e->d_name);
        if (len > 4 && strcmp(e->d_name + len - 4, ".bvh") == 0)
            files[n_files++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(files, n_files, sizeof *files, compare_names);
    assert_int_equal(n_files, expected);
    for (size_t i = 0; i < n_files; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        check_file(path, files[i], tot);
        free(files[i]);
    }
}

static void test_corpora_round_trip(void **state)
{
    const char *dir1 = tu_corpus_dir();
    if (!dir1) {
        skip();
        return;
    }
    static const char dir2[] = AFFECT_SHARED_DIR "/corpora/bandai-namco-2-dev/data";
    totals tot;
    memset(&tot, 0, sizeof tot);
    check_corpus(dir1, 174, &tot);
    struct stat st;
    if (stat(dir2, &st) == 0 && S_ISDIR(st.st_mode))
        check_corpus(dir2, 504, &tot);
    else
        printf("SKIP: %s is absent: bandai-namco-2-dev not checked\n", dir2);
    printf("%zu files: stored rotations reproduce positions within %.3g cm (worst %s); IK export "
           "within %.3g of the body height of the rigid projection (worst %s); rigid bone-length "
           "variation at most %.3g (%.2f of the float32 bound)\n",
           tot.files, tot.stored, tot.worst_stored, tot.ik_rel, tot.worst_ik, tot.rigid_var,
           tot.rigid_excess);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_corpora_round_trip),
    };
    return cmocka_run_group_tests_name("corpus_bvh", tests, NULL, NULL);
}
