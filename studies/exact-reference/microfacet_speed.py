"""Time and checked error of the microfacet (GGX) exact reference, 96² with 4 × 4 samples.

    python studies/exact-reference/microfacet_speed.py [MAP ...]

For each shipped map (default: studio and sunrise, 512 × 1024) on the studio scene (the
bunny, its material f_λ = 1, k_d = 0: what ``envstudio compare --methods splitsum
--param trace=false`` takes) and each Phong exponent N (GGX α = √(2 / (4N + 2))), the
untraced ``model=microfacet`` at the reflectors' 384² samples, as compare's exact run
evaluates it (measure/exact_reference.exact_frame), its parts timed apart: the GL surface
pass, the GPU lobe integration (exact_lobes.py; a fresh pyramid for each N, as each compare
process builds one) and the check against the Gauss brute force (checked_error: median and
largest relative difference at its samples), and the same samples against the tests'
independent NumPy sum (tests/microfacet_numpy_reference.py: Gauss points per texel, finer
where the lobe bends, across the horizon and on bright texels), which says which of the two
is off where they disagree. One process, one map at a time.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from envstudio.engine.session import RenderSession
from envstudio.io.scene_setup import build_scene
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import checked_error, exact_radiance, lobe_model
from envstudio.resources import asset_root

# the tests' independent NumPy sum
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from microfacet_numpy_reference import ggx_sum

EXPONENTS = (5.0, 50.0, 500.0, 5000.0)
SIZE = 96
SSAA = 4


def main(maps: list[str]) -> None:
    for name in maps:
        scene = build_scene("studio", env=asset_root() / "hdr" / f"{name}.exr")
        session = RenderSession(scene)
        try:
            base = session.method("reference").values.as_dict()
            for exponent in EXPONENTS:
                values = {**base, "model": "microfacet", "phong_exponent": exponent}
                assert not np.any(values["kd"]), "the independent sum is the glossy term alone"
                started = time.perf_counter()
                fine = (SIZE * SSAA, SIZE * SSAA)
                normals, views = session.renderer.reflector_surface(
                    session.gpu_scene, session.camera, fine
                )
                covered = np.linalg.norm(normals, axis=-1) > 0.5
                n, v = normals[covered], views[covered]
                surface = time.perf_counter()
                lobes = LobeEvaluator(session.ctx, session.programs)
                try:
                    shaded = exact_radiance(scene.environment.radiance, n, v, values, lobes)
                finally:
                    lobes.release()
                evaluated = time.perf_counter()
                checked = checked_error(scene.environment.radiance, n, v, shaded, values)
                done = time.perf_counter()
                print(
                    f"{name} | N = {exponent:g} | {len(n)} samples | surface "
                    f"{surface - started:.2f} s | lobes {evaluated - surface:.2f} s | check "
                    f"{done - evaluated:.2f} s | total {done - started:.2f} s | median "
                    f"{100 * checked.median:.2g} %, largest {100 * checked.largest:.2g} % "
                    f"at {checked.samples} samples",
                    flush=True,
                )
                # the samples checked_error picks, against the independent sum
                facing = np.nonzero(np.einsum("sk,sk->s", n, v) > 0.0)[0]
                picked = facing[np.linspace(0, len(facing) - 1, checked.samples).astype(int)]
                model = lobe_model(values)
                independent = ggx_sum(
                    scene.environment.radiance, n[picked], v[picked], model.alpha, model.fresnel
                )
                differences = np.abs(shaded[picked] - independent).max(axis=1)
                differences /= np.maximum(independent.max(axis=1), 1e-30)
                print(
                    f"    against the independent sum: median "
                    f"{100 * np.median(differences):.2g} %, largest "
                    f"{100 * differences.max():.2g} % ({time.perf_counter() - done:.1f} s)",
                    flush=True,
                )
        finally:
            session.release()


if __name__ == "__main__":
    main(sys.argv[1:] or ["studio", "sunrise"])
