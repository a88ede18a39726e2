#!/usr/bin/env python3
"""strength_eval.py — emotion strength by relative attributes, measured with the paper's protocol.

Usage (from the repository root, after any build of build/affect.so; about 15 minutes):
    OPENBLAS_NUM_THREADS=1 python3 tests/bench/strength_eval.py [--db build/strength.db]
        [--tasks anger,happiness,exhausted] [--seeds 1,2,3] [--quick] [--features]
        [--synthesis-features keyframes|both] [--recognizer [--recognizer-options JSON]]
        [--score-timing]
AFFECT_EXT overrides the extension's path (default build/affect). Python 3 standard library and
sqlite3 only. It imports the BVH files of ../shared/corpora/bandai-namco-1 and
bandai-namco-2-dev into --db once (motion_from_bvh), then, for every task:

  anger      bandai-namco-1, normal < angry   (the 10 contents recorded in every style: 22 motions)
  happiness  bandai-namco-1, sad < normal < happy                                  (33 motions)
  exhausted  bandai-namco-2-dev, normal < exhausted  (6 contents × 12 takes × 2: 144 motions)

runs the protocol of the paper's §6.3: for each seed, half the motions (stratified by label,
drawn by the seed) train, half test; strength_train gets the training motions with
"fraction" = 10, 30, 50, 70, 90 % of the training pairs (all ordered pairs of different labels
and similar pairs of the same label; the sample drawn by the seed), for PCA-40, PCA-80 and no
PCA (default options otherwise: standardized features), and at PCA-40 with relative poses and
without standardization (the paper's features); the accuracy is the share of the test
motions' ordered pairs (different labels, never seen in training) that affect_strength orders
right. Then leave one content out (train on every other content with all its pairs; test on
the held-out content's ordered pairs, pooled over the folds). Then, on exhausted (the task with enough takes), synthesis and editing: a model of
one content's training half synthesizes 5 strengths spread over its training range, and every
test normal motion of that content is edited to the same 5 strengths; the Spearman correlation
between the strength asked and the strength affect_strength measures on the result, and the
correlation of laban_time and laban_weight with it. Output: Markdown tables (mean ± sd over the
seeds), and the wall and CPU time of the runs.

--recognizer (about 7 minutes) runs only the recognizer check, for every task of --tasks: per
seed, a PCA-40 model and affect_train's recognizer (its defaults) trained on the training half,
strength_synthesize at 5 strengths from the lowest to the highest level's training mean and
strength_edit of every test motion to each; per result affect_strength (the Spearman
correlation with the strength asked), affect_classify (recognized as the label whose training
mean strength is nearest the strength asked?), laban_time and laban_weight (their Pearson
correlation with it). --recognizer-options gives the recognizer other affect_train options
(for example {"descriptors":"none"}: no kinematic summaries). --edit-features fisher edits with
the default (Fisher) model instead of a PCA-40 keyframe model (its edits move the joint
positions along the gradient of its ranker; it does not synthesize, so that column is empty).

The rows above rank by keyframe features ("features": "keyframes"). --features replaces them by
the inputs of the ranker, "keyframes", "laban", "both", "fisher" (the default of
strength_train: the representation of a recognizer trained on the training motions) and
"fisher" with "descriptors": "none" (no kinematic summaries, so no durations), with default
options otherwise (about 2 minutes; the "dims" column is then the keyframe PCA's).
--synthesis-features chooses the synthesis models' input (a "laban" or "fisher" model cannot
synthesize).

--score-timing (under a minute) only times affect_strength through SQL, one statement per
motion with its decoding, for a default (Fisher), a Laban and a PCA-40 keyframe model of each
task trained on all its motions: process CPU per call over 5 passes after a warm-up pass.
"""
import argparse
import json
import math
import os
import random
import sys
import time

from corpus_import import CORPORA, ROOT, TEN, connect, import_corpora

