/*
 * fn_generate.c — SQL wrappers of affect generation (core: affect/generate.h, affect/rmlr.h;
 * SCIENCE.md §5, thesis Fig. 5.4):
 *
 *   affect_generate(index_name, desired_motion, target_label [, options])  → motion BLOB
 *   affect_generate_explain(index_name, desired_motion, target_label [, options]) → JSON
 *   laban_salient(index_name [, options])  → JSON: per label the salient Laban components
 *                                            (elastic-net multinomial logistic regression),
 *                                            and per pair of labels the discriminative set
 *   motion_dtw(a, b)                        → REAL: DTW distance of two motions of one skeleton
 *                                            (affect_dtw_distance), to judge generated motions
 *
 * How it works: index_name names a `laban` virtual table (vt_laban.c), read only through the
 * index's own API (vt_laban.h): its labelled rows (content rowids, labels, Laban vectors), the
 * label of a motion it holds, its content table, and a cache it keeps for us. The salient
 * components come from an RMLR fit on those vectors (missing components imputed by the
 * component's mean); the fit is cached in the index (entry `rmlr`, tag `rmlr_key`) and kept per
 * connection as well; when the database cannot be written (read-only, busy) the fit is only
 * kept in memory. The key is a 64-bit FNV-1a hash of a format tag, the component names, and
 * every labelled row's label and vector bytes, with the row count, seed and folds: a fit is
 * used only for the index content it was fitted on (a rebuild that changes nothing keeps it; a
 * changed label, a recreated index of the same name or a copied `_info` row does not), and a
 * decoded or cached fit must also have the index's class, component and row counts, else it is
 * refitted; the index's 'check' command validates the stored fit with ax_gen_check_fit. An
 * index without labelled rows is an error ("index \"g\" is empty: …"). The components of the
 * searches are L \ L′_target, or L \ (L′_source ∩ L′_target) when the source emotion is known
 * (affect_transfer_components): given (source_label), read
 * from the index when the desired motion is one of its rows (same bytes), or recognized with a
 * classifier (option classifier: the classifier BLOB as hex text, e.g.
 * json_object('classifier', hex(model))).
 *   method "transfer" (default): the index's distances from the desired motion to every row on
 *   those components (its own query, k = all), the donor pairs chosen in core
 *   (affect_transfer_pairs, with pair_by's content keys when given; with pairing "action" each
 *   pair's target row is chosen among 5 candidates by affect_generate_rank_by_action), their
 *   motions read from the content table, and affect_transfer (core).
 *   method "hmm_nn": the index's own query
 *     SELECT rowid, distance FROM <index> WHERE query = :desired AND label = :target
 *                                           AND radius = :epsilon AND components = :json
 *   (ε relative to the furthest target motion, the thesis's), or `k = n`; at least
 *   min_neighbours; with prefer_action three times as many candidates ranked by DTW; their
 *   motions handed to affect_generate (core), which excludes neighbours on another skeleton.
 *
 * These functions read (and laban_salient and affect_generate may write the cache into) the
 * index's tables, so they are registered SQLITE_DIRECTONLY (not usable from triggers or views)
 * and not deterministic in SQLite's sense: for the same database content and options they
 * return the same bytes.
 *
 * Options (affect_generate and affect_generate_explain; docs/reference.md): method, components
 * ("auto" = RMLR, or an array of names), source_label, classifier (hex text), seed (1), threads
 * (1); transfer: strength (1), pairs (3), pairing ("action"), pair_by, bands ([1, 3]),
 * amplitude ("velocity"), max_ratio (3), pooled (false), keep_contacts (true); hmm_nn: copies
 * (0), states (12), epsilon (0.1), k, min_neighbours (3), prefer_action (true), cutoff_hz (3),
 * covariance_scale (1), render ("linear"), keep_path (true). An option of the other method is
 * an error. laban_salient: seed, folds (10), threads.
 */
#include "fn_generate.h"

#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "util/bytes.h"
#include "affect/classifier.h"
#include "affect/features.h"
#include "affect/generate.h"
#include "affect/skeleton.h"
#include "affect/hmm_blob.h"
#include "affect/laban.h"
#include "affect/rmlr.h"
#include "affect/roles.h"
#include "util/strbuf.h"
#include "affect/transfer.h"
#include "seqs.h"
#include "vt_laban.h"

#define N_COMP AFFECT_LABAN_N
/* Versions the cached fit's key: a fit stored under another tag is refitted. 3: the Newton
 * solver (a fit made by the coordinate-descent solver is refitted). */
#define RMLR_CACHE_TAG "affect-rmlr-cache-3"

/* ---- the per-function cache of RMLR fits ---- */

/* Donor motions kept in their skeletal form (with joint rotations): a position-only corpus
 * would otherwise go through inverse kinematics for every donor of every call. An entry is
 * found by the content row and the FNV-1a hash of its motion BLOB, so an edited row misses. */
#define DONOR_CACHE 32

typedef struct donor_entry {
    sqlite3_int64 rowid;
    uint64_t hash; /* of the BLOB's bytes, 0 for an empty entry */
    affect_motion *skeletal;
} donor_entry;

struct ax_gen_fn {
    char name[32]; /* first: AX_NAME(ctx) reads it */
    char *index;   /* the cached fit's index, content key and seed */
    uint64_t key;
    uint64_t seed;
    uint32_t folds;
    affect_rmlr *fit;
    donor_entry donors[DONOR_CACHE];
    uint32_t donor_next; /* the entry replaced next (round robin) */
};

ax_gen_fn *ax_gen_fn_new(const char *name)
{
    ax_gen_fn *fn = sqlite3_malloc64(sizeof *fn);
    if (!fn)
        return NULL;
    memset(fn, 0, sizeof *fn);
    ax_copy_name(fn->name, sizeof fn->name, name);
    return fn;
}

static void gen_cache_clear(ax_gen_fn *fn)
{
    sqlite3_free(fn->index);
    affect_rmlr_free(fn->fit);
    fn->index = NULL;
    fn->fit = NULL;
}

void ax_gen_fn_free(void *p)
{
    ax_gen_fn *fn = p;
    if (fn) {
        gen_cache_clear(fn);
        for (uint32_t i = 0; i < DONOR_CACHE; i++)
            affect_motion_free(fn->donors[i].skeletal);
        sqlite3_free(fn);
    }
}

/* ---- the index ---- */

typedef struct gen_index {
    const char *name;
    char *content, *motion; /* content table and motion column */
    uint64_t key;           /* FNV-1a of the cache tag, component names, labels and vectors */
    uint32_t n;             /* rows with a label */
    sqlite3_int64 *ids;
    double *x;     /* n × N_COMP, missing components imputed by the mean */
    uint32_t *y;   /* class of each row */
    char **labels; /* n: each row's label (owned) */
    uint32_t n_classes;
    char **classes; /* distinct labels in byte order (pointers into labels) */
} gen_index;

static void index_free(gen_index *ix)
{
    sqlite3_free(ix->content);
    sqlite3_free(ix->motion);
    affect_free(ix->ids);
    affect_free(ix->x);
    affect_free(ix->y);
    for (uint32_t i = 0; ix->labels && i < ix->n; i++)
        affect_free(ix->labels[i]);
    affect_free(ix->labels);
    affect_free(ix->classes);
    memset(ix, 0, sizeof *ix);
}

