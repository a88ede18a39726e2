#!/usr/bin/env python3
"""fda_eval.py — the functional methods (fda_train, thesis chapter 3) under the thesis's
Table 3.1/3.2 protocol, on the real corpora.

Usage (from the repository root, after a build of build/affect.so):
    OPENBLAS_NUM_THREADS=1 python3 tests/bench/fda_eval.py [--db build/fda.db]
        [--corpora 1,2] [--methods fpca,ffda,fspca-linear,fspca-rbf,fisomap]
        [--options '{"basis":200}'] [--sigmas 0.25,0.5,1,2] [--no-loco] [--folds2 N]
AFFECT_EXT overrides the extension's path (default build/affect). Python's standard library and
sqlite3 only.

It imports the corpora of ../shared/corpora into --db once (motion_from_bvh, unit cm; the file
is reused when it already holds them), then for each method:
  - bandai-namco-1, the 44 motions of angry, happy, normal and sad over the ten contents
    recorded in every style: leave-one-out — for every motion, fda_train on the 43 others, the
    held-out motion embedded with fda_embed and classified by its nearest training motion
    (1-NN; the training motions' coordinates are the model's own, from fda_info) in the first 2
    and the first 3 dimensions of the embedding (one model serves both:
    the first two axes of a 3-D model are the 2-D model's axes for every method here);
    the training rate is the same 1-NN among the training motions of the model fitted on all
    44, each motion's own point left out;
  - bandai-namco-2-dev, 504 motions of 7 styles: the same leave-one-out (or, with --folds2 N,
    N-fold cross-validation by motion id modulo N — leave-one-out trains 504 models per
    method);
  - FSPCA-RBF on the 4 emotions, leave one content out (10 folds), for every σ of --sigmas.
Output: Markdown tables with the thesis's rates beside ours, and the CPU time per training.
"""
import argparse
import json
import os
import struct
import sys
import time

from corpus_import import CORPORA, FOUR, ROOT, TEN, connect, import_corpora

METHODS = {
    "fpca": {"method": "fpca"},
    "ffda": {"method": "ffda"},
    "fspca-linear": {"method": "fspca", "kernel": "linear"},
    "fspca-rbf": {"method": "fspca", "kernel": "rbf", "sigma": 0.5},
    "fisomap": {"method": "fisomap"},
}
# The thesis's Table 3.1/3.2 test rates (hand set; full-body set), SCIENCE.md §4.
THESIS = {"fpca": (67, 43), "ffda": (30, 37), "fspca-linear": (97, 44), "fspca-rbf": (93, 54),
          "fisomap": (57, 44)}


