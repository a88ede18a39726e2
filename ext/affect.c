/*
 * affect.c — entry point of the sqlite-affect loadable extension.
 *
 *   sqlite3 shell:  .load ./build/affect
 *   Python:         conn.enable_load_extension(True); conn.load_extension("./build/affect")
 *
 * sqlite3_affect_init checks the host SQLite's version, routes the core library's allocations
 * to sqlite3_malloc64 (so SQLite's memory accounting and fault injection cover them), and
 * registers every SQL function from one table per kind (scalar functions, aggregates),
 * reporting a failure with the function's name.
 * Every function here is pure (deterministic, no file or table access), so each is
 * SQLITE_DETERMINISTIC | SQLITE_INNOCUOUS.
 */
#include <string.h>

#include "common.h"
#include "fn_affect.h"
#include "fn_fda.h"
#include "fn_generate.h"
#include "fn_hmm.h"
#include "fn_laban.h"
#include "fn_motion.h"
#include "fn_skeleton.h"
#include "fn_strength.h"
#include "vt_laban.h"
#include "fn_plot.h"
#include "fn_preview.h"
#include "affect/strbuf.h"

#include <svm.h>

SQLITE_EXTENSION_INIT1

#ifndef AFFECT_VERSION
#define AFFECT_VERSION "0.0.0"
#endif
#ifndef AFFECT_COMPILE_FLAGS
#define AFFECT_COMPILE_FLAGS ""
#endif
#ifndef AFFECT_BUILD_TYPE
#define AFFECT_BUILD_TYPE ""
#endif

/* SQLITE_INNOCUOUS and SQLITE_DIRECTONLY arrived in 3.31.0. */
#define AFFECT_MIN_SQLITE 3031000
#define AFFECT_MIN_SQLITE_TEXT "3.31.0"

/* From OpenBLAS (cblas.h declares it, but its location varies between Debian flavours). */
char *openblas_get_config(void);
int openblas_get_num_threads(void);

static void *ax_malloc(size_t n)
{
    return sqlite3_malloc64(n);
}

static void *ax_realloc(void *p, size_t n)
{
    return sqlite3_realloc64(p, n);
}

static void ax_free(void *p)
{
    sqlite3_free(p);
}

static void fn_version(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    sqlite3_result_text(ctx, AFFECT_VERSION, -1, SQLITE_STATIC);
}

static void fn_build_info(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_puts(&sb, "{\"version\":");
    affect_strbuf_json_string(&sb, AFFECT_VERSION);
    affect_strbuf_puts(&sb, ",\"sqlite_compiled\":");
    affect_strbuf_json_string(&sb, SQLITE_VERSION);
    affect_strbuf_puts(&sb, ",\"sqlite_runtime\":");
    affect_strbuf_json_string(&sb, sqlite3_libversion());
    affect_strbuf_puts(&sb, ",\"blas\":");
    affect_strbuf_json_string(&sb, openblas_get_config());
    affect_strbuf_printf(&sb, ",\"blas_threads\":%d", openblas_get_num_threads());
    affect_strbuf_printf(&sb, ",\"libsvm\":%d", libsvm_version);
    affect_strbuf_puts(&sb, ",\"build_type\":");
    affect_strbuf_json_string(&sb, AFFECT_BUILD_TYPE);
    affect_strbuf_puts(&sb, ",\"compile_flags\":");
    affect_strbuf_json_string(&sb, AFFECT_COMPILE_FLAGS);
    affect_strbuf_putc(&sb, '}');
    ax_result_json_buffer(ctx, &sb);
}

typedef struct ax_function {
    const char *name;
    int n_arg;
    bool json; /* returns JSON text (subtype 'J') */
    void (*fn)(sqlite3_context *, int, sqlite3_value **);
} ax_function;