TASKS = {
    "anger": ("bandai-namco-1", ["normal", "angry"]),
    "happiness": ("bandai-namco-1", ["sad", "normal", "happy"]),
    "exhausted": ("bandai-namco-2-dev", ["normal", "exhausted"]),
}
FRACTIONS = [0.1, 0.3, 0.5, 0.7, 0.9]
# (name, strength_train options): the paper's three feature sizes with the defaults
# (standardized features), then the two feature options at PCA-40
# (the keyframe features' options: these rows rank by them, "features": "keyframes")
KF = {"features": "keyframes"}
CONFIGS = [("PCA-40", dict(KF, pca_dims=40)), ("PCA-80", dict(KF, pca_dims=80)),
           ("no PCA", dict(KF, pca_dims=0)),
           ("PCA-40, relative poses", dict(KF, pca_dims=40, relative=True)),
           ("PCA-40, not standardized (the paper's features)",
            dict(KF, pca_dims=40, standardize=False))]
# --features: what the ranker sees (docs/EVALUATION.md, "Laban features"), default options
# otherwise (PCA-40 keyframes for the regression and for "both")
FEATURE_CONFIGS = [("keyframes", {"features": "keyframes"}), ("laban", {"features": "laban"}),
                   ("both", {"features": "both"}), ("fisher", {"features": "fisher"}),
                   ("fisher, no descriptors", {"features": "fisher", "descriptors": "none"})]


def task_rows(con, task):
    source, order = TASKS[task]
    marks = ",".join("?" * len(order))
    sql = ("SELECT id, content, style FROM motions WHERE source = ? AND style IN (%s)" % marks)
    args = [source] + order
    if source == "bandai-namco-1":
        sql += " AND content IN (%s)" % ",".join("?" * len(TEN))
        args += TEN
    return [dict(id=r[0], content=r[1], style=r[2], level=order.index(r[2]))
            for r in con.execute(sql + " ORDER BY id", args)]


def split_half(rows, seed):
    """Half of each label to training (the odd one out alternates), by the seed."""
    rng = random.Random(seed)
    train, test = [], []
    for level in sorted(set(r["level"] for r in rows)):
        group = [r for r in rows if r["level"] == level]
        rng.shuffle(group)
        k = (len(group) + (level % 2)) // 2
        train += group[:k]
        test += group[k:]
    return train, test


def train(con, task, rows, opts):
    order = TASKS[task][1]
    con.execute("DROP TABLE IF EXISTS temp.tr")
    con.execute("CREATE TEMP TABLE tr(id INTEGER PRIMARY KEY)")
    con.executemany("INSERT INTO tr VALUES (?)", [(r["id"],) for r in rows])
    o = dict(opts)
    o["order"] = order
    t0, c0 = time.perf_counter(), time.process_time()
    blob = con.execute("SELECT strength_train(motion, style, ?) FROM motions JOIN tr USING (id)",
                       (json.dumps(o),)).fetchone()[0]
    return blob, time.perf_counter() - t0, time.process_time() - c0


def scores(con, model, rows):
    out = {}
    for r in rows:
        out[r["id"]] = con.execute("SELECT affect_strength(?, motion) FROM motions WHERE id = ?",
                                   (model, r["id"])).fetchone()[0]
    return out


def pair_accuracy(rows, sc, same_content=False):
    right = total = 0
    for a in rows:
        for b in rows:
            if a["level"] > b["level"] and (not same_content or a["content"] == b["content"]):
                total += 1
                right += sc[a["id"]] > sc[b["id"]]
    return right, total


def mean_sd(v):
    if not v:
        return float("nan"), float("nan")
    m = sum(v) / len(v)
    sd = math.sqrt(sum((x - m) ** 2 for x in v) / (len(v) - 1)) if len(v) > 1 else 0.0
    return m, sd