static int cmp_text(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Reports the connection's last error as "<fn>: <what>: <sqlite message>"; no error recorded
 * means our own sqlite3_mprintf failed: out of memory. */
static void db_error(sqlite3_context *ctx, const char *what)
{
    sqlite3 *db = sqlite3_context_db_handle(ctx);
    int code = sqlite3_errcode(db);
    if (code == SQLITE_NOMEM || code == SQLITE_OK)
        sqlite3_result_error_nomem(ctx);
    else
        ax_errorf(ctx, "%s: %s", what, sqlite3_errmsg(db));
}

/* A statement from a formatted SQL text, or NULL with the error reported as "<what>: …". */
static sqlite3_stmt *prepare(sqlite3_context *ctx, const char *what, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    char *sql = sqlite3_vmprintf(fmt, ap);
    va_end(ap);
    sqlite3_stmt *st = NULL;
    if (!sql ||
        sqlite3_prepare_v2(sqlite3_context_db_handle(ctx), sql, -1, &st, NULL) != SQLITE_OK) {
        sqlite3_finalize(st);
        st = NULL;
        db_error(ctx, what);
    }
    sqlite3_free(sql);
    return st;
}

/* The content key of a cached fit: FNV-1a of the cache tag, the component names, and every
 * labelled row's label and vector bytes. */
static uint64_t rows_key(const ax_laban_rows *rows)
{
    uint64_t key = affect_fnv1a64((const unsigned char *)RMLR_CACHE_TAG, sizeof RMLR_CACHE_TAG);
    for (int j = 0; j < N_COMP; j++)
        key = affect_fnv1a64_update(key, (const unsigned char *)affect_laban_names[j],
                                    strlen(affect_laban_names[j]) + 1);
    for (uint32_t i = 0; i < rows->n; i++) {
        const char *label = rows->labels[i];
        key = affect_fnv1a64_update(key, (const unsigned char *)label, strlen(label) + 1);
        key = affect_fnv1a64_update(key, rows->vectors + (size_t)i * 4 * N_COMP, 4 * N_COMP);
    }
    return key;
}

/* The index's rows (through the index's own API, vt_laban.h): ids, vectors (NaN kept for
 * now), labels, classes, and the content key of the cached fit. */
static ax_arg index_rows(sqlite3_context *ctx, gen_index *ix)
{
    sqlite3 *db = sqlite3_context_db_handle(ctx);
    ax_laban_rows rows;
    char *msg = NULL;
    int rc = ax_laban_read(db, ix->name, &rows, &msg);
    if (rc == SQLITE_NOTFOUND) {
        ax_errorf(ctx, "\"%s\" is not a laban table (CREATE VIRTUAL TABLE %s USING laban(…))",
                  ix->name, ix->name);
        return AX_ERROR;
    }
    if (rc != SQLITE_OK) {
        if (rc == SQLITE_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else if (rc == SQLITE_INTERRUPT)
            ax_interrupted(ctx);
        else
            ax_errorf(ctx, "index \"%s\": %s", ix->name, msg ? msg : "cannot be read");
        sqlite3_free(msg);
        return AX_ERROR;
    }
    /* take the strings; copy the vectors */
    ix->content = rows.content;
    ix->motion = rows.motion;
    rows.content = rows.motion = NULL;
    uint32_t n = rows.n;
    ix->ids = affect_malloc_array(n ? n : 1, sizeof *ix->ids);
    ix->x = affect_malloc_array((size_t)(n ? n : 1) * N_COMP, sizeof *ix->x);
    ix->labels = affect_calloc(n ? n : 1, sizeof *ix->labels);
    ix->classes = affect_malloc_array(n ? n : 1, sizeof *ix->classes);
    ix->y = affect_malloc_array(n ? n : 1, sizeof *ix->y);
    ax_arg r = AX_ERROR;
    if (!ix->ids || !ix->x || !ix->labels || !ix->classes || !ix->y) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    ix->key = rows_key(&rows);
    for (uint32_t i = 0; i < n; i++) {
        const unsigned char *v = rows.vectors + (size_t)i * 4 * N_COMP;
        const char *label = rows.labels[i];
        ix->ids[i] = rows.ids[i];
        for (int j = 0; j < N_COMP; j++)
            ix->x[(size_t)i * N_COMP + (size_t)j] = ax_get_f32(v + 4 * j);
        ix->labels[i] = affect_strndup(label, strlen(label));
        if (!ix->labels[i]) {
            sqlite3_result_error_nomem(ctx);
            goto done;
        }
        ix->n++;
    }
    /* classes: the distinct labels in byte order */
    memcpy(ix->classes, ix->labels, ix->n * sizeof *ix->classes);
    qsort(ix->classes, ix->n, sizeof *ix->classes, cmp_text);
    uint32_t k = 0;
    for (uint32_t i = 0; i < ix->n; i++)
        if (k == 0 || strcmp(ix->classes[i], ix->classes[k - 1]) != 0)
            ix->classes[k++] = ix->classes[i];
    ix->n_classes = k;
    for (uint32_t i = 0; i < ix->n; i++) {
        char **hit =
            bsearch(&ix->labels[i], ix->classes, ix->n_classes, sizeof *ix->classes, cmp_text);
        ix->y[i] = (uint32_t)(hit - ix->classes);
    }
    r = AX_OK;
done:
    ax_laban_rows_free(&rows);
    return r;
}

static ax_arg index_load(sqlite3_context *ctx, const char *name, gen_index *ix)
{
    memset(ix, 0, sizeof *ix);
    ix->name = name;
    if (index_rows(ctx, ix) != AX_OK)
        return AX_ERROR;
    if (ix->n == 0) { /* nothing to fit, search or learn from */
        ax_errorf(ctx, "index \"%s\" is empty: it holds no row with a label", name);
        return AX_ERROR;
    }
    /* missing components: the component's mean (0 when no row has it) */
    affect_impute_column_means(ix->x, ix->n, N_COMP);
    return AX_OK;
}

/* ---- the RMLR fit, cached ---- */

/* The key under which a fit of ix with this seed and these folds is stored. */
static void fit_key(const gen_index *ix, uint64_t seed, uint32_t folds, char out[80])
{
    sqlite3_snprintf(80, out, "%016llx:%u:%llu:%u", (unsigned long long)ix->key, ix->n,
                     (unsigned long long)seed, folds);
}

/* A fit read back from a table or a cache is only used when it was fitted on this index's
 * rows: its class, feature and row counts must match (a row vector read past them would
 * read past the fit's arrays). */
static bool fit_matches(const affect_rmlr *fit, const gen_index *ix)
{
    return affect_rmlr_n_classes(fit) == ix->n_classes && affect_rmlr_n_features(fit) == N_COMP &&
           affect_rmlr_n_train(fit) == ix->n;
}

/* The persisted fit of the index (the index's cache, vt_laban.h), if its key (the index's
 * content, seed and folds) is current and it decodes to a fit of this index's shape; NULL
 * otherwise. */
static affect_rmlr *stored_fit(sqlite3 *db, const gen_index *ix, uint64_t seed, uint32_t folds)
{
    char key[80];
    fit_key(ix, seed, folds, key);
    void *blob;
    int size;
    affect_rmlr *fit = NULL;
    if (ax_laban_cache_get(db, ix->name, "rmlr", key, &blob, &size) == SQLITE_OK && blob) {
        affect_br r;
        affect_br_init(&r, blob, (size_t)size);
        affect_error err;
        if (affect_rmlr_decode(&r, &fit, &err))
            fit = NULL;
        else if (!fit_matches(fit, ix)) {
            affect_rmlr_free(fit);
            fit = NULL;
        }
        sqlite3_free(blob);
    }
    return fit;
}

/* Stores the fit in the index's cache; failures (read-only database, busy) are ignored: the
 * fit stays cached in memory. */
static void store_fit(sqlite3 *db, const gen_index *ix, uint64_t seed, uint32_t folds,
                      const affect_rmlr *fit)
{
    affect_bw w;
    affect_bw_init(&w);
    affect_rmlr_encode(fit, &w);
    char key[80];
    fit_key(ix, seed, folds, key);
    if (!w.failed && w.len <= INT32_MAX)
        ax_laban_cache_put(db, ix->name, "rmlr", key, w.data, (int)w.len);
    affect_bw_free(&w);
}

/* Reads up to max_digits digits of base 10 or 16 (lower case) at p into *out, overflow-checked;
 * the end, or NULL when there are none or too many. */
static const char *parse_digits(const char *p, int base, int max_digits, uint64_t *out)
{
    uint64_t v = 0;
    int n = 0;
    for (;; p++, n++) {
        int d = *p >= '0' && *p <= '9'                 ? *p - '0'
                : base == 16 && *p >= 'a' && *p <= 'f' ? *p - 'a' + 10
                                                       : -1;
        if (d < 0)
            break;
        if (n == max_digits || v > (UINT64_MAX - (uint64_t)d) / (uint64_t)base)
            return NULL;
        v = v * (uint64_t)base + (uint64_t)d;
    }
    *out = v;
    return n ? p : NULL;
}

/* A fit's key as fit_key writes it: content key, rows, seed, folds. */
static bool parse_fit_key(const char *tag, uint64_t out[4])
{
    const char *p = parse_digits(tag, 16, 16, &out[0]);
    for (int i = 1; i < 4 && p; i++)
        p = *p == ':' ? parse_digits(p + 1, 10, 20, &out[i]) : NULL;
    return p && *p == '\0' && p - tag <= 80 && out[1] <= UINT32_MAX && out[3] <= UINT32_MAX;
}

int ax_gen_check_fit(const ax_laban_rows *rows, const char *tag, const void *blob, int size,
                     char **why)
{
    *why = NULL;
    uint64_t key[4];
    affect_rmlr *fit = NULL;
    char *what = NULL;
    bool bad = true;
    int rc = SQLITE_OK;
    affect_br r;
    affect_br_init(&r, blob, size > 0 ? (size_t)size : 0);
    affect_error err;
    if (!parse_fit_key(tag, key)) {
        what = sqlite3_mprintf("its key \"%.40s\" is not content:rows:seed:folds as "
                               "laban_salient writes it",
                               tag);
    } else if (affect_rmlr_decode(&r, &fit, &err)) {
        if (err.status == AFFECT_ERR_NOMEM) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        what = sqlite3_mprintf("it is not an RMLR fit (%s)", err.msg);
    } else if (r.off != r.size) {
        what =
            sqlite3_mprintf("%llu bytes follow the RMLR fit", (unsigned long long)(r.size - r.off));
    } else if (affect_rmlr_n_features(fit) != N_COMP) {
        what = sqlite3_mprintf("the fit has %llu components, expected %d",
                               (unsigned long long)affect_rmlr_n_features(fit), N_COMP);
    } else if (affect_rmlr_n_train(fit) != key[1]) {
        what = sqlite3_mprintf("the fit has %u rows, its key says %llu", affect_rmlr_n_train(fit),
                               (unsigned long long)key[1]);
    } else if (key[0] == rows_key(rows)) {
        /* the fit of the index's current rows: it must have their shape */
        const char **sorted = affect_malloc_array(rows->n ? rows->n : 1, sizeof *sorted);
        if (!sorted) {
            rc = SQLITE_NOMEM;
            goto done;
        }
        for (uint32_t i = 0; i < rows->n; i++)
            sorted[i] = rows->labels[i];
        qsort(sorted, rows->n, sizeof *sorted, cmp_text);
        uint32_t classes = 0;
        for (uint32_t i = 0; i < rows->n; i++)
            classes += i == 0 || strcmp(sorted[i], sorted[i - 1]) != 0;
        affect_free(sorted);
        if (affect_rmlr_n_train(fit) != rows->n)
            what = sqlite3_mprintf("its key names the index's rows, but the fit has %u rows and "
                                   "the index %u",
                                   affect_rmlr_n_train(fit), rows->n);
        else if (affect_rmlr_n_classes(fit) != classes)
            what = sqlite3_mprintf("its key names the index's rows, but the fit has %u classes "
                                   "and the index %u labels",
                                   affect_rmlr_n_classes(fit), classes);
        else
            bad = false;
    } else {
        bad = false; /* the fit of other rows (before a change): unused, replaced by the next */
    }
    if (bad) {
        *why = what ? sqlite3_mprintf("%s; the next laban_salient or affect_generate on the "
                                      "index replaces it",
                                      what)
                    : NULL;
        rc = *why ? SQLITE_ERROR : SQLITE_NOMEM;
    }
done:
    sqlite3_free(what);
    affect_rmlr_free(fit);
    return rc;
}

/* The index's RMLR fit: from this function's cache, the index's _info, or fitted now (the
 * α grid in `threads` threads; the fit does not depend on it). */
static ax_arg rmlr_fit(sqlite3_context *ctx, const gen_index *ix, uint64_t seed, uint32_t folds,
                       uint32_t threads, const affect_rmlr **out)
{
    ax_gen_fn *fn = sqlite3_user_data(ctx);
    if (fn->fit && fn->key == ix->key && fn->seed == seed && fn->folds == folds &&
        strcmp(fn->index, ix->name) == 0 && fit_matches(fn->fit, ix)) {
        *out = fn->fit;
        return AX_OK;
    }
    gen_cache_clear(fn);
    if (ix->n_classes < 2) {
        ax_errorf(ctx, "index \"%s\" has %u label%s; salient components need at least 2", ix->name,
                  ix->n_classes, ix->n_classes == 1 ? "" : "s");
        return AX_ERROR;
    }
    sqlite3 *db = sqlite3_context_db_handle(ctx);
    affect_rmlr *fit = stored_fit(db, ix, seed, folds);
    if (!fit) {
        affect_rmlr_options o;
        affect_rmlr_options_default(&o);
        o.seed = seed;
        o.folds = folds;
        o.threads = threads;
        o.lambda_min_ratio = 0.01; /* the weakly penalized end of the path converges slowly
                                      and is never chosen on these data */
        affect_error err;
        ax_monitor am;
        if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
            return AX_ERROR;
        o.monitor = &am.mon;
        affect_status st =
            affect_rmlr_cv(ix->x, ix->n, N_COMP, ix->y, ix->n_classes, &o, &fit, &err);
        ax_monitor_end(&am);
        if (st) {
            if (err.status == AFFECT_ERR_NOMEM || err.status == AFFECT_ERR_INTERRUPTED)
                ax_error(ctx, &err);
            else
                ax_errorf(ctx, "salient components of \"%s\": %s", ix->name, err.msg);
            return AX_ERROR;
        }
        store_fit(db, ix, seed, folds, fit);
    }
    fn->index = sqlite3_mprintf("%s", ix->name);
    if (!fn->index) {
        affect_rmlr_free(fit);
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    fn->fit = fit;
    fn->key = ix->key;
    fn->seed = seed;
    fn->folds = folds;
    *out = fit;
    return AX_OK;
}

/* Salient components of class k: the non-zero coefficients. */
static void salient_of(const affect_rmlr *fit, uint32_t k, bool on[N_COMP])
{
    const double *beta = affect_rmlr_beta(fit) + (size_t)k * N_COMP;
    for (int j = 0; j < N_COMP; j++)
        on[j] = beta[j] != 0.0;
}

static void put_components(affect_strbuf *sb, const bool on[N_COMP], bool want)
{
    affect_strbuf_putc(sb, '[');
    bool first = true;
    for (int j = 0; j < N_COMP; j++)
        if (on[j] == want) {
            affect_strbuf_puts(sb, first ? "" : ",");
            affect_strbuf_json_string(sb, affect_laban_names[j]);
            first = false;
        }
    affect_strbuf_putc(sb, ']');
}

/* ---- laban_salient ---- */

/* The "threads" option's range (the RMLR fit's). */
static ax_arg check_threads(sqlite3_context *ctx, uint32_t threads)
{
    if (threads >= 1 && threads <= AFFECT_RMLR_MAX_THREADS)
        return AX_OK;
    ax_errorf(ctx, "option \"threads\" must be from 1 to %u, got %u", AFFECT_RMLR_MAX_THREADS,
              threads);
    return AX_ERROR;
}

static const char *const salient_keys[] = {"seed", "folds", "threads", NULL};

void ax_laban_salient(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    const char *name;
    size_t len;
    ax_arg r = ax_arg_text(ctx, argv, 0, &name, &len);
    if (r != AX_OK)
        return;
    ax_opts opts;
    double seed = 1;
    uint32_t folds = 10, threads = 1;
    if (ax_opts_parse(ctx, argc, argv, 1, salient_keys, &opts) != AX_OK)
        return;
    gen_index ix;
    memset(&ix, 0, sizeof ix);
    const affect_rmlr *fit;
    if (ax_opt_whole(ctx, &opts, "seed", 9007199254740992.0, &seed) ||
        ax_opt_u32(ctx, &opts, "folds", &folds) || ax_opt_u32(ctx, &opts, "threads", &threads) ||
        check_threads(ctx, threads) || index_load(ctx, name, &ix) ||
        rmlr_fit(ctx, &ix, (uint64_t)seed, folds, threads, &fit))
        goto done;
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    affect_strbuf_printf(&sb, "{\"index\":");
    affect_strbuf_json_string(&sb, name);
    affect_strbuf_printf(&sb, ",\"rows\":%u,\"alpha\":", ix.n);
    affect_strbuf_double(&sb, affect_rmlr_alpha(fit));
    affect_strbuf_puts(&sb, ",\"lambda\":");
    affect_strbuf_double(&sb, affect_rmlr_lambda(fit));
    affect_strbuf_puts(&sb, ",\"cv_error\":");
    affect_strbuf_double(&sb, affect_rmlr_cv_error(fit));
    affect_strbuf_puts(&sb, ",\"salient\":{");
    for (uint32_t k = 0; k < ix.n_classes; k++) {
        bool on[N_COMP];
        salient_of(fit, k, on);
        affect_strbuf_puts(&sb, k ? "," : "");
        affect_strbuf_json_string(&sb, ix.classes[k]);
        affect_strbuf_putc(&sb, ':');
        put_components(&sb, on, true);
    }
    affect_strbuf_puts(&sb, "},\"pairs\":{");
    bool first = true;
    for (uint32_t a = 0; a < ix.n_classes; a++)
        for (uint32_t b = a + 1; b < ix.n_classes; b++) {
            bool sa[N_COMP], sbb[N_COMP], both[N_COMP];
            salient_of(fit, a, sa);
            salient_of(fit, b, sbb);
            for (int j = 0; j < N_COMP; j++)
                both[j] = sa[j] && sbb[j];
            char *key = sqlite3_mprintf("%s|%s", ix.classes[a], ix.classes[b]);
            affect_strbuf_puts(&sb, first ? "" : ",");
            affect_strbuf_json_string(&sb, key ? key : "");
            sqlite3_free(key);
            affect_strbuf_putc(&sb, ':');
            put_components(&sb, both, true);
            first = false;
        }
    affect_strbuf_puts(&sb, "}}");
    ax_result_json_buffer(ctx, &sb);
done:
    ax_opts_free(&opts);
    index_free(&ix);
}

/* ---- affect_generate and affect_generate_explain ---- */

static const char *const gen_keys[] = {"method",
                                       "strength",
                                       "pairs",
                                       "bands",
                                       "max_ratio",
                                       "keep_contacts",
                                       "copies",
                                       "states",
                                       "epsilon",
                                       "k",
                                       "components",
                                       "source_label",
                                       "classifier",
                                       "cutoff_hz",
                                       "covariance_scale",
                                       "seed",
                                       "render",
                                       "keep_path",
                                       "threads",
                                       "pair_by",
                                       "min_neighbours",
                                       "prefer_action",
                                       "amplitude",
                                       "pooled",
                                       "pairing",
                                       NULL};
/* In the order of affect_generate_render. */
static const char *const render_names[] = {"steps", "linear", NULL};

/* Generation methods. */
enum { METHOD_TRANSFER, METHOD_HMM_NN };
static const char *const method_names[] = {"transfer", "hmm_nn", NULL};
/* Neighbours at most (hmm_nn). */
#define MAX_NEIGHBOURS 1024u
/* Donor pairs at most. */
#define MAX_PAIRS 64u
/* Target rows among which pairing "action" chooses by DTW. */
#define PAIR_CANDIDATES 5u
/* How a donor pair's target row is chosen. */
enum { PAIRING_ACTION, PAIRING_LABAN };
static const char *const pairing_names[] = {"action", "laban", NULL};
/* Options of one method only: using one with the other method is an error, not ignored. */
static const char *const hmm_only[] = {"copies",         "states",           "epsilon", "k",
                                       "cutoff_hz",      "covariance_scale", "render",  "keep_path",
                                       "min_neighbours", "prefer_action",    NULL};
static const char *const transfer_only[] = {"strength",      "pairs",   "bands",     "max_ratio",
                                            "keep_contacts", "pair_by", "amplitude", "pooled",
                                            "pairing",       NULL};
/* In the order of affect_transfer_amplitude. */
static const char *const amplitude_names[] = {"velocity", "displacement", NULL};

typedef struct gen_opts {
    int method;
    affect_transfer_options tr;
    uint32_t pairs; /* donor pairs (transfer) */
    int pairing;    /* PAIRING_ACTION (default) or PAIRING_LABAN */
    affect_generate_options g;
    double epsilon;
    uint32_t k;              /* 0: by epsilon */
    uint32_t min_neighbours; /* hmm_nn: at least this many (3) */
    bool prefer_action;      /* hmm_nn: candidates ranked by DTW to the desired motion (true) */
    uint32_t threads;        /* for the RMLR fit when it is not cached (1) */
    bool auto_components;
    bool use[N_COMP]; /* the components asked for (not auto) */
    const char *source_label;
    const char *classifier_hex;
    const char *pair_by; /* content table column naming each row's content (transfer) */
} gen_opts;

/* The "components" option: "auto" or an array of component names. */
static ax_arg opt_components(sqlite3_context *ctx, const ax_opts *opts, gen_opts *o)
{
    const affect_json_node *n = ax_opt(opts, "components");
    o->auto_components = true;
    if (!n || (n->type == AFFECT_JSON_STRING && strcmp(n->str, "auto") == 0))
        return AX_OK;
    if (n->type != AFFECT_JSON_ARRAY || n->count == 0) {
        ax_errorf(ctx, "option \"components\" must be \"auto\" or a non-empty array of Laban "
                       "component names (laban_names())");
        return AX_ERROR;
    }
    o->auto_components = false;
    for (const affect_json_node *e = affect_json_first(opts->doc, n); e;
         e = affect_json_next_sibling(opts->doc, e)) {
        int found = -1;
        for (int j = 0; j < N_COMP && e->type == AFFECT_JSON_STRING; j++)
            if (strcmp(e->str, affect_laban_names[j]) == 0)
                found = j;
        if (found < 0) {
            ax_errorf(ctx,
                      "option \"components\": %s%s%s is not a Laban component name "
                      "(laban_names())",
                      e->type == AFFECT_JSON_STRING ? "\"" : "",
                      e->type == AFFECT_JSON_STRING ? e->str : affect_json_type_name(e->type),
                      e->type == AFFECT_JSON_STRING ? "\"" : "");
            return AX_ERROR;
        }
        o->use[found] = true;
    }
    return AX_OK;
}

/* The "bands" option: two edges in Hz, [low, high]. */
static ax_arg opt_bands(sqlite3_context *ctx, const ax_opts *opts, double band_hz[2])
{
    const affect_json_node *n = ax_opt(opts, "bands");
    if (!n)
        return AX_OK;
    const affect_json_node *e =
        n->type == AFFECT_JSON_ARRAY && n->count == 2 ? affect_json_first(opts->doc, n) : NULL;
    const affect_json_node *f = e ? affect_json_next_sibling(opts->doc, e) : NULL;
    if (!e || !f || e->type != AFFECT_JSON_NUMBER || f->type != AFFECT_JSON_NUMBER) {
        ax_errorf(ctx, "option \"bands\" must be an array of two frequencies in Hz, [low, high]");
        return AX_ERROR;
    }
    band_hz[0] = e->num;
    band_hz[1] = f->num;
    return AX_OK;
}

static ax_arg read_gen_options(sqlite3_context *ctx, int argc, sqlite3_value **argv, ax_opts *opts,
                               gen_opts *o)
{
    memset(o, 0, sizeof *o);
    affect_generate_options_default(&o->g);
    affect_transfer_options_default(&o->tr);
    o->method = METHOD_TRANSFER;
    o->pairs = 3;
    o->min_neighbours = 3;
    o->prefer_action = true;
    o->g.render = AFFECT_GENERATE_LINEAR; /* no steps between state means */
    o->epsilon = 0.1;
    o->threads = 1;
    double seed = (double)o->g.seed;
    int render = (int)o->g.render, amplitude = (int)o->tr.amplitude;
    if (ax_opts_parse(ctx, argc, argv, 3, gen_keys, opts) != AX_OK)
        return AX_ERROR;
    if (ax_opt_enum(ctx, opts, "method", method_names, &o->method) ||
        ax_opt_number(ctx, opts, "strength", &o->tr.strength) ||
        ax_opt_u32(ctx, opts, "pairs", &o->pairs) || opt_bands(ctx, opts, o->tr.band_hz) ||
        ax_opt_number(ctx, opts, "max_ratio", &o->tr.max_ratio) ||
        ax_opt_bool(ctx, opts, "keep_contacts", &o->tr.keep_contacts) ||
        ax_opt_enum(ctx, opts, "amplitude", amplitude_names, &amplitude) ||
        ax_opt_bool(ctx, opts, "pooled", &o->tr.pooled) ||
        ax_opt_enum(ctx, opts, "pairing", pairing_names, &o->pairing) ||
        ax_opt_u32(ctx, opts, "copies", &o->g.copies) ||
        ax_opt_u32(ctx, opts, "states", &o->g.states) ||
        ax_opt_number(ctx, opts, "epsilon", &o->epsilon) || ax_opt_u32(ctx, opts, "k", &o->k) ||
        ax_opt_u32(ctx, opts, "min_neighbours", &o->min_neighbours) ||
        ax_opt_bool(ctx, opts, "prefer_action", &o->prefer_action) ||
        opt_components(ctx, opts, o) ||
        ax_opt_string(ctx, opts, "source_label", &o->source_label) ||
        ax_opt_string(ctx, opts, "classifier", &o->classifier_hex) ||
        ax_opt_string(ctx, opts, "pair_by", &o->pair_by) ||
        ax_opt_number(ctx, opts, "cutoff_hz", &o->g.cutoff_hz) ||
        ax_opt_number(ctx, opts, "covariance_scale", &o->g.covariance_scale) ||
        ax_opt_whole(ctx, opts, "seed", 9007199254740992.0, &seed) ||
        ax_opt_enum(ctx, opts, "render", render_names, &render) ||
        ax_opt_bool(ctx, opts, "keep_path", &o->g.keep_path) ||
        ax_opt_u32(ctx, opts, "threads", &o->threads) || check_threads(ctx, o->threads))
        return AX_ERROR;
    o->g.seed = (uint64_t)seed;
    o->g.render = (affect_generate_render)render;
    o->tr.amplitude = (affect_transfer_amplitude)amplitude;
    if (!(o->epsilon > 0) || !(o->epsilon <= 1)) {
        ax_errorf(ctx, "option \"epsilon\" must be in (0, 1] (a fraction of the distance to the "
                       "furthest target motion)");
        return AX_ERROR;
    }
    if (ax_opt(opts, "k") && o->k == 0) {
        ax_errorf(ctx, "option \"k\" must be at least 1");
        return AX_ERROR;
    }
    const char *const *other = o->method == METHOD_TRANSFER ? hmm_only : transfer_only;
    for (int i = 0; other[i]; i++)
        if (ax_opt(opts, other[i])) {
            ax_errorf(ctx, "option \"%s\" applies to {\"method\":\"%s\"} only", other[i],
                      method_names[o->method == METHOD_TRANSFER ? METHOD_HMM_NN : METHOD_TRANSFER]);
            return AX_ERROR;
        }
    if (o->min_neighbours < 1 || o->min_neighbours > MAX_NEIGHBOURS / 3) {
        ax_errorf(ctx, "option \"min_neighbours\" must be from 1 to %u, got %u", MAX_NEIGHBOURS / 3,
                  o->min_neighbours);
        return AX_ERROR;
    }
    if (o->pairs < 1 || o->pairs > MAX_PAIRS) {
        ax_errorf(ctx, "option \"pairs\" must be from 1 to %u, got %u", MAX_PAIRS, o->pairs);
        return AX_ERROR;
    }
    const char *bad = affect_transfer_options_check(&o->tr);
    if (bad) {
        ax_errorf(ctx, "option %s", bad);
        return AX_ERROR;
    }
    return AX_OK;
}

/* Index of a label among the index's classes, or −1. */
static int class_of(const gen_index *ix, const char *label)
{
    for (uint32_t k = 0; k < ix->n_classes; k++)
        if (strcmp(ix->classes[k], label) == 0)
            return (int)k;
    return -1;
}

static void unknown_label(sqlite3_context *ctx, const gen_index *ix, const char *what,
                          const char *label)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    for (uint32_t k = 0; k < ix->n_classes && k < 20; k++) {
        affect_strbuf_puts(&sb, k ? ", " : "");
        affect_strbuf_puts(&sb, ix->classes[k]);
    }
    char *list;
    size_t len;
    affect_error err;
    if (affect_strbuf_finish(&sb, &list, &len, &err)) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    ax_errorf(ctx, "%s \"%s\": no motion of \"%s\" has this label (labels: %s)", what, label,
              ix->name, len ? list : "none");
    affect_free(list);
}

/* Where the source emotion came from. */
typedef struct source_info {
    int cls;          /* class index, or −1 */
    const char *how;  /* "option", "index", "classifier", "none" */
    char *recognized; /* classifier's label (affect_free) */
} source_info;

static uint8_t hex_digit(char c, bool *bad)
{
    if (c >= '0' && c <= '9')
        return (uint8_t)(c - '0');
    if (c >= 'a' && c <= 'f')
        return (uint8_t)(c - 'a' + 10);
    if (c >= 'A' && c <= 'F')
        return (uint8_t)(c - 'A' + 10);
    *bad = true;
    return 0;
}

/* The source label by the classifier of the option (hex text of a classifier BLOB). */
static ax_arg classify_source(sqlite3_context *ctx, const char *hex, const affect_motion *m,
                              source_info *src)
{
    size_t len = strlen(hex);
    bool bad = len % 2 != 0;
    unsigned char *blob = affect_malloc(len / 2 + 1);
    if (!blob) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    for (size_t i = 0; i + 1 < len; i += 2)
        blob[i / 2] = (uint8_t)(hex_digit(hex[i], &bad) << 4 | hex_digit(hex[i + 1], &bad));
    affect_classifier *c = NULL;
    double *x = NULL, *desc = NULL;
    uint32_t T = 0;
    affect_error err;
    ax_arg r = AX_ERROR;
    if (bad) {
        ax_errorf(ctx, "option \"classifier\" must be a classifier BLOB as hex text "
                       "(json_object('classifier', hex(model)))");
        goto done;
    }
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    affect_status st = affect_classifier_decode(blob, len / 2, &c, &err);
    if (!st)
        st = affect_classifier_observe(c, m, &x, &T, &desc, &am.mon, &err);
    if (st && st != AFFECT_ERR_INTERRUPTED) {
        ax_monitor_end(&am);
        if (err.status == AFFECT_ERR_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else
            ax_errorf(ctx, "option \"classifier\": %s", err.msg);
        goto done;
    }
    affect_classifier_out o = {0};
    if (!st)
        st = affect_classifier_eval(c, x, T, desc, false, &o, &am.mon, &err);
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    const char *label = affect_classifier_label(c, o.svm);
    src->recognized = affect_strndup(label, strlen(label));
    if (!src->recognized) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    r = AX_OK;
done:
    affect_free(x);
    affect_free(desc);
    affect_classifier_free(c);
    affect_free(blob);
    return r;
}

/* The source emotion: option, the index row with the desired motion's bytes, the classifier,
 * or none. */
static ax_arg find_source(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                          sqlite3_value *desired, const affect_motion *m, source_info *src)
{
    src->cls = -1;
    src->how = "none";
    src->recognized = NULL;
    if (o->source_label) {
        src->cls = class_of(ix, o->source_label);
        if (src->cls < 0) {
            unknown_label(ctx, ix, "source_label", o->source_label);
            return AX_ERROR;
        }
        src->how = "option";
        return AX_OK;
    }
    if (o->classifier_hex) {
        if (classify_source(ctx, o->classifier_hex, m, src) != AX_OK)
            return AX_ERROR;
        src->cls = class_of(ix, src->recognized);
        src->how = "classifier";
        return AX_OK;
    }
    char *label = NULL, *msg = NULL;
    int rc =
        ax_laban_label_of(sqlite3_context_db_handle(ctx), ix->name, sqlite3_value_blob(desired),
                          sqlite3_value_bytes(desired), &label, &msg);
    if (rc != SQLITE_OK) {
        if (rc == SQLITE_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else
            ax_errorf(ctx, "reading the index: %s", msg ? msg : "failed");
        sqlite3_free(msg);
        return AX_ERROR;
    }
    if (label) {
        src->cls = class_of(ix, label);
        src->how = "index";
    }
    sqlite3_free(label);
    return AX_OK;
}

/* The components for the neighbour search (and the salient sets, for the explanation). */
typedef struct comp_choice {
    bool use[N_COMP];
    bool sal_t[N_COMP], sal_o[N_COMP];
    bool fell_back; /* every component was salient: all used */
    const affect_rmlr *fit;
} comp_choice;

static ax_arg choose_components(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                                int target, const source_info *src, comp_choice *cc)
{
    memset(cc, 0, sizeof *cc);
    if (!o->auto_components) {
        memcpy(cc->use, o->use, sizeof cc->use);
        return AX_OK;
    }
    if (rmlr_fit(ctx, ix, o->g.seed, 10, o->threads, &cc->fit) != AX_OK)
        return AX_ERROR;
    /* the two classes' salience as rows 0 (source) and 1 (target) */
    bool salient[2 * N_COMP];
    salient_of(cc->fit, (uint32_t)target, cc->sal_t);
    if (src->cls >= 0)
        salient_of(cc->fit, (uint32_t)src->cls, cc->sal_o);
    memcpy(salient, cc->sal_o, sizeof cc->sal_o);
    memcpy(salient + N_COMP, cc->sal_t, sizeof cc->sal_t);
    cc->fell_back = affect_transfer_components(salient, N_COMP, src->cls >= 0 ? 0 : -1, 1, cc->use);
    return AX_OK;
}

static char *components_json(const bool use[N_COMP])
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    put_components(&sb, use, true);
    char *text;
    size_t len;
    affect_error err;
    return affect_strbuf_finish(&sb, &text, &len, &err) ? NULL : text;
}

/* The neighbours: content rowids and distances from the index's own query. */
typedef struct neighbours {
    uint32_t n;
    sqlite3_int64 ids[MAX_NEIGHBOURS];
    double dist[MAX_NEIGHBOURS];
    double dtw[MAX_NEIGHBOURS]; /* with prefer_action: DTW to the desired motion */
    bool by_k, filled, ranked;
} neighbours;

/* The index's query: the k nearest target rows (by_k) or the ε-ball, into nb. */
static ax_arg query_neighbours(sqlite3_context *ctx, const gen_index *ix, sqlite3_value *desired,
                               const char *target, const char *comps, bool by_k, uint32_t k,
                               double epsilon, neighbours *nb)
{
    nb->n = 0;
    sqlite3_stmt *st = prepare(ctx, "the neighbour search",
                               "SELECT rowid, distance FROM \"%w\" WHERE query = ?1 AND "
                               "label = ?2 AND components = ?3 AND %s = ?4 "
                               "ORDER BY distance, rowid",
                               ix->name, by_k ? "k" : "radius");
    if (!st)
        return AX_ERROR;
    sqlite3_bind_value(st, 1, desired);
    sqlite3_bind_text(st, 2, target, -1, SQLITE_STATIC);
    sqlite3_bind_text(st, 3, comps, -1, SQLITE_STATIC);
    if (by_k)
        sqlite3_bind_int64(st, 4, k);
    else
        sqlite3_bind_double(st, 4, epsilon);
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW && nb->n < MAX_NEIGHBOURS) {
        nb->ids[nb->n] = sqlite3_column_int64(st, 0);
        nb->dist[nb->n++] = sqlite3_column_double(st, 1);
    }
    sqlite3_finalize(st);
    if (rc != SQLITE_ROW && rc != SQLITE_DONE) {
        db_error(ctx, "the neighbour search");
        return AX_ERROR;
    }
    return AX_OK;
}

static ax_arg load_motions(sqlite3_context *ctx, const gen_index *ix, const sqlite3_int64 *ids,
                           uint32_t n, affect_motion **out);

/* Keeps the `want` candidates of nb nearest to m by DTW (affect_generate_rank_by_action), in
 * that order. */
static ax_arg rank_by_action(sqlite3_context *ctx, const gen_index *ix, const affect_motion *m,
                             uint32_t want, neighbours *nb)
{
    uint32_t n = nb->n;
    affect_motion **cand = affect_calloc(n ? n : 1, sizeof *cand);
    uint32_t *order = affect_malloc_array(n ? n : 1, sizeof *order);
    double *dtw = affect_malloc_array(n ? n : 1, sizeof *dtw);
    sqlite3_int64 *ids = affect_malloc_array(n ? n : 1, sizeof *ids);
    double *dist = affect_malloc_array(n ? n : 1, sizeof *dist);
    ax_arg r = AX_ERROR;
    affect_error err;
    if (!cand || !order || !dtw || !ids || !dist) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    if (load_motions(ctx, ix, nb->ids, n, cand) != AX_OK)
        goto done;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    affect_status st = affect_generate_rank_by_action(m, (const affect_motion *const *)cand, n,
                                                      order, dtw, &am.mon, &err);
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    if (want > n)
        want = n;
    for (uint32_t i = 0; i < want; i++) {
        ids[i] = nb->ids[order[i]];
        dist[i] = nb->dist[order[i]];
        nb->dtw[i] = dtw[order[i]];
    }
    memcpy(nb->ids, ids, want * sizeof *ids);
    memcpy(nb->dist, dist, want * sizeof *dist);
    nb->n = want;
    nb->ranked = true;
    r = AX_OK;
done:
    for (uint32_t i = 0; cand && i < n; i++)
        affect_motion_free(cand[i]);
    affect_free(cand);
    affect_free(order);
    affect_free(dtw);
    affect_free(ids);
    affect_free(dist);
    return r;
}

/* HMM_NN's neighbours: the ε-ball (or the k nearest), at least min_neighbours of them; with
 * prefer_action that many chosen among three times as many nearest candidates by their DTW
 * distance to the desired motion, so that neighbours of the desired motion's own action come
 * first when the index has them. */
static ax_arg find_neighbours(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                              sqlite3_value *desired, const affect_motion *m, const char *target,
                              const char *comps, neighbours *nb)
{
    nb->by_k = o->k > 0;
    nb->filled = nb->ranked = false;
    if (query_neighbours(ctx, ix, desired, target, comps, nb->by_k, o->k, o->epsilon, nb))
        return AX_ERROR;
    uint32_t want = nb->n;
    if (want < o->min_neighbours) {
        want = o->min_neighbours;
        nb->filled = true;
    }
    if (!o->prefer_action)
        return nb->filled ? query_neighbours(ctx, ix, desired, target, comps, true, want, 0, nb)
                          : AX_OK;
    uint32_t pool = want > MAX_NEIGHBOURS / 3 ? MAX_NEIGHBOURS : 3 * want;
    if (query_neighbours(ctx, ix, desired, target, comps, true, pool, 0, nb) != AX_OK)
        return AX_ERROR;
    return rank_by_action(ctx, ix, m, want, nb);
}

/* What is made of one content row's motion BLOB (a decoded motion into *out); a status with
 * err on failure. */
typedef affect_status (*motion_row_fn)(void *arg, sqlite3_int64 id, const unsigned char *blob,
                                       size_t size, affect_motion **out, affect_error *err);

/* Reads the motion BLOB of content rows ids[0 .. n) and makes out[i] of each with row. Errors:
 * "content row 7 of "g" has no motion (run the index's 'check' command)", SQLITE_NOMEM, the
 * interrupt, or "content row 7: <row's message>". */
static ax_arg read_motions(sqlite3_context *ctx, const gen_index *ix, const sqlite3_int64 *ids,
                           uint32_t n, motion_row_fn row, void *arg, affect_motion **out)
{
    sqlite3_stmt *st =
        prepare(ctx, "reading the content table", "SELECT \"%w\" FROM \"%w\" WHERE rowid = ?1",
                ix->motion, ix->content);
    if (!st)
        return AX_ERROR;
    ax_arg r = AX_OK;
    for (uint32_t i = 0; i < n && r == AX_OK; i++) {
        sqlite3_reset(st);
        sqlite3_bind_int64(st, 1, ids[i]);
        if (sqlite3_step(st) != SQLITE_ROW || sqlite3_column_type(st, 0) != SQLITE_BLOB) {
            ax_errorf(ctx,
                      "content row %" PRId64 " of \"%s\" has no motion (run the index's "
                      "'check' command)",
                      (int64_t)ids[i], ix->name);
            r = AX_ERROR;
            break;
        }
        affect_error err;
        affect_status s = row(arg, ids[i], sqlite3_column_blob(st, 0),
                              (size_t)sqlite3_column_bytes(st, 0), &out[i], &err);
        if (s) {
            if (s == AFFECT_ERR_NOMEM)
                sqlite3_result_error_nomem(ctx);
            else if (s == AFFECT_ERR_INTERRUPTED)
                ax_error(ctx, &err);
            else
                ax_errorf(ctx, "content row %" PRId64 ": %s", (int64_t)ids[i], err.msg);
            r = AX_ERROR;
        }
    }
    sqlite3_finalize(st);
    return r;
}

static affect_status decode_row(void *arg, sqlite3_int64 id, const unsigned char *blob, size_t size,
                                affect_motion **out, affect_error *err)
{
    (void)arg;
    (void)id;
    return affect_motion_decode(blob, size, out, err);
}

/* The motions of content rows ids[0 .. n) from the content table. */
static ax_arg load_motions(sqlite3_context *ctx, const gen_index *ix, const sqlite3_int64 *ids,
                           uint32_t n, affect_motion **out)
{
    return read_motions(ctx, ix, ids, n, decode_row, NULL, out);
}

typedef struct donor_reader {
    ax_gen_fn *fn;
    affect_ik_options io;
} donor_reader;

/* A donor in its skeletal form, from the cache when the row's BLOB is the one cached, else
 * decoded and given joint rotations (affect_motion_skeletal, as affect_transfer would: the same
 * motion, bit for bit) and cached. A motion that has no skeletal form is returned as decoded,
 * uncached: affect_transfer then says what is wrong. */
static affect_status donor_row(void *arg, sqlite3_int64 id, const unsigned char *blob, size_t size,
                               affect_motion **out, affect_error *err)
{
    donor_reader *dr = arg;
    ax_gen_fn *fn = dr->fn;
    uint64_t hash = affect_fnv1a64(blob, size) | 1u; /* never 0, the empty entry's */
    donor_entry *hit = NULL;
    for (uint32_t e = 0; e < DONOR_CACHE && !hit; e++)
        if (fn->donors[e].hash == hash && fn->donors[e].rowid == id)
            hit = &fn->donors[e];
    if (hit)
        return affect_motion_clone(hit->skeletal, out, err);
    affect_status s = affect_motion_decode(blob, size, out, err);
    if (s)
        return s;
    affect_motion *made = NULL, *keep = NULL;
    affect_status k = affect_motion_skeletal(*out, AFFECT_ROTATIONS_AUTO, &dr->io, &made, err);
    if (k == AFFECT_ERR_INTERRUPTED || k == AFFECT_ERR_NOMEM)
        return k;
    if (!k && made) {
        affect_motion_free(*out);
        *out = made;
    }
    if (!k && affect_motion_clone(*out, &keep, err) == AFFECT_OK) {
        donor_entry *slot = &fn->donors[fn->donor_next];
        affect_motion_free(slot->skeletal);
        *slot = (donor_entry){id, hash, keep};
        fn->donor_next = (fn->donor_next + 1) % DONOR_CACHE;
    }
    return AFFECT_OK;
}

/* load_motions for the transfer's donors (donor_row), from fn's cache when it can. */
static ax_arg load_donors(sqlite3_context *ctx, ax_gen_fn *fn, const gen_index *ix,
                          const sqlite3_int64 *ids, uint32_t n, affect_monitor *mon,
                          affect_motion **out)
{
    donor_reader dr = {.fn = fn};
    affect_ik_options_default(&dr.io);
    dr.io.rigid.monitor = mon;
    return read_motions(ctx, ix, ids, n, donor_row, &dr, out);
}

/* The explanation's common head: index, method, target, source and components (the object
 * left open). */
static void explain_head(affect_strbuf *sb, const gen_index *ix, const gen_opts *o,
                         const char *target, const source_info *src, const comp_choice *cc)
{
    affect_strbuf_puts(sb, "{\"index\":");
    affect_strbuf_json_string(sb, ix->name);
    affect_strbuf_printf(sb, ",\"method\":\"%s\",\"target\":", method_names[o->method]);
    affect_strbuf_json_string(sb, target);
    affect_strbuf_puts(sb, ",\"source\":{\"label\":");
    if (src->cls >= 0)
        affect_strbuf_json_string(sb, ix->classes[src->cls]);
    else
        affect_strbuf_puts(sb, "null");
    affect_strbuf_printf(sb, ",\"from\":\"%s\"", src->how);
    if (src->recognized) {
        affect_strbuf_puts(sb, ",\"recognized\":");
        affect_strbuf_json_string(sb, src->recognized);
    }
    affect_strbuf_printf(sb, "},\"components\":{\"chosen_by\":\"%s\",\"used\":",
                         o->auto_components ? "rmlr" : "option");
    put_components(sb, cc->use, true);
    affect_strbuf_puts(sb, ",\"excluded\":");
    put_components(sb, cc->use, false);
    if (o->auto_components) {
        affect_strbuf_puts(sb, ",\"salient_target\":");
        put_components(sb, cc->sal_t, true);
        if (src->cls >= 0) {
            affect_strbuf_puts(sb, ",\"salient_source\":");
            put_components(sb, cc->sal_o, true);
        }
        affect_strbuf_printf(sb, ",\"all_salient_fallback\":%s", cc->fell_back ? "true" : "false");
    }
    affect_strbuf_puts(sb, "}");
}

static void explain_json(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                         const char *target, const source_info *src, const comp_choice *cc,
                         const neighbours *nb, const affect_generate_report *rep, uint32_t frames)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    explain_head(&sb, ix, o, target, src, cc);
    affect_strbuf_puts(&sb, ",\"neighbours\":{\"by\":");
    if (nb->by_k)
        affect_strbuf_printf(&sb, "\"k\",\"k\":%u", o->k);
    else {
        affect_strbuf_puts(&sb, "\"epsilon\",\"epsilon\":");
        affect_strbuf_double(&sb, o->epsilon);
    }
    affect_strbuf_printf(&sb,
                         ",\"min_neighbours\":%u,\"filled_to_min\":%s,"
                         "\"ranked_by_action\":%s,\"rows\":[",
                         o->min_neighbours, nb->filled ? "true" : "false",
                         nb->ranked ? "true" : "false");
    for (uint32_t i = 0; i < nb->n; i++) {
        affect_strbuf_printf(&sb, "%s{\"rowid\":%" PRId64 ",\"distance\":", i ? "," : "",
                             (int64_t)nb->ids[i]);
        affect_strbuf_double(&sb, nb->dist[i]);
        if (nb->ranked) {
            affect_strbuf_puts(&sb, ",\"dtw\":");
            if (isfinite(nb->dtw[i]))
                affect_strbuf_double(&sb, nb->dtw[i]);
            else
                affect_strbuf_puts(&sb, "null");
        }
        affect_strbuf_putc(&sb, '}');
    }
    affect_strbuf_printf(&sb,
                         "],\"used\":%u,\"excluded_skeleton\":%u},\"hmm\":{\"states\":%u,"
                         "\"copies\":%u,\"iterations\":%u,\"loglik\":",
                         rep->neighbours_used, rep->excluded, o->g.states, o->g.copies,
                         rep->iterations);
    affect_strbuf_double(&sb, rep->loglik);
    affect_strbuf_printf(&sb, "},\"output\":{\"render\":\"%s\",\"keep_path\":%s,\"cutoff_hz\":",
                         render_names[o->g.render], o->g.keep_path ? "true" : "false");
    affect_strbuf_double(&sb, o->g.cutoff_hz);
    affect_strbuf_puts(&sb, ",\"covariance_scale\":");
    affect_strbuf_double(&sb, o->g.covariance_scale);
    affect_strbuf_puts(&sb, "},\"viterbi\":{\"logprob\":");
    affect_strbuf_double(&sb, rep->viterbi_logprob);
    affect_strbuf_puts(&sb, ",\"path\":[");
    for (uint32_t t = 0; t < frames && rep->path; t++)
        affect_strbuf_printf(&sb, "%s%d", t ? "," : "", (int)rep->path[t]);
    affect_strbuf_puts(&sb, "]}}");
    ax_result_json_buffer(ctx, &sb);
}

/* ---- the transfer method ---- */

typedef struct donors {
    uint32_t n;
    uint32_t from[MAX_PAIRS], to[MAX_PAIRS];    /* index rows */
    uint32_t cand[MAX_PAIRS * PAIR_CANDIDATES]; /* the target candidates of each pair */
    double cand_dist[MAX_PAIRS * PAIR_CANDIDATES];
    double dq[MAX_PAIRS], dist[MAX_PAIRS]; /* desired → from, from → to */
    sqlite3_int64 ids[2 * MAX_PAIRS];      /* content rowids: the from rows, then the to rows */
} donors;

static int cmp_id(const void *a, const void *b)
{
    sqlite3_int64 x = *(const sqlite3_int64 *)a, y = *(const sqlite3_int64 *)b;
    return (x > y) - (x < y);
}

/* dq[i]: the index's distance from the desired motion to its row i on the components (NaN
 * when the index gives none), from the index's own query. */
static ax_arg query_distances(sqlite3_context *ctx, const gen_index *ix, sqlite3_value *desired,
                              const char *comps, double *dq)
{
    for (uint32_t i = 0; i < ix->n; i++)
        dq[i] = NAN;
    sqlite3_stmt *st = prepare(ctx, "the donor search",
                               "SELECT rowid, distance FROM \"%w\" WHERE query = ?1 AND "
                               "components = ?2 AND k = ?3",
                               ix->name);
    if (!st)
        return AX_ERROR;
    sqlite3_bind_value(st, 1, desired);
    sqlite3_bind_text(st, 2, comps, -1, SQLITE_STATIC);
    sqlite3_bind_int64(st, 3, (sqlite3_int64)ix->n + 1000000);
    int rc;
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        sqlite3_int64 id = sqlite3_column_int64(st, 0);
        const sqlite3_int64 *hit = bsearch(&id, ix->ids, ix->n, sizeof *ix->ids, cmp_id);
        if (hit && sqlite3_column_type(st, 1) != SQLITE_NULL)
            dq[hit - ix->ids] = sqlite3_column_double(st, 1);
    }
    sqlite3_finalize(st);
    if (rc != SQLITE_DONE) {
        db_error(ctx, "the donor search");
        return AX_ERROR;
    }
    return AX_OK;
}

