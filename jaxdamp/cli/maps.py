"""``jaxdamp map``: the damper's effective-field maps over amplitude × frequency, and the
structure's response they predict (:mod:`jaxdamp.studies.maps`,
:mod:`jaxdamp.analysis.harmonic_balance`)."""

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
    nonnegative_int,
    positive_int,
    say_written,
)
from jaxdamp.config import ConfigError

#: --quick: a demo of a minute or two on 2 cores.
QUICK = dict(amplitudes=(0.01, 0.04), frequencies=(14.0, 15.0), periods=3, transient=1,
             replicates=2)
QUICK_SET = ["numerics.settle_time=0.3"]


def _grid(args, cfg):
    """The amplitudes [m] and frequencies [Hz] asked for, or the defaults (module help)."""
    if args.amplitudes:
        amps = float_list(args.amplitudes, "--amplitudes", "amplitudes [m]", "0.005,0.01,0.02")
    elif args.quick:
        amps = list(QUICK["amplitudes"])
    else:
        a0 = (cfg.drive.amplitude if cfg.drive is not None
              else cfg.primary.U if cfg.primary is not None else 0.0)
        amps = [a0 * k for k in (1.0, 2.0, 4.0, 8.0)]
    if args.frequencies:
        freqs = float_list(args.frequencies, "--frequencies", "frequencies [Hz]", "12,14,15")
    else:
        freqs = list(QUICK["frequencies"]) if args.quick else [cfg.frequency]
    return amps, freqs


def cmd_map(args) -> int:
    cfg = command_config(args, QUICK_SET)
    amps, freqs = _grid(args, cfg)
    periods = args.periods if args.periods is not None else (
        QUICK["periods"] if args.quick else 20)
    transient = args.transient if args.transient is not None else (
        QUICK["transient"] if args.quick else 5)
    R = args.replicates if args.replicates is not None else (
        QUICK["replicates"] if args.quick else 3)
    from jaxdamp.studies import maps

    maps.check(amps, freqs, periods, transient)  # before any compute (and before JAX)
    if args.predict and cfg.primary is None:
        raise ConfigError(f"--predict: {cfg.name!r} has no structure to insert the map into "
                          "(give a configuration with a primary, system = 'primary')")
    stem = (args.png or args.out or "map.png").rsplit(".", 1)[0]
    pngs = ([f"{stem}.png"] + ([f"{stem}_prediction.png"] if args.predict else [])
            if args.out or args.png else [])
    check_outputs([args.out] + pngs if args.out else pngs, args.overwrite,
                  keep=_same_map(args.out, cfg, amps, freqs, periods, transient, R))
    n = maps.protocol(cfg, amps, freqs, periods, transient).numerics
    print(f"{cfg.name}: the damper alone, {cfg.n_grains} grains, {len(amps)} amplitudes × "
          f"{len(freqs)} frequencies × {R} bed(s) in one batch; {transient} + {periods} "
          f"periods at {min(freqs):g} Hz ({n.duration:.3g} s), dt = {n.dt:.3g} s")
    field = maps.measure(cfg, amps, freqs, periods=periods, transient=transient, replicates=R,
                         out=args.out, progress=not args.no_progress)
    _print_map(field)
    prediction = None
    if args.predict:
        from jaxdamp.analysis.harmonic_balance import predict

        prediction = predict(field, cfg)
        _print_prediction(prediction, cfg.primary.U)
    if pngs:
        from jaxdamp.figures import save
        from jaxdamp.figures.maps import map_figure, prediction_figure

        save(map_figure(field, f"{cfg.name}: effective fields, mean ± SE over {R} bed(s), "
                               f"{periods} periods after {transient}"), pngs[0])
        if prediction is not None:
            save(prediction_figure(prediction, cfg.primary.U,
                                   title=f"{cfg.name}: the response the map predicts "
                                         "(harmonic balance)"), pngs[1])
    say_written(args.out, *pngs)
    return 0


def _print_map(field) -> None:
    ok = field.stationary
    print(f"m_p = {field.grain_mass:.4g} kg; {field.wall_time:.0f} s compute; steady state "
          f"detected (MSER on per-period losses) in {int(ok.sum())} of {ok.size} runs (the "
          "others: the final window)")
    print("  f [Hz]  A [mm]   E_diss [J]           m_eff [kg]           c_eff [N s/m]        "
          "ψ [-]")
    for j, f in enumerate(field.frequencies):
        for i, a in enumerate(field.amplitudes):
            cells = [pm(field.mean(q)[i, j], field.se(q)[i, j], 4)
                     for q in ("E_diss", "m_eff", "c_eff", "psi")]
            print(f"  {f:6.3g}  {a * 1e3:6.3g}   " + "  ".join(f"{c:19s}" for c in cells))


