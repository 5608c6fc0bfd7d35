"""Time of the GPU descents alone (exact_lobes.glossy_term) on one atlas scene.

    python studies/exact-reference/descent_speed.py [MESH] [REPEATS] [OUT.npz]

The atlas's sunrise scene (its sphere by default, or ``knot``) at 96² with 4 × 4 samples:
the reflectors' covered samples of the 384² surface pass, and the GPU integration of
``microfacet`` at N = 10 and 1000 (GGX α by the matching) and of ``banks`` (the reference's
own parameters, its tangent field), each ``REPEATS`` times (default 2) in one process, the
pyramid built once. Prints the fastest time of each (the machine's speed varies by about
20 % from run to run: compare versions in the same session, the fastest of several) and the
mean of the result, and keeps the results in ``OUT.npz`` to hold two versions' against each
other.
"""

from __future__ import annotations

import sys
import time

import numpy as np

from envstudio.engine.session import RenderSession
from envstudio.measure.atlas.cells import cell_scene
from envstudio.measure.atlas.grid import SceneCell
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import lobe_model
from envstudio.scene.tangents import TangentField

FINE = (384, 384)
CASES = (("microfacet", 10.0), ("microfacet", 1000.0), ("banks", 100.0))


def main(mesh: str = "sphere", repeats: int = 2, out: str | None = None) -> None:
    scene = cell_scene(SceneCell(env="sunrise", mesh=mesh, exponent=100.0, kd=0.0, camera=0), 1)
    session = RenderSession(scene)
    renderer = session.renderer
    base = session.method("reference").values.as_dict()
    normals, views = renderer.reflector_surface(session.gpu_scene, session.camera, FINE)
    field = TangentField(str(base["tangent_field"]), str(base["tangent_axis"]))
    tangents = renderer.reflector_tangents(session.gpu_scene, session.camera, FINE, field)
    covered = np.linalg.norm(normals, axis=-1) > 0.5
    n, v, t = normals[covered], views[covered], tangents[covered]
    print(f"sunrise {mesh}: {len(n)} samples")
    lobes = LobeEvaluator(session.ctx, session.programs)
    results = {}
    for model, exponent in CASES:
        values = {**base, "model": model, "phong_exponent": exponent, "kd": [0, 0, 0]}
        times = []
        for _ in range(repeats):
            started = time.perf_counter()
            glossy = lobes.glossy(
                scene.environment.radiance,
                lobe_model(values),
                n,
                v,
                t if model == "banks" else None,
            )
            session.ctx.finish()
            times.append(time.perf_counter() - started)
        results[f"{model}_{exponent:g}"] = glossy
        listed = ", ".join(f"{s:.2f}" for s in times)
        print(f"{model} N = {exponent:g}: {min(times):.2f} s ({listed}), mean {glossy.mean():.5f}")
    lobes.release()
    if out:
        np.savez(out, **results)


if __name__ == "__main__":
    main(*sys.argv[1:2], *(int(a) for a in sys.argv[2:3]), *sys.argv[3:4])
