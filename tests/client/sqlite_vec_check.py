"""sqlite_vec_check.py — sqlite-vec's vec0 over laban_zvector vectors finds the laban index's
neighbours (tests/client/sqlite_vec_test.sh runs it; see there for the cases).

    sqlite_vec_check.py AFFECT_MODULE VEC0_MODULE DB INDEX [DB INDEX ...]

For each database (its `motions` table, with a laban index INDEX over it, label = emotion):
  1. the README's statement fills a vec0 table, with the label as a metadata column:
       INSERT INTO v(rowid, label, embedding)
       SELECT id, emotion, laban_zvector(motion, 'INDEX') FROM motions
     and a second one of 2 dimensions over components TimeAll and FlowAll;
  2. for every indexed motion q, the 5 nearest other motions are asked of both:
       the index   SELECT rowid, distance FROM INDEX WHERE query = q AND k = 5
                   [AND label = L] [AND components = '["TimeAll","FlowAll"]']
       vec0        SELECT rowid, distance FROM v WHERE embedding MATCH :vec_of_q AND k = 6
                   [AND label = L]          (q itself, at distance 0, dropped)
     without a label filter and with each label, over all 27 components and over the two;
  3. the two lists must be equal, rowid for rowid. The only allowed difference is the order of
     near-ties: vec0 sums float32 squares in float32, the index in double, so two distances
     closer than TIE_TOL (relative) may come out swapped; such a list passes only when at every
     position the index's distance of vec0's row equals the index's own distance there within
     TIE_TOL, and is counted as "near-tie" in the report. Distances themselves must agree within
     DIST_TOL (relative).
  4. inside a transaction that changed the index, laban_zvector refuses the stale statistics.
Prints one line per database and case, and exits 1 on any failure.
"""
import os
import sqlite3
import sys

TIE_TOL = 1e-5
DIST_TOL = 1e-5
K = 5


def connect(affect, vec0, path):
    conn = sqlite3.connect(path, isolation_level=None)
    conn.enable_load_extension(True)
    conn.load_extension(affect)
    conn.load_extension(vec0)
    conn.enable_load_extension(False)
    return conn


def check_db(conn, index, name):
    failures = 0
    comps = '["TimeAll","FlowAll"]'
    conn.execute("DROP TABLE IF EXISTS temp.v27")
    conn.execute("DROP TABLE IF EXISTS temp.v2")
    conn.execute("CREATE VIRTUAL TABLE temp.v27 USING vec0(label text, embedding float[27])")
    conn.execute("CREATE VIRTUAL TABLE temp.v2 USING vec0(label text, embedding float[2])")
    # the README's statement (its temp. prefix aside)
    conn.execute("INSERT INTO temp.v27(rowid, label, embedding) "
                 "SELECT id, emotion, laban_zvector(motion, ?) FROM motions "
                 "WHERE id IN (SELECT rowid FROM %s)" % index, (index,))
    conn.execute("INSERT INTO temp.v2(rowid, label, embedding) "
                 "SELECT id, emotion, laban_zvector(motion, ?, json_object('components', "
                 "json(?))) FROM motions WHERE id IN (SELECT rowid FROM %s)" % index,
                 (index, comps))
    ids = [r[0] for r in conn.execute("SELECT rowid FROM %s ORDER BY rowid" % index)]
    labels = [r[0] for r in conn.execute(
        "SELECT DISTINCT label FROM %s WHERE label IS NOT NULL ORDER BY label" % index)]
    n_vec = conn.execute("SELECT count(*) FROM temp.v27").fetchone()[0]
    if n_vec != len(ids):
        print("FAIL: %s: vec0 has %d rows, the index %d" % (name, n_vec, len(ids)))
        return 1
    for table, comp in (("v27", None), ("v2", comps)):
        for label in [None] + labels:
            exact = near = 0
            worst = 0.0
            case = "%s %s: %s%s" % (name, index, "27 components" if comp is None else comp,
                                "" if label is None else ", label = " + label)
            for q in ids:
                where, args = "query = ? AND k = ?", [q, K]
                if label is not None:
                    where += " AND label = ?"
                    args.append(label)
                if comp is not None:
                    where += " AND components = ?"
                    args.append(comp)
                want = conn.execute("SELECT rowid, distance FROM %s WHERE %s"
                                    % (index, where), args).fetchall()
                # the index's distance from q to every row, for near-ties
                all_d = dict(conn.execute(
                    "SELECT rowid, distance FROM %s WHERE query = ? AND k = 1000000%s"
                    % (index, "" if comp is None else " AND components = ?"),
                    [q] + ([] if comp is None else [comp])).fetchall())
                vec = conn.execute("SELECT embedding FROM temp.%s WHERE rowid = ?" % table,
                                   (q,)).fetchone()[0]
                vwhere, vargs = "embedding MATCH ? AND k = ?", [vec, K + 1]
                if label is not None:
                    vwhere += " AND label = ?"
                    vargs.append(label)
                got = conn.execute("SELECT rowid, distance FROM temp.%s WHERE %s"
                                   % (table, vwhere), vargs).fetchall()
                got = [(r, d) for r, d in got if r != q][:K]
                want_ids = [r for r, _ in want]
                got_ids = [r for r, _ in got]
                for (r, d) in got:
                    if r in all_d:
                        worst = max(worst, abs(d - all_d[r]) / (1 + all_d[r]))
                if got_ids == want_ids:
                    exact += 1
                    continue
                tied = len(got_ids) == len(want_ids) and all(
                    g in all_d and abs(all_d[g] - wd) <= TIE_TOL * (1 + wd)
                    for g, (_, wd) in zip(got_ids, want))
                if tied:
                    near += 1
                else:
                    failures += 1
                    print("FAIL: %s, query %d: vec0 %s, index %s" % (case, q, got, want))
            if worst > DIST_TOL:
                failures += 1
                print("FAIL: %s: a vec0 distance differs from the index's by %.3g (relative)"
                      % (case, worst))
            print("%s: %d queries, top-%d equal: %d, equal up to near-ties: %d, "
                  "largest distance deviation %.2g" % (case, len(ids), K, exact, near, worst))
    # stale statistics inside a transaction that changed the index
    conn.execute("BEGIN")
    try:
        conn.execute("INSERT INTO %s(%s, rowid) VALUES('delete', ?)" % (index, index),
                     (ids[0],))
        try:
            conn.execute("SELECT laban_zvector(motion, ?) FROM motions WHERE id = ?",
                         (index, ids[1])).fetchone()
            print("FAIL: %s: laban_zvector accepted statistics out of date" % index)
            failures += 1
        except sqlite3.OperationalError as e:
            if "out of date until the transaction that changed it commits" not in str(e):
                print("FAIL: %s: unexpected error %s" % (index, e))
                failures += 1
            else:
                print("%s: inside a transaction that changed the index: %s" % (name, e))
    finally:
        conn.execute("ROLLBACK")
    return failures


def main(argv):
    if len(argv) < 5 or len(argv) % 2 == 0:
        print(__doc__)
        return 2
    affect, vec0 = argv[1], argv[2]
    failures = 0
    for path, index in zip(argv[3::2], argv[4::2]):
        conn = connect(affect, vec0, path)
        print("sqlite-vec %s, SQLite %s" % (conn.execute("SELECT vec_version()").fetchone()[0],
                                            sqlite3.sqlite_version))
        failures += check_db(conn, index, os.path.basename(path))
        conn.close()
    print("sqlite-vec: %s" % ("all checks passed" if failures == 0
                              else "%d failures" % failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
