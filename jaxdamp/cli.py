"""The ``jaxdamp`` command line. Side effects (files, printing) live here and in the runner."""

from __future__ import annotations

import argparse
import sys
import textwrap

from jaxdamp.config import ConfigError, apply_overrides, load_toml

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


def _base_config(args):
    from jaxdamp.cases import presets

    if args.preset is None and args.config is None:
        raise ConfigError("give --preset NAME or --config FILE.toml (see `jaxdamp presets`)")
    base = presets.get(args.preset) if args.preset else None
    cfg = load_toml(args.config, base) if args.config else base
    return cfg


def _run_config(args):
    cfg = _base_config(args)
    overrides = list(args.set or [])
    if args.quick:
        # A demo of about a minute on 2 cores: short drive, quick settling, coarser samples.
        overrides = ["numerics.duration=1.0", "numerics.settle_time=0.3", "numerics.chunk=0.1"] + overrides
    if args.frequency is not None:
        overrides.append(f"frequency={args.frequency}")
    if args.duration is not None:
        overrides.append(f"numerics.duration={args.duration}")
    if args.seed is not None:
        overrides.append(f"numerics.seed={args.seed}")
    return apply_overrides(cfg, overrides)


def print_steady(steady: dict, keys=("amplitude", "granular_loss_per_cycle", "phase")) -> None:
    """Print the steady-state estimates of one point (:func:`jaxdamp.analysis.stats.summarise` arrays):
    mean ± SE over replicates, the detected start of the steady state, the batch-means error."""
    import numpy as np

    from jaxdamp.analysis.stats import format_estimate, unit

    a = steady[keys[0]]
    start = np.atleast_1d(a["start"]).ravel()
    ok = np.atleast_1d(a["stationary"]).ravel()
    R = len(start)
    print(f"steady state detected (MSER on per-period amplitude and dissipation) in "
          f"{int(ok.sum())} of {R} replicate(s); starts at t = "
          + ", ".join(f"{t:.3g}" if k else "never" for t, k in zip(start, ok)) + " s")
    for k in keys:
        e = steady[k]
        bse = np.atleast_1d(e["batch_se"]).ravel()
        extra = (f"; within-run batch-means SE {np.nanmean(bse):.2g}"
                 if np.isfinite(bse).any() else "")
        print(f"  {k} = {format_estimate(float(e['mean']), float(e['se']), int(e['n']), unit(k))}"
              + extra)


def cmd_run(args) -> int:
    from jaxdamp.studies.runner import run
    from jaxdamp.validation import validate

    cfg = validate(_run_config(args))
    R = _replicates(args)
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


def _replicates(args) -> int:
    R = getattr(args, "replicates", None)
    R = 1 if R is None else R
    if R < 1:
        raise ConfigError(f"--replicates {R}: need at least 1 independent bed")
    return R


