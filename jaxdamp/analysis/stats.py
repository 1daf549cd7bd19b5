"""Steady-state statistics: per-period series, detection of the steady state, replicates.

A steady-state number of a granular damper is a random variable: the bed is chaotic, so two
independently poured beds (two *replicates*) give different trajectories and different
per-period values. This module turns recorded samples into estimates with error bars
(``docs/physics.md`` §7):

1. **Per-period series** (:func:`per_period`): the run is cut into whole drive periods
   ``[k T, (k+1) T)`` with ``T = 1/f``; for each period the box amplitude (half the
   peak-to-peak of the sampled ``z_box``), the first-harmonic phase against ``cos Ωt``, and the
   energy of every work channel spent in it (cumulative work interpolated linearly at the period
   boundaries).

2. **Start of the steady state, from the data** (:func:`mser`): the marginal standard error
   rule (White 1997; MSER-``m`` with batches of ``m`` periods) picks the truncation ``d`` that
   minimises ``MSER(d) = Σ_{i≥d} (x_i − x̄_d)² / (n − d)²``, searched over ``d ≤ n/2``.
   A minimum at the edge of the search range (``d`` past ``n/2``) or fewer than
   ``min_keep`` periods left means the series never became stationary: the estimate says so
   (``stationary = False``) instead of quoting a mean. At least ``min_discard`` periods are
   always dropped (the start from a bed at rest is never steady).

3. **Within-run error** (:func:`batch_means_se`): the standard error of the mean of the
   retained per-period values by non-overlapping batch means (``n_batches`` batches) — a
   secondary figure, since consecutive periods of one trajectory are correlated and one
   trajectory does not sample the bed's other states.

4. **Across replicates** (:func:`across`): the steady mean of each replicate is one
   independent sample; the estimate is their mean ± the standard error
   ``s / sqrt(R)`` with a Student-t 95 % interval (``R ≥ 2``; with ``R = 1`` the standard error
   is NaN and only the batch-means figure remains).

Example::

    >>> import numpy as np
    >>> from jaxdamp.analysis import stats
    >>> rng = np.random.default_rng(0)
    >>> x = np.r_[np.linspace(2.0, 1.0, 10), 1.0 + 0.01 * rng.standard_normal(90)]
    >>> d = stats.mser(x)
    >>> d.start >= 9 and d.stationary
    True
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from jaxdamp.analysis.uncertainty import mean_se, pm, standard_error  # noqa: F401

#: Per-period quantities and their units (``*_per_cycle``: energy spent in one period).
PERIOD_UNITS = {"amplitude": "m", "phase": "rad", "granular_loss_per_cycle": "J"}

def unit(key: str) -> str:
    """Unit of a per-period quantity of :func:`per_period`."""
    return PERIOD_UNITS.get(key, "J" if key.endswith("_per_cycle") else "")


#: Work channels that :func:`summarise` adds to the per-period series (besides the granular
#: loss, which is always there).
CHANNELS = ("input", "primary_damping")

#: The per-period series whose stationarity decides the start of a replicate's steady state.
DETECT_ON = ("amplitude", "granular_loss_per_cycle")


@dataclass(frozen=True)
class Truncation:
    """Result of :func:`mser` on one series.

    Attributes:
      start: index of the first retained element (periods).
      stationary: the minimum lay inside the search range and enough elements remain.
      kept: number of retained elements.
    """

    start: int
    stationary: bool
    kept: int


def mser(x, batch: int = 1, min_discard: int = 1, min_keep: int = 5) -> Truncation:
    """Marginal standard error rule on the series ``x`` (MSER-``batch``).

    Args:
      x: per-period values, shape ``(n,)``.
      batch: periods per batch (MSER-5 uses 5); the truncation is a whole number of batches.
      min_discard: periods always dropped at the start.
      min_keep: the fewest periods a stationary tail must have.
    Returns:
      :class:`Truncation`. ``stationary`` is False when the MSER minimum is at the end of the
      search range ``d ≤ n/2`` (the series still drifts) or fewer than ``min_keep`` remain.
    """
    x = np.asarray(x, float)
    n_all = len(x)
    if n_all - min_discard < min_keep or not np.isfinite(x).all():
        return Truncation(min(min_discard, n_all), False, max(n_all - min_discard, 0))
    nb = n_all // batch
    xb = x[: nb * batch].reshape(nb, batch).mean(axis=1) if batch > 1 else x
    first = math.ceil(min_discard / batch)
    last = nb // 2  # search d ≤ n/2 (in batches)
    if last < first:
        last = first
    # suffix sums for the mean and variance of every tail xb[d:]
    s1 = np.cumsum(xb[::-1])[::-1]
    s2 = np.cumsum((xb * xb)[::-1])[::-1]
    d = np.arange(first, last + 1)
    m = nb - d
    ss = s2[d] - s1[d] ** 2 / m
    crit = np.maximum(ss, 0.0) / m**2
    k = int(np.argmin(crit))
    start = int(d[k]) * batch
    kept = n_all - start
    at_edge = k == len(d) - 1 and last > first
    return Truncation(start, bool(not at_edge and kept >= min_keep), kept)


def batch_means_se(x, n_batches: int = 5) -> float:
    """Standard error of the mean of ``x`` by ``n_batches`` non-overlapping batch means
    (NaN with fewer than 2 elements per batch or fewer than 2 batches)."""
    x = np.asarray(x, float)
    size = len(x) // n_batches
    if size < 1 or n_batches < 2:
        return float("nan")
    means = x[: size * n_batches].reshape(n_batches, size).mean(axis=1)
    return float(standard_error(means))


def t_quantile(p: float, dof: int) -> float:
    """Student-t quantile (two-sided 95 %: ``t_quantile(0.975, R - 1)``)."""
    from scipy.stats import t

    return float(t.ppf(p, dof))


def welch(x, y) -> tuple[float, float]:
    """Difference of means ``x̄ − ȳ`` of two independent samples (NaN dropped) and the
    half-width of its Welch 95 % interval,
    ``t_{0.975, ν} sqrt(s_x²/n_x + s_y²/n_y)`` with the Welch–Satterthwaite ``ν``.
    NaN half-width with fewer than two values on either side.

    >>> d, h = welch([1.0, 1.2, 1.1], [0.5, 0.6, 0.7])
    >>> round(d, 6), h > 0
    (0.5, True)
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    x, y = x[np.isfinite(x)], y[np.isfinite(y)]
    if min(len(x), len(y)) < 2:
        return (float(x.mean() - y.mean()) if len(x) and len(y) else math.nan), math.nan
    se, dof = welch_terms(x, y)
    return float(x.mean() - y.mean()), t_quantile(0.975, dof) * se


