"""Order-2 spherical harmonics of seed 000 section 4.1 (no GL)."""

from __future__ import annotations

import numpy as np
import pytest

from envstudio.core import cubemap, latlong, sh

COEFFS = np.random.default_rng(7).normal(size=(9, 3))


def frame(n: np.ndarray) -> np.ndarray:
    """(3, 3) orthonormal basis with n as its third column."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t = np.cross(helper, n)
    t /= np.linalg.norm(t)
    return np.stack([t, np.cross(n, t), n], axis=-1)


def hemisphere_cosine_integral(radiance, n: np.ndarray) -> np.ndarray:
    """E(n) = ∫_{n·l > 0} L(l) (n·l) dl by Gauss–Legendre in μ = n·l and the trapezoid
    rule in φ; exact to rounding for L a polynomial of order ≤ 2 in l."""
    mu, w_mu = np.polynomial.legendre.leggauss(16)
    mu, w_mu = 0.5 * (mu + 1.0), 0.5 * w_mu  # [-1, 1] -> [0, 1]
    phi = 2.0 * np.pi * np.arange(16) / 16
    m, p = np.meshgrid(mu, phi, indexing="ij")
    r = np.sqrt(1.0 - m * m)
    local = np.stack([r * np.cos(p), r * np.sin(p), m], axis=-1)
    world = local @ frame(n).T
    weights = (w_mu[:, None] * (2.0 * np.pi / 16)) * m  # dμ dφ times the cosine
    return np.einsum("ij,ijc->c", weights, radiance(world))


def test_constants_follow_eq_9_and_eq_12():
    x, y, z = 0.36, 0.48, 0.8
    Y = sh.sh9_basis([x, y, z])
    c1, c2 = np.sqrt(3 / (4 * np.pi)), np.sqrt(15 / (4 * np.pi))
    expected = [
        1 / np.sqrt(4 * np.pi),
        c1 * y,
        c1 * z,
        c1 * x,
        c2 * x * y,
        c2 * y * z,
        np.sqrt(5 / (16 * np.pi)) * (3 * z * z - 1),
        c2 * x * z,
        np.sqrt(15 / (16 * np.pi)) * (x * x - y * y),
    ]
    np.testing.assert_allclose(Y, expected, rtol=1e-15)
    np.testing.assert_allclose(sh.A_HAT, [np.pi] + [2 * np.pi / 3] * 3 + [np.pi / 4] * 5)


def test_basis_is_orthonormal():
    n = 64
    Y = sh.sh9_basis(cubemap.texel_directions(n)).reshape(-1, 9)
    w = cubemap.texel_solid_angles(n).reshape(-1)
    np.testing.assert_allclose((Y * w[:, None]).T @ Y, np.eye(9), atol=2e-4)


def test_projection_recovers_coefficients_from_a_cube_map():
    n = 128
    faces = sh.sh9_basis(cubemap.texel_directions(n)) @ COEFFS
    np.testing.assert_allclose(sh.project_cube_sh9(faces), COEFFS, atol=1e-4)


def test_projection_recovers_coefficients_from_a_latlong_map():
    img = sh.sh9_basis(latlong.texel_directions(256)) @ COEFFS
    np.testing.assert_allclose(sh.project_latlong_sh9(img), COEFFS, atol=1e-4)


def test_constant_environment_has_irradiance_pi_l():
    L = np.array([0.5, 1.0, 2.0])
    faces = np.broadcast_to(L, (6, 16, 16, 3))
    coeffs = sh.project_cube_sh9(faces)
    np.testing.assert_allclose(coeffs[0], L * np.sqrt(4 * np.pi), rtol=1e-12)
    np.testing.assert_allclose(coeffs[1:], 0.0, atol=1e-12)
    normals = np.array([[0, 1, 0], [0.6, 0, -0.8], [0, 0, -1]])
    np.testing.assert_allclose(
        sh.irradiance_sh9(coeffs, normals), np.tile(np.pi * L, (3, 1)), rtol=1e-12
    )


def test_irradiance_matches_a_hemispherical_cosine_integral():
    """For an environment of order ≤ 2 the 9-term formula of eq. 12 is exact."""

    def radiance(d):
        return sh.sh9_basis(d) @ COEFFS

    rng = np.random.default_rng(11)
    normals = rng.normal(size=(12, 3))
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    irradiance = sh.irradiance_sh9(COEFFS, normals)
    for n, e in zip(normals, irradiance, strict=True):
        np.testing.assert_allclose(e, hemisphere_cosine_integral(radiance, n), atol=1e-10)


def test_project_then_irradiance_of_a_smooth_cube_map():
    """The whole path: a sampled order-2 environment, projected, then looked up by normal."""

    def radiance(d):
        x, y, z = d[..., 0], d[..., 1], d[..., 2]
        return np.stack([1.0 + 0.5 * x + 0.2 * y * z, 1.0 + 0.3 * z * z, 0.6 - 0.4 * y], -1)

    coeffs = sh.project_cube_sh9(radiance(cubemap.texel_directions(128)))
    for n in np.eye(3):
        expected = hemisphere_cosine_integral(radiance, n)
        np.testing.assert_allclose(sh.irradiance_sh9(coeffs, n), expected, rtol=1e-4)


def test_shapes_are_checked():
    with pytest.raises(ValueError, match="leading shape"):
        sh.project_sh9(np.ones((4, 3)), np.ones((5, 3)), np.ones(4))
    with pytest.raises(ValueError, match=r"\(9, 3\)"):
        sh.irradiance_sh9(np.ones((4, 3)), [0, 0, 1])
    with pytest.raises(ValueError):
        sh.project_cube_sh9(np.ones((6, 4, 5, 3)))
