"""Throughput of the Python path against the raypack command, on the same rays and backend.

From the repository root, after .ci/setup.sh (README, "Use it from Python"):

    PYTHONPATH=build/python /usr/bin/python3 bench/python_vs_cli.py --scene ../shared/scenes/bunny.obj

For each ray kind (random: incoherent rays from around the scene; primary: the camera rays of a
1000x1000 image in 4x2-pixel packets, traced as coherent), the rays are made once in numpy and
written to a binary ray file. Then, alternating --runs times:
- the command: `raypack trace --rays FILE` (its own process, scene loaded and backend built each
  time); its figure is the Mrays/s it prints, which times its intersect_parallel alone (no file
  reading or writing, no normals);
- the Python path: Backend.intersect on the numpy arrays (backend built once, one untimed
  warm-up call), the whole call timed from Python: reading the arrays, tracing, the result
  arrays; once as called by default, which also works out the geometric normals ng (the command
  works them out too, for its hit file, but outside the time it prints), and once with
  normals=False, the command's timed work.
It prints the median of each, the Python path's share of the command's rate, and whether the
Python hits are the command's hit file bit for bit. --json writes the same for machines.
"""

import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import raypack


def rays_of_kind(scene, kind, count, seed):
    if kind == "random":
        return raypack.random_rays(scene, count, seed)
    # The smallest image of 4x2-pixel packets with `count` pixels, its first `count` rays, as
    # `raypack diff --kind primary` makes them.
    side = max(2, math.ceil(math.sqrt(count)))
    rays = raypack.primary_rays(scene, (side + 3) // 4 * 4, (side + 1) // 2 * 2, order="tiles")
    del rays["pixel"]
    return {key: value[:count] for key, value in rays.items()}


def command_mrays(args, rays_file, hits_file, coherence):
    done = subprocess.run([args.raypack, "trace", "--scene", args.scene, "--rays", rays_file, "-o", hits_file,
                           "--backend", args.backend, "--variant", args.variant, "--coherence", coherence,
                           "-t", str(args.threads)], capture_output=True, text=True, check=True)
    found = re.search(r"\(([0-9.]+) Mrays/s\)", done.stderr)
    if not found:
        sys.exit(f"python_vs_cli: no Mrays/s in the output of raypack trace: {done.stderr.strip()}")
    return float(found.group(1))


def python_mrays(backend, rays, coherent, threads, normals=True):
    start = time.perf_counter()
    hits = backend.intersect(**rays, coherent=coherent, threads=threads, normals=normals)
    seconds = time.perf_counter() - start
    return len(hits["t"]) / seconds * 1e-6, hits


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="default", help="a scene file, or default (default: %(default)s)")
    parser.add_argument("--backend", default="embree", help="backend name (default: %(default)s)")
    parser.add_argument("--variant", default="default", help="backend variant (default: %(default)s)")
    parser.add_argument("--count", type=int, default=1_000_000, help="rays per kind (default: %(default)s)")
    parser.add_argument("--kind", action="append", choices=["random", "primary"],
                        help="ray kind, repeatable (default: both)")
    parser.add_argument("--runs", type=int, default=7, help="timed runs of each side (default: %(default)s)")
    parser.add_argument("--threads", type=int, default=0, help="worker threads, 0 = all cores (default: 0)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the random rays (default: %(default)s)")
    parser.add_argument("--raypack", default=os.path.join("build", "raypack"), help="the raypack command")
    parser.add_argument("--json", help="also write the results to this file")
    args = parser.parse_args()

    scene = raypack.load_scene(args.scene)
    backend = raypack.Backend(args.backend, scene, args.variant)
    results = []
    with tempfile.TemporaryDirectory(prefix="raypack-bench-") as tmp:
        for kind in args.kind or ["random", "primary"]:
            rays = rays_of_kind(scene, kind, args.count, args.seed)
            coherent = kind == "primary"
            rays_file, hits_file = os.path.join(tmp, f"{kind}.rays"), os.path.join(tmp, f"{kind}.hits")
            raypack.write_rays(rays_file, **rays)
            python_mrays(backend, rays, coherent, args.threads)  # warm-up
            command, python, bare = [], [], []
            for _ in range(args.runs):
                command.append(command_mrays(args, rays_file, hits_file, "coherent" if coherent else "incoherent"))
                rate, hits = python_mrays(backend, rays, coherent, args.threads)
                python.append(rate)
                bare.append(python_mrays(backend, rays, coherent, args.threads, normals=False)[0])
            cli_hits = raypack.read_hits(hits_file)
            same = all(hits[key].tobytes() == cli_hits[key].tobytes() for key in hits)
            result = dict(scene=args.scene, backend=f"{args.backend}/{args.variant}", kind=kind, rays=len(rays["tnear"]),
                          threads=args.threads, runs=args.runs, command_mrays=statistics.median(command),
                          python_mrays=statistics.median(python), python_no_normals_mrays=statistics.median(bare),
                          command_runs=command, python_runs=python, python_no_normals_runs=bare, same_bits=same)
            result["python_share"] = result["python_mrays"] / result["command_mrays"]
            result["python_no_normals_share"] = result["python_no_normals_mrays"] / result["command_mrays"]
            results.append(result)
            print(f"{args.scene} {args.backend}/{args.variant} {kind:7} {result['rays']} rays: raypack trace "
                  f"{result['command_mrays']:.2f} Mrays/s; Python {result['python_mrays']:.2f} Mrays/s "
                  f"({100 * result['python_share']:.1f}%), with normals=False "
                  f"{result['python_no_normals_mrays']:.2f} Mrays/s ({100 * result['python_no_normals_share']:.1f}%); "
                  f"same bits: {'yes' if same else 'NO'}", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(dict(raypack=raypack.__version__, numpy=np.__version__, results=results), f, indent=2)
    return 0 if all(r["same_bits"] for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
