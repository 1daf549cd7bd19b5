"""Designing for an operating envelope: a band of frequencies, a range of levels, a mass budget.

A particle damper is strongly nonlinear: the clearance that is optimal at one excitation level
is poor at another. A designer's requirement is an **envelope** — the frequencies the mode may
take (it shifts with temperature or load) and the vibration levels it must meet (run-up,
operation) — and budgets for the added mass and the cavity. This module states that
requirement and scores a design against it.

* :class:`Envelope` — the frequencies ``f_j`` [Hz] × the base amplitudes ``U_l`` [m] of the
  S1 primary (its points, every pair), the statistic (``"worst"`` or ``"mean"``) and the
  budgets: the grains' mass over the primary's mass ``μ ≤ mass_budget`` and the cavity's volume
  (every cell) ``V ≤ volume_budget`` [m³].
* :class:`EnvelopeProblem` — :class:`~jaxdamp.design.space.DesignProblem` run at every point
  of the envelope (one bed per design and replicate, shared by its points: the points of one
  bed are paired), scoring each point by the grains' equivalent damping
  ``C_eq = E / (π Ω Z²)`` [N s/m] (:mod:`jaxdamp.design.objectives`), and each design by

  - ``worst``: ``min_p C̄_p``, the smallest over the points of the mean over beds; its ± is
    the standard error of that point's mean (the choice of the point is not counted: where
    two points' intervals overlap the worst point is ambiguous, and every point's mean ± SE
    is reported beside it);
  - ``mean``: the envelope average ``(1/P) Σ_p C_p`` of each bed, mean ± SE over beds.

  Designs outside the budgets are infeasible (:meth:`EnvelopeProblem.feasible` says which
  budget, before any compute).
* :func:`front` — the designs no other design beats in both damping (larger) and added mass
  (smaller): the damping–mass front.

Example::

    >>> import numpy as np
    >>> from jaxdamp.design.envelope import Envelope, summarise
    >>> env = Envelope(frequencies=(14.0, 15.0), levels=(0.003,))
    >>> C = np.array([[[20.0, 22.0]], [[10.0, 12.0]]])   # (points, designs, beds)
    >>> s = summarise(C, "worst")
    >>> float(s["value"][0]), float(s["se"][0]), int(s["worst_point"][0])
    (11.0, 1.0, 1)
    >>> float(summarise(C, "mean")["value"][0])
    16.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jaxdamp.analysis.stats import t_quantile
from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.config import Config, ConfigError, apply_overrides
from jaxdamp.design.objectives import Objective, equivalent_damping
from jaxdamp.design.space import DesignProblem
from jaxdamp.validation import validate

#: How an envelope's points combine into one number per design (module doc).
STATISTICS = ("worst", "mean")


@dataclass(frozen=True)
class Envelope:
    """An operating envelope (module doc): ``frequencies`` [Hz] × ``levels`` (the S1
    primary's base amplitude ``U`` [m]), ``statistic`` (:data:`STATISTICS`), ``mass_budget``
    (largest grains' mass over the primary's mass, or ``None``) and ``volume_budget``
    (largest cavity volume of all cells [m³], or ``None``)."""

    frequencies: tuple
    levels: tuple
    statistic: str = "worst"
    mass_budget: float | None = None
    volume_budget: float | None = None

    def __post_init__(self):
        object.__setattr__(self, "frequencies", tuple(float(f) for f in self.frequencies))
        object.__setattr__(self, "levels", tuple(float(u) for u in self.levels))
        if not self.frequencies or not all(f > 0 and math.isfinite(f) for f in self.frequencies):
            raise ConfigError(f"envelope frequencies {self.frequencies}: give at least one, "
                              "each > 0 Hz")
        if not self.levels or not all(u > 0 and math.isfinite(u) for u in self.levels):
            raise ConfigError(f"envelope levels {self.levels}: give at least one base "
                              "amplitude U, each > 0 m")
        if self.statistic not in STATISTICS:
            raise ConfigError(f"envelope statistic {self.statistic!r}: expected one of "
                              f"{', '.join(STATISTICS)}")
        for name in ("mass_budget", "volume_budget"):
            v = getattr(self, name)
            if v is not None and not (v > 0 and math.isfinite(v)):
                raise ConfigError(f"envelope {name} = {v}: must be > 0 (or not given)")

    @property
    def points(self) -> list:
        """``[(f, U), ...]``: every frequency at every level (levels outer)."""
        return [(f, u) for u in self.levels for f in self.frequencies]

    def conditions(self) -> list:
        """The points as configuration overrides (:attr:`DesignProblem.conditions`)."""
        return [{"frequency": f, "primary.U": u} for f, u in self.points]

    def describe(self) -> dict:
        return {"frequencies": list(self.frequencies), "levels": list(self.levels),
                "statistic": self.statistic, "mass_budget": self.mass_budget,
                "volume_budget": self.volume_budget,
                "points": [list(p) for p in self.points]}


def summarise(C, statistic: str) -> dict:
    """One envelope number per design from ``C`` ``(P, n, R)``: the equivalent damping at the
    ``P`` points of ``n`` designs on ``R`` beds each (module doc). Returns ``{"value", "se",
    "ci95" (n,), "worst_point" (n,) int, "point_mean", "point_se" (P, n), "per_bed" (n, R)}``
    (``per_bed``: each bed's envelope mean, or its smallest point for ``worst``; 95 %
    Student-t half-widths)."""
    C = np.asarray(C, float)
    if C.ndim != 3:
        raise ValueError(f"C: expected (points, designs, beds), got shape {C.shape}")
    P, n, R = C.shape
    pm = C.mean(axis=2)
    ps = standard_error(C, axis=2) if R > 1 else np.full((P, n), np.nan)
    worst = np.argmin(pm, axis=0)
    cols = np.arange(n)
    if statistic == "worst":
        value, se = pm[worst, cols], ps[worst, cols]
        per_bed = C.min(axis=0)
    elif statistic == "mean":
        per_bed = C.mean(axis=0)
        value = per_bed.mean(axis=1)
        se = standard_error(per_bed, axis=1) if R > 1 else np.full(n, np.nan)
    else:
        raise ConfigError(f"statistic {statistic!r}: expected one of {', '.join(STATISTICS)}")
    half = t_quantile(0.975, R - 1) * se if R > 1 else se
    return {"value": value, "se": se, "ci95": half, "worst_point": worst, "point_mean": pm,
            "point_se": ps, "per_bed": per_bed}


def front(mass, value) -> np.ndarray:
    """Indices of the designs on the damping–mass front, by increasing mass: those that no
    other design matches or beats in both ``value`` (larger) and ``mass`` (smaller), strictly
    in one."""
    mass = np.asarray(mass, float)
    value = np.asarray(value, float)
    keep = []
    for i in range(len(mass)):
        beaten = (mass <= mass[i]) & (value >= value[i]) & ((mass < mass[i]) | (value > value[i]))
        if not beaten.any():
            keep.append(i)
    return np.asarray(sorted(keep, key=lambda i: mass[i]), int)


class EnvelopeProblem(DesignProblem):
    """The envelope score of designs of several variables, replicated (module doc).

    Args:
      config: an S1 configuration with a harmonic base motion (``primary.U``; the envelope
        sets it), e.g. ``sanchez2012-optimal``.
      envelope: the :class:`Envelope`.
      names, bounds, duration, seed, margin, progress: as :class:`DesignProblem` (``names``
        from :data:`jaxdamp.design.space.VARIABLES`; ``mass_ratio`` and ``radius`` change the
        grains and run in batches of their own).
    """

    def __init__(self, config: Config, envelope: Envelope, names=("Lz",), **kw):
        if config.system == "primary" and (config.random is not None
                                           or config.shock is not None
                                           or config.structure is not None):
            raise ConfigError("an envelope is of harmonic base motion on the 1-DOF primary: "
                              "remove [random], [shock] and [structure]")
        super().__init__(config, Objective("damping"), names=names, **kw)
        self.envelope = envelope
        self.conditions = envelope.conditions()

    def combine(self, Z, E):
        """Each row's (bed's) envelope number: its smallest ``C_eq`` over the points
        (``worst``) or their mean."""
        C = self.damping(Z, E)
        return C.min(axis=0) if self.envelope.statistic == "worst" else C.mean(axis=0)

    def damping(self, Z, E) -> np.ndarray:
        """``C_eq`` [N s/m] ``(P, n)`` of amplitudes ``Z`` and dissipations ``E`` ``(P, n)``."""
        f = np.asarray([c["frequency"] for c in self.conditions])[:, None]
        return equivalent_damping(E, Z, f)

    def design_config(self, x) -> Config:
        """The validated configuration of design ``x`` (physical units)."""
        return validate(apply_overrides(self.config, self.space.overrides(x)))

    def budgets(self, x) -> dict:
        """``{"mass_ratio", "volume"}`` of design ``x``: the grains' mass over the primary's
        mass (every cell) and the cavity's volume [m³] (every cell)."""
        from jaxdamp.cases.filling import cavity_volume, mass_ratio

        cfg = self.design_config(x)
        return {"mass_ratio": mass_ratio(cfg), "volume": cavity_volume(cfg)}

    def feasible(self, x) -> tuple:
        """``(ok, {"mass_budget": ok, "volume_budget": ok})`` of design ``x``."""
        b, env = self.budgets(x), self.envelope
        out = {}
        if env.mass_budget is not None:
            out["mass_budget"] = b["mass_ratio"] <= env.mass_budget * (1 + 1e-9)
        if env.volume_budget is not None:
            out["volume_budget"] = b["volume"] <= env.volume_budget * (1 + 1e-9)
        return all(out.values()), out

    def evaluate(self, X, replicates: int) -> dict:
        """Every design of ``X`` ``(n, d)`` at every point of the envelope on ``replicates``
        fresh beds (one batch per grain shape): :func:`summarise`'s dict with ``"mean"`` (=
        ``value``, the search's objective), ``"J"`` (``per_bed``), ``"C"`` ``(P, n, R)``,
        ``"Z"``, ``"E"``, ``"stationary_each"`` (same shape: the steady state detected at that
        point), ``"stationary"`` (n, R: at every point), ``"budgets"`` (per design),
        ``"sim_seconds"``. Refuses designs outside the budgets, naming the budget."""
        X = np.atleast_2d(np.asarray(X, float))
        R = int(replicates)
        if R < 1:
            raise ConfigError(f"replicates = {R}: need at least 1")
        budgets = [self.budgets(x) for x in X]
        for x, b in zip(X, budgets):
            ok, which = self.feasible(x)
            if not ok:
                name = next(k for k, v in which.items() if not v)
                have = b["mass_ratio"] if name == "mass_budget" else b["volume"]
                raise ConfigError(f"design {np.round(x, 6).tolist()}: {name} = "
                                  f"{getattr(self.envelope, name):g} exceeded ({have:.4g})")
        rows = np.repeat(X, R, axis=0)
        m = self.measure(rows, self.seeds(len(rows)))
        P, n = len(self.conditions), len(X)
        C = self.damping(m["Z"], m["E"]).reshape(P, n, R)
        s = summarise(C, self.envelope.statistic)
        s.update({"mean": s["value"], "J": s["per_bed"], "C": C,
                  "Z": m["Z"].reshape(P, n, R), "E": m["E"].reshape(P, n, R),
                  "stationary": m["stationary"].reshape(n, R),
                  "stationary_each": m["stationary_each"].reshape(P, n, R), "budgets": budgets,
                  "sim_seconds": m["sim_seconds"]})
        return s

    def describe(self) -> dict:
        d = super().describe()
        d.update({"envelope": self.envelope.describe(),
                  "score": "C_eq = E/(pi Omega Z^2) per point; " + (
                      "worst: min over points of the mean over beds, ± that point's SE"
                      if self.envelope.statistic == "worst" else
                      "mean: each bed's envelope mean, mean ± SE over beds")})
        return d
