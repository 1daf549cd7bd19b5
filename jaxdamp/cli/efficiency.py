"""``jaxdamp efficiency``: dissipation efficiency of a driven box over drive amplitudes."""

from __future__ import annotations

import argparse
import textwrap

from jaxdamp.analysis.uncertainty import pm
from jaxdamp.cli.common import (
    add_config_options,
    add_no_progress,
    add_overwrite,
    base_config,
    check_outputs,
    float_list,
    nonnegative_int,
    positive_int,
    replicates,
)
from jaxdamp.config import ConfigError, apply_overrides


def _amplitudes(text):
    """``A0:A1:N`` (N evenly spaced values) or ``A1,A2,...`` [m]."""
    import numpy as np

    if ":" in text:
        parts = text.split(":")
        try:
            lo, hi, n = float(parts[0]), float(parts[1]), int(parts[2])
        except (ValueError, IndexError):
            raise ConfigError(f"--amplitude {text!r}: expected A0:A1:N, e.g. 0.02:0.04:9") from None
        if len(parts) != 3 or n < 1 or not 0 < lo <= hi:
            raise ConfigError(f"--amplitude {text!r}: need 0 < A0 <= A1 and N >= 1")
        return list(np.linspace(lo, hi, n))
    values = float_list(text, "--amplitude")
    if not values or min(values) <= 0:
        raise ConfigError(f"--amplitude {text!r}: every amplitude must be > 0 m")
    return values


_PHASE_NAMES = {0: "top, v = 0", 1: "fastest, moving down", 2: "bottom, v = 0",
                3: "fastest, moving up"}


def efficiency_figures(results, stem, title):
    """The PNGs of ``jaxdamp efficiency``: ``<stem>.png`` (⟨E_d⟩/m vs A_d), ``<stem>_phase.png``
    and ``<stem>_snapshots.png`` at the amplitude closest to 3 cm. ``results``: ``[(label,
    EfficiencyResult), ...]``. Returns the paths written."""
    import numpy as np

    from jaxdamp.figures import efficiency_figure, phase_figure, save, snapshot_grid_figure
    from jaxdamp.physics.model import grain_radii, grain_species

    curves = [(lab, r.amplitudes, r.summary["E_d_mean_per_mass"],
               r.summary["E_d_std_per_mass"]) for lab, r in results]
    paths = [save(efficiency_figure(curves, title), f"{stem}.png")]
    cases, rows = [], []
    for lab, r in results:
        k = int(np.argmin(np.abs(r.amplitudes - 0.03)))
        names = [sp.name for sp in r.config.grains]
        cases.append((f"{lab}, A_d = {r.amplitudes[k] * 100:.3g} cm",
                      {n: v[k] for n, v in r.phase.items()}, names))
        if r.snapshots is not None:
            f = r.config.frequency
            frames = []
            for j, t in enumerate(r.snapshots["t"]):
                q = int(round((t * f % 1.0) * 4)) % 4
                frames.append((f"t/T = {t * f:.2f}: {_PHASE_NAMES[q]}", r.snapshots["r"][k, j],
                               r.snapshots["z_box"][k, j]))
            rows.append((f"{lab}, A_d = {r.amplitudes[k] * 100:.3g} cm", frames,
                         grain_radii(r.config), grain_species(r.config), r.config))
    paths.append(save(phase_figure(cases, title), f"{stem}_phase.png"))
    if rows:
        paths.append(save(snapshot_grid_figure(rows, title), f"{stem}_snapshots.png"))
    return paths


def _png_paths(stem: str) -> list[str]:
    """The PNGs :func:`efficiency_figures` writes for ``stem`` (a driven box always has
    snapshots)."""
    return [f"{stem}{suffix}.png" for suffix in ("", "_phase", "_snapshots")]


