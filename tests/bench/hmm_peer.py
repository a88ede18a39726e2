#!/usr/bin/env python3
"""hmm_peer.py — the peer of bench_hmm: pomegranate (Debian's python3-pomegranate, 0.14.8) timed
on exactly the data and models bench_hmm measured, and the two compared.

Usage:
    /usr/bin/python3 tests/bench/hmm_peer.py FILE...      # the hmm-m<m>.bin files of bench_hmm
    bash tests/bench/run.sh                               # runs bench_hmm --out DIR, then this

A benchmark peer, not a dependency: run.sh runs it only when /usr/bin/python3 can import
pomegranate. It forces OPENBLAS_NUM_THREADS=1 (and the other BLAS thread variables) before numpy
is imported and, when threadpoolctl is installed, also limits every BLAS pool to one thread and
prints them: pomegranate's Gaussians call scipy's BLAS, which on Debian is the same OpenBLAS
the C engine links.

For each file (format: see the header of bench_hmm.c):
  * the generating model is rebuilt in pomegranate: a HiddenMarkovModel whose states are
    GeneralMixtureModels of MultivariateGaussianDistributions with our weights, means and full
    covariances, an edge from the start state to each state with π > 0 (π = the first state)
    and our transition matrix, baked with merge='None' (no edge is added or removed);
  * scoring: model.log_probability(seq) over all sequences, one pass = every sequence once;
    warm-up pass, then 5 runs of N passes (N so that a run takes about a second), median —
    as bench_hmm. Before timing, the per-sequence log-likelihoods are compared with ours;
  * Baum–Welch: the initial model bench_hmm's affect_hmm_train started from (its k-means
    initialisation) is rebuilt and trained with model.fit(sequences, algorithm='baum-welch',
    max_iterations=1, stop_threshold=-inf, n_jobs=1). In 0.14.8 that is exactly two E+M
    iterations: the loop runs from_summaries (nothing to do yet), E, M, E, M, then stops
    (max_iterations=0 would be one iteration, but 0.14.8 then fails in fit's final callback:
    `logs` is assigned only from the second pass). So a Baum–Welch iteration is half the fit
    time; the model is rebuilt, untimed, before each run. The log-likelihoods it reports
    (initial, after one iteration) and its model's score after the second iteration are
    compared with our report's L0, L1, L2: with reg = 0 both do the same maximum-likelihood
    update, so they agree to rounding when the two run the same algorithm.
Output: a table per file, the ratios against ours and issue 12's goals (scoring ≥ 12× and a
training iteration ≥ 10× pomegranate's speed), then one line per metric for scripts:
    BENCH <metric> <value> <unit>
Exit status 1 when a file cannot be read or the log-likelihoods disagree by more than 1e-6
relative.
"""
import os

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ[_var] = "1"

import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

RUNS = 5
TARGET_RUN_SECONDS = 1.0
CALIBRATE_SECONDS = 0.1
MAX_REPEAT = 100000
AGREE_TOL = 1e-6  # relative difference of log-likelihoods accepted
SCORE_GOAL = 12.0  # scoring at least 12× pomegranate (issue 12, item 4)
TRAIN_GOAL = 10.0  # a Baum–Welch iteration at least 10× faster (issue 12, item 4)
MAGIC = b"AFHMMBN1"


def read_peer_file(path):
    """The header, our results, both models, our per-sequence log-likelihoods and the data."""
    with open(path, "rb") as f:
        raw = f.read()
    if raw[:8] != MAGIC:
        raise ValueError("%s: not a bench_hmm peer file" % path)
    hdr = np.frombuffer(raw, "<u4", 8, 8)
    N, M, m, S, T = (int(v) for v in hdr[:5])
    pos = [40]

    def take(n, shape=None):
        a = np.frombuffer(raw, "<f8", n, pos[0])
        pos[0] += 8 * n
        return a.reshape(shape).copy() if shape else a.copy()

    def model():
        return {
            "start": take(N),
            "trans": take(N * N, (N, N)),
            "weights": take(N * M, (N, M)),
            "means": take(N * M * m, (N, M, m)),
            "covs": take(N * M * m * m, (N, M, m, m)),
        }

    res = take(8)
    d = {
        "N": N, "M": M, "m": m, "S": S, "T": T,
        "ours": {"score_fps": res[0], "bound_fps": res[1], "bw_s": res[2],
                 "L": [res[3], res[4], res[5]], "total": res[6]},
        "gen": model(),
        "init": model(),
        "ll": take(S),
        "x": take(S * T * m, (S, T, m)),
    }
    if pos[0] != len(raw):
        raise ValueError("%s: %d bytes, expected %d" % (path, len(raw), pos[0]))
    return d