def welch_terms(x, y) -> tuple[float, float]:
    """Standard error of ``x̄ − ȳ``, ``sqrt(s_x²/n_x + s_y²/n_y)``, and its Welch–Satterthwaite
    degrees of freedom (two independent samples of ≥ 2 finite values each); where neither
    sample varies, the pooled ``n_x + n_y − 2``.

    >>> se, dof = welch_terms([1.0, 1.2, 1.1], [0.5, 0.6, 0.7])
    >>> round(dof, 6)
    4.0
    """
    x, y = np.asarray(x, float), np.asarray(y, float)
    va, vb = x.var(ddof=1) / len(x), y.var(ddof=1) / len(y)
    if va + vb == 0:
        return 0.0, float(len(x) + len(y) - 2)
    dof = (va + vb) ** 2 / (va ** 2 / (len(x) - 1) + vb ** 2 / (len(y) - 1))
    return math.sqrt(va + vb), float(dof)


@dataclass(frozen=True)
class Estimate:
    """A steady-state quantity over ``R`` independent replicates.

    Attributes:
      mean: mean over replicates of each replicate's steady mean.
      se: standard error of ``mean`` across replicates, ``s/√R`` (NaN for ``R = 1``).
      ci95: half-width of the Student-t 95 % interval, ``t_{0.975, R-1} · se``.
      n: number of replicates that became stationary (the others are excluded).
      values: steady mean of every replicate, ``(R,)`` (NaN where not stationary).
      batch_se: within-run batch-means standard error of every replicate, ``(R,)``.
      start: detected start of every replicate's steady state [s], ``(R,)``.
      stationary: ``(R,)`` booleans.
    """

    mean: float
    se: float
    ci95: float
    n: int
    values: np.ndarray
    batch_se: np.ndarray
    start: np.ndarray
    stationary: np.ndarray

    def __str__(self) -> str:
        return format_estimate(self.mean, self.se, self.n)


