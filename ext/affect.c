/*
 * affect.c — entry point of the sqlite-affect loadable extension.
 *
 *   sqlite3 shell:  .load ./build/affect
 *   Python:         conn.enable_load_extension(True); conn.load_extension("./build/affect")
 *
 * sqlite3_affect_init checks the host SQLite's version, routes the core library's allocations
 * to sqlite3_malloc64 (so SQLite's memory accounting and fault injection cover them), and
 * registers everything from two tables, each in the order of docs/reference.md's contents:
 *   functions  every SQL function (scalar or aggregate), one row per accepted argument count:
 *              name, argument count, flags, xFunc or xStep/xFinal, and how its user data is
 *              made (the name itself, which AX_NAME reads, or a constructor/destructor pair for
 *              the functions that keep a cache: fn_affect.c, fn_fda.c, fn_generate.c);
 *   modules    every virtual-table module (the eponymous table-valued functions and the laban
 *              virtual table), by the function of its vt_*.c file that registers it.
 * One loop registers each table; a failure is reported with the function's or module's name
 * ("affect: cannot register motion_slice/3: …").
 *
 * Flags: pure functions (deterministic, no file or table access) are
 * SQLITE_UTF8 | SQLITE_DETERMINISTIC | SQLITE_INNOCUOUS. The functions that read the laban index
 * named by their argument (laban_zvector, laban_salient, affect_generate,
 * affect_generate_explain) are SQLITE_UTF8 | SQLITE_DIRECTONLY and not deterministic: their
 * result follows the index, and they are not for triggers, views, generated columns or
 * expression indexes. Scalar functions returning JSON text (subtype 'J') add
 * SQLITE_RESULT_SUBTYPE, which is left out when the host SQLite is older than 3.45 (it does not
 * know the flag).
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
#include "util/strbuf.h"

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

/* How a function's user data is made: the per-function caches, one per registration, freed
 * with the connection (or by SQLite when the registration fails). */
typedef struct ax_user_data {
    void *(*make)(const char *name); /* NULL when out of memory */
    void (*destroy)(void *);
} ax_user_data;

static void *blob_cache_new(const char *name)
{
    return ax_cached_fn_new(name);
}

static void *generation_cache_new(const char *name)
{
    return ax_gen_fn_new(name);
}

/* the functions on a classifier, functional model or strength model BLOB: their last decoded
 * model (ax_cached_fn, common.h) */
static const ax_user_data blob_cache = {blob_cache_new, ax_cached_fn_free};
/* generation: the RMLR fit of the last laban index used (fn_generate.c) */
static const ax_user_data generation_cache = {generation_cache_new, ax_gen_fn_free};

typedef struct ax_function {
    const char *name;
    int n_arg;
    int flags;
    void (*func)(sqlite3_context *, int, sqlite3_value **); /* a scalar function */
    void (*step)(sqlite3_context *, int, sqlite3_value **); /* an aggregate */
    void (*final)(sqlite3_context *);
    const ax_user_data *user; /* NULL: the user data is the name */
} ax_function;

#define PURE AX_PURE
#define READS (SQLITE_UTF8 | SQLITE_DIRECTONLY) /* reads the laban index named by an argument */
#define JSON SQLITE_RESULT_SUBTYPE              /* returns JSON text (subtype 'J') */

