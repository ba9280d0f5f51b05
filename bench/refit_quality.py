"""How a refit tree's trace speed falls behind a rebuilt one's as a mesh deforms further.

For each amplitude (of the mesh's box diagonal) the mesh is wobbled as `raypack bench` moves
meshes (analysis/motion.h: three sine waves across the box), a simd backend built at rest is
refit (refit_limit=inf), and a backend is built over the deformed mesh; both trace the same
primary (coherent) and random (incoherent) rays, alternately, and the medians are compared
beside the SAH costs. The figures behind BackendOptions::refit_limit (docs/updates.md).

    PYTHONPATH=build/python python3 bench/refit_quality.py ../shared/scenes/dragon.ply
"""

import argparse
import statistics
import time

import numpy as np

import raypack

THREADS = 0  # --threads


def wobbled(rest, amplitude, phase=0.1):
    lo, hi = rest.min(0), rest.max(0)
    length = float(np.linalg.norm(hi.astype(np.float64) - lo))
    w, s = 2 * np.pi * 3 / length, 2 * np.pi * phase
    r = rest.astype(np.float64)
    d = np.stack([np.sin(w * r[:, 1] + s), np.sin(w * r[:, 2] + s), np.sin(w * r[:, 0] + s)], axis=1)
    return (r + amplitude * length * d).astype(np.float32)


def timed(backend, rays, coherent):
    start = time.perf_counter()
    backend.intersect(**rays, coherent=coherent, normals=False, invalid="miss", threads=THREADS)
    return time.perf_counter() - start


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene")
    p.add_argument("--amplitudes", default="0.003,0.01,0.02,0.03,0.05,0.1")
    p.add_argument("--pairs", type=int, default=7, help="alternating timing pairs per ray kind")
    p.add_argument("--threads", type=int, default=0, help="tracing threads (0: every core)")
    a = p.parse_args()
    global THREADS
    THREADS = a.threads
    scene = raypack.load_scene(a.scene)
    rest = scene.vertices(0)
    primary = raypack.primary_rays(scene, 512, 512, order="tiles")  # the renderer's packets
    del primary["pixel"]
    scattered = raypack.random_rays(scene, 1 << 18, seed=5)
    refit = raypack.Backend("simd", scene, refit_limit=float("inf"))
    built_cost = refit.stats["sah_cost"]
    print(f"{a.scene}: {scene.triangle_count} triangles, SAH cost at rest {built_cost:.2f}")
    print(f"{'amplitude':>9} {'refit ms':>9} {'SAH refit/rest':>15} {'SAH rebuilt/rest':>17} "
          f"{'primary refit/rebuilt':>22} {'random refit/rebuilt':>21}")
    for amplitude in [float(x) for x in a.amplitudes.split(",")]:
        scene.set_vertices(0, wobbled(rest, amplitude))
        report = refit.update()
        rebuilt = raypack.Backend("simd", scene)
        ratios = []
        for rays, coherent in ((primary, True), (scattered, False)):
            timed(refit, rays, coherent), timed(rebuilt, rays, coherent)  # warm
            r = [timed(rebuilt, rays, coherent) / timed(refit, rays, coherent) for _ in range(a.pairs)]
            ratios.append(f"{statistics.median(r):.3f} ({min(r):.2f}-{max(r):.2f})")
        print(f"{amplitude:>9} {1e3 * report['seconds']:>9.1f} {refit.stats['sah_cost'] / built_cost:>15.3f} "
              f"{rebuilt.stats['sah_cost'] / built_cost:>17.3f} {ratios[0]:>22} {ratios[1]:>21}")
        scene.set_vertices(0, rest)
        refit.update()


if __name__ == "__main__":
    main()
