#!/usr/bin/env bash
# scripts_test.sh — runs the sql/ scripts in the sqlite3 shell the way users do (schema,
# synthetic corpus, corpus import, demo page) and checks what they produce, so the scripts
# and the README's instructions cannot drift from the code.
#   scripts_test.sh SQLITE3_SHELL MODULE SOURCE_DIR [CORPUS_DIR]
set -euo pipefail
shell=$1 module=$2 src=$3 corpus=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }
q() { "$shell" demo.db -cmd ".load $module" "$@"; }

"$shell" demo.db < "$src/sql/schema.sql"
q < "$src/sql/synth_corpus.sql"
[ "$(q 'SELECT count(*) FROM motions WHERE source = "synth"')" = 80 ] || fail "synthetic corpus is not 80 motions"
[ "$(q 'SELECT count(DISTINCT content) || "/" || count(DISTINCT emotion) FROM motions')" = 4/4 ] ||
    fail "synthetic corpus labels"

# a folder with one small BVH whose name follows the corpus pattern, and one that does not
mkdir bvh
printf 'HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n}\nMOTION\nFrames: 2\nFrame Time: 0.5\n0 1 0\n0 2 0\n' \
    > bvh/dataset-1_walk-back_not-confident_002.bvh
cp bvh/dataset-1_walk-back_not-confident_002.bvh bvh/other.bvh
q -cmd ".parameter set :dir bvh" < "$src/sql/import_bvh.sql"
[ "$(q "SELECT content || '|' || emotion || '|' || frames || '|' || fps FROM motions WHERE name = 'dataset-1_walk-back_not-confident_002'")" = "walk-back|not-confident|2|2.0" ] ||
    fail "labels parsed from the file name"
[ "$(q "SELECT ifnull(content, 'NULL') || '|' || ifnull(emotion, 'NULL') FROM motions WHERE name = 'other'")" = "NULL|NULL" ] ||
    fail "a file outside the naming pattern keeps NULL labels"

# a folder with two good files and two bad ones (truncated, garbage), in a database of its own:
# sql/import_bvh.sql and examples/import_folder.py import the good ones, skip the bad ones and
# record each with its file, line and message
mkdir mixed
q "SELECT writefile('mixed/dataset-1_wave_sad_001.bvh', motion_to_bvh(motion_synth('wave', 'sad', 1)))" >/dev/null
cp bvh/other.bvh mixed/other.bvh
head -n -5 mixed/dataset-1_wave_sad_001.bvh > mixed/truncated.bvh
truncated_line=$(( $(wc -l < mixed/truncated.bvh) + 1 ))  # where the missing frames were due
printf 'GIF89a\001\000\377 x\n' > mixed/garbage.bvh
qi() { "$shell" "$1" -cmd ".load $module" "${@:2}"; }
errors="SELECT file || '|' || line || '|' || message FROM import_errors ORDER BY file"
"$shell" shell.db < "$src/sql/schema.sql"
out=$(qi shell.db -cmd ".parameter set :dir mixed" -cmd ".parameter set :unit cm" < "$src/sql/import_bvh.sql") ||
    fail "sql/import_bvh.sql stopped at a bad file: $out"
echo "$out" | grep -qx "imported 2 of 4 BVH files from mixed; skipped 2 (recorded in import_errors)" ||
    fail "sql/import_bvh.sql summary: $out"
echo "$out" | grep -qx 'skipped: motion_from_bvh: expected HIERARCHY, found GIF89a\\x01\\x00\\xff (mixed/garbage.bvh, line 1)' ||
    fail "sql/import_bvh.sql lists the skipped files: $out"
[ "$(qi shell.db "SELECT group_concat(name || ':' || frames || ':' || json_extract(motion_info(motion), '\$.unit'), ' ') FROM (SELECT * FROM motions ORDER BY name)")" = \
  "dataset-1_wave_sad_001:$(qi shell.db "SELECT motion_frames(motion_from_bvh(readfile('mixed/dataset-1_wave_sad_001.bvh')))"):cm other:2:cm" ] ||
    fail "sql/import_bvh.sql imports the two good files"
