"""Backend.intersect and Backend.occluded: the C++ backends' hits bit for bit (the raypack
command's hit file on the same rays), the shapes and dtypes of the results, broadcasting, and
every input layout giving the same bits."""

import numpy as np
import pytest

import raypack
from conftest import MISS, assert_same_bits, run_cli, seeded_rays


@pytest.mark.parametrize("coherence", ["incoherent", "coherent"])
def test_hits_equal_the_commands_bit_for_bit(scene, backend_name, raypack_exe, tmp_path, coherence):
    rays = seeded_rays(scene, 20000) if coherence == "incoherent" else raypack.primary_rays(scene, 160, 128)
    raypack.write_rays(tmp_path / "rays.bin", **rays)
    run_cli(raypack_exe, "trace", "--scene", "default", "--rays", tmp_path / "rays.bin", "-o", tmp_path / "hits.bin",
            "--backend", backend_name, "--coherence", coherence, "-q")
    cli = raypack.read_hits(tmp_path / "hits.bin")
    ours = raypack.Backend(backend_name, scene).intersect(**rays, coherent=coherence == "coherent")
    lead = rays["tfar"].shape  # primary_rays: (128, 160), an image; written flat, row by row
    assert set(ours) - set(cli) == {"geometry_id"}  # a hit file has no geometry ids (test_geometry.py)
    assert_same_bits({k: ours[k] for k in cli}, {k: v.reshape(lead + v.shape[1:]) for k, v in cli.items()})
    assert (ours["prim_id"] != MISS).sum() > len(ours["t"]) // 10  # the rays do hit the scene


def test_a_scene_from_arrays_traces_as_the_same_scene_from_a_file(backend_name, raypack_exe, tmp_path):
    rng = np.random.default_rng(3)
    vertices = rng.uniform(-1, 1, size=(300, 3)).astype(np.float32)
    indices = rng.integers(0, len(vertices), size=(400, 3))
    with open(tmp_path / "soup.obj", "w") as f:
        f.writelines(f"v {x:.9g} {y:.9g} {z:.9g}\n" for x, y, z in vertices.tolist())
        f.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in indices.tolist())
    arrays = raypack.Scene.from_arrays(vertices, indices)
    loaded = raypack.load_scene(str(tmp_path / "soup.obj"))
    assert arrays.prim_count == loaded.prim_count == 400
    rays = raypack.random_rays(arrays, 5000, seed=11)
    raypack.write_rays(tmp_path / "rays.bin", **rays)
    run_cli(raypack_exe, "trace", "--scene", tmp_path / "soup.obj", "--rays", tmp_path / "rays.bin", "-o",
            tmp_path / "hits.bin", "--backend", backend_name, "-q")
    hits = raypack.Backend(backend_name, arrays).intersect(**rays)
    from_file = raypack.read_hits(tmp_path / "hits.bin")
    assert_same_bits({k: hits[k] for k in from_file}, from_file)
    assert (hits["geometry_id"] == np.where(hits["prim_id"] == MISS, MISS, 0)).all()  # one mesh: geometry 0
    assert_same_bits(hits, raypack.Backend(backend_name, loaded).intersect(**rays))


def test_analytic_primitives_from_arrays_are_numbered_after_the_triangles(backend_name):
    scene = raypack.Scene.from_arrays([[-1, -1, 0], [1, -1, 0], [0, 1, 0]], [[0, 1, 2]],
                                      spheres=[[0, 0, 5, 1]], planes=[[0, 0, 1, 10]])
    assert scene.prim_count == 3
    hits = raypack.Backend(backend_name, scene).intersect([[0, 0, -5], [0, 0, 10], [5, 5, 0]],
                                                          [[0, 0, 1], [0, 0, -1], [0, 0, -1]])
    assert hits["prim_id"].tolist() == [0, 1, 2]  # the triangle, the sphere (z 4..6), the plane z = -10
    np.testing.assert_allclose(hits["t"], [5, 4, 10], rtol=1e-6)
    np.testing.assert_allclose(hits["ng"][1], [0, 0, 1], atol=1e-6)


def test_results_have_the_documented_shapes_and_dtypes(scene, backend_name):
    rays = seeded_rays(scene, 1000)
    backend = raypack.Backend(backend_name, scene)
    hits = backend.intersect(**rays)
    assert list(hits) == ["t", "prim_id", "u", "v", "instance_id", "geometry_id", "ng"]
    for key, dtype, shape in [("t", np.float32, (1000,)), ("prim_id", np.uint32, (1000,)), ("u", np.float32, (1000,)),
                              ("v", np.float32, (1000,)), ("instance_id", np.uint32, (1000,)),
                              ("geometry_id", np.uint32, (1000,)), ("ng", np.float32, (1000, 3))]:
        assert hits[key].dtype == dtype and hits[key].shape == shape, key
        assert hits[key].flags["C_CONTIGUOUS"] and hits[key].flags["WRITEABLE"] and hits[key].flags["OWNDATA"] is not None
    miss = hits["prim_id"] == MISS
    assert miss.any() and (~miss).any()
    assert np.isinf(hits["t"][miss]).all() and (hits["u"][miss] == 0).all() and (hits["ng"][miss] == 0).all()
    assert (hits["instance_id"] == MISS).all()  # no instances in this scene
    np.testing.assert_allclose(np.linalg.norm(hits["ng"][~miss], axis=1), 1, rtol=1e-5)
    without = backend.intersect(**rays, normals=False)
    assert list(without) == ["t", "prim_id", "u", "v", "instance_id", "geometry_id"]
    assert_same_bits(without, {key: hits[key] for key in without})
    blocked = backend.occluded(**rays)
    assert blocked.dtype == np.bool_ and blocked.shape == (1000,)
    assert (blocked == ~miss).all()  # any hit within [tnear, tfar] exactly where there is a closest one