/* group[i]: a key of the value of column pair_by in row i's content row (its dense rank:
 * equal values, equal keys), INT64_MIN when NULL. */
static ax_arg content_keys(sqlite3_context *ctx, const gen_index *ix, const char *column,
                           int64_t *group)
{
    for (uint32_t i = 0; i < ix->n; i++)
        group[i] = INT64_MIN;
    sqlite3 *db = sqlite3_context_db_handle(ctx);
    /* a double-quoted name that is not a column would be read as a string: check it first */
    sqlite3_stmt *chk =
        prepare(ctx, "reading the content table",
                "SELECT count(*) FROM pragma_table_info(%Q) WHERE name = %Q", ix->content, column);
    if (!chk)
        return AX_ERROR;
    bool exists = sqlite3_step(chk) == SQLITE_ROW && sqlite3_column_int(chk, 0) > 0;
    sqlite3_finalize(chk);
    if (!exists) {
        ax_errorf(ctx, "option \"pair_by\": \"%s\" is not a column of the content table \"%s\"",
                  column, ix->content);
        return AX_ERROR;
    }
    char *sql = sqlite3_mprintf("SELECT rowid, dense_rank() OVER (ORDER BY \"%w\") FROM \"%w\" "
                                "WHERE \"%w\" IS NOT NULL",
                                column, ix->content, column);
    sqlite3_stmt *st = NULL;
    if (!sql) {
        sqlite3_result_error_nomem(ctx);
        return AX_ERROR;
    }
    int rc = sqlite3_prepare_v2(db, sql, -1, &st, NULL);
    sqlite3_free(sql);
    if (rc != SQLITE_OK) {
        if (rc == SQLITE_NOMEM)
            sqlite3_result_error_nomem(ctx);
        else
            ax_errorf(ctx,
                      "option \"pair_by\": \"%s\" is not a column of the content table "
                      "\"%s\" (%s)",
                      column, ix->content, sqlite3_errmsg(db));
        return AX_ERROR;
    }
    while ((rc = sqlite3_step(st)) == SQLITE_ROW) {
        sqlite3_int64 id = sqlite3_column_int64(st, 0);
        const sqlite3_int64 *hit = bsearch(&id, ix->ids, ix->n, sizeof *ix->ids, cmp_id);
        if (hit)
            group[hit - ix->ids] = sqlite3_column_int64(st, 1);
    }
    sqlite3_finalize(st);
    if (rc != SQLITE_DONE) {
        db_error(ctx, "reading the content table");
        return AX_ERROR;
    }
    return AX_OK;
}

