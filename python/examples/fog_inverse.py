#!/usr/bin/env python3
"""Inverse problem: a fog's scattering and absorption coefficients (sigma_s, sigma_a) recovered from a gated
sequence of images, by Gauss-Newton on the L2 loss between the rendered sequence and a target, with the
derivative images of dartspp.render(..., derivatives=[...]) (docs/python.md §2; Yi et al. 2021).

    python3 python/examples/fog_inverse.py OUT_FOLDER [--scene SCENE.json] [--iterations N] ...

The target is the scene at its own sigma_s and sigma_a, rendered once with another seed and more passes; the
search starts at --start-factor times both (2: twice the truth). The sequence is --frames frames of
--frame-width from --start-time (optical path length), small (--width x --height), rendered by the path tracer.
Each iteration renders the sequence twice with new independent seeds, A and B, both with the two derivative images
per frame, and takes the Gauss-Newton step in log sigma from the gradient (J_A r_B + J_B r_A)/2: the residual of
one render times the derivatives of the other, so that the noise of the two does not multiply into a bias.
The estimate is the geometric mean of the iterates of the second half (--average-from), which averages the
renders' noise out; the last iterate is printed too.

Writes OUT_FOLDER/fog_inverse.csv (per iteration: loss, sigma_s, sigma_a, their relative errors, seconds) and a
plot (fog_inverse.png with matplotlib, else fog_inverse.svg drawn here) of the loss, the relative errors and the
sequence's mean per frame (target, start, end).
"""
import argparse
import copy
import csv
import json
import os
import sys
import time
import warnings

import numpy as np

import dartspp

HERE = os.path.dirname(os.path.abspath(__file__))
SCENE = os.path.join(HERE, "..", "..", "scenes", "gated-fog", "gated-fog.json")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("out", help="folder for the CSV and the plot (created)")
    p.add_argument("--scene", default=SCENE, help="scene file with the fog (default scenes/gated-fog)")
    p.add_argument("--medium", type=int, default=0, help="index of the fog in the scene's media (default 0)")
    p.add_argument("--width", type=int, default=40)
    p.add_argument("--height", type=int, default=24)
    p.add_argument("--frames", type=int, default=6, help="frames of the gated sequence")
    p.add_argument("--start-time", type=float, default=10.0, help="start of the first frame")
    p.add_argument("--frame-width", type=float, default=10.0, help="width of each frame (optical path length)")
    p.add_argument("--spp", type=int, default=64, help="passes of each render of an iteration")
    p.add_argument("--target-spp", type=int, default=1024, help="passes of the target")
    p.add_argument("--pool", type=int, default=8, help="the loss compares the frames' means over blocks of "
                   "POOL x POOL pixels (1: every pixel; default 8): a path tracer's few passes are noisy per pixel")
    p.add_argument("--iterations", type=int, default=16)
    p.add_argument("--average-from", type=int, default=None, metavar="K",
                   help="the estimate: the geometric mean of iterates K.. (default: the second half)")
    p.add_argument("--start-factor", type=float, nargs=2, default=[2.0, 2.0], metavar=("S", "A"),
                   help="the start as multiples of the true sigma_s and sigma_a (default 2 2)")
    p.add_argument("--threads", type=int, default=0, help="threads of each render (0: all cores)")
    a = p.parse_args()
    for name in ("width", "height", "frames", "spp", "target_spp", "iterations", "pool"):
        if getattr(a, name) < 1:
            p.error("--%s: expected a whole number of at least 1, not %d" % (name.replace("_", "-"), getattr(a, name)))
    if a.pool > min(a.width, a.height):
        p.error("--pool %d: larger than the image (%d x %d)" % (a.pool, a.width, a.height))
    if min(a.start_factor) <= 0:
        p.error("--start-factor: expected two numbers above 0")
    return a


def load_scene(a):
    """The scene file made small and gated: the path tracer, a frame sequence, no output file."""
    with open(a.scene) as f:
        scene = json.load(f)
    media = scene.get("media", [])
    if not 0 <= a.medium < len(media):
        sys.exit("--medium %d: the scene has %d media" % (a.medium, len(media)))
    med = media[a.medium]
    for key in ("sigma_s", "sigma_a"):
        if not isinstance(med.get(key), (int, float)):
            sys.exit("%s: media[%d].%s: expected one number (this example fits scalars), not %r"
                     % (a.scene, a.medium, key, med.get(key)))
    scene["camera"]["resolution"] = [a.width, a.height]
    scene["integrator"].update(type="path_tracer", frame_num=a.frames, start_time=a.start_time,
                               transient_time_width=a.frame_width)
    scene.get("renderer", {}).pop("hdr_output_file", None)
    return scene, np.array([med["sigma_s"], med["sigma_a"]], float)


