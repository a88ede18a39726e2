/*
 * fuzz_sql.h — shared by the SQL-driven fuzz targets (fuzz_sql_options, fuzz_sql_laban,
 * fuzz_sql_classifier, fuzz_rmlr): a real connection with the extension's functions, and the
 * checks every statement's outcome must pass.
 *
 * The extension's sources (all of ext/) are compiled into these targets with SQLITE_CORE, so
 * sqlite3_affect_init registers them on a connection of the linked libsqlite3 directly (no
 * loadable module) and the fuzzer's coverage sees inside the wrappers, option parsers and
 * virtual tables. Usage in a target:
 *     sqlite3 *db = fz_open();                  fresh connection, fixtures loaded (below)
 *     sqlite3_stmt *st = fz_prepare(db, "SELECT motion_svg(motion, ?1) FROM motions");
 *     sqlite3_bind_text(st, 1, text, len, SQLITE_TRANSIENT);
 *     int rc = fz_step_all(db, st, "motion_svg", row_callback, arg);
 *     sqlite3_finalize(st);
 *     fz_close(db);
 *
 * Fixtures: LLVMFuzzerInitialize (defined in fuzz_sql.c) builds one database and keeps its
 * image (sqlite3_serialize); every fz_open deserializes a private copy into a new in-memory
 * connection, so no input sees what an earlier one did (per-connection caches included) and a
 * reproducer replays alone.
 *   motions(id INTEGER PRIMARY KEY, motion, label, action, grp)
 *       12 motion_synth motions at 10 fps (26 joints, 33 to 84 frames): knock and wave ×
 *       angry, happy, sad × seeds 1, 2 (grp 'g1', 'g2'); id 1 is knock/angry/1
 *   extra(name PRIMARY KEY, motion)   'skeletal': motion 1 through BVH (stored rotations)
 *   docs(name PRIMARY KEY, body)      'bvh': motion 1 as BVH text; 'csv': as CSV text
 *   models(name PRIMARY KEY, model)   'hmm': hmm_train of the angry motions (2 states, the
 *       right hand); 'classifier': affect_train of all 12 (2 states, the right hand)
 *   points(x, y, label)               laban_weight, laban_time and label of every motion
 *   ix                                a laban index over motions, with an RMLR fit stored
 *                                     as the default one (seed 1, 10 folds; fitted with 2
 *                                     folds, which is 5 times cheaper), so that laban_salient
 *                                     and affect_generate with "components":"auto" read it
 *                                     instead of fitting
 * Each connection has a progress handler that interrupts its statements once it is 2 s old
 * (long trainings and fits poll it through ax_monitor, ext/common.h, and stop with an
 * "interrupted" error; SQL that loops forever stops too), and the process a hard heap limit
 * of 512 MiB (sqlite3_hard_heap_limit64; the core allocates through sqlite3_malloc64 once the
 * extension is registered), so inputs that ask for huge results fail with SQLITE_NOMEM
 * instead of stopping the fuzzer. A call that runs past libFuzzer's -timeout without
 * polling is reported as a timeout. With AFFECT_FUZZ_VERBOSE set in the environment, each
 * statement's outcome (result code and message) is printed on stderr, to read a reproducer;
 * with AFFECT_FUZZ_WRITE_FIXTURES=<file> the fixture database is also written to that file
 * (open it in the sqlite3 shell with the extension loaded to replay a statement by hand).
 */
#ifndef AFFECT_FUZZ_SQL_H
#define AFFECT_FUZZ_SQL_H

#include <sqlite3.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Aborts with a message (a broken invariant: libFuzzer saves the input). */
void fz_fail(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2), noreturn))
#endif
    ;

/* A fresh connection holding a private copy of the fixtures. */
sqlite3 *fz_open(void);
void fz_close(sqlite3 *db);

/* Prepares sql (aborts when it does not compile: the targets' own statements must). */
sqlite3_stmt *fz_prepare(sqlite3 *db, const char *sql);

/* Steps st to its end, calling row (optional) on each row, and returns SQLITE_DONE or the
 * error code. An error must carry a non-empty message; with prefix non-NULL an SQLITE_ERROR's
 * message must start with "<prefix>: " (the extension's "function_name: what is wrong").
 * SQLITE_INTERNAL, SQLITE_CORRUPT, SQLITE_MISUSE and SQLITE_NOTADB (a bug of ours or a
 * broken database) abort. */
int fz_step_all(sqlite3 *db, sqlite3_stmt *st, const char *prefix,
                void (*row)(sqlite3_stmt *st, void *arg), void *arg);

/* Column checks for row callbacks: a motion BLOB must decode and validate; JSON text must be
 * accepted by SQLite's json_valid(); a model BLOB must decode (hmm_blob or classifier) and
 * re-encode to the same bytes. NULL passes every check. */
void fz_check_motion(sqlite3_stmt *st, int col);
void fz_check_json(sqlite3 *db, sqlite3_stmt *st, int col);
void fz_check_hmm(sqlite3_stmt *st, int col);
void fz_check_classifier(sqlite3_stmt *st, int col);

#endif