def cmd_efficiency(args) -> int:
    import numpy as np

    from jaxdamp.cases import mixtures, presets

    amps = _amplitudes(args.amplitude) if args.amplitude else (
        [0.02, 0.03, 0.04] if args.quick else list(np.linspace(0.02, 0.04, 9)))
    periods = args.periods if args.periods is not None else (3 if args.quick else 50)
    transient = args.transient if args.transient is not None else (1 if args.quick else 10)
    sigmas = float_list(args.sigma, "--sigma") if args.sigma else [None]
    if args.preset in mixtures.FAMILIES and args.config is None:
        if mixtures.FAMILIES[args.preset] is None and args.sigma:
            raise ConfigError("--sigma: the reference system (varela2023-reference) is "
                              "monodisperse; use varela2023-a, -b or -c")
        bases = [(s, presets.family(args.preset, s)) for s in sigmas]
    else:
        if args.sigma:
            raise ConfigError(f"--sigma applies to the binary-mixture families "
                              f"{', '.join(k for k, v in mixtures.FAMILIES.items() if v)}")
        bases = [(None, base_config(args))]
    out = args.out
    stem = (args.png or out or "efficiency.png").rsplit(".", 1)[0]
    R = replicates(args)
    plan = []  # (sigma, configuration, sweep file or None)
    for sigma, cfg in bases:
        cfg = apply_overrides(cfg, list(args.set or []))
        path = out
        if out and len(bases) > 1:
            path = f"{out.rsplit('.', 1)[0]}_sigma{sigma:g}.h5"
        plan.append((sigma, cfg, path))
    paths = [path for _, _, path in plan] + (_png_paths(stem) if out or args.png else [])
    check_outputs(paths, args.overwrite, keep=_same_sweeps(plan, amps, periods, transient, R))

    from jaxdamp.studies import efficiency as ef

    results = []
    for sigma, cfg, path in plan:
        label = cfg.name + (f", σ = {sigma:g}" if sigma is not None else "")
        print(f"{label}: {cfg.n_grains} grains, {len(amps)} amplitudes, "
              f"{transient} + {periods} periods at {cfg.frequency:g} Hz")
        r = ef.measure(cfg, amps, periods=periods, transient=transient, out=path,
                       progress=not args.no_progress, replicates=R)
        s = r.summary
        print(f"  m = {s['mass'][0]:.4g} kg, dt = {r.config.numerics.dt:.4g} s, "
              f"{r.wall_time:.0f} s wall")
        print("  A_d [cm]  <E_d> mean ± std   fit     <E_d>/m [1/kg]  E_pp [J]  E_pw [J]  "
              "contacts  balance")
        for i, a in enumerate(r.amplitudes):
            print(f"  {a * 100:7.3f}  {pm(s['E_d_mean'][i], s['E_d_std'][i], '.4f', '.4f')}  "
                  f"{s['E_d_fit'][i]:.4f}  {s['E_d_mean_per_mass'][i]:12.4g}  "
                  f"{s['E_pp'][i]:8.4g}  {s['E_pw'][i]:8.4g}  {s['contacts_mean'][i]:8.3g}  "
                  f"{s['balance_error'][i]:.1e}")
        from jaxdamp.analysis.stats import format_estimate

        print(f"  steady state from the data (MSER on per-period E_d, {R} replicate(s)):")
        for i, a in enumerate(r.amplitudes):
            e = {k: v[i] if np.ndim(v) else v for k, v in r.steady["E_d"].items()}
            starts = ", ".join(f"{t:.3g}" if ok else "never"
                               for t, ok in zip(e["start"], e["stationary"]))
            print(f"  {a * 100:7.3f}  <E_d> = {format_estimate(e['mean'], e['se'], int(e['n']))}; "
                  f"steady from t = {starts} s")
        if path:
            print(f"  wrote {path}")
        results.append((label, r))
    if out or args.png:
        for p in efficiency_figures(results, stem, f"{bases[0][1].name}: E_max = 4 m A_d² ω², "
                                    f"{periods} periods after {transient}"):
            print(f"wrote {p}")
    return 0


