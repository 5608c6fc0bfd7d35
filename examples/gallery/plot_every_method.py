"""
Every method on the same scene
==============================

Each method envmap-studio ships (``envstudio methods``) renders the shipped ``studio`` scene
(a mirror-like bunny under a studio HDR) from the scene's own camera, at 64×64. The reference
is the Monte Carlo ground truth, here stopped early at 256 samples per pixel; the others are
one frame each. The viewer shows the same grid live: ``envstudio view --grid``.
"""

import numpy as np
from PIL import Image, ImageDraw

import envstudio as es


def labelled(pixels, text):
    """An sRGB tile with its label above it."""
    tile = Image.fromarray(np.pad(pixels, ((12, 0), (0, 0), (0, 0)), constant_values=255))
    ImageDraw.Draw(tile).text((2, 0), text, fill=(0, 0, 0))
    return np.asarray(tile)


METHODS = [
    "mirror",
    "rsibr",
    "hwconv",
    "banks",
    "pem",
    "kautz",
    "parallax",
    "splitsum",
    "reference",
]
scene = es.load_scene("studio")
tiles = []
for name in METHODS:
    extra = {"max_samples": 256} if name == "reference" else {}
    tiles.append(labelled(es.display(es.render(scene, name, size=(64, 64), **extra)), name))

rows = [np.hstack(tiles[i : i + 3]) for i in range(0, len(tiles), 3)]
es.show(np.vstack(rows))