def build(pm, p, N, M):
    """A baked pomegranate HMM with the parameters p (the shapes of affect/hmm.h)."""
    states = []
    for i in range(N):
        comps = [pm.MultivariateGaussianDistribution(p["means"][i, j], p["covs"][i, j])
                 for j in range(M)]
        gmm = pm.GeneralMixtureModel(comps, weights=p["weights"][i])
        states.append(pm.State(gmm, name="s%d" % i))
    model = pm.HiddenMarkovModel("hmm")
    model.add_states(states)
    for i in range(N):
        if p["start"][i] > 0:
            model.add_transition(model.start, states[i], float(p["start"][i]))
    for i in range(N):
        for k in range(N):
            if p["trans"][i, k] > 0:
                model.add_transition(states[i], states[k], float(p["trans"][i, k]))
    model.bake(merge="None")
    return model


def measure(fn, repeat=0):
    """Warm-up call, calibration (repeat 0), then RUNS runs: (median, min, max, repeat)."""
    fn()
    if repeat == 0:
        k = 1
        while True:
            t0 = time.perf_counter()
            for _ in range(k):
                fn()
            t = time.perf_counter() - t0
            if t >= CALIBRATE_SECONDS or k >= MAX_REPEAT:
                break
            k *= 2
        want = k * TARGET_RUN_SECONDS / t if t > 0 else MAX_REPEAT
        repeat = max(1, min(MAX_REPEAT, int(want + 0.5)))
    times = []
    for _ in range(RUNS):
        t0 = time.perf_counter()
        for _ in range(repeat):
            fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), max(times), repeat


def rel(a, b):
    return abs(a - b) / abs(b) if b != 0 else abs(a - b)


def row(name, r, frames, per_run_passes=1.0):
    s = r[0] / r[3] / per_run_passes
    print("%-24s %6d %9.4f %9.4f %9.4f %12.0f %9.3f"
          % (name, r[3], r[0], r[1], r[2], frames / s, s / frames * 1e6))


