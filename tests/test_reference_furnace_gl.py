"""White-furnace checks of the traced reference on a closed, concave shape (issue 27, part 5).

Under a constant environment L the exitant radiance of eq. 8 at a point
seen along v is (1 − F) k_d D + F P with Schlick's F = f_λ + (1 − f_λ)(1 − n·v)⁵
(seed 000 §5.2): D, the cosine-weighted mean of the incident radiance, and P,
the Phong lobe's, are each at most L wherever nothing brighter than L is seen.
On a closed surface everything seen is the environment or the surface itself,
whose radiance, by the same argument, is at most L (every bounce's weight
(1 − F) k_d + F is at most 1), so by induction over the bounces

    L_o ≤ L · a(n·v),  a = (1 − F) k_d + F ≤ 1,

with equality only where the point sees the whole hemisphere unoccluded.
With f_λ = 0 and the diffuse part alone in mind, a ≈ k_d away from grazing
(F < 0.25 % at n·v > 0.7) but tends to 1 at grazing: eq. 8 has no pure
Lambertian material, so the bound is per pixel, through the pixel's own n·v.

Gaining energy (light arriving through surfaces that should block it) shows
as pixels above L · a; counting self-occlusion shows as a mean clearly below
it. The untraced reference, which sees the environment from every point,
meets the bound with equality.
"""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core.bvh import build_bvh, intersect
from envstudio.engine.session import RenderSession
from envstudio.scene.camera import OrbitCamera
from envstudio.scene.environment import Environment
from envstudio.scene.graph import Node, Scene
from envstudio.scene.primitives import torus_knot

#: Constant environment radiance per channel.
RADIANCE = np.array([1.0, 0.5, 0.25])
KD = 0.8
SIZE = (32, 32)
BATCHES, SAMPLES = 16, 16
#: Per-pixel slack in standard errors, plus the n·v differences between the
#: rasterised normal and the CPU ray's (float32 against float64).
Z_BOUND, SLACK = 4.5, 1e-3


def knot_scene() -> Scene:
    """The (2, 3) torus knot (scene/primitives.torus_knot) under the constant environment."""
    mesh = torus_knot().fitted(1.0)
    camera = OrbitCamera(azimuth=30.0, elevation=25.0, distance=2.6, fov_y=45.0)
    environment = Environment(np.broadcast_to(RADIANCE, (16, 32, 3)).astype(np.float32))
    return Scene(environment, [Node("knot", mesh)], camera, "knot")


def centre_n_dot_v(scene: Scene, size) -> np.ndarray:
    """(h, w) shading n·v where each pixel's centre ray meets the knot (CPU BVH), NaN off it."""
    mesh = scene.reflectors()[0].mesh
    tris = mesh.positions[mesh.indices].astype(np.float64)
    normals = mesh.normals[mesh.indices].astype(np.float64)
    bvh = build_bvh(tris)
    camera = scene.camera
    w, h = size
    inverse = np.linalg.inv(
        camera.projection_matrix(w / h).astype(np.float64) @ camera.view_matrix().astype(np.float64)
    )
    eye = np.asarray(camera.position, np.float64)
    out = np.full((h, w), np.nan)
    for row in range(h):
        for col in range(w):
            far = inverse @ [(col + 0.5) / w * 2 - 1, 1 - (row + 0.5) / h * 2, 1.0, 1.0]
            d = far[:3] / far[3] - eye
            d /= np.linalg.norm(d)
            t, tri = intersect(bvh, tris, eye, d)
            if tri < 0:
                continue
            # barycentrics of the hit, then the interpolated normal (as trace.glsl)
            a, b, c = tris[tri]
            p = eye + t * d
            m = np.column_stack([b - a, c - a])
            u, v = np.linalg.lstsq(m, p - a, rcond=None)[0]
            n = (1 - u - v) * normals[tri, 0] + u * normals[tri, 1] + v * normals[tri, 2]
            out[row, col] = -(n @ d) / np.linalg.norm(n)
    return out


def furnace(ctx, scene: Scene, trace: bool):
    """Our reference at the pixel centres, k_d = :data:`KD`, f_λ = 0 (estimate, error, coverage)."""
    session = RenderSession(scene, ctx=ctx, cube_size=16)
    method = session.method("reference")
    method.values.update(
        {
            "model": "phong",
            "kd": KD,
            "fresnel": 0.0,
            "phong_exponent": 1.0,
            "trace": trace,
            "pixel_filter": False,
            "sequence": "random",
            "adaptive": False,
            "samples": SAMPLES,
            "max_samples": 10**6,
            "tolerance": 1e-5,
        }
    )
    session.renderer.display["background"] = False
    for _ in range(BATCHES):
        session.render_offscreen(method, SIZE)
    result = (
        method.estimate().astype(np.float64) / RADIANCE,
        method.standard_error().astype(np.float64) / RADIANCE,
        method.coverage(),
    )
    session.release()
    return result


