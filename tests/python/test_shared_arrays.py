"""Meshes read in place from numpy arrays (Scene.add_triangles(copy=False)): the same hits as the
scene's own copy on both backends, a column slice of a wider array read as it lies, moves written
into the array reaching the backends through vertices_changed and update, the arrays kept alive
by the scene, and the arrays it cannot read in place refused with a message."""

import gc

import numpy as np
import pytest

import raypack
from conftest import assert_same_bits, available_backends


def wavy_grid(n=40):
    """An (n x n)-vertex grid over [-1, 1]^2 at z = 0.1 sin(3x): float32 vertices, int32 triangles."""
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    vertices = np.stack([x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel())], axis=1).astype(np.float32)
    i = np.arange(n - 1)
    a = (i[:, None] * n + i[None, :]).ravel()
    tris = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)])
    return vertices, tris.astype(np.int32)


def down_rays(count=5000, seed=4):
    """Rays from z = 2 straight down onto the grid's square: (count, 6) float32."""
    rng = np.random.default_rng(seed)
    org = np.column_stack([rng.uniform(-0.95, 0.95, (count, 2)), np.full(count, 2.0)])
    dirs = np.tile([0.0, 0.0, -1.0], (count, 1))
    return np.hstack([org, dirs]).astype(np.float32)


def test_in_place_arrays_give_the_hits_of_the_copy(backend_name):
    backend = backend_name
    vertices, tris = wavy_grid()
    # The positions as the first three columns of an (V, 8) array: rows 32 bytes apart.
    wide = np.zeros((len(vertices), 8), np.float32)
    wide[:, :3] = vertices
    wide[:, 3:] = 7.0  # another attribute the scene must not read
    shared, copied = raypack.Scene(), raypack.Scene()
    shared.add_triangles(wide[:, :3], tris.astype(np.uint32), copy=False)
    copied.add_triangles(vertices, tris)
    rays = down_rays()
    a = raypack.Backend(backend, shared).intersect(rays)
    b = raypack.Backend(backend, copied).intersect(rays)
    assert (a["prim_id"] != 0xFFFFFFFF).all()
    assert_same_bits(a, b)
    np.testing.assert_array_equal(shared.vertices(0), vertices)


def test_moves_written_in_place_reach_the_backend_after_vertices_changed(backend_name):
    backend = backend_name
    vertices, tris = wavy_grid()
    scene = raypack.Scene()
    mesh_geometry = scene.add_triangles(vertices, tris, copy=False)
    assert mesh_geometry == 0
    b = raypack.Backend(backend, scene)
    rays = down_rays()
    before = b.intersect(rays)["t"]
    vertices[:, 2] += 0.25  # the grid rises: every ray stops 0.25 earlier
    scene.vertices_changed(0)
    with pytest.raises(raypack.Error, match="update"):
        b.intersect(rays)
    b.update()
    after = b.intersect(rays)["t"]
    np.testing.assert_allclose(before - after, 0.25, atol=1e-5)
    with pytest.raises(raypack.Error, match="vertices_changed"):
        scene.set_vertices(0, vertices)


def test_the_scene_keeps_the_arrays_alive():
    vertices, tris = wavy_grid()
    copied = raypack.Scene()
    copied.add_triangles(vertices, tris)
    name = available_backends()[0]
    scene = raypack.Scene()
    scene.add_triangles(vertices, tris, copy=False)
    b = raypack.Backend(name, scene)
    del vertices, tris, scene  # the backend's scene still views the arrays
    gc.collect()
    junk = [np.full((1600, 3), 9.0, np.float32) for _ in range(50)]  # would take freed memory
    rays = down_rays(1000)
    b.update()  # nothing changed: a no-op
    assert_same_bits(b.intersect(rays), raypack.Backend(name, copied).intersect(rays))
    assert len(junk) == 50


def test_arrays_that_cannot_be_read_in_place_are_refused():
    vertices, tris = wavy_grid()
    scene = raypack.Scene()
    cases = [
        (vertices.astype(np.float64), tris, "vertices: copy=False needs float32, not float64"),
        (vertices, tris.astype(np.int64), "triangles: copy=False needs int32 or uint32, not int64"),
        (np.asfortranarray(vertices), tris, "vertices: copy=False needs each row's 3 values adjacent"),
        (vertices[:, [0, 1]], tris, r"vertices: shape \(1600, 2\) is not \(N, 3\)"),
        (vertices.tolist(), tris, "vertices: copy=False needs a numpy array, not list"),
        (vertices, np.where(tris == 5, 4000, tris), "uses vertex 4000 of 1600"),
        (vertices, np.where(tris == 5, -1, tris), "uses vertex 4294967295 of 1600"),
    ]
    for v, t, message in cases:
        with pytest.raises(raypack.Error, match=message):
            scene.add_triangles(v, t, copy=False)
    assert scene.geometry_count == 0
    vertices[3, 1] = np.nan
    scene.add_triangles(wavy_grid()[0], tris, copy=False)
    with pytest.raises(raypack.Error, match="non-finite"):
        scene.add_triangles(vertices, tris, copy=False)
