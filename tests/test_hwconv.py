"""Method hwconv without GL: seed 004 §5.2's radii, filter sizes, shrink factors, blend."""

import math

import numpy as np
import pytest

from envstudio.errors import ParameterError
from envstudio.methods.hwconv.radii import (
    blend_weight,
    clamp_angle,
    kernel_weights,
    large_radius,
    plan_filters,
    shrink_factor,
    small_radius,
)

# §5.2's table: exponent → filter size small/large (texels), shrink factor small/large,
# for 512-texel faces, ε = 0.1 and a maximum kernel of 7.
PAPER = {
    10: (174, 260, 32, 64),
    50: (78, 136, 16, 32),
    100: (56, 100, 8, 16),
    250: (36, 66, 8, 16),
    500: (26, 48, 4, 8),
}


@pytest.mark.parametrize("exponent", sorted(PAPER))
def test_filter_sizes_and_shrink_factors_match_the_papers_table(exponent):
    plan = plan_filters(exponent, 0.1, 512, 64, 7)
    small, large, shrink_s, shrink_l = PAPER[exponent]
    # "Within rounding": the table's sizes are 2·⌈r⌉; r itself is within 1 texel of half.
    assert (plan.size_small, plan.size_large) == (small, large)
    assert abs(2 * plan.radius_small - small) <= 2 and abs(2 * plan.radius_large - large) <= 2
    assert (plan.shrink_small, plan.shrink_large) == (shrink_s, shrink_l)
    assert plan.size_small / plan.shrink_small <= 7 < plan.size_small / (plan.shrink_small / 2)


def test_radii_from_the_paraboloid_mapping():
    theta = clamp_angle(100, 0.1)
    assert math.cos(theta) ** 100 == pytest.approx(0.1)
    # A cap of angular radius θ about +Z spans s = tan(θ/2) (core.paraboloid).
    assert small_radius(theta, 1.0) == pytest.approx(math.sin(theta) / (1 + math.cos(theta)))
    # About the rim its inner edge lies at angle π/2 − θ from the axis.
    inner = 0.5 * math.pi - theta
    assert 1 - large_radius(theta, 1.0) == pytest.approx(math.sin(inner) / (1 + math.cos(inner)))
    # "The ratio between the smallest filter radius and largest filter radius is about 2".
    tiny = clamp_angle(1e6, 0.1)
    assert large_radius(tiny, 1.0) / small_radius(tiny, 1.0) == pytest.approx(2.0, rel=1e-2)


def test_shrink_halves_until_the_kernel_fits():
    assert shrink_factor(7, 7) == 1
    assert shrink_factor(8, 7) == 2
    assert shrink_factor(260, 7) == 64
    assert shrink_factor(260, 15) == 32


def test_blend_weight_is_d_squared():
    assert blend_weight(0.0) == 0.0
    assert blend_weight(0.5) == pytest.approx(0.25)
    assert blend_weight(1.0) == 1.0
    assert blend_weight(1.3) == 1.0  # the border takes map L


@pytest.mark.parametrize("which", ["small", "large"])
def test_kernel_weights_sum_to_one_and_vanish_beyond_the_radius(which):
    plan = plan_filters(100, 0.1, 128, 36, 7)
    weights = kernel_weights(plan, which)
    assert weights.shape == (7, 7)
    assert weights.sum() == pytest.approx(1.0, abs=1e-6)
    assert np.array_equal(weights, weights.T) and np.array_equal(weights, weights[::-1])
    shrink = plan.shrink_small if which == "small" else plan.shrink_large
    radius = plan.radius_small if which == "small" else plan.radius_large
    k = np.arange(-3, 4)
    rho = shrink * np.hypot(*np.meshgrid(k, k))
    assert np.all(weights[rho > radius + 1e-9] == 0)
    assert weights[3, 3] == weights.max()


@pytest.mark.parametrize(
    ("arguments", "fragment"),
    [
        ((0, 0.1), "phong_exponent=0: expected a number > 0"),
        ((-5, 0.1), "phong_exponent=-5"),
        ((10, 0.0), "epsilon=0.0: expected a number in (0, 1)"),
        ((10, 1.0), "epsilon=1.0: expected a number in (0, 1)"),
    ],
)
def test_bad_exponent_or_epsilon_is_one_line(arguments, fragment):
    with pytest.raises(ParameterError) as info:
        plan_filters(*arguments, 128, 36)
    assert fragment in str(info.value) and "\n" not in str(info.value)


def test_a_border_too_small_for_the_large_kernel_names_the_value_and_the_minimum():
    plan = plan_filters(10, 0.1, 128, 20, 7)
    with pytest.raises(ParameterError) as info:
        plan.check_border()
    message = str(info.value)
    assert message.startswith("border=20: expected an integer >= 33") and "\n" not in message
    with pytest.raises(ParameterError, match=r"^border=20: expected an integer >= 22 "):
        plan.check_border(one_pass=True)  # one pass only needs r_s = 21.7
    plan_filters(10, 0.1, 128, 33, 7).check_border()
