"""The exact microfacet reference against Mitsuba 3's GGX ``roughconductor``.

Mitsuba 3 (``scalar_rgb``, tests/mitsuba_scene.py) renders tests/test_mitsuba_gl.py's sphere
with ``roughconductor``, ``distribution="ggx"``, ``material="none"`` (F = 1: a conductor of
index 0 + 1i), direct lighting only (``max_depth`` 2: a convex sphere sees nothing of
itself), one ray through each pixel centre, SPP paths each. Against it, at the same pixel
centres (``ssaa`` 1):

- ours: the exact reference (exact_reference.exact_frame with the GPU's exact_lobes
  .LobeEvaluator) of ``model=microfacet, fresnel=1, kd=0`` at the Phong exponent whose α
  (√(2 / (4N + 2))) is Mitsuba's, Schlick's F with f_λ = 1 being 1 as well;
- NumPy G2: tests/microfacet_numpy_reference.py's independent sum of the same model (the
  height-correlated Smith G2), the anchor of ours;
- NumPy separable: the same sum with Mitsuba's Smith term, G1(v) G1(l): the model Mitsuba
  renders, the like-with-like check of that anchor against Mitsuba.

The NumPy sums take our rasterised normals and views; the largest difference of n·v between
them and Mitsuba's hit points is printed. Compared: the pixels whose centre ray meets the
sphere with n·v > ``N_DOT_V`` (Mitsuba's shading normal), where the two Smith terms differ
by a few per cent at most.

    python studies/exact-reference/mitsuba_ggx.py [SPP] [MAP] [RINGS]

MAP: ``sky`` (default, tests/test_mitsuba_gl.py's smooth sky with a broad lamp) or ``sun``
(tests/test_exact_microfacet.py's 32 × 64 sky with a 2 × 2-texel sun at 2000, reflected in
the sphere near n·v = 0.6). RINGS: the uv sphere's rings (default 48, the tests' sphere; it
has twice as many segments). Mitsuba's sphere is the same mesh with the same interpolated
normals, but a ray leaving it below the flat face's plane meets the sphere again: that cuts
off a thin band of directions just above the shading normal's horizon, which ours and the
NumPy sums keep. A finer sphere narrows the band.

Per α it prints the ratios of the sums over those pixels per channel, Mitsuba's 1 σ (from
its paths' spread; the NumPy sums and ours have no noise), the median and largest per-pixel
relative difference (largest channel), and for the NumPy separable sum the median over
pixels and channels of |difference| over Mitsuba's standard error (0.67 for noise alone);
then the same over the pixels where ours is more than ``OFF_ANCHOR`` off its own anchor,
the NumPy G2 sum, which shows whose side Mitsuba takes there (before ac38e6a: the sun map's
pixels whose horizon ⟨n, l⟩ = 0 crosses the sun; since then there are none).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
import mitsuba_scene as ms
from envstudio.core import ggx
from envstudio.engine.session import RenderSession
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import exact_frame
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import uv_sphere
from microfacet_numpy_reference import ggx_sum
from test_exact_microfacet import sun_map
from test_mitsuba_gl import sky_and_lamp, sphere_scene

#: GGX α compared (Phong exponents 1.5, 12 and 101.5).
ALPHAS = (0.5, 0.2, 0.07)
#: Least n·v at the pixel centre of a compared pixel.
N_DOT_V = 0.3
#: A pixel's difference from the NumPy G2 sum past which ours is reported apart.
OFF_ANCHOR = 0.01
MAPS = {"sky": sky_and_lamp, "sun": sun_map}


def per_pixel(ours, theirs) -> np.ndarray:
    """Each pixel's largest channel |difference| over its largest channel's value (as
    exact_reference.checked_error's)."""
    return np.abs(ours - theirs).max(axis=1) / theirs.max(axis=1)


def ratio_line(label: str, ours, theirs, sigma=None) -> str:
    """``label``: the ratio of the sums per channel (± ``sigma``) and the median and largest
    :func:`per_pixel` difference."""
    ratio = ours.sum(0) / theirs.sum(0)
    noise = "" if sigma is None else f" ± {np.array2string(sigma, precision=5)}"
    difference = per_pixel(ours, theirs)
    return (
        f"  {label:<26} {np.array2string(ratio, precision=5)}{noise}; per pixel: median "
        f"{100 * np.median(difference):.3f} %, largest {100 * difference.max():.2f} %"
    )


def comparison(ours, mitsuba, mitsuba_error, correlated, separable) -> list[str]:
    """The four lines of one set of pixels: ours and the NumPy sums against Mitsuba, ours
    against its anchor and the two Smith terms against each other; (s, 3) arrays."""
    sigma = np.sqrt(np.sum(mitsuba_error**2, 0)) / mitsuba.sum(0)
    z = np.median(np.abs(separable - mitsuba) / np.maximum(mitsuba_error, 1e-30))
    return [
        ratio_line("ours / Mitsuba", ours, mitsuba, sigma),
        ratio_line("NumPy separable / Mitsuba", separable, mitsuba, sigma)
        + f"; median |difference| / σ {z:.2f}",
        ratio_line("ours / NumPy G2", ours, correlated),
        ratio_line("NumPy G2 / NumPy separable", correlated, separable),
    ]


def main(spp: int, map_name: str, rings: int) -> None:
    """Render, evaluate and print the comparison for every α of :data:`ALPHAS`."""
    begun = time.perf_counter()
    tests_scene, size = sphere_scene()
    sphere = Node("sphere", uv_sphere(1.0, rings, 2 * rings))
    scene = Scene(Environment(MAPS[map_name]()), [sphere], tests_scene.camera, map_name)
    radiance = scene.environment.radiance
    session = RenderSession(scene, cube_size=16)
    lobes = LobeEvaluator(session.ctx, session.programs)
    frames = {}
    try:
        normals, views = session.renderer.reflector_surface(session.gpu_scene, session.camera, size)
        for alpha in ALPHAS:
            values = {
                "model": "microfacet",
                "fresnel": (1.0, 1.0, 1.0),
                "kd": (0.0, 0.0, 0.0),
                "phong_exponent": ggx.exponent_for_alpha(alpha),
            }
            frames[alpha] = exact_frame(normals, views, radiance, values, 1, lobes=lobes)
    finally:
        lobes.release()
        session.release()
    print(
        f"map {map_name}, sphere of {rings} rings, {size[0]}x{size[1]} pixel centres, "
        f"Mitsuba {spp} paths a pixel"
    )
    for alpha in ALPHAS:
        ours = frames[alpha]
        mi_scene = ms.load_scene(scene, size, ms.ggx_bsdf(alpha), 2)
        _, mi_n_dot_v = ms.centre_rays(mi_scene)
        interior = ours.mask & (np.nan_to_num(mi_n_dot_v, nan=-1.0) > N_DOT_V)
        started = time.perf_counter()
        theirs = ms.render_centres(mi_scene, spp, mask=interior, seed=1)
        mitsuba_s = time.perf_counter() - started
        n = normals[interior].astype(np.float64)
        v = views[interior].astype(np.float64)
        started = time.perf_counter()
        correlated = ggx_sum(radiance, n, v, alpha, (1.0, 1.0, 1.0))
        separable = ggx_sum(radiance, n, v, alpha, (1.0, 1.0, 1.0), smith="separable")
        numpy_s = time.perf_counter() - started
        o = ours.hdr[interior].astype(np.float64)
        t, s = theirs.mean[interior], theirs.standard_error[interior]
        shift = np.abs(np.einsum("sk,sk->s", n, v) - mi_n_dot_v[interior]).max()
        checked = ours.error
        print(
            f"α = {alpha} (N = {ggx.exponent_for_alpha(alpha):g}): {int(interior.sum())} pixels "
            f"with n·v > {N_DOT_V} (ours and Mitsuba's n·v differ by {shift:.1e} at most); "
            f"exact {ours.seconds:.1f} s (checked against the brute force at "
            f"{checked.describe()}: median {100 * checked.median:.2g} %, largest "
            f"{100 * checked.largest:.2g} %), Mitsuba {mitsuba_s:.1f} s, NumPy {numpy_s:.1f} s"
        )
        print("\n".join(comparison(o, t, s, correlated, separable)))
        off = per_pixel(o, correlated) > OFF_ANCHOR
        if off.any():
            print(f" the {int(off.sum())} of them where ours is > {OFF_ANCHOR:.0%} off its anchor:")
            print("\n".join(comparison(o[off], t[off], s[off], correlated[off], separable[off])))
    print(f"total {time.perf_counter() - begun:.0f} s")


if __name__ == "__main__":
    main(
        int(sys.argv[1]) if len(sys.argv) > 1 else 4096,
        sys.argv[2] if len(sys.argv) > 2 else "sky",
        int(sys.argv[3]) if len(sys.argv) > 3 else 48,
    )