def format_estimate(mean, se, n, unit: str = "") -> str:
    """``"1.234e-03 ± 5.6e-05 (R = 4)"``; ``± n/a`` without a standard error."""
    u = f" {unit}" if unit else ""
    if not np.isfinite(mean):
        return f"n/a (R = {n}, not stationary)"
    if not np.isfinite(se):
        return f"{mean:.5g}{u} (R = {n}, no replicate error)"
    return f"{pm(mean, se, unit=unit)} (R = {n})"


def across(values, batch_se=None, start=None, stationary=None) -> Estimate:
    """Combine per-replicate steady means ``values`` ``(R,)`` into an :class:`Estimate`.
    Replicates that did not become stationary (``stationary`` False) are left out."""
    values = np.asarray(values, float)
    R = len(values)
    ok = np.ones(R, bool) if stationary is None else np.asarray(stationary, bool)
    ok = ok & np.isfinite(values)
    v = values[ok]
    n = int(ok.sum())
    mean = float(v.mean()) if n else float("nan")
    se = float(standard_error(v))
    ci = t_quantile(0.975, n - 1) * se if n >= 2 else float("nan")
    nan = np.full(R, np.nan)
    return Estimate(mean, se, ci, n, np.where(ok, values, np.nan),
                    nan if batch_se is None else np.asarray(batch_se, float),
                    nan if start is None else np.asarray(start, float),
                    ok if stationary is None else np.asarray(stationary, bool))


@dataclass(frozen=True)
class ReplicateExtremum:
    """The extremum of every replicate's sampled curve and its estimate over replicates
    (:func:`replicate_extrema`).

    Attributes:
      x: abscissa of each replicate's extremum, ``(R,)`` (the parabola's vertex, or the best
        sample where none is bracketed).
      y: the curve's value there, ``(R,)``.
      best: index of each replicate's best sample, ``(R,)``.
      estimate: :class:`Estimate` of ``x`` over the replicates (mean, se, ci95, n).
      at_edge: how many replicates have their best sample at either end of the grid (their
        extremum is not bracketed: an interval of the optimum needs ``at_edge == 0``).
    """

    x: np.ndarray
    y: np.ndarray
    best: np.ndarray
    estimate: Estimate
    at_edge: int


def replicate_extrema(x, Y, kind: str = "max", log_x: bool = False,
                      log_y: bool = False) -> ReplicateExtremum:
    """The ``kind`` (``"max"``/``"min"``) extremum of each column of ``Y`` ``(L, R)`` sampled
    at ``x`` ``(L,)``, refined by :func:`jaxdamp.analysis.response.parabolic_extremum` (the
    parabola through the best sample and its two neighbours), with ``log_x``/``log_y`` the
    parabola in ``log x``/``log y`` (results returned in ``x``, ``y``); then the replicates'
    extrema combined by :func:`across`. The one definition of "the optimum with an interval
    over replicates" (the gap scans, the grain-number scan, the design studies).

    Example::

        x = np.array([1.0, 2.0, 3.0, 4.0])
        Y = np.stack([-(x - 2.4) ** 2, -(x - 2.6) ** 2], axis=1)
        replicate_extrema(x, Y).estimate.mean  # 2.5
    """
    from jaxdamp.analysis.response import parabolic_extremum

    x, Y = np.asarray(x, float), np.asarray(Y, float)
    u = np.log(x) if log_x else x
    V = np.log(Y) if log_y else Y
    v = [parabolic_extremum(u, V[:, r], kind) for r in range(V.shape[1])]
    xs = np.array([a[0] for a in v])
    ys = np.array([a[1] for a in v])
    best = np.array([a[2] for a in v], int)
    xs, ys = (np.exp(xs) if log_x else xs), (np.exp(ys) if log_y else ys)
    return ReplicateExtremum(xs, ys, best, across(xs),
                             int(np.sum((best == 0) | (best == len(x) - 1))))


