#!/usr/bin/env bash
# build_demo.sh — builds demo.db and demo.html in the current directory, as `./run.sh demo`
# does (run.sh calls it; so does the README's test, tests/sql/readme_test.py):
#   build_demo.sh SQLITE3_SHELL MODULE SOURCE_DIR [BVH_DIR]
# schema, the synthetic corpus (80 motions), the BVH files of BVH_DIR when it exists (in cm,
# the source named after BVH_DIR's parent folder: bandai-namco-1 for the shared corpus), then
# sql/demo.sql, which prints the summary and writes demo.html.
set -euo pipefail
shell=$1 module=$2 src=$3 dir=${4:-}
q=("$shell" demo.db -cmd ".load $module")
rm -f demo.db demo.html
"$shell" demo.db < "$src/sql/schema.sql"
"${q[@]}" < "$src/sql/synth_corpus.sql"
if [ -n "$dir" ] && [ -d "$dir" ]; then
    echo "== importing the BVH files of $dir"
    "${q[@]}" -cmd ".parameter set :dir '$dir'" -cmd ".parameter set :unit cm" \
        -cmd ".parameter set :source '$(basename "$(dirname "$dir")")'" < "$src/sql/import_bvh.sql"
else
    echo "== no BVH folder at ${dir:-(none given)}: the demo uses the synthetic corpus only"
fi
"${q[@]}" < "$src/sql/demo.sql"
