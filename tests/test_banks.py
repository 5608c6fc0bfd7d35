"""Method banks without GL: the Banks lobe and its integral, the ring-form map against a
brute-force integral, its symmetry, tangent fields, bad input (seed 004 §5.3)."""

import numpy as np
import pytest

from envstudio.core import latlong, resample
from envstudio.errors import ParameterError
from envstudio.io.meshes import load_mesh
from envstudio.methods.banks import lobe as banks
from envstudio.methods.banks.maps import MapSpec, build_cpu, rings_cpu
from envstudio.methods.banks.method import BanksMethod
from envstudio.resources import asset_root
from envstudio.scene.primitives import uv_sphere
from envstudio.scene.tangents import TangentField, mesh_tangents

SHARPNESS = (0.0, 0.5, 0.9, 0.99)


def smooth_environment(height: int = 64) -> np.ndarray:
    """(h, 2h, 3) float32: low-order polynomials of the direction plus a broad lobe."""
    x, y, z = np.moveaxis(latlong.texel_directions(height), -1, 0)
    blob = 3.0 * np.exp(8.0 * (0.6 * x + 0.8 * y - 1.0))
    channels = [1.5 + 0.5 * x + 0.3 * y - 0.4 * z + 0.3 * x * y + blob, 1.2 - 0.3 * x + 0.5 * z * z]
    channels.append(1.0 + 0.2 * y + 0.4 * x * z + blob)
    return np.stack(channels, -1).astype(np.float32)


def brute_force(image: np.ndarray, tangent, v_dot_t: float, sharpness: float) -> np.ndarray:
    """(3,) ∫ f(v, l) L(l) dl over every lat-long texel (§5.3, ⟨n,l⟩ dropped)."""
    h = image.shape[0]
    d = latlong.texel_directions(h)
    omega = latlong.texel_solid_angles(h)
    f = banks.lobe(d @ np.asarray(tangent, np.float64), v_dot_t, sharpness)
    return np.einsum("hw,hw,hwc->c", f, omega, image.astype(np.float64))


@pytest.mark.parametrize("s", SHARPNESS)
def test_the_closed_form_lobe_integral_matches_quadrature_and_the_weights(s):
    a = np.linspace(-1.0, 1.0, 400_001)
    for b in (-0.9, -0.3, 0.0, 0.42, 0.97, 1.0):
        numeric = 2.0 * np.pi * np.trapezoid(banks.lobe(a, b, s), a)
        assert banks.lobe_integral(b, s) == pytest.approx(numeric, rel=2e-4)
    weights = banks.ring_weights(16, 128, s)
    expected = banks.lobe_integral(np.cos(banks.slice_angles(16)), s)
    np.testing.assert_allclose(2.0 * np.pi * weights.sum(1), expected, rtol=2e-4)


def test_a_constant_environment_gives_a_map_independent_of_t_equal_to_the_lobe_integral():
    colour = np.array([0.25, 0.5, 4.0])
    faces = np.broadcast_to(colour, (6, 32, 32, 3))
    for s in (0.5, 0.99):
        spec = MapSpec(size=12, slices=9, bins=64, sharpness=s)
        m = build_cpu(faces, spec, progress=False)
        expected = banks.lobe_integral(np.cos(banks.slice_angles(spec.slices)), s)
        want = np.broadcast_to(expected[:, None, None, None] * colour, m[..., :3].shape)
        np.testing.assert_allclose(m[..., :3], want, rtol=3e-4)
        np.testing.assert_allclose(
            m[..., 3], np.broadcast_to(expected[:, None, None], m.shape[:3]), rtol=3e-4
        )
        assert np.ptp(m[..., :3] / m[..., 3:], axis=(1, 2)).max() < 1e-5  # no dependence on t


@pytest.mark.parametrize("s", (0.5, 0.9))
def test_the_map_matches_a_brute_force_integral_at_a_few_texels(s):
    """Map texels (front face, border included) against ∑ f L Ω over a 128 × 256 lat-long;
    within 0.2 % (measured 0.021 % at s = 0.5, 0.029 % at s = 0.9)."""
    image = smooth_environment(128)
    faces = resample.latlong_to_cube(image, 64)
    spec = MapSpec(size=10, slices=12, bins=96, sharpness=s)
    m = build_cpu(faces, spec, progress=False)
    tangents = banks.texel_tangents(spec.size)
    angles = banks.slice_angles(spec.slices)
    for i, j, k in ((0, 0, 3), (5, 4, 6), (9, 2, 0), (3, 7, 11), (4, 5, 5)):
        expected = brute_force(image, tangents[i, j], np.cos(angles[k]), s)
        np.testing.assert_allclose(m[k, i, j, :3], expected, rtol=2e-3, err_msg=str((i, j, k)))


