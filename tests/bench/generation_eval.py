#!/usr/bin/env python3
"""generation_eval.py — affect_generate measured as a user meets it, on both real corpora.

Usage (from the repository root, after any build of build/affect.so):
    OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/generation_eval.py
        [--db build/recognition.db] [--corpus 1|2|both] [--options JSON] [--quick]
        [--protocol takes|content|both] [--recognizer JSON]
AFFECT_EXT overrides the extension's path (default build/affect). The corpora are imported into
--db by corpus_import.py (once; reused when the file holds them).

Everything generated goes through SQL: affect_generate(index, source, target, options) with
{"source_label": the source's style} added to --options (default: none, i.e. the defaults).

bandai-namco-1 (the 44 angry/happy/normal/sad motions of the ten contents recorded in every
style), leave one content out: for each content c a laban index over the other contents and a
recognizer affect_train(motion, style) with its defaults on them (c is in neither); every
motion of c is converted to the three other emotions. Measured per conversion:
  - recognized as the target by that recognizer (next to it, the same recognizer on the real
    recordings of c: the reference row);
  - action kept: the nearest motion by motion_dtw among the 44 (the source excluded) has the
    source's content;
  - direction: WeightAll and TimeAll each move from the source the way the real recording of
    c in the target emotion moves (same take when there are two);
  - closer to that real recording than the source is: Euclidean distance over the 27 Laban
    components z-scored over the 44 motions, and motion_dtw.
bandai-namco-2-dev (504 motions, 7 styles, 6 contents × 12 takes): every normal motion of takes
1, 4, 7 and 10 is converted to each other style, under two protocols:
  - "takes out": the index and the recognizer hold every motion except the source's take group
    (takes 1–3, 4–6, 7–9 or 10–12 of every content and style: 4 folds);
  - "content out": they hold the other five contents (6 folds);
and measured: recognized as the target; closer than the source to the real takes of that
content and style (Laban: to the mean of their z-scored vectors; DTW: the mean motion_dtw to
them); action kept (nearest by motion_dtw, the source excluded, among one take (12) of every
content and style: 42 references).
Output: Markdown tables.
"""
import argparse
import json
import math
import os
import statistics
import struct
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import corpus_import as ci  # noqa: E402  (the importer and the corpora's lists)

ROOT = os.path.dirname(os.path.dirname(HERE))


def pct(n, d):
    return "%.1f %% (%d of %d)" % (100.0 * n / d if d else 0.0, n, d)


def vec(blob):
    return struct.unpack("<27f", blob)


def zscorer(vectors):
    mean, sd = [], []
    for j in range(27):
        col = [v[j] for v in vectors if not math.isnan(v[j])]
        mean.append(statistics.fmean(col) if col else 0.0)
        s = statistics.stdev(col) if len(col) > 1 else 0.0
        sd.append(s if s > 0 else 1.0)
    return lambda v: [(v[j] - mean[j]) / sd[j] if not math.isnan(v[j]) else float("nan")
                      for j in range(27)]


def dist(a, b):
    s = 0.0
    for x, y in zip(a, b):
        if not (math.isnan(x) or math.isnan(y)):
            s += (x - y) ** 2
    return math.sqrt(s)


RUN = "r%d_" % os.getpid()  # table names of this run: runs may share one --db
RECOGNIZER = {"threads": 2}  # affect_train's options (--recognizer adds to them)


def fold_setup(con, name, where, params):
    """A training table, its laban index and a recognizer (affect_train with RECOGNIZER)."""
    name = RUN + name
    con.execute('DROP TABLE IF EXISTS "lab_%s"' % name)
    con.execute('DROP TABLE IF EXISTS "tr_%s"' % name)
    con.execute('CREATE TABLE "tr_%s" AS SELECT * FROM pool WHERE %s' % (name, where), params)
    con.execute('CREATE VIRTUAL TABLE "lab_%s" USING laban(content="tr_%s", motion=motion, '
                'label=style)' % (name, name))
    model = con.execute('SELECT affect_train(motion, style, ?) FROM "tr_%s"' % name,
                        (json.dumps(RECOGNIZER),)).fetchone()[0]
    return "lab_" + name, model


