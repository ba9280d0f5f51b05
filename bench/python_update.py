"""Moving a mesh from Python: Scene.set_vertices + Backend.update() against building a new
Backend over the moved mesh, on a 100,000-triangle mesh (a wavy grid) or a model file, for each
backend; both answer the same rays, and their hits are checked to be equal bit for bit.

    PYTHONPATH=build/python python3 bench/python_update.py [--scene FILE] [--runs 9]
"""

import argparse
import statistics
import time

import numpy as np

import raypack


def grid(triangles):
    n = int(np.sqrt(triangles / 2)) + 1
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    vertices = np.stack([x.ravel(), y.ravel(), 0.1 * np.sin(3 * x.ravel())], axis=1).astype(np.float32)
    i = np.arange(n - 1)
    a = (i[:, None] * n + i[None, :]).ravel()
    return vertices, np.concatenate([np.stack([a, a + 1, a + n + 1], 1), np.stack([a, a + n + 1, a + n], 1)])


def frame(rest, k):
    """Frame k of a moderate motion: a sine wave 1% of the box's diagonal travelling over the mesh."""
    length = float(np.linalg.norm(rest.max(0).astype(np.float64) - rest.min(0)))
    out = rest.astype(np.float64)
    out[:, 2] += 0.01 * length * np.sin(2 * np.pi * (3 * rest[:, 0] / length + 0.1 * k))
    return out.astype(np.float32)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", help="a model file (its mesh 0 moves); default: a 100,000-triangle grid")
    p.add_argument("--runs", type=int, default=9)
    p.add_argument("--variants", default="simd/default,embree/default,embree/dynamic",
                   help="backend/variant list (Embree's dynamic variant refits; the others rebuild)")
    a = p.parse_args()
    if a.scene:
        scene = raypack.load_scene(a.scene)
    else:
        vertices, triangles = grid(100_000)
        scene = raypack.Scene.from_arrays(vertices, triangles)
    rest = scene.vertices(0)
    rays = raypack.random_rays(scene, 100_000, seed=2)
    print(f"{scene.triangle_count} triangles; median of {a.runs} frames, each its own motion")
    print(f"{'backend':<16} {'set_vertices+update ms':>23} {'new Backend ms':>15} {'ratio':>7}  same hits")
    available = [b["name"] for b in raypack.backends() if b["available"]]
    for label in a.variants.split(","):
        name, variant = label.split("/")
        if name not in available:
            continue
        backend = raypack.Backend(name, scene, variant)
        updates, builds, same = [], [], True
        for k in range(1, a.runs + 1):
            moved = frame(rest, k)
            start = time.perf_counter()
            scene.set_vertices(0, moved)
            backend.update()
            updates.append(time.perf_counter() - start)
            start = time.perf_counter()
            fresh = raypack.Backend(name, scene, variant)
            builds.append(time.perf_counter() - start)
            h1, h2 = backend.intersect(**rays, invalid="miss"), fresh.intersect(**rays, invalid="miss")
            same &= all(h1[key].tobytes() == h2[key].tobytes() for key in h1)
        u, b = statistics.median(updates), statistics.median(builds)
        print(f"{label:<16} {1e3 * u:>23.2f} {1e3 * b:>15.2f} {b / u:>6.1f}x  {'yes' if same else 'NO'}")
        scene.set_vertices(0, rest)


if __name__ == "__main__":
    main()
