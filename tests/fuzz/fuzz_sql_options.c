/*
 * fuzz_sql_options.c — libFuzzer target for the JSON options of every SQL function that takes
 * them (ext/common.c ax_opts_parse and each wrapper's option reading), through a real
 * connection: motion import (BVH, CSV: options and document together), export, rigid bones,
 * roles, normalization, motion_svg (film strip and animation), motion_svg_group, affect_heatmap,
 * motion_synth, motion_angles, every laban_* descriptor, laban_zvector (its options, and its
 * index name as ?1), laban_series, laban_plot (its time-series mode too), hmm_train,
 * hmm_loglik, affect_train, affect_crossval(_json), laban_salient, fda_train, strength_train
 * (through fda_info and strength_info) and affect_generate(_explain) (its classifier option as
 * hex text included).
 *
 * Usage (see tests/fuzz/run.sh, or build with -DAFFECT_FUZZ=ON and clang):
 *     build-fuzz/tests/fuzz/fuzz_sql_options -max_total_time=60 <a copy of
 * tests/fuzz/corpus/fuzz_sql_options>
 *
 * Input: the call's name (a row of calls[] below), a line break, then the options text, bound
 * as the statement's ?1 as is (not NUL-terminated; any bytes). For motion_from_bvh and
 * motion_from_csv the options are the second line only and the rest of the input is the
 * document (?2; without a second line break the fixture's document is used). An unknown name
 * does nothing. The fixtures are fuzz_sql.h's; each input gets a fresh copy of them.
 * Seeds (tests/fuzz/corpus/fuzz_sql_options): <call>*.txt, options from docs/reference.md;
 * tests/fuzz/fuzz_sql_options.dict holds the option keys and values of the previews, of
 * laban_series and of laban_plot's time-series mode.
 * Checks beyond "no crash, no leak, no undefined behaviour" (fuzz_sql.c): an error carries a
 * message starting with "<function>: "; a motion result decodes and validates; a JSON result
 * is valid JSON; a trained model or classifier decodes and re-encodes to the same bytes.
 */
#include "fuzz_sql.h"

#include <string.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct call {
    const char *name;   /* the input's first line */
    const char *prefix; /* the function name its errors start with */
    char result;        /* column 0: 'm' motion, 'j' JSON, 'h' model, 'c' classifier, 'x'
                           anything */
    bool document;      /* options on line 2, the document after it (?2) */
    const char *sql;
} call;

#define M1 "(SELECT motion FROM motions WHERE id = 1)"

