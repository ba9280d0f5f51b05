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
        (lambda: backend.intersect(np.zeros((4, 2)), np.zeros((4, 3))), "origins: shape (4, 2) is not (N, 3) or (3,)"),
        (lambda: backend.intersect(np.zeros((4, 3)), np.zeros(3 * 4)), "directions: shape (12,) is not (N, 3) or (3,)"),
        (lambda: backend.intersect(np.zeros(3), np.ones(3), np.zeros((2, 2))), "tnear: shape (2, 2) is not (N,) or a scalar"),
        (lambda: backend.occluded(np.zeros((4, 3)), np.ones((5, 3))), "directions: 5 rays, but origins has 4"),
        (lambda: backend.intersect(np.zeros(3), np.ones((5, 3)), tfar=np.ones(4)), "tfar: 4 rays, but directions has 5"),
        (lambda: raypack.Scene.from_arrays(np.zeros((3, 2)), [[0, 1, 2]]), "vertices: shape (3, 2) is not (V, 3)"),
        (lambda: raypack.Scene.from_arrays(np.zeros((3, 3)), [0, 1, 2]), "indices: shape (3,) is not (T, 3)"),
        (lambda: raypack.Scene.from_arrays(np.zeros((3, 3)), [[0, 1, 2]], spheres=[[0, 0, 0]]),
         "spheres: shape (1, 3) is not (S, 4): centre x, y, z and radius"),
        (lambda: raypack.write_image("x.exr", np.zeros((4, 4))),
         "image: shape (4, 4) is not (height, width, 3) with sides 1..32768"),
    ]
    for call, message in cases:
        assert message_of(call) == message
    with pytest.raises(TypeError, match="^origins: a str is not numbers numpy can make float32$"):
        backend.intersect("up", np.ones(3))
    with pytest.raises(TypeError, match="^indices: a list is not numbers numpy can make int64$"):
        raypack.Scene.from_arrays(np.eye(3), [["a", "b", "c"]])


def test_bad_values_name_the_argument(scene):
    backend = raypack.Backend("embree", scene)
    o, d = np.zeros(3), np.ones(3)
    assert message_of(lambda: backend.intersect(o, d, threads=-1)) == "threads: -1 is negative (0 uses every core)"
    assert message_of(lambda: backend.intersect(o, d, invalid="ignore")) == "invalid: 'ignore' is not warn, raise or miss"
    assert message_of(lambda: raypack.render(scene, sampler="halton")) == (
        "sampler: 'halton' is not uniform, random, stratified or adaptive")
    assert message_of(lambda: raypack.render(scene, spp=0)) == "render: spp 0 must be >= 1"
    assert message_of(lambda: raypack.render(scene, width=0)) == (
        "resolution: 0x768 is out of range (each side 1..32768, at most 2^28 pixels)")
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