def spearman(x, y):
    def ranks(v):
        order = sorted(range(len(v)), key=lambda i: v[i])
        r = [0.0] * len(v)
        for k, i in enumerate(order):
            r[i] = float(k)
        return r
    rx, ry = ranks(x), ranks(y)
    return pearson(rx, ry)


def pearson(x, y):
    n = len(x)
    mx, my = sum(x) / n, sum(y) / n
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sxx = sum((a - mx) ** 2 for a in x)
    syy = sum((b - my) ** 2 for b in y)
    return sxy / math.sqrt(sxx * syy) if sxx > 0 and syy > 0 else float("nan")


def protocol(con, task, seeds, fractions, configs):
    rows = task_rows(con, task)
    print("\n### %s: %s, %d motions (%s)\n" % (task, " < ".join(TASKS[task][1]), len(rows),
                                               TASKS[task][0]))
    print("Half train / half test; accuracy on the test motions' ordered pairs (unseen), "
          "mean ± sd over seeds %s.\n" % ",".join(map(str, seeds)))
    print("| features | " + " | ".join("%d %%" % round(100 * f) for f in fractions) +
          " | train time (CPU, 90 %) | dims |")
    print("|---|" + "---:|" * (len(fractions) + 2))
    summary = {}
    for name, copts in configs:
        cells, times, used_dims = [], [], set()
        for f in fractions:
            accs = []
            for seed in seeds:
                tr, te = split_half(rows, seed)
                o = dict(copts, fraction=f, seed=seed)
                model, wall, cpu = train(con, task, tr, o)
                sc = scores(con, model, te)
                right, total = pair_accuracy(te, sc)
                accs.append(right / total)
                if f == fractions[-1]:
                    times.append(cpu)
                    info = json.loads(con.execute("SELECT strength_info(?)", (model,)).fetchone()[0])
                    used_dims.add(info["pca"]["dims"] if info["pca"] else info["features"])
            m, sd = mean_sd(accs)
            cells.append("%.1f ± %.1f" % (100 * m, 100 * sd))
            summary[(name, f)] = m
        print("| %s | %s | %.3f s | %s |" % (name, " | ".join(cells), mean_sd(times)[0],
                                             ",".join(map(str, sorted(used_dims)))))
    return summary


def leave_one_content_out(con, task, configs):
    rows = task_rows(con, task)
    contents = sorted(set(r["content"] for r in rows))
    print("\nLeave one content out (%d folds; all training pairs; accuracy on the held-out "
          "content's ordered pairs, pooled):\n" % len(contents))
    print("| features | accuracy | pairs |")
    print("|---|---:|---:|")
    for name, copts in configs:
        right = total = 0
        for c in contents:
            tr = [r for r in rows if r["content"] != c]
            te = [r for r in rows if r["content"] == c]
            model, _, _ = train(con, task, tr, copts)
            rr, tt = pair_accuracy(te, scores(con, model, te))
            right += rr
            total += tt
        print("| %s | %.1f | %d |" % (name, 100.0 * right / total if total else float("nan"),
                                      total))


