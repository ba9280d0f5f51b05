"""Ownership: a Backend keeps its scene alive by itself, whatever becomes of the Python Scene."""

import gc

import numpy as np

import raypack
from conftest import assert_same_bits


def test_a_backend_outlives_its_scene_object(backend_name):
    rng = np.random.default_rng(1)
    scene = raypack.Scene.from_arrays(rng.uniform(-1, 1, (90, 3)), rng.integers(0, 90, (30, 3)))
    rays = raypack.random_rays(scene, 2000, seed=4)
    backend = raypack.Backend(backend_name, scene)
    want = backend.intersect(**rays)
    del scene
    gc.collect()
    assert_same_bits(backend.intersect(**rays), want)  # under AddressSanitizer too: no freed memory read
    assert backend.scene.name == "arrays" and backend.scene.prim_count == 30
    assert repr(backend) == f"<raypack.Backend {backend_name}/default over 'arrays'>"


def test_results_outlive_the_backend(scene, backend_name):
    backend = raypack.Backend(backend_name, scene)
    hits = backend.intersect([0, 3.4, 8.5], [0, -0.27, -1])
    del backend
    gc.collect()
    assert hits["prim_id"].tolist() == 56666
