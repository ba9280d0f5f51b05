"""Errors as Python exceptions carrying the one-line messages of the library and the raypack
command: unknown backends and variants, bad shapes and values, scene files and arrays, and the
policy for rays outside the valid-ray rule (misses, with a warning, an error or nothing)."""

import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

import raypack
from conftest import MISS, run_cli


def message_of(call):
    with pytest.raises(raypack.Error) as caught:
        call()
    return str(caught.value)


def test_error_is_a_value_error():
    assert issubclass(raypack.Error, ValueError)


def test_unknown_backends_and_variants_have_the_commands_messages(scene, raypack_exe, tmp_path):
    for args, call in [(["--backend", "nope"], lambda: raypack.Backend("nope", scene)),
                       (["--backend", "simd", "--variant", "robust"], lambda: raypack.Backend("simd", scene, "robust")),
                       (["--backend", "embree", "--variant", "fastest"],
                        lambda: raypack.Backend("embree", scene, variant="fastest"))]:
        status, stderr = run_cli(raypack_exe, "trace", *args, "--rays", tmp_path / "r.bin", "-o", tmp_path / "h.bin",
                                 check=False)
        assert status == 2
        flag = "--variant" if "--variant" in args else "--backend"
        assert stderr == f"raypack: {flag}: {message_of(call)}\n"
    assert message_of(lambda: raypack.Backend("nope", scene)) == "unknown backend 'nope' (available: embree, simd)"
    assert message_of(lambda: raypack.Backend("embree", scene, coherent_method="large")).startswith("embree: ")


def test_bad_shapes_name_the_argument(scene):
    backend = raypack.Backend("embree", scene)
    cases = [
        (lambda: backend.intersect(np.zeros((4, 2)), np.zeros((4, 3))), "origins: shape (4, 2) is not (..., 3)"),
        (lambda: backend.intersect(np.zeros((4, 3)), np.zeros(3 * 4)), "directions: shape (12,) is not (..., 3)"),
        (lambda: backend.intersect(np.zeros(3), np.ones(())), "directions: shape () is not (..., 3)"),
        (lambda: backend.intersect(np.zeros((4, 3))),
         "rays: shape (4, 3) is not (..., 6): origin and direction (or give directions too)"),
        (lambda: backend.occluded(np.zeros((4, 3)), np.ones((5, 3))),
         "directions: rays of shape (5,), but origins has rays of shape (4,)"),
        (lambda: backend.intersect(np.zeros(3), np.ones((5, 3)), tfar=np.ones(4)),
         "tfar: rays of shape (4,), but directions has rays of shape (5,)"),
        (lambda: backend.intersect(np.zeros((2, 5, 6)), tnear=np.zeros((3, 1))),
         "tnear: rays of shape (3, 1), but rays has rays of shape (2, 5)"),
        (lambda: raypack.Scene.from_arrays(np.zeros((3, 2)), [[0, 1, 2]]), "vertices: shape (3, 2) is not (V, 3)"),
        (lambda: raypack.Scene.from_arrays(np.zeros((3, 3)), [0, 1, 2]), "indices: shape (3,) is not (T, 3)"),
        (lambda: raypack.Scene.from_arrays(np.zeros((3, 3)), [[0, 1, 2]], spheres=[[0, 0, 0]]),
         "spheres: shape (1, 3) is not (S, 4): centre x, y, z and radius"),
        (lambda: raypack.write_image("x.exr", np.zeros((4, 4))),
         "image: shape (4, 4) is not (height, width, 3)"),
        (lambda: raypack.write_image("x.exr", np.zeros((0, 4, 3))),
         "image: shape (0, 4, 3): 4x0 is out of range (each side 1..32768, at most 268435456 pixels)"),
        (lambda: raypack.write_image("x.exr", np.broadcast_to(np.float32(0), (40000, 1, 3))),
         "image: shape (40000, 1, 3): 1x40000 is out of range (each side 1..32768, at most 268435456 pixels)"),
    ]
    for call, message in cases:
        assert message_of(call) == message
    with pytest.raises(TypeError, match="^origins: a str is not numbers numpy can make float32$"):
        backend.intersect("up", np.ones(3))
    # Indices are never truncated (2.9 is not vertex 2), not even when whole (2.0), nor wrapped (2^64-1 is not -1).
    for indices, dtype in [([["a", "b", "c"]], "<U1"), ([[0, 1, 2.7]], "float64"), ([[0, 1, 2.0]], "float64"),
                           (np.array([[0, 1, 2]], np.float32), "float32"), (np.ones((1, 3), bool), "bool")]:
        assert message_of(lambda: raypack.Scene.from_arrays(np.eye(3), indices)) == (
            f"indices: dtype {dtype} is not an array of integers (vertex numbers)")
    assert message_of(lambda: raypack.Scene.from_arrays(np.eye(3), np.array([[0, 1, 2**64 - 1]], np.uint64))) == (
        "indices: 18446744073709551615 (triangle 0) is not a vertex index")
    assert raypack.Scene.from_arrays(np.eye(3), np.array([[0, 1, 2]], np.uint16)) is not None


