"""The microfacet exact reference against the Monte Carlo one run long.

    python studies/exact-reference/microfacet_montecarlo.py [SECONDS] [MAP] [N]

A sphere (uv_sphere, 48 rings) seen as tests/scene_files.py's ball (azimuth 20°, elevation
10°, distance 3) under a shipped map (default studio), 64² pixels, the reference's untraced
``model=microfacet`` (f_λ = 0.5, k_d = 0.3, N = 50 by default: α = 0.0995): its Monte Carlo
estimate (``sequence=random``, 16 spp a frame) accumulated for SECONDS (default 120), and
the exact frame (4 × 4 samples a pixel, exact_reference.exact_frame), compared over the
pixels wholly on the sphere (a rim pixel's two footprints differ: the exact frame averages
its covered samples, the Monte Carlo one is drawn only where the pixel's centre is
covered): the mean relative difference and its standard error, the median per-pixel
|difference| over the Monte Carlo standard error (0.67 for noise alone).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from envstudio.engine.session import RenderSession
from envstudio.io.images import read_image
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import exact_frame
from envstudio.resources import asset_root
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import uv_sphere

SIZE = 64
SSAA = 4
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def main(seconds: float, name: str, exponent: float) -> None:
    radiance = read_image(asset_root() / "hdr" / f"{name}.exr")[..., :3]
    camera = OrbitCamera(azimuth=20.0, elevation=10.0, distance=3.0, fov_y=45.0)
    scene = Scene(Environment(radiance), [Node("ball", uv_sphere(1.0))], camera, "ball")
    session = RenderSession(scene)
    lobes = LobeEvaluator(session.ctx, session.programs)
    try:
        reference = session.method("reference")
        reference.values.update(
            {"model": "microfacet", "trace": False, "sequence": "random", "adaptive": False}
        )
        reference.values.update({"samples": 16, "max_samples": 1 << 20, "tolerance": 1e-5})
        reference.values.update({"fresnel": 0.5, "kd": 0.3, "phong_exponent": exponent})
        started = time.perf_counter()
        while time.perf_counter() - started < seconds:
            session.render_offscreen(reference, (SIZE, SIZE))
        sampled, noise = reference.estimate(), reference.standard_error()
        print(f"Monte Carlo: {reference.status_line()} in {time.perf_counter() - started:.0f} s")
        fine = (SIZE * SSAA, SIZE * SSAA)
        normals, views = session.renderer.reflector_surface(session.gpu_scene, camera, fine)
        values = reference.values.as_dict()
        frame = exact_frame(normals, views, scene.environment.radiance, values, SSAA, lobes=lobes)
    finally:
        lobes.release()
        session.release()
    checked = frame.error
    print(
        f"exact: {frame.seconds:.1f} s, checked median {100 * checked.median:.2g} %, "
        f"largest {100 * checked.largest:.2g} % at {checked.samples} samples"
    )
    core = (np.linalg.norm(normals, axis=-1) > 0.5).reshape(SIZE, SSAA, SIZE, SSAA)
    core = core.all(axis=(1, 3))
    mean = (sampled @ LUMINANCE)[core]
    difference = (frame.hdr @ LUMINANCE)[core] - mean
    error = (noise @ LUMINANCE)[core]
    relative, relative_error = difference / mean, error / mean
    spread = np.sqrt(np.sum(relative_error**2)) / core.sum()
    print(
        f"{core.sum()} pixels wholly on the sphere: mean relative difference (exact − Monte "
        f"Carlo) {100 * relative.mean():+.3f} % ± {100 * spread:.3f} % (1 σ of the Monte "
        f"Carlo noise); median |difference| {100 * np.median(np.abs(relative)):.3f} %, "
        f"median |z| {np.median(np.abs(difference / error)):.2f}; Monte Carlo per-pixel "
        f"noise (median) {100 * np.median(relative_error):.3f} %"
    )


if __name__ == "__main__":
    arguments = sys.argv[1:]
    main(
        float(arguments[0]) if arguments else 120.0,
        arguments[1] if len(arguments) > 1 else "studio",
        float(arguments[2]) if len(arguments) > 2 else 50.0,
    )