/* Pairing "action": each source row takes, among its PAIR_CANDIDATES nearest target rows, the
 * one nearest to it by DTW (affect_generate_rank_by_action: the same action), preferring one
 * that no earlier pair took. */
static ax_arg choose_by_action(sqlite3_context *ctx, const gen_index *ix, uint32_t nc, donors *dn)
{
    affect_motion *a = NULL, *cand[PAIR_CANDIDATES] = {NULL};
    ax_arg r = AX_OK;
    for (uint32_t k = 0; k < dn->n && r == AX_OK; k++) {
        uint32_t m = 0;
        sqlite3_int64 ids[PAIR_CANDIDATES];
        uint32_t rows[PAIR_CANDIDATES];
        for (uint32_t c = 0; c < nc; c++)
            if (dn->cand[(size_t)k * nc + c] != UINT32_MAX) {
                rows[m] = dn->cand[(size_t)k * nc + c];
                ids[m] = ix->ids[rows[m]];
                m++;
            }
        sqlite3_int64 aid = ix->ids[dn->from[k]];
        uint32_t order[PAIR_CANDIDATES];
        affect_error err;
        if (m < 2)
            continue;
        ax_monitor am;
        affect_status st = AFFECT_OK;
        if (load_motions(ctx, ix, &aid, 1, &a) != AX_OK ||
            load_motions(ctx, ix, ids, m, cand) != AX_OK ||
            ax_monitor_begin(&am, ctx, NULL) != AX_OK) {
            r = AX_ERROR;
        } else if ((st = affect_generate_rank_by_action(a, (const affect_motion *const *)cand, m,
                                                        order, NULL, &am.mon, &err)),
                   ax_monitor_end(&am), st) {
            ax_error(ctx, &err);
            r = AX_ERROR;
        } else {
            uint32_t pick = affect_transfer_pick_target(order, rows, m, dn->to, k);
            dn->to[k] = rows[pick];
            for (uint32_t c = 0; c < nc; c++)
                if (dn->cand[(size_t)k * nc + c] == rows[pick])
                    dn->dist[k] = dn->cand_dist[(size_t)k * nc + c];
        }
        affect_motion_free(a);
        a = NULL;
        for (uint32_t c = 0; c < m; c++) {
            affect_motion_free(cand[c]);
            cand[c] = NULL;
        }
    }
    return r;
}

