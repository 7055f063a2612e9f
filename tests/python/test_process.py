"""The render inside a Python process: Ctrl-C (SIGINT) and memory over many renders (docs/python.md §5)."""
import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np

import dartspp
from conftest import ROOT, small_fogbox

CHILD = textwrap.dedent("""
    import json, signal, sys, time
    import numpy as np
    import dartspp
    # Python's own handler, as in a terminal: a parent that ignores SIGINT (a background job, CI) passes the
    # ignore on, and a process that ignores SIGINT is not interrupted (docs/python.md §5)
    signal.signal(signal.SIGINT, signal.default_int_handler)
    scene = json.loads(sys.argv[1])
    def progress(passes, seconds, radii):
        if passes == 2:
            print("started", flush=True)
    try:
        dartspp.render(scene, time=60, progress=progress)
        print("finished")
    except dartspp.Interrupted as e:
        r = e.result
        print("interrupted", time.monotonic(), r.passes, r.interrupted, bool(np.isfinite(r.image).all()),
              float(r.image.mean()), flush=True)
""")


def test_ctrl_c_stops_within_a_second_with_the_completed_passes():
    """SIGINT during a 60 s render: dartspp.Interrupted within a second, carrying the completed passes; the
    Python handler is back afterwards (a second SIGINT is a plain KeyboardInterrupt)."""
    scene = small_fogbox(160, 120, photon_count=200000, volume_photon_count=150000)
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "build", "python"))
    child = subprocess.Popen([sys.executable, "-c", CHILD, __import__("json").dumps(scene)], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "started"
        time.sleep(0.3)
        sent = time.monotonic()
        child.send_signal(signal.SIGINT)
        line = child.stdout.readline().split()
        child.wait(timeout=20)
    finally:
        child.kill()
    assert line and line[0] == "interrupted", child.stderr.read()
    stopped, passes, flagged, finite, mean = float(line[1]), int(line[2]), line[3], line[4], float(line[5])
    assert stopped - sent < 1.0
    assert passes >= 2 and flagged == "True" and finite == "True" and mean > 0
    assert child.returncode == 0


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_no_leak_over_100_renders():
    """100 small renders with frames and an error log: resident memory after the last is within 4 MiB of
    after the 10th (one render's arrays are 0.4 MiB, so a leak of them would add 36 MiB)."""
    scene = small_fogbox(80, 60, frame_num=8, start_time=6.3, transient_time_width=0.05)
    ref = np.zeros((60, 80, 3), np.float32)
    for i in range(100):
        r = dartspp.render(scene, spp=1, seed=i, threads=2, reference=ref)
        assert r.frames.shape == (8, 60, 80, 3)
        if i == 9:
            base = rss_bytes()
    grown = rss_bytes() - base
    print("resident memory: %.1f MiB after 10 renders, %+.2f MiB after 100" % (base / 2**20, grown / 2**20))
    assert grown < 4 * 2**20


def test_example_runs(tmp_path):
    """python/examples/photon_count_study.py end to end on a small scene, briefly: its table has the six
    points of the grid, each with a positive error."""
    scene = tmp_path / "small.json"
    scene.write_text(__import__("json").dumps(small_fogbox(48, 36)))
    env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "build", "python"))
    out = subprocess.run([sys.executable, os.path.join(ROOT, "python", "examples", "photon_count_study.py"),
                          str(scene), "--seconds", "0.3", "--plot", str(tmp_path / "plot.png")], env=env,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    rows = [line for line in out.stdout.splitlines() if line.startswith("| ") and line[2].isdigit()]
    assert len(rows) == 6
    assert all(float(r.split("|")[4]) > 0 for r in rows)
