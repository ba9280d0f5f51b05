"""Scenes that move from Python: set_vertices, set_transform and Backend.update give the hits of
a backend built afresh over the changed scene; a backend whose scene changed raises until updated."""

import threading
import time

import numpy as np
import pytest

import raypack
from conftest import assert_same_bits


def grid_mesh(n):
    """A wavy (n x n)-vertex grid over [-1, 1]^2: 2 (n - 1)^2 triangles sharing edges."""
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    vertices = np.stack([x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel())], axis=1).astype(np.float32)
    i = np.arange(n - 1)
    a = (i[:, None] * n + i[None, :]).ravel()
    tris = np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)])
    return vertices, tris


def deformed(vertices, amount):
    out = vertices.copy()
    out[:, 2] += amount * np.sin(5 * vertices[:, 0]) * np.cos(4 * vertices[:, 1])
    return out


def rays_at(scene, count=20000, seed=3):
    return raypack.random_rays(scene, count, seed=seed)


def test_set_vertices_then_update_gives_the_hits_of_a_new_backend(backend_name):
    vertices, tris = grid_mesh(60)
    scene = raypack.Scene.from_arrays(vertices, tris)
    backend = raypack.Backend(backend_name, scene)
    rays = rays_at(scene)
    before = backend.intersect(**rays)
    moved = deformed(vertices, 0.3)
    scene.set_vertices(0, moved)
    assert not backend.current
    with pytest.raises(raypack.Error, match=r"mesh 0 has new vertices.*update\(\)"):
        backend.intersect(**rays)
    with pytest.raises(raypack.Error, match=r"update\(\)"):
        backend.occluded(**rays)
    report = backend.update()
    assert backend.current
    assert report["refits"] + report["rebuilds"] == 1 and not report["top"]
    after = backend.intersect(**rays)
    assert_same_bits(after, raypack.Backend(backend_name, scene).intersect(**rays))
    np.testing.assert_array_equal(scene.vertices(0), moved)
    # The deformation moved the surface: some rays now meet it at another distance.
    assert np.any(after["t"] != before["t"])


def test_a_moved_instance_answers_as_a_new_backend(backend_name, tmp_path):
    # Two placements of one mesh (a JSON scene: a declared mesh placed twice is instanced).
    vertices, tris = grid_mesh(12)
    obj = tmp_path / "grid.obj"
    with open(obj, "w") as f:
        for v in vertices:
            f.write(f"v {v[0]} {v[1]} {v[2]}\n")
        for t in tris:
            f.write(f"f {t[0] + 1} {t[1] + 1} {t[2] + 1}\n")
    doc = tmp_path / "two.json"
    doc.write_text(
        '{"meshes": {"grid": {"file": "grid.obj"}}, "objects": ['
        '{"type": "instance", "mesh": "grid", "transform": {"translate": [-1.2, 0, 0]}},'
        '{"type": "instance", "mesh": "grid", "transform": {"translate": [1.2, 0, 0], "scale": 0.5}}]}'
    )
    scene = raypack.load_scene(str(doc))
    assert scene.instance_count == 2
    backend = raypack.Backend(backend_name, scene)
    rays = rays_at(scene)
    m = scene.transform(1)
    assert m.shape == (4, 4) and m[3].tolist() == [0, 0, 0, 1]
    c, s = np.cos(0.7), np.sin(0.7)
    moved = np.array([[c, 0, s, 1.0], [0, 1, 0, 0.3], [-s, 0, c, 0.2], [0, 0, 0, 1]], dtype=np.float32)
    scene.set_transform(1, moved)
    with pytest.raises(raypack.Error, match=r"instance 1 has a new transform"):
        backend.intersect(**rays)
    report = backend.update()
    assert report["top"] and report["refits"] + report["rebuilds"] == 0
    np.testing.assert_array_equal(scene.transform(1), moved)
    assert_same_bits(backend.intersect(**rays), raypack.Backend(backend_name, scene).intersect(**rays))
    scene.set_transform(0, moved[:3])  # the top rows alone
    backend.update()
    assert_same_bits(backend.intersect(**rays), raypack.Backend(backend_name, scene).intersect(**rays))


def test_bad_changes_raise_and_change_nothing():
    vertices, tris = grid_mesh(8)
    scene = raypack.Scene.from_arrays(vertices, tris)
    version = scene.version
    with pytest.raises(raypack.Error, match=r"3 new positions for 64 vertices"):
        scene.set_vertices(0, vertices[:3])
    bad = vertices.copy()
    bad[5, 1] = np.nan
    with pytest.raises(raypack.Error, match=r"vertex 5 has a non-finite coordinate"):
        scene.set_vertices(0, bad)
    with pytest.raises(raypack.Error, match=r"out of range"):
        scene.set_vertices(3, vertices)
    with pytest.raises(raypack.Error, match=r"shape \(64, 2\) is not \(V, 3\)"):
        scene.set_vertices(0, vertices[:, :2])
    with pytest.raises(raypack.Error, match=r"instance 0 out of range"):
        scene.set_transform(0, np.eye(4))
    assert scene.version == version
    np.testing.assert_array_equal(scene.vertices(0), vertices)


def test_changes_from_another_thread_never_give_a_torn_answer(backend_name):
    # A thread moves the mesh back and forth and updates while this one traces: every answer is
    # the answer for one of the two states, or raypack.Error (stale), never a mixture.
    vertices, tris = grid_mesh(40)
    moved = deformed(vertices, 0.4)
    scene = raypack.Scene.from_arrays(vertices, tris)
    rays = rays_at(scene, 4000)
    backend = raypack.Backend(backend_name, scene)
    answers = [raypack.Backend(backend_name, scene).intersect(**rays)["t"]]
    scene.set_vertices(0, moved)
    answers.append(raypack.Backend(backend_name, scene).intersect(**rays)["t"])
    backend.update()
    stop = threading.Event()

    def mover():
        k = 0
        while not stop.is_set():
            scene.set_vertices(0, vertices if k % 2 == 0 else moved)
            backend.update()
            k += 1
            time.sleep(0.001)  # a window in which the backend is current

    t = threading.Thread(target=mover)
    t.start()
    seen = stale = 0
    try:
        for _ in range(5000):
            if seen >= 20:
                break
            try:
                got = backend.intersect(**rays)["t"]
            except raypack.Error:
                stale += 1
                continue
            assert any(np.array_equal(got, a, equal_nan=True) for a in answers)
            seen += 1
    finally:
        stop.set()
        t.join()
    assert seen > 0