# ---------------------------------------------------------------------------------------------
# per-period series from samples


def per_period(records: dict, frequency: float, channels: tuple[str, ...] = ()) -> dict:
    """Cut the samples of one system into whole drive periods.

    Args:
      records: samples ``t`` [s], ``z_box`` [m], ``work`` ``(T, N_CHANNELS)`` [J] (one system).
      frequency: drive frequency ``f`` [Hz]; periods start at ``t = 0``.
      channels: work channels (names of :data:`jaxdamp.physics.model.CHANNELS`) to add as
        ``<name>_per_cycle``.
    Returns:
      ``{"t_start": (P,), "amplitude": (P,), "phase": (P,), "granular_loss_per_cycle": (P,),
      ...}`` for the ``P`` periods lying wholly inside the samples.
    """
    from jaxdamp.analysis.response import first_harmonic
    from jaxdamp.physics.energy import granular_loss
    from jaxdamp.physics.model import CH

    t = np.asarray(records["t"], float)
    z = np.asarray(records["z_box"], float)
    work = np.asarray(records["work"], float)
    T = 1.0 / frequency
    if len(t) < 2:
        return {k: np.zeros(0) for k in ("t_start", *PERIOD_UNITS,
                                          *(f"{c}_per_cycle" for c in channels))}
    k0 = math.ceil(t[0] / T - 1e-9)
    k1 = math.floor(t[-1] / T + 1e-9)
    edges = np.arange(k0, k1 + 1) * T
    P = max(len(edges) - 1, 0)
    out = {"t_start": edges[:-1]}
    amp = np.full(P, np.nan)
    phase = np.full(P, np.nan)
    idx = np.searchsorted(t, edges - 1e-12 * T)
    for p in range(P):
        a, b = idx[p], idx[p + 1]
        if b - a >= 3:
            zz = z[a:b]
            amp[p] = 0.5 * (zz.max() - zz.min())
            phase[p] = first_harmonic(t[a:b], zz, frequency)[1]
    out["amplitude"] = amp
    out["phase"] = np.unwrap(phase) if P else phase

    def at_edges(col):
        return np.interp(edges, t, col)

    g = at_edges(granular_loss(work))
    out["granular_loss_per_cycle"] = np.diff(g)
    for c in channels:
        out[f"{c}_per_cycle"] = np.diff(at_edges(work[:, CH[c]]))
    return out


@dataclass(frozen=True)
class Detection:
    """Start of the steady state of one replicate: ``start`` [s] and ``period`` (index of
    the first steady period), decided on :data:`DETECT_ON`; ``stationary`` if all of them
    became stationary."""

    start: float
    period: int
    stationary: bool


def detect(series: dict, on=DETECT_ON, **mser_kwargs) -> Detection:
    """The steady state of one replicate starts where the latest of the series ``on`` does
    (:func:`mser` on each)."""
    cuts = [mser(series[k], **mser_kwargs) for k in on if k in series]
    if not cuts or len(series["t_start"]) == 0:
        return Detection(float("nan"), 0, False)
    start = max(c.start for c in cuts)
    stationary = all(c.stationary for c in cuts) and len(series["t_start"]) - start >= mser_kwargs.get("min_keep", 5)
    t0 = float(series["t_start"][start]) if start < len(series["t_start"]) else float("nan")
    return Detection(t0, start, bool(stationary))


def steady(series_list: list[dict], keys=None, n_batches: int = 5, **mser_kwargs) -> dict:
    """Estimates over replicates from their per-period series (:func:`per_period`).

    Each replicate's steady state starts at its own detected start (:func:`detect`); its
    steady mean of every quantity is the mean of the retained periods.

    Returns ``{key: Estimate}`` for every per-period quantity (or ``keys``).
    """
    dets = [detect(s, **mser_kwargs) for s in series_list]
    keys = keys or [k for k in series_list[0] if k != "t_start"]
    out = {}
    for k in keys:
        vals, bse = [], []
        for s, d in zip(series_list, dets):
            x = np.asarray(s[k], float)[d.period:]
            vals.append(float(x.mean()) if len(x) else float("nan"))
            bse.append(batch_means_se(x, n_batches))
        out[k] = across(vals, bse, [d.start for d in dets], [d.stationary for d in dets])
    return out


