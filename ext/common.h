/*
 * common.h — helpers shared by the SQL function wrappers and virtual tables: argument
 * checking, motion BLOBs in and out, JSON options, error mapping.
 *
 * Conventions every wrapper follows:
 *   - NULL in gives NULL out (helpers return AX_NULL so the wrapper can stop);
 *   - a wrong type or malformed value gives "function_name: what is wrong (where)";
 *   - allocation failure gives SQLITE_NOMEM through sqlite3_result_error_nomem;
 *   - results allocated by the core (which allocates with sqlite3_malloc64 once the
 *     extension is loaded) are handed to SQLite with sqlite3_free as destructor, no copy.
 */
#ifndef AFFECT_EXT_COMMON_H
#define AFFECT_EXT_COMMON_H

#include <sqlite3ext.h>
SQLITE_EXTENSION_INIT3

#include "affect/base.h"
#include "util/json.h"
#include "affect/monitor.h"
#include "affect/motion.h"
#include "affect/roles.h"

/* Flags for pure functions; JSON-returning ones add the result-subtype flag when the host
 * SQLite knows it (3.45+). */
#define AX_PURE (SQLITE_UTF8 | SQLITE_DETERMINISTIC | SQLITE_INNOCUOUS)
#ifndef SQLITE_RESULT_SUBTYPE
#define SQLITE_RESULT_SUBTYPE 0x001000000
#endif
#define AX_JSON_SUBTYPE 74 /* 'J', the subtype of SQLite's own JSON functions */

/* Outcome of an argument helper. */
typedef enum ax_arg { AX_OK = 0, AX_NULL = 1, AX_ERROR = 2 } ax_arg;

/* The function's name, as registered (sqlite3_user_data points at it). */
#define AX_NAME(ctx) ((const char *)sqlite3_user_data(ctx))

/* "fn: message" as the result error; AFFECT_ERR_NOMEM becomes SQLITE_NOMEM, except a large
 * request named by affect_nomem_of, which is an error with its message: "affect_train: cannot
 * allocate the 4032 x 95333 Fisher score block (2.9 GiB): out of memory" (a bare SQLITE_NOMEM
 * says nothing, and clients such as Python drop its text). Every error
 * message is one line of valid UTF-8: what it quotes from the input (a name, a text argument,
 * BLOB bytes) goes through affect_escape_text, so control bytes and bytes that are not UTF-8
 * become \xNN (clients such as Python decode messages as UTF-8). */
