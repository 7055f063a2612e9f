#!/usr/bin/python3
"""The thread-scaling table of bench/thread_scaling.sh's runs: bench/thread_table.py DIR [LABEL...]

DIR holds LABEL-tT-sS.txt, a render's summary for T threads and seed S ("rendered N passes in X s", "time in
photon pass A s, map builds B s, sensor pass C s", "peak resident M MiB"). Per label and thread count: the mean
time of the whole pass and of each phase over the seeds, the speed-up over one thread (the ratio of the means)
with a 95 % percentile bootstrap interval (seeds resampled with replacement, the one-thread and the T-thread
runs independently, 4000 times: bench/seed_stats.py's ratio_ci), and the peak resident memory. Prints Markdown. Written by us for the
benchmarks (no library needed)."""
import glob
import os
import re
import sys

from seed_stats import ratio_ci

PHASES = ["pass", "photon", "maps", "gather"]


def read(path):
    txt = open(path).read()
    r = re.search(r"rendered \d+ passes in ([\d.]+) s", txt)
    p = re.search(r"time in photon pass ([\d.]+) s, map builds ([\d.]+) s, sensor pass ([\d.]+) s", txt)
    m = re.search(r"peak resident ([\d.]+) MiB", txt)
    if not (r and p and m):
        raise SystemExit(f"{path}: no render summary (was the run cut short?)")
    return {"pass": float(r.group(1)), "photon": float(p.group(1)), "maps": float(p.group(2)),
            "gather": float(p.group(3)), "mib": float(m.group(1))}


def mean(xs):
    return sum(xs) / len(xs)


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    folder = sys.argv[1]
    runs = {}
    for path in glob.glob(os.path.join(folder, "*-t*-s*.txt")):
        m = re.match(r"(.+)-t(\d+)-s(\d+)\.txt$", os.path.basename(path))
        if m:
            runs.setdefault((m.group(1), int(m.group(2))), []).append(read(path))
    labels = sys.argv[2:] or sorted({k[0] for k in runs})
    print("| build | threads | seeds | pass (s) | speed-up | photon pass (s) | speed-up | map builds (s) | speed-up "
          "| sensor pass (s) | speed-up | peak resident (MiB) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for label in labels:
        one = runs.get((label, 1))
        for t in sorted(k[1] for k in runs if k[0] == label):
            rows = runs[(label, t)]
            cells = [label, str(t), str(len(rows))]
            for key in PHASES:
                cells.append("%.3f" % mean([r[key] for r in rows]))
                if one:
                    cells.append("%.2f [%.2f, %.2f]" % ratio_ci([r[key] for r in one], [r[key] for r in rows]))
                else:
                    cells.append("–")
            cells.append("%.1f" % mean([r["mib"] for r in rows]))
            print("| " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
