#!/usr/bin/env python3
"""fda_landmarks_eval.py — how well fda_train's automatic landmarks ("alignment":"landmarks")
work on the real corpora: the template found, and how much of the functions' variance the
registration removes, per content (motions of one action in every style, where the timing of
one movement differs between styles and takes) and over the whole corpus.

Usage (from the repository root, after a build of build/affect.so):
    OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/fda_landmarks_eval.py [--db build/fda.db]
        [--options '{}']
AFFECT_EXT overrides the extension's path. Python's standard library and sqlite3 only.

For each corpus (bandai-namco-1's 44 motions of 4 emotions × 10 contents; bandai-namco-2-dev's
504 motions of 7 styles × 6 contents) and each content, an FPCA model (fda_train, default
observations and basis) is fitted with linear and with landmark alignment; the table gives the
template's landmarks (count, rests / peaks) and the total variance of the functions (fda_info's
total_variance) with landmarks over that without: below 1 means the warps made the motions'
curves more alike (registration working), about 1 that it changed nothing, above 1 that it
made them less alike (landmarks matched to the wrong partners).
"""
import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from corpus_import import CORPORA, FOUR, ROOT, TEN, connect, import_corpora  # noqa: E402


def info(con, table, where, opts):
    row = con.execute("SELECT fda_info(fda_train(motion, style, ?)) FROM %s WHERE %s"
                      % (table, where), (json.dumps(opts),)).fetchone()
    return json.loads(row[0])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--db", default=os.path.join(ROOT, "build", "fda.db"))
    ap.add_argument("--options", default="{}")
    a = ap.parse_args()
    if not os.path.isdir(CORPORA):
        print("fda_landmarks_eval: skipped: %s is absent" % CORPORA)
        return 0
    con = connect(a.db)
    import_corpora(con)
    con.execute("CREATE TEMP TABLE c1 AS SELECT id, content, style, motion FROM motions WHERE "
                "source = 'bandai-namco-1' AND style IN (%s) AND content IN (%s) ORDER BY id"
                % (",".join("'%s'" % e for e in FOUR), ",".join("'%s'" % c for c in TEN)))
    con.execute("CREATE TEMP TABLE c2 AS SELECT id, content, style, motion FROM motions WHERE "
                "source = 'bandai-namco-2-dev' ORDER BY id")
    base = dict(json.loads(a.options), method="fpca")
    for source, table in (("bandai-namco-1", "c1"), ("bandai-namco-2-dev", "c2")):
        print("\n### %s\n" % source)
        print("| content | motions | template: landmarks (rests / peaks) | at times | "
              "variance ratio (landmarks / linear) |")
        print("|---|---:|---|---|---:|")
        contents = [r[0] for r in con.execute("SELECT DISTINCT content FROM %s ORDER BY content"
                                              % table)]
        ratios = []
        for c in contents + [None]:
            where = "content = '%s'" % c if c else "1"
            n = con.execute("SELECT count(*) FROM %s WHERE %s" % (table, where)).fetchone()[0]
            lin = info(con, table, where, base)
            lm = info(con, table, where, dict(base, alignment="landmarks"))
            marks = lm["landmarks"]
            rests = sum(1 for m in marks if m["type"] == "rest")
            ratio = lm["total_variance"] / lin["total_variance"]
            if c:
                ratios.append(ratio)
            print("| %s | %d | %d (%d / %d) | %s | %.2f |" % (
                c or "**all contents**", n, len(marks), rests, len(marks) - rests,
                " ".join("%.2f" % m["t"] for m in marks), ratio))
            sys.stdout.flush()
        ratios.sort()
        print("\nper-content ratio: median %.2f, range %.2f .. %.2f, below 1 for %d of %d"
              % (ratios[len(ratios) // 2], ratios[0], ratios[-1],
                 sum(r < 1 for r in ratios), len(ratios)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
