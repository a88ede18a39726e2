#!/usr/bin/env bash
# tests/fuzz/run.sh — build the libFuzzer targets with clang and run each for a bounded time.
#
# Usage: bash tests/fuzz/run.sh [seconds per target, default 20]
#
# Configures build-fuzz (CC=clang, -DAFFECT_FUZZ=ON -DAFFECT_WERROR=ON), builds the targets and
# runs `ctest -R '^fuzz/'`: each target fuzzes a fresh copy of tests/fuzz/corpus/<target> under
# build-fuzz/tests/fuzz/work/<target>/, where any crash-* reproducer is written. Exit status is
# non-zero if a target crashes, leaks, hits undefined behaviour or breaks an invariant.
set -euo pipefail

seconds="${1:-20}"
case "$seconds" in
    '' | *[!0-9]*) echo "usage: $0 [seconds per target]" >&2; exit 2 ;;
esac
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="$root/build-fuzz"

if ! command -v clang >/dev/null 2>&1; then
    echo "clang not found: apt-get install clang" >&2
    exit 1
fi

CC=clang cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DAFFECT_FUZZ=ON -DAFFECT_WERROR=ON -DAFFECT_FUZZ_SECONDS="$seconds" >/dev/null
cmake --build "$build" -j"$(nproc)" --target affect_fuzzers
cd "$build"
ctest -R '^fuzz/' --output-on-failure
