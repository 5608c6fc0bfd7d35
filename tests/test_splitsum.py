"""splitsum without GL: the DFG table against quadrature, the GGX kernel, the level mapping."""

import math

import numpy as np
import pytest

from envstudio.core import ggx
from envstudio.methods.splitsum import dfg
from envstudio.methods.splitsum.method import level_alphas, level_of
from envstudio.prefilter import brute_force, kernels
from envstudio.prefilter.chain_gpu import ggx_lobe_samples


def test_dfg_table_matches_quadrature_at_20_points_within_half_a_percent():
    """The cached table, read as the shader reads it, against a 384² Gauss–Legendre rule."""
    table = dfg.load_dfg_table()
    assert dfg.load_dfg_table() is not table  # the second comes from the cache file
    np.testing.assert_array_equal(dfg.load_dfg_table(), table)
    rng = np.random.default_rng(30)
    points = np.column_stack([rng.uniform(0.05, 1.0, 20), rng.uniform(0.1, 1.0, 20) ** 2])
    for n_dot_v, alpha in points:
        a_ref, b_ref = dfg.dfg_quadrature(n_dot_v, alpha, 384)
        a, b = dfg.lookup(table, n_dot_v, alpha)
        for f0 in (0.04, 1.0):  # a dielectric and the white conductor
            expected = f0 * a_ref + b_ref
            assert f0 * a + b == pytest.approx(expected, rel=0.005), (n_dot_v, alpha, f0)


def test_dfg_cache_entry_that_does_not_load_is_computed_again(capsys):
    table = dfg.load_dfg_table(8, 256)
    (entry,) = dfg.cache_dir().glob("dfg-8-*.npy")
    entry.write_bytes(b"not a table")
    np.testing.assert_array_equal(dfg.load_dfg_table(8, 256), table)
    assert "computed again" in capsys.readouterr().err


def test_energy_compensation_makes_the_white_conductor_white():
    a, b = dfg.dfg_quadrature(0.5, 1.0, 256)
    assert a + b < 0.8  # single scattering loses a fifth and more at alpha = 1
    assert (a + b) * dfg.energy_compensation(1.0, a, b) == pytest.approx(1.0)


def test_alpha_and_phong_exponent_map_both_ways():
    for alpha in (0.05, 0.2, 0.5, 0.9, 1.0):
        assert ggx.alpha_for_exponent(ggx.exponent_for_alpha(alpha)) == pytest.approx(alpha)
    assert ggx.alpha_for_exponent(200.0) == pytest.approx(math.sqrt(2.0 / 802.0))


@pytest.mark.parametrize("alpha", [0.2, 1.0])
def test_ggx_kernel_and_lattice_keep_a_constant(alpha):
    constant = np.full((32, 64, 3), 0.7)
    directions = np.array([[0.0, 1.0, 0.0], [0.6, 0.0, 0.8]])
    got = brute_force.prefilter(constant, directions, kernels.ggx(alpha))
    np.testing.assert_allclose(got, 0.7, rtol=0.01)  # the 32-row map's quadrature error
    _, weights = ggx_lobe_samples(alpha, 512)
    assert weights.sum() == pytest.approx(1.0, rel=1e-6)


def test_level_mapping_is_filaments():
    alphas = level_alphas(128)
    assert len(alphas) == 8 and alphas[0] == 0.0 and alphas[-1] == 1.0
    assert alphas[1] == pytest.approx(1 / 49)
    assert level_of(alphas[3], 8) == (3, pytest.approx(0.0))
    assert level_of(1.0, 8) == (6, pytest.approx(1.0))