def bench_file(pm, path):
    d = read_peer_file(path)
    N, M, m, S, T = d["N"], d["M"], d["m"], d["S"], d["T"]
    ours = d["ours"]
    frames = float(S * T)
    seqs = [d["x"][s] for s in range(S)]

    # scoring: agreement first, then the timing
    gen = build(pm, d["gen"], N, M)
    ll = np.array([gen.log_probability(x) for x in seqs])
    diffs = np.abs(ll - d["ll"]) / np.abs(d["ll"])
    worst = int(np.argmax(diffs))
    total_diff = rel(float(ll.sum()), float(d["ll"].sum()))
    score_r = measure(lambda: [gen.log_probability(x) for x in seqs])

    # Baum–Welch from our initial model: two iterations per fit (see the header)
    fit_state = {}

    def fresh():
        fit_state["model"] = build(pm, d["init"], N, M)

    def fit():
        _, hist = fit_state["model"].fit(seqs, algorithm="baum-welch", max_iterations=1,
                                         stop_threshold=-math.inf, n_jobs=1, verbose=False,
                                         return_history=True)
        fit_state["hist"] = hist

    fresh()
    fit()
    times = []
    for _ in range(RUNS):
        fresh()
        t0 = time.perf_counter()
        fit()
        times.append(time.perf_counter() - t0)
    fit_r = (statistics.median(times), min(times), max(times), 1)
    hist = fit_state["hist"]
    if len(hist.log_probabilities) != 1:
        raise RuntimeError("fit ran %d epochs after the first, not 1" % len(hist.log_probabilities))
    pg_L = [hist.initial_log_probability, hist.log_probabilities[0],
            sum(fit_state["model"].log_probability(x) for x in seqs)]
    L_diff = [rel(a, b) for a, b in zip(pg_L, ours["L"])]

    pg_score_fps = frames / (score_r[0] / score_r[3])
    pg_bw_s = fit_r[0] / 2.0
    score_ratio = ours["score_fps"] / pg_score_fps
    bw_ratio = pg_bw_s / ours["bw_s"]

    print("m = %d: %d sequences x %d frames = %.0f frames (%s)" % (m, S, T, frames, path))
    print("%-24s %6s %9s %9s %9s %12s %9s"
          % ("kernel", "passes", "median", "fastest", "slowest", "frames/s", "us/frame"))
    row("log_probability", score_r, frames)
    row("fit (2 iterations)", fit_r, frames)
    print("agreement, scoring under the generating model: per sequence max relative difference "
          "%.2e (sequence %d); total: ours %.6f, pomegranate %.6f, relative difference %.2e"
          % (diffs[worst], worst, d["ll"].sum(), ll.sum(), total_diff))
    print("agreement, training from our initial model: L0 %.6f vs ours %.6f (%.2e), "
          "L1 %.6f vs %.6f (%.2e), L2 %.6f vs %.6f (%.2e)"
          % (pg_L[0], ours["L"][0], L_diff[0], pg_L[1], ours["L"][1], L_diff[1],
             pg_L[2], ours["L"][2], L_diff[2]))
    print("scoring: ours %.0f frames/s, pomegranate %.0f frames/s: %.1fx; goal >= %.0fx: %s"
          % (ours["score_fps"], pg_score_fps, score_ratio, SCORE_GOAL,
             "met" if score_ratio >= SCORE_GOAL else "NOT met (%.1fx short)"
             % (SCORE_GOAL / score_ratio)))
    print("Baum-Welch iteration: ours %.4f s, pomegranate %.4f s: %.1fx; goal >= %.0fx: %s"
          % (ours["bw_s"], pg_bw_s, bw_ratio, TRAIN_GOAL,
             "met" if bw_ratio >= TRAIN_GOAL else "NOT met (%.1fx short)"
             % (TRAIN_GOAL / bw_ratio)))
    print()
    print("BENCH hmm_m%d_pomegranate_score %.0f frames/s" % (m, pg_score_fps))
    print("BENCH hmm_m%d_score_vs_pomegranate %.2f ratio" % (m, score_ratio))
    print("BENCH hmm_m%d_score_max_rel_diff %.3e ratio" % (m, diffs[worst]))
    print("BENCH hmm_m%d_pomegranate_bw_iteration %.4f s" % (m, pg_bw_s))
    print("BENCH hmm_m%d_bw_vs_pomegranate %.2f ratio" % (m, bw_ratio))
    print("BENCH hmm_m%d_train_loglik_max_rel_diff %.3e ratio" % (m, max(L_diff)))
    print()
    return 0 if diffs[worst] <= AGREE_TOL and max(L_diff) <= AGREE_TOL else 1


def main(argv):
    if len(argv) < 2:
        print("usage: %s FILE..." % argv[0], file=sys.stderr)
        return 2
    import pomegranate as pm
    import scipy

    limits = None
    try:
        import threadpoolctl
        limits = threadpoolctl.threadpool_limits(1)
        pools = ", ".join("%s %s %s (%d thread%s)"
                          % (p.get("internal_api"), p.get("version"), p.get("architecture", ""),
                             p["num_threads"], "" if p["num_threads"] == 1 else "s")
                          for p in threadpoolctl.threadpool_info())
    except ImportError:
        pools = "threadpoolctl not installed; OPENBLAS_NUM_THREADS=1"
    print("pomegranate %s, numpy %s, scipy %s, python %s; BLAS: %s"
          % (pm.__version__, np.__version__, scipy.__version__, sys.version.split()[0], pools))
    print()
    rc = 0
    for path in argv[1:]:
        rc |= bench_file(pm, path)
    if rc:
        print("hmm_peer: the log-likelihoods disagree by more than %g relative" % AGREE_TOL)
    del limits
    return rc


if __name__ == "__main__":
    sys.exit(main(sys.argv))
