"""raypack: ray casting over numpy arrays through the simd and embree backends.

    import numpy as np, raypack
    scene = raypack.load_scene("bunny.obj")           # or raypack.Scene.from_arrays(vertices, indices)
    backend = raypack.Backend("simd", scene)          # raypack.backends() lists names and variants
    hits = backend.intersect(origins, directions)     # dict of arrays: t, prim_id, u, v, ng
    blocked = backend.occluded(origins, directions, tfar=1.0)

The hit convention is the C++ library's: a hit counts for tnear <= t <= tfar, directions are
never normalized, a miss has prim_id 0xffffffff and t = inf. Errors raise raypack.Error (a
ValueError) with the one-line message of the raypack command. See README.md, "Use it from
Python".
"""

import math  # noqa: F401 -- inspect.signature evaluates the defaults math.inf (tfar) in sys.modules

from ._raypack import (Backend, Error, Scene, __version__, backends, diff, load_scene, pinhole_rays, primary_rays,
                       random_rays, read_hits, read_image, read_rays, render, write_image, write_rays)

__all__ = ["Backend", "Error", "Scene", "__version__", "backends", "diff", "load_scene", "pinhole_rays",
           "primary_rays", "random_rays", "read_hits", "read_image", "read_rays", "render", "write_image",
           "write_rays"]
