"""Camera rays as images: pinhole_rays against the pinhole formula of render/camera.h worked out
in float64, primary_rays in image order against pinhole_rays of the scene's own camera, and the
depth, normals and ids of render(aovs=True) against intersect on those rays."""

import json

import numpy as np
import pytest

import raypack
from conftest import MISS

EYE, LOOK_AT, UP, FOV = [0.4, 1.8, 6.0], [0.1, 0.6, -0.5], [0, 1, 0], 38.0


def pinhole_oracle(width, height, eye, look_at, up, fov):
    """The pinhole of render/camera.h in float64: w = unit(look_at - eye), u = unit(w x up),
    v = u x w; pixel (i, r), r from the top, has direction unit(w + x u + y v) with
    x = ((i + 0.5) / W * 2 - 1) aspect tan(fov/2), y = (1 - (r + 0.5) / H * 2) tan(fov/2)."""
    eye, look_at, up = (np.asarray(a, np.float64) for a in (eye, look_at, up))
    w = (look_at - eye) / np.linalg.norm(look_at - eye)
    u = np.cross(w, up)
    u /= np.linalg.norm(u)
    v = np.cross(u, w)
    half = np.tan(np.radians(fov) / 2)
    x = ((np.arange(width) + 0.5) / width * 2 - 1) * (width / height) * half
    y = (1 - (np.arange(height) + 0.5) / height * 2) * half
    d = w + x[None, :, None] * u + y[:, None, None] * v
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


@pytest.fixture(scope="module")
def camera_scene(tmp_path_factory):
    """A scene with a pinhole camera of its own: a plane, a sphere and a tilted triangle mesh."""
    folder = tmp_path_factory.mktemp("camera")
    (folder / "tri.obj").write_text("v -2 0 -2\nv 2 0.5 -2\nv 0 3 -1\nv 1 0 0\nf 1 2 3\nf 1 4 2\n")
    (folder / "scene.json").write_text(json.dumps({
        "camera": {"eye": EYE, "look_at": LOOK_AT, "up": UP, "fov": FOV},
        "objects": [{"type": "plane", "normal": [0, 1, 0], "offset": 0},
                    {"type": "sphere", "center": [-1, 1, 0], "radius": 0.8},
                    {"type": "mesh", "file": "tri.obj"}]}))
    return raypack.load_scene(str(folder / "scene.json"))


