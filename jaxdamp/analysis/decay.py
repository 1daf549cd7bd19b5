"""Free decay of the primary: the damper's characteristic curve ζ(Z), f(Z).

A free-decay test starts the primary (S1, ``primary.U = 0``) displaced by ``primary.z0`` (or
moving at ``primary.v0``) and lets it ring down. Between two successive positive peaks
``X_k, X_{k+1}`` of the displacement from equilibrium ``x = z − z_eq`` the logarithmic
decrement and the equivalent viscous damping ratio of that cycle are

.. math::

    δ_k = \\ln(X_k / X_{k+1}),\\qquad ζ_k = δ_k / \\sqrt{4π^2 + δ_k^2},

exact for a linear viscous oscillator at any ζ (its peaks are one damped period ``T_d`` apart
and shrink by ``exp(ζ ω_n T_d)``, ``δ = 2πζ/\\sqrt{1−ζ^2}``). The cycle's amplitude is the
geometric mean ``Z_k = \\sqrt{X_k X_{k+1}}`` and its frequency ``f_k = 1/(t_{k+1} − t_k)``, the
damped frequency. For a particle damper ζ and f depend on the amplitude: ``ζ(Z)`` is the
damper's characteristic curve (structural damping included: the empty box gives
``C / (2\\sqrt{K (M + m_p)})`` with its grains' mass ``m_p`` as dead mass).

The grains' own share is measured from the energy they dissipate, not from the decrement:
with the cumulative granular loss ``W(t)`` (the contact work channels) between the cycle's two
peaks, ``ΔW_k``, the **granular damping ratio** is the energy-equivalent

.. math::

    ζ_{g,k} = ΔW_k / (2π K Z_k^2),

the ratio a linear viscous damper dissipating ``ΔW_k`` per cycle at amplitude ``Z_k`` near
resonance would have (``π c ω Z^2 / (2π K Z^2) = c ω / 2K ≈ ζ``). It needs no model of the
structural damping and is defined the same way for a stepped-sine run (loss per cycle at its
steady amplitude), which is how the two tests are compared.

Peaks are the sampled maxima refined by the parabola through each and its two neighbours, at
least ``0.6`` of the undamped period apart (impacts make the signal jagged), and above
``floor × X_0`` (below it the decay has reached the numerical noise).

Example::

    >>> import numpy as np
    >>> from jaxdamp.analysis.decay import decay_curve
    >>> t = np.arange(0, 2, 1e-3); wn = 2 * np.pi * 10; z = 0.02
    >>> x = 0.01 * np.exp(-z * wn * t) * np.cos(wn * np.sqrt(1 - z * z) * t)
    >>> c = decay_curve(t, x, z_eq=0.0, f_hint=10.0)
    >>> bool(np.allclose(c["zeta"], 0.02, rtol=1e-3))
    True
"""

from __future__ import annotations

import numpy as np

#: Units of the per-cycle arrays of :func:`decay_curve`.
UNITS = {"t": "s", "Z": "m", "zeta": "1", "f": "Hz", "zeta_g": "1"}


def peaks(t, x, min_distance: int = 1):
    """Positive local maxima of the sampled ``x(t)`` (uniform ``t``), each refined by the
    parabola through it and its neighbours, at least ``min_distance`` samples apart (the
    larger of two closer ones kept): ``(t_k, X_k)``."""
    from scipy.signal import find_peaks

    t = np.asarray(t, float)
    x = np.asarray(x, float)
    i, _ = find_peaks(x, height=0.0, distance=max(1, int(min_distance)))
    i = i[(i > 0) & (i < len(x) - 1)]
    y0, y1, y2 = x[i - 1], x[i], x[i + 1]
    den = y0 - 2.0 * y1 + y2
    safe = np.where(den < 0, den, -1.0)
    d = np.where(den < 0, 0.5 * (y0 - y2) / safe, 0.0)  # vertex offset in samples
    h = t[i + 1] - t[i]
    return t[i] + d * h, y1 - 0.25 * (y0 - y2) * d


def decay_curve(t, z, z_eq: float, f_hint: float, floor: float = 1e-4, loss=None,
                K: float | None = None) -> dict:
    """Per cycle of a free decay ``z(t)`` about the equilibrium ``z_eq``: ``t`` [s] (the
    cycle's start), amplitude ``Z`` [m], damping ratio ``zeta`` and damped frequency ``f``
    [Hz] (:data:`UNITS`), from successive positive peaks at least 0.6 / ``f_hint`` apart
    (``f_hint``: the undamped natural frequency [Hz]) and above ``floor × X_0``. With the
    cumulative granular loss ``loss`` [J] at the samples and the stiffness ``K`` [N/m], also
    ``zeta_g``, the granular damping ratio ``ΔW / (2π K Z²)`` of each cycle."""
    t = np.asarray(t, float)
    x = np.asarray(z, float) - float(z_eq)
    dt = float(np.median(np.diff(t)))
    tk, X = peaks(t, x, min_distance=int(0.6 / (f_hint * dt)))
    if len(X):
        keep = X > floor * X[0]
        stop = np.flatnonzero(~keep)
        n = int(stop[0]) if len(stop) else len(X)
        tk, X = tk[:n], X[:n]
    names = [k for k in UNITS if k != "zeta_g" or loss is not None]
    if len(X) < 2:
        return {k: np.zeros(0) for k in names}
    delta = np.log(X[:-1] / X[1:])
    out = dict(t=tk[:-1], Z=np.sqrt(X[:-1] * X[1:]),
               zeta=delta / np.sqrt(4.0 * np.pi ** 2 + delta ** 2), f=1.0 / np.diff(tk))
    if loss is not None:
        if K is None or K <= 0:
            raise ValueError(f"K = {K!r}: the granular damping ratio needs the stiffness > 0")
        W = np.interp(tk, t, np.asarray(loss, float))
        out["zeta_g"] = np.diff(W) / (2.0 * np.pi * K * out["Z"] ** 2)
    return out


