/*
 * test_corpus.c — the real corpus (../shared/corpora/bandai-namco-1): every BVH file imports;
 * joint and frame counts match what the file's header declares (counted independently of the
 * parser); every bone keeps its length within 1e-4 relative over all frames. The link from
 * joint_Root to Hips is not a bone: Hips' position channels carry the global translation.
 * Skips with a message when ../shared is absent.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "testutil.h"
#include "affect/io.h"
#include "affect/roles.h"

/* Counts ROOT, JOINT and "End Site" keywords and reads "Frames:" with plain string search. */
static void header_counts(const char *text, uint32_t *joints, uint32_t *frames)
{
    *joints = 0;
    *frames = 0;
    const char *motion = strstr(text, "MOTION");
    for (const char *p = text; p && p < motion; p++) {
        if ((p == text || p[-1] == '\n' || p[-1] == ' ' || p[-1] == '\t') &&
            (strncmp(p, "ROOT ", 5) == 0 || strncmp(p, "JOINT ", 6) == 0 ||
             strncmp(p, "End Site", 8) == 0))
            (*joints)++;
    }
    const char *f = motion ? strstr(motion, "Frames:") : NULL;
    if (f)
        *frames = (uint32_t)strtoul(f + 7, NULL, 10);
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

static void test_corpus(void **state)
{
    const char *dir = tu_corpus_dir();
    if (!dir) {
        skip();
        return;
    }
    DIR *d = opendir(dir);
    assert_non_null(d);
    char *files[512];
    size_t n_files = 0;
    struct dirent *e;
    while ((e = readdir(d)) && n_files < 512) {
        size_t len = strlen(e->d_name);
        if (len > 4 && strcmp(e->d_name + len - 4, ".bvh") == 0)
            files[n_files++] = strdup(e->d_name);
    }
    closedir(d);
    qsort(files, n_files, sizeof *files, compare_names);
    assert_int_equal(n_files, 174);

    double worst = 0;
    size_t total_frames = 0;
    for (size_t i = 0; i < n_files; i++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, files[i]);
        size_t len;
        char *text = tu_read_file(path, &len);
        assert_non_null(text);
        affect_motion *m = NULL;
        affect_error err;
        if (affect_bvh_parse(text, len, NULL, &m, &err))
            fail_msg("%s: %s", files[i], err.msg);
        uint32_t joints, frames;
        header_counts(text, &joints, &frames);
        if (m->n_joints != joints || m->n_frames != frames)
            fail_msg("%s: %u joints × %u frames, header says %u × %u", files[i], m->n_joints,
                     m->n_frames, joints, frames);
        assert_int_equal(m->n_joints, 27);
        tu_assert_near(m->fps, 30.0, 1e-3);
        total_frames += m->n_frames;

        affect_roles roles;
        affect_roles_resolve(m, &roles);
        int32_t pelvis = roles.joint[AFFECT_ROLE_PELVIS];
        assert_string_equal(m->names[pelvis], "Hips");
        for (uint32_t j = 0; j < m->n_joints; j++) {
            int32_t p = m->parents[j];
            if (p < 0 || (int32_t)j == pelvis)
                continue;
            const float *a = affect_motion_at(m, 0, j), *b = affect_motion_at(m, 0, (uint32_t)p);
            double l0 = sqrt(pow(a[0] - b[0], 2) + pow(a[1] - b[1], 2) + pow(a[2] - b[2], 2));
            for (uint32_t t = 1; t < m->n_frames; t++) {
                a = affect_motion_at(m, t, j);
                b = affect_motion_at(m, t, (uint32_t)p);
                double l = sqrt(pow(a[0] - b[0], 2) + pow(a[1] - b[1], 2) + pow(a[2] - b[2], 2));
                /* relative for real bones; End Sites here have zero length (absolute, in cm) */
                double dev = l0 > 1e-3 ? fabs(l - l0) / l0 : fabs(l - l0);
                if (dev > worst)
                    worst = dev;
                if (dev > 1e-4)
                    fail_msg("%s: bone %s-%s varies by %g at frame %u", files[i], m->names[p],
                             m->names[j], dev, t);
            }
        }
        affect_motion_free(m);
        free(text);
        free(files[i]);
    }
    printf("corpus: 174 files, %zu frames, worst bone-length deviation %.2g\n", total_frames,
           worst);
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_corpus)};
    return cmocka_run_group_tests_name("corpus", tests, NULL, NULL);
}
