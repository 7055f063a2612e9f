#!/usr/bin/env python3
"""The photon-count study of bench/photon_count.sh, in-process: DARTS photon points at equal time for a grid of
photons per iteration (photon_count x volume_photon_count), the error of each against a reference, as a table
and (with matplotlib) a plot of error against time.

    python3 python/examples/photon_count_study.py [SCENE.json] [--reference REF.exr] [--seconds S]

Without --reference, a DARTS path-tracer render of 8 x S seconds is made first and used as the reference (it is
noisy: for a study to keep, give a long render).
"""
import argparse
import os
import warnings

import dartspp

HERE = os.path.dirname(os.path.abspath(__file__))

p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
p.add_argument("scene", nargs="?", default=os.path.join(HERE, "..", "..", "scenes", "fogbox", "fogbox.json"))
p.add_argument("--reference", help="reference image (EXR or PFM) of the scene")
p.add_argument("--seconds", type=float, default=5.0, help="render time of each point of the grid")
p.add_argument("--plot", default="photon_count_study.png", help="where the plot goes (needs matplotlib)")
args = p.parse_args()

reference = args.reference
if reference is None:
    print("reference: DARTS path tracer, %.0f s" % (8 * args.seconds))
    with warnings.catch_warnings():  # the scene's photon keys, which the path tracer does not read
        warnings.simplefilter("ignore", dartspp.SceneWarning)
        reference = dartspp.render(args.scene, time=8 * args.seconds, set={"type": "path_tracer"}).image

runs = {}
print("| photon_count | volume_photon_count | iterations | MSE | relative MSE |")
print("|---|---|---|---|---|")
for pc in (25000, 100000, 400000):
    for vc in (10000, 40000):
        r = dartspp.render(args.scene, time=args.seconds, seed=1, reference=reference, log_every=0.5,
                           set={"photon_count": pc, "volume_photon_count": vc})
        runs[pc, vc] = r.log
        last = r.log[-1]
        print("| %d | %d | %d | %.4g | %.4g |" % (pc, vc, r.passes, last["mse"], last["rel_mse"]))

try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no plot")
else:
    fig, ax = plt.subplots(figsize=(6, 4))
    for (pc, vc), log in runs.items():
        ax.loglog([row["seconds"] for row in log], [row["mse"] for row in log], label="%d / %d" % (pc, vc))
    ax.set_xlabel("render time (s)")
    ax.set_ylabel("MSE against the reference")
    ax.legend(title="photon_count / volume_photon_count", fontsize=7)
    fig.tight_layout()
    fig.savefig(args.plot, dpi=120)
    print("wrote", args.plot)
