#!/usr/bin/python3
"""Checks a reference image against independent renders of another estimator, tile by tile.

    bench/tile_check.py --tiles N --ref R0.pfm R1.pfm ... --check C0.pfm C1.pfm ...

Each group is a set of independent renders (different seeds) of one method: the reference's chunks and, say,
the DARTS path tracer's. For every tile of an N x N grid (and for the whole image) it compares the two
groups' means: z = (mean_ref - mean_check) / sqrt(se_ref^2 + se_check^2), each standard error from the
spread of that group's renders (so each group needs at least 2). A consistent reference and an unbiased
check give |z| of order 1 in every tile; a biased reference shows as tiles with large |z| of one sign.
Prints one line per tile with |z| above 2 and a summary: tiles, max |z|, mean z^2 (about 1 when the two
agree), image means and their relative difference. PFM only (dartspp writes it with --output x.pfm).
"""
import argparse
import sys

import numpy as np


def read_pfm(path):
    with open(path, "rb") as f:
        kind = f.readline().strip()
        if kind not in (b"PF", b"Pf"):
            sys.exit(f"{path}: not a PFM file")
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    ch = 3 if kind == b"PF" else 1
    if data.size != w * h * ch:
        sys.exit(f"{path}: {data.size} values for {w}x{h}x{ch}")
    return data.reshape(h, w, ch).astype(np.float64).mean(axis=2)


def tile_means(img, n):
    h, w = img.shape
    out = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            out[i, j] = img[i * h // n:(i + 1) * h // n, j * w // n:(j + 1) * w // n].mean()
    return out


def group(paths, n):
    imgs = [read_pfm(p) for p in paths]
    if len(imgs) < 2:
        sys.exit("each group needs at least 2 independent renders (the spread gives the standard error)")
    if any(i.shape != imgs[0].shape for i in imgs):
        sys.exit("the renders of a group differ in size")
    tiles = np.array([tile_means(i, n) for i in imgs])
    whole = np.array([i.mean() for i in imgs])
    k = len(imgs)
    return (tiles.mean(axis=0), tiles.std(axis=0, ddof=1) / np.sqrt(k), whole.mean(),
            whole.std(ddof=1) / np.sqrt(k), imgs[0].shape)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tiles", type=int, default=8)
    ap.add_argument("--ref", nargs="+", required=True)
    ap.add_argument("--check", nargs="+", required=True)
    a = ap.parse_args()
    rm, rse, rw, rwse, rshape = group(a.ref, a.tiles)
    cm, cse, cw, cwse, cshape = group(a.check, a.tiles)
    if rshape != cshape:
        sys.exit(f"sizes differ: reference {rshape}, check {cshape}")
    se = np.sqrt(rse ** 2 + cse ** 2)
    live = se > 0
    z = np.zeros_like(rm)
    z[live] = (rm[live] - cm[live]) / se[live]
    for i, j in zip(*np.nonzero(np.abs(z) > 2)):
        print(f"tile ({i},{j}): reference {rm[i, j]:.6g} ± {rse[i, j]:.2g}, check {cm[i, j]:.6g} ± {cse[i, j]:.2g}, z {z[i, j]:+.2f}")
    zw = (rw - cw) / np.hypot(rwse, cwse)
    print(f"tiles {live.sum()} of {a.tiles * a.tiles} with signal; max |z| {np.abs(z).max():.2f}; "
          f"mean z^2 {np.mean(z[live] ** 2):.2f}")
    print(f"image mean: reference {rw:.6g} ± {rwse:.2g} ({len(a.ref)} renders), check {cw:.6g} ± {cwse:.2g} "
          f"({len(a.check)} renders), relative difference {(rw - cw) / cw:+.4f}, z {zw:+.2f}")


if __name__ == "__main__":
    main()
