"""Steady-state quantities of a run and the analytic response of the primary system.

Importing it does not import JAX (the FRF fit and its rule, :func:`fit_failure`, serve the file
commands too); :func:`steady_state_summary` imports the physics when it is called.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from jaxdamp.analysis.uncertainty import pm, standard_error
from jaxdamp.config import Config

if TYPE_CHECKING:
    from jaxdamp.physics.model import State


def frf_amplitude(f, M, K, C, U):
    """Steady-state amplitude ``Z`` [m] of a base-excited mass–spring–damper (thesis eq. 2.1.21).

    ``Z = U sqrt((K² + (CΩ)²) / ((K - MΩ²)² + (CΩ)²))`` with ``Ω = 2π f``; ``f`` in Hz (array OK).
    """
    w = 2 * np.pi * np.asarray(f, dtype=float)
    return U * np.sqrt((K**2 + (C * w) ** 2) / ((K - M * w**2) ** 2 + (C * w) ** 2))


def analysis_start(config: Config, duration: float) -> float:
    """Start [s] of the analysis window: the final ``numerics.analysis_window`` of the run, but
    at least one drive period (an amplitude needs a whole period), at most the whole run."""
    span = max(config.numerics.analysis_window * duration, 1.0 / config.frequency)
    return max(0.0, duration - span)


def first_harmonic(t, x, f):
    """Amplitude and phase [rad] of the component of ``x(t)`` at frequency ``f``:
    ``x ≈ a cos(2π f t + phase)`` by least squares on ``cos``, ``sin`` and a constant.
    The phase is relative to the excitation ``cos 2π f t`` (negative: ``x`` lags)."""
    w = 2 * np.pi * f * np.asarray(t)
    A = np.stack([np.cos(w), np.sin(w), np.ones_like(w)], axis=1)
    (c, s, _), *_ = np.linalg.lstsq(A, np.asarray(x), rcond=None)
    return float(np.hypot(c, s)), float(np.arctan2(-s, c))


def grain_force_coefficients(t, z_box, force, f, t_start=None, interval: float = 0.0) -> dict:
    """The grains' force on the box as an added mass and damper, from its phase.

    With the box at ``z = Re(Ẑ e^{iΩt})`` and the grains' vertical force on it
    ``F = Re(F̂ e^{iΩt}) + …`` (first harmonics by :func:`first_harmonic`), a force
    ``F = −m_add z̈ − c_add ż`` has ``F̂ = (m_add Ω² − i Ω c_add) Ẑ``, so

        m_add = Re(F̂/Ẑ) / Ω²,   c_add = −Im(F̂/Ẑ) / Ω,   φ = arg(F̂/Ẑ).

    ``M + m_add`` and ``C + c_add`` are the effective mass and damping of one run at one
    frequency, measured without any FRF fit; ``φ`` is the impact phase (0: the grains push
    the box along its displacement — a mass; −90°: against its velocity — a damper; 180°: a
    negative mass). A bed locked to the box gives ``m_add = m_p``, ``c_add = 0``.

    A recorded force is the mean over the sampling interval ``Δ`` ending at its sample
    (``force_box``, :func:`jaxdamp.physics.energy.record`: impulse / interval): its first
    harmonic is the force's times ``H = (1 − e^{−iΩΔ})/(iΩΔ) = e^{−iΩΔ/2} sin(ΩΔ/2)/(ΩΔ/2)``,
    a lag of half an interval, which ``interval = Δ`` divides out (without it a bed moving
    with the box would show a spurious ``c_add ≈ m_p Ω² Δ/2``: 1 N s/m for the thesis' bed at
    15 Hz sampled every ms).

    Args: t [s], z_box [m], force [N] (positive upwards), f [Hz]; t_start [s]: first sample
    used (the steady state); interval [s]: the interval each force sample is the mean over (0:
    instantaneous values). Returns ``{"m_add" [kg], "c_add" [N s/m], "phase" [rad]}``.

    >>> import numpy as np
    >>> t = np.linspace(0, 2, 4001); w = 2 * np.pi * 10
    >>> z = 1e-3 * np.cos(w * t); F = -0.5 * (-w**2 * z) - 3.0 * (-1e-3 * w * np.sin(w * t))
    >>> r = grain_force_coefficients(t, z, F, 10.0)
    >>> round(r["m_add"], 6), round(r["c_add"], 6)
    (0.5, 3.0)
    """
    t = np.asarray(t, float)
    keep = slice(None) if t_start is None else t >= t_start
    t, z, F = t[keep], np.asarray(z_box, float)[keep], np.asarray(force, float)[keep]
    az, pz = first_harmonic(t, z, f)
    aF, pF = first_harmonic(t, F, f)
    ratio = aF / az * np.exp(1j * (pF - pz))
    Om = 2 * np.pi * f
    if interval > 0:
        x = 0.5 * Om * interval
        ratio = ratio / (np.exp(-1j * x) * np.sin(x) / x)
    return {"m_add": float(ratio.real / Om**2), "c_add": float(-ratio.imag / Om),
            "phase": float(np.angle(ratio))}


#: Residual weightings of the FRF fit: ``relative`` (``Z_model/Z − 1``, every frequency
#: counts alike; the default) and ``absolute`` (``(Z_model − Z)/U``, dominated by the largest
#: amplitudes, as the thesis describes its fit).
RESIDUALS = ("relative", "absolute")


#: Fitted parameters of the FRF fit, and the least number of frequencies that determines them
#: with a residual variance left to estimate their errors (``len(FIT_PARAMETERS) + 1``).
FIT_PARAMETERS = ("M_ef", "C_ef")
FIT_MIN_POINTS = len(FIT_PARAMETERS) + 1
#: Largest relative standard error of a fitted parameter that is still a result: at ``SE/value
#: > 1/2`` the ≈ 95 % interval ``value ± 2 SE`` contains 0, so the data cannot tell the
#: parameter from zero (nor from twice its value) — the number does not say what it seems to.
FIT_MAX_RELATIVE_SE = 0.5
#: Below these a fitted value sits on its lower bound 0 (``M_ef, C_ef ≥ 0`` are constrained): the
#: optimiser stopped against the wall, not at a minimum (e.g. ``C_ef = 5.9e-10`` N s/m).
FIT_AT_BOUND = {"M_ef": 1e-9, "C_ef": 1e-6}
FIT_UNITS = {"M_ef": "kg", "C_ef": "N s/m"}
#: The rule of :func:`fit_failure` in one sentence (printed by ``jaxdamp frf``).
FIT_RULE = (f"a fit is FAILED, not a result, when it has fewer than {FIT_MIN_POINTS} "
            "frequencies, a value or its standard error is not finite, a value sits on its "
            f"bound 0, or a standard error exceeds {100 * FIT_MAX_RELATIVE_SE:g} % of its value")


def fit_frf(f, Z, U, K, M0, C0, weights=None, residuals: str = "relative"):
    """Least-squares fit of the analytic FRF to amplitudes ``Z(f)`` with ``U, K`` fixed.

    Returns ``(M_ef, C_ef, stderr_M, stderr_C)`` [kg, N s/m]; standard errors from the
    Jacobian at the optimum and the residual variance (NaN when they are not determined: fewer
    than :data:`FIT_MIN_POINTS` frequencies leave no residual variance, a rank-deficient
    Jacobian no covariance). ``residuals`` (:data:`RESIDUALS`): ``"relative"``
    (``Z_model/Z - 1``, so that the resonance does not swamp the flanks) or ``"absolute"``
    (``(Z_model - Z)/U``). The FRF depends on ``C²`` only, so ``C`` is constrained ≥ 0 (else
    the fit may return the mirror ``-C``). Whether the fit is a result: :func:`fit_failure`.
    """
    from scipy.optimize import least_squares

    if residuals not in RESIDUALS:
        raise ValueError(f"residuals = {residuals!r}: expected one of {RESIDUALS}")
    f = np.asarray(f, float)
    Z = np.asarray(Z, float)
    wts = np.ones_like(Z) if weights is None else np.asarray(weights, float)

    def resid(x):
        model = frf_amplitude(f, x[0], K, x[1], U)
        if residuals == "relative":
            return wts * (model / Z - 1.0)
        return wts * (model - Z) / U

    sol = least_squares(resid, [M0, C0], x_scale=[M0, max(C0, 1e-3)], method="trf",
                        bounds=([0.0, 0.0], [np.inf, np.inf]))
    return float(sol.x[0]), float(sol.x[1]), *_standard_errors(sol.jac, sol.fun)


def _standard_errors(jac, fun) -> tuple[float, float]:
    """Standard errors ``sqrt(diag((JᵀJ)⁻¹) s²)`` with ``s² = Σ r² / (n − p)``, from the SVD
    ``J = U S Vᵀ`` (``(JᵀJ)⁻¹ = V S⁻² Vᵀ``, whose diagonal is a sum of squares: never a
    negative variance); NaN without degrees of freedom or for a rank-deficient ``J``."""
    n, k = jac.shape
    if n - k < 1 or not (np.all(np.isfinite(jac)) and np.all(np.isfinite(fun))):
        return float("nan"), float("nan")
    _, s, vt = np.linalg.svd(jac, full_matrices=False)
    if s.min() <= s.max() * max(n, k) * np.finfo(float).eps:
        return float("nan"), float("nan")
    s2 = float(np.sum(fun**2)) / (n - k)
    err = np.sqrt(np.sum((vt / s[:, None]) ** 2, axis=0) * s2)
    return float(err[0]), float(err[1])


def fit_frf_replicates(f, Z, U, K, M0, C0, residuals: str = "relative") -> dict:
    """FRF fit with the uncertainty of independent replicates.

    ``Z``: amplitudes ``(F, R)``, one independent FRF per replicate (column). Every replicate
    is fitted on its own (:func:`fit_frf`); the effective mass and damping are the means of
    the ``R`` fits ± their standard error across replicates ``s/√R`` (NaN for ``R = 1``, then
    the fit's own Jacobian error is the only figure). Also the fit of the replicate-mean FRF
    with its Jacobian errors.

    Returns ``{"M_ef", "C_ef", "se_M", "se_C", "M_reps", "C_reps", "M_mean_fit", "C_mean_fit",
    "fit_se_M", "fit_se_C", "residuals", "replicates", "points"}`` (``points``: the number of
    frequencies). Whether it is a result: :func:`fit_failure`.
    """
    Z = np.asarray(Z, float).reshape(len(f), -1)
    R = Z.shape[1]
    reps = np.array([fit_frf(f, Z[:, r], U, K, M0, C0, residuals=residuals)[:2] for r in range(R)])
    Mm, Cm, dM, dC = fit_frf(f, Z.mean(axis=1), U, K, M0, C0, residuals=residuals)
    se = standard_error(reps, axis=0) if R >= 2 else np.full(2, np.nan)
    return {"M_ef": float(reps[:, 0].mean()), "C_ef": float(reps[:, 1].mean()),
            "se_M": float(se[0]), "se_C": float(se[1]),
            "M_reps": reps[:, 0], "C_reps": reps[:, 1],
            "M_mean_fit": Mm, "C_mean_fit": Cm, "fit_se_M": dM, "fit_se_C": dC,
            "residuals": residuals, "replicates": R, "points": len(f)}


def fit_uncertainties(fit: dict) -> dict:
    """The uncertainties of a :func:`fit_frf_replicates` result that :func:`fit_failure` checks,
    ``{parameter: [(what, value, SE), ...]}``: the mean over replicates with its standard error
    across them (``R ≥ 2``), and the fit of the (replicate-mean) FRF with its Jacobian error
    (the only one for ``R = 1``)."""
    R = int(fit.get("replicates", 1))
    out = {}
    for name, rep, mean_fit, jac in (("M_ef", "se_M", "M_mean_fit", "fit_se_M"),
                                     ("C_ef", "se_C", "C_mean_fit", "fit_se_C")):
        rows = [(f"SE over R = {R} replicates", fit[name], fit[rep])] if R >= 2 else []
        if jac in fit:
            rows.append(("fit error" + (" of the mean FRF" if R >= 2 else ""),
                         fit.get(mean_fit, fit[name]), fit[jac]))
        out[name] = rows
    return out


def fit_failure(fit: dict) -> str:
    """Why an FRF fit (:func:`fit_frf_replicates`) is not a result, in words, or ``""`` when it
    is one. The one rule for every FRF fit (either weighting): ``jaxdamp frf`` prints, stores
    (``/fit/ok``, ``/fit/failure``) and draws by it. A fit FAILED when, checked in this order:

    1. it has no degrees of freedom: fewer than :data:`FIT_MIN_POINTS` frequencies for the
       two parameters (the curve then passes through the points and its error is unknown);
    2. a fitted value (the mean, or any replicate's) is not finite;
    3. a fitted value (the mean, or any replicate's) stopped on its bound 0
       (:data:`FIT_AT_BOUND`): the optimiser hit the wall, not a minimum;
    4. an uncertainty (:func:`fit_uncertainties`: the SE across replicates for ``R ≥ 2``, and
       the Jacobian error of the fit) is not finite;
    5. an uncertainty exceeds :data:`FIT_MAX_RELATIVE_SE` (50 %) of its value: the ≈ 95 %
       interval ``± 2 SE`` then reaches 0 — the data do not determine the parameter.

    >>> why = fit_failure({"M_ef": 2.6, "C_ef": 8.1, "fit_se_M": 0.1, "fit_se_C": 6e5,
    ...                    "points": 9})
    >>> why.split(": ")[0], why.split(", ")[0].split(": ")[1]
    ('C_ef = 8.1 ± 6e+05 N s/m (fit error)', 'its standard error is 7.4e+04 times the value')
    """
    n = fit.get("points")
    if n is not None and n < FIT_MIN_POINTS:
        return (f"no degrees of freedom: {n} frequenc{'y' if n == 1 else 'ies'} for "
                f"{len(FIT_PARAMETERS)} parameters, need at least {FIT_MIN_POINTS}")
    reps = {"M_ef": fit.get("M_reps", []), "C_ef": fit.get("C_reps", [])}
    for key in FIT_PARAMETERS:
        if not np.isfinite(fit[key]):
            return f"{key} = {fit[key]} is not finite"
        v = np.append(np.atleast_1d(np.asarray(reps[key], float)), fit[key])
        if not np.all(np.isfinite(v)):
            return f"a replicate's {key} is not finite"
        if np.any(v < FIT_AT_BOUND[key]):
            return (f"{key} stopped on its bound 0 ({float(v.min()):.2g}): the fit did not "
                    "converge")
    rows = [(key, *row) for key, rr in fit_uncertainties(fit).items() for row in rr]
    for key, what, value, se in rows:
        if not np.isfinite(se):
            return f"the uncertainty of {key} ({what}) is not finite ({se})"
    for key, what, value, se in rows:
        if se > FIT_MAX_RELATIVE_SE * abs(value):
            ratio = se / abs(value)
            size = f"{100 * ratio:.0f} % of" if ratio < 10 else f"{ratio:.2g} times"
            return (f"{key} = {pm(value, se, 4, unit=FIT_UNITS[key])} ({what}): its standard "
                    f"error is {size} the value, above the limit of "
                    f"{100 * FIT_MAX_RELATIVE_SE:g} % — not determined by the data")
    return ""


def replicate_mean(values):
    """Mean over the last axis (the replicates) of ``values`` and its standard error across
    them ``s/√R``; the error is ``None`` for ``R = 1``."""
    values = np.asarray(values, float)
    R = values.shape[-1]
    se = standard_error(values) if R >= 2 else None
    return values.mean(axis=-1), se


def parabolic_extremum(x, y, kind: str = "max") -> tuple[float, float, int]:
    """The extremum of sampled ``y(x)`` refined between samples.

    The parabola through the best sample ``k`` (largest for ``kind = "max"``, smallest for
    ``"min"``) and its two neighbours in ``x`` has its vertex at ``x*``; when that vertex is an
    extremum of the right kind and lies between the neighbours, ``(x*, y(x*), k)`` is returned,
    otherwise (best sample at either end of the range, or a parabola of the wrong curvature)
    the sample itself ``(x_k, y_k, k)``. ``k`` indexes the arrays as given (``x`` need not be
    sorted).

    >>> import numpy as np
    >>> x = np.array([0.0, 1.0, 2.0, 3.0])
    >>> round(parabolic_extremum(x, -(x - 1.3) ** 2)[0], 6)
    1.3
    """
    if kind not in ("max", "min"):
        raise ValueError(f"kind = {kind!r}: expected 'max' or 'min'")
    x = np.asarray(x, float)
    y = np.asarray(y, float)
    order = np.argsort(x)
    xs, ys = x[order], (y[order] if kind == "max" else -y[order])
    k = int(np.nanargmax(ys))
    if 0 < k < len(xs) - 1 and np.all(np.isfinite(ys[k - 1:k + 2])):
        c = np.polyfit(xs[k - 1:k + 2], ys[k - 1:k + 2], 2)
        if c[0] < 0:
            xv = -c[1] / (2 * c[0])
            if xs[k - 1] <= xv <= xs[k + 1]:
                yv = float(np.polyval(c, xv))
                return float(xv), yv if kind == "max" else -yv, int(order[k])
    return float(xs[k]), float(y[order][k]), int(order[k])


def resonance(f, Z):
    """Resonance frequency [Hz] and peak amplitude of a sampled FRF ``Z(f)`` (``(F,)`` each):
    :func:`parabolic_extremum` of ``log Z`` versus ``f`` (the largest sample at either end of
    the range)."""
    fp, logz, _ = parabolic_extremum(f, np.log(np.asarray(Z, float)), "max")
    return fp, float(np.exp(logz))


def resonances(f, Z):
    """:func:`resonance` of every sampled FRF in ``Z`` ``(F, ...)`` (frequency first; heights,
    replicates, … after it): the resonance frequencies [Hz] and the peak amplitudes, each an
    array of shape ``Z.shape[1:]`` — per column, the vertex of the parabola in ``log Z``
    through the largest sample and its two neighbours.

    >>> f = np.array([10.0, 12.0, 14.0, 16.0])
    >>> fp, Zp = resonances(f, np.exp(-(f[:, None] - [12.5, 13.0]) ** 2))  # log Z: parabolas
    >>> np.round(fp, 6).tolist(), np.round(Zp, 6).tolist()
    ([12.5, 13.0], [1.0, 1.0])
    """
    Z = np.asarray(Z, float)
    cols = Z.reshape(len(Z), -1)
    peaks = np.array([resonance(f, cols[:, k]) for k in range(cols.shape[1])], float)
    return peaks[:, 0].reshape(Z.shape[1:]), peaks[:, 1].reshape(Z.shape[1:])


def fit_frf_scan(f, Z, primary, residuals: str = "relative") -> list[dict]:
    """:func:`fit_frf_replicates` of every column of a scan's amplitudes ``Z`` ``(F, L, R)``
    (frequency × a scanned parameter such as the box height × replicate): per ``j`` the
    replicates' FRFs ``Z[:, j]`` fitted with the ``primary``'s ``U`` and ``K`` fixed, started
    at ``M0 = M`` and ``C0 = max(C, 1)`` N s/m (off the bound 0 for an undamped primary).
    Returns the ``L`` fits.

    Example: amplitudes of the model itself fit back to its parameters::

        Z = frf_amplitude(f, 2.6, p.K, 12.0, p.U)[:, None, None] * np.ones((1, 1, 2))
        fit_frf_scan(f, Z, p)[0]["M_ef"]  # 2.6
    """
    Z = np.asarray(Z, float)
    return [fit_frf_replicates(f, Z[:, j], primary.U, primary.K, M0=primary.M,
                               C0=max(primary.C, 1.0), residuals=residuals)
            for j in range(Z.shape[1])]


def secondary_maxima(Z, se, k: float = 2.0) -> dict:
    """Local maxima of a sampled curve ``Z`` ``(F,)`` that stand out of its uncertainty.

    A local maximum ``i`` has prominence ``p_i = Z_i − Z_b``, where ``Z_b`` is the higher of
    the two lowest points between ``i`` and the nearest higher sample on either side (or the
    end of the range) — the usual topographic prominence (:func:`scipy.signal.peak_prominences`).
    It is *significant* when ``p_i > k sqrt(se_i² + se_b²)``: its drop to the base exceeds
    ``k`` combined standard errors. The global maximum counts as the main peak; every other
    significant maximum is a *secondary* one. ``se`` ``(F,)`` or a scalar (0 for an exact
    curve: then every strict local maximum counts).

    Returns ``{"peaks": indices of significant maxima, "prominence": their p_i,
    "secondary": count of significant maxima other than the global one,
    "roughness": total variation of Z over (2 max Z − Z_first − Z_last)}`` — the roughness is
    1 for a curve that rises to one peak and falls, larger when it wiggles.

    >>> r = secondary_maxima(np.array([1.0, 3.0, 2.0, 2.5, 1.0]), 0.1)
    >>> [int(i) for i in r["peaks"]], r["secondary"], round(r["roughness"], 3)
    ([1, 3], 1, 1.25)
    """
    from scipy.signal import find_peaks, peak_prominences

    Z = np.asarray(Z, float)
    se = np.broadcast_to(np.asarray(se, float), Z.shape)
    idx, _ = find_peaks(Z)
    if np.argmax(Z) in (0, len(Z) - 1):  # a maximum at an end is the main peak too
        idx = np.sort(np.append(idx, np.argmax(Z)))
    keep, prom = [], []
    for i in idx:
        if i in (0, len(Z) - 1):
            keep.append(i), prom.append(float(Z[i] - Z.min()))
            continue
        p, lb, rb = (x[0] for x in peak_prominences(Z, [i]))
        b = lb if Z[lb] >= Z[rb] else rb
        if p > k * np.hypot(se[i], se[b]):
            keep.append(i), prom.append(float(p))
    span = 2 * Z.max() - Z[0] - Z[-1]
    rough = float(np.abs(np.diff(Z)).sum() / span) if span > 0 else float("nan")
    top = int(np.argmax(Z))
    return {"peaks": np.asarray(keep, int), "prominence": np.asarray(prom),
            "secondary": int(sum(1 for i in keep if i != top)), "roughness": rough}


def crossings(x, y, level):
    """Every ``x`` where the piecewise-linear ``y(x)`` crosses ``level`` (``x`` sorted).

    Used for the box height where the effective mass crosses the primary mass ``M`` (the
    thesis' proposed estimate of the optimal gap)."""
    x = np.asarray(x, float)
    d = np.asarray(y, float) - level
    out = []
    for i in range(len(x) - 1):
        if d[i] == 0:
            out.append(float(x[i]))
        elif d[i] * d[i + 1] < 0:
            out.append(float(x[i] - d[i] * (x[i + 1] - x[i]) / (d[i + 1] - d[i])))
    if len(x) and d[-1] == 0:
        out.append(float(x[-1]))
    return out


def optimal_gap(Lz, C_ef, Z_peak, M_ef=None, M=None):
    """The optimum of an ``Lz`` scan by the criteria of the thesis (ch. 3).

    Args:
      Lz: box heights [m] ``(L,)``; C_ef: fitted effective damping [N s/m] ``(L,)``;
      Z_peak: resonant amplitude [m] ``(L,)``; M_ef, M: effective masses [kg] ``(L,)`` and the
      primary mass, for the crossing criterion.
    Returns a dict: ``max_C_ef`` (the ``Lz`` of the largest ``C_ef``), ``min_peak`` (of the
    smallest resonant amplitude), ``M_ef_crosses_M`` (list of ``Lz`` where ``M_ef = M``).
    """
    Lz = np.asarray(Lz, float)
    order = np.argsort(Lz)
    out = {"max_C_ef": float(Lz[int(np.nanargmax(C_ef))]),
           "min_peak": float(Lz[int(np.nanargmin(Z_peak))])}
    if M_ef is not None and M is not None:
        out["M_ef_crosses_M"] = crossings(Lz[order], np.asarray(M_ef, float)[order], M)
    return out


def _window(records: dict, t_start: float):
    t = records["t"]
    i0 = int(np.searchsorted(t, t_start - 1e-12))
    return min(i0, len(t) - 1)


def steady_state_summary(config: Config, records: dict, final: State, t_window: float,
                         duration: float) -> tuple[dict, dict]:
    """Scalars over the analysis window ``[t_window, duration]`` and their units.

    * ``amplitude``: half the peak-to-peak of the box position ``z`` over the window, from
      every step (not only the samples) [m].
    * ``granular_loss_per_cycle`` (and per channel): energy dissipated by the grains per drive
      period ``1/f`` over the window [J].
    * ``input_per_cycle``: work input per period [J].
    * ``mean_vz_bed``: mean vertical velocity of the bed's centre of mass [m/s] (≈ 0 in a
      steady state).
    * ``balance_error``: the largest |energy-balance residual| over the run divided by the
      final ``|input| + losses`` [-].
    * a damper of ``k > 1`` cells (``Config.cells``), for every cell ``c``:
      ``mean_vz_bed_cell{c}``, the mean vertical velocity of its bed's centre of mass [m/s],
      and ``mean_e_kinetic_cell{c}``, the mean translational kinetic energy of its grains [J]
      (from the records ``vz_cm_cell``, ``e_kinetic_cell``), and
      ``granular_loss_per_cycle_cell{c}``, the energy its grains dissipate per period [J]
      (``loss_cell``; the cells' sum is ``granular_loss_per_cycle``); the amplitude, the work
      and the other losses are the whole damper's.
    """
    from jaxdamp.physics.energy import granular_loss
    from jaxdamp.physics.model import CH, CHANNELS, LOSSES

    summary: dict = {}
    units: dict = {}
    if not records:
        return summary, units
    i0 = _window(records, t_window)
    t = records["t"]
    work = records["work"]
    span = t[-1] - t[i0]
    cycles = span * config.frequency if span > 0 else np.nan
    summary["amplitude"] = float(0.5 * (final.z_max - final.z_min))
    units["amplitude"] = "m"
    if config.system == "primary" and config.primary.U > 0:
        summary["amplitude_ratio"] = summary["amplitude"] / config.primary.U
        units["amplitude_ratio"] = "1"
    summary["granular_loss_per_cycle"] = float(
        (granular_loss(work[-1]) - granular_loss(work[i0])) / cycles
    )
    units["granular_loss_per_cycle"] = "J"
    for name in CHANNELS:
        key = f"{name}_per_cycle"
        summary[key] = float((work[-1, CH[name]] - work[i0, CH[name]]) / cycles)
        units[key] = "J"
    amp1, phase = first_harmonic(t[i0:], records["z_box"][i0:], config.frequency)
    summary["phase"] = phase
    units["phase"] = "rad"
    summary["mean_vz_bed"] = float(np.mean(records["vz_cm"][i0:]))
    units["mean_vz_bed"] = "m/s"
    if getattr(config, "cells", 1) > 1 and "vz_cm_cell" in records:
        for c in range(config.cells):
            summary[f"mean_vz_bed_cell{c}"] = float(np.mean(records["vz_cm_cell"][i0:, c]))
            units[f"mean_vz_bed_cell{c}"] = "m/s"
            summary[f"mean_e_kinetic_cell{c}"] = float(
                np.mean(records["e_kinetic_cell"][i0:, c]))
            units[f"mean_e_kinetic_cell{c}"] = "J"
            if "loss_cell" in records:
                loss = records["loss_cell"][:, c]
                summary[f"granular_loss_per_cycle_cell{c}"] = float((loss[-1] - loss[i0])
                                                                    / cycles)
                units[f"granular_loss_per_cycle_cell{c}"] = "J"
    scale = abs(work[-1, CH["input"]]) + work[-1, LOSSES].sum()
    resid = np.max(np.abs(records["balance_residual"]))
    summary["balance_error"] = float(resid / scale) if scale > 0 else float(resid)
    units["balance_error"] = "1"
    summary["window_start"] = float(t[i0])
    summary["window_cycles"] = float(cycles)
    units["window_start"] = "s"
    units["window_cycles"] = "1"
    return summary, units
