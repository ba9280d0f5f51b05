"""Threads: the GIL is released while a backend traces, so other Python threads run meanwhile,
and one Backend serves many Python threads at once with the answers of one thread."""

import threading
import time

import numpy as np

import raypack
from conftest import assert_same_bits, seeded_rays


def test_other_python_threads_run_while_a_batch_is_traced(scene):
    backend = raypack.Backend("embree", scene)
    rays = seeded_rays(scene, 400_000)
    backend.intersect(**rays)  # warm up
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    ticker = threading.Thread(target=tick)
    ticker.start()
    time.sleep(0.02)
    start = time.perf_counter()
    for _ in range(3):
        backend.intersect(**rays)
        backend.occluded(**rays)
    end = time.perf_counter()
    done.set()
    ticker.join()
    during = np.array([t for t in ticks if start <= t <= end])
    # Holding the GIL would stop the ticker for a whole call (its ticks would have one gap of
    # the call's length); released, it ticks every millisecond or so throughout.
    gaps = np.diff(np.concatenate([[start], during, [end]]))
    assert gaps.max() < (end - start) / 12, (gaps.max(), end - start)


def test_one_backend_serves_many_threads_at_once(scene, backend_name):
    backend = raypack.Backend(backend_name, scene)
    batches = [seeded_rays(scene, 20_000, seed=s) for s in range(6)]
    want = [backend.intersect(**b) for b in batches]
    got = [None] * len(batches)

    def trace(i):
        got[i] = backend.intersect(**batches[i], threads=1 + i % 2)

    threads = [threading.Thread(target=trace, args=(i,)) for i in range(len(batches))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for w, g in zip(want, got):
        assert_same_bits(g, w)
