#!/usr/bin/env python3
"""A 32-channel lidar on a street in fog at three visibilities (docs/lidar.md §8): the point clouds side by side,
the share of hard-target echoes lost and of false fog echoes against visibility, the multiple-scattering excess of
the waveform over its single-scattering layer, beams per second and the echo-intensity noise per frame.

usage: bench/lidar_fog.py [--passes N] [--frames K] [--threads T] [--out DIR] [--images DIR]

Each visibility is rendered K times (seeds 1..K, N passes each: one "frame" of the scan) with `dartspp render`;
the clear-air render (no fog) is the ground truth of the hard targets. A fog echo within MATCH of a clear-air
echo of the same beam is that target's; a clear-air echo with none is lost; a fog echo matching none is false.
Results: DIR/lidar-fog.md (a table, with the date and the CPU), plots in --images (the README shows them).
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np

from machine import cpu_model

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENE = os.path.join(ROOT, "scenes", "street-fog-lidar", "street-fog-lidar.json")
DARTSPP = os.path.join(ROOT, "build", "dartspp")
VISIBILITIES = [150.0, 50.0, 20.0]  # meteorological optical range, metres (σt = ln 20 / V, docs/lidar.md §6)
ALBEDO = 0.9998                      # water droplets at 905 nm (docs/lidar.md §6: the Mie tables' 0.99984)
MATCH = 0.5                         # metres: a fog echo within this of a clear-air echo of its beam is that target


def scene_for(base, visibility):
    """The street scene with its fog at `visibility` (None: clear air, the fog's scattering and absorption 0)."""
    s = json.loads(json.dumps(base))
    fog = s["media"][0]
    for k in ("sigma_s", "sigma_a", "visibility", "visibility_convention", "albedo"):
        fog.pop(k, None)
    if visibility is None:
        fog["sigma_s"], fog["sigma_a"] = 0.0, 0.0
    else:
        fog["visibility"], fog["visibility_convention"], fog["albedo"] = visibility, "mor", ALBEDO
    pf = fog.get("phase_function", {})
    if pf.get("type") == "tabulated" and not os.path.isabs(pf["file"]):  # the scenes are written elsewhere
        pf["file"] = os.path.normpath(os.path.join(os.path.dirname(SCENE), pf["file"]))
    return s


def render(scene, folder, name, passes, seed, threads):
    """One scan: returns (waveforms, orders or None, points, seconds)."""
    path = os.path.join(folder, name + ".json")
    with open(path, "w") as f:
        json.dump(scene, f)
    out = os.path.join(folder, name, name + ".exr")
    cmd = [DARTSPP, "render", path, "--spp", str(passes), "--seed", str(seed), "--threads", str(threads),
           "--output", out, "--quiet"]
    t0 = time.time()
    r = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.time() - t0
    if r.returncode != 0:
        sys.exit("dartspp render failed (%d): %s" % (r.returncode, r.stderr.strip()))
    stem = os.path.splitext(out)[0]
    orders = stem + "_waveforms_orders.npy"
    return (np.load(stem + "_waveforms.npy"), np.load(orders) if os.path.exists(orders) else None,
            np.load(stem + "_points.npy"), seconds)


def echoes_by_beam(points):
    """{(channel, azimuth index): [(range, intensity), ...]} from the point rows."""
    d = {}
    for row in points:
        d.setdefault((int(row[5]), int(row[6])), []).append((float(row[7]), float(row[3])))
    return d


def compare(clear, fog):
    """(hard-target echoes lost, their count; false fog echoes, fog echo count; beams with a false echo) against
    the clear-air echoes."""
    lost = total = false = fog_total = 0
    false_beams = set()
    for beam, targets in clear.items():
        got = fog.get(beam, [])
        for r, _ in targets:
            total += 1
            lost += not any(abs(r - g) <= MATCH for g, _ in got)
    for beam, got in fog.items():
        targets = clear.get(beam, [])
        for g, _ in got:
            fog_total += 1
            if not any(abs(r - g) <= MATCH for r, _ in targets):
                false += 1
                false_beams.add(beam)
    return lost, total, false, fog_total, len(false_beams)


def intensity_noise(frames, clear):
    """Median over the hard-target echoes seen in every frame of the relative standard deviation of their
    intensity across frames (one frame: one render of the scan)."""
    rel = []
    for beam, targets in clear.items():
        for r, _ in targets:
            vals = []
            for fr in frames:
                m = [i for g, i in fr.get(beam, []) if abs(r - g) <= MATCH]
                if not m:
                    break
                vals.append(m[0])
            if len(vals) == len(frames) and len(vals) > 1 and np.mean(vals) > 0:
                rel.append(np.std(vals, ddof=1) / np.mean(vals))
    return float(np.median(rel)) if rel else float("nan"), len(rel)


def plot(clouds, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, len(clouds), figsize=(4.2 * len(clouds), 5.2), sharey=True)
    for ax, (title, pts) in zip(axes, clouds):
        if len(pts):
            order = np.argsort(pts[:, 3])
            p = pts[order]
            sc = ax.scatter(p[:, 0], p[:, 2], c=np.log10(np.maximum(p[:, 3], 1e-12)), s=2, cmap="viridis",
                            vmin=-7, vmax=-3)
        ax.set_title("%s: %d points" % (title, len(pts)))
        ax.set_xlim(-15, 15)
        ax.set_ylim(0, 60)
        ax.set_xlabel("x (m)")
        ax.set_aspect("equal")
    axes[0].set_ylabel("z, forward (m)")
    cb = fig.colorbar(sc, ax=axes, shrink=0.8)
    cb.set_label("log10 echo energy per unit aperture area")
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


def patch_mean(w, beam):
    """The mean waveform of the 3 x 3 beams about beam (channel, azimuth step): the last axis kept."""
    c, k = beam
    return w[..., max(c - 1, 0):c + 2, max(k - 1, 0):k + 2, :].mean(axis=(-3, -2))


def plot_waveforms(waves, path, beam):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 4))
    for title, w, o in waves:
        r = (np.arange(w.shape[-1]) + 0.5) * RANGE_BIN
        line, = ax.semilogy(r, np.maximum(patch_mean(w, beam), 1e-12), label="%s: all orders" % title)
        if o is not None:
            ax.semilogy(r, np.maximum(patch_mean(o[1], beam), 1e-12), "--", color=line.get_color(),
                        label="%s: single scattering" % title)
    ax.set_ylim(1e-9, 1e-3)
    ax.set_xlim(0, 35)
    ax.set_xlabel("range (m)")
    ax.set_ylabel("energy per bin per unit aperture area")
    ax.set_title("mean waveform of the 3 x 3 beams about channel %d, azimuth step %d (the pedestrian), %d frames"
                 % (beam[0], beam[1], FRAMES))
    ax.legend(fontsize=7)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)


