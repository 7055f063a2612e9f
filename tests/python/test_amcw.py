"""The AMCW output through Python (docs/amcw.md): Result.amcw and Result.amcw_depth, the CLI's <stem>_amcw.npy and
<stem>_amcw_depth.npy of the same render bit for bit, and None without the key."""
import json
import subprocess

import numpy as np
import pytest

import dartspp
from conftest import small_fogbox


def test_no_amcw(fogbox):
    """Without renderer.amcw_frequencies the result says so."""
    r = dartspp.render(fogbox, spp=1, seed=3)
    assert r.amcw is None and r.amcw_depth is None and r.amcw_frequencies is None


@pytest.mark.filterwarnings("ignore:.*does not read this key")
def test_amcw_same_arrays_as_cli(cli, tmp_path):
    """The path tracer's AMCW values and depth through Python equal the CLI's files bit for bit; complex64 of
    shape (F, height, width, 3); the f → 0 frequency's modulus is the integral over the demo's gate, the gate image
    (a mean over the gate) times its width (float32 rounding)."""
    scene = small_fogbox(type="path_tracer")
    scene["renderer"]["amcw_frequencies"] = [20, 25, 0.001]
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    out = tmp_path / "cli" / "image.exr"
    subprocess.run([cli, "render", str(path), "--spp", "2", "--seed", "7", "--threads", "2", "--quiet", "--output",
                    str(out)], check=True, capture_output=True)
    r = dartspp.render(scene, spp=2, seed=7, threads=2)
    assert r.amcw_frequencies == [20, 25, 0.001]
    assert r.amcw.shape == (3, 30, 40, 3) and r.amcw.dtype == np.complex64
    assert r.amcw_depth.shape == (30, 40) and r.amcw_depth.dtype == np.float32
    cli_amcw = np.load(tmp_path / "cli" / "image_amcw.npy")
    assert cli_amcw.dtype == np.complex64
    assert np.array_equal(r.amcw, cli_amcw)
    assert np.array_equal(r.amcw_depth, np.load(tmp_path / "cli" / "image_amcw_depth.npy"))
    assert np.abs(r.amcw[0]).max() > 0 and np.all(np.isfinite(r.amcw_depth))
    start, end = r.plan["window"]
    assert end - start > 0
    assert np.allclose(np.abs(r.amcw[2]), r.image * (end - start), rtol=1e-5, atol=1e-9)
