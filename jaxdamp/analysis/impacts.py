"""The bed's impacts on the container: contact episodes in sampled series, impacts per drive
period, their phases (circular means), and the wall-force states of the bed (lid, floor,
flight).

Two observables, each with its own definition:

* from the number of grains touching a wall (``n_floor``, ``n_lid`` records):
  :func:`episode_onsets` / :func:`count_episodes` — runs of touching samples, runs closer than
  ``gap`` samples merged (a landing bed is many grain contacts within a short time);
* from the grains' force on the container (``force_box``): :func:`force_states` — each sample
  lid, floor or free by thresholds on the force in units of the grains' weight.
"""

from __future__ import annotations

import math

import numpy as np


def episode_onsets(touching, gap: int) -> np.ndarray:
    """Sample indices where contact episodes start in a boolean series: runs of ``True``,
    two runs closer than ``gap`` samples counted as one. A series touching from its first
    sample starts an episode there."""
    idx = np.flatnonzero(touching)
    if idx.size == 0:
        return idx
    return idx[np.r_[True, np.diff(idx) > gap]]


def count_episodes(touching, gap: int) -> int:
    """Number of contact episodes (:func:`episode_onsets`).

    >>> count_episodes(np.array([0, 1, 1, 0, 1, 0, 0, 0, 0, 1], bool), gap=2)
    2
    """
    return len(episode_onsets(touching, gap))


def circular_mean(angles, degrees: bool = False) -> float:
    """Circular mean ``arg(mean(exp(i a)))`` of angles ``a`` [rad], in rad or, with
    ``degrees``, in degrees; NaN for none.

    >>> round(circular_mean([3.1, -3.1], degrees=True), 6)
    180.0
    """
    a = np.asarray(angles, float)
    if not a.size:
        return math.nan
    m = np.angle(np.mean(np.exp(1j * a)))
    return float(np.degrees(m)) if degrees else float(m)


def force_states(t, force_box, weight: float, frequency: float) -> dict:
    """Impacts per drive period from the interval-averaged vertical force ``F`` of the grains
    on the container: each sample is *lid* (``F > +0.5 m_p g``: grains push the lid up),
    *floor* (``F < -0.5 m_p g``) or *free* (``|F| < 0.2 m_p g``: the bed in flight);
    ambiguous samples keep the previous state. An impact is a change of state into lid or
    floor (a bed resting on the floor all the time has no floor impacts). Also the fraction of
    samples in each state. ``weight`` = ``m_p g`` [N], ``frequency`` [Hz]."""
    F = np.asarray(force_box) / weight
    periods = (t[-1] - t[0]) * frequency
    code = np.where(F > 0.5, 2, np.where(F < -0.5, 1, np.where(np.abs(F) < 0.2, 0, -1)))
    idx = np.where(code >= 0, np.arange(code.size), 0)
    np.maximum.accumulate(idx, out=idx)
    state = code[idx]  # forward-filled (a leading ambiguous run takes the first sample's code)
    if state[0] < 0:
        state = np.where(state < 0, 1, state)
    enter = np.r_[False, state[1:] != state[:-1]]
    return dict(lid_hits_per_period=np.count_nonzero(enter & (state == 2)) / periods,
                floor_hits_per_period=np.count_nonzero(enter & (state == 1)) / periods,
                lid_contact_fraction=float(np.mean(code == 2)),
                floor_contact_fraction=float(np.mean(code == 1)),
                free_fraction=float(np.mean(code == 0)))