got=$(qi shell.db "$errors")
expected="mixed/garbage.bvh|1|motion_from_bvh: expected HIERARCHY, found GIF89a\\x01\\x00\\xff (mixed/garbage.bvh, line 1)"
[ "$(echo "$got" | head -1)" = "$expected" ] || fail "import_errors: the garbage file: $got"
echo "$got" | tail -1 | grep -qx "mixed/truncated.bvh|$truncated_line|motion_from_bvh: expected [0-9]* frames, found [0-9]* (mixed/truncated.bvh, line $truncated_line)" ||
    fail "import_errors: the truncated file (line $truncated_line): $got"
[ "$(echo "$got" | wc -l)" = 2 ] || fail "import_errors has $(echo "$got" | wc -l) rows"
[ "$(qi shell.db "SELECT count(*) FROM import_errors WHERE at LIKE '____-__-__T__:__:__Z'")" = 2 ] ||
    fail "import_errors: the time of each error"
if /usr/bin/python3 -c 'import sqlite3; sqlite3.connect(":memory:").enable_load_extension' 2>/dev/null; then
    out=$(/usr/bin/python3 "$src/examples/import_folder.py" mixed py.db --unit cm --module "$module") ||
        fail "examples/import_folder.py: $out"
    echo "$out" | grep -qx '\[1/4\] mixed/dataset-1_wave_sad_001.bvh: [0-9]* frames, [0-9]* joints' ||
        fail "examples/import_folder.py progress: $out"
    echo "$out" | grep -qx '\[2/4\] mixed/garbage.bvh: skipped: motion_from_bvh: expected HIERARCHY, .* (mixed/garbage.bvh, line 1)' ||
        fail "examples/import_folder.py progress of a skipped file: $out"
    echo "$out" | tail -1 | grep -qx "imported 2 of 4 BVH files from mixed; skipped 2 (recorded in import_errors)" ||
        fail "examples/import_folder.py summary: $out"
    [ "$(qi py.db "$errors")" = "$got" ] || fail "examples/import_folder.py records other errors: $(qi py.db "$errors")"
    same="SELECT group_concat(name || quote(content) || quote(emotion) || fps || frames || hex(motion) || source) FROM (SELECT * FROM motions ORDER BY name)"
    [ "$(qi py.db "$same")" = "$(qi shell.db "$same")" ] || fail "examples/import_folder.py imports other rows"
else
    echo "SKIP: /usr/bin/python3 cannot load extensions: examples/import_folder.py not run"
fi
# the truncated file mended: re-running imports it and forgets its error
cp mixed/dataset-1_wave_sad_001.bvh mixed/truncated.bvh
out=$(qi shell.db -cmd ".parameter set :dir mixed" < "$src/sql/import_bvh.sql")
echo "$out" | grep -qx "imported 3 of 4 BVH files from mixed; skipped 1 (recorded in import_errors)" ||
    fail "sql/import_bvh.sql after mending a file: $out"
[ "$(qi shell.db "SELECT group_concat(file) FROM import_errors")" = mixed/garbage.bvh ] ||
    fail "a file that imports loses its import_errors row"

if [ -n "$corpus" ] && [ -d "$corpus" ]; then
    q -cmd ".parameter set :dir '$corpus'" -cmd ".parameter set :unit cm" \
      -cmd ".parameter set :source bandai-namco-1" < "$src/sql/import_bvh.sql"
    got=$(q "SELECT count(*) || '|' || sum(frames) || '|' || count(DISTINCT content) || '|' || count(DISTINCT emotion) FROM motions WHERE source = 'bandai-namco-1'")
    [ "$got" = "174|31914|16|15" ] || fail "real corpus import: $got"
    [ "$(q "SELECT count(*) FROM motions WHERE source = 'bandai-namco-1' AND emotion IN ('angry','happy','sad','normal') AND content IN ('walk','run','dash','walk-back','walk-left','walk-right','bow','bye','byebye','guide')")" = 44 ] ||
        fail "the four emotions over the ten shared contents"
else
    echo "SKIP: the real corpus is absent: its import is not checked"
fi