def generate(con, index, model, sources, targets, options):
    """rows (source id, target, generated motion, recognized)"""
    out = []
    for sid, smotion, sstyle in sources:
        for t in targets:
            if t == sstyle:
                continue
            opts = dict(options)
            opts["source_label"] = sstyle
            g = con.execute("SELECT affect_generate(?, ?, ?, ?)",
                            (index, smotion, t, json.dumps(opts))).fetchone()[0]
            r = con.execute("SELECT affect_classify(?, ?)", (model, g)).fetchone()[0]
            out.append((sid, t, g, r))
    return out


FEET = ("Foot_L", "Foot_R", "Toes_L", "Toes_R")


def fidelity(con, g, src):
    """(bone-length variation of g, worst extra foot sliding in cm/s): over the frames where a
    foot joint of the source moves slower than 10 cm/s (resting), the mean of the generated
    motion's foot speed minus the source's, the worst foot; the corpora are in cm."""
    bones = con.execute("SELECT json_extract(motion_info(?), '$.bone_variation')",
                        (g,)).fetchone()[0]
    worst = 0.0
    for foot in FEET:
        pts = con.execute(
            "SELECT a.x, a.y, a.z, b.x, b.y, b.z FROM motion_points(?) AS a "
            "JOIN motion_points(?) AS b USING (frame, joint) WHERE a.name = ? ORDER BY frame",
            (src, g, foot)).fetchall()
        if len(pts) < 2:
            continue
        fps = con.execute("SELECT motion_fps(?)", (src,)).fetchone()[0]
        extra = []
        for p0, p1 in zip(pts, pts[1:]):
            vs = math.dist(p0[:3], p1[:3]) * fps
            vg = math.dist(p0[3:], p1[3:]) * fps
            if vs < 10.0:
                extra.append(vg - vs)
        if extra:
            worst = max(worst, statistics.fmean(extra))
    return bones, worst


def nearest_content(con, g, refs, exclude):
    best, content = None, None
    for rid, rmotion, rcontent in refs:
        if rid == exclude:
            continue
        d = con.execute("SELECT motion_dtw(?, ?)", (g, rmotion)).fetchone()[0]
        if best is None or d < best:
            best, content = d, rcontent
    return content