@pytest.mark.parametrize("size", [(33, 21), (64, 48), (1, 1)])
def test_pinhole_rays_follow_the_cameras_formula(size):
    width, height = size
    rays = raypack.pinhole_rays(width, height, EYE, LOOK_AT, UP, FOV)
    assert rays.shape == (height, width, 6) and rays.dtype == np.float32
    assert (rays[..., :3] == np.float32(EYE)).all()
    np.testing.assert_allclose(rays[..., 3:], pinhole_oracle(width, height, EYE, LOOK_AT, UP, FOV), atol=2e-6)
    if width % 2 and height % 2:  # the centre pixel looks at look_at
        centre = np.subtract(LOOK_AT, EYE) / np.linalg.norm(np.subtract(LOOK_AT, EYE))
        np.testing.assert_allclose(rays[height // 2, width // 2, 3:], centre, atol=1e-7)
    if width > 1 and height > 1:  # row 0 on top, column 0 on the left (this camera's up is y, its right about x)
        assert rays[0, 0, 4] > rays[-1, 0, 4] and rays[0, 0, 3] < rays[0, -1, 3]


def test_pinhole_rays_refuse_a_camera_the_renderer_refuses():
    with pytest.raises(raypack.Error, match="^camera: eye and look-at coincide$"):
        raypack.pinhole_rays(8, 8, EYE, EYE, UP, FOV)
    with pytest.raises(raypack.Error, match="^camera: vertical fov 180"):
        raypack.pinhole_rays(8, 8, EYE, LOOK_AT, UP, 180)


def test_primary_rays_are_the_scenes_pinhole_in_image_order(camera_scene):
    width, height = 37, 22  # partial tiles and packets: the renderer's order differs most
    rays = raypack.primary_rays(camera_scene, width, height)
    assert rays["origins"].shape == rays["directions"].shape == (height, width, 3)
    assert rays["tnear"].shape == rays["tfar"].shape == (height, width)
    assert (rays["tnear"] == 0).all() and np.isinf(rays["tfar"]).all()
    pinhole = raypack.pinhole_rays(width, height, EYE, LOOK_AT, UP, FOV)
    assert rays["origins"].tobytes() == np.ascontiguousarray(pinhole[..., :3]).tobytes()
    assert rays["directions"].tobytes() == np.ascontiguousarray(pinhole[..., 3:]).tobytes()
    # The renderer's order, flat, and each ray's pixel: the same rays, permuted.
    tiles = raypack.primary_rays(camera_scene, width, height, order="tiles")
    assert tiles["origins"].shape == (height * width, 3) and tiles["pixel"].dtype == np.uint32
    assert sorted(tiles["pixel"].tolist()) == list(range(width * height))
    assert not (tiles["pixel"] == np.arange(width * height)).all()
    assert (tiles["pixel"][:8] == [0, 1, 2, 3, width, width + 1, width + 2, width + 3]).all()  # a 4x2 packet
    for key in ("origins", "directions", "tnear", "tfar"):
        flat = rays[key].reshape((width * height,) + rays[key].shape[2:])
        assert tiles[key].tobytes() == flat[tiles["pixel"]].tobytes(), key
    with pytest.raises(raypack.Error, match="^order: 'rows' is not image or tiles$"):
        raypack.primary_rays(camera_scene, width, height, order="rows")


def test_render_aovs_are_the_primary_hits_of_pinhole_rays(camera_scene, backend_name):
    width, height = 45, 31
    backend = raypack.Backend(backend_name, camera_scene)
    image = raypack.render(camera_scene, backend, width=width, height=height, spp=2, seed=5)
    out = raypack.render(camera_scene, backend, width=width, height=height, spp=2, seed=5, aovs=True)
    assert list(out) == ["rgb", "depth", "normal", "shading_normal", "uv", "prim_id", "instance_id", "geometry_id"]
    assert out["rgb"].tobytes() == image.tobytes()  # the image is the one render gives without aovs
    for key, dtype, shape in [("depth", np.float32, ()), ("normal", np.float32, (3,)), ("uv", np.float32, (2,)),
                              ("prim_id", np.uint32, ()), ("instance_id", np.uint32, ()), ("geometry_id", np.uint32, ())]:
        assert out[key].dtype == dtype and out[key].shape == (height, width) + shape, key
    hits = backend.intersect(raypack.pinhole_rays(width, height, EYE, LOOK_AT, UP, FOV))
    assert hits["t"].shape == (height, width)
    miss = hits["prim_id"] == MISS
    assert miss.any() and len(np.unique(hits["prim_id"][~miss])) == 4  # plane, sphere, both triangles
    assert (out["prim_id"] == hits["prim_id"]).all() and (out["geometry_id"] == hits["geometry_id"]).all()
    assert sorted(np.unique(out["geometry_id"]).tolist()) == [0, 1, 2, MISS]  # the plane, the sphere, the mesh
    assert (out["instance_id"] == MISS).all()
    np.testing.assert_allclose(out["depth"][~miss], hits["t"][~miss], rtol=1e-6)  # unit directions: depth is t
    assert np.isinf(out["depth"][miss]).all() and (out["normal"][miss] == 0).all()
    # The geometric normal, turned towards the camera.
    towards = np.where((np.sum(hits["ng"] * raypack.pinhole_rays(width, height, EYE, LOOK_AT, UP, FOV)[..., 3:],
                               axis=-1) > 0)[..., None], -hits["ng"], hits["ng"])
    np.testing.assert_allclose(out["normal"][~miss], towards[~miss], atol=1e-6)
