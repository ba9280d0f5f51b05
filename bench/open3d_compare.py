#!/usr/bin/env python3
"""raypack's queries side by side with Open3D's RaycastingScene (Debian's python3-open3d):
the same mesh, rays and points through cast_rays / intersect, count_intersections,
compute_distance / distance and compute_signed_distance / signed_distance, with the answers'
agreement and each call's speed (median of --repeats, all threads).

    sudo apt-get install python3-open3d          # not needed by raypack itself
    PYTHONPATH=build/python /usr/bin/python3 bench/open3d_compare.py [mesh.obj ...]

Without a mesh argument: a closed torus made here (and ../shared/scenes/bunny.obj when present).
Prints one table per mesh; docs/queries.md quotes a run."""

import argparse
import os
import platform
import time

import numpy as np

import raypack

try:
    import open3d as o3d
except ImportError as e:  # the comparison needs it; raypack does not
    raise SystemExit(f"open3d_compare.py: {e}: install python3-open3d (Debian) to compare with Open3D")


def torus(R=1.0, r=0.35, n=192, m=96):
    """A closed torus around the y axis, (V, 3) float32 and (T, 3) int32."""
    u, v = np.meshgrid(np.arange(n) * 2 * np.pi / n, np.arange(m) * 2 * np.pi / m, indexing="ij")
    verts = np.stack([(R + r * np.cos(v)) * np.cos(u), r * np.sin(v), (R + r * np.cos(v)) * np.sin(u)], -1)
    i, j = np.meshgrid(np.arange(n), np.arange(m), indexing="ij")
    a, b = i * m + j, ((i + 1) % n) * m + j
    c, d = ((i + 1) % n) * m + (j + 1) % m, i * m + (j + 1) % m
    tris = np.concatenate([np.stack([a, c, b], -1).reshape(-1, 3), np.stack([a, d, c], -1).reshape(-1, 3)])
    return verts.reshape(-1, 3).astype(np.float32), tris.astype(np.int32)


def median_seconds(f, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        f()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), float((max(times) - min(times)) / np.median(times))


def compare(name, verts, tris, repeats, n_rays, n_points):
    lo, hi = verts.min(0), verts.max(0)
    extent = float(np.linalg.norm(hi - lo))
    rng = np.random.default_rng(1)
    centre = (lo + hi) / 2
    origins = (centre + rng.normal(size=(n_rays, 3)) * extent).astype(np.float32)
    directions = (rng.uniform(lo, hi, (n_rays, 3)) - origins).astype(np.float32)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    points = rng.uniform(lo - 0.1 * extent, hi + 0.1 * extent, (n_points, 3)).astype(np.float32)
    rays6 = np.concatenate([origins, directions], axis=1)

    o3s = o3d.t.geometry.RaycastingScene()
    o3s.add_triangles(o3d.core.Tensor(verts), o3d.core.Tensor(tris.astype(np.uint32)))
    o3rays = o3d.core.Tensor(rays6)
    o3points = o3d.core.Tensor(points)
    o3 = {
        "intersect": lambda: o3s.cast_rays(o3rays)["t_hit"].numpy(),
        "count": lambda: o3s.count_intersections(o3rays).numpy(),
        "distance": lambda: o3s.compute_distance(o3points).numpy(),
        "signed": lambda: o3s.compute_signed_distance(o3points).numpy(),
    }
    print(f"\n## {name}: {len(tris)} triangles, {n_rays} rays, {n_points} points\n")
    print("| query | Open3D 0.16 Mquery/s (spread) | raypack backend | Mquery/s (spread) | agreement with Open3D |")
    print("|---|---|---|---|---|")
    o3_answers = {k: f() for k, f in o3.items()}
    for backend in [b["name"] for b in raypack.backends() if b["available"]]:
        s = raypack.Scene()
        s.add_triangles(verts, tris)
        b = raypack.Backend(backend, s)
        rp = {
            "intersect": lambda: b.intersect(rays6, normals=False)["t"],
            "count": lambda: b.count_intersections(rays6),
            "distance": lambda: b.distance(points),
            "signed": lambda: b.signed_distance(points),
        }
        for query, f in rp.items():
            mine, theirs = f(), o3_answers[query]
            n = n_rays if query in ("intersect", "count") else n_points
            if query == "intersect":
                hit_mine, hit_theirs = np.isfinite(mine), np.isfinite(theirs)
                close = np.abs(np.where(hit_mine & hit_theirs, mine - theirs, 0)) <= 1e-4 * extent
                agree = np.mean((hit_mine == hit_theirs) & close)
                what = f"{agree:.4f} of rays (hits: raypack {hit_mine.mean():.3f}, Open3D {hit_theirs.mean():.3f})"
            elif query == "count":
                what = f"{np.mean(mine == theirs):.4f} of rays (mean count raypack {mine.mean():.3f}, Open3D {theirs.mean():.3f})"
            elif query == "distance":
                what = f"max |difference| {np.max(np.abs(mine - theirs)) / extent:.2e} of the extent"
            else:
                clear = np.abs(mine) > 1e-3 * extent
                what = (f"sign equal at {np.mean(np.sign(mine[clear]) == np.sign(theirs[clear])):.4f} of points; "
                        f"inside: raypack {np.mean(mine < 0):.3f}, Open3D {np.mean(theirs < 0):.3f}")
            t_o3, spread_o3 = median_seconds(o3[query], repeats)
            t_rp, spread_rp = median_seconds(f, repeats)
            print(f"| {query} | {n / t_o3 / 1e6:.3f} ({spread_o3:.0%}) | {backend} | {n / t_rp / 1e6:.3f} "
                  f"({spread_rp:.0%}) | {what} |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("meshes", nargs="*", help="OBJ or PLY files (their triangles)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--rays", type=int, default=200000)
    ap.add_argument("--points", type=int, default=50000)
    args = ap.parse_args()
    print(f"raypack {raypack.__version__}, Open3D {o3d.__version__}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} threads")
    meshes = [("torus (closed, made here)", *torus())]
    bunny = os.path.join(os.path.dirname(__file__), "..", "..", "shared", "scenes", "bunny.obj")
    for path in args.meshes or ([bunny] if os.path.exists(bunny) else []):
        m = o3d.io.read_triangle_mesh(path)
        meshes.append((os.path.basename(path), np.asarray(m.vertices, np.float32), np.asarray(m.triangles, np.int32)))
    for name, verts, tris in meshes:
        compare(name, verts, tris, args.repeats, args.rays, args.points)


if __name__ == "__main__":
    main()
