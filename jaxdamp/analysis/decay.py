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
UNITS = {"t": "s", "Z": "m", "zeta": "1", "f": "Hz"}


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


def decay_curve(t, z, z_eq: float, f_hint: float, floor: float = 1e-4) -> dict:
    """Per cycle of a free decay ``z(t)`` about the equilibrium ``z_eq``: ``t`` [s] (the
    cycle's start), amplitude ``Z`` [m], damping ratio ``zeta`` and damped frequency ``f``
    [Hz] (:data:`UNITS`), from successive positive peaks at least 0.6 / ``f_hint`` apart
    (``f_hint``: the undamped natural frequency [Hz]) and above ``floor × X_0``."""
    t = np.asarray(t, float)
    x = np.asarray(z, float) - float(z_eq)
    dt = float(np.median(np.diff(t)))
    tk, X = peaks(t, x, min_distance=int(0.6 / (f_hint * dt)))
    if len(X):
        keep = X > floor * X[0]
        stop = np.flatnonzero(~keep)
        n = int(stop[0]) if len(stop) else len(X)
        tk, X = tk[:n], X[:n]
    if len(X) < 2:
        return {k: np.zeros(0) for k in UNITS}
    delta = np.log(X[:-1] / X[1:])
    return dict(t=tk[:-1], Z=np.sqrt(X[:-1] * X[1:]),
                zeta=delta / np.sqrt(4.0 * np.pi ** 2 + delta ** 2), f=1.0 / np.diff(tk))


def on_amplitudes(curves: list[dict], Z_grid) -> dict:
    """Replicates' curves (:func:`decay_curve`) on a common amplitude grid ``Z_grid`` [m]:
    each interpolated linearly in ``log Z`` within its own range (NaN outside), then the mean
    and its standard error across replicates at every amplitude: ``{"Z", "zeta", "zeta_se",
    "f", "f_se", "n"}`` (``n`` replicates covering each amplitude)."""
    Z_grid = np.asarray(Z_grid, float)
    zeta = np.full((len(curves), len(Z_grid)), np.nan)
    freq = np.full_like(zeta, np.nan)
    for j, c in enumerate(curves):
        if len(c["Z"]) < 2:
            continue
        order = np.argsort(c["Z"])
        lz = np.log(c["Z"][order])
        inside = (np.log(Z_grid) >= lz[0]) & (np.log(Z_grid) <= lz[-1])
        zeta[j, inside] = np.interp(np.log(Z_grid[inside]), lz, c["zeta"][order])
        freq[j, inside] = np.interp(np.log(Z_grid[inside]), lz, c["f"][order])
    n = np.isfinite(zeta).sum(axis=0)

    def mean_se(v):
        with np.errstate(invalid="ignore", divide="ignore"):
            m = np.where(n > 0, np.nansum(v, axis=0) / np.maximum(n, 1), np.nan)
            sd = np.sqrt(np.nansum((v - m) ** 2, axis=0) / np.maximum(n - 1, 1))
            return m, np.where(n > 1, sd / np.sqrt(np.maximum(n, 1)), np.nan)

    zm, zs = mean_se(zeta)
    fm, fs = mean_se(freq)
    return dict(Z=Z_grid, zeta=zm, zeta_se=zs, f=fm, f_se=fs, n=n)