/* Every scalar function, one row per accepted argument count. */
static const ax_function functions[] = {
    {"affect_version", 0, false, fn_version},
    {"affect_build_info", 0, true, fn_build_info},
    {"motion_from_bvh", 1, false, ax_motion_from_bvh},
    {"motion_from_bvh", 2, false, ax_motion_from_bvh},
    {"motion_bvh_error", 1, false, ax_motion_bvh_error},
    {"motion_bvh_error", 2, false, ax_motion_bvh_error},
    {"motion_from_csv", 2, false, ax_motion_from_csv},
    {"motion_from_csv", 3, false, ax_motion_from_csv},
    {"motion_from_json", 1, false, ax_motion_from_json},
    {"motion_to_json", 1, true, ax_motion_to_json},
    {"motion_to_csv", 1, false, ax_motion_to_csv},
    {"motion_to_bvh", 1, false, ax_motion_to_bvh},
    {"motion_to_bvh", 2, false, ax_motion_to_bvh},
    {"motion_rigid", 1, false, ax_motion_rigid},
    {"motion_rigid", 2, false, ax_motion_rigid},
    {"motion_rigid", 3, false, ax_motion_rigid},
    {"motion_info", 1, true, ax_motion_info},
    {"motion_frames", 1, false, ax_motion_scalar},
    {"motion_joints", 1, false, ax_motion_scalar},
    {"motion_fps", 1, false, ax_motion_scalar},
    {"motion_duration", 1, false, ax_motion_scalar},
    {"motion_slice", 3, false, ax_motion_slice},
    {"motion_resample", 2, false, ax_motion_resample},
    {"motion_select", 2, false, ax_motion_select},
    {"motion_dtw", 2, false, ax_motion_dtw},
    {"motion_roles", 1, true, ax_motion_roles},
    {"motion_roles", 2, true, ax_motion_roles},
    {"motion_normalize", 1, false, ax_motion_normalize},
    {"motion_normalize", 2, false, ax_motion_normalize},
    {"motion_svg", 1, false, ax_motion_svg},
    {"motion_svg", 2, false, ax_motion_svg},
    {"motion_synth", 3, false, ax_motion_synth},
    {"motion_synth", 4, false, ax_motion_synth},
    {"laban_weight", 1, false, ax_laban_weight},
    {"laban_weight", 2, false, ax_laban_weight},
    {"laban_weight", 3, false, ax_laban_weight},
    {"laban_time", 1, false, ax_laban_time},
    {"laban_time", 2, false, ax_laban_time},
    {"laban_time", 3, false, ax_laban_time},
    {"laban_flow", 1, false, ax_laban_flow},
    {"laban_flow", 2, false, ax_laban_flow},
    {"laban_flow", 3, false, ax_laban_flow},
    {"laban_space", 1, false, ax_laban_space},
    {"laban_space", 2, false, ax_laban_space},
    {"laban_space", 3, false, ax_laban_space},
    {"laban_shape_directional", 2, false, ax_laban_shape_directional},
    {"laban_shape_directional", 3, false, ax_laban_shape_directional},
    {"laban_shape_shaping", 1, true, ax_laban_shape_shaping},
    {"laban_shape_shaping", 2, true, ax_laban_shape_shaping},
    {"laban_shape_flow", 1, false, ax_laban_shape_flow},
    {"laban_shape_flow", 2, false, ax_laban_shape_flow},
    {"laban", 1, true, ax_laban},
    {"laban", 2, true, ax_laban},
    {"motion_kinematics", 1, false, ax_motion_kinematics},
    {"motion_kinematics", 2, false, ax_motion_kinematics},
    {"laban_vector", 1, false, ax_laban_vector},
    {"laban_vector", 2, false, ax_laban_vector},
    {"laban_names", 0, true, ax_laban_names},
    {"hmm_loglik", 2, false, ax_hmm_loglik},
    {"hmm_loglik", 3, false, ax_hmm_loglik},
    {"hmm_viterbi", 2, true, ax_hmm_viterbi},
    {"hmm_viterbi_loglik", 2, false, ax_hmm_viterbi_loglik},
    {"hmm_info", 1, true, ax_hmm_info},
    {"hmm_postures", 1, false, ax_hmm_postures},
    /* emotion strength (fn_strength.c) */
    {"affect_strength", 2, false, ax_affect_strength},
    {"strength_synthesize", 2, false, ax_strength_synthesize},
    {"strength_synthesize", 3, false, ax_strength_synthesize},
    {"strength_edit", 3, false, ax_strength_edit},
    {"strength_edit", 4, false, ax_strength_edit},
    {"strength_info", 1, true, ax_strength_info},
    {"motion_keyframes", 1, true, ax_motion_keyframes},
    {"motion_keyframes", 2, true, ax_motion_keyframes},
    {"rank_score", 2, false, ax_rank_score},
};

typedef struct ax_aggregate {
    const char *name;
    int n_arg;
    void (*step)(sqlite3_context *, int, sqlite3_value **);
    void (*final)(sqlite3_context *);
} ax_aggregate;

