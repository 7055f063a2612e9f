"""Bad input raises dartspp.SceneError naming the file or the key, before any work (docs/python.md §4)."""
import json
import subprocess

import numpy as np
import pytest

import dartspp


@pytest.mark.parametrize("change, words", [
    (lambda s: s["integrator"].update(photon_count=-5), ["integrator", "photon_count"]),
    (lambda s: s["camera"].update(fov="wide"), ["camera", "fov"]),
    (lambda s: s["primitives"].append({"type": "mesh", "file": "nowhere.obj", "bsdf": "white"}), ["nowhere.obj"]),
    (lambda s: s["primitives"].append({"type": "quad", "bsdf": "no-such-bsdf"}), ["no-such-bsdf"]),
], ids=["range", "type", "missing-mesh", "missing-bsdf"])
def test_scene_errors_name_the_key(fogbox, change, words):
    change(fogbox)
    with pytest.raises(dartspp.SceneError) as e:
        dartspp.render(fogbox, spp=1)
    for w in words:
        assert w in str(e.value)
    assert "<dict scene>" in str(e.value) or "nowhere.obj" in str(e.value)


def test_file_errors(tmp_path):
    with pytest.raises(dartspp.SceneError, match="no-such-scene.json"):
        dartspp.render(tmp_path / "no-such-scene.json", spp=1)
    bad = tmp_path / "bad.json"
    bad.write_text('{"camera": {"resolution": [8, 8],}')
    with pytest.raises(dartspp.SceneError, match=r"bad.json:1:\d+: malformed JSON"):
        dartspp.render(bad, spp=1)


@pytest.mark.parametrize("kwargs, words", [
    ({"set": {"photon_count": "many"}}, "photon_count"),
    ({"set": ["photon_count"]}, "key=value"),
    ({"set": {"no_such_key": 1}}, "no_such_key"),
    ({"spp": 0, "time": 0}, "nothing would end"),
    ({"spp": -1}, "spp"),
    ({"spp": 2.5}, "spp"),
    ({"time": "10s"}, "time"),
    ({"threads": -1}, "threads"),
    ({"seed": -1}, "seed"),
    ({"reference": np.zeros((3, 4, 3), np.float32)}, "array is 4x3 but the render is 40x30"),
    ({"reference": np.zeros((30, 40), np.float32)}, "(height, width, 3)"),
    ({"reference": "/nonexistent/ref.exr"}, "/nonexistent/ref.exr"),
    ({"max_memory": 1e6}, "memory"),
    ({"progress": 5}, "progress"),
    ({"base_dir": "/tmp"}, None),  # legal for a dict scene: below the same for a file
], ids=lambda v: str(v)[:40])
def test_option_errors(fogbox, kwargs, words):
    kwargs = dict({"spp": 1}, **kwargs)
    if words is None:
        assert dartspp.render(fogbox, **kwargs).passes == 1
        return
    with pytest.raises(dartspp.SceneError, match=None) as e:
        dartspp.render(fogbox, **kwargs)
    assert words in str(e.value)


def test_reference_with_nan(fogbox):
    ref = np.ones((30, 40, 3), np.float32)
    ref[5, 6, 0] = np.inf
    with pytest.raises(dartspp.SceneError, match="NaN or Inf"):
        dartspp.render(fogbox, spp=1, reference=ref)


def test_scene_type_and_base_dir(tmp_path, fogbox):
    with pytest.raises(dartspp.SceneError, match="expected a path or a dict"):
        dartspp.render(42, spp=1)
    path = tmp_path / "s.json"
    path.write_text(json.dumps(fogbox))
    with pytest.raises(dartspp.SceneError, match="base_dir"):
        dartspp.render(path, spp=1, base_dir=tmp_path)


def test_scene_error_is_a_value_error():
    """SceneError is a dartspp.Error and a ValueError, so either catches it."""
    assert issubclass(dartspp.SceneError, dartspp.Error) and issubclass(dartspp.SceneError, ValueError)
    assert issubclass(dartspp.Interrupted, KeyboardInterrupt)