def synthesis(con, task, seeds, features=None):
    rows = task_rows(con, task)
    contents = sorted(set(r["content"] for r in rows))
    print("\nSynthesis and editing (%s, PCA-40, one model per content from its training half; "
          "5 strengths from the lowest to the highest level's training mean):\n" % task)
    print("| content | synthesized: Spearman | edited: Spearman (mean over test motions) | "
          "edited: r(s, laban_time) | edited: r(s, laban_weight) |")
    print("|---|---:|---:|---:|---:|")
    allsyn, alledit = [], []
    for c in contents:
        syn, edit, lt, lw = [], [], [], []
        for seed in seeds:
            tr, te = split_half([r for r in rows if r["content"] == c], seed)
            o = {"pca_dims": 40, "seed": seed, "features": features or "keyframes"}
            model, _, _ = train(con, task, tr, o)
            info = json.loads(con.execute("SELECT strength_info(?)", (model,)).fetchone()[0])
            lo, hi = info["levels"][0]["strength"], info["levels"][-1]["strength"]
            targets = [lo + (hi - lo) * k / 4 for k in range(5)]
            got = [con.execute("SELECT affect_strength(?1, strength_synthesize(?1, ?2))",
                               (model, t)).fetchone()[0] for t in targets]
            syn.append(spearman(targets, got))
            for r in te:
                if r["level"] != 0:
                    continue
                res = []
                for t in targets:  # the edit once, then its three measures
                    e = con.execute("SELECT strength_edit(?1, motion, ?2) FROM motions "
                                    "WHERE id = ?3", (model, t, r["id"])).fetchone()[0]
                    res.append(con.execute("SELECT affect_strength(?1, ?2), laban_time(?2), "
                                           "laban_weight(?2)", (model, e)).fetchone())
                edit.append(spearman(targets, [x[0] for x in res]))
                lt.append(pearson(targets, [x[1] for x in res]))
                lw.append(pearson(targets, [x[2] for x in res]))
        allsyn += syn
        alledit += edit
        print("| %s | %.2f | %.2f | %+.2f | %+.2f |" % (c, mean_sd(syn)[0], mean_sd(edit)[0],
                                                        mean_sd(lt)[0], mean_sd(lw)[0]))
    print("| **all** | %.2f | %.2f | | |" % (mean_sd(allsyn)[0], mean_sd(alledit)[0]))


def nearest_level(levels, s):
    """The label whose training mean strength is nearest s; None at a tie (the midpoint)."""
    d = sorted((abs(s - lv["strength"]), lv["label"]) for lv in levels)
    if len(d) > 1 and abs(d[0][0] - d[1][0]) <= 1e-9 * (1 + abs(s)):
        return None
    return d[0][1]


