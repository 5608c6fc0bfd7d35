"""The exact reference's diffuse term against Mitsuba 3 (the model both renderers have).

Mitsuba 3 (``scalar_rgb``, tests/mitsuba_scene.py) renders tests/test_mitsuba_gl.py's
sphere under its sky and lamp with a ``diffuse`` BSDF of reflectance 1, direct lighting
only (``max_depth`` 2: a convex sphere sees nothing of itself), one ray through each pixel
centre, many paths each. Ours: ``model=phong, kd=1, fresnel=0, N=1`` evaluated exactly at
the same pixel centres (``ssaa`` 1); F = (1 − n·v)^5 is not 0 at grazing views, so only
pixels with n·v > 0.7 at the centre are compared (F < 0.25 %, as the test does).

    python studies/exact-reference/mitsuba_diffuse.py [SPP]

prints the ratio ours / Mitsuba of the sums over those pixels per channel, its standard
error from Mitsuba's paths, and the median per-pixel relative difference.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
import mitsuba_scene as ms
from envstudio.engine.session import RenderSession
from envstudio.measure.exact_reference import exact_frame
from test_mitsuba_gl import sphere_scene


def main(spp: int) -> None:
    scene, size = sphere_scene()
    session = RenderSession(scene, cube_size=16)
    try:
        started = time.perf_counter()
        normals, views = session.renderer.reflector_surface(session.gpu_scene, session.camera, size)
        values = {"fresnel": (0.0, 0.0, 0.0), "kd": (1.0, 1.0, 1.0), "phong_exponent": 1.0}
        ours = exact_frame(normals, views, scene.environment.radiance, values, 1, started)
    finally:
        session.release()
    mi_scene = ms.load_scene(scene, size, ms.diffuse_bsdf(1.0), 2)
    _, n_dot_v = ms.centre_rays(mi_scene)
    interior = ours.mask & (np.nan_to_num(n_dot_v, nan=-1.0) > 0.7)
    theirs = ms.render_centres(mi_scene, spp, mask=interior, seed=1)
    o, t, s = ours.hdr[interior], theirs.mean[interior], theirs.standard_error[interior]
    ratio = o.sum(0) / t.sum(0)
    sigma = np.sqrt(np.sum(s**2, 0)) / t.sum(0)
    per_pixel = np.median(np.abs(o - t) / t, axis=0)
    print(f"pixels {int(interior.sum())}, Mitsuba {spp} paths each; exact in {ours.seconds:.2f} s")
    print(
        "ratio ours / Mitsuba per channel:", np.round(ratio, 5), "± (1 sigma)", np.round(sigma, 5)
    )
    print("median per-pixel |relative difference|:", np.round(per_pixel, 5))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 512)