def summarise(records_list: list[dict], frequency: float, n_batches: int = 5) -> dict:
    """Steady-state estimates (as :func:`to_arrays` of one point, shape ``()``) from the
    samples of ``R`` replicates of one configuration: :func:`per_period`, then
    :func:`steady`."""
    series = [per_period(r, frequency, channels=CHANNELS) for r in records_list]
    return to_arrays([steady(series, n_batches=n_batches)], ())


def shared_window(series_list: list[dict], keys=DETECT_ON, **mser_kwargs) -> dict:
    """Steady means of runs that share their random numbers — one settled bed at several lid
    heights, say — over **one common window**: from the latest of their detected starts
    (:func:`detect`) to the end. A common window keeps what the runs share (the slow transient
    of the primary, the bed's start) common to all of them, so that it cancels in their
    differences (common random numbers); separate windows would add the difference of their
    transient remnants to every finite difference.

    Returns ``{"start": period index, "stationary": all stationary and ≥ ``min_keep``
    periods left, key: (n,) means}``; with too few periods left, the final ``min_keep``
    periods (flagged not stationary)."""
    dets = [detect(s, **mser_kwargs) for s in series_list]
    n = min(len(s["t_start"]) for s in series_list)
    keep = mser_kwargs.get("min_keep", 5)
    start = max(d.period for d in dets)
    ok = all(d.stationary for d in dets) and n - start >= keep
    if n - start < keep:
        start = max(0, n - keep)
    out = {"start": start, "stationary": bool(ok)}
    for k in keys:
        out[k] = np.array([float(np.mean(np.asarray(s[k], float)[start:n])) for s in series_list])
    return out


def rows_window(records: dict, rows, frequency: float, keys=DETECT_ON) -> dict:
    """:func:`shared_window` of the sweep rows ``rows`` of ``records`` (``t``, ``z_box``,
    ``work`` of shape ``(P, T, ...)``; one bed at several designs, say), cut into periods of
    the drive at ``frequency`` [Hz]; adds ``t_start`` [s], the common window's start."""
    series = [per_period({k: records[k][i] for k in ("t", "z_box", "work")}, frequency)
              for i in rows]
    w = shared_window(series, keys)
    t0 = series[0]["t_start"]
    w["t_start"] = float(t0[w["start"]]) if len(t0) > w["start"] else float("nan")
    return w


def to_arrays(estimates: list[dict], shape: tuple) -> dict:
    """Grid of estimates (a list of ``{key: Estimate}``, grid order) as arrays for files and
    plots: ``{key: {"mean", "se", "ci95", "n"  (shape), "values", "batch_se", "start",
    "stationary" (shape + (R,))}}``."""
    out = {}
    for k in estimates[0]:
        e = [d[k] for d in estimates]
        out[k] = {
            "mean": np.array([x.mean for x in e]).reshape(shape),
            "se": np.array([x.se for x in e]).reshape(shape),
            "ci95": np.array([x.ci95 for x in e]).reshape(shape),
            "n": np.array([x.n for x in e]).reshape(shape),
            "values": np.stack([x.values for x in e]).reshape(shape + (-1,)),
            "batch_se": np.stack([x.batch_se for x in e]).reshape(shape + (-1,)),
            "start": np.stack([x.start for x in e]).reshape(shape + (-1,)),
            "stationary": np.stack([x.stationary for x in e]).reshape(shape + (-1,)),
        }
    return out


def replicate_seed(seed: int, k: int) -> int:
    """Seed of replicate ``k`` of a run seeded ``seed``: ``seed + k`` (replicate 0 is the
    run itself). Different seeds give independently jittered lattices, hence independently
    settled beds; the grain radii stay those of ``seed`` (the same grains, poured anew)."""
    return int(seed) + int(k)
