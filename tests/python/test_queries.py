"""The queries beyond intersect and occluded, from Python, on both backends, against brute force
in double on closed meshes made here (a torus and a stretched UV sphere, not files of the
repository): closest points and distances, the sign of the signed distance against the
generalised winding number, counts and every hit along rays, masks and geometry ids."""

import numpy as np
import pytest

import raypack

MISS = np.uint32(0xFFFFFFFF)


def torus(R=1.0, r=0.35, n=48, m=24, center=(0.0, 0.0, 0.0)):
    """A closed torus mesh around the y axis: (V, 3) float32 vertices, (T, 3) int32 triangles."""
    u, v = np.meshgrid(np.arange(n) * 2 * np.pi / n, np.arange(m) * 2 * np.pi / m, indexing="ij")
    x = (R + r * np.cos(v)) * np.cos(u)
    z = (R + r * np.cos(v)) * np.sin(u)
    y = r * np.sin(v)
    verts = np.stack([x, y, z], -1).reshape(-1, 3) + np.asarray(center)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, ((i + 1) % n) * m + j
    c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
    tris = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return verts.astype(np.float32), tris.astype(np.int32)


def ball(radius=(0.5, 0.3, 0.4), center=(0.0, 1.2, 0.0), slices=32, stacks=16):
    """A closed UV sphere stretched per axis: poles shared, every edge shared by two triangles."""
    verts = [(0.0, 1.0, 0.0)]
    for k in range(1, stacks):
        th = np.pi * k / stacks
        for s in range(slices):
            ph = 2 * np.pi * s / slices
            verts.append((np.sin(th) * np.cos(ph), np.cos(th), np.sin(th) * np.sin(ph)))
    verts.append((0.0, -1.0, 0.0))
    verts = np.asarray(verts) * np.asarray(radius) + np.asarray(center)
    tris, last = [], len(verts) - 1
    ring = lambda k, s: 1 + (k - 1) * slices + s % slices  # noqa: E731
    for s in range(slices):
        tris.append((0, ring(1, s + 1), ring(1, s)))
        tris.append((last, ring(stacks - 1, s), ring(stacks - 1, s + 1)))
        for k in range(1, stacks - 1):
            tris.append((ring(k, s), ring(k, s + 1), ring(k + 1, s + 1)))
            tris.append((ring(k, s), ring(k + 1, s + 1), ring(k + 1, s)))
    return verts.astype(np.float32), np.asarray(tris, np.int32)


def corners(verts, tris):
    return [verts.astype(np.float64)[tris[:, k]] for k in range(3)]


def point_distances(points, verts, tris):
    """Distance from each point to the triangles, in double: to the plane where the point
    projects inside the triangle, else to the nearest edge."""
    a, b, c = corners(verts, tris)
    p = points.astype(np.float64)[:, None, :]

    def seg(p, s0, s1):
        d = s1 - s0
        t = np.clip(np.sum((p - s0) * d, -1) / np.maximum(np.sum(d * d, -1), 1e-300), 0, 1)
        return np.linalg.norm(p - (s0 + t[..., None] * d), axis=-1)

    n = np.cross(b - a, c - a)
    nn = n / np.linalg.norm(n, axis=-1, keepdims=True)
    h = np.sum((p - a) * nn, -1)
    q = p - h[..., None] * nn
    inside = ((np.sum(np.cross(b - a, q - a) * n, -1) >= 0) & (np.sum(np.cross(c - b, q - b) * n, -1) >= 0) &
              (np.sum(np.cross(a - c, q - c) * n, -1) >= 0))
    edges = np.minimum(np.minimum(seg(p, a, b), seg(p, b, c)), seg(p, c, a))
    return np.where(inside, np.abs(h), edges).min(axis=1)


def winding(points, verts, tris):
    """Generalised winding number (van Oosterom and Strackee's solid angles over 4 pi)."""
    a, b, c = (x[None] - points.astype(np.float64)[:, None, :] for x in corners(verts, tris))
    la, lb, lc = (np.linalg.norm(x, axis=-1) for x in (a, b, c))
    num = np.sum(a * np.cross(b, c), -1)
    den = la * lb * lc + np.sum(a * b, -1) * lc + np.sum(b * c, -1) * la + np.sum(c * a, -1) * lb
    return (2 * np.arctan2(num, den)).sum(axis=1) / (4 * np.pi)


