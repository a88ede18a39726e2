#!/usr/bin/env bash
# blas_threads_test.sh — the same SQL gives the same bytes whatever OpenBLAS's thread count:
# runs one set of queries (affect_train with the defaults and with full-covariance mixtures on
# two threads of our own, hmm_train, hmm_loglik, fisher_score, affect_scores, laban_vector,
# affect_generate_explain by both methods) on fresh copies of one synthetic database under
# OPENBLAS_NUM_THREADS=1, 2 and 4, and compares the SHA3 hashes of the results; each run must
# also leave OpenBLAS's thread count as it found it (affect_build_info's blas_threads).
# Statement-based replication relies on it. OpenBLAS caps the variable at the number of
# cores, so on one core this passes trivially (it says so); tests/core/test_blas_threads.c
# sets the counts through OpenBLAS's API instead.
#   blas_threads_test.sh SQLITE3_SHELL MODULE SOURCE_DIR
set -euo pipefail
shell=$1 module=$2 src=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }

"$shell" base.db < "$src/sql/schema.sql"
OPENBLAS_NUM_THREADS=1 "$shell" base.db -cmd ".load $module" < "$src/sql/synth_corpus.sql"

cat > queries.sql <<'EOF'
.headers off
.mode list
CREATE TABLE tr AS SELECT * FROM motions WHERE source = 'synth' AND performer <> 'synth-5';
CREATE TABLE te AS SELECT * FROM motions WHERE source = 'synth' AND performer = 'synth-5';
CREATE TABLE models(kind TEXT PRIMARY KEY, model BLOB);
INSERT INTO models SELECT 'affect_train default', affect_train(motion, emotion) FROM tr;
INSERT INTO models SELECT 'affect_train full', affect_train(motion, emotion,
    '{"frame":"first","states":7,"mixtures":4,"covariance":"full","max_iter":2,"descriptors":"none",
      "mirror":false,"threads":2,"joints":["right_hand","left_hand","head","chest"]}') FROM tr;
INSERT INTO models SELECT 'hmm_train full', hmm_train(motion,
    '{"states":7,"mixtures":4,"covariance":"full","max_iter":5}') FROM tr WHERE emotion = 'sad';
SELECT kind, hex(sha3(model)) FROM models ORDER BY kind;
SELECT 'hmm_loglik', hex(sha3(group_concat(printf('%!.17g', hmm_loglik(model, te.motion)), ',')))
  FROM models, te WHERE kind = 'hmm_train full';
SELECT 'fisher_score ' || kind, hex(sha3(group_concat(hex(fisher_score(model, te.motion)), ',')))
  FROM models, te WHERE kind LIKE 'affect_train%' GROUP BY kind;
SELECT 'affect_scores ' || kind, hex(sha3(group_concat(affect_scores(model, te.motion), ',')))
  FROM models, te WHERE kind LIKE 'affect_train%' GROUP BY kind;
SELECT 'laban_vector', hex(sha3(group_concat(hex(laban_vector(motion)), ','))) FROM te;
CREATE VIRTUAL TABLE gen USING laban(content=tr, motion=motion, label=emotion);
SELECT 'affect_generate_explain ' || m.value,
       hex(sha3(affect_generate_explain('gen', te.motion, 'sad',
           json_object('method', m.value, 'source_label', te.emotion,
                       'components', json('["WeightAll","TimeAll","FlowAll","ShapeFlow"]')))))
  FROM te, json_each('["transfer","hmm_nn"]') AS m WHERE te.name = 'synth_wave_neutral_005';
SELECT 'viterbi logprob', printf('%!.17g', json_extract(affect_generate_explain('gen', te.motion,
           'sad', '{"method":"hmm_nn","components":["WeightAll","TimeAll","FlowAll","ShapeFlow"]}'),
           '$.viterbi.logprob'))
  FROM te WHERE te.name = 'synth_wave_neutral_005';
EOF

count="SELECT 'blas_threads', json_extract(affect_build_info(), '\$.blas_threads');"
most=1
for t in 1 2 4; do
    cp base.db "run$t.db"
    before=$(OPENBLAS_NUM_THREADS=$t "$shell" "run$t.db" -cmd ".load $module" "$count")
    # the queries, then the thread count again in the same connection
    OPENBLAS_NUM_THREADS=$t "$shell" -bail "run$t.db" -cmd ".load $module" \
        < <(cat queries.sql; echo "$count") > "out$t.txt" ||
        fail "the queries failed under OPENBLAS_NUM_THREADS=$t: $(tail -3 "out$t.txt")"
    after=$(grep '^blas_threads|' "out$t.txt")
    [ "$after" = "$before" ] ||
        fail "OPENBLAS_NUM_THREADS=$t: OpenBLAS had ${before#*|} threads before our calls, ${after#*|} after"
    [ "${before#*|}" -gt "$most" ] && most=${before#*|}
    sed -i '/^blas_threads|/d' "out$t.txt"
    lines=$(grep -c . "out$t.txt")
    [ "$lines" = 12 ] || fail "OPENBLAS_NUM_THREADS=$t: $lines result lines, expected 12"
done
for t in 2 4; do
    diff out1.txt "out$t.txt" > /dev/null ||
        fail "results differ between OPENBLAS_NUM_THREADS=1 and $t:
$(diff out1.txt "out$t.txt")"
done
[ "$most" -gt 1 ] ||
    echo "NOTE: OpenBLAS had one thread in every run (one core?): no thread counts were compared"
echo "blas threads: 1 passed, 0 failed (OpenBLAS threads 1 to $most give the same bytes)"
