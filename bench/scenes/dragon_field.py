#!/usr/bin/python3
"""Writes a JSON scene of one mesh placed many times: dragon.ply on a square grid, each
placement turned and scaled a little (deterministic: the same file every run).

    bench/scenes/dragon_field.py [COUNT] > dragon-field.json    (COUNT = 10000)

The mesh path is written relative to the scene file's folder, which must be bench/scenes
(or a folder beside it): ../../../shared/scenes/dragon.ply, as the other bench scenes."""
import json
import math
import sys

count = int(sys.argv[1]) if len(sys.argv) > 1 else 10000
if count < 1:
    sys.exit("dragon_field.py: COUNT must be at least 1")
side = math.ceil(math.sqrt(count))
spacing = 0.3
bottom = 0.0527295  # dragon.ply's lowest y: each scaled dragon is lifted back onto the ground
objects = [{"type": "plane", "normal": [0, 1, 0], "offset": bottom, "material": "ground"}]
for i in range(count):
    row, col = divmod(i, side)
    h = (i * 2654435761) % 4294967296 / 4294967296.0  # Knuth's multiplicative hash in [0, 1)
    scale = 0.85 + 0.3 * h
    objects.append({"type": "instance", "mesh": "dragon", "transform": {
        "scale": round(scale, 4),
        "rotate": {"axis": [0, 1, 0], "degrees": round(360.0 * ((h * 7.0) % 1.0), 2)},
        "translate": [round((col - (side - 1) / 2) * spacing, 4), round(bottom * (1 - scale), 6),
                      round((row - (side - 1) / 2) * spacing, 4)]}})
half = (side - 1) / 2 * spacing
scene = {
    "camera": {"eye": [0.07, 0.75, half + 0.45], "look_at": [0, 0.05, half - 1.6], "fov": 50},
    "lights": [{"type": "directional", "direction": [-0.5, -1, -0.7], "irradiance": [1.0, 0.95, 0.85]},
               {"type": "directional", "direction": [0.6, -0.4, 0.3], "irradiance": [0.25, 0.28, 0.35]}],
    "materials": {"jade": {"diffuse": [0.35, 0.6, 0.4], "specular": [0.3, 0.3, 0.3], "shininess": 40},
                  "ground": {"diffuse": [0.55, 0.5, 0.45]}},
    "meshes": {"dragon": {"file": "../../../shared/scenes/dragon.ply", "material": "jade"}},
    "objects": objects,
}
json.dump(scene, sys.stdout, separators=(",", ":"))
sys.stdout.write("\n")
