"""Issue 31 part 5: PSNR of compare's displayed images binned by n·v of the reflector pixel.

Run after the compares of studies/pem-bake/README.md ("Issue 31, part 5"), with their
scratch folder: ``python studies/pem-bake/glossy_rims.py /tmp/gl``. The room's scene
camera at 96 × 96, one centre ray per pixel through the bake's tracer gives
each reflector pixel its shading normal's n·v.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

from envstudio.io.scene_file import load_scene
from envstudio.methods.pem.bake.trace import SceneTracer

BINS = ((0.0, 0.2), (0.2, 0.4), (0.4, 1.01))


def n_dot_v(size: int = 96) -> np.ndarray:
    """(size², ) n·v at each pixel centre whose ray hits a reflector first, NaN elsewhere."""
    scene = load_scene("room")
    tracer = SceneTracer(scene)
    _, o, d = tracer.centre_rays(scene.camera, size)
    tri, _, u, v = tracer._intersect(False, o, d)
    hit = (tri >= 0) & (tracer.part[np.maximum(tri, 0)] >= 0)
    out = np.full(size * size, np.nan)
    n = tracer._shading_normal(tri[hit], u[hit], v[hit], d[hit])
    out[hit] = -np.einsum("ij,ij->i", n, d[hit])
    return out


def main(folder: Path) -> None:
    ndv = n_dot_v()

    def image(path):
        rgb = np.asarray(Image.open(folder / path).convert("RGB"), dtype=np.float64)
        return rgb.reshape(-1, 3) / 255.0

    counts = [int(((ndv >= a) & (ndv < b)).sum()) for a, b in BINS]
    print(
        "n·v bins", ", ".join(f"[{a}, {b}): {c} px" for (a, b), c in zip(BINS, counts, strict=True))
    )
    for exponent in (50, 200, 1000):
        reference = image(f"final_n{exponent}/reference.png")
        runs = {
            "pem glossy": f"g384_n{exponent}/pem.png",
            "pem mirror": f"m384_n{exponent}/pem.png",
            "parallax": f"final_n{exponent}/parallax.png",
            "kautz": f"final_n{exponent}/kautz.png",
        }
        for name, path in runs.items():
            x = image(path)
            cells = []
            for a, b in BINS:
                m = (ndv >= a) & (ndv < b)
                cells.append(f"{10 * np.log10(1.0 / ((x[m] - reference[m]) ** 2).mean()):.1f}")
            print(f"N = {exponent}, {name}: " + " / ".join(cells) + " dB")


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/gl"))