/* The donor pairs (affect_transfer_pairs on the index's rows). */
static ax_arg find_donors(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                          sqlite3_value *desired, int target, const source_info *src,
                          const comp_choice *cc, const char *comps, donors *dn)
{
    double *dq = affect_malloc_array(ix->n ? ix->n : 1, sizeof *dq);
    int32_t *label = affect_malloc_array(ix->n ? ix->n : 1, sizeof *label);
    int64_t *group = o->pair_by ? affect_malloc_array(ix->n ? ix->n : 1, sizeof *group) : NULL;
    ax_arg r = AX_ERROR;
    if (!dq || !label || (o->pair_by && !group)) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    if (query_distances(ctx, ix, desired, comps, dq) != AX_OK ||
        (group && content_keys(ctx, ix, o->pair_by, group) != AX_OK))
        goto done;
    for (uint32_t i = 0; i < ix->n; i++)
        label[i] = (int32_t)ix->y[i];
    affect_error err;
    uint32_t nc = o->pairing == PAIRING_ACTION ? PAIR_CANDIDATES : 1;
    if (affect_transfer_pairs(ix->x, ix->n, N_COMP, label, group, cc->use, dq, src->cls, target,
                              o->pairs, nc, dn->from, dn->cand, dn->cand_dist, &dn->n, &err)) {
        ax_error(ctx, &err);
        goto done;
    }
    if (dn->n == 0) {
        ax_errorf(ctx,
                  "index \"%s\": no motion can donate the change (no row of the source "
                  "emotion with a row of the target emotion%s)",
                  ix->name, o->pair_by ? " of the same pair_by value" : "");
        goto done;
    }
    for (uint32_t k = 0; k < dn->n; k++) {
        dn->to[k] = dn->cand[(size_t)k * nc];
        dn->dist[k] = dn->cand_dist[(size_t)k * nc];
    }
    if (nc > 1 && choose_by_action(ctx, ix, nc, dn) != AX_OK)
        goto done;
    for (uint32_t k = 0; k < dn->n; k++) {
        dn->dq[k] = dq[dn->from[k]];
        dn->ids[k] = ix->ids[dn->from[k]];
        dn->ids[dn->n + k] = ix->ids[dn->to[k]];
    }
    r = AX_OK;
done:
    affect_free(dq);
    affect_free(label);
    affect_free(group);
    return r;
}