/* Every aggregate function, one row per accepted argument count. */
static const ax_aggregate aggregates[] = {
    {"laban_plot", 3, ax_laban_plot_step, ax_laban_plot_final},
    {"laban_plot", 4, ax_laban_plot_step, ax_laban_plot_final},
    {"motion_svg_group", 2, ax_motion_svg_group_step, ax_motion_svg_group_final},
    {"motion_svg_group", 3, ax_motion_svg_group_step, ax_motion_svg_group_final},
    {"affect_heatmap", 3, ax_affect_heatmap_step, ax_affect_heatmap_final},
    {"affect_heatmap", 4, ax_affect_heatmap_step, ax_affect_heatmap_final},
    {"hmm_train", 1, ax_hmm_train_step, ax_hmm_train_final},
    {"hmm_train", 2, ax_hmm_train_step, ax_hmm_train_final},
    {"affect_train", 2, ax_affect_train_step, ax_affect_train_final},
    {"affect_train", 3, ax_affect_train_step, ax_affect_train_final},
    {"affect_crossval_json", 4, ax_affect_crossval_step, ax_affect_crossval_final},
    {"strength_train", 2, ax_strength_train_step, ax_strength_train_final},
    {"strength_train", 3, ax_strength_train_step, ax_strength_train_final},
    {"rank_train", 2, ax_rank_train_step, ax_rank_train_final},
    {"rank_train", 3, ax_rank_train_step, ax_rank_train_final},
    {"fda_train", 2, ax_fda_train_step, ax_fda_train_final},
    {"fda_train", 3, ax_fda_train_step, ax_fda_train_final},
};

/* The functions on a classifier BLOB: each registration gets its own one-classifier cache
 * (fn_affect.c) as user data, freed with the connection. */
static const ax_function classifier_functions[] = {
    {"affect_classify", 2, false, ax_affect_classify},
    {"affect_classify", 3, false, ax_affect_classify},
    {"affect_scores", 2, true, ax_affect_scores},
    {"fisher_score", 2, false, ax_fisher_score},
    {"affect_embed", 2, false, ax_affect_embed},
    {"affect_info", 1, true, ax_affect_info},
};

/* The functions on a functional model BLOB (fn_fda.c), each with its one-model cache. */
static const ax_function fda_functions[] = {
    {"fda_embed", 2, false, ax_fda_embed},         {"fda_classify", 2, false, ax_fda_classify},
    {"fda_classify", 3, false, ax_fda_classify},   {"fda_info", 1, true, ax_fda_info},
    {"fda_prototype", 2, false, ax_fda_prototype}, {"fda_plot", 1, false, ax_fda_plot},
    {"fda_plot", 2, false, ax_fda_plot},
};

#ifdef _WIN32
__declspec(dllexport)
#endif
    __attribute__((visibility("default"))) int sqlite3_affect_init(sqlite3 *db, char **err,
                                                                   const sqlite3_api_routines *api);

