"""Small scene files the tests write: a glossy ball under a given sky."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from envstudio.io.images import write_image


def ball_scene(folder: Path, sky: np.ndarray) -> Path:
    """``folder``/ball.toml: a sphere of size 2 (k_d 0.3, f_λ 0.5, N 20) seen from azimuth
    20°, elevation 10°, distance 3 under ``sky`` ((h, 2h, 3) linear radiance, saved beside it
    as sky.exr)."""
    write_image(folder / "sky.exr", sky)
    scene = folder / "ball.toml"
    scene.write_text(
        'name = "ball"\n[environment]\nfile = "sky.exr"\n'
        "[camera]\nazimuth = 20.0\nelevation = 10.0\ndistance = 3.0\nfov = 45.0\n"
        '[[object]]\nname = "ball"\nprimitive = "sphere"\nsize = 2.0\nrole = "reflector"\n'
        "[object.material]\nkd = 0.3\nfresnel = 0.5\nphong_exponent = 20.0\n"
    )
    return scene
