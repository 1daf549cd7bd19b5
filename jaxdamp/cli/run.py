"""``jaxdamp run``: one damper at one frequency (or R replicates of it)."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.cli.common import (
    add_config_options,
    add_no_progress,
    add_overwrite,
    check_outputs,
    positive_float,
    positive_int,
    print_steady,
    replicates,
    resume_or_overwrite,
    run_config,
)

EPILOG_RUN = textwrap.dedent(
    """\
    examples:
      jaxdamp run --preset sanchez2012-optimal --quick --out run.h5
          a one-minute demo of the thesis' optimal damper at its resonance (15.16 Hz)
      jaxdamp run --preset sanchez2012-optimal --frequency 12 --duration 5 --out f12.h5
      jaxdamp run --preset sanchez2012-optimal --set box.Lz=0.07 --set primary.C=26.3
      jaxdamp run --config my_damper.toml --set grains.0.count=100 --out mine.h5
      jaxdamp run --preset sanchez2012-optimal --out long.h5 --resume   (after an interruption)

    configuration:
      A run is described by a configuration tree (see `jaxdamp presets --show NAME` for one in
      full, as TOML). Start from a preset, from a TOML file (keys override the preset when both
      are given), then apply --set key=value overrides with dotted keys: box.Lz, frequency,
      primary.M, grains.0.radius, grains.0.material.gamma_n, numerics.dt, numerics.duration,
      numerics.stiffness_scale, ... Values are TOML (numbers, strings in quotes or bare, true/false).
      Contact damping is either gamma_n/gamma_s (thesis) or restitution + v_ref (paper).

    output:
      One HDF5 file (schema in docs/output.md): configuration (JSON attribute), sampled time
      series, cumulative work channels, energy-balance residual, snapshots, summary scalars,
      and a checkpoint after every chunk (--resume continues bit-identically).
    """
)


def cmd_run(args) -> int:
    from jaxdamp.validation import check_periods, validate

    cfg = run_config(args)
    R = replicates(args)
    check_outputs([args.out], args.overwrite, keep=resume_or_overwrite(args),
                  resumable=[args.out])
    cfg = validate(cfg)
    check_periods(cfg)
    from jaxdamp.studies.runner import run

    if R > 1:  # R independent beds in one batch: a sweep of one point (sweep file layout)
        from jaxdamp.studies.sweep import sweep

        res = sweep(cfg, {}, out=args.out, resume=args.resume, progress=not args.no_progress,
                    replicates=R)
        s = res.summary
        print(f"{R} replicates, fixed analysis window: amplitude Z = {float(s['amplitude']):.6g} m, "
              f"granular dissipation per cycle = {float(s['granular_loss_per_cycle']):.6g} J, "
              f"max energy balance error = {float(res.replicate_summary['balance_error'].max()):.3g}")
        print_steady(res.steady)
        if args.out:
            print(f"wrote {args.out} (a sweep file of one point with {R} replicates)")
        return 0
    res = run(cfg, out=args.out, resume=args.resume, progress=not args.no_progress)
    s = res.summary
    print(f"amplitude Z = {s['amplitude']:.6g} m"
          + (f" (Z/U = {s['amplitude_ratio']:.4g})" if "amplitude_ratio" in s else "")
          + " (fixed analysis window)")
    print(f"granular dissipation per cycle = {s['granular_loss_per_cycle']:.6g} J "
          f"(pp: {s['pp_normal_per_cycle'] + s['pp_friction_per_cycle']:.4g} J, "
          f"pw: {s['pw_normal_per_cycle'] + s['pw_friction_per_cycle']:.4g} J)")
    print(f"energy balance error = {s['balance_error']:.3g}; {s['steps']} steps of "
          f"{s['dt']:.4g} s at {s['steps_per_second']:.4g} steps/s")
    if res.steady is not None:
        print_steady(res.steady)
    if args.out:
        print(f"wrote {args.out}")
    return 0


def register(sub) -> None:
    """Add the subcommand(s) to the ``jaxdamp`` parser."""
    r = sub.add_parser(
        "run", help="simulate one damper at one frequency and write an HDF5 run file",
        description="Settle the grains, drive the system at one frequency and record it.",
        epilog=EPILOG_RUN, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(r)
    r.add_argument("--frequency", type=positive_float, metavar="HZ", help="excitation frequency f [Hz]")
    r.add_argument("--duration", type=positive_float, metavar="S", help="simulated time after settling [s]")
    r.add_argument("--seed", type=int, help="seed of radii and lattice jitter")
    r.add_argument("--out", metavar="FILE.h5", help="output HDF5 file (default: none)")
    r.add_argument("--quick", action="store_true",
                   help="short demo run (1 s driven after settling, under a minute on 2 cores)")
    r.add_argument("--resume", action="store_true", help="continue --out from its checkpoint")
    add_overwrite(r, resume=True)
    r.add_argument("--replicates", type=positive_int, metavar="R",
                   help="independent beds (seeds seed..seed+R-1) run in one batch (default 1); "
                        "steady-state numbers get mean ± standard error over them and the file "
                        "is a sweep file of one point")
    add_no_progress(r)
    r.set_defaults(func=cmd_run)