def _float_list(text):
    try:
        return [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise ConfigError(f"expected a comma-separated list of numbers, got {text!r}") from None


def cmd_frf(args) -> int:
    import h5py
    import numpy as np

    from jaxdamp.analysis.response import RESIDUALS, fit_frf_replicates
    from jaxdamp.figures import frf_figure, save
    from jaxdamp.io.sweepfile import write_fit
    from jaxdamp.physics.model import grain_mass
    from jaxdamp.studies.grid import steady_or_window
    from jaxdamp.studies.sweep import sweep

    cfg = _base_config(args)
    overrides = list(args.set or [])
    if args.quick:
        overrides = ["numerics.duration=0.5", "numerics.settle_time=0.3", "numerics.chunk=0.1"] + overrides
    if args.duration is not None:
        overrides.append(f"numerics.duration={args.duration}")
    cfg = apply_overrides(cfg, overrides)
    if cfg.system not in ("primary", "impact"):
        raise ConfigError("jaxdamp frf needs system 'primary' (S1) or 'impact' (S3): an FRF is "
                          "the primary's response")
    impact = cfg.system == "impact"  # S3: one particle of mass impactor.mass, gap impactor.gap
    if args.frequencies:
        freqs = _float_list(args.frequencies)
    else:
        n = 6 if args.quick and args.n is None else (args.n or 30)
        if not 0 < args.fmin < args.fmax:
            raise ConfigError(f"--fmin {args.fmin} / --fmax {args.fmax}: need 0 < fmin < fmax")
        freqs = list(np.linspace(args.fmin, args.fmax, n))
    if any(f <= 0 for f in freqs):
        raise ConfigError(f"--frequencies: every frequency must be > 0 Hz, got {freqs}")
    axes = {"frequency": freqs}
    lz = _float_list(args.lz) if args.lz else None
    if lz:
        axes["box.Lz"] = lz
    R = _replicates(args)
    res = sweep(cfg, axes, out=args.out, resume=args.resume, progress=not args.no_progress,
                replicates=R)
    L = len(lz) if lz else 1
    p = cfg.primary
    if res.steady is not None:
        Zr, fallback = steady_or_window(res, "amplitude")
        Zr = Zr.reshape(len(freqs), L, R)
        if fallback:
            print(f"warning: {fallback} of {Zr.size} runs did not become stationary (MSER on "
                  "per-period amplitude and dissipation); their fixed-window amplitude is used "
                  "— run longer (--duration)")
    else:  # S3: deterministic, one realisation
        Zr = res.summary["amplitude"].reshape(len(freqs), L, 1)
    Z = Zr.mean(axis=-1)
    Z_se = Zr.std(axis=-1, ddof=1) / np.sqrt(R) if R >= 2 else None
    fits, lines, fit_all = [], [], {w: [] for w in RESIDUALS}
    for j in range(L):
        for w in RESIDUALS:
            fit_all[w].append(fit_frf_replicates(freqs, Zr[:, j], p.U, p.K, M0=p.M,
                                                 C0=max(p.C, 1.0), residuals=w))
        fr = fit_all[args.residuals][j]
        other = fit_all[[w for w in RESIDUALS if w != args.residuals][0]][j]
        fits.append((fr["M_ef"], fr["C_ef"]))
        label = (f"Lz = {lz[j]:g} m" if lz else f"gap = {cfg.impactor.gap:g} m" if impact
                 else f"Lz = {cfg.box.Lz:g} m")
        k = int(np.argmax(Z[:, j]))
        err = ((lambda e: f"± {e:.2g} (SE over R = {R})") if R >= 2 else
               (lambda e: f"± {e:.2g} (fit error, R = 1)"))
        eM = fr["se_M"] if R >= 2 else fr["fit_se_M"]
        eC = fr["se_C"] if R >= 2 else fr["fit_se_C"]
        lines.append(f"{label}: peak Z/U = {Z[k, j] / p.U:.4g} at {freqs[k]:.4g} Hz; "
                     f"{args.residuals} fit M_ef = {fr['M_ef']:.4g} {err(eM)} kg, "
                     f"C_ef = {fr['C_ef']:.4g} {err(eC)} N s/m (C_ef/C = {fr['C_ef'] / p.C:.3g}); "
                     f"{other['residuals']} fit: M_ef = {other['M_ef']:.4g}, "
                     f"C_ef = {other['C_ef']:.4g}")
    print("\n".join(lines))
    m_p = cfg.impactor.mass if impact else grain_mass(cfg)
    if args.out:
        with h5py.File(args.out, "a") as h:
            write_fit(h, fit_all, args.residuals)
        png = args.png or args.out.rsplit(".", 1)[0] + ".png"
        save(frf_figure(np.asarray(freqs), Z, lz or [None], p, m_p, fits,
                   title=(f"{cfg.name}: one particle, m = {m_p:.4g} kg, e = "
                          f"{cfg.impactor.restitution:g}" if impact else
                          f"{cfg.name}: N = {cfg.n_grains}")
                   + f", {res.summary['wall_time']:.0f} s wall"
                   + (f", mean of R = {R} beds ± 2 SE" if R > 1 else ""),
                   model="S3" if impact else "DEM", Z_se=Z_se), png)
        print(f"wrote {args.out} and {png}")
    return 0


def cmd_optimize(args) -> int:
    import json
    import math

    import h5py

    from jaxdamp.design import Objective, adaptive_scan, make_problem, optimize, trust_region
    from jaxdamp.design.surrogate import propose
    from jaxdamp.io import optimisation as optimisation_file

    cfg = apply_overrides(_base_config(args), list(args.set or []))
    band = tuple(_float_list(args.band)) if args.band else None
    objective = Objective(args.objective, frequency=args.frequency, band=band)
    impact = cfg.system == "impact"
    method = args.method or ("gradient" if impact else "trust")
    if impact and method == "trust":
        raise ConfigError("--method trust is the DEM's multi-fidelity search (S3 proposes, "
                          "the DEM corrects); for S3 use gradient or scan")
    if args.estimator == "windows" and method != "gradient":
        raise ConfigError("--estimator windows applies to --method gradient")
    if args.replicates is not None and args.replicates < 1:
        raise ConfigError(f"--replicates {args.replicates}: need at least 1")
    if args.budget is not None and args.budget <= 0:
        raise ConfigError(f"--budget {args.budget}: must be > 0 simulated system-seconds")
    over = dict(lr=args.lr, max_iter=args.max_iter, duration=args.duration)
    if not impact:
        over.update(estimator=args.estimator, h=args.h,
                    replicates=args.replicates if args.estimator == "steady" else None)
    elif args.replicates not in (None, 1):
        raise ConfigError("--replicates: the single-particle model (S3) is deterministic")
    prob, s = make_problem(cfg, objective, quick=args.quick, **over)
    lo, hi = prob.bounds()
    if args.lo is not None:
        lo = prob.from_lz(args.lo)
    if args.hi is not None:
        hi = prob.from_lz(args.hi)
    if not lo < hi:
        raise ConfigError(f"no feasible design: lower bound {lo:.5g} m ≥ upper bound {hi:.5g} m")
    var = prob.variable
    x0 = None
    if impact and args.gap0 is not None:
        x0 = args.gap0
    elif args.gap0 is not None:
        raise ConfigError("--gap0 applies to S3 (sanchez2012-impact); use --lz0 for the DEM")
    elif args.lz0 is not None:
        x0 = prob.from_lz(args.lz0)
    for name, x in (("--lz0/--gap0", x0),):
        if x is not None and not lo <= x <= hi:
            raise ConfigError(f"{name} = {prob.to_lz(x):.5g} m (Lz): outside the feasible range "
                              f"[{prob.to_lz(lo):.5g}, {prob.to_lz(hi):.5g}] m")
    what = "maximise" if objective.maximise else "minimise"
    freqs = ", ".join(f"{f:.4g}" for f in objective.frequencies(cfg))
    R = getattr(prob, "R", 1)
    print(f"{what} {objective.kind} [{objective.unit}] at {freqs} Hz over {var} in "
          f"[{lo:.4g}, {hi:.4g}] m by {method}" + (f", {R} replicates per point" if R > 1 else ""))
    progress = not args.no_progress
    sim_extra = 0.0
    if method == "gradient":
        x0 = 0.07 if x0 is None and not impact else x0
        x0 = prob.from_lz(0.07) if x0 is None else x0
        res = optimize(prob, x0, lr=s["lr"], decay=s["decay"], max_iter=s["max_iter"],
                       xtol=s["xtol"], lo=lo, hi=hi, out=args.out, progress=progress,
                       config_json=cfg.to_json(), budget=args.budget)
        opt, sim = res.optimum, res.sim_seconds
        x_best = res.x_average
        print(f"{len(res.history['x'])} iterates ({res.reason}); average of the last iterates "
              f"{var} = {x_best:.5g} m")
    else:
        if method == "trust" and x0 is None:
            p = propose(prob.config, objective, prob.bed_height, lo, hi)
            sim_extra = p["sim_seconds"]
            x0 = float(p["lz"])
            print(f"S3 surrogate proposes Lz = {x0:.5g} m ({sim_extra:.3g} simulated s of the "
                  "single-particle model)" + (" — on the bound" if p["at_bound"] else ""))
        echo = print if progress else None
        if method == "trust":
            sr = trust_region(prob, x0, lo, hi, echo=echo)
        else:
            sr = adaptive_scan(prob, lo, hi, echo=echo)
        opt, sim = sr.optimum, sr.sim_seconds + sim_extra
        x_best = opt.x
        if args.out:
            optimisation_file.write_search(args.out, cfg, objective, prob, sr, method, sim)
    if opt is not None:
        ci = (f" [{prob.to_lz(opt.lo):.5g}, {prob.to_lz(opt.hi):.5g}] m (95 %, jackknife over "
              f"{opt.replicates} replicates)" if opt.replicates > 1 else " (no replicates: no interval)")
        print(f"optimum Lz = {prob.to_lz(opt.x):.5g} m{ci}; fitted {objective.kind} = "
              f"{opt.value:.5g} {objective.unit}")
        if not opt.interior or min(abs(opt.x - lo), abs(opt.x - hi)) < 1e-9:
            print(f"warning: no interior optimum of {objective.kind} on the feasible range — it "
                  "lies on (or beyond) a bound; widen --lo/--hi or choose another objective")
    else:
        g = res.history["gradient"][-1] if method == "gradient" and len(res.history["x"]) else math.nan
        print(f"optimum Lz = {prob.to_lz(x_best):.5g} m ({var} = {x_best:.5g} m); "
              f"{objective.kind} = {res.value:.5g} {objective.unit}, last gradient {g:.3g} "
              f"(exact: no interval)")
    print(f"cost: {sim:.4g} simulated system-seconds" + (f" (of which S3 surrogate {sim_extra:.3g})"
                                                          if sim_extra else ""))
    if args.out:
        if opt is not None:
            with h5py.File(args.out, "a") as h:
                h.attrs["optimum"] = json.dumps(
                    {"lz": prob.to_lz(opt.x), "lo": prob.to_lz(opt.lo), "hi": prob.to_lz(opt.hi),
                     "se": opt.se, "interior": bool(opt.interior), "replicates": opt.replicates,
                     "sim_seconds": sim, "method": method})
        print(f"wrote {args.out}")
    return 0


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
    values = _float_list(text)
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
                         grain_radii(r.config), grain_species(r.config),
                         (r.config.box.Lx, r.config.box.Ly, r.config.box.Lz)))
    paths.append(save(phase_figure(cases, title), f"{stem}_phase.png"))
    if rows:
        paths.append(save(snapshot_grid_figure(rows, title), f"{stem}_snapshots.png"))
    return paths


