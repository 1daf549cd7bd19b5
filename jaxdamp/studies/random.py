"""Random-excitation tests of the primary (S1): band-limited random base motion at several
levels, ``R`` independent realisations each (independently poured beds, and — unless
``random.seed`` fixes it — each its own excitation phases), run as one batch; per level the
H1 FRF ``z/u`` with coherence, the response spectra and RMS (:mod:`jaxdamp.analysis.spectra`).

The damper is nonlinear, so an FRF belongs to its level: each level is reported with the
RMS base acceleration (from the spectrum), the RMS of the primary's displacement relative to
the base and its absolute amplitude, so that it can be set beside a stepped-sine FRF at a
matching amplitude.

Example::

    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies import random as rnd
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {"primary.U": 0.0, "random.psd": [[5, 0.5], [30, 0.5]],
                           "random.resolution": 0.5})
    res = rnd.measure(cfg, scales=[1.0, 4.0], duration=6.0, replicates=3)
    res.levels[0]["H"], res.levels[0]["coherence"]   # on res.levels[0]["f"]
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxdamp.config import Config, ConfigError, apply_overrides


@dataclasses.dataclass
class RandomResult:
    """Random-excitation tests at the spectrum scales ``scales`` ``(P,)``.

    ``levels[i]``: the pooled H1 estimate of :func:`jaxdamp.analysis.spectra.h1` restricted to
    the band (``f``, ``H``, ``coherence``, ``Gxx``, ``Gyy``, ``H_each``, ``mag_se``,
    ``segments``) and ``a_rms`` the base's RMS acceleration [m/s²] from the spectrum,
    ``y_rms`` ``(R,)`` each realisation's RMS of the relative displacement ``z - u`` [m],
    ``z_rms`` ``(R,)`` of ``z`` [m] (``z`` the displacement of the degree of freedom ``dof``,
    the structure's numbering; the box's by default), ``start`` ``(R,)`` the detected start
    of the stationary record [s] and ``stationary`` ``(R,)``; ``period`` the excitation's period ``1/Δf`` [s];
    ``sweep`` the :class:`jaxdamp.studies.grid.SweepResult` (records, configuration, file)."""

    scales: np.ndarray
    levels: list
    period: float
    replicates: int
    sweep: object
    dof: int = 0


def random_config(config: Config) -> Config:
    """``config`` as a random test: S1 with a ``[random]`` table; the harmonic base motion
    ``primary.U`` is switched off. Refuses other systems and a missing spectrum."""
    if config.system != "primary":
        raise ConfigError(f"system = {config.system!r}: random base excitation needs the "
                          "primary (S1, system 'primary')")
    if config.random is None:
        raise ConfigError("random: no base spectrum; give the base acceleration density "
                          "breakpoints [(m/s²)²/Hz]: --psd 5:0.5,30:0.5 on the command line, or "
                          "random.psd = [[5, 0.5], [30, 0.5]] in the configuration")
    from jaxdamp.validation import validate

    return validate(apply_overrides(config, {"primary.U": 0.0}))


def band_rms(config: Config) -> float:
    """RMS base acceleration [m/s²] of ``config.random``: ``sqrt(scale Σ_k S_a(f_k) Δf)`` over
    the multisine's lines (:func:`jaxdamp.physics.excitation.random_lines`)."""
    from jaxdamp.physics.excitation import random_lines

    lines = random_lines(config)
    amp = np.hypot(lines[:, 1], lines[:, 2]) * lines[:, 0] ** 2
    return float(math.sqrt(0.5 * np.sum(amp**2)))