# the trigger template keeps an index over motions current
q "CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion)"
q < "$src/sql/laban_triggers.sql"
before=$(q "SELECT count(*) FROM motion_laban")
q "INSERT INTO motions(name, content, emotion, motion, source) VALUES('extra', 'wave', 'sad', motion_synth('wave', 'sad', 99), 'synth')"
q "UPDATE motions SET emotion = 'angry' WHERE name = 'extra'"
[ "$(q "SELECT count(*) || '|' || label FROM motion_laban WHERE rowid = (SELECT id FROM motions WHERE name = 'extra')")" = "1|angry" ] ||
    fail "the triggers of sql/laban_triggers.sql keep the index current"
q "DELETE FROM motions WHERE name = 'extra'"
[ "$(q "SELECT count(*) FROM motion_laban")" = "$before" ] || fail "a deleted row leaves the index"
q "INSERT INTO motion_laban(motion_laban) VALUES('check')" || fail "the index is stale after trigger updates"
q "DROP TABLE motion_laban; DROP TRIGGER motions_laban_insert; DROP TRIGGER motions_laban_update; DROP TRIGGER motions_laban_delete"

q < "$src/sql/demo.sql" > summary.txt
grep -q "what demo.db holds" summary.txt || fail "demo summary"
grep -q "wrote demo.html" summary.txt || fail "demo page"
[ "$(grep -o '<svg' demo.html | wc -l)" -ge 16 ] || fail "demo.html has too few SVG previews"
grep -q '</html>' demo.html || fail "demo.html is incomplete"
grep -q "Laban nearest neighbours" summary.txt || fail "demo: nearest neighbours"
grep -q "Laban Weight vs Time" demo.html || fail "demo: the Weight vs Time figure"
[ "$(grep -o '<animate attributeName="d"' demo.html | wc -l)" -ge 10 ] || fail "demo: animated figures"
grep -q 'caption" text-anchor="middle" fill="#333">real · ' demo.html || fail "demo: source / generated / real animated side by side"
grep -q 'class="column-label"' demo.html || fail "demo: the salience heat map with joint names"
grep -q '>state 5</text>' demo.html || fail "demo: HMM postures labelled by state"
grep -q 'class="facing"' demo.html || fail "demo: the top view of a walk"
grep -q "generated (strengths 0.5, 1, 1.5) vs source vs the real recording" summary.txt ||
    fail "demo: generation summary"
[ "$(q "SELECT count(*) FROM generated WHERE motion_frames(motion) > 0")" = 9 ] ||
    fail "demo: nine generated motions (three targets at three strengths)"
[ "$(q "SELECT count(*) FROM generated WHERE json_extract(motion_info(motion), '\$.bone_variation') <= 1e-4")" = 9 ] ||
    fail "demo: every generated motion is rigid"
grep -q "Generation: the source, the generated motion at three strengths, the real recording" demo.html ||
    fail "demo: generation film strips"
if [ -n "$corpus" ] && [ -d "$corpus" ]; then
    q < "$src/sql/laban_corpus.sql" > laban.md
    [ "$(grep -c '^| ' laban.md)" = 13 ] || fail "sql/laban_corpus.sql: the table has $(grep -c '^| ' laban.md) lines"
    grep -q "angry > sad on WeightAll in 11 of 11 contents" laban.md || fail "sql/laban_corpus.sql: ordering line"
    # the generation evaluation's smoke run (two contents), with Debian's Python
    if /usr/bin/python3 -c 'import sqlite3; sqlite3.connect(":memory:").enable_load_extension' 2>/dev/null; then
        OPENBLAS_NUM_THREADS=1 AFFECT_MODULE="$module" /usr/bin/python3 "$src/sql/generate_eval.py" demo.db --quick > gen.md ||
            fail "sql/generate_eval.py --quick"
        grep -q '^| steps, copies 0 | ' gen.md || fail "sql/generate_eval.py: the results table"
        grep -q '^| sad | ' gen.md || fail "sql/generate_eval.py: the Laban shift table"
    else
        echo "SKIP: /usr/bin/python3 cannot load extensions: sql/generate_eval.py not run"
    fi
fi
echo "scripts: 1 passed, 0 failed"
