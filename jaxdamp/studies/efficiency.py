"""Dissipation efficiency of a driven box (S2; docs/physics.md §4; Varela-Rosales et al. 2023,
eqs. 3–5).

Per drive period ``T = 1/f`` (energies in J per period, not the paper's ``1/T`` powers):

* ``E_pp``, ``E_pw``: energy dissipated in grain–grain and grain–wall contacts (collisional
  and, if any, frictional), from the cumulative work channels of every run;
* ``E_max = 4 m A_d² ω²``: the most a granulate of mass ``m`` could dissipate in one period
  (Sack et al., PRL 111, 018001, 2013, read literally: every grain hits floor and lid once per
  period each at the walls' largest relative speed ``2 A_d ω`` and loses all of it,
  ``2 × ½ m (2 A_d ω)²``); the paper does not restate the formula, so this is our reading;
* ``E_d = (E_pp + E_pw) / E_max``;
* per period, the mean height of each species' centre of mass above the floor, ``h_s``, and
  for two species the segregation index :func:`segregation_index` (large over small: ``> 0``
  when the large grains ride higher, the Brazil-nut sense).

The average ``⟨E_d⟩`` over the analysed periods (after a transient) is given two ways: the
paper's "linear fit to E_d(t)" (``E_d(t)`` with the one-period integrals starting at every
sample ``t`` whose period lies in the window, a least-squares line through them read at the
window's middle; its slope is reported as the trend per period) and the plain mean of the
per-period values, with their standard deviation and the standard error of the mean.
Phase-resolved diagnostics average over the analysed periods in
``samples_per_period`` phase bins: grains touching floor or lid (per species), the vertical
force of the grains on floor + lid, and the centre of mass ``z``, ``v_z`` per species.

:func:`protocol` sets a run's timing so that periods, samples and chunks line up exactly
(``dt`` divides ``T / samples_per_period``); :func:`measure` runs an amplitude sweep through
:func:`jaxdamp.studies.sweep.sweep` and writes the analysis into the sweep file's ``/efficiency``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import numpy as np

from jaxdamp.config import Config, ConfigError
from jaxdamp.physics.model import CH, config_dt, grain_radii

#: Units of the per-point scalars of :func:`analyse`.
SUMMARY_UNITS = {
    "mass": "kg", "E_max": "J", "E_pp": "J", "E_pw": "J", "E_input": "J", "E_d_mean": "1",
    "E_d_std": "1", "E_d_sem": "1", "E_d_fit": "1", "E_d_trend": "1/period",
    "E_d_mean_per_mass": "1/kg", "E_d_fit_per_mass": "1/kg", "E_d_std_per_mass": "1/kg",
    "wall_fraction": "1", "contacts_mean": "1", "balance_error": "1", "periods": "1",
    "segregation": "1",
}
#: Units of the per-period arrays of :func:`analyse`.
PER_PERIOD_UNITS = {"E_pp": "J", "E_pw": "J", "E_input": "J", "E_d": "1", "t_end": "s",
                    "h_cm_species": "m", "segregation": "1"}
#: Units of the phase-resolved arrays of :func:`analyse`.
PHASE_UNITS = {
    "phase": "1", "contacts": "1", "contacts_species": "1", "force_floor_lid": "N",
    "z_cm_species": "m", "vz_cm_species": "m/s", "z_box": "m", "v_box": "m/s",
}


def e_max(mass: float, amplitude: float, frequency: float) -> float:
    """``4 m A_d² ω²`` [J]: the largest energy a granulate of ``mass`` [kg] can dissipate in
    one period of a box driven at ``amplitude`` [m] and ``frequency`` [Hz] (module doc)."""
    return 4.0 * mass * amplitude**2 * (2.0 * math.pi * frequency) ** 2


def segregation_index(h_cm_species) -> np.ndarray:
    """Segregation index of a binary bed from the heights ``h_cm_species`` ``(..., 2)`` [m] of
    its two species' centres of mass above the floor (large first):

    .. math:: S = 2\\,\\frac{h_\\text{large} - h_\\text{small}}{h_\\text{large} + h_\\text{small}}

    ``S = 0`` when both species sit at the same mean height, ``S > 0`` when the large grains
    ride higher (Brazil-nut sense), ``S < 0`` when they sink; ``|S| ≤ 2``. NaN for any other
    number of species. In a well-mixed bed of unequal radii ``S`` is not exactly 0: a small
    grain's centre can come ``R_large − R_small`` closer to the floor.

    >>> float(segregation_index(np.array([0.03, 0.01])))
    1.0
    """
    h = np.asarray(h_cm_species, dtype=float)
    if h.shape[-1] != 2:
        return np.full(h.shape[:-1], np.nan)
    return 2.0 * (h[..., 0] - h[..., 1]) / (h[..., 0] + h[..., 1])


class Comparison(NamedTuple):
    """One quantity of two groups of beds compared (:func:`compare_beds`)."""

    ratio: float
    ratio_se: float
    diff: float
    half: float
    verdict: str


def compare_beds(x, y) -> Comparison:
    """A quantity of two families compared across their independent beds ``x`` and ``y``
    (NaN: a bed left out, e.g. not stationary; e.g. a mixture's ⟨E_d⟩/m against the
    reference's at one amplitude): the ratio of the means with its delta-method SE,

    .. math:: r = \\bar x / \\bar y, \\qquad
              \\mathrm{SE}_r = |r| \\sqrt{(\\mathrm{SE}_x/\\bar x)^2 + (\\mathrm{SE}_y/\\bar y)^2}

    (means and SEs across beds, :func:`jaxdamp.analysis.stats.across`), the difference
    ``x̄ − ȳ`` with the half-width of its Welch 95 % interval
    (:func:`jaxdamp.analysis.stats.welch`), and the ``verdict``: ``"above"``/``"below"``
    when that interval excludes 0, ``"not significant"`` when it includes it,
    ``"undetermined"`` with fewer than two beds on a side.

    >>> c = compare_beds([2.0, 2.2, 2.1], [1.0, 1.1, 1.2])
    >>> round(c.ratio, 6), round(c.diff, 6), c.verdict
    (1.909091, 1.0, 'above')
    """
    from jaxdamp.analysis import stats

    ex, ey = stats.across(x), stats.across(y)
    ratio = ex.mean / ey.mean
    rse = abs(ratio) * np.hypot(ex.se / ex.mean, ey.se / ey.mean)
    d, h = stats.welch(x, y)
    if not np.isfinite(h):
        verdict = "undetermined"
    else:
        verdict = "above" if d - h > 0 else "below" if d + h < 0 else "not significant"
    return Comparison(ratio, rse, d, h, verdict)


def optimal_amplitudes(amplitudes, values) -> np.ndarray:
    """Each bed's optimal drive amplitude ``A_opt`` [m], the amplitude of its largest
    efficiency: ``values`` ``(P, R)`` (e.g. :attr:`EfficiencyResult.steady`
    ``["E_d_per_mass"]["values"]``) at ``amplitudes`` ``(P,)``, per bed the vertex of the
    parabola through its largest value and the two neighbours,

    .. math:: A_\\text{opt} = A_k + \\frac{h}{2}\\,\\frac{y_{k-1} - y_{k+1}}
              {y_{k-1} - 2 y_k + y_{k+1}}

    (``h`` the spacing; :func:`jaxdamp.analysis.stats.replicate_extrema`; the sample itself
    when it lies at either end of the range). NaN for a bed with a NaN at any amplitude (not
    stationary there) and for every bed when there are fewer than 3 amplitudes.

    >>> A = np.array([0.02, 0.025, 0.03, 0.035])
    >>> np.round(optimal_amplitudes(A, -(A[:, None] - [0.026, 0.028]) ** 2), 6).tolist()
    [0.026, 0.028]
    """
    from jaxdamp.analysis.stats import replicate_extrema

    y = np.asarray(values, float)
    out = np.full(y.shape[1], np.nan)
    ok = np.isfinite(y).all(axis=0)
    if len(amplitudes) >= 3 and ok.any():
        out[ok] = replicate_extrema(amplitudes, y[:, ok]).x
    return out


def protocol(config: Config, periods: int = 50, transient: int = 10,
             samples_per_period: int = 100, amplitudes=None) -> Config:
    """``config`` with timing for an efficiency measurement (system ``driven`` only).

    ``transient + periods`` drive periods are simulated, the last ``periods`` analysed;
    ``samples_per_period`` samples per period (a multiple of 4); chunks of a quarter period (so
    chunk ends fall on the drive's turning points and largest speeds, for snapshots). ``dt`` is
    the largest step ``≤ t_c / dt_per_collision`` (at the largest of ``amplitudes``, default
    the config's) that divides the sampling interval exactly.
    """
    if config.system != "driven":
        raise ConfigError(f"efficiency needs a driven box (system = 'driven', S2); "
                          f"{config.name!r} has system = {config.system!r}")
    for name, value, low in (("periods", periods, 1), ("transient", transient, 0),
                             ("samples_per_period", samples_per_period, 4)):
        if not isinstance(value, int) or value < low:
            raise ConfigError(f"{name} = {value!r}: must be an integer ≥ {low}")
    if samples_per_period % 4:
        raise ConfigError(f"samples_per_period = {samples_per_period}: must be a multiple of 4 "
                          "(chunks are quarter periods)")
    amps = [config.drive.amplitude] if amplitudes is None else [float(a) for a in amplitudes]
    if not amps or min(amps) <= 0:
        raise ConfigError(f"amplitudes {amps}: every drive amplitude must be > 0 (E_max ∝ A_d²)")
    T = 1.0 / config.frequency
    loudest = config.replace(drive=dataclasses.replace(config.drive, amplitude=max(amps)))
    dt_max = config_dt(loudest, grain_radii(config))
    if config.numerics.dt is not None:
        dt_max = min(dt_max, config.numerics.dt)
    per_sample = int(math.ceil(T / samples_per_period / dt_max * (1 - 1e-12)))
    total = transient + periods
    num = dataclasses.replace(
        config.numerics, dt=T / samples_per_period / per_sample, record_dt=T / samples_per_period,
        chunk=T / 4.0, duration=total * T, analysis_window=periods / total)
    return config.replace(numerics=num)


def _sample_index(t, frequency, spp):
    """Sample number ``s`` (sample ``s`` is at ``s T / spp``) of each record time."""
    s = np.rint(np.asarray(t) * frequency * spp).astype(np.int64)
    if np.any(np.abs(np.asarray(t) * frequency * spp - s) > 1e-6):
        raise ConfigError("records are not on the period grid; run with efficiency.protocol()")
    return s


def analyse(config: Config, records: dict, periods: int, samples_per_period: int = 100) -> dict:
    """Efficiency of one run from its records (arrays over samples, see
    :data:`jaxdamp.physics.energy.RECORD_UNITS`); the last ``periods`` whole periods are analysed.

    Returns ``{"summary": {name: float}, "per_period": {name: (n,[S])},
    "phase": {name: (spp,[S])}}`` where ``per_period`` covers every simulated period
    (:data:`PER_PERIOD_UNITS`: ``E_pp``,
    ``E_pw``, ``E_input``, ``E_d``, ``t_end``, the species' mean heights above the floor
    ``h_cm_species`` ``(n, S)`` and the ``segregation`` index) and ``phase`` the analysed ones
    (``phase`` bin starts in units of ``T``); ``summary["segregation"]`` is the index's mean over
    the analysed periods. See the module doc for the definitions.
    """
    spp = samples_per_period
    f = config.frequency
    s = _sample_index(records["t"], f, spp)
    work = np.asarray(records["work"], dtype=float)
    pp = work[:, CH["pp_normal"]] + work[:, CH["pp_friction"]]
    pw = work[:, CH["pw_normal"]] + work[:, CH["pw_friction"]]
    inp = work[:, CH["input"]]
    ends = np.flatnonzero(s % spp == 0)
    # the run starts at t = 0 with zero work: prepend it as the first boundary
    cum = lambda x: np.concatenate([[0.0], x[ends]])  # noqa: E731
    if s[0] != 1 or len(ends) < 1:
        raise ConfigError("records must start at the first sample of a run from t = 0")
    E_pp, E_pw, E_in = (np.diff(cum(x)) for x in (pp, pw, inp))
    n_total = len(E_pp)
    if periods > n_total:
        raise ConfigError(f"periods = {periods}: the run covers only {n_total} whole periods")
    from jaxdamp.cases.mixtures import granulate_mass

    mass = granulate_mass(config)
    emax = e_max(mass, config.drive.amplitude, f)
    E_d = (E_pp + E_pw) / emax
    sel = slice(n_total - periods, n_total)
    ed = E_d[sel]

    # the paper's linear fit to E_d(t), its eq. 3 with the one-period integrals of eqs. 4-5
    # starting at any time t: E_d(t) at every sample whose period lies in the window, a
    # least-squares line through them, read at the window's middle
    loss = np.concatenate([[0.0], pp + pw])  # index = sample number (0: t = 0)
    s_lo, s_hi = (n_total - periods) * spp, n_total * spp - spp
    starts = np.arange(s_lo, s_hi + 1)
    ed_t = (loss[starts + spp] - loss[starts]) / emax
    if len(starts) > 1:
        slope_t, icpt = np.polyfit(starts / (f * spp), ed_t, 1)
        fit = icpt + slope_t * 0.5 * (starts[0] + starts[-1]) / (f * spp)
    else:
        slope_t, fit = 0.0, ed_t[0]
    trend = slope_t / f  # change of E_d per period

    contacts = np.asarray(records["n_floor"]) + np.asarray(records["n_lid"])
    resid = np.asarray(records["balance_residual"], dtype=float)
    scale = max(float(np.max(np.abs(inp))), float(np.max(np.abs(pp + pw))), 1e-300)
    in_window = (s > (n_total - periods) * spp) & (s <= n_total * spp)
    summary = dict(
        mass=mass, E_max=emax, E_pp=float(E_pp[sel].mean()), E_pw=float(E_pw[sel].mean()),
        E_input=float(E_in[sel].mean()),
        E_d_mean=float(ed.mean()), E_d_std=float(ed.std(ddof=1)) if periods > 1 else 0.0,
        E_d_fit=float(fit), E_d_trend=float(trend),
        wall_fraction=float(E_pw[sel].sum() / max((E_pp[sel] + E_pw[sel]).sum(), 1e-300)),
        contacts_mean=float(contacts[in_window].mean()),
        balance_error=float(np.max(np.abs(resid)) / scale), periods=float(periods),
    )
    summary["E_d_sem"] = summary["E_d_std"] / math.sqrt(periods)
    for k in ("mean", "fit", "std"):
        summary[f"E_d_{k}_per_mass"] = summary[f"E_d_{k}"] / mass

    # phase-resolved averages over the analysed periods (bin 0 = phase 0, the box at its top)
    bins = s[in_window] % spp

    def fold(x):
        x = np.asarray(x, dtype=float)[in_window]
        out = np.zeros((spp,) + x.shape[1:])
        np.add.at(out, bins, x)
        return out / np.bincount(bins, minlength=spp).reshape((spp,) + (1,) * (x.ndim - 1))

    phase = dict(
        phase=np.arange(spp) / spp,
        contacts=fold(contacts),
        contacts_species=fold(np.asarray(records["n_floor_species"])
                              + np.asarray(records["n_lid_species"])),
        force_floor_lid=fold(records["force_floor_lid"]),
        z_cm_species=fold(records["z_cm_species"]),
        vz_cm_species=fold(records["vz_cm_species"]),
        z_box=fold(records["z_box"]),
        v_box=fold(records["v_box"]),
    )
    # per-period mean height of each species above the floor (samples 1..spp of each period)
    h = (np.asarray(records["z_cm_species"], dtype=float)
         - np.asarray(records["z_box"], dtype=float)[:, None])
    period_of = (s - 1) // spp
    whole = period_of < n_total
    h_pp = np.zeros((n_total, h.shape[1]))
    np.add.at(h_pp, period_of[whole], h[whole])
    h_pp /= np.bincount(period_of[whole], minlength=n_total)[:, None]
    seg = segregation_index(h_pp)
    summary["segregation"] = float(seg[sel].mean())
    per_period = dict(E_pp=E_pp, E_pw=E_pw, E_input=E_in, E_d=E_d,
                      t_end=(np.arange(n_total) + 1) / f, h_cm_species=h_pp, segregation=seg)
    return dict(summary=summary, per_period=per_period, phase=phase)


@dataclasses.dataclass
class EfficiencyResult:
    """An amplitude sweep's efficiency: ``amplitudes`` [m] ``(P,)``; ``summary`` ``{name: (P,)}``
    (:data:`SUMMARY_UNITS`); ``per_period`` ``{name: (P, n)}``; ``phase`` ``{name: (P, spp, ...)}``
    (:data:`PHASE_UNITS`); ``snapshots`` from the sweep (the last period's quarter points) or
    ``None``; ``config`` the base configuration (with :func:`protocol` timing);
    ``wall_time`` [s] of the sweep; ``path`` its file.

    With ``replicates = R`` independent beds per amplitude, ``summary``, ``per_period`` and
    ``phase`` are means over the replicates, ``replicate_summary`` ``{name: (P, R)}`` and
    ``replicate_per_period`` ``{name: (P, R, n, ...)}`` and ``replicate_phase``
    ``{name: (P, R, spp, ...)}`` hold each replicate's values (so any phase feature, a peak
    force or a largest speed, gets a spread across beds), and ``steady`` the estimates of
    ``E_d`` and ``E_d_per_mass`` over
    replicates from each replicate's detected steady state (MSER on its per-period ``E_d``;
    :func:`jaxdamp.analysis.stats.to_arrays` layout: ``mean``, ``se``, ``ci95``, ``n`` ``(P,)``,
    ``values``, ``batch_se``, ``start``, ``stationary`` ``(P, R)``)."""

    amplitudes: np.ndarray
    summary: dict
    per_period: dict
    phase: dict
    snapshots: dict | None
    config: Config
    wall_time: float
    path: str | None
    replicates: int = 1
    replicate_summary: dict | None = None
    steady: dict | None = None
    replicate_per_period: dict | None = None
    replicate_phase: dict | None = None


def measure(config: Config, amplitudes, periods: int = 50, transient: int = 10,
            samples_per_period: int = 100, out: str | None = None, progress: bool = True,
            echo=print, replicates: int = 1) -> EfficiencyResult:
    """Run ``config`` at every drive amplitude [m] as one batch and analyse its efficiency.

    With ``out`` the sweep file is reused or resumed when it already holds this sweep
    (:func:`jaxdamp.studies.sweep.reuse_or_run`) and the analysis is written to its ``/efficiency``
    group (units in attributes, the ``E_max`` formula in ``/efficiency`` attrs).
    ``replicates``: independent beds per amplitude, in the same batch (:class:`EfficiencyResult`).
    """
    from jaxdamp.analysis import stats
    from jaxdamp.studies import sweep as sw

    amplitudes = np.asarray([float(a) for a in amplitudes])
    cfg = protocol(config, periods, transient, samples_per_period, amplitudes)
    axes = {"drive.amplitude": list(amplitudes)}
    R = int(replicates)
    kw = dict(progress=progress, echo=echo, snapshots=4, replicates=R)
    res = (sw.reuse_or_run(cfg, axes, out, **kw) if out else sw.sweep(cfg, axes, **kw))
    per = [[analyse(c, {k: v[res.point(i, r)] for k, v in res.records.items()}, periods,
                    samples_per_period) for r in range(R)]
           for i, c in enumerate(res.configs)]

    def stack(part, reduce=True):
        out = {k: np.stack([np.stack([p[part][k] for p in reps]) for reps in per])
               for k in per[0][0][part]}  # (P, R, ...)
        return {k: v.mean(axis=1) for k, v in out.items()} if reduce else out

    steady = []
    for reps in per:
        series = [{"t_start": p["per_period"]["t_end"] - 1.0 / cfg.frequency,
                   "E_d": p["per_period"]["E_d"],
                   "E_d_per_mass": p["per_period"]["E_d"] / p["summary"]["mass"]} for p in reps]
        steady.append(stats.steady(series, on=("E_d",)))
    result = EfficiencyResult(amplitudes=amplitudes, summary=stack("summary"),
                              per_period=stack("per_period"), phase=stack("phase"),
                              snapshots=res.snapshots, config=cfg,
                              wall_time=float(res.summary["wall_time"]), path=out,
                              replicates=R, replicate_summary=stack("summary", reduce=False),
                              replicate_per_period=stack("per_period", reduce=False),
                              replicate_phase=stack("phase", reduce=False),
                              steady=stats.to_arrays(steady, (len(amplitudes),)))
    if out:
        from jaxdamp.io import efficiency as efficiency_file

        efficiency_file.write(out, result, transient, samples_per_period, SUMMARY_UNITS,
                              PER_PERIOD_UNITS, PHASE_UNITS)
    return result


def read(path: str) -> EfficiencyResult:
    """Load an :class:`EfficiencyResult` written by :func:`measure` (``/efficiency``)."""
    from jaxdamp.config import from_json
    from jaxdamp.io import efficiency as efficiency_file

    d = efficiency_file.read(path)
    return EfficiencyResult(config=from_json(d.pop("config_json")), **d)
