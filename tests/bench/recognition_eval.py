#!/usr/bin/env python3
"""recognition_eval.py — the recognizer measured as a user meets it, beside a scikit-learn peer.

Usage (from the repository root, after ./run.sh demo or any build of build/affect.so):
    OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/recognition_eval.py
        [--db build/recognition.db] [--configs NAME,NAME,...] [--no-peer] [--no-cross]
        [--no-resampled] [--grid]
AFFECT_EXT overrides the extension's path (default build/affect). The peer needs Debian's
python3-sklearn (a peer only: the project itself never uses it).

It imports both corpora of ../shared/corpora (bandai-namco-1 and bandai-namco-2-dev) into --db
(once; the file is reused when it already holds them) with the extension's motion_from_bvh, then
runs, for every configuration of CONFIGS (affect_train options; "defaults" = no option at all):
  - bandai-namco-1, the 44 motions of angry, happy, sad and normal over the ten contents recorded
    in every style: leave one content out (10 folds) and stratified 10-fold (seed 7);
  - bandai-namco-2-dev, 504 motions of 7 styles: leave one content out (6 folds);
  - both again WITHOUT DURATION CUES: every motion time-stretched to 200 frames at 30 fps
    (motion_resample to 30 · 199.5 / (frames − 1) fps, then the frame rate relabelled 30), so
    that no motion is longer or shorter than another (the corpus's SOURCE.md asks for it);
  - cross-corpus: trained on bandai-namco-1's styles that match bandai-namco-2-dev's (active,
    feminine, masculinity → masculine, normal, tired → exhausted, old → elderly, childish →
    youthful; every content), tested on all 504 motions of bandai-namco-2-dev.
The three methods of affect_crossval (ML, Fisher + SVM, Fisher + sPCA + kNN) are scored on the
same folds. The peer: scikit-learn's LinearSVC (C = 1, standardized features) on the kinematic
summaries of motion_kinematics (21 values: speeds, durations, turning, posture), on exactly the
same leave-one-content-out folds (and the same cross-corpus split): the "few lines of
scikit-learn" the issue compares against. Folds run two at a time
("threads": 2); OpenBLAS single-threaded. Output: Markdown tables (pooled accuracy, and the
accuracy of each held-out content).
"""
import argparse
import json
import os
import sys
import time

import corpus_import
from corpus_import import CORPORA, FOUR, ROOT, TEN, connect

# name → options (merged into every protocol's options); "defaults" passes none of its own
CONFIGS = {
    "defaults": {},
    "defaults without mirror images": {"mirror": False},
    "defaults without kinematic summaries": {"descriptors": "none"},
    "first-frame observations 5x1 diag (the earlier recommendation)": {
        "frame": "first", "velocity": True, "descriptors": "none", "mirror": False},
    # the thesis's 7 x 4 full on end-effectors + torso (not run unless named: --configs)
    "thesis": {"frame": "first", "states": 7, "mixtures": 4, "covariance": "full",
               "velocity": True, "max_iter": 50, "descriptors": "none", "mirror": False,
               "joints": ["pelvis", "chest", "head", "left_hand", "right_hand", "left_foot",
                          "right_foot"]},
}

# The table that chose the defaults (--grid): leave one content out on both corpora, every
# option set with "seed": 7 (the runs of docs/EVALUATION.md, "Choosing the defaults"). Options
# not listed take the values they had before the choice: the first-frame observations, no
# descriptors, no mirror images, 5 states x 1 diagonal, 20 iterations.
BEFORE = {"frame": "first", "root": False, "velocity": False, "descriptors": "none",
          "mirror": False, "states": 5, "mixtures": 1, "covariance": "diag", "max_iter": 20,
          "seed": 7}
GRID = [
    {"velocity": True},
    {"frame": "body", "velocity": True, "root": True},
    {"frame": "body", "velocity": True},
    {"frame": "body", "root": True},
    {"frame": "body", "velocity": True, "root": True, "states": 3, "mixtures": 2},
    {"frame": "body", "velocity": True, "states": 4},
    {"frame": "body", "velocity": True, "root": True, "states": 7},
    {"frame": "body", "velocity": True, "root": True, "mixtures": 2, "covariance": "full",
     "joints": ["pelvis", "chest", "head", "left_hand", "right_hand", "left_foot",
                "right_foot"]},
    {"frame": "body", "velocity": True, "root": True, "descriptors": "kinematics"},
    {"frame": "body", "velocity": True, "root": True, "descriptors": "kinematics",
     "descriptor_weight": 0.3},
    {"frame": "body", "velocity": True, "root": True, "descriptors": "kinematics",
     "descriptor_weight": 0.1},
    {"frame": "body", "velocity": True, "root": True, "descriptors": "all",
     "descriptor_weight": 0.3},
    {"frame": "body", "velocity": True, "mirror": True},
    {"frame": "body", "velocity": True, "mirror": True, "mixtures": 2},
    {"frame": "body", "velocity": True, "mirror": True, "descriptors": "kinematics",
     "descriptor_weight": 1},
    {"frame": "body", "velocity": True, "mirror": True, "descriptors": "kinematics",
     "descriptor_weight": 0.3},
    {"frame": "body", "velocity": True, "mirror": True, "descriptors": "kinematics",
     "descriptor_weight": 0.1},
    {"frame": "body", "velocity": True, "mirror": True, "descriptors": "all",
     "descriptor_weight": 0.3},
    {"frame": "body", "mirror": True},
    {"frame": "body", "mirror": True, "states": 4},
    {"frame": "body", "mirror": True, "states": 7},
    {"frame": "body", "mirror": True, "descriptors": "kinematics", "descriptor_weight": 0.3},
    {"frame": "body", "mirror": True, "descriptors": "kinematics", "descriptor_weight": 0.1},
]


