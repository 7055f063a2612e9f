"""`pip install ./python` (docs/python.md §1): the package built by pip from the library's sources, offline,
into a new virtual environment, then a render there equal to the command line's. Slow: pip compiles the whole
library (about 15 s on 2 cores, without the release build's LTO); skipped, with the reason, where Python's
venv module or pip is missing (Debian: python3-venv, python3-pip)."""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import dartspp
from conftest import ROOT, small_fogbox

# What pip needs of the checkout: the package folder, the library's sources and headers, and the Makefile (the
# version). A copy, so that pip's build folder is not left in the checkout and nothing else of it is used.
NEEDED = ["python", "src", "include", "Makefile"]

RENDER = textwrap.dedent("""
    import json, sys
    import numpy as np
    import dartspp
    r = dartspp.render(json.loads(sys.argv[1]), spp=3, seed=5, threads=2)
    np.save(sys.argv[2], r.image)
    print(dartspp.__file__)
""")


def missing_tools():
    """Why pip cannot install here (None when it can)."""
    if importlib.util.find_spec("venv") is None:
        return "Python's venv module is missing (Debian: apt-get install python3-venv)"
    if importlib.util.find_spec("pip") is None:
        return "pip is missing (Debian: apt-get install python3-pip)"
    return None


def copy_checkout(dest):
    for name in NEEDED:
        src = os.path.join(ROOT, name)
        if os.path.isdir(src):
            shutil.copytree(src, os.path.join(dest, name),
                            ignore=shutil.ignore_patterns("build", "__pycache__", "*.egg-info"))
        else:
            shutil.copy(src, os.path.join(dest, name))


def clean_env():
    """The environment without the test suite's PYTHONPATH (build/python), so that the venv's Python imports
    the package pip installed and nothing else."""
    env = dict(os.environ)
    env.pop("PYTHONPATH", None)
    env["PIP_NO_INDEX"] = "1"  # offline: pip must not look for anything on a package index
    return env


@pytest.mark.skipif(missing_tools() is not None, reason=missing_tools() or "")
@pytest.mark.skipif(bool(os.environ.get("DARTSPP_QUICK")),
                    reason="make check (DARTSPP_QUICK): the install compiles the whole library (~1 min); make test runs it")
def test_pip_install_renders_as_the_cli(cli, tmp_path):
    """pip install --no-build-isolation --no-index ./python into a venv with the system's site packages (NumPy,
    setuptools); the venv's Python imports the installed package (not build/python) and its render of a small
    scene is the CLI's image, float for float, at the same seed and passes."""
    repo = tmp_path / "repo"
    repo.mkdir()
    copy_checkout(repo)
    venv = tmp_path / "venv"
    env = clean_env()
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)], check=True,
                   env=env)
    py = str(venv / "bin" / "python")
    pip = subprocess.run([py, "-m", "pip", "install", "--no-build-isolation", "--no-index", str(repo / "python")],
                         env=env, capture_output=True, text=True)
    assert pip.returncode == 0, pip.stdout[-3000:] + pip.stderr[-3000:]
    scene = small_fogbox()
    out = tmp_path / "image.npy"
    run = subprocess.run([py, "-c", RENDER, json.dumps(scene), str(out)], env=env, capture_output=True, text=True,
                         cwd=str(tmp_path))
    assert run.returncode == 0, run.stderr[-3000:]
    assert os.path.realpath(run.stdout.strip()).startswith(os.path.realpath(str(venv)))
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    exr = tmp_path / "cli.pfm"
    subprocess.run([cli, "render", str(path), "--spp", "3", "--seed", "5", "--threads", "2", "--quiet",
                    "--no-viewer", "--output", str(exr)], check=True, capture_output=True)
    img = np.load(out)
    assert img.shape == (30, 40, 3) and img.mean() > 0
    assert np.array_equal(img, dartspp.read_image(exr))
