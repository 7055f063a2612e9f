#!/usr/bin/env python3
"""Inverse problem: the distance of a wall hidden in fog recovered from its transient, by Gauss-Newton on the L2
loss between the rendered frames and a target, with the derivative of every frame with respect to the wall's
position (dartspp.render(..., derivatives=["/primitives/0/transform/position/2"]); docs/derivatives.md §6;
Yi et al. 2021).

    python3 python/examples/hidden_wall.py OUT_FOLDER [--distance D] [--start S] [--iterations N] ...

The scene is written here: a fog (sigma_s 0.25, sigma_a 0.02, Henyey-Greenstein g 0.5), a pinhole camera at the
origin looking along +z, a point light beside it with a box pulse, and a wall (a 40 x 40 quad, its edges out of
view) at z = D facing the camera; the path tracer renders --frames frames of --frame-width from --start-time,
single scattering (max_bounces 2: the fog's glow and the wall's direct echo). The wall's echo arrives at 2D and
the fog's backscatter before it; through the fog the echo is faint, which is what makes the search need the
whole transient. The target is the scene at --distance, rendered once with another seed and more passes; the
search starts at --start. Each iteration renders twice with new seeds and steps by the decorrelated
Gauss-Newton step (J_A r_B + J_B r_A) / (J_A J_A + J_B J_B) in the distance, at most --max-step.

The loss compares the cumulative transients (the frames' running sums: the 1-D Wasserstein distance between the
echoes), so that an echo far from the target's still feels it. Writes OUT_FOLDER/hidden_wall.csv (per iteration: loss, distance, its error, seconds) and hidden_wall.svg (the
loss, the distance's error and the transients of the target, the start and the end), and prints the result.
"""
import argparse
import copy
import csv
import os
import time

import numpy as np

import dartspp
from fog_inverse import svg_panel  # the other example's hand-drawn SVG panel (no matplotlib on Debian's base)

POINTER = "/primitives/0/transform/position/2"


def scene(distance, a):
    return {
        "media": [{"name": "fog", "type": "homogeneous", "sigma_s": 0.25, "sigma_a": 0.02,
                   "phase_function": {"type": "henyey_greenstein", "g": 0.5}}],
        "bsdfs": [{"name": "wall", "type": "lambert", "albedo": 0.8}],
        "primitives": [
            {"type": "quad", "bsdf": "wall",
             "transform": {"position": [0.0, 0.0, distance], "scale": [40, 1, 40], "rotation": [-90, 0, 0]}},
            {"type": "point", "power": 400.0, "ext_medium": "fog", "pulse_start": 0.0, "pulse_width": 0.6,
             "transform": {"position": [0.3, 0.0, 0.0]}},
        ],
        "camera": {"type": "pinhole", "resolution": [a.width, a.height], "fov": 30, "medium": "fog",
                   "transform": {"position": [0, 0, 0], "look_at": [0, 0, 1], "up": [0, 1, 0]}},
        "integrator": {"type": "path_tracer", "max_bounces": 2, "frame_num": a.frames, "start_time": a.start_time,
                       "transient_time_width": a.frame_width},
        "renderer": {"spp": 1},
    }


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", help="folder for the CSV (created)")
    p.add_argument("--distance", type=float, default=6.0, help="the wall's true distance (default 6)")
    p.add_argument("--start", type=float, default=7.5, help="the search's first distance (default 7.5)")
    p.add_argument("--width", type=int, default=16)
    p.add_argument("--height", type=int, default=12)
    p.add_argument("--frames", type=int, default=14)
    p.add_argument("--start-time", type=float, default=6.0)
    p.add_argument("--frame-width", type=float, default=1.0)
    p.add_argument("--spp", type=int, default=64, help="passes of each render of an iteration")
    p.add_argument("--target-spp", type=int, default=512)
    p.add_argument("--iterations", type=int, default=10)
    p.add_argument("--max-step", type=float, default=1.0, help="the largest step in distance (default 1)")
    p.add_argument("--threads", type=int, default=0)
    a = p.parse_args()
    for name in ("width", "height", "frames", "spp", "target_spp", "iterations"):
        if getattr(a, name) < 1:
            p.error("--%s: expected a whole number of at least 1" % name.replace("_", "-"))
    if min(a.distance, a.start) <= 1.0:
        p.error("--distance and --start: the wall must be more than 1 in front of the camera")
    return a


