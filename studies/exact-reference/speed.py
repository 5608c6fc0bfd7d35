"""Time and checked error of the exact reference at 96² with 4 × 4 footprint samples.

    python studies/exact-reference/speed.py [SCENE ...]

For each scene (default: studio, the bunny under the 512 × 1024 studio map) and Phong
exponent N, in a fresh process per scene, the untraced model=phong evaluated at the
reflectors' 384² samples: glossy only (f_λ = 1, k_d = 0) and glossy + diffuse (f_λ = 0.5,
k_d = 0.3), cold (the spectral tables built) and warm, with the check against the Gauss
brute force (median and largest relative difference at its samples).
"""

from __future__ import annotations

import sys
import time

from envstudio.engine.session import RenderSession
from envstudio.io.scene_setup import build_scene
from envstudio.measure.exact_reference import exact_frame

EXPONENTS = (10.0, 100.0, 1000.0, 5000.0)
MATERIALS = {
    "glossy": {"fresnel": (1.0, 1.0, 1.0), "kd": (0.0, 0.0, 0.0)},
    "glossy + diffuse": {"fresnel": (0.5, 0.5, 0.5), "kd": (0.3, 0.3, 0.3)},
}


def main(scenes: list[str]) -> None:
    for name in scenes:
        scene = build_scene(name)
        session = RenderSession(scene)
        try:
            for material, values in MATERIALS.items():
                for exponent in EXPONENTS:
                    for run in ("cold", "warm"):
                        started = time.perf_counter()
                        normals, views = session.renderer.reflector_surface(
                            session.gpu_scene, session.camera, (384, 384)
                        )
                        frame = exact_frame(
                            normals,
                            views,
                            scene.environment.radiance,
                            {**values, "phong_exponent": exponent},
                            4,
                            started,
                        )
                        checked = frame.error
                        print(
                            f"{name} | {material} | N = {exponent:g} | {run} | "
                            f"{frame.seconds:.2f} s | median {100 * checked.median:.2g} %, "
                            f"largest {100 * checked.largest:.2g} % at {checked.samples} samples"
                        )
        finally:
            session.release()


if __name__ == "__main__":
    main(sys.argv[1:] or ["studio"])
