"""FRF estimates from random-excitation runs: the H1 estimator with coherence, response
spectra and RMS (issue 16; Bendat & Piersol, *Random Data*, §9.1).

For input ``x`` (the base displacement ``u``) and output ``y`` (the primary's displacement
``z``), Welch averages over segments ``k`` (and over independent realisations ``r``: beds and
excitation phases) give the one-sided auto- and cross-spectra::

    G_xx = ⟨|X_k|²⟩,  G_yy = ⟨|Y_k|²⟩,  G_xy = ⟨X_k* Y_k⟩
    H1 = G_xy / G_xx,   γ² = |G_xy|² / (G_xx G_yy)   (0 ≤ γ² ≤ 1)

H1 is unbiased by noise on the output (the bed's chaotic, non-repeatable part); for a
nonlinear damper it is the *best linear approximation* at that excitation level, and
``1 - γ²`` is the fraction of the output power not linearly explained by the input.

Random base motion in jaxdamp is a random-phase multisine of period ``1/Δf``
(:mod:`jaxdamp.physics.excitation`): with segments of exactly one period and a rectangular
window, every line falls on a bin and there is no leakage, so the empty box's H1 equals the
analytic FRF to round-off. The start of the usable record is detected from the data
(:func:`steady_start`): MSER on the mean square of the response in short blocks.

Example::

    >>> import numpy as np
    >>> from jaxdamp.analysis.spectra import h1
    >>> fs, n = 1000.0, 4000
    >>> t = np.arange(n) / fs
    >>> x = np.random.default_rng(1).standard_normal(n)
    >>> y = 2.0 * x                               # a gain of 2
    >>> est = h1([x], [y], fs, nperseg=500)
    >>> bool(np.allclose(est["H"][1:], 2.0) and np.allclose(est["coherence"][1:], 1.0))
    True
"""

from __future__ import annotations

import numpy as np

from jaxdamp.analysis.stats import mser
from jaxdamp.analysis.uncertainty import standard_error


def _segments(x, nperseg: int, window: str):
    """Rows of non-overlapping segments of ``x`` (mean removed) times the window, FFT'd."""
    from scipy.signal import get_window

    n = len(x) // nperseg
    seg = np.asarray(x[: n * nperseg], float).reshape(n, nperseg)
    seg = seg - seg.mean(axis=1, keepdims=True)
    return np.fft.rfft(seg * get_window(window, nperseg), axis=1)


def h1(xs, ys, fs: float, nperseg: int, window: str = "boxcar") -> dict:
    """H1 and coherence pooled over realisations, with the spread between realisations.

    Args:
      xs, ys: input and output records, one array per realisation (equal sampling ``fs``
        [Hz]); each is cut into non-overlapping segments of ``nperseg`` samples.
      window: ``scipy.signal.get_window`` name; ``"boxcar"`` for periodic (multisine)
        records whose period is ``nperseg`` samples, ``"hann"`` otherwise.

    Returns a dict: ``f`` [Hz] ``(F,)``; ``H`` the pooled H1 (complex) and ``coherence``
    ``γ²``; ``Gxx``, ``Gyy`` the pooled one-sided densities [unit²/Hz]; ``H_each`` ``(R, F)``
    each realisation's H1; ``mag_se`` the standard error of ``|H|`` between realisations
    (``s/√R``; NaN for ``R < 2``); ``segments`` the number averaged.
    """
    X = [_segments(x, nperseg, window) for x in xs]
    Y = [_segments(y, nperseg, window) for y in ys]
    if not X or any(len(s) == 0 for s in X):
        raise ValueError(f"h1: every record needs at least nperseg = {nperseg} samples")
    from scipy.signal import get_window

    w = get_window(window, nperseg)
    scale = 2.0 / (fs * np.sum(w * w))  # one-sided density; DC and Nyquist are not doubled
    def dens(a, b):
        g = scale * np.mean(np.conj(a) * b, axis=0)
        g[0] *= 0.5
        if nperseg % 2 == 0:
            g[-1] *= 0.5
        return g

    each = [(dens(a, a).real, dens(b, b).real, dens(a, b)) for a, b in zip(X, Y)]
    k = np.array([len(a) for a in X], float)
    gxx = sum(kk * e[0] for kk, e in zip(k, each)) / k.sum()
    gyy = sum(kk * e[1] for kk, e in zip(k, each)) / k.sum()
    gxy = sum(kk * e[2] for kk, e in zip(k, each)) / k.sum()
    with np.errstate(divide="ignore", invalid="ignore"):
        H = gxy / gxx
        coh = np.abs(gxy) ** 2 / (gxx * gyy)
        H_each = np.array([e[2] / e[0] for e in each])
    R = len(each)
    mag_se = (standard_error(np.abs(H_each), axis=0) if R > 1
              else np.full(len(H), np.nan))
    return dict(f=np.fft.rfftfreq(nperseg, 1.0 / fs), H=H, coherence=coh, Gxx=gxx, Gyy=gyy,
                H_each=H_each, mag_se=mag_se, segments=int(k.sum()))


def steady_start(t, y, block: float) -> tuple[float, bool]:
    """Start [s] of the stationary part of the response ``y(t)``, from the data: MSER
    (:func:`jaxdamp.analysis.stats.mser`) on the mean square of ``y - mean(y)`` in blocks of
    ``block`` seconds. Returns ``(start, stationary)``."""
    t = np.asarray(t, float)
    y = np.asarray(y, float)
    dt = t[1] - t[0]
    nb = max(1, int(round(block / dt)))
    n = len(y) // nb
    if n < 8:
        return float(t[0]), False
    yb = y[: n * nb].reshape(n, nb)
    ms = ((yb - y.mean()) ** 2).mean(axis=1)
    cut = mser(ms)
    return float(t[0] + cut.start * nb * dt), bool(cut.stationary)


def rms(x) -> float:
    """Root mean square of ``x`` about its mean."""
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean((x - x.mean()) ** 2)))