def on_amplitudes(curves: list[dict], Z_grid) -> dict:
    """Replicates' curves (:func:`decay_curve`) on a common amplitude grid ``Z_grid`` [m]:
    each interpolated linearly in ``log Z`` within its own range (NaN outside), then the mean
    and its standard error across replicates at every amplitude: ``{"Z", "zeta", "zeta_se",
    "f", "f_se", "n"}`` and, when the curves have it, ``"zeta_g", "zeta_g_se"`` (``n``
    replicates covering each amplitude); ``"values"``: each replicate's interpolated values
    ``{name: (R, G)}``."""
    Z_grid = np.asarray(Z_grid, float)
    names = [k for k in ("zeta", "f", "zeta_g") if curves and all(k in c for c in curves)]
    vals = {k: np.full((len(curves), len(Z_grid)), np.nan) for k in names}
    for j, c in enumerate(curves):
        if len(c["Z"]) < 2:
            continue
        order = np.argsort(c["Z"])
        lz = np.log(c["Z"][order])
        inside = (np.log(Z_grid) >= lz[0]) & (np.log(Z_grid) <= lz[-1])
        for k in names:
            vals[k][j, inside] = np.interp(np.log(Z_grid[inside]), lz, c[k][order])
    n = (np.isfinite(vals["zeta"]).sum(axis=0) if names
         else np.zeros(len(Z_grid), int))
    out = dict(Z=Z_grid, n=n, values=vals)
    for k in names:
        v = vals[k]
        with np.errstate(invalid="ignore", divide="ignore"):
            m = np.where(n > 0, np.nansum(v, axis=0) / np.maximum(n, 1), np.nan)
            sd = np.sqrt(np.nansum((v - m) ** 2, axis=0) / np.maximum(n - 1, 1))
        out[k], out[f"{k}_se"] = m, np.where(n > 1, sd / np.sqrt(np.maximum(n, 1)), np.nan)
    return out


def at_starting_peak(curve: dict) -> dict:
    """A decay curve (:func:`decay_curve`, cycles at ``Z = √(X_k X_{k+1})``) re-expressed
    at each cycle's starting peak: with the cycle's decrement ``δ = 2πζ/√(1 − ζ²)``,

    .. math:: X_k = Z\\, e^{δ/2}, \\qquad ζ_g(X_k) = ΔW/(2π K X_k^2) = ζ_g(Z)\\, e^{-δ},

    the other end of the amplitude a cycle can be said to have (the other arrays kept). Where
    ``ζ_g`` depends steeply on the amplitude and a cycle loses much of it, the two conventions
    place the same loss at visibly different amplitudes.

    >>> c = at_starting_peak({"Z": np.array([0.01]), "zeta": np.array([0.0]),
    ...                       "zeta_g": np.array([0.02])})
    >>> float(c["Z"][0]), float(c["zeta_g"][0])
    (0.01, 0.02)
    """
    zeta = np.asarray(curve["zeta"])
    delta = 2 * np.pi * zeta / np.sqrt(1 - zeta ** 2)
    out = dict(curve)
    out["Z"] = np.asarray(curve["Z"]) * np.exp(delta / 2)
    out["zeta_g"] = np.asarray(curve["zeta_g"]) * np.exp(-delta)
    return out


def on_common_range(curves: list[dict], n: int = 40) -> dict:
    """Replicates' curves (those with at least two cycles) by :func:`on_amplitudes` on ``n``
    amplitudes spaced evenly in ``log Z`` over the range every one of them covers, from the
    largest of their smallest ``Z`` to the smallest of their largest.

    >>> c = [{"Z": np.array([1.0, 4.0]), "zeta": np.array([0.1, 0.1]),
    ...       "f": np.array([1.0, 1.0])}, {"Z": np.array([2.0, 8.0]),
    ...       "zeta": np.array([0.3, 0.3]), "f": np.array([1.0, 1.0])}]
    >>> r = on_common_range(c, 3)
    >>> np.round(r["Z"], 4).tolist(), np.round(r["zeta"], 6).tolist()
    ([2.0, 2.8284, 4.0], [0.2, 0.2, 0.2])
    """
    beds = [c for c in curves if len(c["Z"]) >= 2]
    lo = max(np.min(c["Z"]) for c in beds)
    hi = min(np.max(c["Z"]) for c in beds)
    return on_amplitudes(beds, np.geomspace(lo, hi, n))