def recognizer_check(con, task, seeds, npoints=5, rec_options="{}", edit_features="keyframes"):
    """Synthesized and edited motions checked by the ranker, affect_train's recognizer and Laban.

    Per seed: the half split of protocol(); a PCA-40 strength model and affect_train's recognizer
    (its defaults, the task's labels) trained on the training half only; npoints strengths evenly
    from the lowest to the highest level's training mean; strength_synthesize at each, and every
    test motion edited (strength_edit) to each. Per result: affect_strength, affect_classify
    (svm), laban_time, laban_weight. The label a strength carries is the level whose training
    mean strength is nearest (the midpoint of two levels carries none and is not counted)."""
    rows = task_rows(con, task)
    order = TASKS[task][1]
    acc = {k: [0, 0] for k in ("test", "syn", "edit", "edit_changed", "syn_ends", "edit_ends")}
    conf = {}  # (kind, carried label) -> {recognized label: count}
    rho = {"syn": [], "edit": []}
    lab = {"syn_t": [], "syn_w": [], "edit_t": [], "edit_w": []}
    for seed in seeds:
        tr, te = split_half(rows, seed)
        # keyframe features (the default), or the default model (Fisher: edits only, by the
        # gradient of its ranker; it cannot synthesize)
        opts = dict(KF, pca_dims=40, seed=seed) if edit_features == "keyframes" else {"seed": seed}
        model, _, _ = train(con, task, tr, opts)
        rec = con.execute("SELECT affect_train(motion, style, ?) FROM motions JOIN tr USING (id)",
                          (rec_options,)).fetchone()[0]
        info = json.loads(con.execute("SELECT strength_info(?)", (model,)).fetchone()[0])
        levels = info["levels"]
        lo, hi = levels[0]["strength"], levels[-1]["strength"]
        targets = [lo + (hi - lo) * k / (npoints - 1) for k in range(npoints)]
        carried = [nearest_level(levels, t) for t in targets]
        for r in te:  # the recognizer on the unseen motions as recorded: its own accuracy here
            got = con.execute("SELECT affect_classify(?, motion) FROM motions WHERE id = ?",
                              (rec, r["id"])).fetchone()[0]
            acc["test"][0] += got == r["style"]
            acc["test"][1] += 1

        def measure(kind, blob, k):
            s, lt, lw, label = con.execute(
                "SELECT affect_strength(?1, ?2), laban_time(?2), laban_weight(?2), "
                "affect_classify(?3, ?2)", (model, blob, rec)).fetchone()
            if carried[k] is not None:
                acc[kind][0] += label == carried[k]
                acc[kind][1] += 1
                c = conf.setdefault((kind, carried[k]), {})
                c[label] = c.get(label, 0) + 1
                if k in (0, npoints - 1):
                    acc[kind + "_ends"][0] += label == carried[k]
                    acc[kind + "_ends"][1] += 1
            return s, lt, lw, label

        if edit_features == "keyframes":
            res = [measure("syn", con.execute("SELECT strength_synthesize(?, ?)",
                                              (model, t)).fetchone()[0], k)
                   for k, t in enumerate(targets)]
            rho["syn"].append(spearman(targets, [x[0] for x in res]))
            lab["syn_t"].append(pearson(targets, [x[1] for x in res]))
            lab["syn_w"].append(pearson(targets, [x[2] for x in res]))
        for r in te:
            res = []
            for k, t in enumerate(targets):
                e = con.execute("SELECT strength_edit(?1, motion, ?2) FROM motions WHERE id = ?3",
                                (model, t, r["id"])).fetchone()[0]
                res.append(measure("edit", e, k))
                if carried[k] is not None and carried[k] != r["style"]:
                    acc["edit_changed"][0] += res[-1][3] == carried[k]
                    acc["edit_changed"][1] += 1
            rho["edit"].append(spearman(targets, [x[0] for x in res]))
            lab["edit_t"].append(pearson(targets, [x[1] for x in res]))
            lab["edit_w"].append(pearson(targets, [x[2] for x in res]))

    def pct(k):
        return "%.1f %% (%d/%d)" % (100.0 * acc[k][0] / acc[k][1] if acc[k][1] else float("nan"),
                                    acc[k][0], acc[k][1])

    def msd(v):
        v = [x for x in v if not math.isnan(x)]
        return "%+.2f ± %.2f" % mean_sd(v) if v else "n/a"
    print("\n### Recognizer check, %s: %s (%s; seeds %s; %d strengths from the lowest to the "
          "highest level's training mean)\n" % (task, " < ".join(order), TASKS[task][0],
                                                 ",".join(map(str, seeds)), npoints))
    print("| | synthesized | edited (every test motion) |")
    print("|---|---:|---:|")
    print("| Spearman(s asked, affect_strength), mean ± sd | %s | %s |" % (msd(rho["syn"]),
                                                                          msd(rho["edit"])))
    print("| recognized as the label s carries | %s | %s |" % (pct("syn"), pct("edit")))
    print("| … at the two ends (lowest, highest level mean) | %s | %s |" % (pct("syn_ends"),
                                                                            pct("edit_ends")))
    print("| … edits to a label other than the motion's own | | %s |" % pct("edit_changed"))
    print("| Pearson(s, laban_time), mean ± sd | %s | %s |" % (msd(lab["syn_t"]),
                                                               msd(lab["edit_t"])))
    print("| Pearson(s, laban_weight), mean ± sd | %s | %s |" % (msd(lab["syn_w"]),
                                                                 msd(lab["edit_w"])))
    print("\nThe recognizer on the unseen test motions as recorded: %s." % pct("test"))
    print("\nRecognized labels by the label carried:\n")
    print("| kind | carried | " + " | ".join(order) + " |")
    print("|---|---|" + "---:|" * len(order))
    for (kind, c), d in sorted(conf.items(), key=lambda kv: (kv[0][0], order.index(kv[0][1]))):
        print("| %s | %s | %s |" % (kind, c, " | ".join(str(d.get(x, 0)) for x in order)))


