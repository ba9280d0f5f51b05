"""What the Python module's tests share: the default scene, the backends this machine runs, the
raypack command (RAYPACK_EXE, set by CTest) to compare with, and seeded rays."""

import os
import subprocess

import numpy as np
import pytest

import raypack

MISS = np.uint32(0xFFFFFFFF)


@pytest.fixture(scope="session")
def scene():
    return raypack.load_scene("default")


def available_backends():
    return [b["name"] for b in raypack.backends() if b["available"]]


@pytest.fixture(scope="session", params=available_backends())
def backend_name(request):
    return request.param


@pytest.fixture(scope="session")
def raypack_exe():
    exe = os.environ.get("RAYPACK_EXE")
    assert exe and os.access(exe, os.X_OK), "RAYPACK_EXE must name the raypack command (CTest sets it)"
    return exe


def run_cli(exe, *args, check=True):
    """Runs the raypack command; returns (status, stderr)."""
    done = subprocess.run([exe, *map(str, args)], capture_output=True, text=True)
    if check:
        assert done.returncode == 0, done.stderr
    return done.returncode, done.stderr


def seeded_rays(scene, count, seed=7):
    """The default scene's random rays, plus a few with finite tfar and tnear > 0."""
    rays = raypack.random_rays(scene, count, seed)
    rng = np.random.default_rng(seed)
    rays["tnear"][::5] = rng.uniform(0, 2, size=rays["tnear"][::5].shape).astype(np.float32)
    rays["tfar"][::3] = rng.uniform(2, 30, size=rays["tfar"][::3].shape).astype(np.float32)
    return rays


def assert_same_bits(a, b):
    """Every array of hit dict a equals b's bit for bit, with the same dtype and shape."""
    assert a.keys() == b.keys()
    for key in a:
        assert a[key].dtype == b[key].dtype and a[key].shape == b[key].shape, key
        assert a[key].tobytes() == b[key].tobytes(), key
