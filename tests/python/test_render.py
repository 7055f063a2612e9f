"""dartspp.render against the CLI and its contract: the same images float for float, dict scenes, the
error log, progress, warnings, the GIL, and nothing printed (docs/python.md)."""
import json
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import dartspp
from conftest import small_fogbox

FRAMES = {"frame_num": 4, "start_time": 6.3, "transient_time_width": 0.1}


def cli_render(cli, scene, tmp_path, spp, seed, sets=()):
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    out = tmp_path / "cli" / "image.pfm"
    cmd = [cli, "render", str(path), "--spp", str(spp), "--seed", str(seed), "--threads", "2", "--quiet",
           "--no-viewer", "--output", str(out)]
    for s in sets:
        cmd += ["--set", s]
    subprocess.run(cmd, check=True, capture_output=True)
    cube = tmp_path / "cli" / "image_cube.npy"
    return dartspp.read_image(out), (np.load(cube) if cube.exists() else None)


@pytest.mark.parametrize("method", [
    [],                                                    # DARTS photon points (the scene's own)
    ["enable_guiding=false", "enable_elliptical=false"],  # baseline photon points
    ["type=path_tracer"],                                 # DARTS path tracer (the scene's DARTS keys)
    ["type=path_tracer", "enable_guiding=false", "enable_elliptical=false"],  # the path tracer
    ["volume_photon_type=beams", "enable_guiding=false", "enable_elliptical=false"],  # photon beams
    ["volume_photon_type=beams"],                         # DARTS photon beams
], ids=["darts-pp", "baseline-pp", "darts-pt", "pt", "beams", "darts-beams"])
@pytest.mark.filterwarnings("ignore:.*does not read this key")
def test_same_image_as_cli(cli, tmp_path, method):
    """The gate image and every frame equal the CLI's at the same seed and passes, bit for bit."""
    scene = small_fogbox(**FRAMES)
    img, cube = cli_render(cli, scene, tmp_path, spp=3, seed=7, sets=method)
    r = dartspp.render(scene, spp=3, seed=7, threads=2, set=method)
    assert r.passes == 3 and not r.interrupted
    assert r.image.dtype == np.float32 and r.image.shape == (30, 40, 3)
    assert r.image.mean() > 0
    assert np.array_equal(r.image, img)
    assert r.frames.shape == (4, 30, 40, 3)
    assert np.array_equal(r.frames, cube)
    np.testing.assert_allclose(r.frame_times, [[6.3 + 0.1 * k, 6.4 + 0.1 * k] for k in range(4)], rtol=1e-12)


def test_seed_and_threads(fogbox):
    """Another seed gives another image; another thread count the same image (docs/python.md §3)."""
    a = dartspp.render(fogbox, spp=2, seed=3, threads=1)
    b = dartspp.render(fogbox, spp=2, seed=3, threads=2)
    c = dartspp.render(fogbox, spp=2, seed=4, threads=2)
    assert np.array_equal(a.image, b.image)
    assert not np.array_equal(b.image, c.image)


