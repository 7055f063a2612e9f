"""A lidar camera through Python (docs/lidar.md, docs/python.md): the waveforms and points arrays equal the command
line's <stem>_waveforms.npy and <stem>_points.npy bit for bit, the PLY holds the same points, the sidecar describes
the waveforms, and a camera that is not a lidar gives None."""
import json
import subprocess

import numpy as np
import pytest

import dartspp
from conftest import small_fogbox

LIDAR = {
    "media": [{"name": "fog", "type": "homogeneous", "sigma_s": 0.05, "sigma_a": 0.01,
               "phase_function": {"type": "henyey_greenstein", "g": 0.7}}],
    "bsdfs": [{"name": "white", "type": "lambert", "albedo": 0.8}],
    "primitives": [{"type": "quad", "bsdf": "white",
                    "transform": {"position": [0, 0, 8.02], "scale": [30, 1, 30], "rotation": [-90, 0, 0]}}],
    "camera": {"type": "lidar", "medium": "fog", "channels": 3, "elevation": [-4, 4], "azimuth": [-10, 10],
               "azimuth_steps": 5, "beam_divergence": 0.004, "receiver_fov": 0.004, "pulse_shape": "box",
               "pulse_width": 0.3, "max_range": 12, "range_bin": 0.15, "echoes": "all",
               "transform": {"position": [0, 0, 0], "look_at": [0, 0, 1], "up": [0, 1, 0]}},
    "integrator": {"type": "path_tracer", "max_bounces": 8},
    "renderer": {"spp": 1},
}


def test_lidar_arrays_equal_the_cli_files(cli, tmp_path):
    path = tmp_path / "lidar.json"
    path.write_text(json.dumps(LIDAR))
    out = tmp_path / "cli" / "scan.exr"
    subprocess.run([cli, "render", str(path), "--spp", "40", "--seed", "3", "--threads", "2", "--quiet",
                    "--output", str(out)], check=True, capture_output=True)
    r = dartspp.render(LIDAR, spp=40, seed=3, threads=2)
    assert r.waveforms.shape == (3, 5, 80) and r.waveforms.dtype == np.float32
    assert r.range_bin == 0.15
    assert np.array_equal(r.waveforms, np.load(tmp_path / "cli" / "scan_waveforms.npy"))
    points = np.load(tmp_path / "cli" / "scan_points.npy")
    assert points.shape[1] == 8 and np.array_equal(r.points, points)
    # every beam sees the wall at z = 8.02: at least one echo per beam, the wall's at range 8.02 / cos
    beams = {(int(p[5]), int(p[6])) for p in points}
    assert len(beams) == 15
    wall = points[np.abs(points[:, 2] - 8.02) < 0.15]
    assert len(wall) == 15
    side = json.loads((tmp_path / "cli" / "scan_waveforms.json").read_text())
    assert side["range_bin"] == 0.15 and side["bins"] == 80
    ply = (tmp_path / "cli" / "scan_points.ply").read_bytes()
    head, body = ply.split(b"end_header\n", 1)
    assert b"element vertex %d" % len(points) in head
    assert len(body) == len(points) * (4 * 4 + 1 + 2 + 2 + 4)


@pytest.mark.filterwarnings("ignore:.*does not read this key")
def test_other_cameras_have_no_waveforms():
    r = dartspp.render(small_fogbox(type="path_tracer"), spp=1, seed=1, threads=1)
    assert r.waveforms is None and r.points is None and r.range_bin is None