int sqlite3_affect_init(sqlite3 *db, char **err, const sqlite3_api_routines *api)
{
    SQLITE_EXTENSION_INIT2(api);
    if (sqlite3_libversion_number() < AFFECT_MIN_SQLITE) {
        *err = sqlite3_mprintf("affect: SQLite " AFFECT_MIN_SQLITE_TEXT
                               " or later is required (this host runs %s)",
                               sqlite3_libversion());
        return SQLITE_ERROR;
    }
    static const affect_allocator allocator = {ax_malloc, ax_realloc, ax_free};
    affect_set_allocator(&allocator);

    int subtype_flag = sqlite3_libversion_number() >= 3045000 ? SQLITE_RESULT_SUBTYPE : 0;
    for (size_t i = 0; i < sizeof functions / sizeof functions[0]; i++) {
        const ax_function *f = &functions[i];
        int flags = AX_PURE | (f->json ? subtype_flag : 0);
        int rc = sqlite3_create_function_v2(db, f->name, f->n_arg, flags, (void *)f->name, f->fn,
                                            NULL, NULL, NULL);
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", f->name, f->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    for (size_t i = 0; i < sizeof aggregates / sizeof aggregates[0]; i++) {
        const ax_aggregate *a = &aggregates[i];
        int rc = sqlite3_create_function_v2(db, a->name, a->n_arg, AX_PURE, (void *)a->name, NULL,
                                            a->step, a->final, NULL);
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", a->name, a->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    for (size_t i = 0; i < sizeof classifier_functions / sizeof classifier_functions[0]; i++) {
        const ax_function *f = &classifier_functions[i];
        ax_cls_fn *user = ax_cls_fn_new(f->name);
        if (!user)
            return SQLITE_NOMEM;
        int flags = AX_PURE | (f->json ? subtype_flag : 0);
        int rc = sqlite3_create_function_v2(db, f->name, f->n_arg, flags, user, f->fn, NULL, NULL,
                                            ax_cls_fn_free); /* frees user on failure */
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", f->name, f->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    for (size_t i = 0; i < sizeof fda_functions / sizeof fda_functions[0]; i++) {
        const ax_function *f = &fda_functions[i];
        ax_fda_fn *user = ax_fda_fn_new(f->name);
        if (!user)
            return SQLITE_NOMEM;
        int flags = AX_PURE | (f->json ? subtype_flag : 0);
        int rc = sqlite3_create_function_v2(db, f->name, f->n_arg, flags, user, f->fn, NULL, NULL,
                                            ax_fda_fn_free); /* frees user on failure */
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", f->name, f->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    /* generation: reads (and may cache into) the laban index named by its argument, so not
     * deterministic in SQLite's sense and not for triggers or views */
    static const ax_function generation_functions[] = {
        {"affect_generate", 3, false, ax_affect_generate},
        {"affect_generate", 4, false, ax_affect_generate},
        {"affect_generate_explain", 3, true, ax_affect_generate_explain},
        {"affect_generate_explain", 4, true, ax_affect_generate_explain},
        {"laban_salient", 1, true, ax_laban_salient},
        {"laban_salient", 2, true, ax_laban_salient},
    };
    for (size_t i = 0; i < sizeof generation_functions / sizeof generation_functions[0]; i++) {
        const ax_function *f = &generation_functions[i];
        ax_gen_fn *user = ax_gen_fn_new(f->name);
        if (!user)
            return SQLITE_NOMEM;
        int flags = SQLITE_UTF8 | SQLITE_DIRECTONLY | (f->json ? subtype_flag : 0);
        int rc = sqlite3_create_function_v2(db, f->name, f->n_arg, flags, user, f->fn, NULL, NULL,
                                            ax_gen_fn_free);
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", f->name, f->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    /* laban_zvector reads the statistics of the laban index named by its argument: not
     * deterministic in SQLite's sense (the vector follows the index) and not for triggers,
     * views, generated columns or expression indexes */
    static const ax_function index_functions[] = {
        {"laban_zvector", 2, false, ax_laban_zvector},
        {"laban_zvector", 3, false, ax_laban_zvector},
    };
    for (size_t i = 0; i < sizeof index_functions / sizeof index_functions[0]; i++) {
        const ax_function *f = &index_functions[i];
        int rc = sqlite3_create_function_v2(db, f->name, f->n_arg, SQLITE_UTF8 | SQLITE_DIRECTONLY,
                                            (void *)f->name, f->fn, NULL, NULL, NULL);
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", f->name, f->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    int rc = ax_register_affect_tables(db);
    if (rc != SQLITE_OK) {
        *err = sqlite3_mprintf("affect: cannot register affect_crossval/affect_salience: %s",
                               sqlite3_errmsg(db));
        return rc;
    }
    rc = ax_register_points(db);
    if (rc != SQLITE_OK) {
        *err = sqlite3_mprintf("affect: cannot register motion_points: %s", sqlite3_errmsg(db));
        return rc;
    }
    rc = ax_register_angles(db);
    if (rc != SQLITE_OK) {
        *err = sqlite3_mprintf("affect: cannot register motion_angles: %s", sqlite3_errmsg(db));
        return rc;
    }
    rc = ax_register_laban_series(db);
    if (rc != SQLITE_OK) {
        *err = sqlite3_mprintf("affect: cannot register laban_series: %s", sqlite3_errmsg(db));
        return rc;
    }
    static const ax_laban_cache_kind laban_caches[] = {{"rmlr", ax_gen_check_fit}, {NULL, NULL}};
    rc = ax_register_laban(db, laban_caches);
    if (rc != SQLITE_OK) {
        *err = sqlite3_mprintf("affect: cannot register laban: %s", sqlite3_errmsg(db));
        return rc;
    }
    return SQLITE_OK;
}