void ax_error(sqlite3_context *ctx, const affect_error *err);
/* "fn: interrupted" with the code SQLITE_INTERRUPT (a call stopped by sqlite3_interrupt). */
void ax_interrupted(sqlite3_context *ctx);
void ax_errorf(sqlite3_context *ctx, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* sqlite3_mprintf (its %q, %w, …) with the result escaped as above; NULL when out of memory. */
char *ax_mprintf(const char *fmt, ...);
/* Every error of a virtual table's method goes through this: the message (printf's format,
 * escaped as above) replaces vt->zErrMsg, and the method returns SQLITE_ERROR (SQLITE_NOMEM
 * when the message cannot be allocated). err, when not NULL, is the core's error the message
 * reports: AFFECT_ERR_NOMEM gives SQLITE_NOMEM and AFFECT_ERR_INTERRUPTED SQLITE_INTERRUPT,
 * with no message. Usage:
 *     return ax_vtab_error(vt, NULL, "motion_points: the argument must be a motion BLOB, got %s",
 *                          ax_type_name(argv[0]));
 *     if (st) return ax_vtab_error(cur->pVtab, &err, "motion_angles: %s", err.msg); */
int ax_vtab_error(sqlite3_vtab *vt, const affect_error *err, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The same into *dst, for a method with no vtab yet (xCreate's and xConnect's pzErr) or a
 * message that the caller hands on (ax_laban_read's *err). */
int ax_error_into(char **dst, const affect_error *err, const char *fmt, ...); /* (takes %q, %w) */
/* Name of a value's type for messages: "integer", "real", "text", "blob", "null". */
const char *ax_type_name(sqlite3_value *v);

/* Decodes argument i (0-based) as a motion BLOB. */
ax_arg ax_arg_motion(sqlite3_context *ctx, sqlite3_value **argv, int i, affect_motion **out);
/* Argument i as text (its bytes and length); a BLOB is refused. */
ax_arg ax_arg_text(sqlite3_context *ctx, sqlite3_value **argv, int i, const char **text,
                   size_t *len);
/* A decoded BLOB argument that a function keeps between calls (the model of affect_classify,
 * fda_embed, …): decoded again only when the argument's bytes change. */
typedef affect_status (*ax_decode_fn)(const unsigned char *data, size_t size, void **out,
                                      affect_error *err);
typedef struct ax_blob_cache {
    unsigned char *bytes; /* the BLOB obj was decoded from (size bytes) */
    size_t size;
    void *obj;                /* NULL when empty */
    void (*free_obj)(void *); /* frees obj */
} ax_blob_cache;

/* Empties the cache. */
void ax_blob_cache_clear(ax_blob_cache *c);

/* The user data of a function that keeps its last decoded BLOB argument (the classifier, the
 * functional model, the strength model): its name first, as AX_NAME reads it, then the cache;
 * one per registration, freed with the connection. */
typedef struct ax_cached_fn {
    char name[32];
    ax_blob_cache cache;
} ax_cached_fn;
ax_cached_fn *ax_cached_fn_new(const char *name); /* NULL when out of memory */
void ax_cached_fn_free(void *fn);

/* The classes of a training aggregate's n rows: the distinct labels in byte order (classes,
 * n_classes; pointers into labels) and each row's class (y). classes and y hold n entries
 * each. AX_ERROR with the message set for fewer than 2 classes ("need motions of at least 2
 * labels, got 1 ("sad")"). */
ax_arg ax_label_classes(sqlite3_context *ctx, char *const *labels, uint32_t n, char **classes,
                        uint32_t *n_classes, uint32_t *y);

/* Argument 1 (argv[0]) decoded by decode, from c when its bytes are the cached ones: AX_NULL
 * for NULL; errors "argument 1 must be a <what> BLOB (from <from>), got text" and "argument 1
 * is not a valid <what>: <decoder's message>", or SQLITE_NOMEM. *out stays owned by c. */
ax_arg ax_arg_cached_blob(sqlite3_context *ctx, sqlite3_value **argv, ax_blob_cache *c,
                          ax_decode_fn decode, void (*free_obj)(void *), const char *what,
                          const char *from, const void **out);

/* Argument i as a text document: text, or a BLOB holding text (as the shell's readfile()
 * returns). */
ax_arg ax_arg_document(sqlite3_context *ctx, sqlite3_value **argv, int i, const char **text,
                       size_t *len);
/* Argument i as an integer (an integral REAL is accepted). */
ax_arg ax_arg_int(sqlite3_context *ctx, sqlite3_value **argv, int i, int64_t *out);
/* Argument i as a finite number. */
ax_arg ax_arg_double(sqlite3_context *ctx, sqlite3_value **argv, int i, double *out);

/* Sets a motion BLOB as the result (the motion is not freed). */
void ax_result_motion(sqlite3_context *ctx, const affect_motion *m);
/* Sets text allocated by the core as the result, taking ownership. */
void ax_result_text(sqlite3_context *ctx, char *text, size_t len);
/* The same, marked as JSON (subtype 'J'), so json_object() nests it. */
void ax_result_json(sqlite3_context *ctx, char *text, size_t len);
/* float32 vectors (little-endian, the sqlite-vec convention): one value in or out, and n doubles
 * as a BLOB result. A NaN is always written as the quiet NaN 0x7fc00000, so equal vectors are
 * byte-identical. */
/* name into dst[size], cut to fit (the name field of a function's user-data struct, which
 * AX_NAME reads). */
void ax_copy_name(char *dst, size_t size, const char *name);
void ax_put_f32(unsigned char *p, float f);
float ax_get_f32(const unsigned char *p);
void ax_result_f32(sqlite3_context *ctx, const double *v, size_t n);

/* Finishes a text buffer built by the core and sets it as a JSON result (SQLITE_NOMEM if any
 * append failed). */
struct affect_strbuf;
void ax_result_json_buffer(sqlite3_context *ctx, struct affect_strbuf *sb);

/* ---- JSON options ---- */
typedef struct ax_opts {
    affect_json_doc *doc;
    const affect_json_node *obj; /* NULL when no options were given */
} ax_opts;

/* Parses argument i as a JSON object of options whose keys must be in allowed (NULL-terminated).
 * A NULL argument or a missing argument (i >= argc) means no options. */
ax_arg ax_opts_parse(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                     const char *const *allowed, ax_opts *opts);
void ax_opts_free(ax_opts *opts);
const affect_json_node *ax_opt(const ax_opts *opts, const char *key);
/* Typed getters: leave *out unchanged when the key is absent; error on a wrong type. */
ax_arg ax_opt_bool(sqlite3_context *ctx, const ax_opts *opts, const char *key, bool *out);
ax_arg ax_opt_number(sqlite3_context *ctx, const ax_opts *opts, const char *key, double *out);
ax_arg ax_opt_string(sqlite3_context *ctx, const ax_opts *opts, const char *key, const char **out);
/* A string that must be one of choices (NULL-terminated); *out gets its index. */
ax_arg ax_opt_enum(sqlite3_context *ctx, const ax_opts *opts, const char *key,
                   const char *const *choices, int *out);
/* An aggregate reads its options on the first row and requires the same text on every row:
 * ax_opts_text_keep copies argument i's text (nothing when it is absent or not text; free
 * ot->text with sqlite3_free), ax_opts_text_same fails with "options must be the same on every
 * row" unless argument i is that text (or both are absent). */
typedef struct ax_opts_text {
    char *text;
    size_t len;
} ax_opts_text;
ax_arg ax_opts_text_keep(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                         ax_opts_text *ot);
ax_arg ax_opts_text_same(sqlite3_context *ctx, int argc, sqlite3_value **argv, int i,
                         const ax_opts_text *ot);
/* "up": "x" | "y" | "z" → 0..2. */
ax_arg ax_opt_up(sqlite3_context *ctx, const ax_opts *opts, int *up);
/* Resolves the motion's roles, then applies the "roles" option: {"left_hand": "MyHand", …}
 * (null unassigns a role). */
ax_arg ax_opt_roles(sqlite3_context *ctx, const ax_opts *opts, const affect_motion *m,
                    affect_roles *roles);

/* ---- stopping long calls (affect/monitor.h) ----
 * A long call runs with an ax_monitor whose stop hook steps a prepared "SELECT 1" on the
 * calling connection: the step fails with SQLITE_INTERRUPT once sqlite3_interrupt() was called
 * on the connection (SQLite 3.40, which has no sqlite3_is_interrupted, included) or once the
 * connection's progress handler (which counts the probe's VM steps) asked to stop. With a
 * progress function (the "progress" option: the name of an SQL function of 3 arguments), the
 * monitor calls SELECT fn(stage, done, total) as the call advances; its result and errors are
 * ignored.
 *
 *     ax_monitor am;
 *     if (ax_monitor_begin(&am, ctx, progress_fn) != AX_OK) return;   (error reported)
 *     cfg.monitor = &am.mon;  … the core call …   (AFFECT_ERR_INTERRUPTED: ax_error says so)
 *     ax_monitor_end(&am);
 */
typedef struct ax_monitor {
    affect_monitor mon;
    sqlite3 *db;
    sqlite3_stmt *probe;  /* SELECT 1, prepared at the first poll */
    sqlite3_stmt *report; /* SELECT fn(?1, ?2, ?3), or NULL */
} ax_monitor;

/* progress_fn may be NULL; an unknown function is reported as "option \"progress\": …". */
ax_arg ax_monitor_begin(ax_monitor *am, sqlite3_context *ctx, const char *progress_fn);
/* The same for a virtual table's methods (no context; errors into *errmsg, sqlite3_malloc'd). */
int ax_monitor_begin_db(ax_monitor *am, sqlite3 *db, const char *progress_fn, char **errmsg);
void ax_monitor_end(ax_monitor *am);
/* Asks now, unthrottled (an aggregate's step: see ext/seqs.c). */
bool ax_monitor_interrupted(ax_monitor *am);

/* ---- table-valued functions of a motion ----
 * xBestIndex of an eponymous table whose hidden columns col_motion and col_options (−1: none)
 * are its arguments: an equality on motion is required (idxNum bit 1, argv 1) and one on
 * options taken (bit 2, argv 2); any other constraint on options, or an unusable one on motion,
 * is SQLITE_CONSTRAINT (another plan will do); no constraint on motion at all is the error
 * "<name>: a motion argument is required, as in SELECT * FROM <name>(:motion)". */
int ax_motion_tvf_best_index(sqlite3_vtab *vt, sqlite3_index_info *info, int col_motion,
                             int col_options, const char *name);
/* The methods every such table shares. Its table is an ax_tvf_vtab (the connection, for the
 * monitor of a long call); ax_tvf_connect declares the schema (CREATE TABLE x(…)) and marks the
 * table innocuous; ax_tvf_disconnect frees it; ax_tvf_open allocates a cursor of size bytes,
 * zeroed (the cursor of any virtual table: laban's and vt_rows.c's use it too). Usage:
 *     static int points_connect(sqlite3 *db, void *aux, int argc, const char *const *argv,
 *                               sqlite3_vtab **out, char **err)
 *     { return ax_tvf_connect(db, "CREATE TABLE x(frame INTEGER, …, motion HIDDEN)", out); }
 *     … .xDisconnect = ax_tvf_disconnect, … */
typedef struct ax_tvf_vtab {
    sqlite3_vtab base;
    sqlite3 *db;
} ax_tvf_vtab;
int ax_tvf_connect(sqlite3 *db, const char *schema, sqlite3_vtab **out);
int ax_tvf_disconnect(sqlite3_vtab *vt);
int ax_tvf_open(size_t size, sqlite3_vtab_cursor **out);
/* xFilter's arguments under that plan: argv[0] a motion BLOB, decoded into *m polling mon (a
 * NULL motion leaves *m NULL: no rows), and, when idx_num has bit 2, argv[1] the options as text
 * (*text, *len; NULL or absent: *text = NULL). Errors into err (the caller prefixes its name):
 * "the argument must be a motion BLOB, got text", "options must be a JSON object as text, got
 * integer", "the argument is not a valid motion: …", AFFECT_ERR_NOMEM, AFFECT_ERR_INTERRUPTED. */
affect_status ax_motion_tvf_args(int idx_num, int argc, sqlite3_value **argv, affect_monitor *mon,
                                 affect_motion **m, const char **text, size_t *len,
                                 affect_error *err);

#endif
