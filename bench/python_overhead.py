#!/usr/bin/env python3
"""The cost of a render through Python against the same render by the CLI: the same scene, seed and passes,
runs alternating, several repeats; the images compared bit for bit.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [REPEATS]

For each case: the CLI's wall time (a process: load, render, write the image), the wall time of
dartspp.render in a running Python (load and render, arrays back, no file), and the render time both report
(passes only). Prints a Markdown table, also written to bench/results/python-overhead.md.
"""
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

import dartspp

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CLI = os.path.join(ROOT, "build", "dartspp")
repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 3


def fogbox(w, h):
    with open(os.path.join(ROOT, "scenes", "fogbox", "fogbox.json")) as f:
        s = json.load(f)
    s["camera"]["resolution"] = [w, h]
    s["renderer"].pop("hdr_output_file", None)
    return s


CASES = [("demo fog box 256², 32 passes", fogbox(256, 256), 32),
         ("demo fog box 40×30, 2 passes (a sweep's small point)", fogbox(40, 30), 2)]

rows = []
with tempfile.TemporaryDirectory() as tmp:
    for name, scene, spp in CASES:
        path = os.path.join(tmp, "scene.json")
        with open(path, "w") as f:
            json.dump(scene, f)
        out = os.path.join(tmp, "cli.pfm")
        cli_wall, cli_render, py_wall, py_render = [], [], [], []
        for i in range(repeats):
            t0 = time.monotonic()
            p = subprocess.run([CLI, "render", path, "--spp", str(spp), "--seed", "1", "--threads", "2", "--quiet",
                                "--no-viewer", "--no-cube", "--output", out], check=True, capture_output=True,
                               text=True)
            cli_wall.append(time.monotonic() - t0)
            cli_render.append(float(p.stdout.split("passes in ")[1].split()[0]))
            t0 = time.monotonic()
            r = dartspp.render(path, spp=spp, seed=1, threads=2)
            py_wall.append(time.monotonic() - t0)
            py_render.append(r.seconds)
            same = np.array_equal(r.image, dartspp.read_image(out))
            assert same, "the images differ"
        rows.append((name, cli_wall, py_wall, cli_render, py_render))

table = ["Python against the CLI (%s, %d cores, %s; %d repeats alternating, 2 threads; images equal bit for bit in "
         "every repeat)" % (time.strftime("%Y-%m-%d"), os.cpu_count(), platform.processor() or platform.machine(),
                            repeats), "",
         "| case | CLI wall (s) | Python call wall (s) | Python ÷ CLI, wall | render time CLI / Python (s) |",
         "|---|---|---|---|---|"]
for name, cw, pw, cr, pr in rows:
    table.append("| %s | %s | %s | %.3f | %.3f / %.3f |" % (name, ", ".join("%.3f" % v for v in cw),
                                                          ", ".join("%.3f" % v for v in pw),
                                                          np.median(pw) / np.median(cw), np.median(cr),
                                                          np.median(pr)))
text = "\n".join(table) + "\n"
print(text)
os.makedirs(os.path.join(ROOT, "bench", "results"), exist_ok=True)
with open(os.path.join(ROOT, "bench", "results", "python-overhead.md"), "w") as f:
    f.write(text)
