"""``jaxdamp frf``: a batched frequency-response sweep, its fit and figure."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.cli.common import (
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
    if args.frequencies:
        freqs = float_list(args.frequencies, "--frequencies")
    else:
        n = args.n if args.n is not None else (6 if args.quick else 30)
        if not 0 < args.fmin < args.fmax:
            raise ConfigError(f"--fmin {args.fmin} / --fmax {args.fmax}: need 0 < fmin < fmax")
        freqs = list(np.linspace(args.fmin, args.fmax, n))
    if any(f <= 0 for f in freqs):
        raise ConfigError(f"--frequencies: every frequency must be > 0 Hz, got {freqs}")
    axes = {"frequency": freqs}
    lz = float_list(args.lz, "--lz") if args.lz else None
    if lz:
        axes["box.Lz"] = lz
    R = replicates(args)
    png = args.png or (args.out.rsplit(".", 1)[0] + ".png" if args.out else None)
    check_outputs([args.out, png], args.overwrite, keep=resume_or_overwrite(args),
                  resumable=[args.out])

    import h5py

    from jaxdamp.analysis.response import RESIDUALS, fit_frf_replicates
    from jaxdamp.figures import frf_figure, save
    from jaxdamp.io.sweepfile import fit_failure, write_fit
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
    Z = Zr.mean(axis=-1)
    Z_se = Zr.std(axis=-1, ddof=1) / np.sqrt(R) if R >= 2 else None
    fits, failures, lines, fit_all = [], [], [], {w: [] for w in RESIDUALS}
    for j in range(L):
        for w in RESIDUALS:
            fit_all[w].append(fit_frf_replicates(freqs, Zr[:, j], p.U, p.K, M0=p.M,
                                                 C0=max(p.C, 1.0), residuals=w))
        fr = fit_all[args.residuals][j]
        other = fit_all[next(w for w in RESIDUALS if w != args.residuals)][j]
        why, why_other = fit_failure(fr), fit_failure(other)
        fits.append(None if why else (fr["M_ef"], fr["C_ef"]))
        failures.append(why)
        label = (f"Lz = {lz[j]:g} m" if lz else f"gap = {cfg.impactor.gap:g} m" if impact
                 else f"Lz = {cfg.box.Lz:g} m")
        k = int(np.argmax(Z[:, j]))
        err = ((lambda e: f"± {e:.2g} (SE over R = {R})") if R >= 2 else
               (lambda e: f"± {e:.2g} (fit error, R = 1)"))
        eM = fr["se_M"] if R >= 2 else fr["fit_se_M"]
        eC = fr["se_C"] if R >= 2 else fr["fit_se_C"]
        head = f"{label}: peak Z/U = {Z[k, j] / p.U:.4g} at {freqs[k]:.4g} Hz; "
        if why:
            main = f"{args.residuals} fit FAILED ({why}): no M_ef, C_ef; "
        else:
            main = (f"{args.residuals} fit M_ef = {fr['M_ef']:.4g} {err(eM)} kg, "
                    f"C_ef = {fr['C_ef']:.4g} {err(eC)} N s/m (C_ef/C = {fr['C_ef'] / p.C:.3g}); ")
        second = (f"{other['residuals']} fit FAILED ({why_other})" if why_other else
                  f"{other['residuals']} fit: M_ef = {other['M_ef']:.4g}, "
                  f"C_ef = {other['C_ef']:.4g}")
        lines.append(head + main + second)
    print("\n".join(lines))
    if any(failures):
        print(f"warning: the {args.residuals} FRF fit failed for {sum(map(bool, failures))} of "
              f"{L} curve(s): not a result (flagged in /fit/ok, not drawn); more frequencies "
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
            per point), /axes, /fit (M_ef, C_ef per Lz) and a checkpoint (--resume)."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    fr.add_argument("--preset")
    fr.add_argument("--config", metavar="FILE")
    fr.add_argument("--set", action="append", metavar="KEY=VALUE")
    fr.add_argument("--fmin", type=positive_float, default=5.0, help="lowest frequency [Hz] (default 5)")
    fr.add_argument("--fmax", type=positive_float, default=25.0, help="highest frequency [Hz] (default 25)")
    fr.add_argument("--n", type=positive_int, help="number of frequencies (default 30; 6 with --quick)")
    fr.add_argument("--frequencies", metavar="F1,F2,...", help="explicit list of frequencies [Hz]")
    fr.add_argument("--lz", metavar="LZ1,LZ2,...", help="second axis: box heights [m]")
    fr.add_argument("--duration", type=positive_float, help="simulated time per point [s]")
    fr.add_argument("--out", metavar="FILE.h5")
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
    fr.add_argument("--no-progress", action="store_true")
    fr.set_defaults(func=cmd_frf)
