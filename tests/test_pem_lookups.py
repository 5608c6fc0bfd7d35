"""PEM bake, all MIP levels (seed 003 §4): lookups, trilinear A, the multi-level solve, hull."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core.cubemap import direction_to_uv
from envstudio.methods.pem.bake import SceneTracer
from envstudio.methods.pem.bake.hull import hull_mask, mesh_check, node_world_mesh, reflector_hulls
from envstudio.methods.pem.bake.infer import distant_box, infer_mip, local_ellipsoid
from envstudio.methods.pem.bake.lookups import MODELS, pixel_lookups, trilinear_matrix
from envstudio.methods.pem.bake.mip import decimate, decimated_chain, level_offsets, mip_sizes
from envstudio.methods.pem.bake.models import (
    fit_pixels,
    infer_view_models,
    playback_psnr,
    predict,
    static_em,
)
from envstudio.methods.pem.bake.pem_file import decode_levels, encode_levels
from envstudio.scene.graph import Node, Transform
from envstudio.scene.primitives import uv_sphere


@pytest.fixture(scope="module")
def room():
    from envstudio.io.scene_file import load_scene

    scene = load_scene("room")
    tracer = SceneTracer(scene)
    view = tracer.trace(scene.camera, size=40, samples=4)
    local = [local_ellipsoid(tracer, p) for p in range(len(tracer.part_names))]
    lookups = pixel_lookups(
        tracer,
        scene.camera,
        40,
        8,
        distant_box(scene),
        [g for g, _ in local],
        [o for _, o in local],
    )
    return scene, tracer, view, lookups


def _brute(face, st, lod, n, levels):
    """Per-entry trilinear weights {column: weight} written out from the contract."""
    out = {}
    offsets = level_offsets(n, levels)
    lod = min(max(lod, 0.0), levels - 1)
    l0 = int(np.floor(lod))
    l1 = min(l0 + 1, levels - 1)
    for level, share in ((l0, 1 - (lod - l0)), (l1, lod - l0)):
        nk = n >> level
        x, y = st[0] * nk - 0.5, st[1] * nk - 0.5
        j0, i0 = int(np.floor(x)), int(np.floor(y))
        fx, fy = x - j0, y - i0
        for i, wy in ((i0, 1 - fy), (i0 + 1, fy)):
            for j, wx in ((j0, 1 - fx), (j0 + 1, fx)):
                ii, jj = min(max(i, 0), nk - 1), min(max(j, 0), nk - 1)
                col = offsets[level] + face * nk * nk + ii * nk + jj
                out[col] = out.get(col, 0.0) + share * wy * wx
    return out


def test_trilinear_rows_sum_to_one_and_match_a_brute_evaluation():
    rng = np.random.default_rng(1)
    m, n, levels = 300, 8, 4
    face = rng.integers(0, 6, m)
    st = rng.random((m, 2))
    st[:5] = [[0, 0], [1, 1], [0.5, 0.001], [0.999, 0.5], [0.0625, 0.0625]]
    lod = rng.uniform(-1.0, levels + 0.5, m)
    A = trilinear_matrix(np.arange(m), face, st, lod, n, levels, m + 4)
    assert A.shape == (m + 4, level_offsets(n, levels)[-1])
    sums = np.asarray(A.sum(axis=1)).ravel()
    np.testing.assert_allclose(sums[:m], 1.0, atol=1e-12)
    assert (sums[m:] == 0).all()
    dense = A.toarray()
    for e in range(m):
        row = np.zeros(A.shape[1])
        for col, w in _brute(face[e], st[e], lod[e], n, levels).items():
            row[col] += w
        np.testing.assert_allclose(dense[e], row, atol=1e-12)
    # several weighted lookups in one pixel: the weighted sum of their rows
    pix = np.array([0, 0, 1])
    w = np.array([0.25, 0.75, 2.0])
    B = trilinear_matrix(pix, face[:3], st[:3], lod[:3], n, levels, 2, weight=w).toarray()
    np.testing.assert_allclose(B[0], 0.25 * dense[0] + 0.75 * dense[1], atol=1e-12)
    np.testing.assert_allclose(B[1], 2.0 * dense[2], atol=1e-12)


def test_pixel_lookups_follow_the_contract(room):
    scene, tracer, view, lookups = room
    assert lookups.part.dtype == np.int8 and lookups.part.shape == (40, 40)
    on = lookups.part >= 0
    assert on.sum() > 100 and (view.coverage.sum(axis=0)[on] > 0).all()
    for model in MODELS:
        assert (lookups.face[model][on] >= 0).all() and (lookups.face[model][~on] == -1).all()
        assert np.isfinite(lookups.lod[model]).all()
        for p in range(len(tracer.part_names)):
            sums = np.asarray(lookups.matrix(model, p).sum(axis=1)).ravel()
            np.testing.assert_allclose(sums[lookups.part.ravel() == p], 1.0, atol=1e-9)
            assert (sums[lookups.part.ravel() != p] == 0).all()
    # the sphere model's lookup is the reflection at the pixel centre
    _, o, d = tracer.centre_rays(scene.camera, 40)
    tri, _, u, v = tracer._intersect(False, o, d)
    i = np.flatnonzero(on.ravel())
    n = tracer._shading_normal(tri[i], u[i], v[i], d[i])
    r = d[i] - 2 * np.einsum("ij,ij->i", d[i], n)[:, None] * n
    face, st = direction_to_uv(r)
    np.testing.assert_array_equal(lookups.face["sphere"].ravel()[i], face)
    np.testing.assert_allclose(lookups.st["sphere"].reshape(-1, 2)[i], st, atol=1e-6)
    part = lookups.part.ravel()[i]
    np.testing.assert_array_equal(tri[i] - tracer.part_start[part], lookups.triangle.ravel()[i])


def _smooth_levels(n, levels, channels, seed):
    """A known map: per level a smooth positive function of the texel direction."""
    from envstudio.core.cubemap import texel_directions

    rng = np.random.default_rng(seed)
    out = []
    for k, nk in enumerate(mip_sizes(n, levels)):
        d = texel_directions(nk)
        coef = rng.uniform(-0.2, 0.2, (3, channels))
        out.append(0.5 + 0.1 * k + d @ coef)
    return out


def test_inference_recovers_a_known_multi_level_map():
    rng = np.random.default_rng(7)
    n, levels, m = 8, 4, 24000
    d = rng.normal(size=(m, 3))
    d[:, 2] = np.abs(d[:, 2]) + 0.3 * np.abs(d[:, :2]).max(axis=1)  # −Z face never looked up
    face, st = direction_to_uv(d)
    lod = rng.uniform(0.0, levels - 1, m)
    A = trilinear_matrix(np.arange(m), face, st, lod, n, levels, m)
    truth = _smooth_levels(n, levels, 3, 2)
    x_true = np.concatenate([x.reshape(-1, 3) for x in truth])
    b = A @ x_true
    res = infer_mip(A, np.ones(m, bool), b, n, levels, smoothness=1e-7, tie=1e-7, rtol=1e-12)
    weight = np.asarray(A.sum(axis=0)).ravel()
    got = res.flat()
    contributing = weight > 0.5
    assert contributing.sum() > 0.4 * len(weight)
    np.testing.assert_allclose(got[contributing], x_true[contributing], atol=1e-3)
    # −Z texels no lookup reaches are filled from their neighbours: finite, non-zero
    offsets = level_offsets(n, levels)
    dark = [
        np.arange(o + 5 * nk * nk, o + 6 * nk * nk)
        for o, nk in zip(offsets, mip_sizes(n), strict=False)
    ]
    dark = np.concatenate(dark)
    assert (weight[dark] == 0).sum() > 20
    fill = got[dark][weight[dark] == 0]
    assert np.isfinite(fill).all() and (fill > 0.1).all()
    assert np.abs(fill - x_true[dark][weight[dark] == 0]).max() < 0.5


def test_local_rgba_inference_keeps_its_range(room):
    _, _, view, lookups = room
    n, part = 8, 0
    A = lookups.matrix("local", part)
    levels = _smooth_levels(n, None, 4, 5)
    for lv in levels:  # premultiplied: alpha in (0, 1), rgb ≤ alpha
        lv[..., 3] = np.clip(lv[..., 3], 0.05, 0.95)
        lv[..., :3] = np.minimum(lv[..., :3], lv[..., 3:]) * 0.9
    x_true = np.concatenate([x.reshape(-1, 4) for x in levels])
    pixels = lookups.part.ravel() == part
    b = A @ x_true
    res = infer_mip(A, pixels, b, n, smoothness=1e-6, tie=1e-6, hi=[np.inf] * 3 + [1.0])
    assert res.psnr > 40
    # a real local layer (alpha 0 on hull triangles) fits within [0, 1] alpha, rgb ≥ 0
    hull = reflector_hulls(room[0])
    models = infer_view_models(view, lookups, n, hull)
    for fit in models.fits["local"]:
        x = fit.flat()
        assert x.shape[1] == 4 and (x >= 0).all() and (x[:, 3] <= 1).all()
    predicted = predict(
        view, lookups, models, n, hull, static_em(room[1], room[0].reflector_centre(), n)
    )
    scores = playback_psnr(view, lookups, predicted)
    assert set(scores) == {"layered", "sphere", "static", "ptm"}
    assert scores["layered"] > scores["static"] + 3 and scores["sphere"] > scores["static"] + 3
    assert fit_pixels(view, lookups, 0).sum() > 50


def test_hull_masks():
    sphere = uv_sphere(1.0, 16, 32)
    assert hull_mask(sphere.positions, sphere.indices).all()
    from envstudio.io.scene_file import load_scene

    scene = load_scene("room")
    masks = reflector_hulls(scene)
    teapot, lid = scene.reflectors()
    assert [len(m) for m in masks] == [teapot.mesh.triangle_count, lid.mesh.triangle_count]
    assert 0 < masks[0].sum() < len(masks[0])  # body on the hull, spout and handle inside
    alone = hull_mask(*node_world_mesh(teapot))
    assert (alone >= masks[0]).all()  # the union's hull touches fewer triangles
    check = mesh_check(teapot)
    assert check["triangles"] == teapot.mesh.triangle_count and len(check["sha256"]) == 64
    moved = Node("teapot", teapot.mesh, teapot.material, Transform((0.0, 1e-3, 0.0), scale=0.06))
    assert mesh_check(moved)["sha256"] != check["sha256"]


def _hull_mask_brute_force(v, f, hull_points, tol=1e-5, cos_tol=0.999):
    """Every triangle against every facet (what hull_mask's normal search must equal)."""
    from scipy.spatial import ConvexHull

    planes = np.unique(np.round(ConvexHull(hull_points).equations, 9), axis=0)
    scale = float(np.linalg.norm(np.ptp(hull_points, axis=0)))
    c = v[f]
    normal = np.cross(c[:, 1] - c[:, 0], c[:, 2] - c[:, 0])
    length = np.linalg.norm(normal, axis=1)
    unit = normal / np.where(length > 0, length, 1.0)[:, None]
    dist = np.einsum("kcx,fx->kcf", c, planes[:, :3]) + planes[:, 3]
    on_plane = np.all(np.abs(dist) <= tol * scale, axis=1)
    parallel = np.abs(unit @ planes[:, :3].T) >= cos_tol
    degenerate = (length <= 1e-10 * scale * scale)[:, None]
    return np.any(on_plane & (parallel | degenerate), axis=1)


def test_hull_mask_equals_every_triangle_against_every_facet():
    from envstudio.io.scene_file import load_scene

    teapot, lid = load_scene("room").reflectors()
    meshes = [node_world_mesh(n) for n in (teapot, lid)]
    points = np.concatenate([m[0] for m in meshes]).astype(np.float64)
    for v, f in meshes:
        v = v.astype(np.float64)
        f = np.concatenate([f, [[f[0, 0], f[0, 0], f[0, 1]]]])  # and a degenerate one
        for faces in (f, f[:, ::-1]):  # either winding
            fast = hull_mask(v, faces, hull_points=points)
            assert fast.tolist() == _hull_mask_brute_force(v, faces, points).tolist()
            assert 0 < fast.sum() < len(faces)


def test_levels_as_residuals_round_trip():
    rng = np.random.default_rng(0)
    finest = rng.random((2, 6, 8, 8, 3)).astype(np.float32)
    chain = [finest]
    for _ in range(3):
        chain.append(
            decimate(chain[-1].reshape(-1, *chain[-1].shape[-3:])).reshape(
                2, 6, *[chain[-1].shape[2] // 2] * 2, 3
            )
        )
    chain = [c + 0.01 * rng.standard_normal(c.shape).astype(np.float32) for c in chain]
    stored = encode_levels(chain)
    assert all(s.dtype == np.float16 for s in stored)
    assert max(float(np.abs(s).max()) for s in stored[1:]) < 0.1  # residuals are small
    back = decode_levels(stored)
    for a, b in zip(back, chain, strict=True):
        np.testing.assert_allclose(a, b, atol=2e-3)
    assert len(decimated_chain(finest[0])) == 4
