"""
A PEM orbit: on the baked arc and off it
========================================

Hakura, Snyder and Lengyel (seed 003) ray trace a scene at a set of viewpoints and infer for
each the environment maps that reproduce the trace when the graphics hardware applies them
(§4, "EM Inference"): a layered pair, a box for the distant room and an RGBA ellipsoid for the
teapot's reflections of itself, blended between the nearest views as the camera moves. The
shipped bake ``assets/pem/room.pem`` holds 6 views on a 10° arc; ``coverage="file"`` plays it.
(The default, ``coverage="auto"``, bakes every view of the orbit on first use instead, which
takes minutes on a CPU.) Here the camera orbits the teapot from azimuth 25° to 115° at the
arc's elevation: 192×192 frames, cropped to the teapot.
"""

import json
import struct
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import envstudio as es
from envstudio.core.images import tile
from envstudio.resources import asset_root


def labelled(pixels, text):
    """An sRGB tile with its label above it."""
    picture = Image.fromarray(np.pad(pixels, ((12, 0), (0, 0), (0, 0)), constant_values=255))
    ImageDraw.Draw(picture).text((2, 0), text, fill=(0, 0, 0))
    return np.asarray(picture)


# %%
# The bake's views, from the ``.pem`` header (magic, version, the header's length, then the
# header as JSON; the file formats page has the rest):
with open(asset_root() / "pem" / "room.pem", "rb") as bake:
    magic, version, length = struct.unpack("<8sIQ", bake.read(20))
    header = json.loads(bake.read(length))
space = header["view_space"]
print(f"{magic!r} version {version}: {header['views']} views of {header['scene']!r}")
print(f"azimuths {space['azimuths']}, elevations {space['elevations']}, at {space['distance']}")
print("models", header["models"], "parts", header["parts"], f"{header['em_size']}² cube maps")

# %%
# Top: the layered PEM; middle: one sphere at infinity inferred the same way (the paper's
# single-EM comparison, Figure 6); bottom: the static EM, one cube map captured at the teapot's
# centre (seed 003 Figure 1c, what ``mirror`` reads). On the arc (25°–35°; 30° blends the views
# at 29° and 31°) the PEMs put the teapot's reflections of its spout, handle and lid on the
# body, which the static EM cannot show. Past the arc's end the playback keeps the end view's
# maps: at 60° and 115° the layered maps no longer fit the surface (misplaced self-reflections,
# speckles where the local layer's texels were never seen), while the static EM, wrong the same
# way from every side, stays plausible. The full orbit (``coverage="auto"``) bakes a view every
# 5° instead (:checkout:`studies/pem-orbit <studies/pem-orbit/README.md>`).
scene = es.load_scene("room")
azimuths = (25, 30, 35, 60, 115)
rows = []
for model in ("layered", "sphere", "static"):
    row = []
    for azimuth in azimuths:
        frame = es.render(
            scene, "pem", size=(192, 192), camera=(azimuth, 18, 3), coverage="file", em_model=model
        )
        row.append(labelled(es.display(frame)[56:136, 36:172], f"{model}, azimuth {azimuth}°"))
    rows.append(row)
es.show(tile(rows))

# %%
# Against the ray trace: ``envstudio figure pem-offmanifold`` (seed 003 Figures 6 and 7)
# renders the three models midway between baked views and 10° and 20° above the arc beside
# the bake's ray tracer, with the displayed PSNR and FLIP of each (``*`` marks the best).
folder = Path(tempfile.mkdtemp())
command = ["figure", "pem-offmanifold", "--scene", "room", "--size", "96x96", "-o", "off.png"]
print("$ envstudio", " ".join(command))
done = subprocess.run(
    [sys.executable, "-m", "envstudio", *command],
    cwd=folder,
    capture_output=True,
    text=True,
    check=False,
)
if done.returncode:
    raise RuntimeError(done.stderr)
print(done.stdout.strip())
es.show(np.asarray(Image.open(folder / "off.png").convert("RGB")))
