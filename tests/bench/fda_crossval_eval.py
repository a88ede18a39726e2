#!/usr/bin/env python3
"""fda_crossval_eval.py — the functional methods of fda_train compared by affect_crossval on the
real corpora: one query per corpus, protocol and dimension count, every method on the same folds
(1-NN in the embedding, the thesis's chapter 3 protocol).

Usage (from the repository root, after a build of build/affect.so):
    OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/fda_crossval_eval.py [--db build/fda.db]
        [--corpora 1,2] [--protocols loco,loo,k10] [--dims 2,3]
        [--methods fpca,ffda,fspca,fspca_rbf,fisomap] [--options '{"sigma":0.5}']
        [--observations default,chosen]
AFFECT_EXT overrides the extension's path (default build/affect). Python's standard library and
sqlite3 only.

It imports the corpora of ../shared/corpora into --db once (corpus_import.py), then runs
    SELECT method, fold, accuracy, pooled_accuracy, params
      FROM affect_crossval('c1', 'motion', 'style', :options)
with "group":"content" (loco: leave one content out; bandai-namco-1: the 44 motions of angry,
happy, normal and sad over the ten contents of every style, 10 folds; bandai-namco-2-dev: 504
motions of 7 styles, 6 folds), "group":"id" (loo: leave one motion out; 44 or 504 folds) or
"group":"k10" (k10: the motion's id modulo 10, fda_eval.py's --folds2 10).
Observations: "default" = affect_crossval's (body frame, every joint, positions), "chosen" =
docs/EVALUATION.md's set chosen on bandai-namco-1 (body frame, 7 joints, with velocities).
A method whose training fails (for example a singular fit) is reported as such and the
others run without it. Output: a Markdown table per corpus and protocol (pooled accuracy =
correct / all held-out motions) and the CPU time of each query.
"""
import argparse
import json
import os
import sqlite3
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corpus_import import CORPORA, FOUR, ROOT, TEN, connect, import_corpora  # noqa: E402

OBSERVATIONS = {
    "default": {"frame": "body"},
    "chosen": {"frame": "body", "velocity": True,
               "joints": ["pelvis", "chest", "head", "left_hand", "right_hand", "left_foot",
                          "right_foot"]},
}


def tables(con):
    con.execute("DROP TABLE IF EXISTS temp.c1")
    con.execute("CREATE TEMP TABLE c1 AS SELECT id, id %% 10 AS k10, content, style, motion "
                "FROM motions WHERE "
                "source = 'bandai-namco-1' AND style IN (%s) AND content IN (%s) ORDER BY id"
                % (",".join("'%s'" % e for e in FOUR), ",".join("'%s'" % c for c in TEN)))
    con.execute("DROP TABLE IF EXISTS temp.c2")
    con.execute("CREATE TEMP TABLE c2 AS SELECT id, id % 10 AS k10, content, style, motion "
                "FROM motions WHERE "
                "source = 'bandai-namco-2-dev' ORDER BY id")


def crossval(con, table, options):
    """{method: (pooled accuracy, n_test)} of one affect_crossval query, and its CPU seconds;
    or the error text."""
    t0 = time.process_time()
    try:
        rows = con.execute("SELECT method, pooled_accuracy, n_test FROM affect_crossval(?, "
                           "'motion', 'style', ?) WHERE fold IS NULL",
                           (table, json.dumps(options))).fetchall()
    except sqlite3.Error as e:
        return str(e), time.process_time() - t0
    return {m: (a, n) for m, a, n in rows}, time.process_time() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "fda.db"))
    ap.add_argument("--corpora", default="1,2")
    ap.add_argument("--protocols", default="loco")
    ap.add_argument("--dims", default="2,3")
    ap.add_argument("--methods", default="fpca,ffda,fspca,fspca_rbf,fisomap")
    ap.add_argument("--options", default="{}")
    ap.add_argument("--observations", default="default,chosen")
    a = ap.parse_args()
    if not os.path.isdir(CORPORA):
        print("fda_crossval_eval: skipped: %s is absent" % CORPORA)
        return 0
    which = [{"1": "bandai-namco-1", "2": "bandai-namco-2-dev"}[c] for c in a.corpora.split(",")]
    con = connect(a.db)
    import_corpora(con, which)
    tables(con)
    methods = a.methods.split(",")
    extra = json.loads(a.options)
    for source in which:
        table = "c1" if source == "bandai-namco-1" else "c2"
        n = con.execute("SELECT count(*) FROM %s" % table).fetchone()[0]
        for proto in a.protocols.split(","):
            group = {"loco": "content", "loo": "id", "k10": "k10"}[proto]
            name = {"loco": "leave one content out", "loo": "leave one motion out",
                    "k10": "10-fold by motion id modulo 10"}[proto]
            print("\n### %s, %d motions, %s, 1-NN (pooled accuracy)\n" % (source, n, name))
            cols = ["%s %s-D" % (o, d) for o in a.observations.split(",")
                    for d in a.dims.split(",")]
            print("| method | " + " | ".join(cols) + " |")
            print("|---|" + "---:|" * len(cols))
            cells = {m: [] for m in methods}
            secs = []
            for obs in a.observations.split(","):
                for d in a.dims.split(","):
                    opts = dict(OBSERVATIONS[obs], **extra)
                    opts.update(group=group, dims=int(d), methods=methods)
                    res, s = crossval(con, table, opts)
                    if isinstance(res, str):  # one method failed: the others without it
                        print("<!-- %s -->" % res)
                        ok = [m for m in methods if m != "fisomap"]
                        opts["methods"] = ok
                        res2, s2 = crossval(con, table, opts)
                        s += s2
                        res = res2 if isinstance(res2, dict) else {}
                    secs.append(s)
                    for m in methods:
                        if m in res:
                            cells[m].append("%.0f %%" % (100 * res[m][0]))
                        else:
                            cells[m].append("fails")
            for m in methods:
                print("| %s | %s |" % (m, " | ".join(cells[m])))
            print("\nCPU s per query: %s" % ", ".join("%.1f" % s for s in secs))
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
