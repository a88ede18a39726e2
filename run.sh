#!/usr/bin/env bash
# run.sh — the commands of the README.
#
#   ./run.sh demo [BVH_DIR]   install what is missing, build, and run the demo: demo.db with the
#                             synthetic corpus (and the real one when ../shared/corpora/
#                             bandai-namco-1/data or BVH_DIR exists), a summary, and demo.html
#   ./run.sh install          install what is missing, build, and `cmake --install build` (README,
#                             "Install": /usr/local, so that `.load affect` works from anywhere)
#   ./run.sh test             install what is missing, build, and run the whole test suite:
#                             unit, SQL and out-of-memory tests, examples and scripts, the real
#                             corpus (skipped when absent), Blender importing our BVH files and
#                             headless Chromium rendering demo.html (blender and chromium are
#                             installed for this command only), sqlite-vec's vec0 finding the
#                             laban index's neighbours (npm package, under build/npm), a
#                             sanitizer build, and the fuzzers
#
# Works on a fresh Debian 12 machine as root (or with sudo). Set AFFECT_FUZZ_SECONDS to change
# the time each fuzz target runs (default 20). OpenBLAS runs single-threaded unless
# OPENBLAS_NUM_THREADS is set: at this project's matrix sizes its threads cost more than they
# give (the corpus evaluation runs 2-3 times slower with them on this 2-core machine).
set -euo pipefail
export OPENBLAS_NUM_THREADS="${OPENBLAS_NUM_THREADS:-1}"
cd "$(dirname "$0")"
ROOT=$(pwd)

PACKAGES=(build-essential cmake pkg-config sqlite3 libsqlite3-dev libopenblas-dev liblapacke-dev
          libsvm-dev libcmocka-dev clang clang-format python3)
# The Python package (python/) and its tests: NumPy, and an offline venv + pip install.
PACKAGES+=(python3-numpy python3-venv python3-setuptools python3-wheel)
# Only for ./run.sh test: the real clients of tests/client/blender_test.sh (headless Blender
# imports our BVH files) and tests/client/chromium_test.sh (headless Chromium renders demo.html).
# If one cannot be installed the tests go on and its test is skipped.
TEST_PACKAGES=(blender chromium)
# Only for ./run.sh test: sqlite-vec (the npm package sqlite-vec-linux-x64, its vec0.so, under
# build/npm), the real client of tests/client/sqlite_vec_test.sh (vec0 over laban_zvector
# finds the laban index's neighbours). If it cannot be installed that test is skipped.
install_sqlite_vec() {
    [ -f build/npm/node_modules/sqlite-vec-linux-x64/vec0.so ] && return 0
    command -v npm >/dev/null 2>&1 || install_missing npm || return 1 # npm may come with nodejs
    mkdir -p build/npm
    npm install --silent --no-audit --no-fund --prefix build/npm sqlite-vec-linux-x64 >/dev/null
}

# install_missing [PACKAGE...]: installs those of the packages (default: PACKAGES) not installed.
install_missing() {
    local missing=() wanted=("$@")
    [ ${#wanted[@]} -eq 0 ] && wanted=("${PACKAGES[@]}")
    for p in "${wanted[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    echo "== installing: ${missing[*]}"
    local sudo=""
    [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}

build() {
    echo "== building (build/)"
    cmake -S . -B build -DCMAKE_BUILD_TYPE=RelWithDebInfo -DAFFECT_WERROR=ON >/dev/null
    cmake --build build -j"$(nproc)" >/dev/null
}

demo() {
    local dir="${1:-$ROOT/../shared/corpora/bandai-namco-1/data}"
    echo "== building demo.db"
    bash sql/build_demo.sh sqlite3 "$ROOT/build/affect" "$ROOT" "$dir"
    echo "== open demo.html in a browser; query demo.db with: sqlite3 demo.db -cmd '.load ./build/affect'"
}

# Runs a command, echoing its output, and adds the counts of ctest's closing line to the totals.
passed=0 failed=0
counted() {
    local log rc=0 line
    log=$(mktemp)
    "$@" 2>&1 | tee "$log" || rc=$?
    line=$(grep -E '[0-9]+% tests passed, [0-9]+ tests? failed out of [0-9]+' "$log" | tail -1 || true)
    rm -f "$log"
    if [ -z "$line" ]; then
        return 1
    fi
    local total bad
    total=$(echo "$line" | sed -E 's/.* out of ([0-9]+).*/\1/')
    bad=$(echo "$line" | sed -E 's/.* ([0-9]+) tests? failed.*/\1/')
    passed=$((passed + total - bad))
    failed=$((failed + bad))
    return "$rc"
}

tests() {
    local status=0
    echo "== tests (build/)"
    counted ctest --test-dir build --output-on-failure -j"$(nproc)" -E '^fuzz/' || status=1
    echo "== sanitizer build (build-asan/): unit and SQL tests under ASan + UBSan"
    cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DAFFECT_WERROR=ON -DAFFECT_SANITIZE=ON >/dev/null
    cmake --build build-asan -j"$(nproc)" >/dev/null
    ASAN_OPTIONS=detect_leaks=1 counted ctest --test-dir build-asan --output-on-failure -j"$(nproc)" \
        -E '^fuzz/|^examples/|^sql/scripts|^sql/readme|^sql/blas-threads|^client/' || status=1
    echo "== fuzzers (build-fuzz/, clang + libFuzzer)"
    counted bash tests/fuzz/run.sh "${AFFECT_FUZZ_SECONDS:-20}" || status=1
    echo
    echo "all suites: $passed passed, $failed failed"
    return "$status"
}

case "${1:-}" in
    demo) install_missing; build; shift; demo "$@" ;;
    install) install_missing; build; cmake --install build ;;
    test)
        install_missing
        for p in "${TEST_PACKAGES[@]}"; do
            install_missing "$p" || echo "== could not install $p: client/$p will be skipped"
        done
        install_sqlite_vec ||
            echo "== could not install sqlite-vec-linux-x64 (npm): client/sqlite-vec will be skipped"
        build; tests ;;
    *) echo "usage: ./run.sh demo [BVH_DIR] | ./run.sh test | ./run.sh install" >&2; exit 2 ;;
esac
