"""The reference against Mitsuba 3, on the materials both renderers have (issue 13).

Mitsuba (``scalar_rgb``, tests/mitsuba_scene.py) renders the same scene,
camera and environment as our ``reference`` method, traced (``trace=true``),
with its path tracer's ``max_depth`` matched to our bounce count. Two
materials have a counterpart in both:

- diffuse: ours ``model=phong, kd=1, fresnel=0``, Mitsuba ``diffuse`` with
  reflectance 1;
- GGX: ours ``model=microfacet, kd=0, fresnel=1`` with alpha =
  sqrt(2 / (4N + 2)), Mitsuba ``roughconductor`` with ``material="none"``
  (F = 1), ``distribution="ggx"`` and the same alpha.
- Coloured f_λ (issue 28): ours ``model=microfacet, kd=0, fresnel=gold`` (linear RGB
  F0 (1, 0.71, 0.29), Schlick per channel at v·h), Mitsuba ``principled`` with
  ``metallic=1``, ``base_color`` = that F0 and ``roughness`` = sqrt(alpha): the same
  GGX lobe times the same Schlick F per channel (mitsuba_scene.schlick_ggx_bsdf says
  why, and why a ``roughconductor`` tint is not the counterpart).

The Phong lobe of seed 000 eq. 7 (``model=phong`` with a glossy part) has no
Mitsuba counterpart (Mitsuba 3 has no Phong BSDF), so it is not compared here;
the diffuse and GGX agreement is what vouches for the tracing, the footprint,
the environment sampling and the MIS weights that it shares with them.

What is compared, and why the tolerances are what they are:

- Pixels: those our reference covers (``coverage()``) whose centre ray meets
  the reflector with a shading normal n·v above a threshold.
  Diffuse: n·v > 0.7. Schlick's F with f_λ = 0 is (1 − n·v)^5, not 0, so
  ours is (1 − F) k_d D + F P with a Phong part F P; F < 0.25 % there and P
  is of the order of D. The same leftover weights the paths' later bounces
  (material.glsl), unmasked; a scratch build without it moved the
  self-reflecting bunny's ratio by 0.1 %.
  GGX: n·v > 0.5. Mitsuba's Smith term is the separable G1(v) G1(l), ours
  the height-correlated one: at alpha = 0.1 the GGX albedo under the
  separable one is 1.2 % lower at n·v = 0.1, 0.28 % at 0.2, 0.08 % at 0.3 and
  0.01 % at 0.5 (numerical integration). And on the 3 674-triangle bunny
  the lobe reaches below the face's plane while above the shading normal's:
  with the shading plane alone ours came out 2.2 % brighter at n·v from 0.3
  to 0.5 (direct lighting) and 2.1 % from 0.1 to 0.3, where Mitsuba's ray,
  started on the far side of the face, is blocked. paths.glsl now blocks
  directions below either plane: 0.9 % and 0.0 % (±0.4 %, ±0.9 %).
- Footprint off (``pixel_filter=false``): our sample is the pixel centre;
  Mitsuba's is the same camera ray through the pixel centre
  (:func:`mitsuba_scene.render_centres`). Footprint on: ours averages over
  the footprint's points on the reflector (misses dropped); Mitsuba's
  counterpart is a box-filtered RGBA film with the environment hidden,
  value = rgb / alpha (:func:`mitsuba_scene.render_footprint`). With the
  footprint on, the GGX ring of pixels left out by the n·v threshold (the
  silhouette and the terminator, footprints partly covered) is checked too,
  its mean within 3 % (the two differences above) plus 4 standard errors.
- Noise: ours from ``standard_error()`` with ``sequence=random`` (independent
  batches: an honest standard error), Mitsuba's from the spread of its paths
  (centres) or of independent renders (footprint). Over the compared pixels
  the ratio of the sums, ours / Mitsuba, must be within 0.5 % (the model
  differences above, and the lat-long resampling, are an order below) plus
  4 standard errors of that ratio, per channel; and per pixel and channel,
  at least 99 % of the differences within 4.5 standard errors of both
  estimates combined (the traced paths' noise is not Gaussian: a path that
  reaches the bright lamp only after a bounce is a rare large sample).
- GGX runs with ``environment_sampling=global``. With ``lobe`` (what
  ``auto`` picks without local objects) environment samples come only from
  the cap about the mirror direction, so the lamp outside the cap is reached
  by the GGX lobe's tail alone: rare samples of 50 times a pixel's mean. The
  estimate stays unbiased (ratio 1.002 here) but its batch spread understates
  the error: the two halves of 32 batches differ by √5 times their standard
  error (``global``: by 0.97 times).

:func:`test_exact_ggx_reference_agrees_with_mitsuba` holds the exact untraced GGX reference
(measure/exact_lobes.py) against Mitsuba's direct lighting instead, noise on Mitsuba's side
only.
"""