def frame_means(r):
    """The transient the search fits: each frame's mean over the image, accumulated over the frames (frames, 3).
    The cumulative transient makes the loss the 1-D Wasserstein distance between the echoes: where the rendered
    echo and the target's do not overlap in time, the frames themselves give no gradient toward each other, and
    their running sums do."""
    return np.cumsum(r.frames.astype(np.float64).mean(axis=(1, 2)), axis=0)


def residual_and_jacobian(a, distance, seed, target):
    r = dartspp.render(scene(distance, a), spp=a.spp, seed=seed, threads=a.threads, derivatives=[POINTER])
    res = (frame_means(r) - target).ravel()
    jac = np.cumsum(r.derivative_frames[0].astype(np.float64).mean(axis=(1, 2)), axis=0).ravel()
    return res, jac


def plot_svg(path, rows, profiles):
    it = [r[0] for r in rows]
    colours = ["#1f77b4", "#d62728", "#2ca02c"]
    body = svg_panel(0, "loss (cumulative transient)", [("loss", it, [r[1] for r in rows], colours[0])])
    body += svg_panel(310, "|distance error|", [("|d - truth|", it, [max(abs(r[3]), 1e-6) for r in rows], colours[0])])
    body += svg_panel(620, "transient (mean of each frame)", [(n, list(range(len(p))), list(p), c)
                                                              for (n, p), c in zip(profiles, colours)], log=False)
    with open(path, "w") as f:
        f.write('<svg xmlns="http://www.w3.org/2000/svg" width="930" height="220" font-family="sans-serif">\n'
                '<rect width="930" height="220" fill="white"/>\n%s\n</svg>\n' % "\n".join(body))


def transient(a, distance, seed, spp):
    r = dartspp.render(scene(distance, a), spp=spp, seed=seed, threads=a.threads)
    return r.frames.astype(np.float64).mean(axis=(1, 2, 3))


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    t0 = time.monotonic()
    target = frame_means(dartspp.render(scene(a.distance, a), spp=a.target_spp, seed=1000, threads=a.threads))
    d, rows = a.start, []
    print("%4s %12s %10s %9s %7s" % ("iter", "loss", "distance", "error", "s"))
    for it in range(a.iterations + 1):
        ra, ja = residual_and_jacobian(a, d, 2 * it + 1, target)
        rb, jb = residual_and_jacobian(a, d, 2 * it + 2, target)
        loss = 0.5 * (np.mean(ra ** 2) + np.mean(rb ** 2))
        rows.append([it, loss, d, d - a.distance, time.monotonic() - t0])
        print("%4d %12.5e %10.5f %+9.5f %7.1f" % tuple(rows[-1]), flush=True)
        if it == a.iterations:
            break
        step = -0.5 * (ja @ rb + jb @ ra) / max(0.5 * (ja @ ja + jb @ jb), 1e-300)
        d += float(np.clip(step, -a.max_step, a.max_step))
    with open(os.path.join(a.out, "hidden_wall.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["iteration", "loss", "distance", "error", "seconds"])
        w.writerows(rows)
    last = np.mean([r[2] for r in rows[len(rows) // 2:]])
    profiles = [("target", transient(a, a.distance, 1000, a.target_spp)), ("start", transient(a, a.start, 7, a.spp)),
                ("end", transient(a, d, 9, a.spp))]
    plot_svg(os.path.join(a.out, "hidden_wall.svg"), rows, profiles)
    print("recovered distance %.4f (truth %.4f, error %+.4f = %+.2f %%; mean of the second half's iterates) in %d "
          "iterations, %.1f s" % (last, a.distance, last - a.distance, 100 * (last - a.distance) / a.distance,
                                  a.iterations, time.monotonic() - t0))


if __name__ == "__main__":
    main()