static const call calls[] = {
    {"motion_from_bvh", "motion_from_bvh", 'm', true,
     "SELECT motion_from_bvh(coalesce(?2, (SELECT body FROM docs WHERE name = 'bvh')), ?1)"},
    {"motion_from_csv", "motion_from_csv", 'm', true,
     "SELECT motion_from_csv(coalesce(?2, (SELECT body FROM docs WHERE name = 'csv')), 10, ?1)"},
    {"motion_to_bvh", "motion_to_bvh", 'x', false, "SELECT motion_to_bvh(" M1 ", ?1)"},
    {"motion_to_bvh_stored", "motion_to_bvh", 'x', false,
     "SELECT motion_to_bvh(motion, ?1) FROM extra WHERE name = 'skeletal'"},
    {"motion_rigid", "motion_rigid", 'm', false, "SELECT motion_rigid(" M1 ", ?1)"},
    {"motion_rigid_reference", "motion_rigid", 'm', false,
     "SELECT motion_rigid(" M1 ", ?1, (SELECT motion FROM motions WHERE id = 2))"},
    {"motion_roles", "motion_roles", 'j', false, "SELECT motion_roles(" M1 ", ?1)"},
    {"motion_normalize", "motion_normalize", 'm', false, "SELECT motion_normalize(" M1 ", ?1)"},
    {"motion_svg", "motion_svg", 'x', false, "SELECT motion_svg(" M1 ", ?1)"},
    {"motion_svg_group", "motion_svg_group", 'x', false,
     "SELECT motion_svg_group(motion, label, ?1) FROM motions"},
    {"affect_heatmap", "affect_heatmap", 'x', false,
     "SELECT affect_heatmap(label, CAST(round(y) AS TEXT), x, ?1) FROM points"},
    {"motion_synth", "motion_synth", 'm', false, "SELECT motion_synth('wave', 'happy', 3, ?1)"},
    {"motion_angles", "motion_angles", 'x', false,
     "SELECT frame, joint, name, qw, qx, qy, qz, \"order\", rx, ry, rz, speed "
     "FROM motion_angles(" M1 ", ?1)"},
    {"motion_angles_stored", "motion_angles", 'x', false,
     "SELECT frame, joint, name, qw, rx, speed "
     "FROM motion_angles((SELECT motion FROM extra WHERE name = 'skeletal'), ?1)"},
    {"laban_weight", "laban_weight", 'x', false, "SELECT laban_weight(" M1 ", 'all', ?1)"},
    {"laban_time", "laban_time", 'x', false, "SELECT laban_time(" M1 ", 'all', ?1)"},
    {"laban_flow", "laban_flow", 'x', false, "SELECT laban_flow(" M1 ", 'all', ?1)"},
    {"laban_space", "laban_space", 'x', false, "SELECT laban_space(" M1 ", 'right_hand', ?1)"},
    {"laban_shape_directional", "laban_shape_directional", 'x', false,
     "SELECT laban_shape_directional(" M1 ", 'right', ?1)"},
    {"laban_shape_shaping", "laban_shape_shaping", 'j', false,
     "SELECT laban_shape_shaping(" M1 ", ?1)"},
    {"laban_shape_flow", "laban_shape_flow", 'x', false, "SELECT laban_shape_flow(" M1 ", ?1)"},
    {"laban", "laban", 'j', false, "SELECT laban(" M1 ", ?1)"},
    {"motion_kinematics", "motion_kinematics", 'x', false, "SELECT motion_kinematics(" M1 ", ?1)"},
    {"laban_vector", "laban_vector", 'x', false, "SELECT laban_vector(" M1 ", ?1)"},
    {"laban_zvector", "laban_zvector", 'x', false, "SELECT laban_zvector(" M1 ", 'ix', ?1)"},
    /* the index name itself (quoted into laban_zvector's reads of the index's tables) */
    {"laban_zvector_index", "laban_zvector", 'x', false, "SELECT laban_zvector(" M1 ", ?1)"},
    {"laban_plot", "laban_plot", 'x', false, "SELECT laban_plot(x, y, label, ?1) FROM points"},
    {"laban_series", "laban_series", 'x', false,
     "SELECT frame, seconds, first_frame, last_frame, part, weight, time, space, flow "
     "FROM laban_series(" M1 ", ?1)"},
    {"hmm_train", "hmm_train", 'h', false,
     "SELECT hmm_train(motion, ?1) FROM motions WHERE label = 'angry'"},
    {"hmm_loglik", "hmm_loglik", 'x', false,
     "SELECT hmm_loglik((SELECT model FROM models WHERE name = 'hmm'), " M1 ", ?1)"},
    {"affect_train", "affect_train", 'c', false,
     "SELECT affect_train(motion, label, ?1) FROM motions"},
    {"affect_crossval_json", "affect_crossval_json", 'j', false,
     "SELECT affect_crossval_json(motion, label, grp, ?1) FROM motions"},
    {"affect_crossval", "affect_crossval", 'x', false,
     "SELECT method, fold, held_out, n_train, n_test, accuracy, confusion, params "
     "FROM affect_crossval('motions', 'motion', 'label', ?1)"},
    {"laban_salient", "laban_salient", 'j', false, "SELECT laban_salient('ix', ?1)"},
    {"fda_train", "fda_train", 'j', false,
     "SELECT fda_info(fda_train(motion, label, ?1)) FROM motions"},
    {"strength_train", "strength_train", 'j', false,
     "SELECT strength_info(strength_train(motion, label, ?1)) FROM motions"},
    {"affect_generate", "affect_generate", 'm', false,
     "SELECT affect_generate('ix', " M1 ", 'sad', ?1)"},
    {"affect_generate_explain", "affect_generate_explain", 'j', false,
     "SELECT affect_generate_explain('ix', " M1 ", 'sad', ?1)"},
};

typedef struct row_ctx {
    sqlite3 *db;
    char result;
} row_ctx;

static void check_row(sqlite3_stmt *st, void *arg)
{
    const row_ctx *r = arg;
    switch (r->result) {
    case 'm':
        fz_check_motion(st, 0);
        break;
    case 'j':
        fz_check_json(r->db, st, 0);
        break;
    case 'h':
        fz_check_hmm(st, 0);
        break;
    case 'c':
        fz_check_classifier(st, 0);
        break;
    default:
        break;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *nl = memchr(data, '\n', size);
    if (!nl)
        return 0;
    size_t name_len = (size_t)(nl - data);
    const call *c = NULL;
    for (size_t i = 0; i < sizeof calls / sizeof calls[0] && !c; i++)
        if (strlen(calls[i].name) == name_len && memcmp(calls[i].name, data, name_len) == 0)
            c = &calls[i];
    if (!c)
        return 0;
    const uint8_t *opt = nl + 1, *end = data + size, *doc = NULL;
    size_t opt_len = (size_t)(end - opt), doc_len = 0;
    if (c->document) {
        const uint8_t *nl2 = memchr(opt, '\n', opt_len);
        if (nl2) {
            doc = nl2 + 1;
            doc_len = (size_t)(end - doc);
            opt_len = (size_t)(nl2 - opt);
        }
    }
    sqlite3 *db = fz_open();
    sqlite3_stmt *st = fz_prepare(db, c->sql);
    sqlite3_bind_text(st, 1, (const char *)opt, (int)opt_len, SQLITE_TRANSIENT);
    if (doc)
        sqlite3_bind_text(st, 2, (const char *)doc, (int)doc_len, SQLITE_TRANSIENT);
    row_ctx r = {db, c->result};
    fz_step_all(db, st, c->prefix, check_row, &r);
    sqlite3_finalize(st);
    fz_close(db);
    return 0;
}
