"""What intersect and occluded copy: float32 input, contiguous or strided, is read in place;
other dtypes are converted once. numpy reports its allocations to tracemalloc, so the peak of
traced memory during a call is the results plus whatever numpy had to convert (the per-thread
ray buffers are C++'s and fixed: 32 bytes x 4096 rays a thread, whatever the batch)."""

import tracemalloc

import numpy as np
import pytest

import raypack

N = 200_000
RESULTS = N * (4 + 4 + 4 + 4 + 4 + 4 + 12)  # t, prim_id, u, v, instance_id, geometry_id, ng
CONVERTED = N * (12 + 12)  # float32 copies of origins and directions


@pytest.fixture(scope="module")
def rays():
    scene = raypack.load_scene("default")
    return raypack.Backend("embree", scene), raypack.random_rays(scene, N, seed=2)


def peak_bytes(call):
    """Peak of numpy's (and Python's) traced allocations during call(), over what was there before."""
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        result = call()
        peak = tracemalloc.get_traced_memory()[1] - before
    finally:
        tracemalloc.stop()
    del result
    return peak


def test_float32_rays_are_read_in_place(rays):
    backend, r = rays
    slack = CONVERTED // 4  # far less than any copy of the rays
    assert peak_bytes(lambda: backend.intersect(r["origins"], r["directions"])) < RESULTS + slack
    records = np.concatenate([r["origins"], r["directions"]], axis=1)  # strided columns of one array
    assert peak_bytes(lambda: backend.intersect(records[:, :3], records[:, 3:])) < RESULTS + slack
    assert peak_bytes(lambda: backend.occluded(r["origins"], r["directions"])) < N + slack


def test_other_dtypes_are_converted_once(rays):
    backend, r = rays
    o, d = r["origins"].astype(np.float64), r["directions"].astype(np.float64)
    peak = peak_bytes(lambda: backend.intersect(o, d))
    assert RESULTS + CONVERTED <= peak < RESULTS + CONVERTED * 3 // 2  # the copies are made, and only once


def test_results_are_the_arrays_numpy_allocated(rays):
    backend, r = rays
    hits = backend.intersect(r["origins"][:10], r["directions"][:10])
    for key, array in hits.items():
        assert array.base is None, key  # owns its memory: no view of a buffer kept elsewhere
