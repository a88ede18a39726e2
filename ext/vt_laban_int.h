/*
 * vt_laban_int.h — what the files of the laban virtual table share among themselves (and no
 * other file includes: the rest of the extension reads an index through vt_laban.h):
 *   vt_laban.c        the module: create/connect, transactions, commands, planning, cursors
 *   vt_laban_args.c   the constructor's key=value arguments and Laban options, the content check
 *   vt_laban_store.c  errors, shadow tables (_data, _info), vectors, the per-connection cache,
 *                     rebuild/refresh/check
 *   vt_laban_read.c   the API of vt_laban.h: which tables are indexes, rows, caches, statistics
 * The manual of the table (its columns, queries, shadow tables, commands) heads vt_laban.c.
 */
#ifndef AFFECT_EXT_VT_LABAN_INT_H
#define AFFECT_EXT_VT_LABAN_INT_H

#include "vt_laban.h"

#include "affect/laban.h"

#define LAB_N AFFECT_LABAN_N
#define LAB_VECTOR_BYTES (LAB_N * 4)
#define LAB_FORMAT "1"
/* Rows searched (or standardized) between two polls of the interrupt: about 3 ms of a search
 * over the 27 components (22 ns a row, measured on 1,000,000 rows; a poll costs 20-50 µs). */
#define LAB_POLL_ROWS ((size_t)1 << 17)

/* The cached rows of one generation of the index; shared by the table and its cursors. */
typedef struct lab_cache {
    int refs;
    sqlite3_int64 generation;
    size_t n, cap;
    int64_t *ids;           /* ascending */
    int32_t *label;         /* per row: index into labels, −1 for a NULL label */
    float *raw;             /* n × LAB_N, NaN where missing */
    double *z;              /* n × LAB_N standardized */
    sqlite3_value **labels; /* distinct labels (slots may be NULL) */
    size_t n_labels;
    double mean[LAB_N], sd[LAB_N];
} lab_cache;

typedef struct lab_vtab {
    sqlite3_vtab base;
    sqlite3 *db;
    char *schema, *name; /* where the index lives */
    char *content, *motion, *label;
    char *options_json; /* normalized */
    affect_laban_options opt;
    lab_cache *cache;
    bool dirty;                        /* _info statistics are out of date until xSync */
    const ax_laban_cache_kind *caches; /* the module's aux: what 'check' validates in _info */
} lab_vtab;

/* ---- vt_laban_store.c ---- */
int lab_db_error(char **dst, sqlite3 *db, int rc);
int lab_interrupted(char **dst);
int lab_core_error(char **dst, const affect_error *err, const char *prefix);
const char *lab_value_desc(sqlite3_value *v, char *buf, int size);
int lab_prepare(sqlite3 *db, char **err, sqlite3_stmt **st, const char *fmt, ...);
int lab_step_done(sqlite3 *db, char **err, sqlite3_stmt *st);
int lab_exec(sqlite3 *db, char **err, const char *fmt, ...);
bool lab_vector_corrupt(int type, const unsigned char *p, int n, char *why, int size);
char *lab_ident(const char *name);
char *lab_corrupt_message(const char *prefix, const char *name, sqlite3_int64 id, const char *why,
                          sqlite3_int64 more);
sqlite3_int64 lab_fnv1a(const unsigned char *p, size_t n);
affect_status lab_vector(const lab_vtab *vt, const unsigned char *data, size_t n, float out[LAB_N],
                         bool *bad_blob, affect_error *err);
int lab_value_equal(sqlite3_value *a, sqlite3_value *b, bool exact);
void lab_cache_unref(lab_cache *c);
void lab_cache_drop(lab_vtab *vt);
int lab_cache_current(lab_vtab *vt, char **err, lab_cache **out);
ptrdiff_t lab_cache_find(const lab_cache *c, sqlite3_int64 id);
int lab_flush_stats(lab_vtab *vt, char **err);
int lab_rebuild(lab_vtab *vt, char **err);
int lab_refresh(lab_vtab *vt, sqlite3_int64 id, bool remove, char **err);
int lab_check(lab_vtab *vt, char **err);

/* ---- vt_laban_args.c ---- */
int lab_parse_options(lab_vtab *vt, const char *text, char **err);
void lab_free(lab_vtab *vt);
bool lab_is_column_name(const char *name);
int lab_init(sqlite3 *db, void *aux, int argc, const char *const *argv, lab_vtab **out, char **err);
int lab_check_content(lab_vtab *vt, char **err);

/* ---- vt_laban_read.c ---- */
int lab_rows_load(sqlite3 *db, const char *schema, const char *name, ax_laban_rows *out,
                  char **err);

#endif
