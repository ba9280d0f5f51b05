"""Geometry ids and masks: a scene built with Scene() and its add_* calls numbers every mesh,
sphere, plane, polygon and quadric in the order added; hits name the geometry they hit (the one
each ray was aimed at); a geometry's mask against a ray's hides it exactly as a scene built
without it does (Embree's rule: seen when ray mask & geometry mask != 0)."""

import json

import numpy as np
import pytest

import raypack
from conftest import MISS

# The objects of the test scene, in the order they are added, each with a point on it that a
# ray straight down -z from z = 50 meets first (nothing else above it), x apart.
TRIANGLE = ([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], [[0, 1, 2]])  # about x = 0
SPHERE = ([6, 0, 0], 1.0)  # about x = 6
SQUARE = [[11, -1, 1], [13, -1, 1], [13, 1, 1], [11, 1, 1]]  # the polygon, about x = 12
CYLINDER = ([1, 0, 1, 0, 0, 0, 0, 0, 0, -1], [17, -1, -2], [19, 1, 2], (18, 0, 0))  # x^2 + z^2 = 1 about (18, 0, 0)
FLOOR = ([0, 0, 1], 10.0)  # the plane z = -10, under everything
AIMS = [0, 6, 12, 18, 30]  # x of the rays at triangle, sphere, polygon, cylinder, floor alone


def build(skip=()):
    """The test scene without the objects named in `skip`; returns it and the ids add_* gave."""
    scene = raypack.Scene()
    ids = {}
    adds = [("triangle", lambda: scene.add_triangles(*TRIANGLE)), ("sphere", lambda: scene.add_sphere(*SPHERE)),
            ("polygon", lambda: scene.add_polygon(SQUARE)),
            ("quadric", lambda: scene.add_quadric(*CYLINDER[:3], center=CYLINDER[3])),
            ("plane", lambda: scene.add_plane(*FLOOR))]
    for name, add in adds:
        if name not in skip:
            ids[name] = add()
    return scene, ids


def down_at(xs):
    """Rays straight down -z from z = 50 at (x, 0)."""
    origins = np.array([[x, 0, 50] for x in xs], np.float32)
    return origins, np.array([0, 0, -1], np.float32)


def test_each_add_returns_the_next_id_and_hits_name_the_geometry(backend_name):
    scene, ids = build()
    assert list(ids.values()) == [0, 1, 2, 3, 4] and scene.geometry_count == 5
    backend = raypack.Backend(backend_name, scene)
    origins, down = down_at(AIMS + [0])
    directions = np.where(np.arange(6)[:, None] < 5, down, -down)  # the last ray goes up: no hit
    hits = backend.intersect(origins, directions)
    assert hits["geometry_id"].tolist() == [ids[k] for k in ("triangle", "sphere", "polygon", "quadric", "plane")] + [
        MISS]
    np.testing.assert_allclose(hits["t"][:5], [50, 49, 49, 49, 60], rtol=1e-6)
    assert backend.occluded(origins, directions).tolist() == [True] * 5 + [False]


def test_geometry_ids_follow_the_order_of_addition_not_of_prim_ids(backend_name):
    # Scene.from_arrays adds the mesh, then the spheres, then the planes; a mesh added afterwards is
    # the next geometry, while prim_ids number the triangles of every mesh before the analytic
    # primitives.
    scene = raypack.Scene.from_arrays(*TRIANGLE, spheres=[[6, 0, 0, 1]], planes=[[0, 0, 1, 10]])
    assert scene.geometry_count == 3
    assert scene.add_triangles([[29, -1, 0], [31, -1, 0], [30, 1, 0]], [[0, 1, 2]]) == 3
    hits = raypack.Backend(backend_name, scene).intersect(*down_at([0, 6, 15, 30]))
    assert hits["geometry_id"].tolist() == [0, 1, 2, 3]
    assert hits["prim_id"].tolist() == [0, 2, 3, 1]  # triangles first (both meshes), then the sphere, the plane


def test_both_placements_of_an_instanced_mesh_are_one_geometry(tmp_path, backend_name):
    (tmp_path / "tri.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    (tmp_path / "scene.json").write_text(json.dumps({
        "meshes": {"tri": {"file": "tri.obj"}},
        "objects": [{"type": "sphere", "center": [6, 0, 0], "radius": 1},
                    {"type": "instance", "mesh": "tri"},
                    {"type": "instance", "mesh": "tri", "transform": {"translate": [12, 0, 0]}}]}))
    scene = raypack.load_scene(str(tmp_path / "scene.json"))
    assert scene.geometry_count == 2
    hits = raypack.Backend(backend_name, scene).intersect(*down_at([0, 12, 6]))
    assert hits["instance_id"].tolist() == [0, 1, MISS]
    mesh, sphere = hits["geometry_id"][0], hits["geometry_id"][2]
    assert hits["geometry_id"][1] == mesh != sphere and {int(mesh), int(sphere)} == {0, 1}