def test_broadcast_inputs_trace_as_the_arrays_they_stand_for(scene, backend_name):
    backend = raypack.Backend(backend_name, scene)
    n = 777
    rng = np.random.default_rng(5)
    directions = rng.normal(size=(n, 3)).astype(np.float32)
    origin = np.array([0.5, 2.0, 9.0], np.float32)
    tfar = rng.uniform(1, 20, n).astype(np.float32)
    full = backend.intersect(np.tile(origin, (n, 1)), directions, np.zeros(n, np.float32), tfar)
    assert_same_bits(backend.intersect(origin, directions, 0.0, tfar), full)
    assert_same_bits(backend.intersect(origin[None, :], directions, np.zeros(1), tfar), full)
    assert_same_bits(backend.intersect(list(origin), directions, tfar=tfar), full)
    one = backend.intersect(origin, directions[0], tfar=float(tfar[0]))  # a single ray: leading shape ()
    assert one["t"].shape == () and one["ng"].shape == (3,) and backend.occluded(origin, directions[0]).shape == ()
    assert one["t"].tobytes() == full["t"][:1].tobytes()
    assert backend.intersect(origin[None, :], directions[:1])["t"].shape == (1,)  # (1, 3): one ray, shape (1,)
    empty = backend.intersect(np.zeros((0, 3)), np.zeros((0, 3)))
    assert empty["t"].shape == (0,) and empty["ng"].shape == (0, 3) and backend.occluded(empty["ng"], origin).shape == (0,)


def test_every_layout_and_dtype_gives_the_same_bits(scene, backend_name):
    backend = raypack.Backend(backend_name, scene)
    rays = seeded_rays(scene, 3000)
    want = backend.intersect(**rays)
    records = np.concatenate([rays["origins"], rays["tnear"][:, None], rays["directions"], rays["tfar"][:, None]], 1)
    # Columns of one (N, 8) float32 array (strided, not C-contiguous), Fortran order, float64 and big-endian copies.
    views = dict(origins=records[:, 0:3], directions=records[:, 4:7], tnear=records[:, 3], tfar=records[:, 7])
    assert not views["origins"].flags["C_CONTIGUOUS"]
    assert_same_bits(backend.intersect(**views), want)
    assert_same_bits(backend.intersect(np.asfortranarray(rays["origins"]), np.asfortranarray(rays["directions"]),
                                       rays["tnear"], rays["tfar"]), want)
    assert_same_bits(backend.intersect(**{k: v.astype(np.float64) for k, v in rays.items()}), want)
    assert_same_bits(backend.intersect(**{k: v.astype(">f4") for k, v in rays.items()}), want)
    reversed_rays = {k: v[::-1] for k, v in rays.items()}  # negative strides
    assert_same_bits(backend.intersect(**reversed_rays), {k: v[::-1].copy() for k, v in want.items()})
    assert (backend.occluded(**views) == backend.occluded(**rays)).all()


def test_the_thread_count_does_not_change_the_bits(scene, backend_name):
    backend = raypack.Backend(backend_name, scene)
    rays = seeded_rays(scene, 30000)
    want = backend.intersect(**rays, threads=1)
    assert_same_bits(backend.intersect(**rays, threads=2), want)
    assert_same_bits(backend.intersect(**rays), want)
    assert (backend.occluded(**rays, threads=1) == backend.occluded(**rays, threads=2)).all()


def test_ray_files_round_trip_through_numpy(scene, tmp_path):
    rays = seeded_rays(scene, 100)
    for name in ("rays.bin", "rays.csv"):
        raypack.write_rays(tmp_path / name, **rays)
        back = raypack.read_rays(tmp_path / name)
        assert list(back) == ["origins", "directions", "tnear", "tfar"]
        for key in rays:
            assert back[key].dtype == np.float32 and back[key].tobytes() == rays[key].tobytes(), (name, key)


def test_instances_are_named_in_the_hits(tmp_path, backend_name):
    # One triangle (z = 0) stored once and placed twice: at z = 1 and, turned over, at z = 3.
    # Rays down -z from z = 5 meet the placement at z = 3 (instance 1) first, at t = 2; rays
    # beside it (x = 5) miss both. The same triangle's prim_id in either placement.
    (tmp_path / "tri.obj").write_text("v -1 -1 0\nv 1 -1 0\nv 0 1 0\nf 1 2 3\n")
    (tmp_path / "scene.json").write_text(
        '{"meshes": {"tri": {"file": "tri.obj"}}, "objects": ['
        '{"type": "instance", "mesh": "tri", "transform": {"translate": [0, 0, 1]}},'
        '{"type": "instance", "mesh": "tri", "transform": {"rotate": {"axis": [0, 1, 0], "degrees": 180},'
        ' "translate": [0, 0, 3]}}]}')
    scene = raypack.load_scene(str(tmp_path / "scene.json"))
    org = np.array([[0.0, -0.2, 5.0], [5.0, 0.0, 5.0]], dtype=np.float32)
    hits = raypack.Backend(backend_name, scene).intersect(org, np.array([0, 0, -1], dtype=np.float32))
    assert hits["instance_id"].tolist() == [1, MISS]
    assert hits["prim_id"].tolist() == [0, MISS]
    np.testing.assert_allclose(hits["t"][0], 2.0, rtol=1e-6)
    np.testing.assert_allclose(np.abs(hits["ng"][0]), [0, 0, 1], atol=1e-6)