from __future__ import annotations

import mitsuba as mi
import numpy as np
import pytest

import mitsuba_scene as ms
from envstudio.core import ggx, latlong
from envstudio.engine.session import RenderSession
from envstudio.io.meshes import load_mesh
from envstudio.measure.exact_lobes import LobeEvaluator
from envstudio.measure.exact_reference import exact_frame
from envstudio.methods.reference import tracing
from envstudio.resources import asset_root
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import torus_knot, uv_sphere

#: Our batches and samples per batch: 256 estimates per pixel.
BATCHES, SAMPLES = 16, 16
#: Mitsuba's paths per pixel at the centre, and its footprint renders × samples per pixel.
CENTRE_SPP, FOOTPRINT_RENDERS, FOOTPRINT_SPP = 512, 8, 128
#: Phong exponent of the GGX material: alpha = sqrt(2 / (4N + 2)) = 0.0995.
GGX_EXPONENT = 50.0
GGX_ALPHA = float(np.sqrt(2.0 / (4.0 * GGX_EXPONENT + 2.0)))
MATERIALS = {
    "diffuse": (
        {"model": "phong", "kd": 1.0, "fresnel": 0.0, "phong_exponent": 1.0},
        ms.diffuse_bsdf(1.0),
        0.7,
    ),
    "ggx": (
        {
            "model": "microfacet",
            "kd": 0.0,
            "fresnel": 1.0,
            "phong_exponent": GGX_EXPONENT,
            "environment_sampling": "global",
        },
        ms.ggx_bsdf(GGX_ALPHA),
        0.5,
    ),
}
GOLD = (1.0, 0.71, 0.29)  # core/presets.py's gold
MATERIALS["gold"] = (
    {**MATERIALS["ggx"][0], "fresnel": "gold"},
    ms.schlick_ggx_bsdf(GGX_ALPHA, GOLD),
    0.5,
)
MODEL_TOLERANCE = 0.005
SILHOUETTE_TOLERANCE = 0.03
Z_BOUND, Z_INSIDE = 4.5, 0.99


def max_depth(bounces: int) -> int:
    """Mitsuba's ``max_depth`` for our ``u_trace_bounces`` (methods/reference/tracing.py).

    From the first hit our traced path (reference/paths.glsl) follows at most
    ``bounces`` segments, continuing at each reflector it meets and taking
    the environment where a segment escapes; the one after the last returns
    black. Mitsuba's depth counts the camera segment as well: 1 renders the
    visible emitters, 2 direct lighting at the first hit, so ours is
    ``bounces + 1``.
    """
    return bounces + 1


def sky_and_lamp(height: int = 32) -> np.ndarray:
    """(h, 2h, 3) a dim, coloured sky with one broad bright lamp off to the side.

    The lamp lights one flank of the reflector; the other side sees it only
    through the reflector's own bounces, which is what the self-reflection
    tests measure.
    """
    d = latlong.texel_directions(height)
    sky = 0.05 * np.stack([1 + 0.5 * d[..., 1], 1 + 0.2 * d[..., 0], 1.5 - 0.3 * d[..., 2]], -1)
    lamp_direction = np.array([-0.8, 0.2, 0.5]) / np.linalg.norm([-0.8, 0.2, 0.5])
    lamp = 4.0 * np.exp(-3.0 * np.sum((d - lamp_direction) ** 2, -1))
    return np.maximum(sky + lamp[..., None] * [1.0, 0.9, 0.7], 0).astype(np.float32)