/* Laban vectors of the desired and the generated motion (default options; NaN when a
 * component cannot be computed), for the explanation's per-component change. */
static void laban_change(const affect_motion *a, const affect_motion *b, double *delta)
{
    affect_laban_options lo;
    affect_laban_options_default(&lo);
    lo.missing_null = true;
    double va[N_COMP], vb[N_COMP];
    affect_roles ra, rb;
    affect_roles_resolve(a, &ra);
    affect_roles_resolve(b, &rb);
    affect_error err;
    bool ok = affect_laban_vector(a, &ra, &lo, va, &err) == AFFECT_OK &&
              affect_laban_vector(b, &rb, &lo, vb, &err) == AFFECT_OK;
    for (int j = 0; j < N_COMP; j++)
        delta[j] = ok ? vb[j] - va[j] : NAN;
}

static void explain_transfer(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                             const char *target, const source_info *src, const comp_choice *cc,
                             const donors *dn, const affect_transfer_report *rep,
                             const double *delta)
{
    affect_strbuf sb;
    affect_strbuf_init(&sb);
    explain_head(&sb, ix, o, target, src, cc);
    affect_strbuf_puts(&sb, ",\"strength\":");
    affect_strbuf_double(&sb, o->tr.strength);
    affect_strbuf_puts(&sb, ",\"pairs\":[");
    for (uint32_t k = 0; k < dn->n; k++) {
        affect_strbuf_printf(&sb, "%s{\"from\":{\"rowid\":%" PRId64 ",\"label\":", k ? "," : "",
                             (int64_t)dn->ids[k]);
        affect_strbuf_json_string(&sb, ix->labels[dn->from[k]]);
        affect_strbuf_puts(&sb, ",\"distance\":");
        affect_strbuf_double(&sb, dn->dq[k]);
        affect_strbuf_printf(
            &sb, "},\"to\":{\"rowid\":%" PRId64 ",\"label\":", (int64_t)dn->ids[dn->n + k]);
        affect_strbuf_json_string(&sb, ix->labels[dn->to[k]]);
        affect_strbuf_puts(&sb, ",\"distance\":");
        affect_strbuf_double(&sb, dn->dist[k]);
        affect_strbuf_puts(&sb, "}}");
    }
    affect_strbuf_printf(&sb, "],\"change\":{\"joints\":%u,\"posture_deg\":", rep->joints_changed);
    affect_strbuf_double(&sb, rep->posture_deg);
    affect_strbuf_puts(&sb, ",\"amplitude_ratios\":[");
    for (int b = 0; b < AFFECT_TRANSFER_BANDS; b++) {
        affect_strbuf_puts(&sb, b ? "," : "");
        affect_strbuf_double(&sb, rep->ratio[b]);
    }
    affect_strbuf_puts(&sb, "],\"bands_hz\":[");
    affect_strbuf_double(&sb, o->tr.band_hz[0]);
    affect_strbuf_putc(&sb, ',');
    affect_strbuf_double(&sb, o->tr.band_hz[1]);
    affect_strbuf_puts(&sb, "],\"max_ratio\":");
    affect_strbuf_double(&sb, o->tr.max_ratio);
    affect_strbuf_printf(&sb,
                         "},\"contacts\":{\"kept\":%s,\"left_frames\":%u,"
                         "\"right_frames\":%u},\"laban_change\":{",
                         o->tr.keep_contacts ? "true" : "false", rep->contact_frames[0],
                         rep->contact_frames[1]);
    for (int j = 0; j < N_COMP; j++) {
        affect_strbuf_puts(&sb, j ? "," : "");
        affect_strbuf_json_string(&sb, affect_laban_names[j]);
        affect_strbuf_putc(&sb, ':');
        if (isnan(delta[j]))
            affect_strbuf_puts(&sb, "null");
        else
            affect_strbuf_double(&sb, delta[j]);
    }
    affect_strbuf_puts(&sb, "}}");
    ax_result_json_buffer(ctx, &sb);
}

