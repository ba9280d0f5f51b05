"""Rays in the shapes users have: origins and directions (..., 3) or one (..., 6) array (Open3D's
layout), tnear, tfar and mask broadcast by numpy's rule, and answers of the rays' leading shape.
The oracle is the flat call on numpy's own broadcast of the same arguments (np.broadcast_arrays),
reshaped: the same rays, so the same bits."""

import numpy as np
import pytest

import raypack
from conftest import MISS, assert_same_bits, seeded_rays

H, W = 24, 37  # not multiples of the 4x2 packets nor of the 4096-ray chunks' rows


def image_rays(scene, seed=7):
    """H x W seeded rays: origins and directions (H, W, 3), tnear and tfar (H, W), float32."""
    flat = seeded_rays(scene, H * W, seed)
    return {k: v.reshape((H, W) + v.shape[1:]) for k, v in flat.items()}


def flat_oracle(origins, directions, tnear=0.0, tfar=np.inf):
    """numpy's broadcast of the arguments, as C-order (N, 3) and (N,) float32 arrays, and the
    leading shape."""
    o, d = np.asarray(origins, np.float32), np.asarray(directions, np.float32)
    lead = np.broadcast_shapes(o.shape[:-1], d.shape[:-1], np.shape(tnear), np.shape(tfar))
    flat = {"origins": np.broadcast_to(o, lead + (3,)).reshape(-1, 3),
            "directions": np.broadcast_to(d, lead + (3,)).reshape(-1, 3),
            "tnear": np.broadcast_to(np.asarray(tnear, np.float32), lead).reshape(-1),
            "tfar": np.broadcast_to(np.asarray(tfar, np.float32), lead).reshape(-1)}
    return {k: np.ascontiguousarray(v) for k, v in flat.items()}, lead


def reshaped(hits, lead):
    return {k: v.reshape(lead + v.shape[1:]) for k, v in hits.items()}