def sphere_scene() -> tuple[Scene, tuple[int, int]]:
    """A smooth unit sphere (analytic vertex normals) at 32 × 32."""
    camera = OrbitCamera(azimuth=30.0, elevation=15.0, distance=3.0, fov_y=45.0)
    node = Node("sphere", uv_sphere(1.0, 48, 96))
    return Scene(Environment(sky_and_lamp()), [node], camera, "sphere"), (32, 32)


def bunny_scene() -> tuple[Scene, tuple[int, int]]:
    """The studio scene's bunny (assets/mesh/bunny.ply, fitted into the unit sphere) at 40 × 40."""
    mesh = load_mesh(asset_root() / "mesh" / "bunny.ply").fitted(1.0)
    camera = OrbitCamera(azimuth=115.0, elevation=20.0, distance=2.4, fov_y=45.0)
    return Scene(Environment(sky_and_lamp()), [Node("bunny", mesh)], camera, "bunny"), (40, 40)


def knot_scene() -> tuple[Scene, tuple[int, int]]:
    """The (2, 3) torus knot (4160 triangles, smooth normals), fitted into the unit sphere, 48².

    Its strands come within 0.03 of one another (tube radius 0.4, before fitting):
    most of the surface looks into a crevice, the strongly self-occluding case of issue 27.
    """
    mesh = torus_knot().fitted(1.0)
    camera = OrbitCamera(azimuth=30.0, elevation=25.0, distance=2.6, fov_y=45.0)
    return Scene(Environment(sky_and_lamp()), [Node("knot", mesh)], camera, "knot"), (48, 48)


def reference(
    ctx, scene: Scene, size, material: dict, pixel_filter: bool, batches=BATCHES, samples=SAMPLES
):
    """Our traced reference after ``batches`` independent batches of ``samples``.

    Parameters
    ----------
    ctx
        The test's GL context.
    scene, size
        What to render and the (width, height) of the image.
    material : dict
        The reference's material parameters (:data:`MATERIALS`).
    pixel_filter : bool
        Footprint on (box filter over the covered footprint) or pixel centre only.

    Returns
    -------
    estimate, standard_error : (h, w, 3) float64
    coverage : (h, w) bool
    """
    session = RenderSession(scene, ctx=ctx, cube_size=16)
    method = session.method("reference")
    method.values.update(
        {
            "trace": True,
            "pixel_filter": pixel_filter,
            "sequence": "random",
            "adaptive": False,
            "samples": samples,
            "max_samples": 10**6,
            "tolerance": 1e-5,
            **material,
        }
    )
    session.renderer.display["background"] = False
    for _ in range(batches):
        session.render_offscreen(method, size)
    estimate = method.estimate().astype(np.float64)
    error = method.standard_error().astype(np.float64)
    covered = method.coverage()
    session.release()
    assert method.status.batches == batches
    return estimate, error, covered


def mitsuba(
    scene: Scene,
    size,
    bsdf: dict,
    depth: int,
    pixel_filter: bool,
    covered,
    threshold,
    renders=FOOTPRINT_RENDERS,
):
    """Mitsuba's image of the same scene and the interior pixels to compare.

    Parameters
    ----------
    scene, size
        As for :func:`reference`.
    bsdf : dict
        The Mitsuba material (:data:`MATERIALS`).
    depth : int
        Mitsuba's ``max_depth`` (:func:`max_depth`).
    pixel_filter : bool
        Box-filtered RGBA film (rgb / alpha) or the pixel-centre rays only.
    covered : (h, w) bool
        Our reference's coverage.
    threshold : float
        Least shading n·v at the pixel centre of an interior pixel.
    renders : int
        Independent footprint renders of :data:`FOOTPRINT_SPP` samples.

    Returns
    -------
    estimate : mitsuba_scene.Estimate
    interior : (h, w) bool
        Pixels ``covered`` whose centre ray meets the reflector with n·v
        above ``threshold`` (without the footprint only they are rendered).
    """
    mi_scene = ms.load_scene(scene, size, bsdf, depth)
    _, n_dot_v = ms.centre_rays(mi_scene)
    n_dot_v = np.nan_to_num(n_dot_v, nan=-1.0)
    interior = covered & (n_dot_v > threshold)
    if pixel_filter:
        estimate = ms.render_footprint(mi_scene, FOOTPRINT_SPP, renders, seed=1)
    else:
        estimate = ms.render_centres(mi_scene, CENTRE_SPP, mask=interior, seed=1)
    return estimate, interior


