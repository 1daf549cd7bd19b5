"""``jaxdamp random``: band-limited random base excitation of the primary, H1 FRF with coherence."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.analysis.uncertainty import mean_se, pm
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


def psd_table(text: str) -> list[list[float]]:
    """``"5:0.5,30:0.5"`` -> ``[[5.0, 0.5], [30.0, 0.5]]`` (breakpoints ``f:S``); a one-line
    error naming ``--psd`` otherwise."""
    rows = []
    for item in text.split(","):
        if not item.strip():
            continue
        parts = item.split(":")
        try:
            if len(parts) != 2:
                raise ValueError
            rows.append([float(parts[0]), float(parts[1])])
        except ValueError:
            raise ConfigError(f"--psd {text!r}: expected breakpoints f:S separated by commas "
                              "(f [Hz], S [(m/s²)²/Hz]), e.g. 5:0.5,30:0.5") from None
    return rows


def cmd_random(args) -> int:
    import numpy as np

    options = []
    if args.psd:
        options.append(f"random.psd={psd_table(args.psd)!r}")
    if args.resolution is not None:
        options.append(f"random.resolution={args.resolution!r}")
    from jaxdamp.studies import random as rnd

    given = command_config(args, ["numerics.settle_time=0.3"], options)
    cfg = rnd.random_config(given)  # S1 with a spectrum, validated; the harmonic base off
    scales = float_list(args.scale, "--scale") if args.scale else [cfg.random.scale]
    R = replicates(args)
    png = args.png or (args.out.rsplit(".", 1)[0] + ".png" if args.out else None)
    check_outputs([args.out, png], args.overwrite, keep=resume_or_overwrite(args),
                  resumable=[args.out])
    if given.primary.U != 0:
        print(f"random test: the harmonic base motion is switched off (primary.U = "
              f"{given.primary.U:g} -> 0)")

    from jaxdamp.figures import random_figure, save
    from jaxdamp.physics.structure import attachments

    res = rnd.measure(cfg, scales, duration=args.duration, replicates=R, out=args.out,
                      resume=args.resume, progress=not args.no_progress, dof=args.dof)
    seed = "numerics.seed of each bed" if cfg.random.seed is None else cfg.random.seed
    where = ("" if cfg.structure is None
             else f" at degree of freedom {res.dof} (the box is on {attachments(cfg)[0]})")
    print(f"random-phase multisine, period {res.period:g} s, phases from {seed}; H1 = z/u"
          f"{where} pooled over R = {R} realisation(s)")
    for s, lev in zip(res.scales, res.levels):
        f, mag, coh = lev["f"], np.abs(lev["H"]), lev["coherence"]
        k = int(np.argmax(mag))
        y_rms = pm(*mean_se(lev["y_rms"]), 4, scale=1e3, unit="mm")
        print(f"scale {s:g}: base RMS acceleration {lev['a_rms']:.4g} m/s², RMS of z − u "
              f"{y_rms}; peak |H1| = {pm(mag[k], lev['mag_se'][k], 4, 3)} at "
              f"{f[k]:g} Hz (coherence {coh[k]:.3f}); coherence over the band "
              f"{coh.min():.3f}–{coh.max():.3f}; {lev['segments']} period(s) averaged; "
              f"stationary start detected in {int(lev['stationary'].sum())} of {R}")
    if png:
        title = (f"{cfg.name}: N = {cfg.n_grains}, random base motion, R = {R} realisation(s)"
                 + (" ± 2 SE" if R > 1 else "")
                 + ("" if cfg.structure is None else f", degree of freedom {res.dof}"))
        labels = [f"a_rms = {lev['a_rms']:.3g} m/s²" for lev in res.levels]
        save(random_figure(res.levels, labels, title=title), png)
    say_written(args.out, png)
    return 0


def register(sub) -> None:
    """Add the subcommand to the ``jaxdamp`` parser."""
    p = sub.add_parser(
        "random", help="random base excitation: H1 FRF with coherence, response RMS",
        description="Shake the primary's base (S1) with band-limited random motion of a given "
        "acceleration spectral density (a random-phase multisine: its lines carry exactly the "
        "density, its phases come from the seed), at one or more levels, on R independent "
        "realisations at once (independently poured beds, each with its own phases unless "
        "random.seed fixes them). From the stationary part of each record (detected from the "
        "data): the H1 estimate of the transmissibility z/u, its coherence, spectra and RMS. "
        "The damper is nonlinear: every FRF belongs to its level. A half-sine shock pulse is "
        "set with --set shock.peak=... --set shock.duration=... (see docs/physics.md §1).",
        epilog=textwrap.dedent("""\
            examples:
              jaxdamp random --preset sanchez2012-random --out random.h5
                  the preset's spectrum: 2 (m/s²)²/Hz over 5–30 Hz, 12 s
              jaxdamp random --preset sanchez2012-optimal --psd 5:0.5,30:0.5 --resolution 0.5 \\
                             --duration 8 --replicates 3 --scale 1,4 --out random.h5
              jaxdamp random --config my_damper.toml --resolution 0.25 --out random.h5
                  my_damper.toml with a [random] table (psd = [[5, 0.5], [30, 0.5]])
              jaxdamp random --preset sanchez2012-chain --psd 5:0.5,30:0.5 --duration 8 \\
                             --dof 0 --out lower_mass.h5
            --psd gives breakpoints f:S (f [Hz], S the base acceleration density
            [(m/s²)²/Hz], linear between, zero outside); a preset without a [random] table
            needs it. --duration must hold two periods 1/DF (8 s at the default 0.25 Hz): one
            for the transient, one to analyse. The HDF5 holds the sweep (/records per level
            and realisation, the configuration) and /random: H1, |H1| ± SE, coherence,
            densities, RMS per realisation."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(p, "a named reference case (list: `jaxdamp presets`); "
                       "sanchez2012-random has a spectrum, the others need --psd",
                       "random.scale=2")
    p.add_argument("--psd", metavar="F:S,F:S,...",
                   help="base acceleration density breakpoints f [Hz] : S [(m/s²)²/Hz], e.g. "
                        "5:0.5,30:0.5 (sets random.psd; default: the configuration's)")
    p.add_argument("--resolution", type=positive_float, metavar="DF",
                   help="line spacing [Hz] (random.resolution; the record is cut into periods "
                        "1/DF, default 0.25 Hz)")
    p.add_argument("--scale", metavar="S1,S2,...",
                   help="levels: factors on the density (RMS ∝ √scale), one test each "
                        "(default: random.scale, 1)")
    p.add_argument("--duration", type=positive_float, metavar="S",
                   help="simulated time per test [s] (≥ 2 periods 1/DF; default: "
                        "numerics.duration)")
    p.add_argument("--replicates", type=positive_int, metavar="R",
                   help="independent realisations per level, in the same batch (default 1)")
    p.add_argument("--dof", type=int, metavar="I",
                   help="with a [structure]: the degree of freedom (0-based, the structure's "
                        "numbering) whose response z is analysed; default the box's "
                        "(structure.attach; cell 0's). Every degree of freedom is in the records "
                        "(z_box, y_dofs)")
    p.add_argument("--out", metavar="FILE.h5",
                   help="sweep file with the /random analysis (default: none)")
    p.add_argument("--png", metavar="FILE.png",
                   help="figure (default: next to --out; written with or without --out)")
    p.add_argument("--resume", action="store_true", help="continue --out from its checkpoint")
    add_overwrite(p, resume=True)
    add_no_progress(p)
    p.set_defaults(func=cmd_random)