def _print_prediction(p, U) -> None:
    print("the structure's response the map predicts (harmonic balance, per bed):")
    print("  f [Hz]  Z/U (mean ± SE)      roots per bed")
    for k, f in enumerate(p["frequency"]):
        per = "; ".join(", ".join(f"{z / U:.4g}" for z in row[k].roots) or row[k].where
                        for row in p["balances"])
        mean = (pm(p["mean"][k] / U, p["se"][k] / U, 4) if p["mean"][k] == p["mean"][k]
                else "—")
        print(f"  {f:6.3g}  {mean:19s}  {per}")


def _same_map(out, cfg, amps, freqs, periods, transient, R) -> list[str]:
    """``out`` when it already holds this very map's sweep: re-running continues or reuses it
    (no ``--overwrite`` needed)."""
    import os

    if not out or not os.path.exists(out):
        return []
    from jaxdamp.io.sweepfile import holds
    from jaxdamp.studies.maps import protocol

    planned = protocol(cfg, amps, freqs, periods, transient)
    return [out] if holds(out, planned, {"drive.amplitude": [float(a) for a in amps],
                                         "frequency": [float(f) for f in freqs]}, R) else []


def register(sub) -> None:
    """Add the subcommand to the ``jaxdamp`` parser."""
    p = sub.add_parser(
        "map", help="the damper's effective-field maps over amplitude x frequency",
        description="Move the damper's container alone as z = A cos(2 pi f t) at every "
        "amplitude and frequency of a grid, with independently poured beds, all in one batch, "
        "and measure per point and bed: the energy the grains dissipate per cycle (E_diss, "
        "from the contact losses over whole periods of the steady state detected from the "
        "data), the effective mass and damping of the grains' force on the container (m_eff, "
        "c_eff: its first harmonic, F = (m_eff W^2 - i W c_eff) Z), the specific damping "
        "capacity psi = E_diss / (m_p W^2 A^2 / 2) and the loss factor psi / 2 pi; mean +- SE "
        "over the beds. With --predict, the map is inserted into the configuration's structure "
        "(its primary, or structure) by harmonic balance and the response it predicts is "
        "reported per frequency, every branch of a multi-valued response included.",
        epilog=textwrap.dedent("""            examples:
              jaxdamp map --preset sanchez2012-optimal --quick --out map.h5
                  2 amplitudes x 2 frequencies x 2 beds, 1 + 3 periods: a minute or two
              jaxdamp map --preset sanchez2012-optimal --amplitudes 0.005,0.01,0.02,0.03 \\
                  --frequencies 13,14,15,16 --replicates 3 --predict --out map.h5

            defaults: amplitudes U, 2U, 4U, 8U (the primary's base amplitude, or the drive's),
            the configuration's frequency, 5 + 20 periods of the slowest drive, 3 beds.
            cost: every point runs as long as the slowest drive's periods, at the time step
            of the loudest point (the largest A f); the batch is one sweep file (records,
            checkpoint: an interrupted map resumes when re-run with the same options) with a
            /map group (values per bed, mean, se; units in attributes), and PNGs:
            <out>.png (the maps), <out>_prediction.png (with --predict)."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(p, example="box.Lz=0.1225")
    p.add_argument("--amplitudes", metavar="A1,A2,...", help="drive amplitudes [m]")
    p.add_argument("--frequencies", metavar="F1,F2,...", help="drive frequencies [Hz]")
    p.add_argument("--replicates", type=positive_int, metavar="R",
                   help="independently poured beds per point (default 3; quick 2)")
    p.add_argument("--periods", type=positive_int,
                   help="periods of the slowest drive after the transient (default 20)")
    p.add_argument("--transient", type=nonnegative_int,
                   help="periods of the slowest drive before them (default 5)")
    p.add_argument("--predict", action="store_true",
                   help="insert the map into the configuration's structure (harmonic balance)")
    p.add_argument("--out", metavar="FILE.h5", help="sweep file with the /map group")
    p.add_argument("--png", metavar="FILE.png", help="figure stem (default: next to --out)")
    p.add_argument("--quick", action="store_true", help="a small map, for a first look")
    add_overwrite(p)
    add_no_progress(p)
    p.set_defaults(func=cmd_map)