@pytest.fixture(scope="module")
def albedo():
    """(h, w) the bound a(n·v) = (1 − F) k_d + F at each pixel centre, NaN off the knot."""
    n_dot_v = centre_n_dot_v(knot_scene(), SIZE)
    fresnel = (1.0 - np.clip(n_dot_v, 0.0, 1.0)) ** 5
    return (1.0 - fresnel) * KD + fresnel


def test_traced_concave_knot_never_exceeds_the_furnace_bound(gl_ctx, albedo):
    """Traced, 3 bounces: no pixel above L (the environment) nor above L · a(n·v).

    Measured at 32², 256 spp: the interior's mean (n·v above about 0.6) is
    0.91 of the bound, the light the strands hide from one another.
    """
    ratio, error, covered = furnace(gl_ctx, knot_scene(), trace=True)
    pixels = covered & np.isfinite(albedo)
    assert pixels.sum() > 250
    assert (covered != np.isfinite(albedo)).sum() < 0.03 * pixels.sum()
    bound = albedo[pixels][:, None]
    value, sigma = ratio[pixels], error[pixels]
    # never brighter than the environment itself, nor than the albedo bound
    assert np.all(value <= 1.0 + Z_BOUND * sigma + SLACK), value.max()
    excess = (value - bound) / np.maximum(sigma, 1e-9)
    assert np.all(value <= bound + Z_BOUND * sigma + SLACK), (excess.max(), value.max())
    # self-occlusion is counted: the mean lies well below the unoccluded value
    interior = pixels & (albedo < KD + 0.01)
    share = ratio[interior].mean(axis=0) / albedo[interior].mean()
    print(f"traced furnace: mean / bound {share}, largest {np.max(value / bound, axis=0)}")
    assert np.all(share < 0.95), share
    assert np.all(ratio[interior].mean(axis=0) < KD), share


def test_untraced_knot_meets_the_furnace_bound(gl_ctx, albedo):
    """Untraced (no occlusion): every pixel is L · a(n·v) exactly, within its noise.

    The closed form the traced knot must stay under; it checks that the bound
    itself, and the n·v it is taken at, are the reference's.
    """
    ratio, error, covered = furnace(gl_ctx, knot_scene(), trace=False)
    pixels = covered & np.isfinite(albedo) & (albedo < 0.95)
    assert pixels.sum() > 250
    bound = albedo[pixels][:, None]
    z = (ratio[pixels] - bound) / np.maximum(error[pixels], 1e-9)
    share = ratio[pixels].mean(0) / bound.mean()
    print(f"untraced furnace: mean / bound {share}, max |z| {abs(z).max()}")
    np.testing.assert_allclose(share, 1.0, atol=2e-3)
    assert np.mean(np.abs(z) < Z_BOUND) > 0.99


def test_torus_knot_is_a_closed_outward_surface():
    """4160 triangles, every edge shared by two, wound counter-clockwise seen from outside.

    Its normals are unit and agree with the winding; its volume is the tube's,
    π tube² times the knot curve's length (to the polygon's area, cos-factor).
    """
    mesh = torus_knot()
    assert mesh.triangle_count == 4160
    edges = np.sort(mesh.indices[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    _, uses = np.unique(edges, axis=0, return_counts=True)
    assert np.all(uses == 2)
    tris = mesh.positions[mesh.indices].astype(np.float64)
    face = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    assert np.all(np.einsum("ij,ij->i", face, mesh.normals[mesh.indices].sum(1)) > 0)
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-6)
    volume = np.einsum("ij,ij->i", tris[:, 0], np.cross(tris[:, 1], tris[:, 2])).sum() / 6
    u = np.linspace(0.0, 4.0 * np.pi, 20001)
    ring = 2.0 + np.cos(1.5 * u)
    curve = 0.5 * np.stack([ring * np.cos(u), ring * np.sin(u), np.sin(1.5 * u)], -1)
    length = np.linalg.norm(np.diff(curve, axis=0), axis=1).sum()
    polygon = 0.5 * 13 * np.sin(2 * np.pi / 13) * 0.4**2  # the 13-gon's cross-section
    np.testing.assert_allclose(volume, polygon * length, rtol=0.02)