static void run_transfer(sqlite3_context *ctx, const gen_index *ix, const gen_opts *o,
                         sqlite3_value *desired, const affect_motion *m, int target,
                         const source_info *src, const comp_choice *cc, const char *comps,
                         bool explain)
{
    donors *dn = affect_calloc(1, sizeof *dn);
    affect_motion **motions = NULL, *out = NULL;
    if (!dn) {
        sqlite3_result_error_nomem(ctx);
        return;
    }
    if (find_donors(ctx, ix, o, desired, target, src, cc, comps, dn) != AX_OK)
        goto done;
    motions = affect_calloc(2 * (size_t)dn->n, sizeof *motions);
    if (!motions) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    if (load_donors(ctx, sqlite3_user_data(ctx), ix, dn->ids, 2 * dn->n, &am.mon, motions) !=
        AX_OK) {
        ax_monitor_end(&am);
        goto done;
    }
    affect_transfer_report rep;
    affect_error err;
    affect_transfer_options tr = o->tr;
    tr.monitor = &am.mon;
    affect_status st = affect_transfer(m, (const affect_motion *const *)motions,
                                       (const affect_motion *const *)motions + dn->n, dn->n, &tr,
                                       &out, &rep, &err);
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    if (explain) {
        double delta[N_COMP];
        laban_change(m, out, delta);
        explain_transfer(ctx, ix, o, ix->classes[target], src, cc, dn, &rep, delta);
    } else {
        ax_result_motion(ctx, out);
    }
done:
    for (uint32_t i = 0; motions && i < 2 * dn->n; i++)
        affect_motion_free(motions[i]);
    affect_free(motions);
    affect_motion_free(out);
    affect_free(dn);
}

