"""raypack.render gives the raypack command's image bit for bit; raypack.diff gives the summary
`raypack diff --json` writes, key for key."""

import json

import numpy as np

import raypack
from conftest import run_cli, seeded_rays


def test_render_gives_the_commands_image(scene, backend_name, raypack_exe, tmp_path):
    run_cli(raypack_exe, "render", "--scene", "default", "--backend", backend_name, "--resolution", "96x64", "--spp", "4",
            "--seed", "3", "-q", "-o", tmp_path / "cli.exr")
    image = raypack.render(scene, backend_name, width=96, height=64, spp=4, seed=3)
    assert image.dtype == np.float32 and image.shape == (64, 96, 3)
    assert image.tobytes() == raypack.read_image(tmp_path / "cli.exr").tobytes()
    raypack.write_image(tmp_path / "py.exr", image)
    assert (tmp_path / "py.exr").read_bytes() == (tmp_path / "cli.exr").read_bytes()
    # A Backend already built gives the same image; the camera can be moved.
    assert raypack.render(scene, raypack.Backend(backend_name, scene), width=96, height=64, spp=4,
                          seed=3).tobytes() == image.tobytes()
    moved = raypack.render(scene, backend_name, width=96, height=64, eye=[0, 3, 12], look_at=[0, 1, 0], fov=30)
    assert moved.tobytes() != image.tobytes()


def test_diff_gives_the_commands_json(scene, raypack_exe, tmp_path):
    rays = seeded_rays(scene, 20000)
    raypack.write_rays(tmp_path / "rays.bin", **rays)
    for args, kwargs in [((), {}), (("-a", "simd", "--variant-a", "watertight", "-b", "reference"),
                                    dict(a="simd", variant_a="watertight", b="reference")),
                         (("--no-reference", "--coherence", "coherent"), dict(reference=False, coherent=True))]:
        if "simd" not in [b["name"] for b in raypack.backends() if b["available"]]:
            break
        run_cli(raypack_exe, "diff", "--scene", "default", "--rays", tmp_path / "rays.bin", "--json",
                tmp_path / "diff.json", "-q", *args)
        ours = raypack.diff(scene, **rays, rays_label=str(tmp_path / "rays.bin"), **kwargs)
        assert ours == json.loads((tmp_path / "diff.json").read_text()), args
    assert ours["count"] == 20000 and set(ours["classes"]) == {"agree", "tie", "hit/miss", "wrong primitive", "t error"}


def test_diff_takes_backends_already_built(scene):
    rays = seeded_rays(scene, 5000)
    embree = raypack.Backend("embree", scene, "robust")
    d = raypack.diff(scene, **rays, a=embree, b=embree)
    assert d["a"] == d["b"] == "embree/robust" and d["agreement"] == 1.0