RANGE_BIN = 0.15
FRAMES = 1


def main():
    global RANGE_BIN, FRAMES
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--passes", type=int, default=64)
    ap.add_argument("--frames", type=int, default=4)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(ROOT, "bench", "results"))
    ap.add_argument("--images", default=os.path.join(ROOT, "docs", "images"))
    a = ap.parse_args()
    FRAMES = a.frames
    if not os.path.exists(DARTSPP):
        sys.exit("build dartspp first (make)")
    with open(SCENE) as f:
        base = json.load(f)
    base.setdefault("integrator", {})["bounce_orders"] = 2
    RANGE_BIN = base["camera"]["range_bin"]
    cam = base["camera"]
    beams = cam["channels"] * cam["azimuth_steps"]
    tmp = tempfile.mkdtemp(prefix="lidar-fog-")
    rows, clouds, waves = [], [], []
    try:
        cw, co, cp, _ = render(scene_for(base, None), tmp, "clear", a.passes, 1, a.threads)
        clear = echoes_by_beam(cp)
        clouds.append(("clear air", cp))
        # the beam toward the pedestrian (x 1.3, z 20, chest height y -0.4): its channel and azimuth step
        el, az = np.degrees(np.arctan2(-0.4, 20.0)), np.degrees(np.arctan2(1.3, 20.0))
        c = int(round((el - cam["elevation"][0]) / (cam["elevation"][1] - cam["elevation"][0]) * (cam["channels"] - 1)))
        k = int((az - cam["azimuth"][0]) / (cam["azimuth"][1] - cam["azimuth"][0]) * cam["azimuth_steps"])
        waves.append(("clear", cw, co))
        for v in VISIBILITIES:
            frames, secs, ms = [], [], []
            for seed in range(1, a.frames + 1):
                w, o, p, sec = render(scene_for(base, v), tmp, "v%g_s%d" % (v, seed), a.passes, seed, a.threads)
                frames.append(echoes_by_beam(p))
                secs.append(sec)
                wsum = w if seed == 1 else wsum + w
                osum = o if seed == 1 else osum + o
                if seed == 1:
                    clouds.append(("visibility %g m" % v, p))
                    # the multiple-scattering excess beyond the near field (r > 3 m): the energy of all orders over
                    # that of single scattering (by fog or a surface), minus 1
                    near = int(3.0 / RANGE_BIN)
                    single = o[1][..., near:].sum()
                    ms.append(w[..., near:].sum() / single - 1.0 if single > 0 else float("nan"))
            waves.append(("V %g m" % v, wsum / a.frames, osum / a.frames))
            stats = [compare(clear, fr) for fr in frames]
            lost = np.mean([s[0] / max(s[1], 1) for s in stats])
            false = np.mean([s[2] / max(s[3], 1) for s in stats])
            false_beams = np.mean([s[4] / beams for s in stats])
            noise, n_noise = intensity_noise(frames, clear)
            rate = beams * a.passes / np.mean(secs)
            rows.append((v, np.log(20.0) / v, lost, false, false_beams, np.mean([s[3] for s in stats]), ms[0], rate,
                         noise, n_noise))
            print("visibility %5g m: lost %.1f %%, false %.1f %% of %d echoes (%.1f %% of the beams), multiple "
                  "scattering %+.1f %%, %.0f beam samples/s, echo noise %.1f %% (%d echoes)" % (v, 100 * lost,
                  100 * false, rows[-1][5], 100 * false_beams, 100 * ms[0], rate, 100 * noise, n_noise), flush=True)
        os.makedirs(a.images, exist_ok=True)
        plot(clouds, os.path.join(a.images, "lidar_fog_points.png"))
        plot_waveforms(waves, os.path.join(a.images, "lidar_fog_waveform.png"), (c, k))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    os.makedirs(a.out, exist_ok=True)
    with open(os.path.join(a.out, "lidar-fog.md"), "w") as f:
        f.write("# A 32-channel lidar on a street in fog (bench/lidar_fog.py)\n\n")
        f.write("%s, %s, %d threads; %d beams (%d channels x %d azimuths), %d passes per frame, %d frames per "
                "visibility; clear-air echoes: %d.\n\n" % (time.strftime("%Y-%m-%d"), cpu_model(), a.threads, beams,
                cam["channels"], cam["azimuth_steps"], a.passes, a.frames, sum(len(t) for t in clear.values())))
        f.write("| visibility (MOR, m) | σt (1/m) | hard echoes lost | false fog echoes | beams with a false echo | "
                "echoes per frame | multiple scattering beyond 3 m | beam samples/s | echo-intensity noise per frame |\n")
        f.write("|---|---|---|---|---|---|---|---|---|\n")
        for v, st, lost, false, fb, n, ms, rate, noise, nn in rows:
            f.write("| %g | %.3f | %.1f %% | %.1f %% | %.1f %% | %.0f | %+.1f %% | %.0f | %.1f %% (%d echoes) |\n" % (
                v, st, 100 * lost, 100 * false, 100 * fb, n, 100 * ms, rate, 100 * noise, nn))
    print("wrote %s and the plots in %s" % (os.path.join(a.out, "lidar-fog.md"), a.images))


if __name__ == "__main__":
    main()
