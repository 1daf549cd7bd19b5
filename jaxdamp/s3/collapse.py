"""Inelastic collapse of two particles against a wall, event-driven (thesis §5.2, fig. 5.1).

Two equal point particles on a line, no gravity, a fixed wall at ``x = 0``: the near one
(``x₁``) and the far one (``x₂ ≥ x₁``). Between collisions they fly freely; a collision with
the wall or between the two is instantaneous, with the S3 model's collision rule
:func:`jaxdamp.s3.common.collide` (momentum conserved, normal relative velocity reversed with
restitution ``e``; the wall is a partner of infinite mass). The event sequence is exact up to
round-off, like the S3 event-driven model it validates.

For small ``e`` the sequence wall, pair, wall, pair, … never ends: the collisions come ever
faster and infinitely many happen in a finite time ``t∞`` (*inelastic collapse*). One cycle
(wall then pair) maps the velocities linearly, ``v ↦ A v`` with

    A = P W,  W = diag(−e, 1),  P = ½ [[1 − e, 1 + e], [1 + e, 1 − e]],

``tr A = (1 − e)²/2``, ``det A = e²``. The cycle repeats with the same order of collisions
for ever iff the eigenvalues ``λ₁ ≥ λ₂`` of ``A`` are real — ``(1 − e)² ≥ 4e``, i.e.

    e ≤ e_c = 3 − 2√2 ≈ 0.1716;

above it the velocities rotate, the order breaks and the particles escape after a few
collisions. Below it velocities shrink by ``λ₁`` per cycle and cycle durations by
``λ₂/λ₁`` (the measured ratio converges to it), whose small-``e`` limit is the thesis'
``4e²`` (from its argument: distances contract by ``2e²``, velocities by ``½``), so that

    t∞ − t₀ = (t₂ − t₀) / (1 − λ₂/λ₁) ≈ (t₂ − t₀) / (1 − 4e²).

>>> seq = collapse_sequence(0.05)
>>> seq.outcome, round(seq.ratio, 4), round(cycle_ratio(0.05), 4)
('collapsed', 0.0126, 0.0126)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jaxdamp.s3.common import collide

#: Critical restitution of two particles and a wall: the cycle map's eigenvalues turn complex.
E_CRITICAL = 3.0 - 2.0 * math.sqrt(2.0)


def cycle_ratio(e: float) -> float:
    """``λ₂/λ₁`` of the wall-then-pair cycle map (NaN above :data:`E_CRITICAL`): the
    asymptotic ratio of successive cycle durations in a collapse."""
    tr = (1.0 - e) ** 2 / 2.0
    disc = tr * tr - 4.0 * e * e
    if disc < 0:
        return math.nan
    r = math.sqrt(disc)
    return (tr - r) / (tr + r)


@dataclass(frozen=True)
class Sequence:
    """The collisions of :func:`collapse_sequence`.

    Attributes:
      e: restitution. outcome: ``"collapsed"`` (velocities or distances underflowed in a
        converging sequence), ``"escaped"`` (both particles move away, no collision left) or
        ``"max_events"``.
      t, kind, x1, x2, v1, v2: per event, its time [s], ``"W"`` (wall) or ``"P"`` (pair), and
        positions [m] and velocities [m/s] just after it, ``(E,)``.
      ratio: last well-resolved ratio of successive wall-to-wall cycle durations (NaN if
        fewer than four wall collisions).
      t_end: time of the last event [s] (``t∞`` for a collapse).
    """

    e: float
    outcome: str
    t: np.ndarray
    kind: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    v1: np.ndarray
    v2: np.ndarray
    ratio: float
    t_end: float

    @property
    def wall_times(self) -> np.ndarray:
        return self.t[self.kind == "W"]


def collapse_sequence(e: float, X: float = 1.0, V: float = 1.0,
                      max_events: int = 200_000) -> Sequence:
    """Event-driven collisions of two equal particles and a wall, started (``t₀ = 0``) as in
    the thesis: the near particle hits the wall with speed ``V`` [m/s] while the far one, at
    distance ``X`` [m], approaches with ``V``."""
    if not 0.0 <= e < 1.0:
        raise ValueError(f"e = {e}: the restitution must lie in [0, 1)")
    if X <= 0 or V <= 0:
        raise ValueError(f"X = {X} m, V = {V} m/s: both must be > 0")
    x1, x2, v1, v2, t = 0.0, float(X), -float(V), -float(V), 0.0
    rows = []
    outcome = "max_events"
    while len(rows) < max_events:
        tw = 0.0 if (x1 <= 0.0 and v1 < 0) else (-x1 / v1 if v1 < 0 else math.inf)
        tp = (x2 - x1) / (v1 - v2) if v1 > v2 else math.inf
        dt = min(tw, tp)
        if not math.isfinite(dt):
            outcome = "escaped"
            break
        t += dt
        x1, x2 = x1 + v1 * dt, x2 + v2 * dt
        if tw <= tp:
            x1 = 0.0
            v1, _ = collide(v1, 0.0, 1.0, math.inf, e)
            rows.append((t, "W", x1, x2, v1, v2))
        else:
            x2 = x1 = max(x1, 0.0)
            v2, v1 = collide(v2, v1, 1.0, 1.0, e)
            rows.append((t, "P", x1, x2, v1, v2))
        if abs(v1) + abs(v2) < 1e-280 or (len(rows) > 10 and x2 < 1e-290):
            outcome = "collapsed"
            break
    t_, kind, a, b, c, d = (np.array(col) for col in zip(*rows))
    tw_ = t_[kind == "W"]
    dtw = np.diff(tw_)
    ok = dtw[dtw > 1e-8 * max(t_[-1], 1e-300)]  # cycles resolved well above round-off
    ratio = float(ok[-1] / ok[-2]) if len(ok) >= 3 else math.nan
    return Sequence(e, outcome, t_, kind, a, b, c, d, ratio, float(t_[-1]))


def critical_restitution(lo: float = 0.05, hi: float = 0.5, tol: float = 1e-5) -> float:
    """Bisection on the outcome of :func:`collapse_sequence`: the largest ``e`` that still
    collapses, to ``tol``."""
    if collapse_sequence(lo).outcome != "collapsed" or collapse_sequence(hi).outcome == "collapsed":
        raise ValueError(f"[{lo}, {hi}] does not bracket the collapse threshold")
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if collapse_sequence(mid).outcome == "collapsed":
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)