/* Every SQL function, one row per accepted argument count, in the reference's order. */
static const ax_function functions[] = {
    {"affect_version", 0, PURE, .func = fn_version},
    {"affect_build_info", 0, PURE | JSON, .func = fn_build_info},
    {"motion_from_bvh", 1, PURE, .func = ax_motion_from_bvh},
    {"motion_from_bvh", 2, PURE, .func = ax_motion_from_bvh},
    {"motion_bvh_error", 1, PURE, .func = ax_motion_bvh_error},
    {"motion_bvh_error", 2, PURE, .func = ax_motion_bvh_error},
    {"motion_from_csv", 2, PURE, .func = ax_motion_from_csv},
    {"motion_from_csv", 3, PURE, .func = ax_motion_from_csv},
    {"motion_from_json", 1, PURE, .func = ax_motion_from_json},
    {"motion_to_json", 1, PURE | JSON, .func = ax_motion_to_json},
    {"motion_to_csv", 1, PURE, .func = ax_motion_to_csv},
    {"motion_to_bvh", 1, PURE, .func = ax_motion_to_bvh},
    {"motion_to_bvh", 2, PURE, .func = ax_motion_to_bvh},
    {"motion_info", 1, PURE | JSON, .func = ax_motion_info},
    {"motion_frames", 1, PURE, .func = ax_motion_scalar},
    {"motion_joints", 1, PURE, .func = ax_motion_scalar},
    {"motion_fps", 1, PURE, .func = ax_motion_scalar},
    {"motion_duration", 1, PURE, .func = ax_motion_scalar},
    {"motion_slice", 3, PURE, .func = ax_motion_slice},
    {"motion_resample", 2, PURE, .func = ax_motion_resample},
    {"motion_select", 2, PURE, .func = ax_motion_select},
    {"motion_roles", 1, PURE | JSON, .func = ax_motion_roles},
    {"motion_roles", 2, PURE | JSON, .func = ax_motion_roles},
    {"motion_normalize", 1, PURE, .func = ax_motion_normalize},
    {"motion_normalize", 2, PURE, .func = ax_motion_normalize},
    {"motion_rigid", 1, PURE, .func = ax_motion_rigid},
    {"motion_rigid", 2, PURE, .func = ax_motion_rigid},
    {"motion_rigid", 3, PURE, .func = ax_motion_rigid},
    {"motion_svg", 1, PURE, .func = ax_motion_svg},
    {"motion_svg", 2, PURE, .func = ax_motion_svg},
    {"motion_svg_group", 2, PURE, .step = ax_motion_svg_group_step,
     .final = ax_motion_svg_group_final},
    {"motion_svg_group", 3, PURE, .step = ax_motion_svg_group_step,
     .final = ax_motion_svg_group_final},
    {"affect_heatmap", 3, PURE, .step = ax_affect_heatmap_step, .final = ax_affect_heatmap_final},
    {"affect_heatmap", 4, PURE, .step = ax_affect_heatmap_step, .final = ax_affect_heatmap_final},
    {"motion_synth", 3, PURE, .func = ax_motion_synth},
    {"motion_synth", 4, PURE, .func = ax_motion_synth},
    /* Laban */
    {"laban_weight", 1, PURE, .func = ax_laban_weight},
    {"laban_weight", 2, PURE, .func = ax_laban_weight},
    {"laban_weight", 3, PURE, .func = ax_laban_weight},
    {"laban_time", 1, PURE, .func = ax_laban_time},
    {"laban_time", 2, PURE, .func = ax_laban_time},
    {"laban_time", 3, PURE, .func = ax_laban_time},
    {"laban_flow", 1, PURE, .func = ax_laban_flow},
    {"laban_flow", 2, PURE, .func = ax_laban_flow},
    {"laban_flow", 3, PURE, .func = ax_laban_flow},
    {"laban_space", 1, PURE, .func = ax_laban_space},
    {"laban_space", 2, PURE, .func = ax_laban_space},
    {"laban_space", 3, PURE, .func = ax_laban_space},
    {"laban_shape_directional", 2, PURE, .func = ax_laban_shape_directional},
    {"laban_shape_directional", 3, PURE, .func = ax_laban_shape_directional},
    {"laban_shape_shaping", 1, PURE | JSON, .func = ax_laban_shape_shaping},
    {"laban_shape_shaping", 2, PURE | JSON, .func = ax_laban_shape_shaping},
    {"laban_shape_flow", 1, PURE, .func = ax_laban_shape_flow},
    {"laban_shape_flow", 2, PURE, .func = ax_laban_shape_flow},
    {"laban", 1, PURE | JSON, .func = ax_laban},
    {"laban", 2, PURE | JSON, .func = ax_laban},
    {"laban_names", 0, PURE | JSON, .func = ax_laban_names},
    {"laban_vector", 1, PURE, .func = ax_laban_vector},
    {"laban_vector", 2, PURE, .func = ax_laban_vector},
    {"laban_zvector", 2, READS, .func = ax_laban_zvector},
    {"laban_zvector", 3, READS, .func = ax_laban_zvector},
    {"laban_plot", 3, PURE, .step = ax_laban_plot_step, .final = ax_laban_plot_final},
    {"laban_plot", 4, PURE, .step = ax_laban_plot_step, .final = ax_laban_plot_final},
    {"motion_kinematics", 1, PURE, .func = ax_motion_kinematics},
    {"motion_kinematics", 2, PURE, .func = ax_motion_kinematics},
    /* HMMs */
    {"hmm_train", 1, PURE, .step = ax_hmm_train_step, .final = ax_hmm_train_final},
    {"hmm_train", 2, PURE, .step = ax_hmm_train_step, .final = ax_hmm_train_final},
    {"hmm_loglik", 2, PURE, .func = ax_hmm_loglik},
    {"hmm_loglik", 3, PURE, .func = ax_hmm_loglik},
    {"hmm_viterbi", 2, PURE | JSON, .func = ax_hmm_viterbi},
    {"hmm_viterbi_loglik", 2, PURE, .func = ax_hmm_viterbi_loglik},
    {"hmm_info", 1, PURE | JSON, .func = ax_hmm_info},
    {"hmm_postures", 1, PURE, .func = ax_hmm_postures},
    /* recognition */
    {"affect_train", 2, PURE, .step = ax_affect_train_step, .final = ax_affect_train_final},
    {"affect_train", 3, PURE, .step = ax_affect_train_step, .final = ax_affect_train_final},
    {"affect_classify", 2, PURE, .func = ax_affect_classify, .user = &blob_cache},
    {"affect_classify", 3, PURE, .func = ax_affect_classify, .user = &blob_cache},
    {"affect_scores", 2, PURE | JSON, .func = ax_affect_scores, .user = &blob_cache},
    {"fisher_score", 2, PURE, .func = ax_fisher_score, .user = &blob_cache},
    {"affect_embed", 2, PURE, .func = ax_affect_embed, .user = &blob_cache},
    {"affect_info", 1, PURE | JSON, .func = ax_affect_info, .user = &blob_cache},
    {"affect_crossval_json", 4, PURE, .step = ax_affect_crossval_step,
     .final = ax_affect_crossval_final},
    /* functional analysis */
    {"fda_train", 2, PURE, .step = ax_fda_train_step, .final = ax_fda_train_final},
    {"fda_train", 3, PURE, .step = ax_fda_train_step, .final = ax_fda_train_final},
    {"fda_embed", 2, PURE, .func = ax_fda_embed, .user = &blob_cache},
    {"fda_classify", 2, PURE, .func = ax_fda_classify, .user = &blob_cache},
    {"fda_classify", 3, PURE, .func = ax_fda_classify, .user = &blob_cache},
    {"fda_info", 1, PURE | JSON, .func = ax_fda_info, .user = &blob_cache},
    {"fda_prototype", 2, PURE, .func = ax_fda_prototype, .user = &blob_cache},
    {"fda_plot", 1, PURE, .func = ax_fda_plot, .user = &blob_cache},
    {"fda_plot", 2, PURE, .func = ax_fda_plot, .user = &blob_cache},
    /* generation */
    {"laban_salient", 1, READS | JSON, .func = ax_laban_salient, .user = &generation_cache},
    {"laban_salient", 2, READS | JSON, .func = ax_laban_salient, .user = &generation_cache},
    {"affect_generate", 3, READS, .func = ax_affect_generate, .user = &generation_cache},
    {"affect_generate", 4, READS, .func = ax_affect_generate, .user = &generation_cache},
    {"affect_generate_explain", 3, READS | JSON, .func = ax_affect_generate_explain,
     .user = &generation_cache},
    {"affect_generate_explain", 4, READS | JSON, .func = ax_affect_generate_explain,
     .user = &generation_cache},
    {"motion_dtw", 2, PURE, .func = ax_motion_dtw},
    /* emotion strength (fn_strength.c) */
    {"strength_train", 2, PURE, .step = ax_strength_train_step, .final = ax_strength_train_final},
    {"strength_train", 3, PURE, .step = ax_strength_train_step, .final = ax_strength_train_final},
    {"affect_strength", 2, PURE, .func = ax_affect_strength, .user = &blob_cache},
    {"strength_synthesize", 2, PURE, .func = ax_strength_synthesize},
    {"strength_synthesize", 3, PURE, .func = ax_strength_synthesize},
    {"strength_edit", 3, PURE, .func = ax_strength_edit},
    {"strength_edit", 4, PURE, .func = ax_strength_edit},
    {"strength_info", 1, PURE | JSON, .func = ax_strength_info},
    {"motion_keyframes", 1, PURE | JSON, .func = ax_motion_keyframes},
    {"motion_keyframes", 2, PURE | JSON, .func = ax_motion_keyframes},
    {"rank_train", 2, PURE, .step = ax_rank_train_step, .final = ax_rank_train_final},
    {"rank_train", 3, PURE, .step = ax_rank_train_step, .final = ax_rank_train_final},
    {"rank_score", 2, PURE, .func = ax_rank_score},
};