static void run_generation(sqlite3_context *ctx, int argc, sqlite3_value **argv, bool explain)
{
    const char *name, *target;
    size_t len;
    affect_motion *m = NULL, **motions = NULL;
    ax_opts opts = {NULL, NULL};
    gen_index ix;
    memset(&ix, 0, sizeof ix);
    source_info src = {-1, "none", NULL};
    neighbours *nb = NULL;
    char *comps = NULL;
    affect_motion *out = NULL;
    affect_generate_report rep;
    memset(&rep, 0, sizeof rep);
    if (ax_arg_text(ctx, argv, 0, &name, &len) != AX_OK ||
        ax_arg_text(ctx, argv, 2, &target, &len) != AX_OK ||
        ax_arg_motion(ctx, argv, 1, &m) != AX_OK)
        goto done;
    gen_opts o;
    if (read_gen_options(ctx, argc, argv, &opts, &o) != AX_OK ||
        index_load(ctx, name, &ix) != AX_OK)
        goto done;
    int t = class_of(&ix, target);
    if (t < 0) {
        unknown_label(ctx, &ix, "target label", target);
        goto done;
    }
    comp_choice cc;
    if (find_source(ctx, &ix, &o, argv[1], m, &src) != AX_OK ||
        choose_components(ctx, &ix, &o, t, &src, &cc) != AX_OK)
        goto done;
    comps = components_json(cc.use);
    if (comps && o.method == METHOD_TRANSFER) {
        run_transfer(ctx, &ix, &o, argv[1], m, t, &src, &cc, comps, explain);
        goto done;
    }
    nb = affect_malloc(sizeof *nb);
    if (!comps || !nb) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    if (find_neighbours(ctx, &ix, &o, argv[1], m, target, comps, nb) != AX_OK)
        goto done;
    motions = affect_calloc(nb->n ? nb->n : 1, sizeof *motions);
    if (!motions) {
        sqlite3_result_error_nomem(ctx);
        goto done;
    }
    if (load_motions(ctx, &ix, nb->ids, nb->n, motions) != AX_OK)
        goto done;
    affect_error err;
    ax_monitor am;
    if (ax_monitor_begin(&am, ctx, NULL) != AX_OK)
        goto done;
    o.g.monitor = &am.mon;
    affect_status st =
        affect_generate(m, (const affect_motion *const *)motions, nb->n, &o.g, &out, &rep, &err);
    o.g.monitor = NULL;
    ax_monitor_end(&am);
    if (st) {
        ax_error(ctx, &err);
        goto done;
    }
    if (explain)
        explain_json(ctx, &ix, &o, target, &src, &cc, nb, &rep, m->n_frames);
    else
        ax_result_motion(ctx, out);
done:
    for (uint32_t i = 0; motions && nb && i < nb->n; i++)
        affect_motion_free(motions[i]);
    affect_free(motions);
    affect_motion_free(out);
    affect_free(rep.path);
    affect_free(nb);
    affect_free(comps);
    affect_free(src.recognized);
    index_free(&ix);
    ax_opts_free(&opts);
    affect_motion_free(m);
}

void ax_affect_generate(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    run_generation(ctx, argc, argv, false);
}

void ax_affect_generate_explain(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    run_generation(ctx, argc, argv, true);
}

/* ---- motion_dtw ---- */

void ax_motion_dtw(sqlite3_context *ctx, int argc, sqlite3_value **argv)
{
    (void)argc;
    affect_motion *a = NULL, *b = NULL;
    if (ax_arg_motion(ctx, argv, 0, &a) == AX_OK && ax_arg_motion(ctx, argv, 1, &b) == AX_OK) {
        double d;
        affect_error err;
        ax_monitor am;
        if (ax_monitor_begin(&am, ctx, NULL) == AX_OK) {
            affect_status st = affect_dtw_distance(a, b, &d, &am.mon, &err);
            ax_monitor_end(&am);
            if (st)
                ax_error(ctx, &err);
            else
                sqlite3_result_double(ctx, d);
        }
    }
    affect_motion_free(a);
    affect_motion_free(b);
}