def test_unbounded_scene_refused(fogbox):
    """A scene whose renderer sets no limit (spp 0, a negative timeout), rendered without spp or time, is
    refused; with either it renders."""
    fogbox["renderer"].update(spp=0, timeout="-1")
    with pytest.raises(dartspp.SceneError, match="nothing would end the render"):
        dartspp.render(fogbox)
    assert dartspp.render(fogbox, spp=1).passes == 1


# Issue 48: `render(max_memory=-1 | 0 | 2**70)` rendered where `dartspp render --max-memory` refused. Each value
# goes through both; both must refuse it, with the same message (one parser and check, render.h's options).
SAME_REFUSALS = [("max_memory", -1), ("max_memory", 0), ("max_memory", 2 ** 70), ("max_memory", float("nan")),
                 ("max_memory", float("inf")), ("max_memory", True), ("threads", 2000), ("threads", -1),
                 ("threads", 2.5), ("spp", -1), ("spp", 1.5), ("spp", 2 ** 63), ("time", float("inf")),
                 ("time", float("nan")), ("time", -1), ("seed", -1), ("seed", 2 ** 64), ("seed", 1.5),
                 ("log_every", -1), ("log_every", float("nan"))]


@pytest.mark.parametrize("name, value", SAME_REFUSALS, ids=lambda v: str(v))
def test_options_refused_alike(cli, fogbox, tmp_path, name, value):
    text = repr(value) if isinstance(value, float) else str(value)
    path = tmp_path / "s.json"
    path.write_text(json.dumps(fogbox))
    flag = "--" + name.replace("_", "-")
    cmd = [cli, "render", str(path), flag, text, "--output", str(tmp_path / "o.exr")]
    if name != "spp":
        cmd += ["--spp", "1"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert p.returncode == 2, p.stderr
    line = p.stderr.strip().splitlines()[0]
    assert line.startswith("dartspp render: ")
    with pytest.raises(dartspp.SceneError) as e:
        dartspp.render(fogbox, **dict({"spp": 1}, **{name: value}))
    assert str(e.value) == line[len("dartspp render: "):]
    assert name in str(e.value) and flag in str(e.value)


def test_options_accepted_alike(fogbox):
    """The edges of the ranges are accepted by Python as by the command line (tests/cli/test_cli.c)."""
    assert dartspp.render(fogbox, spp=1, threads=0, max_memory="8G", seed=2 ** 64 - 1, log_every=0).passes == 1


# Issue 48: NaN or Inf in a dict scene gave "<dict scene>:1:62: malformed JSON", naming neither key nor reason.
@pytest.mark.parametrize("change, where, value", [
    (lambda s: s["media"][0].update(sigma_s=float("nan")), "media[0].sigma_s", "nan"),
    (lambda s: s["camera"].update(fov=float("inf")), "camera.fov", "inf"),
    (lambda s: s["media"][0].update(sigma_a=[0.1, np.float32("-inf"), 0.1]), "media[0].sigma_a[1]", "-inf"),
    (lambda s: s["integrator"].update(photon_count=float("nan")), "integrator.photon_count", "nan"),
], ids=["medium", "camera", "numpy-in-list", "integrator"])
def test_dict_scene_nonfinite_names_the_key(fogbox, change, where, value):
    change(fogbox)
    with pytest.raises(dartspp.SceneError) as e:
        dartspp.render(fogbox, spp=1)
    assert str(e.value) == "<dict scene>: %s: %s is not a number a scene may hold (JSON has no NaN or Inf)" % (
        where, value)


def test_dict_scene_numpy_numbers(fogbox):
    """NumPy numbers and arrays in a dict scene are the numbers they hold (json.dumps refused them)."""
    plain = dartspp.render(fogbox, spp=1, seed=3).image
    fogbox["camera"]["fov"] = np.float32(fogbox["camera"]["fov"])
    fogbox["media"][0]["sigma_s"] = np.asarray(fogbox["media"][0]["sigma_s"], np.float64)
    assert np.array_equal(dartspp.render(fogbox, spp=1, seed=3).image, plain)
