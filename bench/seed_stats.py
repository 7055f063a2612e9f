#!/usr/bin/python3
"""Per-method statistics over seeds, with a 95 % confidence interval for every ratio.

bench/seed_stats.py DIR BASE METHODS SEEDS [REFERENCE] [VREF]

DIR holds LABEL-sK.exr or LABEL-sK.pfm (K = 1..SEEDS) and LABEL-sK.txt (the render's stdout, "rendered N passes
...") for every LABEL in METHODS (space-separated). For each method:
- passes: the mean over seeds;
- MSE against REFERENCE (mean over seeds, minus VREF, the reference's own noise), the trimmed MSE (without the
  0.1 % of pixels of largest error: `dartspp compare`, docs/cli.md §4) and the papers' MSE/q99²;
- the seed variance: the mean per-pixel variance between seeds, from disjoint pairs of seeds (s1, s2), (s3,
  s4), ...: each pair gives MSE(a, b)/2, an unbiased estimate that shares no image with the others; and the
  trimmed seed variance, the trimmed MSE(a, b)/2 (no reference needed: for unbiased methods the figure to
  compare when the reference cannot resolve the MSE);
- the bias of the mean, apart from the noise: the MSE of the seeds' mean image (`dartspp merge`) against
  REFERENCE is bias² + V/SEEDS + VREF, so bias² = that − V/SEEDS − VREF with V the seed variance, ± twice the
  standard error of V/SEEDS over the pairs (printed "≤ x" when it does not stand out of that: the reference or
  the seeds do not resolve it);
- each figure's ratio to BASE's, with a 95 % percentile bootstrap interval: seeds (MSE) or pairs (variance)
  resampled with replacement, each method independently (its runs share nothing with BASE's), 4000 times.
Prints one Markdown table row per method. Written by us for the benchmarks (no library needed: the numbers come
from `dartspp compare` and `dartspp merge`)."""
import os
import random
import subprocess
import sys

BIN = os.environ.get("DARTSPP", "build/dartspp")


def compare(a, b):
    """MSE, MSE/q99² and the trimmed MSE of image a against b"""
    row = subprocess.run([BIN, "compare", a, b, "--csv"], check=True, capture_output=True, text=True).stdout
    f = row.strip().split(",")
    return float(f[0]), float(f[3]), float(f[7])


def image_of(d, label, k):
    for ext in (".exr", ".pfm"):
        path = "%s/%s-s%d%s" % (d, label, k, ext)
        if os.path.exists(path):
            return path
    return None


def mean_image_mse(imgs, ref, d, label):
    """MSE of the seeds' mean image against the reference (dartspp merge writes the mean)"""
    if len(imgs) < 2:
        return float("nan")
    out = "%s/%s-mean.pfm" % (d, label)
    subprocess.run([BIN, "merge", out] + imgs, check=True, capture_output=True, text=True)
    return compare(out, ref)[0]


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


def bias_cell(mse_mean, var, k, vref):
    """bias² of the mean = MSE(mean, ref) − V/k − V_ref, ± twice the standard error of V/k (from the spread of
    the pairs' variances); '≤ x' (x = estimate + 2 se) where it does not stand out of that noise"""
    if len(var) < 2 or mse_mean != mse_mean:
        return "-"
    b = mse_mean - mean(var) / k - vref
    se = (sum((v - mean(var)) ** 2 for v in var) / (len(var) - 1) / len(var)) ** 0.5 / k
    return "%.3g ± %.2g" % (b, 2 * se) if b > 2 * se else "≤ %.2g" % (max(b, 0.0) + 2 * se)


def main():
    if len(sys.argv) < 5:
        sys.exit("usage: seed_stats.py DIR BASE METHODS SEEDS [REFERENCE] [VREF]")
    d, base, methods, seeds = sys.argv[1], sys.argv[2], sys.argv[3].split(), int(sys.argv[4])
    ref = sys.argv[5] if len(sys.argv) > 5 and sys.argv[5] != "-" else None
    vref = float(sys.argv[6]) if len(sys.argv) > 6 else 0.0
    stats = {}
    for m in methods:
        imgs = [image_of(d, m, k) for k in range(1, seeds + 1)]
        imgs = [p for p in imgs if p]
        mse, q, trim = [], [], []
        if ref:
            for p in imgs:
                a, b, c = compare(p, ref)
                mse.append(a)
                q.append(b)
                trim.append(c)
        pairs = [compare(imgs[i], imgs[i + 1]) for i in range(0, len(imgs) - 1, 2)]
        var = [c[0] / 2 for c in pairs]
        var_trim = [c[2] / 2 for c in pairs]
        ps = [passes(p[:-4] + ".txt") for p in imgs]
        mm = mean_image_mse(imgs, ref, d, m) if ref else float("nan")
        stats[m] = {"passes": mean(ps), "mse": mse, "q": q, "trim": trim, "var": var, "var_trim": var_trim,
                    "n": len(imgs), "mm": mm}
    if base not in stats:
        sys.exit("seed_stats.py: base method %s not among %s" % (base, methods))
    b = stats[base]
    print("| method | seeds | passes | MSE − V_ref | ÷ %s [95 %% CI] | trimmed MSE | ÷ %s [95 %% CI] | MSE/q99² "
          "| ÷ %s [95 %% CI] | seed variance (pairs) | ÷ %s [95 %% CI] | trimmed seed variance | ÷ %s [95 %% CI] "
          "| bias² of the mean |" % ((base,) * 5))
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for m in methods:
        st = stats[m]
        cell = lambda xs, shift=0.0: "%.4g" % (mean(xs) - shift) if xs else "-"
        print("| %s | %d | %.0f | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (
            m, st["n"], st["passes"], cell(st["mse"], vref), fmt(ratio_ci(st["mse"], b["mse"], vref)),
            cell(st["trim"]), fmt(ratio_ci(st["trim"], b["trim"])), cell(st["q"]), fmt(ratio_ci(st["q"], b["q"])),
            cell(st["var"]), fmt(ratio_ci(st["var"], b["var"])), cell(st["var_trim"]),
            fmt(ratio_ci(st["var_trim"], b["var_trim"])), bias_cell(st["mm"], st["var"], st["n"], vref)))


if __name__ == "__main__":
    main()