#undef PURE
#undef READS
#undef JSON

/* The laban virtual table's caches for other files: generation's RMLR fit (fn_generate.c). */
static const ax_laban_cache_kind laban_caches[] = {{"rmlr", ax_gen_check_fit}, {NULL, NULL}};

static int register_laban(sqlite3 *db)
{
    return ax_register_laban(db, laban_caches);
}

typedef struct ax_module {
    const char *name;
    int (*reg)(sqlite3 *db); /* sqlite3_create_module of that name, in its vt_*.c */
} ax_module;

/* Every virtual-table module, in the reference's order. */
static const ax_module modules[] = {
    {"motion_points", ax_register_points},
    {"motion_angles", ax_register_angles},
    {"laban_series", ax_register_laban_series},
    {"laban", register_laban},
    {"affect_salience", ax_register_affect_salience},
    {"affect_crossval", ax_register_affect_crossval},
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

    /* an older host does not know the result-subtype flag */
    int unknown = sqlite3_libversion_number() >= 3045000 ? 0 : SQLITE_RESULT_SUBTYPE;
    for (size_t i = 0; i < sizeof functions / sizeof functions[0]; i++) {
        const ax_function *f = &functions[i];
        void *user = (void *)f->name;
        if (f->user && !(user = f->user->make(f->name)))
            return SQLITE_NOMEM;
        int rc =
            sqlite3_create_function_v2(db, f->name, f->n_arg, f->flags & ~unknown, user, f->func,
                                       f->step, f->final, f->user ? f->user->destroy : NULL);
        if (rc != SQLITE_OK) { /* SQLite has destroyed user */
            *err = sqlite3_mprintf("affect: cannot register %s/%d: %s", f->name, f->n_arg,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    for (size_t i = 0; i < sizeof modules / sizeof modules[0]; i++) {
        int rc = modules[i].reg(db);
        if (rc != SQLITE_OK) {
            *err = sqlite3_mprintf("affect: cannot register %s: %s", modules[i].name,
                                   sqlite3_errmsg(db));
            return rc;
        }
    }
    return SQLITE_OK;
}