@pytest.mark.filterwarnings("ignore:.*does not read this key")
def test_dict_scene_with_relative_mesh(tmp_path):
    """A dict scene's relative mesh path resolves against base_dir, and gives the image of the same scene as a
    file in that folder; without base_dir it resolves against the working folder, where the mesh is not."""
    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "wall.obj").write_text(
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 2 3\nf 1 3 4\n")
    scene = small_fogbox(type="path_tracer")
    scene["primitives"].append({"name": "obj-floor", "type": "mesh", "file": "meshes/wall.obj", "bsdf": "white",
                                "transform": {"position": [0, 0.3, 0], "scale": [0.5, 1, 0.5]}})
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    from_dict = dartspp.render(scene, spp=2, base_dir=tmp_path)
    from_file = dartspp.render(tmp_path / "scene.json", spp=2)
    without = {k: v for k, v in scene.items() if k != "primitives"}
    without["primitives"] = [p for p in scene["primitives"] if p["name"] != "obj-floor"]
    plain = dartspp.render(without, spp=2)
    assert np.array_equal(from_dict.image, from_file.image)
    assert not np.array_equal(from_dict.image, plain.image)  # the mesh is in the image
    cwd = os.getcwd()
    try:
        os.chdir("/")
        with pytest.raises(dartspp.SceneError, match="meshes/wall.obj"):
            dartspp.render(scene, spp=1)
    finally:
        os.chdir(cwd)


def test_result_figures(fogbox):
    """The plan, the integrator and the run's figures come back with the images."""
    r = dartspp.render(fogbox, spp=2, set={"photon_count": 5000})
    assert r.integrator == r.plan["integrator"] == "progressive_transient_photon_map"
    assert r.plan["keys"]["photon_count"] == 5000 and r.plan["darts"]["active"]
    assert r.plan["window"] == pytest.approx([6.475, 6.525])
    assert r.passes == 2 and r.seconds > 0
    assert r.stats["photon_paths"] == 2 * 5000
    assert r.stats["camera_rays"] >= 2 * 40 * 30
    assert r.stats["r_vol"] > 0 and r.stats["nonfinite_pixels"] == 0
    assert r.frames is None and r.frame_times.shape == (0, 2)
    assert r.log == []


def test_reference_log(cli, tmp_path, fogbox):
    """With a reference the error log's rows come back; the last row is the final image's error, as
    dartspp.compare gives it and as numpy computes it."""
    ref, _ = cli_render(cli, fogbox, tmp_path, spp=4, seed=11)
    r = dartspp.render(fogbox, spp=4, seed=1, reference=ref, log_every=0)
    assert [row["iterations"] for row in r.log] == [1, 2, 3, 4]
    last = r.log[-1]
    x, y = r.image.astype(np.float64), ref.astype(np.float64)
    assert last["mse"] == pytest.approx(np.mean((x - y) ** 2), rel=1e-9)
    assert last["rel_mse"] == pytest.approx(np.mean((x - y) ** 2 / (y * y + 0.01)), rel=1e-9)
    m = dartspp.compare(r.image, ref)
    assert m["mse"] == pytest.approx(last["mse"], rel=1e-12)
    assert m["pixels"] == 40 * 30 and m["nonfinite"] == 0
    by_path = dartspp.render(fogbox, spp=4, seed=1, reference=tmp_path / "cli" / "image.pfm", log_every=0)
    once = dartspp.render(fogbox, spp=4, seed=1, reference=ref, log_every=1e9)
    assert [row["iterations"] for row in once.log] == [1, 4]  # the first pass, and the end
    same = lambda log: [{k: v for k, v in row.items() if k != "seconds"} for row in log]  # noqa: E731
    assert same(by_path.log) == same(r.log)
    assert np.array_equal(by_path.image, r.image)


def test_compare_refuses_nan():
    a = np.ones((4, 5, 3), np.float32)
    b = a.copy()
    b[2, 3, 1] = np.nan
    with pytest.raises(dartspp.SceneError, match="NaN or Inf"):
        dartspp.compare(a, b)
    assert dartspp.compare(a, a)["mse"] == 0


def test_progress_and_stop(fogbox):
    """progress gets every pass with its time and radii; a true return stops after that pass; an exception
    stops the render and propagates."""
    seen = []

    def progress(passes, seconds, radii):
        seen.append((passes, seconds, radii))
        return passes == 3

    r = dartspp.render(fogbox, spp=50, progress=progress)
    assert [s[0] for s in seen] == [1, 2, 3]
    assert r.passes == 3 and r.interrupted
    assert all(b[1] >= a[1] for a, b in zip(seen, seen[1:]))
    assert seen[-1][2] == (r.stats["r_vol"], r.stats["r_surf"]) and seen[-1][2][0] > 0

    class Stop(Exception):
        pass

    def fail(passes, seconds, radii):
        raise Stop(passes)

    with pytest.raises(Stop):
        dartspp.render(fogbox, spp=50, progress=fail)


def test_gil_released():
    """Another Python thread runs while a render is in C: between the progress calls of passes 1 and 4 it counts
    at least 30 % as fast as when the main thread sleeps (holding the GIL, it would get only the moments of the
    progress calls)."""
    scene = small_fogbox(120, 90, photon_count=60000, volume_photon_count=40000)
    ticks = [0]
    done = threading.Event()

    def count():
        while not done.is_set():
            ticks[0] += 1

    marks = {}

    def progress(passes, seconds, radii):
        marks[passes] = (ticks[0], time.monotonic())

    t = threading.Thread(target=count)
    t.start()
    try:
        t0, c0 = time.monotonic(), ticks[0]
        time.sleep(0.2)
        rate = (ticks[0] - c0) / (time.monotonic() - t0)
        dartspp.render(scene, spp=4, threads=1, progress=progress)
    finally:
        done.set()
        t.join()
    during = (marks[4][0] - marks[1][0]) / (marks[4][1] - marks[1][1])
    assert marks[4][1] - marks[1][1] > 0.05
    assert during > 0.3 * rate, (during, rate)


def test_write_exr(tmp_path):
    """write_exr writes the image and each frame with the CLI's header; they read back equal."""
    r = dartspp.render(small_fogbox(**FRAMES), spp=2)
    paths = r.write_exr(tmp_path / "out" / "img.exr")
    assert [os.path.basename(p) for p in paths] == ["img.exr"] + ["img_%04d.exr" % k for k in range(4)]
    assert np.array_equal(dartspp.read_image(paths[0]), r.image)
    for k in range(4):
        assert np.array_equal(dartspp.read_image(paths[k + 1]), r.frames[k])
    header = open(paths[0], "rb").read(1 << 16)
    assert r.integrator.encode() in header and b"optical path length" in header


def test_keys(cli):
    """keys() is the table of `dartspp keys`: the same keys in the same order."""
    out = subprocess.run([cli, "keys"], check=True, capture_output=True, text=True).stdout
    names = [line.split()[0] for line in out.splitlines() if line and not line.startswith(" ")]
    k = dartspp.keys()
    assert ["%s.%s" % (row["section"], row["name"]) for row in k] == names
    pc = next(row for row in k if row["name"] == "photon_count")
    assert pc["section"] == "integrator" and pc["changes_image"] and pc["meaning"]


def test_nothing_printed(capfd, fogbox):
    """A render, a refused render and a compare print nothing on stdout or stderr (file descriptors 1 and 2)."""
    dartspp.render(fogbox, spp=1, reference=np.zeros((30, 40, 3), np.float32))
    with pytest.raises(dartspp.SceneError):
        dartspp.render(fogbox, spp=1, set={"photon_count": -1})
    dartspp.compare(np.ones((2, 2, 3)), np.ones((2, 2, 3)))
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_warnings_are_python_warnings(capfd, fogbox):
    """A legal but suspicious scene warns through the warnings module (SceneWarning), naming the cause, and
    prints nothing itself."""
    fogbox["primitives"] = [p for p in fogbox["primitives"] if p["type"] != "point"]
    with pytest.warns(dartspp.SceneWarning, match="light") as w:
        r = dartspp.render(fogbox, spp=1)
    assert r.warnings and str(w[0].message) in r.warnings
    assert r.image.max() == 0
    out, err = capfd.readouterr()
    assert out == "" and err == ""


def test_renders_in_threads_side_by_side(fogbox):
    """Two renders in two Python threads at once give the images each gives alone."""
    alone = [dartspp.render(fogbox, spp=2, seed=s, threads=1).image for s in (5, 6)]
    together = [None, None]

    def one(i):
        together[i] = dartspp.render(fogbox, spp=2, seed=5 + i, threads=1).image

    ts = [threading.Thread(target=one, args=(i,)) for i in range(2)]
    for t in ts:
        t.start()
    for t in ts:
        t.join()
    assert all(np.array_equal(a, b) for a, b in zip(alone, together))


def test_eda_table_build_is_silent(capfd, tmp_path):
    """Building an EDA table (the CLI says so on stderr) prints nothing through Python; the table is stored
    all the same."""
    scene = small_fogbox(eda=True, eda_shape=[8, 8, 16], eda_table_dir=str(tmp_path / "tables"))
    r = dartspp.render(scene, spp=1)
    assert r.plan["eda"] and r.passes == 1
    assert len(list((tmp_path / "tables").glob("eda-*.bin"))) == 1
    out, err = capfd.readouterr()
    assert out == "" and err == ""
