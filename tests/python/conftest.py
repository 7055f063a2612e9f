"""Fixtures of the Python package's tests: the repository's paths and a small fog box as a dict scene.

The package under test is the one built in build/python (tests/run_tests.sh puts it first on PYTHONPATH);
the CLI it is compared against is build/dartspp.
"""
import copy
import json
import os

import pytest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.path.join(ROOT, "build", "dartspp")


def small_fogbox(width=40, height=30, **integrator):
    """scenes/fogbox/fogbox.json at a small size (the demo's fog box: a forward-boundary fog volume, six
    quads, two boxes, a point light), with integrator keys replaced."""
    with open(os.path.join(ROOT, "scenes", "fogbox", "fogbox.json")) as f:
        scene = json.load(f)
    scene["camera"]["resolution"] = [width, height]
    scene["integrator"].update({"photon_count": 4000, "volume_photon_count": 3000})
    scene["integrator"].update(integrator)
    scene["renderer"].pop("hdr_output_file", None)
    return scene


@pytest.fixture
def fogbox():
    return copy.deepcopy(small_fogbox())


@pytest.fixture
def cli():
    if not os.access(CLI, os.X_OK):
        pytest.fail("build/dartspp is not built (make build/dartspp)")
    return CLI
