"""``jaxdamp frf``: a batched frequency-response sweep, its fit and figure."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.cli.common import (
    add_config_options,
    add_no_progress,
    add_overwrite,
    check_outputs,
    command_config,
    float_list,
    positive_float,
    positive_int,
    replicates,
    resume_or_overwrite,
    say_written,
)
from jaxdamp.config import ConfigError


def cmd_frf(args) -> int:
    import numpy as np

    cfg = command_config(
        args, ["numerics.duration=0.5", "numerics.settle_time=0.3", "numerics.chunk=0.1"],
        [None if args.duration is None else f"numerics.duration={args.duration}"])
    if cfg.system not in ("primary", "impact"):
        raise ConfigError("jaxdamp frf needs system 'primary' (S1) or 'impact' (S3): an FRF is "
                          "the primary's response")
    if cfg.structure is not None:
        raise ConfigError("jaxdamp frf fits the 1-DOF primary's FRF (M_ef, C_ef), which does not "
                          "apply to a multi-DOF [structure]; use jaxdamp random (H1 at the box) "
                          "or jaxdamp run, whose records hold every degree of freedom (y_dofs)")
    impact = cfg.system == "impact"  # S3: one particle of mass impactor.mass, gap impactor.gap
    if args.frequencies is not None:
        freqs = float_list(args.frequencies, "--frequencies", "frequencies [Hz]", "12,15,18")
    else:
        n = args.n if args.n is not None else (6 if args.quick else 30)
        if not 0 < args.fmin < args.fmax:
            raise ConfigError(f"--fmin {args.fmin} / --fmax {args.fmax}: need 0 < fmin < fmax")
        freqs = list(np.linspace(args.fmin, args.fmax, n))
    if not all(0 < f < float("inf") for f in freqs):  # NaN fails too
        raise ConfigError(f"--frequencies: every frequency must be a finite number > 0 Hz, got "
                          f"{freqs}")
    axes = {"frequency": freqs}
    lz = float_list(args.lz, "--lz") if args.lz else None
    if lz:
        axes["box.Lz"] = lz
    R = replicates(args)
    png = args.png or (args.out.rsplit(".", 1)[0] + ".png" if args.out else None)
    check_outputs([args.out, png], args.overwrite, keep=resume_or_overwrite(args),
                  resumable=[args.out])
    from jaxdamp.validation import check_periods

    check_periods(cfg, min(freqs))  # every point covers a whole drive period

    import h5py

    from jaxdamp.analysis.response import (
        FIT_RULE,
        RESIDUALS,
        fit_failure,
        fit_frf_scan,
        replicate_mean,
    )
    from jaxdamp.figures import frf_figure, save
    from jaxdamp.io.sweepfile import write_fit
    from jaxdamp.physics.containers import container
    from jaxdamp.physics.model import grain_mass
    from jaxdamp.studies.grid import steady_or_window
    from jaxdamp.studies.sweep import sweep

    res = sweep(cfg, axes, out=args.out, resume=args.resume, progress=not args.no_progress,
                replicates=R)
    L = len(lz) if lz else 1
    p = cfg.primary
    if res.steady is not None:
        Zr, fallback = steady_or_window(res, "amplitude")
        Zr = Zr.reshape(len(freqs), L, R)
        starts = np.asarray(res.steady["amplitude"]["start"], float)
        ok = np.asarray(res.steady["amplitude"]["stationary"], bool)
        if ok.any():
            print(f"steady state detected from the data (MSER on per-period amplitude and "
                  f"dissipation) in {int(ok.sum())} of {ok.size} runs, starting at "
                  f"t = {np.nanmin(starts[ok]):.3g}–{np.nanmax(starts[ok]):.3g} s; R = {R} "
                  "replicate(s) per point")
        if fallback:
            print(f"warning: {fallback} of {Zr.size} runs did not become stationary (MSER on "
                  "per-period amplitude and dissipation); their fixed-window amplitude is used "
                  "— run longer (--duration)")
    else:  # S3: deterministic, one realisation
        Zr = res.summary["amplitude"].reshape(len(freqs), L, 1)
    Z, Z_se = replicate_mean(Zr)
    order = [args.residuals] + [w for w in RESIDUALS if w != args.residuals]
    fits, failures, lines = [], [], []
    fit_all = {w: fit_frf_scan(freqs, Zr, p, w) for w in RESIDUALS}
    for j in range(L):
        fr = fit_all[args.residuals][j]
        why = fit_failure(fr)
        fits.append(None if why else (fr["M_ef"], fr["C_ef"]))
        failures.append(why)
        label = (f"Lz = {lz[j]:g} m" if lz else f"gap = {cfg.impactor.gap:g} m" if impact
                 else f"Lz = {container(cfg).height(cfg):g} m")
        k = int(np.argmax(Z[:, j]))
        lines.append(f"{label}: peak Z/U = {Z[k, j] / p.U:.4g} at {freqs[k]:.4g} Hz; "
                     + "; ".join(_fit_text(fit_all[w][j], p.C) for w in order))
    print("\n".join(lines))
    if not all(fit_failure(f) for fl in fit_all.values() for f in fl):
        print("(± : " + (f"SE over R = {R} replicates" if R >= 2 else
                         "the fit's standard error, R = 1") + ")")
    if any(failures):
        print(f"warning: the {args.residuals} FRF fit FAILED for {sum(map(bool, failures))} of "
              f"{L} curve(s) ({FIT_RULE}): flagged in /fit/ok, not drawn; more frequencies "
              "around the resonance (--fmin/--fmax/--n) or replicates usually help")
    m_p = cfg.impactor.mass if impact else grain_mass(cfg)
    if args.out:
        with h5py.File(args.out, "a") as h:
            write_fit(h, fit_all, args.residuals)
    if png:
        save(frf_figure(np.asarray(freqs), Z, lz or [None], p, m_p, fits,
                   title=(f"{cfg.name}: one particle, m = {m_p:.4g} kg, e = "
                          f"{cfg.impactor.restitution:g}" if impact else
                          f"{cfg.name}: N = {cfg.n_grains}")
                   + f", {res.summary['wall_time']:.0f} s wall"
                   + (f", mean of R = {R} beds ± 2 SE" if R > 1 else ""),
                   model="S3" if impact else "DEM", Z_se=Z_se, failures=failures), png)
    say_written(args.out, png)
    return 0


def _fit_text(fit: dict, C: float) -> str:
    """One weighting's FRF fit for the printed summary: ``M_ef``, ``C_ef`` as mean ± SE
    (:func:`jaxdamp.analysis.stats.format_estimate`; the fit's own error for ``R = 1``), or
    FAILED with the reason (:func:`jaxdamp.analysis.response.fit_failure`)."""
    from jaxdamp.analysis.response import fit_failure
    from jaxdamp.analysis.stats import format_estimate

    why = fit_failure(fit)
    if why:
        return f"{fit['residuals']} fit FAILED ({why}): no M_ef, C_ef"
    R = int(fit["replicates"])
    eM, eC = (fit["se_M"], fit["se_C"]) if R >= 2 else (fit["fit_se_M"], fit["fit_se_C"])
    return (f"{fit['residuals']} fit M_ef = {format_estimate(fit['M_ef'], eM, R, 'kg')}, "
            f"C_ef = {format_estimate(fit['C_ef'], eC, R, 'N s/m')}"
            + (f", C_ef/C = {fit['C_ef'] / C:.3g}" if C > 0 else ""))


def register(sub) -> None:
    """Add the subcommand(s) to the ``jaxdamp`` parser."""
    fr = sub.add_parser(
        "frf", help="frequency response: a batched sweep over frequencies (and Lz), fit, figure",
        description="Run one simulation per frequency (and per box height), all at once as a "
        "batch, and report the steady-state amplitude Z(f), the phase, the granular "
        "dissipation per cycle, and the fitted effective mass and damping.",
        epilog=textwrap.dedent("""\
            examples:
              jaxdamp frf --preset sanchez2012-optimal --quick --out frf.h5
              jaxdamp frf --preset sanchez2012-optimal --fmin 5 --fmax 25 --n 21 --out frf.h5
              jaxdamp frf --preset sanchez2012-optimal --frequencies 12,14,15.16,17 \\
                          --lz 0.06,0.09,0.1225 --out lz.h5
            The HDF5 holds /summary/<name> arrays shaped (frequencies, Lz), /records (samples
            per point), /axes, /fit (M_ef, C_ef per Lz) and a checkpoint (--resume).
            A fit that is not a result (too few frequencies, a value on its bound 0, an error
            not finite or above half its value) is printed as FAILED with the reason, flagged
            in /fit/ok and /fit/failure, and not drawn."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(fr, "a named reference case (list: `jaxdamp presets`); "
                       "sanchez2012-impact runs the single-particle model (S3)")
    fr.add_argument("--fmin", type=positive_float, default=5.0, help="lowest frequency [Hz] (default 5)")
    fr.add_argument("--fmax", type=positive_float, default=25.0, help="highest frequency [Hz] (default 25)")
    fr.add_argument("--n", type=positive_int, help="number of frequencies (default 30; 6 with --quick)")
    fr.add_argument("--frequencies", metavar="F1,F2,...", help="explicit list of frequencies [Hz]")
    fr.add_argument("--lz", metavar="LZ1,LZ2,...", help="second axis: box heights [m]")
    fr.add_argument("--duration", type=positive_float, help="simulated time per point [s]")
    fr.add_argument("--out", metavar="FILE.h5",
                    help="sweep file to write (default: none; the PNG goes beside it)")
    fr.add_argument("--png", metavar="FILE.png",
                    help="figure (default: next to --out; written with or without --out)")
    fr.add_argument("--quick", action="store_true", help="6 frequencies, 0.5 s each")
    fr.add_argument("--resume", action="store_true", help="continue --out from its checkpoint")
    add_overwrite(fr, resume=True)
    fr.add_argument("--replicates", type=positive_int, metavar="R",
                    help="independent beds per point, run in the same batch (default 1): "
                         "amplitudes and M_ef, C_ef get mean ± standard error over them")
    fr.add_argument("--residuals", choices=["relative", "absolute"], default="relative",
                    help="FRF-fit weighting that is reported first and drawn: relative "
                         "(Z_model/Z - 1, default) or absolute ((Z_model - Z)/U, dominated by "
                         "the resonance, as the thesis describes); both are stored in /fit")
    add_no_progress(fr)
    fr.set_defaults(func=cmd_frf)
