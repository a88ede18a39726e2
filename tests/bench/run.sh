#!/usr/bin/env bash
# tests/bench/run.sh — build the benchmarks in Release and run them on one core.
#
# Usage: bash tests/bench/run.sh [extra arguments for the corpus benchmarks, bench_import,
#                                   bench_laban, bench_skeleton, bench_affect and
#                                   bench_generate, e.g. a corpus directory]
#
# Configures build-bench (-DCMAKE_BUILD_TYPE=Release -DAFFECT_WERROR=ON; AFFECT_BENCH_BUILD names
# another build directory), builds the bench targets, prints the machine (CPU, memory, OS,
# compiler, flags) and runs each benchmark pinned to CPU 0 with taskset when it is available:
# bench_import, bench_laban and bench_skeleton (corpus; bench_skeleton reads bandai-namco-1
# and bandai-namco-2-dev unless given directories, about 2 minutes), then bench_knn (the
# built module, no arguments), then bench_hmm with OPENBLAS_NUM_THREADS=1, which writes its
# data and models to $build/tests/bench/hmm-data, and its pomegranate peer
# tests/bench/hmm_peer.py on those files, when /usr/bin/python3 can import pomegranate
# (otherwise it says the peer was skipped), then
# bench_affect (corpus; the recognizer and its 10-fold cross-validation, a few minutes) with
# OPENBLAS_NUM_THREADS=1, then its cross-validation again with two threads, unpinned, then
# bench_generate (corpus and the built module; generation latency by stage and the RMLR fit,
# about a minute) with OPENBLAS_NUM_THREADS=1, then its RMLR fit again with {"threads":2},
# unpinned (--rmlr-only --threads 2; it says so when laban_salient has no threads option),
# then bench_rmlr (affect_rmlr_cv on the Laban vectors of bandai-namco-1's 44 emotion motions
# and bandai-namco-2-dev's 504, pinned; about 3 minutes), then bench_interrupt (the built
# module; the interrupt latency of every long call, unpinned, about a minute).
# AFFECT_BENCH_ONLY="bench_hmm ..." runs only the benchmarks it names (default: all).
# Record the output in docs/BENCHMARKS.md.
set -euo pipefail

root="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
build="${AFFECT_BENCH_BUILD:-$root/build-bench}"

cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DAFFECT_WERROR=ON >/dev/null
cmake --build "$build" -j"$(nproc)" --target affect_benches

pin=()
if command -v taskset >/dev/null 2>&1 && taskset -c 0 true 2>/dev/null; then
    pin=(taskset -c 0)
fi

cc="$(sed -n 's/^CMAKE_C_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt")"
echo "== machine"
echo "cpu:      $(lscpu 2>/dev/null | sed -n 's/^Model name:[[:space:]]*//p' | head -1)" \
     "($(nproc --all) logical CPUs)"
echo "memory:   $(free -h 2>/dev/null | awk '/^Mem:/ {print $2}') total"
echo "os:       $( (. /etc/os-release 2>/dev/null && echo "$PRETTY_NAME") || uname -s)," \
     "kernel $(uname -r)"
echo "compiler: $("$cc" --version | head -1)"
echo "flags:    Release: $(sed -n 's/^CMAKE_C_FLAGS_RELEASE:[A-Z]*=//p' "$build/CMakeCache.txt")" \
     "-std=c11 -ffp-contract=off -fno-fast-math"
echo "pinned:   ${pin[*]:-no (taskset not available)}"
echo

only="${AFFECT_BENCH_ONLY:-}"
want() { [[ -z "$only" || " $only " == *" $1 "* ]]; }

for bench in bench_import bench_laban bench_skeleton; do
    want "$bench" || continue
    echo "== $bench"
    "${pin[@]}" "$build/tests/bench/$bench" "$@"
    echo
done

for bench in bench_knn; do
    want "$bench" || continue
    echo "== $bench"
    "${pin[@]}" "$build/tests/bench/$bench"
    echo
done

# The HMM engine and its peer, both with single-threaded OpenBLAS, on the same data.
if want bench_hmm; then
    hmm_data="$build/tests/bench/hmm-data"
    mkdir -p "$hmm_data"
    echo "== bench_hmm"
    OPENBLAS_NUM_THREADS=1 "${pin[@]}" "$build/tests/bench/bench_hmm" --out "$hmm_data"
    echo
    echo "== hmm_peer (pomegranate)"
    if /usr/bin/python3 -c "import pomegranate" 2>/dev/null; then
        OPENBLAS_NUM_THREADS=1 "${pin[@]}" /usr/bin/python3 "$root/tests/bench/hmm_peer.py" \
            "$hmm_data/hmm-m15.bin" "$hmm_data/hmm-m63.bin"
    else
        echo "hmm_peer: skipped: /usr/bin/python3 cannot import pomegranate" \
             "(apt-get install python3-pomegranate)"
    fi
    echo
fi

# The recognizer on the corpus, single-threaded OpenBLAS like the HMM engine's benchmark.
if want bench_affect; then
    echo "== bench_affect"
    OPENBLAS_NUM_THREADS=1 "${pin[@]}" "$build/tests/bench/bench_affect" "$@"
    echo
    echo "== bench_affect --cv-only --threads 2 (unpinned: both cores)"
    OPENBLAS_NUM_THREADS=1 "$build/tests/bench/bench_affect" --cv-only --threads 2 "$@"
    echo
fi

# Generation on the corpus (loads the built module), single-threaded OpenBLAS.
if want bench_generate; then
    echo "== bench_generate"
    OPENBLAS_NUM_THREADS=1 "${pin[@]}" "$build/tests/bench/bench_generate" "$@"
    echo
    echo "== bench_generate --rmlr-only --threads 2 (unpinned: both cores)"
    OPENBLAS_NUM_THREADS=1 "$build/tests/bench/bench_generate" --rmlr-only --threads 2 "$@"
    echo
fi

# The cross-validated RMLR fit (laban_salient's) on both corpora's Laban vectors, one core.
if want bench_rmlr; then
    echo "== bench_rmlr"
    "${pin[@]}" "$build/tests/bench/bench_rmlr"
    echo
fi

# Emotion strength (issue 16): ranker, regression, training and affect_strength, one core.
if want bench_strength; then
    echo "== bench_strength"
    OPENBLAS_NUM_THREADS=1 "${pin[@]}" "$build/tests/bench/bench_strength"
    echo
fi

# The functional analysis (fda_train) on the 44 emotion motions, single-threaded OpenBLAS, one
# core: the defaults' observations, then the evaluation's (7 joints with velocities).
if want bench_fda; then
    echo "== bench_fda"
    OPENBLAS_NUM_THREADS=1 "${pin[@]}" "$build/tests/bench/bench_fda"
    OPENBLAS_NUM_THREADS=1 "${pin[@]}" "$build/tests/bench/bench_fda" --joints thesis
    echo
fi

# How fast long calls stop when interrupted (the built module), single-threaded OpenBLAS,
# unpinned (some calls run 2 threads, and the interrupting thread needs a core too).
if want bench_interrupt; then
    echo "== bench_interrupt (unpinned)"
    OPENBLAS_NUM_THREADS=1 "$build/tests/bench/bench_interrupt"
    echo
fi
