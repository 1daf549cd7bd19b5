"""``jaxdamp decay``: free-decay tests of the primary and the damper's curves ζ(Z), f(Z)."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.analysis.uncertainty import pm
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


def cmd_decay(args) -> int:
    import numpy as np

    cfg = command_config(args, ["numerics.duration=1.0", "numerics.settle_time=0.3"])
    if cfg.system != "primary":
        raise ConfigError(f"system = {cfg.system!r}: jaxdamp decay rings down the primary (S1, "
                          "system 'primary')")
    z0 = float_list(args.z0, "--z0") if args.z0 else [0.0]
    R = replicates(args)
    png = args.png or (args.out.rsplit(".", 1)[0] + ".png" if args.out else None)
    check_outputs([args.out, png], args.overwrite, keep=resume_or_overwrite(args),
                  resumable=[args.out])
    if cfg.primary.U != 0:
        print(f"free decay: the base motion is switched off (primary.U = {cfg.primary.U:g} -> 0)")

    from jaxdamp.figures import decay_figure, save
    from jaxdamp.studies import decay

    res = decay.measure(cfg, z0, duration=args.duration, v0=args.v0, replicates=R, out=args.out,
                        resume=args.resume, progress=not args.no_progress)
    print(f"undamped frequency with the grains as dead mass f_n = {res.f_n:.4g} Hz; empty-box "
          f"damping ratio {100 * res.zeta_struct:.3f} % (C / (2 √(K (M + m_p))))")
    for x0, c, per in zip(res.z0, res.curves, res.cycles):
        n_cyc = [len(p["Z"]) for p in per]
        print(f"z0 = {x0:g} m, v0 = {args.v0:g} m/s: {min(n_cyc)}–{max(n_cyc)} cycles per bed, "
              f"R = {R}")
        if len(c["Z"]) == 0:
            print("  fewer than two peaks: no cycle to analyse (longer --duration?)")
            continue
        for k in np.unique(np.linspace(0, len(c["Z"]) - 1, 6).round().astype(int))[::-1]:
            zeta = pm(c["zeta"][k], c["zeta_se"][k], ".3f", scale=100, unit="%")
            print(f"  Z = {1e3 * c['Z'][k]:8.3f} mm: ζ = {zeta}, "
                  f"f = {pm(c['f'][k], c['f_se'][k], 4, unit='Hz')} ({int(c['n'][k])} bed(s))")
    if png:
        title = (f"{cfg.name}: N = {cfg.n_grains}, free decay, mean of R = {R} bed(s)"
                 + (" ± 2 SE" if R > 1 else ""))
        save(decay_figure(res.curves, [f"z0 = {1e3 * x:g} mm" for x in res.z0],
                          res.zeta_struct, title), png)
    say_written(args.out, png)
    return 0


def register(sub) -> None:
    """Add the subcommand to the ``jaxdamp`` parser."""
    p = sub.add_parser(
        "decay", help="free decay: ring the primary down, damping ratio and frequency vs amplitude",
        description="Displace the primary (S1) by z0 (and/or give it a velocity v0), switch the "
        "base motion off and let it ring down, on R independently poured beds at once. From "
        "successive peaks: each cycle's equivalent viscous damping ratio ζ (logarithmic "
        "decrement, exact for a linear damper), amplitude and damped frequency — the damper's "
        "characteristic curve ζ(Z), f(Z), mean ± SE over the beds.",
        epilog=textwrap.dedent("""\
            examples:
              jaxdamp decay --preset sanchez2012-optimal --quick --z0 0.02 --out decay.h5
              jaxdamp decay --preset sanchez2012-optimal --z0 0.01,0.03 --duration 4 \\
                            --replicates 3 --out decay.h5
            The HDF5 holds the sweep (/records per test and bed, the configuration) and /decay:
            per-cycle ζ, Z, f of every bed and the mean curves with their SE."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(p, "a named reference case with a primary (S1; list: `jaxdamp presets`)",
                       "primary.C=0")
    p.add_argument("--z0", metavar="Z1,Z2,...",
                   help="initial displacement(s) of the primary from equilibrium [m] "
                        "(one test each; default 0, then --v0 is needed)")
    p.add_argument("--v0", type=float, default=0.0,
                   help="initial velocity of the primary [m/s] (an impulse; default 0)")
    p.add_argument("--duration", type=positive_float, metavar="S",
                   help="simulated time per test [s] (default: numerics.duration; 1 with "
                        "--quick)")
    p.add_argument("--replicates", type=positive_int, metavar="R",
                   help="independent beds per test, in the same batch (default 1)")
    p.add_argument("--out", metavar="FILE.h5",
                   help="sweep file with the /decay analysis (default: none)")
    p.add_argument("--png", metavar="FILE.png",
                   help="figure (default: next to --out; written with or without --out)")
    p.add_argument("--quick", action="store_true", help="1 s of decay, short settling")
    p.add_argument("--resume", action="store_true", help="continue --out from its checkpoint")
    add_overwrite(p, resume=True)
    add_no_progress(p)
    p.set_defaults(func=cmd_decay)