def test_bad_values_name_the_argument(scene):
    backend = raypack.Backend("embree", scene)
    o, d = np.zeros(3), np.ones(3)
    assert message_of(lambda: backend.intersect(o, d, threads=-1)) == "threads: -1 is negative (0 uses every core)"
    assert message_of(lambda: backend.intersect(o, d, invalid="ignore")) == "invalid: 'ignore' is not warn, raise or miss"
    assert message_of(lambda: raypack.render(scene, sampler="halton")) == (
        "sampler: 'halton' is not uniform, random, stratified or adaptive")
    # The command's limits: spp, the image size, and the rays primary_rays and random_rays make.
    assert message_of(lambda: raypack.render(scene, spp=0)) == "spp: 0 is out of range (1..65536)"
    assert message_of(lambda: raypack.render(scene, spp=2**31 - 1)) == "spp: 2147483647 is out of range (1..65536)"
    assert message_of(lambda: raypack.render(scene, width=0)) == (
        "resolution: 0x768 is out of range (each side 1..32768, at most 268435456 pixels)")
    assert message_of(lambda: raypack.primary_rays(scene, 2**31 - 1, 2**31 - 1)) == (
        "camera: resolution: 2147483647x2147483647 is out of range (each side 1..32768, at most 268435456 pixels)")
    assert message_of(lambda: raypack.random_rays(scene, 2**62)) == (
        "random rays: 4611686018427387904 is out of range (0..268435456)")
    assert message_of(lambda: raypack.diff(scene, o, d, tie_tolerance=2)) == "tie_tolerance: 2 is outside [0, 1]"
    other = raypack.Backend("embree", raypack.load_scene("default"))
    assert message_of(lambda: raypack.render(scene, other, width=8, height=8)) == (
        "render: the backend was built over another scene (default, not default)")
    assert message_of(lambda: raypack.diff(scene, o, d, a=None)) == "a: None is not a backend name or a Backend"