def corpus1(con, options, quick):
    con.execute("DROP TABLE IF EXISTS pool")
    con.execute("CREATE TEMP TABLE pool AS SELECT id, content, style, substr(name, -3) AS take, "
                "motion FROM motions WHERE source = 'bandai-namco-1' AND style IN (%s) AND "
                "content IN (%s) ORDER BY id" % (",".join("'%s'" % e for e in ci.FOUR),
                                                  ",".join("'%s'" % c for c in ci.TEN)))
    rows = con.execute("SELECT id, content, style, take, motion, laban_vector(motion) "
                       "FROM pool ORDER BY id").fetchall()
    by_id = {r[0]: r for r in rows}
    z = zscorer([vec(r[5]) for r in rows])
    refs = [(r[0], r[4], r[1]) for r in rows]
    contents = ci.TEN[:2] if quick else ci.TEN
    results, real = [], []
    own = sum(nearest_content(con, r[4], refs, r[0]) == r[1] for r in rows if r[1] in contents)
    n_own = sum(1 for r in rows if r[1] in contents)
    t0 = time.time()
    for c in contents:
        index, model = fold_setup(con, "c1_" + c.replace("-", "_"), "content <> ?", (c,))
        held = [r for r in rows if r[1] == c]
        for r in held:
            real.append(con.execute("SELECT affect_classify(?, ?)", (model, r[4])).fetchone()[0]
                        == r[2])
        gens = generate(con, index, model, [(r[0], r[4], r[2]) for r in held], ci.FOUR,
                        options)
        for sid, t, g, recog in gens:
            s = by_id[sid]
            truth = [r for r in held if r[2] == t and r[3] == s[3]] or \
                [r for r in held if r[2] == t]
            tr = truth[0]
            vg, vs, vt = (vec(con.execute("SELECT laban_vector(?)", (g,)).fetchone()[0]),
                          vec(s[5]), vec(tr[5]))
            d_gt = con.execute("SELECT motion_dtw(?, ?)", (g, tr[4])).fetchone()[0]
            d_st = con.execute("SELECT motion_dtw(?, ?)", (s[4], tr[4])).fetchone()[0]
            results.append(dict(
                source=s[2], target=t, recognized=recog == t, label=recog,
                kept=nearest_content(con, g, refs, sid) == c,
                dw=(vg[0] - vs[0]) * (vt[0] - vs[0]) > 0,
                dt=(vg[5] - vs[5]) * (vt[5] - vs[5]) > 0,
                lab=dist(z(vg), z(vt)) < dist(z(vs), z(vt)),
                dtw=d_gt < d_st, dtw_g=d_gt, dtw_s=d_st, fid=fidelity(con, g, s[4])))
    secs = time.time() - t0
    n = len(results)
    print("### bandai-namco-1, leave one content out (%d contents, %d conversions, %.0f s)\n"
          % (len(contents), n, secs))
    print("| measure | result | goal |")
    print("|---|---:|---:|")
    print("| recognized as the target | %s | ≥ 72 %% |" % pct(sum(r["recognized"] for r in results), n))
    print("| reference: the real recordings recognized as their emotion | %s | |"
          % pct(sum(real), len(real)))
    print("| action kept (DTW nearest neighbour has the source's content) | %s | ≥ 95 %% |"
          % pct(sum(r["kept"] for r in results), n))
    print("| reference: the sources themselves (their nearest other motion has their content) "
          "| %s | |" % pct(own, n_own))
    print("| WeightAll moves as the real recording's | %s | |" % pct(sum(r["dw"] for r in results), n))
    print("| TimeAll moves as the real recording's | %s | |" % pct(sum(r["dt"] for r in results), n))
    print("| both move as the real recording's | %s | ≥ 80 %% |"
          % pct(sum(r["dw"] and r["dt"] for r in results), n))
    print("| closer to the real recording than the source (Laban, z-scored) | %s | ≥ 60 %% |"
          % pct(sum(r["lab"] for r in results), n))
    print("| closer to the real recording than the source (DTW) | %s | |"
          % pct(sum(r["dtw"] for r in results), n))
    print("| mean DTW to the real recording: generated / source | %.3f / %.3f | |"
          % (statistics.fmean(r["dtw_g"] for r in results),
             statistics.fmean(r["dtw_s"] for r in results)))
    print_fidelity(results)
    print("Recognized (rows: target, columns: label):\n")
    print("| target | " + " | ".join(ci.FOUR) + " |")
    print("|---|" + "---:|" * len(ci.FOUR))
    for t in ci.FOUR:
        print("| %s | %s |" % (t, " | ".join(
            str(sum(1 for r in results if r["target"] == t and r["label"] == l))
            for l in ci.FOUR)))
    print()


def print_fidelity(results):
    bones = [r["fid"][0] for r in results]
    slide = [r["fid"][1] for r in results]
    print("| bone-length variation, worst output | %.2g | ≤ 1e-4 |" % max(bones))
    print("| extra foot sliding where the source's foot rests, worst output (cm/s) | %.2f | ≤ 1 |"
          % max(slide))
    print("| the same, median output (cm/s) | %.2f | |\n" % statistics.median(slide))


STYLES2 = ["active", "elderly", "exhausted", "feminine", "masculine", "normal", "youthful"]


