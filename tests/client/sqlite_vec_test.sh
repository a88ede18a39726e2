#!/usr/bin/env bash
# sqlite_vec_test.sh — a real client of laban_zvector: sqlite-vec's vec0 table, filled with the
# vectors standardized by a laban index, must return the index's own 5 nearest neighbours.
#   sqlite_vec_test.sh BUILD_DIR SOURCE_DIR [SHARED_DIR]
#
# sqlite-vec comes from the npm package sqlite-vec-linux-x64 (its vec0.so), installed under
# BUILD_DIR/npm (run.sh test installs it; this script tries `npm install` itself when it is
# missing). Exits 77 (CTest's skip) with a message when it cannot be installed.
# Corpora, each in a database built by the sqlite3 shell with sql/schema.sql, and a laban index
# `motion_laban` (content = motions, label = emotion):
#   synthetic      sql/synth_corpus.sql (80 motions: 4 actions x 4 emotions x 5 performers)
#   bandai-namco-1 SHARED_DIR/corpora/bandai-namco-1/data through sql/import_bvh.sql (skipped
#                  with a message when absent)
# Then tests/client/sqlite_vec_check.py (Debian's /usr/bin/python3, whose sqlite3 module loads
# extensions) compares the two for every motion: see its header.
set -uo pipefail
build=$1 src=$2 shared=${3:-}
here=$(cd "$(dirname "$0")" && pwd)
npm_dir=$build/npm
vec0=$npm_dir/node_modules/sqlite-vec-linux-x64/vec0.so

if [ ! -f "$vec0" ]; then
    if command -v npm >/dev/null 2>&1; then
        echo "== installing sqlite-vec-linux-x64 into $npm_dir"
        mkdir -p "$npm_dir"
        timeout 300 npm install --silent --no-audit --no-fund --prefix "$npm_dir" \
            sqlite-vec-linux-x64 >/dev/null 2>&1 || true
    fi
    if [ ! -f "$vec0" ]; then
        echo "SKIP: sqlite-vec is not installed and could not be installed" \
             "(npm install --prefix $npm_dir sqlite-vec-linux-x64)"
        exit 77
    fi
fi
python=/usr/bin/python3
[ -x "$python" ] || python=$(command -v python3) || { echo "FAIL: no python3"; exit 1; }
shell=$(command -v sqlite3) || { echo "FAIL: no sqlite3 shell"; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
q() { local db=$1; shift; "$shell" -bail -cmd ".load $build/affect" "$db" "$@"; }
index_sql="CREATE VIRTUAL TABLE motion_laban USING laban(content=motions, motion=motion, label=emotion);"

"$shell" "$work/synth.db" < "$src/sql/schema.sql" || exit 1
q "$work/synth.db" < "$src/sql/synth_corpus.sql" >/dev/null || exit 1
q "$work/synth.db" "$index_sql" || exit 1
dbs=("$work/synth.db" motion_laban)

corpus=${shared:+$shared/corpora/bandai-namco-1/data}
if [ -n "$corpus" ] && [ -d "$corpus" ]; then
    "$shell" "$work/bandai.db" < "$src/sql/schema.sql" || exit 1
    q "$work/bandai.db" -cmd ".parameter set :dir '$corpus'" -cmd ".parameter set :unit cm" \
        < "$src/sql/import_bvh.sql" >/dev/null || exit 1
    q "$work/bandai.db" "$index_sql" || exit 1
    dbs+=("$work/bandai.db" motion_laban)
else
    echo "SKIP: no corpus at ${corpus:-SHARED_DIR/corpora/bandai-namco-1/data}:" \
         "only the synthetic corpus is checked"
fi
OPENBLAS_NUM_THREADS=${OPENBLAS_NUM_THREADS:-1} \
    "$python" "$here/sqlite_vec_check.py" "$build/affect.so" "$vec0" "${dbs[@]}"
