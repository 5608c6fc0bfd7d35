"""
Reflection-space IBR: twelve maps and the warp
==============================================

Cabral, Olano and Nemec (seed 002) bake a *radiance* environment map, the environment already
integrated against the BRDF, as a sphere map seen from each of the 12 vertices of an
icosahedron (§3.1). For the camera's view direction they take the three maps of the
icosahedron face that holds it, warp each into the camera's frame so that texels with the same
reflection direction meet (§3.3, the mirror warp), and blend them with spherical barycentric
weights (§3.4). Here with the Phong lobe N = 50 under the studio map, at 64² a map:
``envstudio bake rsibr`` writes the 12 maps, ``envstudio figure rsibr-warp`` draws the
paper's Figure 4 for the scene's camera and ``es.render`` draws the reflector.
"""

import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import envstudio as es
from envstudio.core.images import tile, upright
from envstudio.resources import asset_root

ASSETS = asset_root()
folder = Path(tempfile.mkdtemp())


def envstudio(*args):
    """Run ``envstudio ARGS`` in ``folder``, as typed in a shell; print what it says."""
    print("$ envstudio", " ".join(a.replace(str(ASSETS), "assets") for a in args))
    done = subprocess.run(
        [sys.executable, "-m", "envstudio", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode:
        raise RuntimeError(done.stderr)
    print(done.stdout.strip())
    return done.stdout


def labelled(pixels, text):
    """An sRGB tile with its label above it."""
    picture = Image.fromarray(np.pad(pixels, ((12, 0), (0, 0), (0, 0)), constant_values=255))
    ImageDraw.Draw(picture).text((2, 0), text, fill=(0, 0, 0))
    return np.asarray(picture)


# %%
# The bake: one map per icosahedron vertex v_j, each as a camera in direction v_j from the
# object sees it (its frame T_j). The ``.rsibr`` file is a NumPy archive (the file formats
# page lists its arrays). The corners outside each disc stand for no direction.
studio = str(ASSETS / "hdr" / "studio.exr")
envstudio("bake", "rsibr", "--env", studio, "--param", "phong_exponent=50", "-o", "studio.rsibr")
bake = np.load(folder / "studio.rsibr")
header = json.loads(str(bake["header"]))
print({k: header[k] for k in ("brdf", "parameters", "size", "views", "samples", "warp")})
for j, v in enumerate(bake["views"]):
    print(f"view {j:2d}: v = ({v[0]:+.3f}, {v[1]:+.3f}, {v[2]:+.3f})")
maps = [labelled(upright(es.display(m), 2), f"view {j}") for j, m in enumerate(bake["maps"])]
es.show(tile([maps[:6], maps[6:]]))

# %%
# Figure 4 for the studio camera: top, the three source maps of the face that holds the view
# direction (their weights are printed); bottom, each warped into the camera's frame alone and
# faded near its singularity (the reflection direction opposite its own view, on the rim), and
# last the blend, the map the reflector is drawn with. Features of the maps (the softboxes)
# move to the same place in all three warped maps: the mirror warp matches the Phong lobe.
# The studio camera lies almost on the edge between views 5 and 10, so view 6 weighs 0.001.
said = envstudio(
    "figure", "rsibr-warp", "--param", "phong_exponent=50", "--size", "128x128", "-o", "fig4.png"
)
weights = {int(j): float(w) for j, w in re.findall(r"view (\d+) w = ([\d.]+)", said)}
print("views blended:", ", ".join(f"{j} (weight {w:.3f})" for j, w in weights.items()))
es.show(np.asarray(Image.open(folder / "fig4.png").convert("RGB")))

# %%
# The reflector: ``rsibr`` draws the bunny with the generated map (sphere-mapped, §4), left;
# ``hwconv`` convolves the map with the same lobe ⟨r, l⟩^50 on the GPU, right.
scene = es.load_scene("studio")
tiles = [
    labelled(es.display(es.render(scene, name, size=(96, 96), phong_exponent=50)), name)
    for name in ("rsibr", "hwconv")
]
es.show(np.hstack(tiles))
