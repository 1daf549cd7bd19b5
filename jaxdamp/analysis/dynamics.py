"""Nonlinear-dynamics analysis of a scalar time series (thesis ch. 4, docs/physics.md §6).

For a uniformly sampled scalar series such as the bed's centre of mass ``z_cm(t)``:

- stroboscopic Poincaré section at the drive period (:func:`poincare_section`);
- one-sided power spectral density with the drive's harmonics and subharmonics located
  (:func:`power_spectrum`);
- delay embedding: delay from the first minimum of the average mutual information
  (:func:`mutual_information_delay`), dimension from false nearest neighbours
  (:func:`false_nearest_neighbours`), both for a driven series (:func:`embedding_parameters`),
  the delay vectors themselves (:func:`embed`);
- largest Lyapunov exponent by Kantz's method (:func:`lyapunov_kantz`), fitted over more than
  one drive period, and the exponent of two simulated trajectories' separation
  (:func:`divergence_exponent`);
- noise-robust periodicity levels: stroboscopic spread relative to the orbit
  (:func:`strobe_spread`) and the power fraction at the drive's lines (:func:`harmonic_fraction`);
- a periodic / quasi-periodic / chaotic verdict from all of the above (:func:`classify`).

Pure numpy/scipy, no JAX: these run once on a recorded series, not inside the simulation.
Times are in seconds (or any unit, consistently: an exponent comes back in 1/[unit of ``dt``]);
``frequency`` is the drive's ``f`` [Hz], the drive being ``cos(2π f t)`` with ``t`` counted from
the start of the run (``excitation.py``), so that phase 0 is the drive's maximum.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

# --------------------------------------------------------------------------- Poincaré section


@dataclass(frozen=True)
class PoincareSection:
    """One point per drive period, at ``t_k = (k + phase/2π)/f``.

    Attributes:
      t: section times [s], ``(K,)``.
      x: the series at ``t_k``, ``(K,)`` [units of x].
      dxdt: its time derivative at ``t_k``, ``(K,)`` [units of x / s] (from the interpolating
        spline; meaningless for a map sampled once per period).
      frequency, phase: the drive frequency [Hz] and the section's phase [rad].
    """

    t: np.ndarray
    x: np.ndarray
    dxdt: np.ndarray
    frequency: float
    phase: float

    def points(self, kind: str = "velocity") -> np.ndarray:
        """Section points ``(P, 2)``: ``kind="velocity"`` → ``(x_k, x'_k)`` with ``P = K``;
        ``kind="return"`` → the first-return map ``(x_k, x_{k+1})`` with ``P = K - 1``."""
        if kind == "velocity":
            return np.stack([self.x, self.dxdt], axis=1)
        if kind == "return":
            return np.stack([self.x[:-1], self.x[1:]], axis=1)
        raise ValueError(f"kind must be 'velocity' or 'return', got {kind!r}")


def poincare_section(t, x, frequency, phase=0.0, t_start=None) -> PoincareSection:
    """Stroboscopic Poincaré section of ``x(t)`` at the drive period ``1/f``.

    The series is interpolated by a cubic spline (so the section does not depend on where
    the samples fall within the period) at ``t_k = (k + phase/2π)/f`` for every integer ``k``
    with ``t_k`` inside ``[max(t[0], t_start), t[-1]]``; pass ``t_start`` to drop a transient.
    Use ``.points("velocity")`` for ``(x_k, x'_k)`` or ``.points("return")`` for
    ``(x_k, x_{k+1})``. With one sample per period (a map, ``t = n/f``) the section is the
    series itself.

    Args:
      t: sample times [s], ``(N,)``, increasing. x: the series, ``(N,)``.
      frequency: drive frequency f [Hz]. phase: section phase [rad] within the period.
    """
    from scipy.interpolate import CubicSpline

    t = np.asarray(t, float)
    x = np.asarray(x, float)
    f = float(frequency)
    if f <= 0:
        raise ValueError(f"frequency must be > 0, got {f}")
    lo = t[0] if t_start is None else max(t[0], float(t_start))
    off = phase / (2 * np.pi)
    # small slack so that section times that coincide with the first/last sample survive
    # round-off in k/f
    eps = 1e-9 * (t[-1] - t[0]) + 1e-12
    k = np.arange(np.ceil(lo * f - off - eps), np.floor(t[-1] * f - off + eps) + 1)
    tk = np.clip((k + off) / f, t[0], t[-1])
    spl = CubicSpline(t, x)
    return PoincareSection(tk, spl(tk), spl(tk, 1), f, float(phase))


# --------------------------------------------------------------------------- spectrum


@dataclass(frozen=True)
class Spectrum:
    """One-sided power spectral density and the drive's lines located on it.

    Attributes:
      f: frequencies [Hz], ``(F,)``. psd: PSD [x²/Hz], ``(F,)`` (one-sided: integrates to the
        variance of the mean-removed series).
      method: ``"welch"`` or ``"periodogram"`` and the window used.
      lines: drive lines inside the band, ``[(label, nominal f [Hz], psd at nearest bin)]``:
        harmonics ``f, 2f, ...`` and subharmonics ``f/2, f/3`` (with ``3f/2``, ``2f/3``).
    """

    f: np.ndarray
    psd: np.ndarray
    method: str
    lines: list = field(default_factory=list)


def power_spectrum(t, x, frequency=None, method="welch", periods_per_segment=None,
                   n_harmonics=10) -> Spectrum:
    """One-sided PSD of ``x(t)`` (mean removed, Hann window).

    ``method="welch"`` (default): ``scipy.signal.welch``, Hann window, 50 % overlap; with a
    drive frequency the segment holds a whole number of drive periods (``periods_per_segment``,
    default: a quarter of the record, at least 1 period) so that ``f`` and its harmonics fall
    on bins. ``method="periodogram"``: one Hann-windowed FFT of the whole record (finest
    resolution, noisier; used by :func:`classify` to tell lines from a broadband spectrum).

    Args:
      t: sample times [s], ``(N,)``, uniform. x: ``(N,)``. frequency: drive f [Hz] or None.
    Returns:
      :class:`Spectrum`; ``lines`` lists the drive's harmonics ``n f`` (n ≤ ``n_harmonics``)
      and subharmonics below Nyquist, for marking on plots.
    """
    from scipy import signal

    t = np.asarray(t, float)
    x = np.asarray(x, float)
    dt = (t[-1] - t[0]) / (len(t) - 1)
    fs = 1.0 / dt
    if method == "welch":
        if frequency is not None:
            spp = fs / frequency
            nper = periods_per_segment or max(1, int(len(x) / spp / 4))
            nperseg = min(len(x), max(8, int(round(nper * spp))))
        else:
            nperseg = min(len(x), max(8, len(x) // 4))
        fr, p = signal.welch(x, fs=fs, window="hann", nperseg=nperseg, noverlap=nperseg // 2,
                             detrend="constant", scaling="density")
        label = f"welch (hann, nperseg={nperseg}, 50% overlap)"
    elif method == "periodogram":
        fr, p = signal.periodogram(x, fs=fs, window="hann", detrend="constant",
                                   scaling="density")
        label = "periodogram (hann, whole record)"
    else:
        raise ValueError(f"method must be 'welch' or 'periodogram', got {method!r}")
    lines = []
    if frequency is not None:
        f0 = float(frequency)
        cands = [(f"{n}f" if n > 1 else "f", n * f0) for n in range(1, n_harmonics + 1)]
        cands += [("f/2", f0 / 2), ("f/3", f0 / 3), ("3f/2", 1.5 * f0), ("2f/3", 2 * f0 / 3)]
        for lab, fl in cands:
            if 0 < fl <= fr[-1]:
                i = int(np.argmin(np.abs(fr - fl)))
                lines.append((lab, fl, float(p[i])))
    return Spectrum(fr, p, label, lines)


def line_fraction(psd, n_lines=20, half_width=3, exclude=None):
    """Fraction of the power inside the ``n_lines`` strongest spectral peaks, each taken as
    ``±half_width`` bins (a Hann main lobe is ±2 bins), ignoring the DC bin and the bins in
    the boolean mask ``exclude`` ``(F,)`` (e.g. :func:`harmonic_mask`).

    Close to 1 for a line spectrum (periodic, quasi-periodic: a few discrete frequencies and
    their combinations); well below 1 for a broadband (chaotic or noisy) one, and the
    finer the resolution the lower. Returns 1 if there is no power left.
    """
    from scipy.signal import find_peaks

    p = np.array(psd, float)
    p[0] = 0.0
    if exclude is not None:
        p[np.asarray(exclude, bool)] = 0.0
    total = p.sum()
    if total <= 0:
        return 1.0
    pk, _ = find_peaks(np.concatenate([[0.0], p, [0.0]]))
    pk = pk - 1
    pk = pk[np.argsort(p[pk])[::-1][:n_lines]]
    mask = np.zeros(p.size, bool)
    for i in pk:
        mask[max(0, i - half_width): i + half_width + 1] = True
    return float(p[mask].sum() / total)


def harmonic_mask(freqs, frequency, half_width=3):
    """Bins within ``±half_width`` bins of a drive harmonic ``n f`` (n ≥ 1), ``(F,)`` bool.

    A driven response carries most of its power at the drive's harmonics whatever its
    dynamics (the bed follows the box); masking them lets :func:`line_fraction` judge the
    rest, which is a few lines for quasi-periodic motion and broadband for chaos."""
    freqs = np.asarray(freqs, float)
    df = freqs[1] - freqs[0]
    n = np.round(freqs / frequency)
    return (n >= 1) & (np.abs(freqs - n * frequency) <= half_width * df + 1e-12 * frequency)


# --------------------------------------------------------------------------- delay embedding


def embed(x, dim, delay):
    """Delay vectors ``s_n = (x_n, x_{n+τ}, ..., x_{n+(m-1)τ})``, ``(N - (m-1)τ, m)``.

    ``delay`` τ and the result's row index are in samples (row ``n`` starts at sample ``n``;
    the thesis' eq. 4.1.1 orders the same coordinates backwards, which changes nothing).
    """
    x = np.asarray(x, float)
    dim, delay = int(dim), int(delay)
    n = x.size - (dim - 1) * delay
    if dim < 1 or delay < 1 or n < 1:
        raise ValueError(f"cannot embed {x.size} samples with dim={dim}, delay={delay}")
    return np.lib.stride_tricks.sliding_window_view(x, (dim - 1) * delay + 1)[:, ::delay].copy()


def mutual_information(x, max_lag, bins=16):
    """Average mutual information ``I(τ)`` [nats] between ``x_n`` and ``x_{n+τ}`` for
    ``τ = 0..max_lag`` samples, from a 2-D histogram on ``bins`` equal-width boxes over the
    series' range (as TISEAN ``mutual``), ``(max_lag + 1,)``."""
    x = np.asarray(x, float)
    lo, hi = x.min(), x.max()
    if hi <= lo:
        return np.zeros(max_lag + 1)
    b = np.minimum(((x - lo) / (hi - lo) * bins).astype(int), bins - 1)
    out = np.empty(max_lag + 1)
    for lag in range(max_lag + 1):
        a, c = b[: b.size - lag], b[lag:]
        pxy = np.bincount(a * bins + c, minlength=bins * bins).reshape(bins, bins) / a.size
        px, py = pxy.sum(1), pxy.sum(0)
        nz = pxy > 0
        out[lag] = np.sum(pxy[nz] * np.log(pxy[nz] / np.outer(px, py)[nz]))
    return out


def mutual_information_delay(x, max_lag, bins=16, min_prominence=0.0):
    """Embedding delay τ [samples]: the first local minimum of the average mutual information.

    Returns ``(delay, mi)`` with ``mi`` the curve ``(max_lag + 1,)`` [nats]. If ``I(τ)`` has no
    minimum up to ``max_lag`` (too short a window), falls back to the first ``τ`` where ``I``
    drops below ``I(0)/e`` — or ``max_lag`` if it never does.

    ``min_prominence`` (fraction of ``I(0) - min I``) skips dips shallower than that
    (``scipy.signal.find_peaks`` prominence). Default 0, the plain first minimum (TISEAN
    ``mutual``): the Lorenz ``x`` series' accepted first minimum (0.18 time units) is a
    shallow dip of prominence ~1e-4 of the range. Near-pure sines are the opposite case: the
    histogram estimate of a smooth deterministic signal is jagged from lag to lag (bin
    aliasing), with spurious minima a few samples in; ``min_prominence=0.2`` finds their
    quarter-period minimum.
    """
    from scipy.signal import find_peaks

    mi = mutual_information(x, max_lag, bins)
    rng = mi[0] - mi.min()
    if rng > 0:
        pk, props = find_peaks(-mi, prominence=0.0)
        pk = pk[props["prominences"] >= min_prominence * rng]
        if pk.size:
            return int(pk[0]), mi
    below = np.nonzero(mi < mi[0] / np.e)[0]
    return (int(below[0]) if below.size else int(max_lag)), mi


def _nearest_outside(tree, y, query, theiler, k0):
    """Index of and distance to the nearest point of ``tree`` (built on ``y``) to each row
    ``query`` [indices into y], excluding ``|i - j| <= theiler`` (temporal neighbours on the
    same stretch of orbit are not evidence about the attractor's geometry)."""
    k = min(max(k0, 2 * theiler + 2), len(y))  # 2w+1 points lie in the window: one more is out
    d, j = tree.query(y[query], k=k)
    d, j = np.atleast_2d(d), np.atleast_2d(j)
    bad = np.abs(j - query[:, None]) <= theiler
    d = np.where(bad, np.inf, d)
    col = np.argmin(d, axis=1)
    rows = np.arange(len(query))
    return j[rows, col], d[rows, col]


def false_nearest_neighbours(x, delay, max_dim=8, rtol=10.0, atol=2.0, theiler=None,
                             threshold=0.01, n_ref=4000):
    """False-nearest-neighbour fractions (Kennel, Brown & Abarbanel 1992) for ``m = 1..max_dim``.

    For each reference delay vector (up to ``n_ref``, evenly spaced) its nearest neighbour in
    ``m`` dimensions (Euclidean, outside the Theiler window) is *false* if adding the
    ``(m+1)``-th coordinate separates them: ``|x_{i+mτ} - x_{j+mτ}| / R_m > rtol`` or
    ``R_{m+1} / σ_x > atol`` (the second test catches neighbours that are merely far).

    Args:
      x: series ``(N,)``. delay: τ [samples]. theiler: exclusion window [samples], default τ.
      threshold: the embedding dimension is the first ``m`` whose fraction is below it.
    Returns:
      ``(fractions (max_dim,), dim)`` — fraction for m = 1..max_dim; ``dim = max_dim`` if the
      fraction never drops below ``threshold``.
    """
    from scipy.spatial import cKDTree

    x = np.asarray(x, float)
    w = int(delay if theiler is None else theiler)
    sigma = np.std(x)
    frac = np.empty(max_dim)
    for m in range(1, max_dim + 1):
        y = embed(x, m, delay)[: x.size - m * delay]  # every row has its (m+1)-th coordinate
        if len(y) < 2 * w + 3:
            raise ValueError("series too short for this delay / dimension")
        q = np.unique(np.linspace(0, len(y) - 1, min(n_ref, len(y))).astype(int))
        j, r = _nearest_outside(cKDTree(y), y, q, w, 2)
        extra = np.abs(x[q + m * delay] - x[j + m * delay])
        # a floor on R_m: exact repeats (a periodic series sampled commensurately) sit at
        # R_m ≈ 0, where the ratio would compare round-off with round-off
        false = (extra > rtol * np.maximum(r, 1e-9 * sigma)) | (
            np.sqrt(r**2 + extra**2) > atol * sigma)
        frac[m - 1] = np.mean(false)
    below = np.nonzero(frac < threshold)[0]
    return frac, int(below[0] + 1) if below.size else int(max_dim)


def embedding_parameters(x, frequency, dt=1.0, min_prominence=0.2, max_dim=8, min_horizon=40):
    """Delay and dimension of the delay embedding of a driven series ``x`` (drive ``frequency``
    [Hz], samples ``dt`` [s] apart, ``p = 1/(f dt)`` samples per drive period).

    Delay τ: the first minimum of the mutual information of prominence ``min_prominence`` of
    its range, lags up to ``max(4, ⌊2p⌋)`` (:func:`mutual_information_delay`; the histogram
    estimate of a nearly sinusoidal series has spurious one-sample dips, which with the plain
    first minimum give τ = 1 sample and a degenerate embedding). Dimension: the first with
    < 1 % false nearest neighbours (:func:`false_nearest_neighbours`), trying ``m + 1`` after
    ``m < max_dim`` only while the series leaves room for it: ``N − mτ`` delay vectors less two
    Theiler windows ``max(p, (m + 1)τ)`` (one drive period or one embedding window, as
    :func:`classify` uses) less 3 keep at least ``min_horizon`` samples for Kantz's curve, and
    FNN's test has ``N − (m + 1)τ ≥ 2τ + 3`` vectors. The limit binds on short series only.

    Returns ``(dim, delay, mi, fnn)``: delay [samples], the mutual information
    ``(max_lag + 1,)`` [nats] and the false-neighbour fractions for m = 1, 2, ....

    >>> import numpy as np
    >>> t = np.arange(0.0, 100.0, 0.005)  # 2 Hz, 100 samples per period
    >>> dim, delay, mi, fnn = embedding_parameters(np.sin(4 * np.pi * t + 0.1), 2.0, 0.005)
    >>> abs(delay - 25) <= 2, len(fnn)  # a quarter period; a long series tries 8 dimensions
    (True, 8)
    """
    spp = 1.0 / (frequency * dt)
    delay, mi = mutual_information_delay(x, max_lag=max(4, int(2 * spp)),
                                         min_prominence=min_prominence)
    n, m = len(x), 1
    while m < max_dim and (n - m * delay - 2 * max(spp, (m + 1) * delay) - 3 >= min_horizon
                           and n - (m + 1) * delay >= 2 * delay + 3):
        m += 1
    fnn, dim = false_nearest_neighbours(x, delay, max_dim=m)
    return dim, delay, mi, fnn


# --------------------------------------------------------------------------- Lyapunov (Kantz)


@dataclass(frozen=True)
class LyapunovResult:
    """Largest Lyapunov exponent by Kantz's method.

    Attributes:
      exponent: slope of ``S`` over the fit range per unit of ``dt`` [1/s; 1/iteration if
        ``dt = 1``].
      steps: ``Δn`` [samples], ``(L,)``; S: ``S(Δn)`` = mean log distance, ``(L,)``.
      fit_range: ``(first, last)`` indices into ``steps`` of the fitted points (inclusive).
      intercept: of the fitted line (in S units) against ``Δn·dt``.
      dt: sampling interval; epsilon: neighbourhood radius used [units of x];
      n_ref: reference points that had neighbours; dim, delay, theiler: embedding used.
    """

    exponent: float
    steps: np.ndarray
    S: np.ndarray
    fit_range: tuple
    intercept: float
    dt: float
    epsilon: float
    n_ref: int
    dim: int
    delay: int
    theiler: int

    @property
    def time(self):
        """``Δn·dt``, ``(L,)`` [s]."""
        return self.steps * self.dt


def kantz_curve(y, max_steps, epsilon, theiler, n_ref=2000, min_neighbours=1, max_neighbours=50):
    """Kantz's ``S(Δn) = <ln( mean_{n' ∈ U_ε(n)} |s_{n+Δn} - s_{n'+Δn}| )>_n`` for
    ``Δn = 0..max_steps`` (thesis eq. 4.1.7), over delay vectors ``y`` ``(M, m)``.

    ``U_ε(n)``: points within Euclidean distance ``epsilon`` of ``s_n``, outside the Theiler
    window ``|n - n'| > theiler``, capped at the ``max_neighbours`` nearest (a cap only bounds
    the cost in dense regions). References (up to ``n_ref``, evenly spaced) with fewer than
    ``min_neighbours`` are skipped. Returns ``(S (max_steps+1,), number of references used)``.
    """
    from scipy.spatial import cKDTree

    M = len(y) - max_steps  # every point used must have a future of max_steps samples
    if M < 2 * theiler + 3:
        raise ValueError("series too short for this horizon / Theiler window")
    base = y[:M]
    tree = cKDTree(base)
    refs = np.unique(np.linspace(0, M - 1, min(n_ref, M)).astype(int))
    k = min(M, max_neighbours + 2 * theiler + 1)
    d, j = tree.query(base[refs], k=k, distance_upper_bound=epsilon)
    ok = np.isfinite(d) & (np.abs(j - refs[:, None]) > theiler)
    # keep the max_neighbours nearest valid ones (query returns them sorted by distance)
    ok &= np.cumsum(ok, axis=1) <= max_neighbours
    cnt = ok.sum(1)
    use = cnt >= min_neighbours
    if not np.any(use):
        return np.full(max_steps + 1, np.nan), 0
    r_idx, c_idx = np.nonzero(ok & use[:, None])
    a = refs[r_idx]  # reference of each pair
    b = j[r_idx, c_idx]  # its neighbour
    grp = np.searchsorted(refs[use], a)  # pair → index among used references
    ng = int(use.sum())
    n_in = np.bincount(grp, minlength=ng)
    S = np.empty(max_steps + 1)
    for dn in range(max_steps + 1):
        dist = np.linalg.norm(y[a + dn] - y[b + dn], axis=1)
        mean = np.bincount(grp, weights=dist, minlength=ng) / n_in
        S[dn] = np.mean(np.log(np.maximum(mean, 1e-300)))
    return S, ng


def auto_fit_range(S, min_points=3, min_rise=0.6931471805599453, grid=60):
    """Indices ``(first, last)`` of the linear (exponential-growth) region of ``S(Δn)``.

    A Kantz curve has up to three parts: a fast initial rise while the separation vectors
    turn onto the unstable direction (and embedding distortion decays), the linear region
    whose slope is the exponent, and a plateau once distances reach the attractor's size.
    Fit a continuous three-segment broken line to ``S`` by least squares over all breakpoint
    pairs ``b1 < b2`` (on a grid of at most ``grid`` candidates each; the middle segment
    spans at least ``min_points`` points); the linear region is the longer of the first two
    segments (a map has no initial transient, and the first segment is then the linear one).
    Fixed fractions of the total rise do not work: on the Lorenz ``x`` series the initial
    rise alone is ~40 % of it.

    If ``S`` rises by less than ``min_rise`` (ln 2) overall (distances did not even double:
    regular motion, no exponential divergence to measure) the whole curve is fitted, which
    gives a slope near zero instead of the slope of some fluctuation.
    """
    S = np.asarray(S, float)
    n = len(S)
    rise = np.mean(S[-max(1, n // 5):]) - np.mean(S[: max(1, n // 20)])
    if n < min_points + 2 or not np.isfinite(rise) or rise < min_rise:
        return 0, n - 1
    cand = np.unique(np.linspace(0, n - 1, min(grid, n)).round().astype(int))
    b1, b2 = np.meshgrid(cand, cand, indexing="ij")
    ok = b2 - b1 >= min_points - 1
    b1, b2 = b1[ok], b2[ok]
    k = np.arange(n)[None, :]
    lo, hi = b1[:, None], b2[:, None]
    A = np.stack([np.ones((len(b1), n)), np.minimum(k, lo), np.clip(k - lo, 0, hi - lo),
                  np.maximum(k - hi, 0)], axis=2).astype(float)  # (P, n, 4)
    AtA = np.einsum("pni,pnj->pij", A, A) + 1e-9 * np.eye(4)
    Atb = np.einsum("pni,n->pi", A, S)
    coef = np.linalg.solve(AtA, Atb[..., None])[..., 0]
    res = np.sum((np.einsum("pni,pi->pn", A, coef) - S) ** 2, axis=1)
    best = int(np.argmin(res))
    i1, i2 = int(b1[best]), int(b2[best])
    if i1 + 1 >= min_points and i1 > i2 - i1:
        return 0, i1
    return i1, i2


def lyapunov_kantz(x, dim, delay, dt=1.0, max_steps=None, epsilon=None, theiler=None,
                   fit_range=None, n_ref=2000, min_neighbours=5, max_neighbours=50,
                   min_fit=3):
    """Largest Lyapunov exponent of a scalar series by Kantz's method (Kantz 1994;
    thesis §4.1.3).

    Embeds ``x`` (``dim``, ``delay`` [samples]), computes ``S(Δn)`` (:func:`kantz_curve`) and
    fits a straight line to ``S`` against ``Δn·dt`` over ``fit_range``; the slope is the
    exponent.

    Args:
      x: series ``(N,)``. dt: sampling interval [s] (1 for a map: exponent per iteration).
      max_steps: horizon of ``S`` [samples]; default ``30·delay`` (flows: several mean
        periods, long enough to reach saturation), at least 20, but at most half of what the
        series leaves after the Theiler window (short series).
      epsilon: neighbourhood radius [units of x]; default ``0.02·σ_x·√dim``, doubled (up to 5
        times) while fewer than a quarter of the references have ``min_neighbours``.
      theiler: exclusion window [samples]; default ``dim·delay`` (one embedding window).
      fit_range: ``(first, last)`` indices into ``Δn`` (inclusive), or None for
        :func:`auto_fit_range`.
      min_fit: fewest points of the automatic fit range. A flow's exponent fitted over less
        than one drive period measures how separations turn within the period, not their
        growth from period to period: :func:`classify` asks for one period plus one sample
        (and lengthens the horizon to three periods if needed).
    Returns:
      :class:`LyapunovResult`.
    """
    x = np.asarray(x, float)
    dim, delay = int(dim), int(delay)
    w = int(dim * delay if theiler is None else theiler)
    L = int(max(20, 30 * delay) if max_steps is None else max_steps)
    y = embed(x, dim, delay)
    if max_steps is None:  # a short series: keep at least half the vectors as references
        L = max(1, min(L, (len(y) - 2 * w - 3) // 2))
    eps = 0.02 * np.std(x) * np.sqrt(dim) if epsilon is None else float(epsilon)
    for attempt in range(6):
        S, nref = kantz_curve(y, L, eps, w, n_ref, min_neighbours, max_neighbours)
        enough = nref >= 0.25 * min(n_ref, len(y) - L)
        if epsilon is not None or enough or attempt == 5:
            break
        eps *= 2.0
    if nref == 0:
        raise ValueError("no reference point has neighbours within epsilon")
    i0, i1 = (auto_fit_range(S, min_points=min(int(min_fit), L)) if fit_range is None
              else (int(fit_range[0]), int(fit_range[1])))
    steps = np.arange(L + 1)
    slope, icpt = np.polyfit(steps[i0: i1 + 1] * dt, S[i0: i1 + 1], 1)
    return LyapunovResult(float(slope), steps, S, (i0, i1), float(icpt), float(dt), float(eps),
                          int(nref), dim, delay, w)


# --------------------------------------------------------------------------- periodicity


def strobe_spread(section: PoincareSection, scale, max_period=4):
    """Noise-robust periodicity: for ``k = 1..max_period`` the RMS spread of the stroboscopic
    section points about their own class mean, the classes being the points ``j ≡ i (mod k)``,
    over ``scale`` (the orbit's size, e.g. the series' standard deviation), ``(max_period,)``.

    ``spread_k = sqrt(mean_i (x_i − x̄_{i mod k})²) / scale``: 0 for an exact period-k orbit;
    for a period-k orbit with noise of RMS ``σ`` it is ``σ/scale`` — a level, not a yes/no,
    so a verdict is "period-k within tolerance τ" when ``spread_k < τ``, and the number says
    how close to a tolerance the verdict lies. Unlike :func:`section_return_distances` it
    uses every point (a mean, not a median) and needs no neighbour in time.

    >>> import numpy as np
    >>> sec = PoincareSection(np.arange(6.0), np.array([1, -1, 1, -1, 1, -1.0]),
    ...                       np.zeros(6), 1.0, 0.0)
    >>> np.round(strobe_spread(sec, 1.0, 2), 6).tolist()
    [1.0, 0.0]
    """
    x = np.asarray(section.x, float)
    out = np.full(max_period, np.nan)
    for k in range(1, max_period + 1):
        n = (len(x) // k) * k
        if n < 2 * k:
            continue
        xs = x[:n].reshape(-1, k)
        out[k - 1] = float(np.sqrt(np.mean((xs - xs.mean(axis=0)) ** 2)) / scale)
    return out


def harmonic_fraction(spec: Spectrum, frequency, k=1, half_width=3):
    """Fraction of the (mean-removed) power of a spectrum at the lines ``n f/k`` (n ≥ 1),
    each ``±half_width`` bins: 1 for a period-k response, lower as power leaks into other
    frequencies (quasi-periodic lines, broadband chaos or noise). ``k = 1``: the drive's
    harmonics; ``k = 2``: harmonics and subharmonics ``f/2, 3f/2, ...``."""
    p = np.array(spec.psd, float)
    p[0] = 0.0
    total = p.sum()
    if total <= 0:
        return 1.0
    return float(p[harmonic_mask(spec.f, frequency / k, half_width)].sum() / total)


def divergence_exponent(t, d, frequency, saturation=None, t_start=None, d0=None):
    """Exponent of the growth of the distance ``d(t)`` between two trajectories started a tiny
    perturbation apart (a *twin* run), per second and per drive period.

    ``d`` is reduced to its per-period maximum ``D_k`` (the distance of two driven
    trajectories oscillates within a period). Growth stops at a plateau — the attractor's
    size, or less for an observable the divergence reaches only weakly — taken from the data
    as the median of ``D`` over the last quarter of the periods (capped by ``saturation``
    [units of d] when given). If ``D`` grew by more than a factor 100 to that plateau,
    ``ln D_k`` is fitted by a straight line over the periods before ``D_k`` first reaches a
    tenth of the plateau (at least two, so the fit always spans more than one drive period);
    otherwise (the twins stay together: regular motion) over every period.

    ``d0``: the size of the initial perturbation (in the units of ``d``, e.g. the displacement
    of one grain [m]); the growth is then judged from it rather than from ``D_0``, which
    already holds whatever grew during the first period. If ``D_0`` is itself within a factor
    10 of the plateau, the divergence saturated within the first period and only a lower
    bound is known, ``ln(D_0/d0) / T`` (returned as the exponent, with ``lower_bound``).

    Returns ``{"exponent" [1/s], "per_period", "periods_fitted", "grew" (bool),
    "saturated" (bool: the plateau was reached before the end), "t_sat" [s] or NaN,
    "plateau" [units of d], "lower_bound" (bool), "D" (per-period maxima), "t_D" [s]}``.
    """
    t = np.asarray(t, float)
    d = np.abs(np.asarray(d, float))
    if t_start is not None:
        m = t >= t_start
        t, d = t[m], d[m]
    T = 1.0 / float(frequency)
    k = np.floor((t - t[0]) / T + 1e-9).astype(int)
    n = int(k.max())  # drop the last, partial period
    if n < 3:
        raise ValueError(f"divergence_exponent: {n} whole drive periods, need at least 3")
    D = np.maximum(np.array([d[k == i].max() for i in range(n)]), 1e-300)
    tD = t[0] + (np.arange(n) + 0.5) * T
    plateau = float(np.median(D[-max(2, n // 4):]))
    if saturation is not None:
        plateau = min(plateau, float(saturation))
    base = D[0] if d0 is None else float(d0)
    grew = plateau > 100.0 * base
    hit = np.nonzero(D >= plateau / 10)[0] if grew else np.array([], int)
    if grew and d0 is not None and hit.size and hit[0] == 0:  # saturated in the first period
        slope = float(np.log(D[0] / base) / T)
        return {"exponent": slope, "per_period": slope * T, "periods_fitted": 0, "grew": True,
                "saturated": True, "t_sat": float(tD[0]), "plateau": plateau,
                "lower_bound": True, "D": D, "t_D": tD}
    last = max(int(hit[0]), 2) if hit.size else n
    slope = float(np.polyfit(tD[:last], np.log(D[:last]), 1)[0])
    return {"exponent": slope, "per_period": slope * T, "periods_fitted": last,
            "grew": bool(grew), "saturated": bool(hit.size and hit[0] < n - 1),
            "t_sat": float(tD[hit[0]]) if hit.size else float("nan"), "plateau": plateau,
            "lower_bound": False, "D": D, "t_D": tD}


# --------------------------------------------------------------------------- classification


@dataclass(frozen=True)
class Classification:
    """Verdict of :func:`classify`.

    Attributes:
      label: ``"periodic"``, ``"quasi-periodic"``, ``"chaotic"``, or ``"undetermined"`` when
        the exponent and the spectrum disagree.
      period: k of a period-k response (in drive periods), else None.
      evidence: the numbers the verdict rests on (see :func:`classify`).
      exponent: largest Lyapunov exponent [1/s] when computed, else None.
      lyapunov: the full :class:`LyapunovResult` when computed.
    """

    label: str
    period: int | None
    evidence: dict
    exponent: float | None = None
    lyapunov: LyapunovResult | None = None


def section_return_distances(section: PoincareSection, scale, max_period=8):
    """``d_k`` = median over j of ``|P_{j+k} - P_j| / scale`` for k = 1..max_period, with
    ``P_j = (x_j, x_{j+1})`` the section's return-map points, ``(max_period,)``.
    ``d_k ≈ 0`` iff the section repeats every k periods (k clusters of points). The return
    map rather than ``(x, x')``: the spline derivative amplifies sampling noise (noise 1e-4 of
    the amplitude at 100 samples per period gives ``d_1 ≈ 2.5e-3`` with ``x'/ω``); the median
    tolerates a few outliers (a rare rattle)."""
    P = section.points("return")
    out = np.full(max_period, np.inf)
    for k in range(1, max_period + 1):
        if len(P) >= 2 * k + 1:  # at least two returns, else "repeats" is an assumption
            out[k - 1] = np.median(np.linalg.norm(P[k:] - P[:-k], axis=1)) / scale
    return out


def section_stretch(section: PoincareSection, scale):
    """Median one-period log-stretch ``ln(|P_{i+1} - P_{j+1}| / |P_i - P_j|)`` of section
    points and their nearest section neighbours ``j`` (return-map coordinates
    ``(x_k, x_{k+1})``). ≈ 0 for a rotation on a closed curve (quasi-periodic), > 0 when the
    section map stretches (chaos). Crude — a one-step Lyapunov estimate — and reported as
    evidence only."""
    from scipy.spatial import cKDTree

    P = section.points("return") / scale
    if len(P) < 10:
        return float("nan")
    base = P[:-1]
    d, j = cKDTree(base).query(base, k=2)
    d, j = d[:, 1], j[:, 1]
    i = np.arange(len(base))
    ok = d > 0
    d1 = np.linalg.norm(P[i + 1] - P[j + 1], axis=1)
    ok &= d1 > 0
    return float(np.median(np.log(d1[ok] / d[ok]))) if np.any(ok) else float("nan")


def classify(t, x, frequency, t_start=None, period_tol=1e-2, max_period=8,
             lyap_threshold=0.02, line_threshold=0.9, n_lines=20, embedding=None,
             lyapunov_kw=None) -> Classification:
    """Periodic (period-k), quasi-periodic or chaotic response of ``x(t)`` under a drive at ``f``.

    1. **Periodic** if the stroboscopic section repeats: the smallest ``k ≤ max_period`` with
       return distance ``d_k < period_tol`` (:func:`section_return_distances`, relative to the
       series' standard deviation) → period-k (k clusters of section points).
    2. Otherwise the largest Lyapunov exponent ``λ`` (:func:`lyapunov_kantz`) and the
       spectrum decide. With ≥ 8 samples per drive period the exponent is that of the series
       itself, embedded with the mutual-information delay and the FNN dimension (or
       ``embedding=(dim, delay)``), Theiler window one drive period; with fewer (a map, one
       sample per period) it is that of the series taken as a map. ``λ/f`` (per drive period)
       ``> lyap_threshold`` means exponential divergence. The spectrum (Hann periodogram of
       the whole record) is a line spectrum if, once the drive's harmonics are masked
       (:func:`harmonic_mask`: they dominate any driven response), its ``n_lines`` strongest
       peaks hold more than ``line_threshold`` of the remaining power (:func:`line_fraction`),
       else broadband.
       - chaotic: positive exponent and broadband spectrum;
       - quasi-periodic: exponent ≈ 0 and line spectrum (two or more incommensurate lines:
         points on a closed curve in the section);
       - undetermined: the two disagree (e.g. a weakly chaotic, wrinkled torus, or noise).

    Args:
      t: sample times [s] ``(N,)``, uniform; x: ``(N,)``; frequency: drive f [Hz].
      t_start: drop everything before this time [s] (transient).
      lyapunov_kw: extra keyword arguments for :func:`lyapunov_kantz`.
    Returns:
      :class:`Classification`; ``evidence`` holds ``return_distances`` (d_1..d_max),
      ``n_section_points``, and when not periodic ``line_fraction``, ``lyapunov_per_period``
      (λ/f), ``dim``, ``delay`` [samples], ``section_stretch``, ``strongest_peak_ratio``
      (frequency of the strongest non-harmonic peak over f: irrational for quasi-periodic).
    """
    t = np.asarray(t, float)
    x = np.asarray(x, float)
    if t_start is not None:
        keep = t >= t_start
        t, x = t[keep], x[keep]
    f = float(frequency)
    scale = float(np.std(x))
    sec = poincare_section(t, x, f)
    ev = {"n_section_points": int(len(sec.t))}
    if scale == 0.0:  # a constant is a fixed point: period 1
        ev["return_distances"] = np.zeros(max_period)
        return Classification("periodic", 1, ev)
    dk = section_return_distances(sec, scale, max_period)
    ev["return_distances"] = dk
    hit = np.nonzero(dk < period_tol)[0]
    if hit.size:
        return Classification("periodic", int(hit[0] + 1), ev)

    dt = (t[-1] - t[0]) / (len(t) - 1)
    spp = 1.0 / (f * dt)  # samples per drive period
    kw = dict(lyapunov_kw or {})
    if spp >= 8:
        if embedding is None:
            delay, _ = mutual_information_delay(x, max_lag=max(4, int(2 * spp)))
            _, dim = false_nearest_neighbours(x, delay, max_dim=8)
        else:
            dim, delay = embedding
        kw.setdefault("theiler", max(int(round(spp)), dim * delay))
        kw.setdefault("min_fit", int(np.ceil(spp)) + 1)  # the fit spans > one drive period
        room = (len(x) - (dim - 1) * delay - 2 * kw["theiler"] - 3) // 2  # a short series
        kw.setdefault("max_steps", max(1, min(max(20, 30 * int(delay), 3 * int(np.ceil(spp))),
                                              room)))
        lyap = lyapunov_kantz(x, dim, delay, dt=dt, **kw)
    else:
        xs = sec.x  # the series as a map: one value per drive period
        if embedding is None:
            _, dim = false_nearest_neighbours(xs, 1, max_dim=6)
            delay = 1
        else:
            dim, delay = embedding
        lyap = lyapunov_kantz(xs, dim, delay, dt=1.0 / f, **kw)
    lam_T = lyap.exponent / f
    spec = power_spectrum(t, x, f, method="periodogram")
    lf = line_fraction(spec.psd, n_lines=n_lines, exclude=harmonic_mask(spec.f, f))
    ev.update(line_fraction=lf, lyapunov_per_period=lam_T, dim=int(dim), delay=int(delay),
              section_stretch=section_stretch(sec, scale),
              strongest_peak_ratio=_strongest_nonharmonic(spec, f))
    chaotic_lyap = lam_T > lyap_threshold
    broadband = lf < line_threshold
    if chaotic_lyap and broadband:
        label = "chaotic"
    elif not chaotic_lyap and not broadband:
        label = "quasi-periodic"
    else:
        label = "undetermined"
    return Classification(label, None, ev, lyap.exponent, lyap)


def _strongest_nonharmonic(spec: Spectrum, f, tol_bins=3):
    """Frequency of the strongest spectral peak that is not a harmonic ``n f`` (within
    ``tol_bins``), over ``f``; NaN if none."""
    df = spec.f[1] - spec.f[0]
    p = spec.psd.copy()
    p[0] = 0.0
    near = np.abs(spec.f / f - np.round(spec.f / f)) * f <= tol_bins * df
    near &= np.round(spec.f / f) >= 1
    p[near] = 0.0
    i = int(np.argmax(p))
    return float(spec.f[i] / f) if p[i] > 0 else float("nan")