def test_image_shaped_rays_answer_as_images(scene, backend_name):
    backend = raypack.Backend(backend_name, scene)
    rays = image_rays(scene)
    flat = backend.intersect(**{k: v.reshape((H * W,) + v.shape[2:]) for k, v in rays.items()})
    assert (flat["prim_id"] != MISS).sum() > H * W // 10 and (flat["prim_id"] == MISS).any()
    want = reshaped(flat, (H, W))
    hits = backend.intersect(**rays)
    assert hits["t"].shape == (H, W) and hits["ng"].shape == (H, W, 3) and hits["prim_id"].shape == (H, W)
    assert_same_bits(hits, want)
    # One (H, W, 6) array of origin and direction (Open3D's layout), tnear and tfar by keyword.
    packed = np.concatenate([rays["origins"], rays["directions"]], axis=-1)
    assert packed.shape == (H, W, 6)
    assert_same_bits(backend.intersect(packed, tnear=rays["tnear"], tfar=rays["tfar"]), want)
    assert_same_bits(backend.intersect(packed.astype(np.float64), tnear=rays["tnear"], tfar=rays["tfar"]), want)
    without = backend.intersect(packed, tnear=rays["tnear"], tfar=rays["tfar"], normals=False)
    assert_same_bits(without, {k: want[k] for k in without})
    blocked = backend.occluded(packed, tnear=rays["tnear"], tfar=rays["tfar"])
    assert blocked.shape == (H, W) and (blocked == (want["prim_id"] != MISS)).all()
    assert (backend.occluded(**rays) == blocked).all()
    # More axes: (2, H/2, W, 3), and its transpose (W, H, 3), a view with no C order.
    assert_same_bits(backend.intersect(**{k: v.reshape((2, H // 2) + v.shape[1:]) for k, v in rays.items()}),
                     reshaped(flat, (2, H // 2, W)))
    transposed = {k: v.swapaxes(0, 1) for k, v in rays.items()}
    assert not transposed["origins"].flags["C_CONTIGUOUS"]
    assert_same_bits(backend.intersect(**transposed), {k: v.swapaxes(0, 1).copy() for k, v in want.items()})


@pytest.mark.parametrize("case", ["shared origin", "tfar per column", "tnear per row", "views"])
def test_arguments_broadcast_by_numpys_rule(scene, backend_name, case):
    backend = raypack.Backend(backend_name, scene)
    rays = image_rays(scene, seed=11)
    rng = np.random.default_rng(4)
    if case == "shared origin":
        args = dict(origins=np.float32([0.5, 2.0, 9.0]), directions=rays["directions"], tfar=np.float32(20))
    elif case == "tfar per column":
        args = dict(origins=rays["origins"], directions=rays["directions"], tfar=rng.uniform(2, 30, W))
    elif case == "tnear per row":
        args = dict(origins=rays["origins"][:1], directions=rays["directions"], tnear=rng.uniform(0, 2, (H, 1)))
    else:  # columns of one (W, H, 8) float32 array seen as (H, W): strided, transposed, reversed rows
        records = np.concatenate([rays["origins"], rays["tnear"][..., None], rays["directions"],
                                  rays["tfar"][..., None]], axis=-1).swapaxes(0, 1).copy().swapaxes(0, 1)[::-1]
        args = dict(origins=records[..., 0:3], directions=records[..., 4:7], tnear=records[..., 3], tfar=records[..., 7])
    flat, lead = flat_oracle(**args)
    assert lead == (H, W)
    want = reshaped(backend.intersect(**flat), lead)
    assert_same_bits(backend.intersect(**args), want)
    assert (backend.occluded(**args) == (want["prim_id"] != MISS)).all()
    gathered = raypack._raypack._gather_rays(**args)
    assert gathered["shape"] == lead and not gathered["has_mask"]
    for key in flat:
        assert gathered[key].tobytes() == flat[key].tobytes(), key


def test_one_ray_and_no_rays_keep_their_shapes(scene):
    backend = raypack.Backend("embree", scene)
    one = backend.intersect(np.float32([0, 3.4, 8.5, 0, -0.27, -1]))  # (6,): one ray, leading shape ()
    assert one["t"].shape == () and one["ng"].shape == (3,) and one["prim_id"] == 56666
    assert_same_bits(one, backend.intersect([0, 3.4, 8.5], [0, -0.27, -1]))
    for lead in [(0,), (0, 4), (3, 0, 2)]:
        hits = backend.intersect(np.zeros(lead + (6,), np.float32))
        assert all(v.shape[:len(lead)] == lead and v.size == 0 for v in hits.values())
        assert hits["ng"].shape == lead + (3,) and backend.occluded(np.zeros(lead + (3,)), np.ones(3)).shape == lead


def test_masks_are_read_per_ray_and_must_be_32_bit_integers():
    o = np.zeros((H, W, 3), np.float32)
    d = np.ones(3, np.float32)
    gather = raypack._raypack._gather_rays
    assert (gather(o, d)["mask"] == 0xFFFFFFFF).all()  # no mask: every ray sees every geometry
    masks = np.arange(H * W, dtype=np.uint32).reshape(H, W) * np.uint32(2654435761)  # values over 2^31
    for given in [masks, masks.astype(np.int64), masks.astype(">u4"), masks.T.copy().T, masks.tolist()]:
        got = gather(o, d, mask=given)
        assert got["has_mask"] and got["shape"] == (H, W)
        assert got["mask"].tobytes() == masks.reshape(-1).tobytes()
    assert (gather(o, d, mask=0x80000001)["mask"] == 0x80000001).all()  # a scalar for every ray
    column = np.arange(W, dtype=np.uint8)
    assert gather(o, d, mask=column)["mask"].tobytes() == np.broadcast_to(column, (H, W)).astype(np.uint32).tobytes()
    assert gather(np.zeros(3), d, mask=masks)["shape"] == (H, W)  # the mask gives the rays their shape too

    def message(mask):
        with pytest.raises(raypack.Error) as caught:
            gather(o, d, mask=mask)
        return str(caught.value)

    assert message(-1) == "mask: -1 is not a 32-bit mask (0 .. 0xffffffff)"
    assert message(np.array([1, 2**32])) == "mask: 4294967296 is not a 32-bit mask (0 .. 0xffffffff)"
    assert message(1.0) == "mask: dtype float64 is not an integer type (a mask is 32 bits: uint32)"
    assert message(np.ones(W, bool)) == "mask: dtype bool is not an integer type (a mask is 32 bits: uint32)"
    assert message(np.ones(H, np.uint32)) == "mask: rays of shape (24,), but origins has rays of shape (24, 37)"