class Problem:
    def __init__(self, a, scene):
        self.a, self.scene = a, scene
        self.base_dir = os.path.dirname(os.path.abspath(a.scene))
        self.pointers = ["/media/%d/sigma_s" % a.medium, "/media/%d/sigma_a" % a.medium]

    def render(self, sigma, seed, spp, derivatives=True):
        s = copy.deepcopy(self.scene)
        med = s["media"][self.a.medium]
        med["sigma_s"], med["sigma_a"] = float(sigma[0]), float(sigma[1])
        with warnings.catch_warnings():  # the scene's photon-map keys, which the path tracer does not read
            warnings.simplefilter("ignore", dartspp.SceneWarning)
            return dartspp.render(s, spp=spp, seed=seed, threads=self.a.threads, base_dir=self.base_dir,
                                  derivatives=self.pointers if derivatives else None)

    def pool(self, frames):
        """The means of (..., height, width, 3) frames over blocks of pool x pool pixels (the image cropped to
        whole blocks)."""
        b = self.a.pool
        h, w = frames.shape[-3] // b * b, frames.shape[-2] // b * b
        f = frames[..., :h, :w, :].astype(np.float64)
        return f.reshape(f.shape[:-3] + (h // b, b, w // b, b, 3)).mean(axis=(-4, -2))

    def residual_and_jacobian(self, sigma, seed, target):
        """r = I(sigma) - target over the whole (pooled) sequence (N values) and J (2 x N): dI/d(log sigma_k),
        the derivative images times sigma_k."""
        r = self.render(sigma, seed, self.a.spp)
        res = (self.pool(r.frames) - self.pool(target)).ravel()
        jac = self.pool(r.derivative_frames).reshape(2, -1) * sigma[:, None]
        return res, jac, r.frames


def gauss_newton_step(ra, ja, rb, jb, damping):
    """The step in log sigma: (H + damping diag H)^-1 g with the decorrelated gradient g = (J_A r_B + J_B r_A)/2
    and H = (J_A J_A^T + J_B J_B^T)/2; at most 0.7 in each coordinate (a factor 2)."""
    g = 0.5 * (ja @ rb + jb @ ra)
    h = 0.5 * (ja @ ja.T + jb @ jb.T)
    step = -np.linalg.solve(h + damping * np.diag(np.diag(h)), g)
    return np.clip(step, -0.7, 0.7)


def fit(problem, truth, target):
    a = problem.a
    sigma = truth * np.array(a.start_factor)
    rows, start_frames, damping, t0 = [], None, 0.1, time.monotonic()
    print("%4s %12s %12s %12s %9s %9s %7s" % ("iter", "loss", "sigma_s", "sigma_a", "err_s", "err_a", "s"))
    for it in range(a.iterations + 1):
        # fresh seeds every iteration: with the same ones the search fits those renders' noise (a path
        # tracer's frame means are heavy-tailed: +30 % in one frame at 64 passes)
        ra, ja, fa = problem.residual_and_jacobian(sigma, 2 * it + 1, target)
        rb, jb, _ = problem.residual_and_jacobian(sigma, 2 * it + 2, target)
        loss = 0.5 * (np.mean(ra ** 2) + np.mean(rb ** 2))
        err = sigma / truth - 1
        rows.append([it, loss, sigma[0], sigma[1], err[0], err[1], time.monotonic() - t0])
        print("%4d %12.5e %12.6g %12.6g %+9.4f %+9.4f %7.1f" % tuple(rows[-1]), flush=True)
        if start_frames is None:
            start_frames = fa
        if it == a.iterations:
            return rows, start_frames, fa
        sigma = sigma * np.exp(gauss_newton_step(ra, ja, rb, jb, damping))


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["iteration", "loss", "sigma_s", "sigma_a", "rel_err_sigma_s", "rel_err_sigma_a", "seconds"])
        w.writerows(rows)


def plot_matplotlib(path, rows, profiles):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    it = [r[0] for r in rows]
    fig, ax = plt.subplots(1, 3, figsize=(13, 3.6))
    ax[0].semilogy(it, [r[1] for r in rows], "o-")
    ax[0].set(title="loss (MSE of the sequence)", xlabel="iteration")
    ax[1].plot(it, [abs(r[4]) for r in rows], "o-", label="sigma_s")
    ax[1].plot(it, [abs(r[5]) for r in rows], "s-", label="sigma_a")
    ax[1].set(yscale="log", title="|relative error|", xlabel="iteration")
    ax[1].legend()
    for name, prof in profiles:
        ax[2].plot(range(len(prof)), prof, "o-", label=name)
    ax[2].set(yscale="log", title="mean of each frame", xlabel="frame")
    ax[2].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def svg_panel(x0, title, series, log=True, w=300, h=220):
    """One panel of line plots as SVG elements: series = [(label, xs, ys, colour)], y on a log scale."""
    ys = [y for _, _, v, _ in series for y in v if not log or y > 0]
    xs = [x for _, u, _, _ in series for x in u]
    f = (lambda y: np.log10(y)) if log else (lambda y: y)
    lo, hi = f(min(ys)), f(max(ys))
    hi, lo = (hi + 0.5, lo - 0.5) if hi == lo else (hi, lo)
    x_lo, x_hi = min(xs), max(max(xs), min(xs) + 1)
    px = lambda x: x0 + 50 + (x - x_lo) / (x_hi - x_lo) * (w - 60)
    py = lambda y: 30 + (hi - f(y)) / (hi - lo) * (h - 60)
    out = ['<text x="%g" y="18" font-size="13">%s</text>' % (x0 + 50, title),
           '<rect x="%g" y="30" width="%g" height="%g" fill="none" stroke="#888"/>' % (x0 + 50, w - 60, h - 60)]
    for v in (lo, hi):
        out.append('<text x="%g" y="%g" font-size="10" text-anchor="end">%.3g</text>'
                   % (x0 + 46, 30 + (hi - v) / (hi - lo) * (h - 60) + 4, 10 ** v if log else v))
    for x in (x_lo, x_hi):
        out.append('<text x="%g" y="%g" font-size="10" text-anchor="middle">%g</text>' % (px(x), h - 16, x))
    for k, (label, u, v, colour) in enumerate(series):
        pts = " ".join("%.1f,%.1f" % (px(x), py(y)) for x, y in zip(u, v) if not log or y > 0)
        out.append('<polyline points="%s" fill="none" stroke="%s" stroke-width="1.5"/>' % (pts, colour))
        out.append('<text x="%g" y="%g" font-size="10" fill="%s">%s</text>' % (x0 + w - 80, 44 + 12 * k, colour, label))
    return out


def plot_svg(path, rows, profiles):
    it = [r[0] for r in rows]
    colours = ["#1f77b4", "#d62728", "#2ca02c"]
    body = svg_panel(0, "loss (MSE of the sequence)", [("loss", it, [r[1] for r in rows], colours[0])])
    body += svg_panel(310, "|relative error|", [("sigma_s", it, [abs(r[4]) for r in rows], colours[0]),
                                                 ("sigma_a", it, [abs(r[5]) for r in rows], colours[1])])
    body += svg_panel(620, "mean of each frame", [(n, list(range(len(p))), list(p), c)
                                                   for (n, p), c in zip(profiles, colours)])
    with open(path, "w") as f:
        f.write('<svg xmlns="http://www.w3.org/2000/svg" width="930" height="220" font-family="sans-serif">\n'
                '<rect width="930" height="220" fill="white"/>\n%s\n</svg>\n' % "\n".join(body))


def main():
    a = parse_args()
    os.makedirs(a.out, exist_ok=True)
    scene, truth = load_scene(a)
    problem = Problem(a, scene)
    t0 = time.monotonic()
    print("truth: sigma_s %g, sigma_a %g; start: %g x, %g x; %dx%d, %d frames of %g from %g; %d spp (target %d)"
          % (truth[0], truth[1], a.start_factor[0], a.start_factor[1], a.width, a.height, a.frames, a.frame_width,
             a.start_time, a.spp, a.target_spp), flush=True)
    target = problem.render(truth, 1000, a.target_spp, derivatives=False).frames
    rows, start_frames, end_frames = fit(problem, truth, target)
    wall = time.monotonic() - t0
    write_csv(os.path.join(a.out, "fog_inverse.csv"), rows)
    profiles = [("target", target.mean(axis=(1, 2, 3))), ("start", start_frames.mean(axis=(1, 2, 3))),
                ("end", end_frames.mean(axis=(1, 2, 3)))]
    try:
        plot_matplotlib(os.path.join(a.out, "fog_inverse.png"), rows, profiles)
        plot = "fog_inverse.png"
    except ImportError:
        plot_svg(os.path.join(a.out, "fog_inverse.svg"), rows, profiles)
        plot = "fog_inverse.svg"
    first = a.iterations // 2 if a.average_from is None else min(max(a.average_from, 0), a.iterations)
    est = np.exp(np.mean([np.log(r[2:4]) for r in rows[first:]], axis=0))
    err = est / truth - 1
    last = rows[-1]
    print("last iterate: sigma_s %.6g (%+.2f %%), sigma_a %.6g (%+.2f %%)"
          % (last[2], 100 * last[4], last[3], 100 * last[5]))
    print("recovered (mean of iterates %d..%d): sigma_s %.6g (relative error %+.2f %%), sigma_a %.6g (%+.2f %%); "
          "%d iterations, %.1f s in all; %s and fog_inverse.csv in %s"
          % (first, a.iterations, est[0], 100 * err[0], est[1], 100 * err[1], a.iterations, wall, plot, a.out))


if __name__ == "__main__":
    main()