def test_a_zero_mask_hides_a_geometry_as_if_it_were_not_there(backend_name):
    scene, ids = build()
    backend = raypack.Backend(backend_name, scene)
    rng = np.random.default_rng(9)
    origins = np.column_stack([rng.uniform(-3, 33, 4000), rng.uniform(-3, 3, 4000), np.full(4000, 50)])
    directions = np.column_stack([rng.normal(0, 0.1, 4000), rng.normal(0, 0.1, 4000), -np.ones(4000)])
    origins, directions = origins.astype(np.float32), directions.astype(np.float32)
    for hidden in ("sphere", "polygon", "quadric"):
        scene.set_mask(ids[hidden], 0)
        assert backend.current  # masks are read while tracing: no update
        without, without_ids = build(skip=(hidden,))
        want = raypack.Backend(backend_name, without).intersect(origins, directions)
        got = backend.intersect(origins, directions)
        assert (got["geometry_id"] != ids[hidden]).all() and (want["geometry_id"] != MISS).all()
        renumber = {new: ids[name] for name, new in without_ids.items()}
        assert [renumber[g] for g in want["geometry_id"].tolist()] == got["geometry_id"].tolist(), hidden
        assert got["t"].tobytes() == want["t"].tobytes()
        scene.set_mask(ids[hidden], 0xFFFFFFFF)
    assert scene.mask(ids["sphere"]) == 0xFFFFFFFF


def test_ray_masks_meet_geometry_masks_by_embrees_rule(backend_name):
    scene, ids = build()
    scene.set_mask(ids["sphere"], 0b01)
    scene.set_mask(ids["quadric"], 0b10)
    assert scene.mask(ids["sphere"]) == 1 and scene.mask(ids["triangle"]) == 0xFFFFFFFF
    backend = raypack.Backend(backend_name, scene)
    origins, direction = down_at([6, 6, 6, 6, 18, 18, 18, 18])
    masks = np.array([0b01, 0b10, 0b11, 0b100] * 2, np.uint32)
    hits = backend.intersect(origins, direction, mask=masks)
    sphere, quadric, floor = ids["sphere"], ids["quadric"], ids["plane"]
    assert hits["geometry_id"].tolist() == [sphere, floor, sphere, floor, floor, quadric, quadric, floor]
    blocked = backend.occluded(origins, direction, tfar=55, mask=masks)  # the floor is 60 away
    assert blocked.tolist() == [True, False, True, False, False, True, True, False]
    # One mask for every ray; 0 sees nothing; (H, W) rays with a mask per column.
    assert (backend.intersect(origins, direction, mask=0)["prim_id"] == MISS).all()
    assert backend.intersect(origins, direction, mask=0b10)["geometry_id"].tolist() == [floor] * 4 + [quadric] * 4
    per_column = backend.intersect(origins.reshape(2, 4, 3), direction, mask=masks[:4])
    assert per_column["geometry_id"].tolist() == [[sphere, floor, sphere, floor], [floor, quadric, quadric, floor]]


def test_building_a_scene_changes_its_backends_and_refuses_bad_input():
    scene, ids = build(skip=("plane",))
    backend = raypack.Backend("embree", scene)
    assert scene.add_plane(*FLOOR) == 4
    with pytest.raises(raypack.Error, match="call update"):
        backend.intersect(*down_at([30]))
    backend.update()
    assert backend.intersect(*down_at([30]))["geometry_id"].tolist() == [4]
    for call, message in [
            (lambda: scene.add_triangles(np.eye(3), [[0, 1, 2.0]]),
             "triangles: dtype float64 is not an array of integers (vertex numbers)"),
            (lambda: scene.add_triangles(np.eye(3), [[0, 1, 3]]), "mesh 'arrays': triangle 0 uses vertex 3 of 3"),
            (lambda: scene.add_sphere([0, 0], 1), "center: shape (2,) is not (3,)"),
            (lambda: scene.add_quadric([1, 1, 1], [0, 0, 0], [1, 1, 1]), "coefficients: shape (3,) is not (10,): A .. J"),
            (lambda: scene.add_polygon([[0, 0, 0], [1, 0, 0]]), "polygon: needs at least 3 vertices, got 2"),
            (lambda: scene.set_mask(5, 1), "set_mask: geometry 5 out of range (5 geometries)"),
            (lambda: scene.mask(5), "mask: geometry 5 out of range (5 geometries)")]:
        with pytest.raises(raypack.Error) as caught:
            call()
        assert str(caught.value) == message
    assert scene.geometry_count == 5  # nothing refused was added
