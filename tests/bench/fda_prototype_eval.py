#!/usr/bin/env python3
"""fda_prototype_eval.py — are fda_prototype's prototypes (thesis §3.2) recognized as their class?

Usage (from the repository root, after a build of build/affect.so; about 3 minutes):
    OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/fda_prototype_eval.py [--db build/fda.db]
        [--corpora 1,2] [--dims 3,10,20,40,all] [--options '{"alignment":"landmarks"}']
AFFECT_EXT overrides the extension's path (default build/affect). Python's standard library and
sqlite3 only.

It imports the corpora of ../shared/corpora into --db once (corpus_import.py), then, with the
thesis's generation settings (150 B-splines, FPCA, first-frame observations of every joint) and
each proto_dims of --dims (the FPCA components the class centroids live on; 3 is the thesis's,
"all" fda_train's default, the class's mean function):
  - bandai-namco-1, the 44 angry/happy/normal/sad motions of the ten contents recorded in every
    style: one model over all 44, a prototype per emotion (each the average of ten different
    actions), recognized by affect_train (defaults) trained on the 44;
  - bandai-namco-2-dev, per content (one movement performed in every style, the thesis's
    setting: 12 takes × 7 styles): one model over the content's 84 motions, a prototype per
    style, recognized by affect_train (defaults) trained on the other five contents ("held-out
    content": the recognizer has never seen this movement) and by one trained on all 504
    motions ("all").
For each, the share of prototypes recognized as their class, and the Spearman correlation
between the prototypes' laban_weight (and laban_time) and their classes' mean over the real
motions (the prototypes are in arm lengths, the motions in cm: only the order compares; per
content on bandai-namco-2-dev, averaged). Output: Markdown tables and the CPU time.
"""
import argparse
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corpus_import import FOUR, ROOT, TEN, connect, import_corpora  # noqa: E402

MODEL = '{"basis":150,"frame":"first","method":"fpca","proto_dims":%s}'


def ranks(v):
    order = sorted(range(len(v)), key=lambda i: v[i])
    r = [0.0] * len(v)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and v[order[j + 1]] == v[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = (i + j) / 2.0
        i = j + 1
    return r


def spearman(a, b):
    ra, rb = ranks(a), ranks(b)
    n = len(a)
    ma, mb = sum(ra) / n, sum(rb) / n
    sab = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    saa = sum((x - ma) ** 2 for x in ra)
    sbb = sum((y - mb) ** 2 for y in rb)
    return sab / (saa * sbb) ** 0.5 if saa > 0 and sbb > 0 else float("nan")


def prototypes(con, where, args, classes, dims, extra):
    """{class: prototype BLOB} of one fda_train over the rows of motions matching where."""
    options = json.loads(MODEL % (dims if dims != "all" else '"all"'))
    options.update(extra)
    model = con.execute("SELECT fda_train(motion, style, ?) FROM motions WHERE " + where,
                        [json.dumps(options)] + args).fetchone()[0]
    return {c: con.execute("SELECT fda_prototype(?, ?)", (model, c)).fetchone()[0]
            for c in classes}


def laban_order(con, protos, where, args):
    """Spearman correlations of the prototypes' Weight and Time with their classes' means."""
    out = []
    for fn in ("laban_weight", "laban_time"):
        mine, real = [], []
        for c, p in sorted(protos.items()):
            mine.append(con.execute("SELECT %s(?)" % fn, (p,)).fetchone()[0])
            real.append(con.execute("SELECT avg(%s(motion)) FROM motions WHERE style = ? AND %s"
                                    % (fn, where), [c] + args).fetchone()[0])
        out.append(spearman(mine, real))
    return out


def classify(con, model, protos):
    return sum(con.execute("SELECT affect_classify(?, ?) = ?", (model, p, c)).fetchone()[0]
               for c, p in protos.items())


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "fda.db"))
    ap.add_argument("--corpora", default="1,2")
    ap.add_argument("--dims", default="3,10,20,40,all")
    ap.add_argument("--options", default="{}", help="more fda_train options")
    a = ap.parse_args()
    extra = json.loads(a.options)
    dims = a.dims.split(",")
    con = connect(a.db)
    import_corpora(con)
    t0 = time.process_time()
    if "1" in a.corpora.split(","):
        where = ("source = 'bandai-namco-1' AND style IN (%s) AND content IN (%s)"
                 % (",".join("'%s'" % e for e in FOUR), ",".join("'%s'" % c for c in TEN)))
        rec = con.execute("SELECT affect_train(motion, style) FROM motions WHERE " + where
                          ).fetchone()[0]
        print("\n### bandai-namco-1, 4 emotions, one model over the 44 motions\n")
        print("| proto_dims | recognized | Weight order (Spearman) | Time order (Spearman) |")
        print("|---:|---:|---:|---:|")
        for d in dims:
            protos = prototypes(con, where, [], FOUR, d, extra)
            ok = classify(con, rec, protos)
            w, t = laban_order(con, protos, where, [])
            print("| %s | %d of %d | %.2f | %.2f |" % (d, ok, len(protos), w, t), flush=True)
    if "2" in a.corpora.split(","):
        src = "bandai-namco-2-dev"
        contents = [r[0] for r in con.execute(
            "SELECT DISTINCT content FROM motions WHERE source = ? ORDER BY 1", (src,))]
        styles = [r[0] for r in con.execute(
            "SELECT DISTINCT style FROM motions WHERE source = ? ORDER BY 1", (src,))]
        every = con.execute("SELECT affect_train(motion, style) FROM motions WHERE source = ?",
                            (src,)).fetchone()[0]
        held = {c: con.execute("SELECT affect_train(motion, style) FROM motions "
                               "WHERE source = ? AND content <> ?", (src, c)).fetchone()[0]
                for c in contents}
        print("\n### bandai-namco-2-dev, 7 styles, one model per content (12 takes x 7 styles)\n")
        print("| proto_dims | recognized, held-out content | recognized, all | "
              "Weight order (Spearman, mean) | Time order (Spearman, mean) |")
        print("|---:|---:|---:|---:|---:|")
        for d in dims:
            ok_h = ok_a = n = 0
            ws, ts = [], []
            for c in contents:
                where, args = "source = ? AND content = ?", [src, c]
                protos = prototypes(con, where, args, styles, d, extra)
                ok_h += classify(con, held[c], protos)
                ok_a += classify(con, every, protos)
                n += len(protos)
                w, t = laban_order(con, protos, where, args)
                ws.append(w)
                ts.append(t)
            print("| %s | %d of %d (%.0f %%) | %d of %d (%.0f %%) | %.2f | %.2f |"
                  % (d, ok_h, n, 100.0 * ok_h / n, ok_a, n, 100.0 * ok_a / n,
                     sum(ws) / len(ws), sum(ts) / len(ts)), flush=True)
    print("\nCPU s: %.1f" % (time.process_time() - t0))


if __name__ == "__main__":
    main()
