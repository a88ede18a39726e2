#!/usr/bin/env python3
"""fda_landmarks_time.py — CPU time of fda_train and fda_embed with linear and with landmark
alignment on the real corpora (bandai-namco-1's 44 emotion motions, bandai-namco-2-dev's 504),
default options otherwise; training: the least of 3 runs; embedding: the mean over the training
motions (decoding the motion and extracting its observations included).

Usage: OPENBLAS_NUM_THREADS=1 /usr/bin/python3 tests/bench/fda_landmarks_time.py [DB]
(DB default build/fda.db, filled by corpus_import.py when empty).
"""
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import corpus_import as ci  # noqa: E402

if not os.path.isdir(ci.CORPORA):
    print("fda_landmarks_time: skipped: %s is absent" % ci.CORPORA)
    sys.exit(0)
con = ci.connect(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ci.ROOT, "build", "fda.db"))
ci.import_corpora(con)
con.execute("CREATE TEMP TABLE c1 AS SELECT motion, style FROM motions WHERE "
            "source = 'bandai-namco-1' AND style IN (%s) AND content IN (%s)"
            % (",".join("'%s'" % e for e in ci.FOUR), ",".join("'%s'" % c for c in ci.TEN)))
con.execute("CREATE TEMP TABLE c2 AS SELECT motion, style FROM motions "
            "WHERE source = 'bandai-namco-2-dev'")
for t in ("c1", "c2"):
    for al in ("linear", "landmarks"):
        best = []
        for r in range(3):
            t0 = time.process_time()
            m = con.execute("SELECT fda_train(motion, style, ?) FROM %s" % t,
                            (json.dumps({"alignment": al}),)).fetchone()[0]
            best.append(time.process_time() - t0)
        t0 = time.process_time()
        k = con.execute("SELECT count(fda_embed(?, motion)) FROM %s" % t, (m,)).fetchone()[0]
        e = (time.process_time() - t0) / k
        print("%s %s: train %.3f s CPU, embed %.3f ms CPU per motion" % (t, al, min(best),
                                                                         1000 * e))