def cmd_efficiency(args) -> int:
    import numpy as np

    from jaxdamp.cases import mixtures, presets
    from jaxdamp.studies import efficiency as ef

    amps = _amplitudes(args.amplitude) if args.amplitude else (
        [0.02, 0.03, 0.04] if args.quick else list(__import__("numpy").linspace(0.02, 0.04, 9)))
    periods = args.periods or (3 if args.quick else 50)
    transient = args.transient if args.transient is not None else (1 if args.quick else 10)
    sigmas = _float_list(args.sigma) if args.sigma else [None]
    if args.preset in mixtures.FAMILIES and args.config is None:
        if mixtures.FAMILIES[args.preset] is None and args.sigma:
            raise ConfigError("--sigma: the reference system (varela2023-reference) is "
                              "monodisperse; use varela2023-a, -b or -c")
        bases = [(s, presets.family(args.preset, s)) for s in sigmas]
    else:
        if args.sigma:
            raise ConfigError(f"--sigma applies to the binary-mixture families "
                              f"{', '.join(k for k, v in mixtures.FAMILIES.items() if v)}")
        bases = [(None, _base_config(args))]
    out = args.out
    stem = (args.png or out or "efficiency.png").rsplit(".", 1)[0]
    results = []
    for sigma, cfg in bases:
        cfg = apply_overrides(cfg, list(args.set or []))
        path = out
        if out and len(bases) > 1:
            path = f"{out.rsplit('.', 1)[0]}_sigma{sigma:g}.h5"
        label = cfg.name + (f", σ = {sigma:g}" if sigma is not None else "")
        print(f"{label}: {cfg.n_grains} grains, {len(amps)} amplitudes, "
              f"{transient} + {periods} periods at {cfg.frequency:g} Hz")
        R = _replicates(args)
        r = ef.measure(cfg, amps, periods=periods, transient=transient, out=path,
                       progress=not args.no_progress, replicates=R)
        s = r.summary
        print(f"  m = {s['mass'][0]:.4g} kg, dt = {r.config.numerics.dt:.4g} s, "
              f"{r.wall_time:.0f} s wall")
        print("  A_d [cm]  <E_d> mean ± std   fit     <E_d>/m [1/kg]  E_pp [J]  E_pw [J]  "
              "contacts  balance")
        for i, a in enumerate(r.amplitudes):
            print(f"  {a * 100:7.3f}  {s['E_d_mean'][i]:.4f} ± {s['E_d_std'][i]:.4f}  "
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


def cmd_presets(args) -> int:
    from jaxdamp.cases import presets

    if args.show:
        cfg = presets.get(args.show)
        print(to_toml(cfg.to_dict()))
        return 0
    for name, line in presets.describe():
        print(f"{name:28s} {line}")
    return 0


def cmd_info(args) -> int:
    from jaxdamp.io import describe

    print(describe(args.file))
    return 0


PLOT_KINDS = {
    "band": "run file: floor and lid of the box, the band between the lowest and highest grain "
            "centre, the centre of mass, and the force of the grains on the box, versus time "
            "(default window: the last few drive periods)",
    "energy": "run file: cumulative work channels (input, primary damper, the four granular "
              "losses) and the energy-balance residual, versus time",
    "frf": "sweep file (jaxdamp frf): amplitude ratio Z/U versus frequency per Lz, with the "
           "analytic FRFs and the fitted M_ef, C_ef",
    "snapshot": "run file: 3-D view of the grains at one snapshot (--frame), box wireframe",
    "poincare": "run file: stroboscopic section (z_cm, vz_cm) of the bed's centre of mass once "
                "per drive period",
}


def cmd_plot(args) -> int:
    import os

    from jaxdamp import figures

    stem = os.path.splitext(os.fspath(args.file))[0]
    out = args.out or f"{stem}_{args.kind}.png"
    if args.kind == "frf":
        if args.t0 is not None or args.t1 is not None:
            raise ConfigError("--t0/--t1 do not apply to --kind frf (a sweep's FRF has no time axis)")
        fig = figures.frf_from_file(args.file)
    elif args.kind == "band":
        fig = figures.band_from_file(args.file, args.t0, args.t1)
    elif args.kind == "energy":
        fig = figures.energy_from_file(args.file, args.t0, args.t1)
    elif args.kind == "snapshot":
        fig = figures.snapshot_from_file(args.file, args.frame, args.color)
    else:
        fig = figures.poincare_from_file(args.file, args.t0, args.t1, args.phase)
    figures.save(fig, out)
    print(f"wrote {out}")
    return 0


def cmd_export(args) -> int:
    import os

    from jaxdamp.io.export import export

    if args.format in ("gif", "mp4"):
        from jaxdamp.figures import animate

        out = args.out or os.path.splitext(os.fspath(args.file))[0] + "." + args.format
        if os.path.splitext(out)[1].lower() != "." + args.format:
            raise ConfigError(f"--out {out}: --format {args.format} writes a .{args.format} file")
        animate(args.file, out, every=args.every, fps=args.fps, color=args.color)
        print(f"wrote {out}")
        return 0
    paths = export(args.file, args.format, args.out, args.every)
    if args.format == "vtk":
        print(f"wrote {paths[0]} indexing {len(paths) - 1} frames ({paths[1]} …)")
    else:
        print(f"wrote {paths[0]}")
    return 0


def to_toml(data: dict, prefix: str = "") -> str:
    """Minimal TOML writer for configuration trees (tables, arrays of tables, scalars)."""
    lines, tables = [], []
    for key, value in data.items():
        if isinstance(value, dict):
            tables.append((key, value))
        elif isinstance(value, (list, tuple)) and value and isinstance(value[0], dict):
            tables.append((key, list(value)))
        elif value is None:
            lines.append(f"# {key} = (unset)")
        else:
            lines.append(f"{key} = {_toml_value(value)}")
    out = "\n".join(lines)
    for key, value in tables:
        full = f"{prefix}{key}"
        if isinstance(value, list):
            for item in value:
                out += f"\n\n[[{full}]]\n" + to_toml(item, f"{full}.").lstrip("\n")
        else:
            out += f"\n\n[{full}]\n" + to_toml(value, f"{full}.").lstrip("\n")
    return out.strip("\n") + ("\n" if not prefix else "")


def _toml_value(v):
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(v)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="jaxdamp",
        description="Simulate granular (particle) dampers with a JAX discrete-element model.",
        epilog="Run `jaxdamp COMMAND --help` for each command's options and examples.",
    )
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser(
        "run", help="simulate one damper at one frequency and write an HDF5 run file",
        description="Settle the grains, drive the system at one frequency and record it.",
        epilog=EPILOG_RUN, formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    r.add_argument("--preset", help="a named reference case (list: `jaxdamp presets`)")
    r.add_argument("--config", metavar="FILE", help="TOML configuration (overrides the preset)")
    r.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="override one value by dotted key (repeatable), e.g. box.Lz=0.1")
    r.add_argument("--frequency", type=float, metavar="HZ", help="excitation frequency f [Hz]")
    r.add_argument("--duration", type=float, metavar="S", help="simulated time after settling [s]")
    r.add_argument("--seed", type=int, help="seed of radii and lattice jitter")
    r.add_argument("--out", metavar="FILE.h5", help="output HDF5 file (default: none)")
    r.add_argument("--quick", action="store_true",
                   help="short demo run (1 s driven after settling, under a minute on 2 cores)")
    r.add_argument("--resume", action="store_true", help="continue --out from its checkpoint")
    r.add_argument("--replicates", type=int, metavar="R",
                   help="independent beds (seeds seed..seed+R-1) run in one batch (default 1); "
                        "steady-state numbers get mean ± standard error over them and the file "
                        "is a sweep file of one point")
    r.add_argument("--no-progress", action="store_true", help="no progress bar")
    r.set_defaults(func=cmd_run)

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
    fr.add_argument("--fmin", type=float, default=5.0, help="lowest frequency [Hz] (default 5)")
    fr.add_argument("--fmax", type=float, default=25.0, help="highest frequency [Hz] (default 25)")
    fr.add_argument("--n", type=int, help="number of frequencies (default 30; 6 with --quick)")
    fr.add_argument("--frequencies", metavar="F1,F2,...", help="explicit list of frequencies [Hz]")
    fr.add_argument("--lz", metavar="LZ1,LZ2,...", help="second axis: box heights [m]")
    fr.add_argument("--duration", type=float, help="simulated time per point [s]")
    fr.add_argument("--out", metavar="FILE.h5")
    fr.add_argument("--png", metavar="FILE.png", help="figure (default: next to --out)")
    fr.add_argument("--quick", action="store_true", help="6 frequencies, 0.5 s each")
    fr.add_argument("--resume", action="store_true")
    fr.add_argument("--replicates", type=int, metavar="R",
                    help="independent beds per point, run in the same batch (default 1): "
                         "amplitudes and M_ef, C_ef get mean ± standard error over them")
    fr.add_argument("--residuals", choices=["relative", "absolute"], default="relative",
                    help="FRF-fit weighting that is reported first and drawn: relative "
                         "(Z_model/Z - 1, default) or absolute ((Z_model - Z)/U, dominated by "
                         "the resonance, as the thesis describes); both are stored in /fit")
    fr.add_argument("--no-progress", action="store_true")
    fr.set_defaults(func=cmd_frf)

    op = sub.add_parser(
        "optimize", help="optimise the box height Lz (DEM) or the gap (S3), with an interval",
        description="Find the box height that optimises a design objective, with a 95 %% "
        "confidence interval and the simulated system-seconds it cost. "
        "DEM presets (S1, e.g. sanchez2012-optimal): every evaluation runs R independent "
        "beds (--replicates) in one batch; the start of the steady state is detected from the "
        "data. Methods: 'trust' (default) starts from the optimum of the single-particle "
        "surrogate (S3, seconds) and corrects it with DEM stencils pooled into a quadratic "
        "response surface; 'scan' is the batched baseline (coarse batch, finer batch in the "
        "bracket, quadratic fit); 'gradient' runs optax Adam on central differences Lz +- h "
        "(common random numbers inside each pair, independent pairs across replicates). "
        "S3 presets (one particle, smooth model): the gap = Lz - h_bed; 'gradient' (default) "
        "uses exact steady-state derivatives on the stable periodic orbit (implicit "
        "differentiation of the one-period map) and stops with a message where there is none.",
        epilog=textwrap.dedent("""\
            examples:
              jaxdamp optimize --preset sanchez2012-optimal --replicates 4 --out opt.h5
                  DEM, 250 grains, C_eq at f0, S3 proposal + trust region
              jaxdamp optimize --preset sanchez2012-optimal --method scan --replicates 4
              jaxdamp optimize --preset sanchez2012-impact --quick --out s3_opt.h5
              jaxdamp optimize --preset sanchez2012-impact --objective band --band 14,15.16,16

            objectives:
              damping      (default) equivalent viscous damping added by the grains at
                           --frequency (default f0 = sqrt(K/M)/2pi), C_eq = E/(pi Omega Z^2)
                           [N s/m]; maximised
              amplitude    steady-state amplitude Z at --frequency; minimised
              band         smooth maximum (p-norm, p = 16) of Z over --band frequencies
                           (default 9 points over f0 +- 10 %); minimised
              dissipation  granular dissipation per period at --frequency; maximised. On the
                           thesis' damper it grows with Lz up to every bound tried: expect a
                           warning that the optimum lies on the bound.

            output: the optimum with its interval (jackknife over replicates of the response
            surface), whether it is interior, and the simulated system-seconds; --out writes
            an HDF5 log (schema in docs/output.md)."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    op.add_argument("--preset", help="sanchez2012-optimal (DEM) or sanchez2012-impact (S3), ...")
    op.add_argument("--config", metavar="FILE")
    op.add_argument("--set", action="append", metavar="KEY=VALUE")
    op.add_argument("--objective", choices=["damping", "amplitude", "band", "dissipation"],
                    default="damping", help="what to optimise (default damping, C_eq)")
    op.add_argument("--frequency", type=float, metavar="HZ",
                    help="frequency of damping/amplitude/dissipation (default: the primary's f0)")
    op.add_argument("--band", metavar="F1,F2,...", help="frequencies of the band objective [Hz]")
    op.add_argument("--method", choices=["trust", "scan", "gradient"],
                    help="search (DEM default trust, S3 default gradient)")
    op.add_argument("--replicates", type=int, metavar="R",
                    help="DEM: independent beds per evaluation (default 4; quick 2)")
    op.add_argument("--budget", type=float, metavar="SECONDS",
                    help="gradient method: stop before exceeding this many simulated "
                         "system-seconds")
    op.add_argument("--lz0", type=float,
                    help="starting box height [m] (trust: default the S3 proposal; gradient: 0.07)")
    op.add_argument("--gap0", type=float, help="S3: starting gap [m] (default lz0 - h_bed)")
    op.add_argument("--lo", type=float, metavar="LZ", help="lowest Lz [m] (default bed + 5 mm)")
    op.add_argument("--hi", type=float, metavar="LZ", help="highest Lz [m] (default 0.4 DEM)")
    op.add_argument("--lr", type=float, help="gradient: initial learning rate [m]")
    op.add_argument("--max-iter", type=int, help="gradient: most iterates")
    op.add_argument("--estimator", choices=["steady", "windows"], default="steady",
                    help="DEM gradient: replicated steady states (default) or pathwise "
                         "derivatives over short windows (biased on the chaotic bed; kept for "
                         "the experiment)")
    op.add_argument("--h", type=float, metavar="M",
                    help="DEM: half-step of the central difference [m] (0.005)")
    op.add_argument("--duration", type=float, metavar="S",
                    help="simulated time per evaluation [s] (DEM 3, quick 0.6; S3 run 3)")
    op.add_argument("--out", metavar="FILE.h5", help="log (HDF5)")
    op.add_argument("--quick", action="store_true",
                    help="small settings for a demo (S3 ~30 s; DEM 2 replicates, 0.6 s runs)")
    op.add_argument("--no-progress", action="store_true")
    op.set_defaults(func=cmd_optimize)

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
            quarter points, checkpoint; an interrupted run resumes when re-run) with an
            /efficiency group (summary, per_period, phase; units in attributes), and PNGs:
            <out>.png (<E_d>/m vs A_d), <out>_phase.png, <out>_snapshots.png."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ef.add_argument("--preset", help="varela2023-reference|a|b|c or any driven-box preset")
    ef.add_argument("--config", metavar="FILE")
    ef.add_argument("--set", action="append", metavar="KEY=VALUE")
    ef.add_argument("--sigma", metavar="S1,S2,...", help="size ratio(s) of the mixture, in (0, 1]")
    ef.add_argument("--amplitude", metavar="A0:A1:N|A1,A2,...",
                    help="drive amplitudes [m] (default 0.02:0.04:9; quick 0.02,0.03,0.04)")
    ef.add_argument("--periods", type=int, help="analysed drive periods (default 50; quick 3)")
    ef.add_argument("--transient", type=int, help="periods dropped first (default 10; quick 1)")
    ef.add_argument("--out", metavar="FILE.h5", help="sweep file with the /efficiency analysis")
    ef.add_argument("--png", metavar="FILE.png", help="figure stem (default: next to --out)")
    ef.add_argument("--quick", action="store_true", help="3 amplitudes, 1 + 3 periods")
    ef.add_argument("--replicates", type=int, metavar="R",
                    help="independent beds per amplitude in the same batch (default 1): <E_d> "
                         "gets mean ± standard error over them")
    ef.add_argument("--no-progress", action="store_true")
    ef.set_defaults(func=cmd_efficiency)

    pr = sub.add_parser("presets", help="list the reference cases (or --show one as TOML)")
    pr.add_argument("--show", metavar="NAME", help="print the full configuration of a preset")
    pr.set_defaults(func=cmd_presets)

    i = sub.add_parser("info", help="summarise a run file")
    i.add_argument("file")
    i.set_defaults(func=cmd_info)

    pl = sub.add_parser(
        "plot", help="figures from a run or sweep file (band, energy, frf, snapshot, poincare)",
        description="Draw one figure from an HDF5 output file and write it as PNG.",
        epilog="kinds:\n" + "\n".join(
            textwrap.fill(f"{k}: {v}", 92, initial_indent="  ", subsequent_indent="      ")
            for k, v in PLOT_KINDS.items()) + textwrap.dedent("""

            examples:
              jaxdamp plot run.h5 --kind band                 (writes run_band.png)
              jaxdamp plot run.h5 --kind band --t0 0.5 --t1 0.7 --out bed.png
              jaxdamp plot run.h5 --kind snapshot --frame 0 --color height
              jaxdamp plot frf.h5 --kind frf --out frf.png
            Run files come from `jaxdamp run --out`, sweep files from `jaxdamp frf --out`
            (`jaxdamp info FILE` tells which); times are in seconds from the start of the drive."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    pl.add_argument("file", metavar="FILE.h5", help="run file or sweep file")
    pl.add_argument("--kind", required=True, choices=list(PLOT_KINDS), help="which figure")
    pl.add_argument("--out", metavar="FILE.png", help="output image (default: FILE_<kind>.png)")
    pl.add_argument("--t0", type=float, metavar="S", help="start of the time window [s] "
                    "(band: default the last few drive periods; energy, poincare: the whole run)")
    pl.add_argument("--t1", type=float, metavar="S", help="end of the time window [s]")
    pl.add_argument("--frame", type=int, default=-1, metavar="K",
                    help="snapshot index for --kind snapshot (default -1, the last)")
    pl.add_argument("--color", choices=["species", "height"], default="species",
                    help="grain colour for snapshot: species, or height above the floor")
    pl.add_argument("--phase", type=float, default=0.0, metavar="RAD",
                    help="poincare: section phase within the drive period (0 = drive maximum)")
    pl.set_defaults(func=cmd_plot)

    ex = sub.add_parser(
        "export", help="trajectories of a run file for OVITO / ParaView, or an animation",
        description="Write the grain snapshots of a run file (/snapshots, one after every "
        "chunk) for external viewers.",
        epilog=textwrap.dedent("""\
            formats:
              xyz  one extended-XYZ file, one frame per snapshot (OVITO, ASE): species, position,
                   radius, orientation quaternion (x, y, z, w); the box as Lattice + Origin.
              vtk  one legacy-VTK polydata file per snapshot (FILE_0000.vtk, ...) with radius,
                   species and orientation point data, a ParaView .pvd collection indexing them
                   by time, and a .vtk.series file (ParaView >= 5.5) with the same times.
              gif  animation through Pillow;  mp4  animation through ffmpeg (needs it on PATH).
            examples:
              jaxdamp export run.h5 --format xyz                 (writes run.xyz)
              jaxdamp export run.h5 --format vtk --out vtk/run.pvd --every 2
              jaxdamp export run.h5 --format gif --fps 8
            Positions are in metres in the lab frame (the box moves: its floor is z_box)."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    ex.add_argument("file", metavar="FILE.h5", help="run file (jaxdamp run --out)")
    ex.add_argument("--format", required=True, choices=["xyz", "vtk", "gif", "mp4"])
    ex.add_argument("--out", metavar="PATH", help="output file (.xyz, .pvd, .gif, .mp4; "
                    "default: next to FILE)")
    ex.add_argument("--every", type=int, default=1, metavar="K", help="every K-th snapshot")
    ex.add_argument("--fps", type=int, default=10, help="frames per second (gif, mp4)")
    ex.add_argument("--color", choices=["species", "height"], default="species",
                    help="grain colour in animations")
    ex.set_defaults(func=cmd_export)
    return p


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except ConfigError as err:
        print(f"jaxdamp: error: {err}", file=sys.stderr)
        return 2
    except FloatingPointError as err:
        print(f"jaxdamp: {err}", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