def test_the_map_is_unchanged_under_t_to_minus_t_with_v_dot_t_to_minus_v_dot_t():
    image = smooth_environment(64)
    faces = resample.latlong_to_cube(image, 32)
    spec = MapSpec(size=8, slices=10, bins=64, sharpness=0.9)
    weights = banks.ring_weights(spec.slices, spec.bins, spec.sharpness)
    t = banks.texel_tangents(spec.size).reshape(-1, 3)
    forward = np.einsum("jk,pkc->jpc", weights, rings_cpu(faces, t, spec))
    backward = np.einsum("jk,pkc->jpc", weights, rings_cpu(faces, -t, spec))
    # slice B-1-j is θ_v → π − θ_v, i.e. ⟨v,t⟩ → −⟨v,t⟩
    np.testing.assert_allclose(backward[::-1], forward, rtol=5e-3)
    a, b = np.random.default_rng(1).uniform(-1, 1, (2, 1000))
    np.testing.assert_array_equal(banks.lobe(-a, -b, 0.7), banks.lobe(a, b, 0.7))


def test_texture_coordinates_fold_onto_the_front_face():
    rng = np.random.default_rng(2)
    t = rng.normal(size=(200, 3))
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = rng.uniform(-1, 1, 200)
    np.testing.assert_allclose(
        banks.texture_coordinates(t, b, 64), banks.texture_coordinates(-t, -b, 64)
    )
    uvw = banks.texture_coordinates(t, b, 64)
    assert uvw.min() >= 0.0 and uvw.max() <= 1.0


@pytest.mark.parametrize("kind", ("axis", "radial", "direction", "uv"))
def test_tangent_fields_on_a_sphere_are_unit_and_orthogonal_to_the_normals(kind):
    sphere = uv_sphere(1.0, 16, 32)
    tangents = mesh_tangents(sphere, TangentField(kind, "y"))
    t, n = tangents.vectors.astype(np.float64), sphere.normals.astype(np.float64)
    assert np.all(np.isfinite(t))
    np.testing.assert_allclose(np.linalg.norm(t, axis=1), 1.0, atol=1e-6)
    assert np.abs(np.sum(t * n, 1)).max() < 1e-5
    if kind == "axis":  # around Y: horizontal, along increasing azimuth; the poles fall back
        poles = np.abs(n[:, 1]) > 1 - 1e-6
        assert tangents.degenerate == poles.sum() > 0
        np.testing.assert_allclose(t[~poles, 1], 0.0, atol=1e-6)
        expected = np.cross((0.0, 1.0, 0.0), n[~poles])
        expected /= np.linalg.norm(expected, axis=1, keepdims=True)
        np.testing.assert_allclose(t[~poles], expected, atol=1e-5)
    if kind == "uv":  # the sphere's u is its azimuth: the same circles (where not degenerate)
        axis = mesh_tangents(sphere, TangentField("axis", "y")).vectors
        ok = np.abs(n[:, 1]) < 0.99
        assert np.abs(np.sum(t[ok] * axis[ok], 1)).min() > 0.99


def test_a_mesh_without_uvs_falls_back_with_a_note_and_degenerate_tangents_have_no_nan():
    teapot = load_mesh(asset_root() / "mesh" / "teapot.obj").fitted(1.0)
    assert teapot.uvs is None
    tangents = mesh_tangents(teapot, TangentField("uv", "y"))
    assert tangents.kind == "axis" and "no texture coordinates" in tangents.note
    # along Y: the sphere's poles have n ∥ t, the degenerate case
    sphere = uv_sphere(1.0, 8, 16)
    along = mesh_tangents(sphere, TangentField("direction", "y"))
    assert along.degenerate > 0 and np.all(np.isfinite(along.vectors))
    np.testing.assert_allclose(np.linalg.norm(along.vectors, axis=1), 1.0, atol=1e-6)


def test_bad_input_sharpness_outside_zero_one_and_unknown_fields():
    declared = {p.name: p for p in BanksMethod.parameters}
    for bad in (1.0, 1.5, -0.1, "nan"):
        with pytest.raises(ParameterError, match="sharpness"):
            declared["sharpness"].validate(bad)
    for bad in (1.0, -0.5):
        with pytest.raises(ValueError, match="sharpness"):
            banks.lobe(0.0, 0.0, bad)
        with pytest.raises(ValueError, match="sharpness"):
            MapSpec(sharpness=bad)
    with pytest.raises(ParameterError, match="tangent_field"):
        declared["tangent_field"].validate("spiral")
    with pytest.raises(ValueError, match="tangent_axis"):
        TangentField("axis", "w")