def measure(config: Config, scales=(1.0,), duration: float | None = None, replicates: int = 1,
            out: str | None = None, resume: bool = False, progress: bool = True,
            echo=print, reuse: bool = False, dof: int | None = None) -> RandomResult:
    """Run the random test at every spectrum scale ``scales`` (``random.scale``), ``replicates``
    realisations each, as one batch (:func:`jaxdamp.studies.sweep.sweep`; with ``out`` the file,
    resumable, gets a ``/random`` group). ``duration`` [s]: simulated time (default: the
    configuration's); it must hold the transient and at least one excitation period
    ``1/random.resolution``. ``reuse``: a finished ``out`` of the same test is read back and a
    partial one resumed, anything else replaced (experiments; ``resume`` refuses a different
    test instead). ``dof``: the degree of freedom whose response is the output (the
    structure's numbering; default the box's); :func:`analyse` gives any other from the same
    run."""
    from jaxdamp.physics.structure import position
    from jaxdamp.studies.sweep import sweep

    cfg = random_config(config)
    if duration is not None:
        cfg = apply_overrides(cfg, {"numerics.duration": float(duration)})
    scales = np.atleast_1d(np.asarray(scales, float))
    if not np.all(np.isfinite(scales) & (scales > 0)):
        raise ConfigError(f"scales = {scales.tolist()}: every spectrum scale must be > 0")
    period = 1.0 / cfg.random.resolution
    if cfg.numerics.duration < 2.0 * period:
        raise ConfigError(f"numerics.duration = {cfg.numerics.duration} s: a random test needs "
                          f"at least two excitation periods 1/random.resolution = {period:g} s "
                          "(one for the transient, one to analyse)")
    R = int(replicates)
    position(cfg, dof)  # a clear error before any compute
    axes = {"random.scale": list(scales)}
    if reuse and out:
        from jaxdamp.io.sweepfile import holds

        resume = holds(out, cfg, axes, R)
    res = sweep(cfg, axes, out=out, resume=resume, progress=progress, echo=echo, replicates=R)
    if res is None:
        return None
    result = analyse(res, scales, R, dof)
    if out:
        from jaxdamp.io import random as random_file

        random_file.write(out, result)
    return result


def analyse(res, scales, replicates: int, dof: int | None = None) -> RandomResult:
    """The H1 estimates of a finished random sweep ``res`` (levels ``scales`` × ``replicates``
    realisations; :func:`measure`) at degree of freedom ``dof`` (the structure's numbering,
    ``None``: the box's). Any degree of freedom can be analysed from the same run."""
    from scipy.interpolate import CubicSpline

    from jaxdamp.analysis.spectra import h1, rms, steady_start
    from jaxdamp.physics.model import base_series
    from jaxdamp.physics.structure import displacement
    from jaxdamp.studies.grid import replicate_configs

    R = int(replicates)
    scales = np.atleast_1d(np.asarray(scales, float))
    configs = replicate_configs(res.configs, R)
    cfg = configs[0]
    period = 1.0 / cfg.random.resolution
    f_lo = cfg.random.psd[0][0]
    f_hi = cfg.random.psd[-1][0]
    levels = []
    for i in range(len(scales)):
        xs, ys, y_rms, z_rms, starts, flags = [], [], [], [], [], []
        for r in range(R):
            k = res.point(i, r)
            t = np.asarray(res.records["t"][k])
            z = displacement(res.records, k, configs[k], dof)
            u, _ = base_series(configs[k], t)
            start, ok = steady_start(t, z - u, block=period / 8)
            # whole excitation periods back from the end to the detected start, resampled
            # (cubic spline of z; u exact) on n_per points per period: no leakage
            n_per = int(math.ceil(period / np.median(np.diff(t))))
            n_seg = int((t[-1] - start) // period + 1e-9)
            if n_seg < 1:
                ok, n_seg = False, 1
            tg = t[-1] - n_seg * period + np.arange(n_seg * n_per) * (period / n_per)
            zg = CubicSpline(t, z)(tg)
            ug, _ = base_series(configs[k], tg)
            xs.append(ug)
            ys.append(zg)
            y_rms.append(rms(zg - ug))
            z_rms.append(rms(zg))
            starts.append(float(tg[0]))
            flags.append(ok)
        fs = n_per / period
        est = h1(xs, ys, fs, nperseg=n_per, window="boxcar")
        band = (est["f"] >= f_lo - 1e-9) & (est["f"] <= f_hi + 1e-9)
        lev = {k: (v[..., band] if isinstance(v, np.ndarray) and v.shape[-1] == len(band)
                   else v) for k, v in est.items()}
        lev.update(a_rms=band_rms(configs[res.point(i, 0)]), y_rms=np.array(y_rms),
                   z_rms=np.array(z_rms), start=np.array(starts), stationary=np.array(flags))
        levels.append(lev)
    if dof is None:
        from jaxdamp.physics.structure import attachments

        dof = attachments(cfg)[0]  # the box's (cell 0's); 0 without a structure
    return RandomResult(scales=scales, levels=levels, period=period, replicates=R, sweep=res,
                        dof=int(dof))