def f32(blob):
    return struct.unpack("<%df" % (len(blob) // 4), blob)


def nearest(points, labels, q, dims, skip=None):
    best, lab = None, None
    for i, p in enumerate(points):
        if i == skip:
            continue
        d = sum((p[r] - q[r]) ** 2 for r in range(dims))
        if best is None or d < best:
            best, lab = d, labels[i]
    return lab


def train(con, table, where, options, params=()):
    t0 = time.process_time()
    model = con.execute("SELECT fda_train(motion, style, ?) FROM %s WHERE %s" % (table, where),
                        (json.dumps(options),) + tuple(params)).fetchone()[0]
    return model, time.process_time() - t0


def embed_all(con, table, model, where="1", params=()):
    return [(i, s, f32(z)) for i, s, z in con.execute(
        "SELECT id, style, fda_embed(?, motion) FROM %s WHERE %s ORDER BY id" % (table, where),
        (model,) + tuple(params))]


def training_rate(con, table, options):
    model, secs = train(con, table, "1", options)
    rows = embed_all(con, table, model)
    pts = [z for _, _, z in rows]
    labs = [s for _, s, _ in rows]
    dims = len(pts[0])
    rates = {}
    for d in (2, 3):
        if d > dims:
            rates[d] = None
            continue
        right = sum(nearest(pts, labs, pts[i], d, skip=i) == labs[i] for i in range(len(pts)))
        rates[d] = 100.0 * right / len(pts)
    return rates, secs


def cv_rate(con, table, options, folds):
    """folds: list of (train where, test where); returns {2: %, 3: %} and the mean training
    CPU seconds. The training points are the model's own training embedding (fda_info)."""
    right = {2: 0, 3: 0}
    total, secs = 0, []
    for tw, sw in folds:
        model, s = train(con, table, tw, options)
        secs.append(s)
        info = json.loads(con.execute("SELECT fda_info(?)", (model,)).fetchone()[0])
        te = embed_all(con, table, model, sw)
        pts = info["train_embedding"]
        labs = [info["classes"][k] for k in info["train_labels"]]
        for _, lab, z in te:
            total += 1
            for d in (2, 3):
                if d <= len(z) and nearest(pts, labs, z, d) == lab:
                    right[d] += 1
    return {d: 100.0 * right[d] / total for d in (2, 3)}, sum(secs) / len(secs)


def views(con):
    con.execute("DROP TABLE IF EXISTS temp.c1")
    con.execute("CREATE TEMP TABLE c1 AS SELECT id, content, style, motion FROM motions WHERE "
                "source = 'bandai-namco-1' AND style IN (%s) AND content IN (%s) ORDER BY id"
                % (",".join("'%s'" % e for e in FOUR), ",".join("'%s'" % c for c in TEN)))
    con.execute("DROP TABLE IF EXISTS temp.c2")
    con.execute("CREATE TEMP TABLE c2 AS SELECT id, content, style, motion FROM motions WHERE "
                "source = 'bandai-namco-2-dev' ORDER BY id")


def fmt(v):
    return "–" if v is None else "%.0f %%" % v


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "fda.db"))
    ap.add_argument("--corpora", default="1,2")
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--options", default="{}")
    ap.add_argument("--sigmas", default="0.25,0.5,1,2")
    ap.add_argument("--no-loco", action="store_true")
    ap.add_argument("--folds2", type=int, default=0)
    a = ap.parse_args()
    if not os.path.isdir(CORPORA):
        print("fda_eval: skipped: %s is absent" % CORPORA)
        return 0
    which = [{"1": "bandai-namco-1", "2": "bandai-namco-2-dev"}[c] for c in a.corpora.split(",")]
    con = connect(a.db)
    import_corpora(con, which)
    views(con)
    base = json.loads(a.options)
    print("options: %s" % json.dumps(base))
    for source in which:
        table = "c1" if source == "bandai-namco-1" else "c2"
        ids = [r[0] for r in con.execute("SELECT id FROM %s ORDER BY id" % table)]
        if table == "c2" and a.folds2:
            folds = [("id %% %d <> %d" % (a.folds2, k), "id %% %d = %d" % (a.folds2, k))
                     for k in range(a.folds2)]
            proto = "%d-fold (id mod %d)" % (a.folds2, a.folds2)
        else:
            folds = [("id <> %d" % i, "id = %d" % i) for i in ids]
            proto = "leave-one-out"
        print("\n### %s, %d motions, %s, 1-NN\n" % (source, len(ids), proto))
        print("| method | train 2-D | train 3-D | test 2-D | test 3-D | thesis test (hand; "
              "full body) | CPU s per training |")
        print("|---|---|---|---|---|---|---|")
        for name in a.methods.split(","):
            opts = dict(base, **METHODS[name])
            tr, _ = training_rate(con, table, opts)
            te, secs = cv_rate(con, table, opts, folds)
            th = THESIS[name]
            print("| %s | %s | %s | %s | %s | %d %%; %d %% | %.3f |" % (
                name, fmt(tr[2]), fmt(tr[3]), fmt(te[2]), fmt(te[3]), th[0], th[1], secs))
            sys.stdout.flush()
    if not a.no_loco and "bandai-namco-1" in which:
        print("\n### bandai-namco-1, 4 emotions, FSPCA-RBF, leave one content out (10 folds), "
              "1-NN\n")
        print("| sigma | test 2-D | test 3-D |")
        print("|---|---|---|")
        folds = [("content <> '%s'" % c, "content = '%s'" % c) for c in TEN]
        for s in a.sigmas.split(","):
            opts = dict(base, method="fspca", kernel="rbf", sigma=float(s))
            te, _ = cv_rate(con, "c1", opts, folds)
            print("| %s | %s | %s |" % (s, fmt(te[2]), fmt(te[3])))
            sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