def agreement(ours, ours_error, theirs, theirs_error, mask) -> dict:
    """How two estimates agree over ``mask``.

    Returns
    -------
    dict
        ``pixels``; ``ratio``, (3,) ours / theirs of the sums over the
        pixels, and ``sigma``, its standard error; ``inside``, the fraction
        of pixel values whose difference z (in combined standard errors) is
        within :data:`Z_BOUND`; ``mean_z2``, the mean of z².
    """
    o, so = ours[mask], ours_error[mask]
    t, st = theirs[mask], theirs_error[mask]
    ratio = o.sum(0) / t.sum(0)
    sigma = np.sqrt(np.sum(so**2, 0) + ratio**2 * np.sum(st**2, 0)) / t.sum(0)
    z = (o - t) / np.maximum(np.sqrt(so**2 + st**2), 1e-9)
    return {
        "pixels": int(mask.sum()),
        "ratio": ratio,
        "sigma": sigma,
        "inside": float(np.mean(np.abs(z) < Z_BOUND)),
        "mean_z2": float(np.mean(z**2)),
    }


def compare(
    ctx,
    scene,
    size,
    material_name,
    pixel_filter,
    bounces,
    batches=BATCHES,
    samples=SAMPLES,
    renders=FOOTPRINT_RENDERS,
    tolerance=MODEL_TOLERANCE,
):
    """Render both, print and assert their agreement (the module notes say why so).

    Parameters
    ----------
    ctx
        The test's GL context.
    scene, size
        What to render and at what size.
    material_name : {"diffuse", "ggx", "gold"}
        Key of :data:`MATERIALS`.
    pixel_filter : bool
        Footprint on or off, in both renderers.
    bounces : int
        Our ``u_trace_bounces`` (Mitsuba gets :func:`max_depth` of it).
    batches, samples
        Our independent batches and samples per batch.
    renders
        Mitsuba's footprint renders (:func:`mitsuba`).
    tolerance
        What the two models may differ by, on the ratio of the sums.

    Returns
    -------
    dict
        The interior's :func:`agreement`.
    """
    material, bsdf, threshold = MATERIALS[material_name]
    ours, ours_error, covered = reference(
        ctx, scene, size, material, pixel_filter, batches, samples
    )
    depth = max_depth(bounces)
    theirs, interior = mitsuba(scene, size, bsdf, depth, pixel_filter, covered, threshold, renders)
    label = f"{scene.name} {material_name} pixel_filter={pixel_filter} bounces={bounces}"
    stats = agreement(ours, ours_error, theirs.mean, theirs.standard_error, interior)
    print(f"{label}: {stats}")
    assert stats["pixels"] >= 150, f"{label}: only {stats['pixels']} pixels to compare"
    bound = tolerance + 4 * stats["sigma"]
    assert np.all(np.abs(stats["ratio"] - 1) < bound), f"{label}: {stats}"
    assert stats["inside"] >= Z_INSIDE, f"{label}: {stats}"
    if pixel_filter and material_name == "ggx":
        ring = covered & ~interior & (theirs.coverage > 0)
        edge = agreement(ours, ours_error, theirs.mean, theirs.standard_error, ring)
        print(f"{label}, silhouette: {edge}")
        assert edge["pixels"] >= 20
        bound = SILHOUETTE_TOLERANCE + 4 * edge["sigma"]
        assert np.all(np.abs(edge["ratio"] - 1) < bound), f"{label}, silhouette: {edge}"
    return stats