def grid(con):
    print("| options (beyond the earlier ones) | B-N-1 ML | B-N-1 SVM | B-N-1 kNN | B-N-2 ML | "
          "B-N-2 SVM (worst content) | B-N-2 kNN | mean SVM |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for g in GRID:
        opts = dict(BEFORE)
        opts.update(g)
        r1 = ours(con, "c1", opts, "loco")
        r2 = ours(con, "c2", opts, "loco")
        print("| `%s` | %.1f | %.1f | %.1f | %.1f | %.1f (%.0f) | %.1f | %.1f |" % (
            json.dumps(g, separators=(",", ":")), 100 * r1["ml"]["pooled"],
            100 * r1["svm"]["pooled"], 100 * r1["knn"]["pooled"], 100 * r2["ml"]["pooled"],
            100 * r2["svm"]["pooled"], 100 * min(r2["svm"]["folds"].values()),
            100 * r2["knn"]["pooled"], 50 * (r1["svm"]["pooled"] + r2["svm"]["pooled"])),
            flush=True)


CROSS = {"active": "active", "feminine": "feminine", "masculinity": "masculine",
         "normal": "normal", "tired": "exhausted", "old": "elderly", "childish": "youthful"}


def import_corpora(con):
    """Both corpora into motions (corpus_import.py), and their time-stretched copies."""
    corpus_import.import_corpora(con)
    # the time-stretched copies: 200 frames at 30 fps
    con.execute("CREATE TABLE IF NOT EXISTS stretched(id INTEGER PRIMARY KEY, motion BLOB)")
    if con.execute("SELECT count(*) FROM stretched").fetchone()[0] != \
            con.execute("SELECT count(*) FROM motions").fetchone()[0]:
        con.execute("DELETE FROM stretched")
        con.execute("INSERT INTO stretched SELECT id, motion_from_json(json_set(motion_to_json("
                    "motion_resample(motion, 30.0 * 199.5 / (frames - 1))), '$.fps', 30)) "
                    "FROM motions")
        con.commit()


def views(con):
    four = ",".join("'%s'" % e for e in FOUR)
    ten = ",".join("'%s'" % c for c in TEN)
    for stretched in (False, True):
        sfx = "_s" if stretched else ""
        m = "s.motion" if stretched else "m.motion"
        join = "JOIN stretched AS s USING (id)" if stretched else ""
        con.execute("DROP TABLE IF EXISTS temp.c1%s" % sfx)
        con.execute("CREATE TEMP TABLE c1%s AS SELECT m.id, m.content, m.style, %s AS motion "
                    "FROM motions AS m %s WHERE source = 'bandai-namco-1' AND style IN (%s) AND "
                    "content IN (%s) ORDER BY m.id" % (sfx, m, join, four, ten))
        con.execute("DROP TABLE IF EXISTS temp.c2%s" % sfx)
        con.execute("CREATE TEMP TABLE c2%s AS SELECT m.id, m.content, m.style, %s AS motion "
                    "FROM motions AS m %s WHERE source = 'bandai-namco-2-dev' ORDER BY m.id"
                    % (sfx, m, join))
    cases = " ".join("WHEN '%s' THEN '%s'" % kv for kv in CROSS.items())
    con.execute("DROP TABLE IF EXISTS temp.x1")
    con.execute("CREATE TEMP TABLE x1 AS SELECT id, content, CASE style %s END AS style, motion "
                "FROM motions WHERE source = 'bandai-namco-1' AND style IN (%s) ORDER BY id"
                % (cases, ",".join("'%s'" % k for k in CROSS)))


def ours(con, table, options, protocol):
    opts = dict(options)
    opts["threads"] = 2
    if protocol == "loco":
        opts["group"] = "content"
    else:
        opts["folds"] = 10
        opts["seed"] = 7
    t0 = time.time()
    rows = con.execute("SELECT method, fold, held_out, accuracy, pooled_accuracy FROM "
                       "affect_crossval(?, 'motion', 'style', ?)",
                       (table, json.dumps(opts))).fetchall()
    out = {"seconds": time.time() - t0}
    for method, fold, held, acc, pooled in rows:
        r = out.setdefault(method, {"folds": {}})
        if fold is None:
            r["pooled"] = pooled
        else:
            r["folds"][held if held is not None else str(fold)] = acc
    return out


def peer(con, table):
    """The peer on the leave-one-content-out folds of table."""
    import numpy as np
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import LinearSVC
    rows = con.execute("SELECT content, style, motion_kinematics(motion) FROM %s ORDER BY id"
                       % table).fetchall()
    X = np.array([list(json.loads(k).values()) for _, _, k in rows])
    y = np.array([s for _, s, _ in rows])
    g = np.array([c for c, _, _ in rows])
    folds = [(g != c, g == c, c) for c in sorted(set(g))]
    t0 = time.time()
    hits, res = 0, {"folds": {}}
    for tr, te, name in folds:
        clf = make_pipeline(StandardScaler(), LinearSVC(C=1.0, max_iter=100000, dual=False))
        clf.fit(X[tr], y[tr])
        ok = clf.predict(X[te]) == y[te]
        hits += ok.sum()
        res["folds"][name] = ok.mean()
    res["pooled"] = hits / len(y)
    res["seconds"] = time.time() - t0
    return res


def cross(con, options):
    t0 = time.time()
    opts = json.dumps(options)
    model = con.execute("SELECT affect_train(motion, style, ?) FROM x1", (opts,)).fetchone()[0]
    res = {}
    for method in ("svm", "knn", "ml"):
        n, hit = con.execute("SELECT count(*), sum(affect_classify(?, motion, ?) = style) FROM c2",
                             (model, method)).fetchone()
        res[method] = hit / n
    res["seconds"] = time.time() - t0
    return res


def cross_peer(con):
    import numpy as np
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import LinearSVC

    def load(t):
        rows = con.execute("SELECT style, motion_kinematics(motion) FROM %s ORDER BY id"
                           % t).fetchall()
        return (np.array([list(json.loads(k).values()) for _, k in rows]),
                np.array([s for s, _ in rows]))
    X1, y1 = load("x1")
    X2, y2 = load("c2")
    clf = make_pipeline(StandardScaler(), LinearSVC(C=1.0, max_iter=100000, dual=False))
    clf.fit(X1, y1)
    return (clf.predict(X2) == y2).mean()


def pct(v):
    return "%.1f %%" % (100 * v) if v is not None else "—"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "recognition.db"))
    ap.add_argument("--configs", default=",".join(k for k in CONFIGS if k != "thesis"))
    ap.add_argument("--no-peer", action="store_true")
    ap.add_argument("--no-cross", action="store_true")
    ap.add_argument("--no-resampled", action="store_true")
    ap.add_argument("--grid", action="store_true",
                    help="only the table that chose the defaults")
    a = ap.parse_args()
    if not os.path.isdir(CORPORA):
        print("recognition_eval: skipped: ../shared/corpora is absent")
        return 77
    con = connect(a.db)
    import_corpora(con)
    views(con)
    if a.grid:
        grid(con)
        return 0
    names = a.configs.split(",")
    tasks = [("c1", "loco", "bandai-namco-1, 4 emotions, leave one content out"),
             ("c1", "kfold", "bandai-namco-1, 4 emotions, 10-fold"),
             ("c2", "loco", "bandai-namco-2-dev, 7 styles, leave one content out")]
    if not a.no_resampled:
        tasks += [(t + "_s", p, d + ", no duration cues") for t, p, d in tasks]
    for table, protocol, desc in tasks:
        print("\n### %s\n" % desc)
        print("| configuration | ML | Fisher + SVM | Fisher + sPCA + kNN | time | per held-out "
              "content (SVM) |")
        print("|---|---:|---:|---:|---:|---|")
        for name in names:
            r = ours(con, table, CONFIGS[name], protocol)
            folds = " ".join("%s %.0f" % (k, 100 * v) for k, v in r["svm"]["folds"].items()) \
                if protocol == "loco" else ""
            print("| %s | %s | %s | %s | %.0f s | %s |" % (
                name, pct(r["ml"]["pooled"]), pct(r["svm"]["pooled"]), pct(r["knn"]["pooled"]),
                r["seconds"], folds), flush=True)
        if not a.no_peer and protocol == "loco":
            p = peer(con, table)
            folds = " ".join("%s %.0f" % (k, 100 * v) for k, v in p["folds"].items())
            print("| peer: kinematic summaries + LinearSVC (scikit-learn) | | %s | | %.1f s | %s |"
                  % (pct(p["pooled"]), p["seconds"], folds), flush=True)
    if not a.no_cross:
        print("\n### cross-corpus: trained on bandai-namco-1's 7 matching styles (%d motions), "
              "tested on bandai-namco-2-dev (504)\n"
              % con.execute("SELECT count(*) FROM x1").fetchone()[0])
        print("| configuration | ML | Fisher + SVM | Fisher + sPCA + kNN | time |")
        print("|---|---:|---:|---:|---:|")
        for name in names:
            r = cross(con, CONFIGS[name])
            print("| %s | %s | %s | %s | %.0f s |" % (name, pct(r["ml"]), pct(r["svm"]),
                                                    pct(r["knn"]), r["seconds"]), flush=True)
        if not a.no_peer:
            print("| peer: kinematic summaries + LinearSVC (scikit-learn) | | %s | | |"
                  % pct(cross_peer(con)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
