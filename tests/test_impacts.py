"""The bed's impacts: contact episodes, circular means and the wall-force states, on series
whose answer is known by construction."""

import math

import numpy as np
import pytest

from jaxdamp.analysis.impacts import circular_mean, count_episodes, episode_onsets, force_states


def test_episodes_merge_runs_closer_than_the_gap():
    touching = np.array([0, 1, 1, 0, 1, 0, 0, 0, 0, 1], bool)
    np.testing.assert_array_equal(episode_onsets(touching, gap=2), [1, 9])
    assert count_episodes(touching, gap=2) == 2
    assert count_episodes(touching, gap=1) == 3  # every run its own episode
    assert count_episodes(np.ones(5, bool), gap=1) == 1  # touching from the first sample
    assert count_episodes(np.zeros(5, bool), gap=1) == 0


def test_circular_mean_wraps_and_is_nan_for_none():
    assert circular_mean([3.1, -3.1], degrees=True) == pytest.approx(180.0)
    assert abs(circular_mean([3.1, -3.1])) == pytest.approx(math.pi)
    assert circular_mean([0.1, 0.3]) == pytest.approx(0.2, rel=1e-12)
    assert math.isnan(circular_mean([])) and math.isnan(circular_mean([], degrees=True))


def test_force_states_count_one_lid_and_one_floor_impact_per_period():
    """F = 2 m_p g cos(2π f t) over 10 periods: the bed is at the lid, free and at the floor
    once each per period (thresholds 0.5 and 0.2 of the weight)."""
    f, weight = 5.0, 3.0
    t = np.linspace(0.0, 10 / f, 20001)
    F = 2 * weight * np.cos(2 * np.pi * f * t)
    s = force_states(t, F, weight, f)
    assert s["lid_hits_per_period"] == pytest.approx(1.0, abs=0.1)   # the first is not entered
    assert s["floor_hits_per_period"] == pytest.approx(1.0, abs=0.01)
    lid = np.mean(np.cos(2 * np.pi * f * t) > 0.25)   # F > 0.5 weight
    free = np.mean(np.abs(np.cos(2 * np.pi * f * t)) < 0.1)
    assert s["lid_contact_fraction"] == pytest.approx(lid, abs=1e-12)
    assert s["free_fraction"] == pytest.approx(free, abs=1e-12)
    resting = force_states(t, -weight * np.ones_like(t), weight, f)  # always on the floor
    assert resting["floor_hits_per_period"] == 0 and resting["floor_contact_fraction"] == 1.0