def test_the_rotated_mitsuba_envmap_reads_our_lat_long_texels():
    """Mitsuba's emitter returns our texel for every direction (module notes of mitsuba_scene).

    An 8 × 16 map of random texels, looked up by Mitsuba's ``envmap`` with
    :data:`mitsuba_scene.ENVIRONMENT_TO_WORLD` (the 180° turn about +Y), equals
    the texel our ``direction_to_uv`` picks, exactly, wherever the direction
    is clear of the blend about a texel edge (a resampling step about a row
    edge, half a step about a column edge); the emitter's power (∫ L dω) is
    the map's. Without the turn most directions read another texel.
    """
    rng = np.random.default_rng(3)
    img = rng.uniform(0.1, 1.0, (8, 16, 3)).astype(np.float32)
    directions = rng.normal(size=(3000, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    uv = latlong.direction_to_uv(directions) * [16, 8]
    texel = img[np.minimum(uv[:, 1], 7).astype(int), np.minimum(uv[:, 0], 15).astype(int) % 16]
    # Mitsuba blends within a resampling step of a row edge, half a step of a column edge
    margin = np.array([0.5, 1.0]) / ms.UPSAMPLE + 1e-3
    frac = uv - np.floor(uv)
    clear = np.all((frac > margin) & (frac < 1 - margin), axis=1)
    assert clear.sum() > 700
    emitter = mi.load_dict(ms.environment_emitter(img))
    radiance = ms.emitter_radiance(emitter, directions)
    np.testing.assert_allclose(radiance[clear], texel[clear], rtol=1e-5)
    unrotated = mi.load_dict({**ms.environment_emitter(img), "to_world": mi.ScalarTransform4f()})
    wrong = ~np.isclose(ms.emitter_radiance(unrotated, directions[clear]), texel[clear]).all(1)
    assert wrong.mean() > 0.8
    # power: a midpoint rule on a grid aligned with the texels and the resampled rows
    grid = latlong.texel_directions(128)
    weights = latlong.texel_solid_angles(128)
    looked_up = ms.emitter_radiance(emitter, grid.reshape(-1, 3)).reshape(128, 256, 3)
    power = np.einsum("hwc,hw->c", looked_up, weights)
    exact = np.einsum("hwc,hw->c", img, latlong.texel_solid_angles(8))
    np.testing.assert_allclose(power, exact, rtol=2e-3)


def test_mitsuba_camera_rays_are_the_orbit_cameras():
    """Through every pixel centre Mitsuba's sensor shoots the ray our matrices unproject there.

    Non-square (aspect 4:3), off-axis camera: the vertical field of view,
    the image's orientation (row 0 at the top, x to the right) and the eye.
    """
    camera = OrbitCamera(azimuth=40.0, elevation=-25.0, distance=2.5, fov_y=50.0)
    camera.target = np.array([0.1, -0.2, 0.3])
    w, h = 8, 6
    sensor = mi.load_dict(ms.sensor(camera, (w, h)))
    inverse = np.linalg.inv(
        camera.projection_matrix(w / h).astype(np.float64) @ camera.view_matrix().astype(np.float64)
    )
    for row in range(h):
        for col in range(w):
            ndc = [(col + 0.5) / w * 2 - 1, 1 - (row + 0.5) / h * 2, 1.0, 1.0]
            far = inverse @ ndc
            expected = far[:3] / far[3] - camera.position
            expected /= np.linalg.norm(expected)
            position = mi.Point2f((col + 0.5) / w, (row + 0.5) / h)
            ray, _ = sensor.sample_ray(0.0, 0.5, position, mi.Point2f(0.5))
            np.testing.assert_allclose(np.array(ray.d), expected, atol=2e-6)
            # it starts on the line from the eye (at the near plane)
            offset = np.array(ray.o) - camera.position
            np.testing.assert_allclose(np.cross(offset, expected), 0.0, atol=2e-6)


@pytest.mark.parametrize("pixel_filter", [False, True], ids=["centre", "footprint"])
@pytest.mark.parametrize("material", ["diffuse", "ggx"])
def test_traced_sphere_agrees_with_mitsuba(gl_ctx, material, pixel_filter):
    """A convex sphere: ours traced, Mitsuba at the matched depth, within the noise of both."""
    scene, size = sphere_scene()
    compare(gl_ctx, scene, size, material, pixel_filter, tracing.TRACE_BOUNCES)


def test_traced_sphere_coloured_fresnel_agrees_with_mitsuba_principled(gl_ctx):
    """f_λ = gold, per channel: ours against Mitsuba's metallic principled BSDF, pixel centres.

    Each channel's ratio is checked on its own (:func:`compare`), so a Fresnel applied to
    the wrong channel, or grey, would show: gold's blue is 0.29 of its red at normal incidence.
    """
    scene, size = sphere_scene()
    stats = compare(gl_ctx, scene, size, "gold", False, tracing.TRACE_BOUNCES)
    assert stats["pixels"] >= 150


#: α of the exact GGX check (N = 12), where over its pixels (n·v > 0.3) Mitsuba's separable
#: Smith term and our height-correlated one differ by 0.06 % on the sum, by 0.6 % per pixel
#: at most (studies/exact-reference/mitsuba_ggx.py), and G is far enough from 1 to matter.
EXACT_GGX_ALPHA, EXACT_GGX_N_DOT_V, EXACT_GGX_SPP = 0.2, 0.3, 1024


def test_exact_ggx_reference_agrees_with_mitsuba(gl_ctx):
    """The exact microfacet reference (measure/exact_lobes.py) against Mitsuba's GGX conductor.

    The sphere at pixel centres, direct lighting (Mitsuba ``max_depth`` 2, our untraced
    model), f_λ = 1, k_d = 0, α = :data:`EXACT_GGX_ALPHA`. tests/test_exact_microfacet.py
    holds the same evaluation against a NumPy sum written from the same formulas; Mitsuba
    checks the formulas themselves (D, the 1 / (4 n·v), and G2 as far as it is Mitsuba's
    separable G here). Measured at 16 384 paths: 1.0006 ± 0.0004 per channel.
    """
    scene, size = sphere_scene()
    exponent = ggx.exponent_for_alpha(EXACT_GGX_ALPHA)
    values = {
        "model": "microfacet",
        "fresnel": (1.0, 1.0, 1.0),
        "kd": (0.0, 0.0, 0.0),
        "phong_exponent": exponent,
    }
    session = RenderSession(scene, ctx=gl_ctx, cube_size=16)
    lobes = LobeEvaluator(session.ctx, session.programs)
    try:
        normals, views = session.renderer.reflector_surface(session.gpu_scene, session.camera, size)
        radiance = scene.environment.radiance
        ours = exact_frame(normals, views, radiance, values, 1, lobes=lobes)
    finally:
        lobes.release()
        session.release()
    mi_scene = ms.load_scene(scene, size, ms.ggx_bsdf(EXACT_GGX_ALPHA), 2)
    _, n_dot_v = ms.centre_rays(mi_scene)
    interior = ours.mask & (np.nan_to_num(n_dot_v, nan=-1.0) > EXACT_GGX_N_DOT_V)
    theirs = ms.render_centres(mi_scene, EXACT_GGX_SPP, mask=interior, seed=1)
    hdr = ours.hdr.astype(np.float64)
    stats = agreement(hdr, np.zeros_like(hdr), theirs.mean, theirs.standard_error, interior)
    print(f"exact GGX against Mitsuba: {stats}")
    assert stats["pixels"] >= 500
    assert np.all(np.abs(stats["ratio"] - 1) < MODEL_TOLERANCE + 4 * stats["sigma"]), stats
    assert stats["inside"] >= Z_INSIDE, stats


@pytest.mark.parametrize("material", ["diffuse", "ggx"])
def test_bunny_self_occlusion_agrees_with_mitsuba_direct_lighting(gl_ctx, monkeypatch, material):
    """One traced segment (``u_trace_bounces`` = 1) is Mitsuba's direct lighting, ``max_depth`` 2.

    A path that meets the bunny again returns black in both: self-occlusion
    alone, whatever a continuing path does.
    """
    monkeypatch.setattr(tracing, "TRACE_BOUNCES", 1)
    scene, size = bunny_scene()
    compare(gl_ctx, scene, size, material, False, 1)


@pytest.mark.parametrize("pixel_filter", [False, True], ids=["centre", "footprint"])
@pytest.mark.parametrize("material", ["diffuse", "ggx"])
def test_bunny_self_reflection_agrees_with_mitsuba(gl_ctx, material, pixel_filter):
    """The bunny's self-occlusion and self-reflections at our full bounce count.

    Under :func:`sky_and_lamp` the bounces off the bunny add 9 % to Mitsuba's
    diffuse image over direct lighting (more than 20 % in a seventh of the
    pixels). A reference that continued such paths as mirror bounces, as ours
    did before issue 13, came out 0.94 of Mitsuba here (diffuse, centre).
    """
    scene, size = bunny_scene()
    compare(gl_ctx, scene, size, material, pixel_filter, tracing.TRACE_BOUNCES)


#: The knot's sample counts: ours 512 per pixel in 32 independent batches, Mitsuba's footprint
#: 16 renders × FOOTPRINT_SPP; the ratio's standard error is then about 0.15 %.
KNOT_BATCHES, KNOT_SAMPLES, KNOT_RENDERS = 32, 16, 16
#: Least noise the knot's ratios must reach, so that the 0.5 % bound means something.
KNOT_SIGMA = 0.002
#: What our diffuse material differs from Mitsuba's by on the knot's interreflections: with
#: f_λ = 0 eq. 8's Schlick F is (1 − n·v)⁵, not 0, so the grazing bounces between the
#: strands continue in the Phong lobe about the mirror direction rather than in the cosine
#: lobe. A scratch build with F = f_λ exactly gave 1.0014 ± 0.0012 of Mitsuba here; ours
#: with Schlick, 0.9933 ± 0.0012.
KNOT_SCHLICK_TOLERANCE = 0.012


def test_knot_self_occlusion_agrees_with_mitsuba_direct_lighting(gl_ctx, monkeypatch):
    """The knot lit directly (one traced segment, Mitsuba ``max_depth`` 2): visibility alone.

    Issue 27 part 5 found the reference 2 % brighter than Mitsuba on a
    self-occluding knot and asked whether light arrives that should be
    blocked (ray origins at concave geometry, BVH misses, occluded
    environment samples). Here every direction blocked by a strand is black
    in both: the interior's mean is held to 0.5 % (measured at 48², 2048 spp:
    0.998 ± 0.001 diffuse, 1.002 ± 0.001 GGX; the suite keeps the diffuse case, GGX
    is held at full bounces below).
    """
    material = "diffuse"
    monkeypatch.setattr(tracing, "TRACE_BOUNCES", 1)
    scene, size = knot_scene()
    stats = compare(
        gl_ctx, scene, size, material, True, 1, KNOT_BATCHES, KNOT_SAMPLES, KNOT_RENDERS
    )
    assert np.all(stats["sigma"] < KNOT_SIGMA), stats


def test_traced_knot_ggx_agrees_with_mitsuba(gl_ctx):
    """The knot's GGX interreflections at our full bounce count, held to 0.5 %.

    GGX with F = 1 is the same model in both (up to the Smith term, which
    differs at grazing only, outside the interior compared): measured 0.999 ± 0.001.
    """
    scene, size = knot_scene()
    stats = compare(
        gl_ctx,
        scene,
        size,
        "ggx",
        True,
        tracing.TRACE_BOUNCES,
        KNOT_BATCHES,
        KNOT_SAMPLES,
        KNOT_RENDERS,
    )
    assert np.all(stats["sigma"] < KNOT_SIGMA), stats


def test_traced_knot_diffuse_agrees_with_mitsuba(gl_ctx):
    """The knot's diffuse interreflections at our full bounce count.

    Held to :data:`KNOT_SCHLICK_TOLERANCE`, not 0.5 %: the difference left is
    the model's (eq. 8's Schlick term at grazing bounces), and it makes ours
    darker, never brighter.
    """
    scene, size = knot_scene()
    stats = compare(
        gl_ctx,
        scene,
        size,
        "diffuse",
        True,
        tracing.TRACE_BOUNCES,
        KNOT_BATCHES,
        KNOT_SAMPLES,
        KNOT_RENDERS,
        KNOT_SCHLICK_TOLERANCE,
    )
    assert np.all(stats["sigma"] < KNOT_SIGMA), stats
    assert np.all(stats["ratio"] < 1.0 + 4 * stats["sigma"]), stats
