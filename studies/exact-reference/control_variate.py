"""Variance reduction of the control variate: T − β (U − exact untraced), β per pixel.

    python studies/exact-reference/control_variate.py [BATCHES]

For each scene (a sphere, the (2, 3) torus knot and the bunny under the studio map; the
room with its local objects), 48² with the reference's defaults but ``trace=true``,
``untraced_too=true``, ``sequence=random`` and ``adaptive=false`` (independent batches of
equal size, honest standard errors), at material f_λ = 0.5, k_d = 0.3, N = 50: after
BATCHES batches (default 32), the median relative standard error over the reflector of the
plain traced estimate and of the control-variate one, their ratio squared (the samples the
plain estimate needs for the same noise, per sample of the control variate), and the times
of the batches and of the exact evaluation (4 × 4 samples a pixel).
"""

from __future__ import annotations

import sys
import time

import numpy as np

from envstudio.core.env_sampling import LUMINANCE
from envstudio.engine.session import RenderSession
from envstudio.io.scene_setup import build_scene
from envstudio.measure.exact_reference import exact_frame
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import torus_knot, uv_sphere

SIZE = (48, 48)
MATERIAL = {"fresnel": 0.5, "kd": 0.3, "phong_exponent": 50.0}


def scenes() -> dict[str, Scene]:
    studio = build_scene("studio")
    environment, camera = studio.environment, studio.camera
    return {
        "sphere": Scene(environment, [Node("sphere", uv_sphere(0.8, 48, 96))], camera, "sphere"),
        "knot": Scene(environment, [Node("knot", torus_knot().fitted(0.8))], camera, "knot"),
        "bunny": studio,
        "room": build_scene("room"),
    }


def median_relative(estimate, error, mask) -> float:
    y = estimate[mask] @ LUMINANCE
    lit = y > 0
    return float(np.median((error[mask] @ LUMINANCE)[lit] / y[lit]))


def main(batches: int) -> None:
    print("scene | batches (spp) | s | plain noise | control noise | (plain/control)² | exact s")
    for name, scene in scenes().items():
        session = RenderSession(scene)
        try:
            reference = session.method("reference")
            reference.values.update(MATERIAL)
            reference.values.update({"trace": True, "untraced_too": True})
            reference.values.update({"sequence": "random", "adaptive": False})
            reference.values.update({"max_samples": 65536, "tolerance": 1e-5})
            started = time.perf_counter()
            for _ in range(batches):
                session.render_offscreen(reference, SIZE)
            batch_s = time.perf_counter() - started
            paired = reference.paired()
            started = time.perf_counter()
            fine = (SIZE[0] * 4, SIZE[1] * 4)
            normals, views = session.renderer.reflector_surface(
                session.gpu_scene, session.camera, fine
            )
            exact = exact_frame(
                normals, views, scene.environment.radiance, reference.values.as_dict(), 4
            )
            exact_s = time.perf_counter() - started
            mask = reference.coverage() & exact.mask
            plain = median_relative(paired.traced, paired.traced_error, mask)
            controlled = median_relative(*paired.controlled(exact.hdr), mask)
            print(
                f"{name} | {batches} ({reference.status.samples}) | {batch_s:.1f} | "
                f"{100 * plain:.3g} % | {100 * controlled:.3g} % | "
                f"{(plain / controlled) ** 2:.3g} | {exact_s:.2f}"
            )
        finally:
            session.release()


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 32)