def test_scene_files_fail_with_the_commands_message(raypack_exe, tmp_path):
    (tmp_path / "bad.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
    for path in [tmp_path / "bad.obj", tmp_path / "missing.ply", tmp_path / "scene.txt"]:
        ours = message_of(lambda: raypack.load_scene(path))
        assert str(path) in ours
        status, stderr = run_cli(raypack_exe, "info", "--no-backends", path, check=False)
        assert status == 1 and stderr == f"raypack: {ours}\n"


def test_scene_arrays_fail_with_the_scenes_messages():
    triangle = [[0, 1, 2]]
    assert message_of(lambda: raypack.Scene.from_arrays([[0, 0, 0], [1, 0, np.nan], [0, 1, 0]], triangle)) == (
        "mesh 'arrays': vertex 1 has a non-finite coordinate")
    assert message_of(lambda: raypack.Scene.from_arrays(np.eye(3), [[0, 1, 7]])) == (
        "mesh 'arrays': triangle 0 uses vertex 7 of 3")
    assert message_of(lambda: raypack.Scene.from_arrays(np.eye(3), [[0, -1, 2]])) == (
        "indices: -1 (triangle 0) is not a vertex index")
    assert message_of(lambda: raypack.Scene.from_arrays(np.eye(3) * 2.0**31, triangle)).startswith(
        "mesh 'arrays': vertex 0 (2.14748e+09, 0, 0) is outside the supported coordinate range")
    assert message_of(lambda: raypack.Scene.from_arrays(np.eye(3), triangle, spheres=[[0, 0, 0, -1]])).startswith(
        "sphere at (0, 0, 0)")


def test_rays_outside_the_valid_ray_rule_are_misses_with_the_commands_warning(scene, raypack_exe, tmp_path):
    nan = np.float32("nan")
    origins = np.array([[0, 3.4, 8.5], [nan, 0, 0], [0, 3.4, 8.5], [0, 3.4, 8.5]], np.float32)
    directions = np.array([[0, -0.27, -1], [0, 0, -1], [0, 0, 0], [0, -0.27, -1]], np.float32)
    tnear = np.array([0, 0, 0, 5], np.float32)
    tfar = np.array([np.inf, np.inf, np.inf, 1], np.float32)  # the last: tnear > tfar
    raypack.write_rays(tmp_path / "rays.bin", origins, directions, tnear, tfar)
    _, stderr = run_cli(raypack_exe, "trace", "--scene", "default", "--rays", tmp_path / "rays.bin", "-o",
                        tmp_path / "hits.bin")
    cli_line = stderr.splitlines()[-1]
    assert cli_line.startswith(f"raypack: warning: {tmp_path / 'rays.bin'}: 3 of 4 rays are outside the valid-ray rule")
    backend = raypack.Backend("embree", scene)
    for call in ("intersect", "occluded"):
        trace = getattr(backend, call)
        with pytest.warns(RuntimeWarning) as caught:
            result = trace(origins, directions, tnear, tfar)
        assert len(caught) == 1
        assert str(caught[0].message) == f"{call}: " + cli_line.split(": ", 3)[3]
        if call == "intersect":
            assert result["prim_id"].tolist() == [56666, MISS, MISS, MISS]
            assert result["t"].tobytes() == raypack.read_hits(tmp_path / "hits.bin")["t"].tobytes()
        else:
            assert result.tolist() == [True, False, False, False]
        assert message_of(lambda: trace(origins, directions, tnear, tfar, invalid="raise")) == str(caught[0].message)
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            trace(origins, directions, tnear, tfar, invalid="miss")  # no warning
            trace(origins[:1], directions[:1])  # every ray valid: no warning


def test_read_image_refuses_special_files_before_reading(tmp_path):
    """read_image takes the input rule of load_scene: a FIFO, /dev/zero and links to it named
    .png or .exr are refused with its one-line message before anything is read (read_image
    blocked on the FIFO and spun on /dev/zero). Each in a child process with a time limit, so
    that a regression fails here instead of hanging the suite."""
    os.mkfifo(tmp_path / "fifo.png")
    (tmp_path / "zero.png").symlink_to("/dev/zero")
    (tmp_path / "zero.exr").symlink_to("/dev/zero")
    (tmp_path / "folder.exr").mkdir()
    child = "import sys, raypack\ntry:\n    raypack.read_image(sys.argv[1])\nexcept raypack.Error as e:\n    print(e)\n"
    for path, kind in [(tmp_path / "fifo.png", "a FIFO"), (tmp_path / "zero.png", "a character device"),
                       (tmp_path / "zero.exr", "a character device"), ("/dev/zero", "a character device"),
                       (tmp_path / "folder.exr", "a directory")]:
        done = subprocess.run([sys.executable, "-c", child, str(path)], capture_output=True, text=True, timeout=60)
        assert done.stdout == f"{path}: cannot read: not a regular file ({kind})\n", done.stderr


def test_long_calls_stop_at_ctrl_c():
    """A SIGINT during a long occluded() or render() raises KeyboardInterrupt while the call
    runs, not after it has finished. Each call is timed once whole, then interrupted a tenth of
    the way in: the interrupt must arrive well before a whole call's time (a ratio within one
    run of one child, not a time limit)."""
    child = (
        "import os, signal, threading, time\n"
        "import numpy as np, raypack\n"
        "s = raypack.load_scene('default')\n"
        "b = raypack.Backend('embree', s)\n"
        "n = 1 << 25\n"
        "o = np.broadcast_to(np.float32([0, 3.4, 8.5]), (n, 3))\n"
        "d = np.broadcast_to(np.float32([0, -0.27, -1]), (n, 3))\n"
        "calls = {'occluded': lambda: b.occluded(o, d),\n"
        "         'render': lambda: raypack.render(s, width=512, height=512, spp=16)}\n"
        "for name, call in calls.items():\n"
        "    t = time.monotonic(); call(); whole = time.monotonic() - t\n"
        "    threading.Timer(whole / 10, lambda: os.kill(os.getpid(), signal.SIGINT)).start()\n"
        "    t = time.monotonic()\n"
        "    try:\n"
        "        call()\n"
        "        print(name, 'finished')\n"
        "    except KeyboardInterrupt:\n"
        "        print(name, round((time.monotonic() - t) / whole, 2))\n")
    done = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.split("\n")[:2]
    for line, name in zip(lines, ["occluded", "render"]):
        got, fraction = line.split()
        assert got == name and fraction != "finished" and float(fraction) < 0.6, done.stdout


def test_write_image_on_a_full_disk_fails_and_keeps_the_old_file(tmp_path):
    """Every write of the image writer is checked: past a file-size limit (what a full disk does
    to a write, EFBIG for ENOSPC) write_image raises and the old file stays whole."""
    for name in ["old.png", "old.exr", "old.tif"]:
        (tmp_path / name).write_bytes(b"the old file")
        child = ("import resource, signal, sys\nimport numpy as np, raypack\n"
                 "signal.signal(signal.SIGXFSZ, signal.SIG_IGN)\n"
                 "resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048))\n"
                 "image = np.random.default_rng(1).random((256, 256, 3), np.float32)\n"
                 "try:\n    raypack.write_image(sys.argv[1], image)\nexcept raypack.Error as e:\n    print(e)\n")
        done = subprocess.run([sys.executable, "-c", child, str(tmp_path / name)], capture_output=True, text=True,
                              timeout=120)
        assert done.stdout == f"{tmp_path / name}: cannot write: File too large\n", done.stderr
        assert (tmp_path / name).read_bytes() == b"the old file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["old.exr", "old.png", "old.tif"]


def test_read_image_refuses_a_header_claiming_more_pixels_than_it_may(tmp_path):
    """A few bytes of PNG can claim 50000x50000 pixels: the size is checked before memory is
    asked for, with the limit every image has."""
    import struct
    import zlib

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 50000, 50000, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(b"\0")) + chunk(b"IEND", b""))
    (tmp_path / "huge.png").write_bytes(png)
    assert len(png) < 100
    assert message_of(lambda: raypack.read_image(tmp_path / "huge.png")) == (
        f"cannot read '{tmp_path / 'huge.png'}': its size: 50000x50000 is out of range "
        "(each side 1..32768, at most 268435456 pixels)")
