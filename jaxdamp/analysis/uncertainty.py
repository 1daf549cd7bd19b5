"""The one standard error and the one formatter of a value and its uncertainty.

Every "mean ± SE" of the library and the experiments is computed by :func:`standard_error`
(or :func:`mean_se`) and written by :func:`pm`; :mod:`jaxdamp.analysis.stats` builds its
steady-state estimates on them. Nothing here imports the rest of the package.
"""

from __future__ import annotations

import math

import numpy as np


def standard_error(x, axis: int = -1):
    """Standard error of the mean of independent realisations along ``axis``:
    ``s / √n`` with the sample standard deviation ``s`` (``ddof = 1``); NaN where ``n < 2``.
    The one definition of the ``±`` of a mean over replicates (library and experiments).

    Example::

        standard_error([1.0, 2.0, 3.0])          # 0.5773...
        standard_error(np.ones((4, 1)), axis=1)  # [nan nan nan nan]
    """
    x = np.asarray(x, float)
    n = x.shape[axis]
    if n < 2:
        return np.full(np.delete(np.array(x.shape), axis % x.ndim), np.nan)[()]
    return x.std(axis=axis, ddof=1) / math.sqrt(n)


def mean_se(x, axis: int = -1):
    """``(mean, standard error)`` of independent realisations along ``axis``
    (:func:`standard_error`)."""
    x = np.asarray(x, float)
    return x.mean(axis=axis), standard_error(x, axis)


def lag1_autocorrelation(x) -> float:
    """Lag-1 autocorrelation ``ρ = Σ x'_k x'_{k+1} / Σ x'_k²`` of a series (``x'`` its
    deviations from the mean); NaN for fewer than 3 values or a constant series."""
    x = np.asarray(x, float) - np.mean(x)
    if len(x) < 3 or not np.any(x):
        return float("nan")
    return float(np.sum(x[1:] * x[:-1]) / np.sum(x * x))


def ar1_standard_error(x) -> float:
    """Standard error of the mean of one serially correlated series (a within-run figure,
    not an interval over realisations): :func:`standard_error` times ``√((1+ρ)/(1−ρ))`` with
    ``ρ`` the :func:`lag1_autocorrelation` when ``0 < ρ < 1`` (an AR(1) model); with
    ``ρ ≤ 0`` the plain value, which is then conservative. NaN for fewer than 2 values.

    Example::

        ar1_standard_error([1.0, 2.0, 3.0, 4.0])  # ρ = 0.25: 0.6455 · √(1.25/0.75) = 0.833
    """
    x = np.asarray(x, float)
    if len(x) < 2:
        return float("nan")
    rho = lag1_autocorrelation(x)
    inflate = math.sqrt((1 + rho) / (1 - rho)) if np.isfinite(rho) and 0 < rho < 1 else 1.0
    return float(standard_error(x)) * inflate


def pm(value, error=float("nan"), digits: int = 5, error_digits: int = 2, unit: str = "",
       scale: float = 1.0, compact: bool = False) -> str:
    """The one formatter of a value and its uncertainty: ``"1.2346 ± 0.0012 kg"``.

    ``value`` with ``digits`` significant digits, ``error`` (a standard error or an interval's
    half-width: the caller's text says which) with ``error_digits`` (either may instead be a
    format specification, e.g. ``".4f"``), both multiplied by
    ``scale`` (e.g. 100 for per cent, 1e3 for mm); the ``± error`` part is left out where the
    error is not finite. ``compact``: no spaces around ``±`` (tables, progress bars).

    Example::

        pm(0.123456, 0.0012, unit="m")      # '0.12346 ± 0.0012 m'
        pm(0.0314, 0.002, 3, scale=100)     # '3.14 ± 0.2'
        pm(2.5, float("nan"))               # '2.5'
    """
    sep = "±" if compact else " ± "
    spec = lambda d: d if isinstance(d, str) else f".{d}g"  # noqa: E731
    text = f"{value * scale:{spec(digits)}}"
    if np.isfinite(error):
        text += f"{sep}{error * scale:{spec(error_digits)}}"
    return text + (f" {unit}" if unit else "")
