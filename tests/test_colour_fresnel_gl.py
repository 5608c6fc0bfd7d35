"""f_λ and k_d as colours (issue 28): a colour render is three grey renders, channel by channel.

Schlick's F = f0 + (1 − f0)(1 − cos θ)^5 and eq. 8's (1 − F) k_d are per channel, and the
directions a method samples do not depend on them, so with the same seed the render with
f_λ = (a, b, c) and k_d = (x, y, z) is, in channel i, the render with the greys f_λ = (a, b,
c)[i] and k_d = (x, y, z)[i]. Checked for ``mirror`` (eq. 8, shaders/common/eq8.glsl) and
the untraced ``reference`` (its Phong and microfacet models, a few samples, one seed).
"""

import json

import numpy as np
import pytest

from envstudio.cli import main
from envstudio.engine.session import RenderSession
from envstudio.io.images import write_image
from test_render_gl import render, six_colour_environment, sphere_scene

FRESNEL = (0.9, 0.5, 0.2)
KD = (0.1, 0.4, 0.7)
SIZE = (32, 32)


def _channelwise(render_with) -> tuple[np.ndarray, np.ndarray]:
    """The colour render, and channel i of the grey render i, stacked."""
    colour = render_with(FRESNEL, KD)
    greys = [render_with(f, k)[..., i] for i, (f, k) in enumerate(zip(FRESNEL, KD, strict=True))]
    return colour, np.stack(greys, axis=-1)


def test_mirror_colour_fresnel_is_three_grey_renders(gl_ctx):
    session = RenderSession(sphere_scene(six_colour_environment()), ctx=gl_ctx)

    def mirror(fresnel, kd):
        return render(session, "mirror", SIZE, fresnel=fresnel, kd=kd)

    colour, greys = _channelwise(mirror)
    assert np.ptp(colour.reshape(-1, 3), axis=0).min() > 0.1, "the sphere is drawn"
    np.testing.assert_allclose(colour, greys, rtol=1e-6, atol=1e-7)
    session.release()


@pytest.mark.parametrize("model", ["phong", "microfacet"])
def test_reference_colour_fresnel_is_three_grey_renders(gl_ctx, model):
    session = RenderSession(sphere_scene(six_colour_environment(), rings=32), ctx=gl_ctx)
    reference = session.method("reference")
    fixed = {
        "model": model,
        "phong_exponent": 30.0,
        "trace": False,
        "pixel_filter": False,
        "sequence": "random",
        "adaptive": False,
        "samples": 4,
    }

    def estimate(fresnel, kd):
        reference.values.update({**fixed, "fresnel": fresnel, "kd": kd})
        session.renderer.display["background"] = False
        for _ in range(2):
            session.render_offscreen(reference, SIZE)
        return np.where(reference.coverage()[..., None], reference.estimate(), 0.0)

    colour, greys = _channelwise(estimate)
    assert colour.max() > 0.1, "the sphere is drawn"
    np.testing.assert_allclose(colour, greys, rtol=1e-5, atol=1e-6)
    session.release()


def test_compare_matches_a_scene_files_gold_for_every_method_and_the_reference(tmp_path, capsys):
    """``fresnel = "gold"`` and an RGB k_d in the scene file reach the reference and every
    method alike (measure/matching.py copies them as they are), and the table says so."""
    environment = six_colour_environment(32)
    write_image(tmp_path / "sky.exr", environment.radiance)
    scene = tmp_path / "ball.toml"
    scene.write_text(
        '[environment]\nfile = "sky.exr"\n[[object]]\nprimitive = "sphere"\nsize = 2.0\n'
        '[object.material]\nkd = [0.1, 0.2, 0.3]\nfresnel = "gold"\nphong_exponent = 20.0\n'
    )
    out = tmp_path / "cmp"
    fast = ["--size", "24x24", "--frames", "1", "--warmup", "0", "--param", "trace=false"]
    budget = ["--param", "max_samples=16", "--param", "tolerance=0.1"]
    args = ["compare", "--scene", str(scene), "--out", str(out), "--methods", "mirror,kautz"]
    assert main([*args, *fast, *budget]) == 0
    assert "fresnel=1,0.71,0.29, kd=0.1,0.2,0.3" in capsys.readouterr().out
    report = json.loads((out / "compare.json").read_text())
    for run in [report["reference"], *report["methods"].values()]:
        assert run["parameters"]["fresnel"] == [1.0, 0.71, 0.29]
        assert run["parameters"]["kd"] == [0.1, 0.2, 0.3]
