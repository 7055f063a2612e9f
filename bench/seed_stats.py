#!/usr/bin/python3
"""Per-method statistics over seeds, with a 95 % confidence interval for every ratio.

bench/seed_stats.py DIR BASE METHODS SEEDS [REFERENCE] [VREF]

DIR holds LABEL-sK.exr (K = 1..SEEDS) and LABEL-sK.txt (the render's stdout, "rendered N passes ...") for
every LABEL in METHODS (space-separated). For each method:
- passes: the mean over seeds;
- MSE against REFERENCE (mean over seeds, minus VREF, the reference's own noise), and the papers'
  MSE/q99² (dartspp compare --csv);
- the seed variance: the mean per-pixel variance between seeds, from disjoint pairs of seeds (s1, s2), (s3,
  s4), ...: each pair gives MSE(a, b)/2, an unbiased estimate that shares no image with the others;
- each figure's ratio to BASE's, with a 95 % percentile bootstrap interval: seeds (MSE) or pairs (variance)
  resampled with replacement, each method independently (its runs share nothing with BASE's), 4000 times.
Prints one Markdown table row per method: | label | passes | MSE | ratio [CI] | MSE/q99² | ratio [CI] |
variance | ratio [CI] |. Written by us for the benchmarks (no library needed: the numbers come from
`dartspp compare`)."""
import os
import random
import subprocess
import sys

BIN = os.environ.get("DARTSPP", "build/dartspp")


def compare(a, b):
    row = subprocess.run([BIN, "compare", a, b, "--csv"], check=True, capture_output=True, text=True).stdout
    f = row.strip().split(",")
    return float(f[0]), float(f[3])


def passes(path):
    with open(path) as fh:
        for line in fh:
            if line.startswith("rendered "):
                return float(line.split()[1])
    return float("nan")


def mean(xs):
    return sum(xs) / len(xs) if xs else float("nan")


def ratio_ci(xs, ys, shift=0.0, n=4000):
    """(mean(xs) - shift) / (mean(ys) - shift) and its 95 % percentile bootstrap interval."""
    den = mean(ys) - shift
    if not xs or not ys or den <= 0:
        return float("nan"), float("nan"), float("nan")
    rng = random.Random(12345)
    rs = []
    for _ in range(n):
        a = mean([rng.choice(xs) for _ in xs]) - shift
        b = mean([rng.choice(ys) for _ in ys]) - shift
        if b > 0:
            rs.append(a / b)
    rs.sort()
    if not rs:
        return (mean(xs) - shift) / den, float("nan"), float("nan")
    return (mean(xs) - shift) / den, rs[int(0.025 * len(rs))], rs[min(len(rs) - 1, int(0.975 * len(rs)))]


def fmt(r):
    v, lo, hi = r
    if v != v:
        return "-"
    return "%.3g [%.3g, %.3g]" % (v, lo, hi)


def main():
    if len(sys.argv) < 5:
        sys.exit("usage: seed_stats.py DIR BASE METHODS SEEDS [REFERENCE] [VREF]")
    d, base, methods, seeds = sys.argv[1], sys.argv[2], sys.argv[3].split(), int(sys.argv[4])
    ref = sys.argv[5] if len(sys.argv) > 5 and sys.argv[5] != "-" else None
    vref = float(sys.argv[6]) if len(sys.argv) > 6 else 0.0
    stats = {}
    for m in methods:
        imgs = ["%s/%s-s%d.exr" % (d, m, k) for k in range(1, seeds + 1)]
        imgs = [p for p in imgs if os.path.exists(p)]
        mse, q = [], []
        if ref:
            for p in imgs:
                a, b = compare(p, ref)
                mse.append(a)
                q.append(b)
        var = [compare(imgs[i], imgs[i + 1])[0] / 2 for i in range(0, len(imgs) - 1, 2)]
        ps = [passes(p[:-4] + ".txt") for p in imgs]
        stats[m] = (mean(ps), mse, q, var, len(imgs))
    if base not in stats:
        sys.exit("seed_stats.py: base method %s not among %s" % (base, methods))
    _, bmse, bq, bvar, _ = stats[base]
    print("| method | seeds | passes | MSE − V_ref | ÷ %s [95 %% CI] | MSE/q99² | ÷ %s [95 %% CI] | variance (seed pairs) "
          "| ÷ %s [95 %% CI] |" % (base, base, base))
    print("|---|---|---|---|---|---|---|---|---|")
    for m in methods:
        p, mse, q, var, n = stats[m]
        print("| %s | %d | %.0f | %s | %s | %s | %s | %s | %s |" % (
            m, n, p, "%.4g" % (mean(mse) - vref) if mse else "-", fmt(ratio_ci(mse, bmse, vref)),
            "%.4g" % mean(q) if q else "-", fmt(ratio_ci(q, bq)), "%.4g" % mean(var) if var else "-",
            fmt(ratio_ci(var, bvar))))


if __name__ == "__main__":
    main()