def corpus2(con, options, quick, protocol="both"):
    con.execute("DROP TABLE IF EXISTS pool")
    con.execute("CREATE TEMP TABLE pool AS SELECT id, content, style, "
                "CAST(substr(name, -3) AS INTEGER) AS take, motion FROM motions "
                "WHERE source = 'bandai-namco-2-dev' ORDER BY id")
    rows = con.execute("SELECT id, content, style, take, motion, laban_vector(motion) "
                       "FROM pool ORDER BY id").fetchall()
    z = zscorer([vec(r[5]) for r in rows])
    zrows = {r[0]: z(vec(r[5])) for r in rows}
    contents = sorted({r[1] for r in rows})
    refs = [(r[0], r[4], r[1]) for r in rows if r[3] == 12]
    sources_all = [r for r in rows if r[2] == "normal" and r[3] in (1, 4, 7, 10)]
    if quick:
        sources_all = [r for r in sources_all if r[1] == contents[0] and r[3] == 1]
    protocols = [
        ("takes out", [(("t%d" % g), "(take - 1) / 3 <> ?", (g,),
                        [r for r in sources_all if (r[3] - 1) // 3 == g]) for g in range(4)]),
        ("content out", [(("c_" + c.replace("-", "_")), "content <> ?", (c,),
                          [r for r in sources_all if r[1] == c]) for c in contents]),
    ]
    for pname, folds in protocols:
        if protocol != "both" and not pname.startswith(protocol):
            continue
        t0 = time.time()
        results = []
        for name, where, params, sources in folds:
            if not sources:
                continue
            index, model = fold_setup(con, "c2_" + name, where, params)
            gens = generate(con, index, model, [(r[0], r[4], r[2]) for r in sources], STYLES2,
                            options)
            src = {r[0]: r for r in sources}
            for sid, t, g, recog in gens:
                s = src[sid]
                takes = [r for r in rows if r[1] == s[1] and r[2] == t]
                mean = [statistics.fmean(zrows[r[0]][j] for r in takes
                                         if not math.isnan(zrows[r[0]][j])) for j in range(27)]
                zg = z(vec(con.execute("SELECT laban_vector(?)", (g,)).fetchone()[0]))
                dg = statistics.fmean(con.execute("SELECT motion_dtw(?, ?)", (g, r[4])).fetchone()[0]
                                      for r in takes)
                ds = statistics.fmean(con.execute("SELECT motion_dtw(?, ?)", (s[4], r[4])).fetchone()[0]
                                      for r in takes)
                results.append(dict(
                    target=t, recognized=recog == t, label=recog,
                    lab=dist(zg, mean) < dist(zrows[sid], mean), dtw=dg < ds,
                    kept=nearest_content(con, g, refs, sid) == s[1], fid=fidelity(con, g, s[4])))
        n = len(results)
        print("### bandai-namco-2-dev, normal → the 6 other styles, %s (%d conversions, %.0f s)\n"
              % (pname, n, time.time() - t0))
        print("| measure | result | goal |")
        print("|---|---:|---:|")
        print("| recognized as the target | %s | ≥ 70 %% |"
              % pct(sum(r["recognized"] for r in results), n))
        print("| closer than the source to the mean of the real takes (Laban) | %s | ≥ 70 %% |"
              % pct(sum(r["lab"] for r in results), n))
        print("| closer than the source to the real takes (mean DTW) | %s | ≥ 60 %% |"
              % pct(sum(r["dtw"] for r in results), n))
        print("| action kept | %s | ≥ 95 %% |" % pct(sum(r["kept"] for r in results), n))
        print_fidelity(results)
        print("| target | " + " | ".join(STYLES2) + " |")
        print("|---|" + "---:|" * len(STYLES2))
        for t in STYLES2:
            if t == "normal":
                continue
            print("| %s | %s |" % (t, " | ".join(
                str(sum(1 for r in results if r["target"] == t and r["label"] == l))
                for l in STYLES2)))
        print()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "recognition.db"))
    ap.add_argument("--corpus", default="both", choices=["1", "2", "both"])
    ap.add_argument("--options", default="{}")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--protocol", default="both", choices=["takes", "content", "both"],
                    help="bandai-namco-2-dev: which protocol(s)")
    ap.add_argument("--recognizer", default="{}",
                    help='affect_train options of the recognizers, e.g. {"descriptors":"none"}')
    a = ap.parse_args()
    RECOGNIZER.update(json.loads(a.recognizer))
    if not os.path.isdir(ci.CORPORA):
        sys.exit("generation_eval.py: the corpora are not at %s (../shared)" % ci.CORPORA)
    con = ci.connect(a.db)
    ci.import_corpora(con)
    options = json.loads(a.options)
    print("affect_generate options: %s (plus source_label); recognizer: affect_train %s\n"
          % (json.dumps(options), json.dumps(RECOGNIZER)))
    if a.corpus in ("1", "both"):
        corpus1(con, options, a.quick)
    if a.corpus in ("2", "both"):
        corpus2(con, options, a.quick, a.protocol)
    for (t,) in con.execute("SELECT name FROM sqlite_schema WHERE type = 'table' AND "
                            "(name LIKE 'lab\\_%s%%' ESCAPE '\\' OR name LIKE 'tr\\_%s%%' "
                            "ESCAPE '\\')" % (RUN, RUN)).fetchall():
        if not t.endswith(("_data", "_info")):
            con.execute('DROP TABLE IF EXISTS "%s"' % t)
    con.commit()


if __name__ == "__main__":
    main()
