"""Neyman allocation of the adaptive reference, in NumPy."""

from __future__ import annotations

import numpy as np

from envstudio.methods.reference.sample_allocation import (
    MAX_MULTIPLIER,
    REFERENCE_PERCENTILE,
    SampleAllocation,
    neyman_multipliers,
)


def test_multipliers_are_powers_of_two_of_sigma_over_the_percentile_clipped_to_1_and_4():
    base = np.ones(100)  # the 80th percentile of the covered pixels is 1
    sigma = np.concatenate([base, [0.1, 1.4, 2.2, 6.0, 100.0, 0.0]]).reshape(1, -1)
    covered = np.ones(sigma.shape, bool)
    covered[0, -1] = False
    assert np.percentile(sigma[covered], REFERENCE_PERCENTILE) == 1.0
    m = neyman_multipliers(sigma, covered)
    assert m[0, :100].tolist() == [1.0] * 100
    assert m[0, 100:].tolist() == [1.0, 1.0, 2.0, MAX_MULTIPLIER, MAX_MULTIPLIER, 1.0]
    assert MAX_MULTIPLIER == 4


def test_no_known_deviation_leaves_every_pixel_at_the_plain_rate():
    sigma = np.zeros((4, 4))
    assert np.all(neyman_multipliers(sigma, np.ones((4, 4), bool)) == 1.0)


def test_counts_advance_by_each_pixels_multiplier_and_reallocation_turns_spread_into_sigma():
    shape = (1, 10)
    covered = np.ones(shape, bool)
    plain = SampleAllocation.plain(shape)
    assert plain.samples_per_pixel(8, samples=4) == 32
    # the last pixel's batch means vary 16x as much as the others': 4x the deviation
    variance = np.ones(shape)
    variance[0, -1] = 16.0
    first = plain.reallocate(8, variance, covered)
    assert first.at == 8 and np.all(first.units == 8.0)
    assert first.multipliers[0].tolist() == [1.0] * 9 + [4.0]
    units, inverse = first.at_batch(16)
    assert units[0, -1] == 8 + 8 * 4 and inverse[0, -1] == 8 + 8 / 4
    assert first.samples_per_pixel(16, samples=4) == round(4 * (9 * 16 + 40) / 10)
    # 8 plain batches and 8 of four times the size: the means' variance is
    # sigma² (8 + 8 / 4) / 16; the same sigma keeps the same multiplier
    variance[0, -1] = 16.0 * 10 / 16
    second = first.reallocate(16, variance, covered)
    assert second.multipliers[0].tolist() == [1.0] * 9 + [4.0]


def test_saved_arrays_come_back_and_a_state_without_them_is_plain_sampling():
    allocation = SampleAllocation.plain((2, 2)).reallocate(
        8, np.array([[1.0, 9.0], [1.0, 1.0]]), np.array([[True, True], [False, True]])
    )
    state = {name: np.array(value) for name, value in allocation.as_arrays().items()}
    back = SampleAllocation.from_arrays(state, (2, 2), batches=12)
    assert back.at == 8 and back.samples_per_pixel(12, 1) == allocation.samples_per_pixel(12, 1)
    np.testing.assert_array_equal(back.multipliers, allocation.multipliers)
    np.testing.assert_array_equal(back.covered, allocation.covered)
    old = SampleAllocation.from_arrays({}, (2, 2), batches=12)
    assert old.at == 12 and old.samples_per_pixel(20, samples=8) == 160
