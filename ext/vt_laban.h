/*
 * vt_laban.h — the laban virtual table module (vt_laban.c): an external-content index of the
 * Laban descriptors of a table of motions, with k-nearest and radius queries.
 */
#ifndef AFFECT_EXT_VT_LABAN_H
#define AFFECT_EXT_VT_LABAN_H

#include "common.h"

#include "affect/laban.h"

/* What the rest of the extension reads of an index: the index owns its shadow tables, and no
 * other file reads them. */
typedef struct ax_laban_rows {
    char *content, *motion; /* the content table and its motion column */
    uint32_t n;             /* rows with a label, by content rowid ascending */
    sqlite3_int64 *ids;     /* their content rowids */
    char **labels;          /* their labels as text */
    unsigned char *vectors; /* n × 27 little-endian float32 (NaN: missing), as stored */
} ax_laban_rows;

/* A kind of cache entry that another part of the extension keeps in an index
 * (ax_laban_cache_put under `key`), for the index's 'check' command: check gets the index's
 * labelled rows (as ax_laban_read gives them; content and motion NULL) and the entry, and
 * returns SQLITE_OK when the entry is sound, SQLITE_NOMEM, or SQLITE_ERROR with *why
 * (sqlite3_malloc'd) saying what is wrong. */
typedef struct ax_laban_cache_kind {
    const char *key;
    int (*check)(const ax_laban_rows *rows, const char *tag, const void *blob, int size,
                 char **why);
} ax_laban_cache_kind;

/* Registers the module "laban" on db; caches (ended by an entry with a NULL key, or NULL) are
 * the cache kinds that 'check' validates; they must outlive the connection. */
int ax_register_laban(sqlite3 *db, const ax_laban_cache_kind *caches);

/* Reads index `name` of the main schema: SQLITE_OK; SQLITE_NOTFOUND when it is not a laban
 * table; SQLITE_NOMEM; SQLITE_ERROR with *err (sqlite3_malloc'd) saying what is wrong
 * ("stored vector of rowid 4 is corrupt (1 bytes, expected 108); run INSERT INTO g(g)
 * VALUES('rebuild')", "g_info has format "2"; this version reads format 1", or the database's
 * message: the caller names the index). Every stored vector is validated, those of unlabelled
 * rows too. */
int ax_laban_read(sqlite3 *db, const char *name, ax_laban_rows *out, char **err);
void ax_laban_rows_free(ax_laban_rows *r);

/* *label (sqlite3_free it): the text label of the first indexed row (by rowid) whose motion
 * has exactly these bytes and a label, or NULL. SQLITE_OK, or an error code with *err. */
int ax_laban_label_of(sqlite3 *db, const char *name, const void *blob, int size, char **label,
                      char **err);

/* Caches of other parts of the extension kept in the index's _info table: entry `key` (a BLOB)
 * stored with a text `tag` under the key "<key>_key" (the RMLR fit: "rmlr", "rmlr_key").
 * get: *blob (sqlite3_free it) and *size, or NULL when there is no entry or it has another tag;
 * SQLITE_OK or SQLITE_NOMEM. put: SQLITE_OK or the database's error code (a read-only or busy
 * database: the caller may keep the entry elsewhere). */
int ax_laban_cache_get(sqlite3 *db, const char *name, const char *key, const char *tag, void **blob,
                       int *size);
int ax_laban_cache_put(sqlite3 *db, const char *name, const char *key, const char *tag,
                       const void *blob, int size);

/* What a query of index `name` (main schema) standardizes with, for vectors that other L2
 * searches compare as the index does (laban_zvector): the index's Laban options (a query
 * motion's vector is computed with them), and the mean and sd per component of _info, read
 * back as untrusted input: format 1, options a valid options object, mean an array of 27
 * numbers or nulls, sd 27 numbers, checked by affect_laban_stats_check, generation and rows
 * integers. SQLITE_OK; SQLITE_NOTFOUND when it is not a laban table; SQLITE_NOMEM;
 * SQLITE_ERROR with *err (sqlite3_malloc'd): "corrupt statistics: sd[3] (WeightLHand) is -1,
 * expected a finite number > 0 (index "g", g_info row 'sd'); run INSERT INTO g(g)
 * VALUES('rebuild')", or, inside a transaction that changed the index (the statistics catch up
 * when it commits, see vt_laban.c), "the statistics of index "g" are out of date until the
 * transaction that changed it commits (…)". An index written before stats_generation existed
 * has no such row and is taken as current. */
typedef struct ax_laban_stats {
    affect_laban_options opt; /* missing_null set, monitor NULL */
    double mean[AFFECT_LABAN_N], sd[AFFECT_LABAN_N];
    sqlite3_int64 generation, rows;
} ax_laban_stats;
int ax_laban_stats_read(sqlite3 *db, const char *name, ax_laban_stats *out, char **err);

#endif
