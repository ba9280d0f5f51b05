"""Python.ImportsFromTheInstallTree: `import raypack` with PYTHONPATH at the package that
`cmake --install` put under the prefix given as the argument, its type stubs beside it, and one
ray traced through it (the ray of the README's `raypack trace` example, which hits triangle 56666
of the default scene)."""

import os
import sys

import raypack

prefix = os.path.realpath(sys.argv[1])
assert os.path.realpath(raypack.__file__).startswith(prefix + os.sep), (raypack.__file__, prefix)
package = os.path.dirname(raypack.__file__)
for typing_file in ("_raypack.pyi", "py.typed"):
    assert os.path.isfile(os.path.join(package, typing_file)), typing_file
scene = raypack.load_scene("default")
for name in ("embree", "simd"):
    if name in [b["name"] for b in raypack.backends() if b["available"]]:
        hits = raypack.Backend(name, scene).intersect([0, 3.4, 8.5], [0, -0.27, -1])
        assert hits["prim_id"].tolist() == 56666, (name, hits)
print(f"raypack {raypack.__version__} imported from {raypack.__file__}")