def ray_hits(origins, directions, verts, tris):
    """Every (ray, t) at which a ray meets a triangle, Möller–Trumbore in double."""
    a, b, c = corners(verts, tris)
    o, d = origins.astype(np.float64)[:, None, :], directions.astype(np.float64)[:, None, :]
    e1, e2 = b - a, c - a
    pv = np.cross(d, e2)
    det = np.sum(e1 * pv, -1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / det
        tv = o - a
        u = np.sum(tv * pv, -1) * inv
        qv = np.cross(tv, e1)
        v = np.sum(d * qv, -1) * inv
        t = np.sum(e2 * qv, -1) * inv
    hit = (det != 0) & (u >= 0) & (v >= 0) & (u + v <= 1) & (t >= 0)
    return hit, t


@pytest.fixture(scope="module")
def shapes():
    """Two closed meshes and the scene holding them: torus (geometry 0), ball (geometry 1)."""
    tv, tt = torus()
    bv, bt = ball()
    s = raypack.Scene()
    assert s.add_triangles(tv, tt) == 0
    assert s.add_triangles(bv, bt) == 1
    verts = np.concatenate([tv, bv])
    tris = np.concatenate([tt, bt + len(tv)])
    return s, verts, tris, len(tt)


def random_points(n, seed, half=1.6):
    return np.random.default_rng(seed).uniform(-half, half, (n, 3)).astype(np.float32) + np.float32([0, 0.3, 0])


def test_closest_points_are_the_brute_force_ones(shapes, backend_name):
    s, verts, tris, _ = shapes
    b = raypack.Backend(backend_name, s)
    points = random_points(400, 1)
    extent = float(np.linalg.norm(verts.max(0) - verts.min(0)))
    truth = point_distances(points, verts, tris)
    c = b.closest_points(points)
    assert c["distance"].shape == (400,) and c["points"].shape == (400, 3) and c["uv"].shape == (400, 2)
    np.testing.assert_allclose(c["distance"], truth, atol=1e-5 * extent)
    # The point found lies on the surface, at the distance given.
    np.testing.assert_allclose(point_distances(c["points"], verts, tris), 0, atol=1e-5 * extent)
    np.testing.assert_allclose(np.linalg.norm(c["points"] - points, axis=1), c["distance"], atol=1e-5 * extent)
    # Its triangle, its geometry and its barycentrics name it.
    v0, v1, v2 = (verts[tris[c["prim_id"], k]] for k in range(3))
    u, v = c["uv"][:, :1], c["uv"][:, 1:]
    np.testing.assert_allclose((1 - u - v) * v0 + u * v1 + v * v2, c["points"], atol=1e-5 * extent)
    np.testing.assert_array_equal(c["geometry_id"], (c["prim_id"] >= shapes[3]).astype(np.uint32))
    np.testing.assert_array_equal(b.distance(points), c["distance"])
    # The shape of the points is the shape of the answers; a radius leaves far points unfound.
    grid = b.distance(points.reshape(20, 20, 3))
    assert grid.shape == (20, 20)
    near = b.closest_points(points, radius=0.1)
    far = truth > 0.1 + 1e-5
    assert np.all(near["prim_id"][far] == MISS) and np.all(np.isinf(near["distance"][far]))
    assert np.all(near["prim_id"][truth < 0.1 - 1e-5] != MISS)


def test_signed_distance_has_the_winding_numbers_sign(shapes, backend_name):
    s, verts, tris, _ = shapes
    b = raypack.Backend(backend_name, s)
    points = random_points(1500, 2)
    extent = float(np.linalg.norm(verts.max(0) - verts.min(0)))
    d = point_distances(points, verts, tris)
    inside = winding(points, verts, tris) > 0.5
    sd = b.signed_distance(points)
    np.testing.assert_allclose(np.abs(sd), d, atol=1e-5 * extent)
    clear = d > 1e-3 * extent
    assert inside[clear].sum() > 50, "the points must fall on both sides"
    np.testing.assert_array_equal(sd[clear] < 0, inside[clear])
    np.testing.assert_array_equal(b.inside(points)[clear], inside[clear])


def test_counts_and_every_hit_are_the_brute_force_ones(shapes, backend_name):
    s, verts, tris, _ = shapes
    b = raypack.Backend(backend_name, s)
    rng = np.random.default_rng(3)
    origins = rng.uniform(-2.5, 2.5, (600, 3)).astype(np.float32)
    directions = (random_points(600, 4, 1.0) - origins).astype(np.float32)
    hit, t = ray_hits(origins, directions, verts, tris)
    truth = hit.sum(axis=1)
    counts = b.count_intersections(origins, directions)
    assert counts.dtype == np.uint32 and counts.shape == (600,)
    assert np.count_nonzero(counts != truth) * 300 <= len(origins)
    assert truth.sum() > 600
    every = b.all_hits(origins, directions)
    np.testing.assert_array_equal(np.bincount(every["ray"], minlength=600), counts)
    order = np.lexsort((every["t"], every["ray"]))
    np.testing.assert_array_equal(order, np.arange(len(order)))  # sorted by ray, then t
    for i in np.flatnonzero(counts == truth)[:200]:
        mine = every["t"][every["ray"] == i]
        np.testing.assert_allclose(mine, np.sort(t[i][hit[i]]), rtol=1e-5, atol=1e-6)
    # The nearest two, and the rays of an (H, W, 6) array keep their shape.
    two = b.all_hits(origins, directions, max_per_ray=2)
    np.testing.assert_array_equal(np.bincount(two["ray"], minlength=600), np.minimum(counts, 2))
    rays = np.concatenate([origins, directions], axis=1).reshape(20, 30, 6)
    np.testing.assert_array_equal(b.count_intersections(rays), counts.reshape(20, 30))


def test_masks_hide_a_geometry_and_both_backends_agree(shapes):
    s, verts, tris, torus_tris = shapes
    names = [n for n in ("simd", "embree") if n in [e["name"] for e in raypack.backends() if e["available"]]]
    origins = np.tile(np.float32([0.0, 0.5, 4.0]), (500, 1))
    targets = random_points(500, 5, 1.2)
    directions = targets - origins
    s.set_mask(0, 0b01)
    s.set_mask(1, 0b10)
    try:
        answers = []
        for name in names:
            b = raypack.Backend(name, s)
            seen = b.intersect(origins, directions, mask=0b10)
            hit = seen["prim_id"] != MISS
            assert hit.sum() > 30
            assert np.all(seen["geometry_id"][hit] == 1) and np.all(seen["prim_id"][hit] >= torus_tris)
            both = b.intersect(origins, directions)
            assert np.any(both["geometry_id"] == 0)
            counts = b.count_intersections(origins, directions, mask=0b01)
            hit_t, _ = ray_hits(origins, directions, verts, tris[:torus_tris])
            assert np.count_nonzero(counts != hit_t.sum(axis=1)) * 300 <= len(origins)
            answers.append(seen["prim_id"])
        for other in answers[1:]:
            np.testing.assert_array_equal(other, answers[0])
    finally:
        s.set_mask(0, 0xFFFFFFFF)
        s.set_mask(1, 0xFFFFFFFF)


def test_closest_points_refuse_quadrics_and_bad_points(backend_name):
    s = raypack.Scene()
    s.add_quadric([1, 1, 1, 0, 0, 0, 0, 0, 0, -1], (-1, -1, -1), (1, 1, 1))  # a unit sphere, as a quadric
    b = raypack.Backend(backend_name, s)
    with pytest.raises(raypack.Error, match="quadric"):
        b.closest_points(np.zeros((1, 3), np.float32))
    with pytest.raises(raypack.Error, match=r"points: shape \(4, 2\) is not \(\.\.\., 3\)"):
        b.distance(np.zeros((4, 2), np.float32))