def score_timing(con, task, passes=5):
    """affect_strength through SQL, one statement per motion, the motion's decoding included:
    a model of each kind (the default Fisher model, a Laban model, a PCA-40 keyframe model)
    trained on all the task's motions; after one untimed pass (the model is decoded once per connection), the
    process CPU time of `passes` passes over the motions, per call."""
    rows = task_rows(con, task)
    print("\n#### affect_strength through SQL: %s, %d motions\n" % (task, len(rows)))
    print("| model | CPU per call (ms) |")
    print("|---|---:|")
    for name, opts in (("default (Fisher representation)", {}), ("Laban vector", {"features": "laban"}),
                       ("keyframes, PCA-40", dict(KF, pca_dims=40))):
        model, _, _ = train(con, task, rows, opts)
        scores(con, model, rows)
        c0 = time.process_time()
        for _ in range(passes):
            scores(con, model, rows)
        print("| %s | %.2f |" % (name, 1e3 * (time.process_time() - c0) / (passes * len(rows))))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "strength.db"))
    ap.add_argument("--tasks", default="anger,happiness,exhausted")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--quick", action="store_true",
                    help="one seed, 50 %% of the pairs, PCA-40 only (a smoke run)")
    ap.add_argument("--no-synthesis", action="store_true")
    ap.add_argument("--features", action="store_true",
                    help="compare the ranker's features (keyframes, laban, both, fisher) instead of the "
                         "keyframe options")
    ap.add_argument("--synthesis-features", default="keyframes",
                    help="the synthesis table's models' \"features\": keyframes (default) or "
                         "both (a laban or fisher model cannot synthesize)")
    ap.add_argument("--synthesis-only", action="store_true",
                    help="only the synthesis and editing table (exhausted)")
    ap.add_argument("--recognizer", action="store_true",
                    help="only the recognizer check of synthesized and edited motions, for every "
                    "task of --tasks")
    ap.add_argument("--score-timing", action="store_true",
                    help="only the CPU time of affect_strength through SQL per motion, for the "
                         "default and a keyframe model of each task")
    ap.add_argument("--edit-features", default="keyframes", choices=["keyframes", "fisher"],
                    help="--recognizer: edit with a PCA-40 keyframe model (and synthesize), or "
                         "with the default Fisher model (edits only)")
    ap.add_argument("--recognizer-options", default="{}",
                    help='affect_train options of the recognizer check, e.g. '
                         '{"descriptors":"none"}')
    a = ap.parse_args()
    if not os.path.isdir(CORPORA):
        print("strength_eval: ../shared/corpora is absent; nothing to measure")
        return 0
    seeds = [int(s) for s in a.seeds.split(",")]
    fractions, configs = FRACTIONS, (FEATURE_CONFIGS if a.features else CONFIGS)
    if a.quick:
        seeds, fractions, configs = seeds[:1], [0.5], configs[:1]
    con = connect(a.db)
    t0, c0 = time.perf_counter(), time.process_time()
    import_corpora(con)
    if a.score_timing:
        for task in a.tasks.split(","):
            score_timing(con, task)
        return 0
    if a.recognizer:
        for task in a.tasks.split(","):
            recognizer_check(con, task, seeds, rec_options=a.recognizer_options,
                             edit_features=a.edit_features)
        print("\n(total: %.0f s wall, %.0f s CPU)" % (time.perf_counter() - t0,
                                                      time.process_time() - c0))
        return 0
    for task in ([] if a.synthesis_only else a.tasks.split(",")):
        protocol(con, task, seeds, fractions, configs)
        leave_one_content_out(con, task, configs)
    if not a.no_synthesis and "exhausted" in a.tasks.split(","):
        synthesis(con, "exhausted", seeds, a.synthesis_features)
    print("\n(total: %.0f s wall, %.0f s CPU)" % (time.perf_counter() - t0,
                                                  time.process_time() - c0))
    return 0


if __name__ == "__main__":
    sys.exit(main())