def _same_sweeps(plan, amps, periods, transient, R) -> list[str]:
    """The sweep files of ``plan`` that already hold this very measurement: re-running
    continues or reuses them (:func:`jaxdamp.studies.sweep.reuse_or_run`), which loses
    nothing, so they need no ``--overwrite``."""
    import os

    existing = [(cfg, path) for _, cfg, path in plan if path and os.path.exists(path)]
    if not existing:
        return []
    from jaxdamp.io.sweepfile import holds
    from jaxdamp.studies.efficiency import protocol

    axes = {"drive.amplitude": [float(a) for a in amps]}
    return [path for cfg, path in existing
            if holds(path, protocol(cfg, periods, transient, amplitudes=amps), axes, R)]


def register(sub) -> None:
    """Add the subcommand(s) to the ``jaxdamp`` parser."""
    ef = sub.add_parser(
        "efficiency", help="dissipation efficiency E_d of a driven box over drive amplitudes",
        description="Drive a box (S2) at each amplitude, all at once as a batch, and measure "
        "per period the energy dissipated in grain-grain (E_pp) and grain-wall (E_pw) "
        "contacts, the efficiency E_d = (E_pp + E_pw) / E_max with E_max = 4 m A_d^2 w^2 "
        "(the granulate's mass m colliding twice per period at the walls' largest relative "
        "speed 2 A_d w), its average over the analysed periods (plain mean and the paper's "
        "linear fit), and phase-resolved wall contacts, wall force and centre-of-mass motion "
        "per species. The 2023 paper's families: varela2023-reference and the binary "
        "mixtures varela2023-a (equal mass), -b (equal number), -c (equal number and mass) "
        "of size ratio --sigma.",
        epilog=textwrap.dedent("""            examples:
              jaxdamp efficiency --preset varela2023-reference --quick --out ref.h5
                  3 amplitudes x (1 + 3) periods, about a minute
              jaxdamp efficiency --preset varela2023-a --sigma 0.5 --amplitude 0.02:0.04:9 --out a05.h5
              jaxdamp efficiency --preset varela2023-c --sigma 0.3,0.5,0.7 --amplitude 0.025,0.03,0.035 --out c.h5
                  one sweep file per sigma (c_sigma0.3.h5, ...) and one figure set

            cost: the time step follows the smallest grains (dt ~ sigma) and the largest
            amplitude (dt ~ A^-1/5); the reference takes about 15k steps per period, sigma = 0.1
            ten times more. Output: the sweep file (records, snapshots of the last period's
            quarter points, checkpoint; an interrupted run resumes when re-run with the same
            options, and any other existing file is kept unless --overwrite) with an
            /efficiency group (summary, per_period, phase; units in attributes), and PNGs:
            <out>.png (<E_d>/m vs A_d), <out>_phase.png, <out>_snapshots.png."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(ef, "varela2023-reference|a|b|c or any driven-box preset",
                       "grains.0.material.mu=0.2")
    ef.add_argument("--sigma", metavar="S1,S2,...", help="size ratio(s) of the mixture, in (0, 1]")
    ef.add_argument("--amplitude", metavar="A0:A1:N|A1,A2,...",
                    help="drive amplitudes [m] (default 0.02:0.04:9; quick 0.02,0.03,0.04)")
    ef.add_argument("--periods", type=positive_int, help="analysed drive periods (default 50; quick 3)")
    ef.add_argument("--transient", type=nonnegative_int, help="periods dropped first (default 10; quick 1)")
    ef.add_argument("--out", metavar="FILE.h5", help="sweep file with the /efficiency analysis")
    ef.add_argument("--png", metavar="FILE.png", help="figure stem (default: next to --out)")
    ef.add_argument("--quick", action="store_true", help="3 amplitudes, 1 + 3 periods")
    add_overwrite(ef)
    ef.add_argument("--replicates", type=positive_int, metavar="R",
                    help="independent beds per amplitude in the same batch (default 1): <E_d> "
                         "gets mean ± standard error over them")
    add_no_progress(ef)
    ef.set_defaults(func=cmd_efficiency)
