#!/usr/bin/env python3
"""storage_eval.py — the classifier's compact storage against its float32 storage, decision by
decision (issue 12, item 3; docs/BENCHMARKS.md, "The classifier BLOB at the thesis's
configuration").

Usage (from the repository root, after a build of build/affect.so):
    OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/storage_eval.py
        [--db build/recognition.db] [--corpus c1|c2] [--options JSON] [--in-sample]
AFFECT_EXT overrides the extension's path (default build/affect).

The corpora are imported as recognition_eval.py does (the same --db can serve both): c1 =
bandai-namco-1's 44 motions of angry, happy, sad and normal over its ten shared contents, c2 =
bandai-namco-2-dev's 504 motions of 7 styles. Leaving one content out (or, with --in-sample,
training on every motion and evaluating on every motion), each fold trains two classifiers on
the same motions with the same options (default: the thesis's configuration), one with
"storage": "float32" and one with "storage": "compact", and compares every held-out motion's
affect_scores: the SVM, kNN and ML labels, every pair's SVM decision value (and whether its
sign changed) and the sPCA coordinates. Prints one line: motions, labels equal, the largest
change of a decision value and of a coordinate (absolute and relative to the largest
magnitude), the pair decisions whose sign changed (their float32 values), and the two BLOB
sizes of the last fold.
"""
import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import recognition_eval as rev  # noqa: E402  (the corpora's import and views)

THESIS = {"frame": "first", "velocity": False, "states": 7, "mixtures": 4,
          "covariance": "full", "max_iter": 50, "descriptors": "none", "mirror": False}


def scores(con, model, motions):
    """affect_scores of every motion under one model (one decode: the extension keeps it)."""
    return [json.loads(con.execute("SELECT affect_scores(?, ?)", (model, m)).fetchone()[0])
            for m in motions]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(rev.ROOT, "build", "recognition.db"))
    ap.add_argument("--corpus", default="c1", choices=["c1", "c2"])
    ap.add_argument("--options", default=json.dumps(THESIS))
    ap.add_argument("--in-sample", action="store_true")
    a = ap.parse_args()
    con = rev.connect(a.db)
    rev.import_corpora(con)
    rev.views(con)
    opts = json.loads(a.options)
    groups = [None] if a.in_sample else \
        [r[0] for r in con.execute("SELECT DISTINCT content FROM %s ORDER BY 1" % a.corpus)]
    n = same = 0
    maxd = maxdd = maxe = maxde = 0.0
    flips, sizes, t0 = [], {}, time.time()
    for g in groups:
        train = "1" if g is None else "content != :g"
        test = "1" if g is None else "content = :g"
        models = {}
        for st in ("float32", "compact"):
            o = dict(opts, storage=st, threads=2)
            models[st] = con.execute("SELECT affect_train(motion, style, :o) FROM %s WHERE %s"
                                     % (a.corpus, train), {"o": json.dumps(o), "g": g}
                                     ).fetchone()[0]
            sizes[st] = len(models[st])
        motions = [r[0] for r in con.execute("SELECT motion FROM %s WHERE %s ORDER BY id"
                                             % (a.corpus, test), {"g": g})]
        fa, fb = scores(con, models["float32"], motions), scores(con, models["compact"], motions)
        for x, y in zip(fa, fb):
            n += 1
            same += x["label"] == y["label"]
            for k, v in x["classes"].items():
                for k2, d in v["decision"].items():
                    if k2 < k:
                        continue  # each pair once
                    d2 = y["classes"][k]["decision"][k2]
                    maxd, maxdd = max(maxd, abs(d)), max(maxdd, abs(d - d2))
                    if (d > 0) != (d2 > 0):
                        flips.append(d)
            for p, q in zip(x["embedding"], y["embedding"]):
                maxe, maxde = max(maxe, abs(p)), max(maxde, abs(p - q))
        print("fold %s: %.0f s" % (g or "all", time.time() - t0), file=sys.stderr)
    print("%s %s%s: %d motions, labels (svm, knn, ml) equal for %d; decision values: largest "
          "change %.3g (%.2f %% of %.3g); pair decisions whose sign changed: %d %s; sPCA "
          "coordinates: largest change %.3g (%.2f %% of %.3g); BLOB bytes of the last fold: "
          "float32 %d, compact %d"
          % (a.corpus, json.dumps(opts), " in sample" if a.in_sample else ", leave one content out",
             n, same, maxdd, 100 * maxdd / maxd, maxd, len(flips),
             ["%.2g" % d for d in flips], maxde, 100 * maxde / maxe, maxe,
             sizes["float32"], sizes["compact"]))


if __name__ == "__main__":
    main()
