"""
Self-occlusion on a torus knot
==============================

An environment map knows nothing of the object it lights: every point of the reflector sees
the whole sphere. A (2, 3) torus knot (the atlas's ``knot``) hides much of it from itself.
``es.compare`` separates the two kinds of error when the reference traces the scene: the
**approximation error** is ``kautz`` against the untraced reference (the environment-map model
it approximates), the **scene error** against the traced one (self-occlusion and
self-reflection included). The knot is written to a PLY file and loaded as the studio scene's
reflector (``es.load_scene(mesh=...)``, the CLI's ``--mesh``). At 48×48 this takes a few
seconds.
"""

import tempfile
from pathlib import Path

import numpy as np
import trimesh

import envstudio as es
from envstudio.scene.primitives import torus_knot

knot = torus_knot()
folder = Path(tempfile.mkdtemp())
mesh = trimesh.Trimesh(knot.positions, knot.indices, vertex_normals=knot.normals, process=False)
mesh.export(folder / "knot.ply")

scene = es.load_scene("studio", mesh=folder / "knot.ply")
report = es.compare(scene, ["kautz"], size=(48, 48), time_limit=3)

# %%
# Median relative error of the linear frame over the knot's pixels (``compare.json``'s
# ``approximation`` and ``scene_error``; ``compare.md`` shows the same columns):
for name, measured in report.json["methods"].items():
    approximation = measured["approximation"]["median_relative_error"]
    print(
        f"{name}: approximation error {approximation:.1%}, "
        f"scene error {measured['scene_error']:.1%}"
    )

# %%
# Left: ``kautz``; right: the traced reference (its time limit is short here, so it is
# noisy). The knot's inner sides, dark in the reference, stay lit in the environment map.
es.show(np.hstack([es.display(report.images["kautz"]), es.display(report.reference)]))
