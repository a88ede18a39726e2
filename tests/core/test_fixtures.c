/*
 * test_fixtures.c — every BLOB in tests/fixtures/ through the one codec (util/bytes.h): each
 * file decodes with its format's decoder, chosen by its magic, and today's encoder gives back
 * exactly its bytes — or, for the two versions that are upgraded on re-encoding (classifier
 * version 1, the headerless RMLR fit), an encoding that is a fixed point (decoding and
 * re-encoding it gives the same bytes; rmlr-v1.bin's is rmlr-v2.bin). Every *.bin of the
 * directory must be listed here, so that a fixture cannot be added without this check. The
 * per-format tests (test_motion.c, test_hmm_blob.c, …) check the fixtures' contents.
 */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>

#include <cmocka.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "util/bytes.h"
#include "affect/classifier.h"
#include "affect/fda.h"
#include "affect/features.h"
#include "affect/hmm.h"
#include "affect/hmm_blob.h"
#include "affect/motion.h"
#include "affect/rank.h"
#include "affect/rmlr.h"
#include "affect/strength.h"
#include "testutil.h"

typedef struct fixture {
    const char *file;
    const char *magic;
    const char *upgraded_to; /* NULL: re-encodes to its own bytes; "": to a fixed point */
} fixture;

static const fixture FIXTURES[] = {
    {"motion-v1.bin", "AFMO", NULL},     {"motion-v2.bin", "AFMO", NULL},
    {"hmm-v1.bin", "AFHM", NULL},        {"classifier-v1.bin", "AFCL", ""},
    {"classifier-v2.bin", "AFCL", NULL}, {"classifier-v3.bin", "AFCL", NULL},
    {"fda-v1.bin", "AFFD", NULL},        {"strength-v1.bin", "AFST", NULL},
    {"strength-v2.bin", "AFST", NULL},   {"strength-v3.bin", "AFST", NULL},
    {"ranker-v1.bin", "AFRK", NULL},     {"rmlr-v1.bin", "\x01", "rmlr-v2.bin"},
    {"rmlr-v2.bin", "AFRL", NULL},       {"fda-v2.bin", "AFFD", NULL},
    {"fda-v3.bin", "AFFD", NULL},
};
#define N_FIXTURES (sizeof FIXTURES / sizeof FIXTURES[0])

/* Decodes data as the format of magic and encodes it again into *out (affect_malloc'd). */
static void recode(const char *magic, const unsigned char *data, size_t size, unsigned char **out,
                   size_t *out_size)
{
    affect_error err;
    affect_error_clear(&err);
    affect_status st = AFFECT_ERR_INVALID;
    if (strcmp(magic, "AFMO") == 0) {
        affect_motion *m;
        assert_int_equal(affect_motion_decode(data, size, &m, &err), AFFECT_OK);
        st = affect_motion_encode(m, out, out_size, &err);
        affect_motion_free(m);
    } else if (strcmp(magic, "AFHM") == 0) {
        affect_hmm *h;
        affect_features *f;
        assert_int_equal(affect_hmm_blob_decode(data, size, &h, &f, &err), AFFECT_OK);
        st = affect_hmm_blob_encode(h, f, out, out_size, &err);
        affect_hmm_free(h);
        affect_features_free(f);
    } else if (strcmp(magic, "AFCL") == 0) {
        affect_classifier *c;
        assert_int_equal(affect_classifier_decode(data, size, &c, &err), AFFECT_OK);
        st = affect_classifier_encode(c, out, out_size, &err);
        affect_classifier_free(c);
    } else if (strcmp(magic, "AFFD") == 0) {
        affect_fda *f;
        assert_int_equal(affect_fda_decode(data, size, &f, &err), AFFECT_OK);
        st = affect_fda_encode(f, out, out_size, &err);
        affect_fda_free(f);
    } else if (strcmp(magic, "AFST") == 0) {
        affect_strength *s;
        assert_int_equal(affect_strength_decode(data, size, &s, &err), AFFECT_OK);
        st = affect_strength_encode(s, out, out_size, &err);
        affect_strength_free(s);
    } else if (strcmp(magic, "AFRK") == 0) {
        affect_ranker *r;
        assert_int_equal(affect_ranker_decode(data, size, &r, &err), AFFECT_OK);
        st = affect_ranker_encode(r, out, out_size, &err);
        affect_ranker_free(r);
    } else if (strcmp(magic, "AFRL") == 0 || strcmp(magic, "\x01") == 0) {
        affect_rmlr *m;
        affect_br r;
        affect_br_init(&r, data, size);
        assert_int_equal(affect_rmlr_decode(&r, &m, &err), AFFECT_OK);
        assert_int_equal(r.off, size);
        affect_bw w;
        affect_bw_init(&w);
        affect_rmlr_encode(m, &w);
        affect_rmlr_free(m);
        assert_false(w.failed);
        *out = w.data;
        *out_size = w.len;
        st = AFFECT_OK;
    }
    if (st != AFFECT_OK)
        fail_msg("%s: %s", magic, err.msg);
}

static unsigned char *read_fixture(const char *file, size_t *size)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s", AFFECT_FIXTURES_DIR, file);
    unsigned char *data = (unsigned char *)tu_read_file(path, size);
    if (!data)
        fail_msg("cannot read %s", path);
    return data;
}

static void test_every_fixture_recodes(void **state)
{
    (void)state;
    for (size_t i = 0; i < N_FIXTURES; i++) {
        const fixture *fx = &FIXTURES[i];
        size_t size, out_size, again_size;
        unsigned char *data = read_fixture(fx->file, &size), *out, *again;
        assert_true(size >= 4);
        assert_memory_equal(data, fx->magic, strlen(fx->magic));
        recode(fx->magic, data, size, &out, &out_size);
        if (!fx->upgraded_to) {
            if (out_size != size || memcmp(out, data, size) != 0)
                fail_msg("%s does not re-encode to its own bytes (%zu bytes, %zu written)",
                         fx->file, size, out_size);
        } else {
            /* the upgraded encoding is a fixed point of decode and encode */
            char magic[5] = {0};
            memcpy(magic, out, 4);
            recode(magic, out, out_size, &again, &again_size);
            assert_int_equal(again_size, out_size);
            assert_memory_equal(again, out, out_size);
            affect_free(again);
            if (fx->upgraded_to[0]) {
                size_t want_size;
                unsigned char *want = read_fixture(fx->upgraded_to, &want_size);
                assert_int_equal(out_size, want_size);
                assert_memory_equal(out, want, want_size);
                free(want);
            }
        }
        affect_free(out);
        free(data);
    }
}

/* Every *.bin of the directory is in the table above. */
static void test_every_fixture_listed(void **state)
{
    (void)state;
    DIR *dir = opendir(AFFECT_FIXTURES_DIR);
    assert_non_null(dir);
    size_t seen = 0;
    for (struct dirent *e; (e = readdir(dir)) != NULL;) {
        size_t len = strlen(e->d_name);
        if (len < 4 || strcmp(e->d_name + len - 4, ".bin") != 0)
            continue;
        bool listed = false;
        for (size_t i = 0; i < N_FIXTURES; i++)
            listed = listed || strcmp(FIXTURES[i].file, e->d_name) == 0;
        if (!listed)
            fail_msg("tests/fixtures/%s is not listed in test_fixtures.c", e->d_name);
        seen++;
    }
    closedir(dir);
    assert_int_equal(seen, N_FIXTURES);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_fixture_recodes),
        cmocka_unit_test(test_every_fixture_listed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
