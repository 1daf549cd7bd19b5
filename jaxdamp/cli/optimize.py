"""``jaxdamp optimize``: design optimisation of the box height (DEM) or gap (S3)."""

from __future__ import annotations

import argparse
import math
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
)
from jaxdamp.config import ConfigError, apply_overrides


def band_option(text: str | None, objective: str) -> tuple | None:
    """The ``--band`` frequencies [Hz]: ``None`` when not given; refused (one line naming the
    option) when empty, not numbers, not finite and > 0, or given to another objective."""
    if text is None:
        return None
    if objective != "band":
        raise ConfigError(f"--band applies to --objective band (this run optimises "
                          f"{objective}); give --frequency for a single-frequency objective")
    what, example = "frequencies [Hz], each a finite number > 0", "--band 14,15.16,16"
    values = float_list(text, "--band", what, example)
    if not all(0 < v < math.inf for v in values):
        raise ConfigError(f"--band {text!r}: expected a comma-separated list of {what}, "
                          f"e.g. {example}")
    return tuple(values)


def envelope_option(args):
    """The :class:`~jaxdamp.design.envelope.Envelope` of ``--envelope-frequencies`` and
    ``--envelope-levels`` (both or neither), ``--statistic`` and the budgets; ``None`` without
    them. Refused, naming the option, beside a single-point objective's options."""
    from jaxdamp.design.envelope import Envelope

    given = [f for f, v in (("--envelope-frequencies", args.envelope_frequencies),
                            ("--envelope-levels", args.envelope_levels)) if v is not None]
    rest = [f for f, v in (("--statistic", args.statistic), ("--mass-budget", args.mass_budget),
                           ("--volume-budget", args.volume_budget)) if v is not None]
    if not given:
        if rest:
            raise ConfigError(f"{rest[0]} applies to an envelope: give --envelope-frequencies "
                              "and --envelope-levels")
        return None
    if len(given) == 1:
        other = ({"--envelope-frequencies", "--envelope-levels"} - set(given)).pop()
        raise ConfigError(f"{given[0]} needs {other} too (the envelope is every frequency at "
                          "every level)")
    for flag, val, default in (("--objective", args.objective, "damping"),
                               ("--frequency", args.frequency, None), ("--band", args.band, None)):
        if val != default:
            raise ConfigError(f"{flag} is a single-point objective's; an envelope scores C_eq "
                              "at each of its points (--statistic worst or mean)")
    f = float_list(args.envelope_frequencies, "--envelope-frequencies", "frequencies [Hz]",
                   "13.5,15.16,16.5")
    u = float_list(args.envelope_levels, "--envelope-levels", "base amplitudes U [m]",
                   "0.0015,0.003,0.0045")
    return Envelope(f, u, statistic=args.statistic or "worst", mass_budget=args.mass_budget,
                    volume_budget=args.volume_budget)


def cmd_optimize(args) -> int:
    import json

    cfg = command_config(args)
    band = band_option(args.band, args.objective)
    check_outputs([args.out], args.overwrite)

    import h5py
    import numpy as np

    from jaxdamp.design import Objective, adaptive_scan, make_problem, optimize, trust_region
    from jaxdamp.design.status import EXIT_FAILED
    from jaxdamp.design.surrogate import descend, propose
    from jaxdamp.io import optimisation as optimisation_file

    objective = Objective(args.objective, frequency=args.frequency, band=band)
    impact = cfg.system == "impact"
    names = tuple(v.strip() for v in (args.vars or "Lz").split(",") if v.strip())
    envelope = envelope_option(args)
    if names != ("Lz",) or args.method in ("spsa", "random", "batch") or envelope is not None:
        return _cmd_design(args, cfg, objective, names, envelope)
    if args.bounds:
        raise ConfigError("--bounds applies to several design variables (--vars); for Lz "
                          "alone use --lo/--hi")
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
    if not impact:  # bars of settling and of every DEM batch; the gradient method has its own
        over.update(estimator=args.estimator, h=args.h,
                    replicates=args.replicates if args.estimator == "steady" else None,
                    progress=not args.no_progress and method != "gradient")
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
    if x0 is not None and not lo <= x0 <= hi:  # refused, never moved to the bound
        name, given = ("--gap0", args.gap0) if args.gap0 is not None else ("--lz0", args.lz0)
        lz_range = f"Lz in [{prob.to_lz(lo):.5g}, {prob.to_lz(hi):.5g}] m"
        raise ConfigError(
            f"{name} = {given:.5g} m: outside the feasible range "
            + (f"of the gap [{lo:.5g}, {hi:.5g}] m ({lz_range})" if var == "gap" else lz_range)
            + (f"; the settled bed is {prob.bed_height:.5g} m high"
               if getattr(prob, "bed_height", None) else "")
            + " — nothing is clamped: give a start inside it")
    what = "maximise" if objective.maximise else "minimise"
    freqs = ", ".join(f"{f:.4g}" for f in objective.frequencies(cfg))
    R = getattr(prob, "R", 1)
    print(f"{what} {objective.kind} [{objective.unit}] at {freqs} Hz over {var} in "
          f"[{lo:.4g}, {hi:.4g}] m by {method}" + (f", {R} replicates per point" if R > 1 else ""))
    progress = not args.no_progress
    sim_extra = 0.0
    unit = objective.unit
    if method == "gradient":
        x0 = 0.07 if x0 is None and not impact else x0
        x0 = prob.from_lz(0.07) if x0 is None else x0
        res = optimize(prob, x0, lr=s["lr"], decay=s["decay"], max_iter=s["max_iter"],
                       xtol=s["xtol"], lo=lo, hi=hi, out=args.out, progress=progress,
                       config_json=cfg.to_json(), budget=args.budget)
        opt, sim, status = res.optimum, res.sim_seconds, res.status
        g = res.history["gradient"]
        last = float(g[np.isfinite(g)][-1]) if np.isfinite(g).any() else None
        if status.converged:
            x = res.design
            value = (f"{objective.kind} = {res.value:.5g} {unit}" if x == res.x else
                     f"(the average of the last iterates; {objective.kind} at the last = "
                     f"{pm(res.value, res.history['objective_se'][-1], unit=unit)})")
            print(f"optimum Lz = {prob.to_lz(x):.5g} m"
                  + (f" ({var} = {x:.5g} m)" if var != "Lz" else "") + f": {value}; "
                  f"converged after {status.iterations} iterations: {status.reason}")
        else:
            print(_not_an_optimum(status, prob, objective, res.best, last))
        if opt is not None:
            print(f"response surface of every evaluation: Lz = {prob.to_lz(opt.x):.5g} m"
                  + _interval(prob, opt) + f", fitted {objective.kind} = {opt.value:.5g} "
                  f"{unit}" + ("" if opt.interior else " (not interior: an extrapolation)"))
    else:
        if method == "trust" and x0 is None:
            p = propose(prob.config, objective, prob.bed_height, lo, hi)
            sim_extra = p["sim_seconds"]
            x0 = float(p["lz"])
            print(f"S3 surrogate proposes Lz = {x0:.5g} m ({sim_extra:.3g} simulated s of the "
                  "single-particle model)" + (" — on the bound" if p["at_bound"] else ""))
        elif method == "trust":  # from the user's start: exact-gradient descent on S3
            p = descend(prob.config, objective, prob.bed_height, x0, lo, hi)
            sim_extra = p["sim_seconds"]
            st = p["status"]
            print(f"S3 surrogate from Lz0 = {x0:.5g} m: "
                  + (f"optimum Lz = {p['lz']:.5g} m" if st.converged else
                     f"{st.headline()}, best iterate Lz = {p['lz']:.5g} m")
                  + f" after {p['iterates']} exact-gradient iterates ({p['fallbacks']} without "
                  f"a stable orbit, central differences of long averages there; {st.reason}; "
                  f"{sim_extra:.3g} simulated s of the single-particle model); the DEM search "
                  "starts there")
            x0 = p["lz"]
        echo = print if progress else None
        if method == "trust":
            sr = trust_region(prob, x0, lo, hi, echo=echo)
        else:
            sr = adaptive_scan(prob, lo, hi, echo=echo)
        opt, sim, status = sr.optimum, sr.sim_seconds, sr.status
        if args.out:
            optimisation_file.write_search(args.out, cfg, objective, prob, sr, method, sim)
        if status.converged:
            print(f"optimum Lz = {prob.to_lz(opt.x):.5g} m{_interval(prob, opt)}; fitted "
                  f"{objective.kind} = {opt.value:.5g} {unit}; converged after "
                  f"{status.iterations} rounds: {status.reason}")
            if not opt.interior or min(abs(opt.x - lo), abs(opt.x - hi)) < 1e-9:
                print(f"warning: no interior optimum of {objective.kind} on the feasible range "
                      "— it lies on (or beyond) a bound; widen --lo/--hi or choose another "
                      "objective")
        else:
            best = None
            if np.isfinite(sr.mean).any():
                k = int(np.nanargmax(sr.mean) if objective.maximise else np.nanargmin(sr.mean))
                best = {"x": float(sr.x[k]), "value": float(sr.mean[k]),
                        "value_se": float(sr.se[k])}
            print(_not_an_optimum(status, prob, objective, best, None, "best evaluated point"))
    model = "single-particle" if impact else "DEM"
    print(f"cost: {sim:.4g} simulated {model} system-seconds"
          + (f", plus {sim_extra:.3g} s of the single-particle surrogate (a point mass: "
             "negligible next to a DEM second)" if sim_extra else ""))
    evals = getattr(prob, "evaluations", None)
    if evals:
        runs = sum(e["J"].size * len(prob.freqs) for e in evals)
        bad = sum(e["not_stationary"] for e in evals)
        starts = np.concatenate([np.ravel(e["start"]) for e in evals])
        print(f"steady state detected from the data (MSER on per-period amplitude and "
              f"dissipation) in {runs - bad} of {runs} runs; common window per bed from "
              f"t = {starts.min():.3g}–{starts.max():.3g} s"
              + (" — run longer (--duration) for the rest" if bad else ""))
    if args.out:
        if opt is not None:
            with h5py.File(args.out, "a") as h:
                h.attrs["optimum"] = json.dumps(
                    {"lz": prob.to_lz(opt.x), "lo": prob.to_lz(opt.lo), "hi": prob.to_lz(opt.hi),
                     "se": opt.se, "interior": bool(opt.interior), "replicates": opt.replicates,
                     "sim_seconds": sim, "surrogate_sim_seconds": sim_extra,
                     "method": method, "status": status.state})
        print(f"wrote {args.out}")
    return EXIT_FAILED if status.failed else 0


def _interval(prob, opt) -> str:
    """`` [lo, hi] m (95 %, jackknife over R replicates)`` of a response-surface optimum."""
    if opt.replicates > 1:
        return (f" [{prob.to_lz(opt.lo):.5g}, {prob.to_lz(opt.hi):.5g}] m (95 %, jackknife over "
                f"{opt.replicates} replicates)")
    return " (no replicates: no interval)"


def _not_an_optimum(status, prob, objective, best, gradient, what="best iterate") -> str:
    """The line of a result that is not an optimum (:class:`jaxdamp.design.status.Status`):
    ``NOT CONVERGED after N iterations (reason; last gradient g); best iterate …`` or
    ``FAILED: reason; …``."""
    from jaxdamp.analysis.stats import format_estimate

    var, unit = prob.variable, objective.unit
    grad = "" if gradient is None else f"; last gradient {gradient:.3g} {unit} per m"
    if best is None:
        where = "no iterate with a finite objective"
    else:
        R = getattr(prob, "R", 1)
        value = (format_estimate(best["value"], best["value_se"], R, unit)
                 if best["value_se"] > 0 else f"{best['value']:.5g} {unit}")
        where = (f"{what} Lz = {prob.to_lz(best['x']):.5g} m"
                 + (f" ({var} = {best['x']:.5g} m)" if var != "Lz" else "")
                 + f": {objective.kind} = {value}")
    if status.failed:
        return f"FAILED: {status.reason}{grad}; before it, {where} — not an optimum"
    return f"{status.headline()} ({status.reason}{grad}); {where} — not an optimum"


def _cmd_design(args, cfg, objective, names, envelope=None) -> int:
    """Several design variables (``--vars Lz,base,friction``) or an operating envelope
    (``--envelope-frequencies``, ``--envelope-levels``): SPSA, Latin-hypercube or the batched
    Gaussian-process search on the DEM, then a confirmation on fresh beds of the found design
    next to the start."""
    import numpy as np

    from jaxdamp.design import DEFAULTS
    from jaxdamp.design.bayes import batch_search
    from jaxdamp.design.envelope import EnvelopeProblem
    from jaxdamp.design.space import DesignProblem, DesignSpace, parse_bounds
    from jaxdamp.design.spsa import random_search, spsa
    from jaxdamp.design.status import EXIT_FAILED
    from jaxdamp.io import optimisation as optimisation_file

    if cfg.system != "primary":
        raise ConfigError("--vars and --envelope-*: design variables and envelopes need a DEM "
                          "preset with a primary (S1, e.g. sanchez2012-optimal)")
    method = args.method or ("batch" if envelope is not None else "spsa")
    if method not in ("spsa", "random", "batch"):
        raise ConfigError(f"--method {method}: with several design variables or an envelope "
                          "use spsa, random or batch")
    if method == "batch" and args.budget is not None:
        raise ConfigError("--budget applies to spsa and random; the batch search spends "
                          "--max-iter batches after its start (DEFAULTS)")
    for flag, val in (("--lo", args.lo), ("--hi", args.hi), ("--gap0", args.gap0),
                      ("--h", args.h), ("--lr", args.lr)):
        if val is not None:
            raise ConfigError(f"{flag} applies to Lz alone; with --vars use --bounds "
                              "NAME=LO:HI and --x0")
    if args.estimator != "steady":
        raise ConfigError("--estimator windows applies to Lz alone")
    s = dict(DEFAULTS["design-quick" if args.quick else "design"])
    for key, val in (("replicates", args.replicates), ("duration", args.duration),
                     ("rounds" if method == "batch" else "max_iter", args.max_iter)):
        if val is not None:
            if val <= 0:
                raise ConfigError(f"--{key.replace('_', '-')} {val}: must be > 0")
            s[key] = val
    if args.budget is not None and args.budget <= 0:
        raise ConfigError(f"--budget {args.budget}: must be > 0 simulated system-seconds")
    cfg = apply_overrides(cfg, {"numerics.settle_time": s["settle_time"]})
    bounds = parse_bounds(args.bounds)
    space = DesignSpace.of(cfg, names, bounds)  # refuse bad input before any compute
    discrete = [v.name for v in space.variables if v.kind != "real"]
    if method == "spsa" and discrete:
        raise ConfigError(f"--method spsa perturbs continuous variables; {', '.join(discrete)} "
                          "take whole values: use --method batch (or random)")
    if args.x0:
        x0 = np.asarray(float_list(args.x0, "--x0"), float)
        if len(x0) != space.dim:
            raise ConfigError(f"--x0: {len(x0)} values for {space.dim} variables "
                              f"({','.join(names)})")
        for n, v, a, b in zip(names, x0, space.lo, space.hi):
            if not a <= v <= b:
                raise ConfigError(f"--x0 {n} = {v:.5g}: outside its bounds [{a:.5g}, {b:.5g}]")
    else:  # the preset's design, moved into the bounds if they exclude it
        x0 = np.clip(space.value(), space.lo, space.hi)
    if envelope is not None:
        prob = EnvelopeProblem(cfg, envelope, names, bounds=bounds, duration=s["duration"],
                               seed=cfg.numerics.seed, progress=False)
        start_ok, which = prob.feasible(x0)
        if not start_ok and args.x0:
            bad = next(k for k, v in which.items() if not v)
            raise ConfigError(f"--x0: outside the envelope's {bad.replace('_', '-')}")
        target = (f"the {envelope.statistic} C_eq [N s/m] over {len(envelope.points)} points ("
                  + ", ".join(f"{f:.4g}" for f in envelope.frequencies) + " Hz × U = "
                  + ", ".join(f"{u:.4g}" for u in envelope.levels) + " m)")
    else:
        prob = DesignProblem(cfg, objective, names, bounds=bounds, duration=s["duration"],
                             seed=cfg.numerics.seed, progress=False)
        start_ok = True
        target = (f"{objective.kind} [{objective.unit}] at "
                  + ", ".join(f"{f:.4g}" for f in prob.freqs) + " Hz")
    space = prob.space
    what = "maximise" if objective.maximise else "minimise"
    print(f"{what} {target} over "
          + ", ".join(f"{n} in [{a:.4g}, {b:.4g}]" for n, a, b in zip(names, space.lo, space.hi))
          + f" by {method}; " + (f"{s['pairs']} pairs (own direction and bed) per iterate"
                                 if method == "spsa" else f"{s['replicates']} beds per design")
          + f", {s['duration']:g} s runs")
    per_iter = 2 * s["pairs"] * prob.cost_per_system()
    budget = args.budget
    if method == "spsa":
        res = spsa(prob, x0, pairs=s["pairs"], c=s["c"], lr=s["lr"], decay=s["decay"],
                   max_iter=s["max_iter"],
                   budget=budget, seed=cfg.numerics.seed, progress=not args.no_progress)
        design, found = res.x_average, "average of the last iterates"
    elif method == "batch":
        res = batch_search(prob, n_start=s["n_start"], batch=s["batch"], rounds=s["rounds"],
                           replicates=s["replicates"], seed=cfg.numerics.seed,
                           progress=None if args.no_progress else print)
        design, found = res.best_x, "the surrogate's best run design"
    else:
        budget = budget or s["max_iter"] * per_iter
        res = random_search(prob, budget, replicates=s["replicates"], seed=cfg.numerics.seed)
        design, found = np.asarray(res.best["x"]), "best of the Latin hypercube"
        print(f"{len(res.X)} designs × {s['replicates']} beds in one batch")
    status = res.status
    fmt = lambda x: ", ".join(space.label(x))  # noqa: E731
    search_cost = prob.sim_seconds
    if status.failed:
        print(f"FAILED: {status.reason} — no design to confirm")
        if args.out:
            optimisation_file.write_design(args.out, cfg, objective, prob, method, res, None,
                                           dict(s, budget=budget, x0=list(map(float, x0))))
            print(f"wrote {args.out}")
        return EXIT_FAILED
    if status.converged:
        print(f"optimum ({found}): {fmt(design)}; converged after {status.iterations} "
              f"iterations: {status.reason}")
    else:
        print(f"{status.headline()} ({status.reason}); {found}: {fmt(design)} — not an "
              "optimum")
    R = s["confirm"]
    X = np.stack([design, x0]) if start_ok else design[None]
    conf = prob.evaluate(X, R)  # fresh beds: no winner's curse
    conf.update(X=X, labels=["found", "start"][:len(X)])
    kind = f"{envelope.statistic} C_eq" if envelope is not None else objective.kind
    print(f"confirmed on {R} fresh beds (95 %): {kind} = "
          f"{pm(conf['mean'][0], conf['ci95'][0], unit=objective.unit)}; "
          + (f"at the start ({fmt(x0)}): {pm(conf['mean'][1], conf['ci95'][1])}" if start_ok
             else f"the start ({fmt(x0)}) is outside the envelope's budgets: not run"))
    if envelope is not None:
        pts = envelope.points
        print("  per point (f, U): " + "; ".join(
            f"{f:.4g} Hz, {u:.4g} m: {pm(conf['point_mean'][p, 0], conf['point_se'][p, 0])}"
            for p, (f, u) in enumerate(pts)) + " (mean ± SE over beds)")
        b = conf["budgets"][0]
        print(f"  added mass ratio {b['mass_ratio']:.4g}, cavity volume {b['volume']:.4g} m³")
    edge = [n for n, v, a, b in zip(names, space.to_u(design), space.lo, space.hi)
            if v < 0.02 or v > 0.98]
    if edge:
        print(f"note: {', '.join(edge)} at (or next to) a bound of its range: the objective "
              "still improves that way; widen --bounds if that is feasible")
    print(f"cost: {search_cost:.4g} simulated DEM system-seconds for the search (runs and "
          f"settling), {prob.sim_seconds - search_cost:.4g} for the confirmation")
    if args.out:
        optimisation_file.write_design(args.out, cfg, objective, prob, method, res, conf,
                                       dict(s, budget=budget, x0=list(map(float, x0))))
        print(f"wrote {args.out}")
    return 0


def register(sub) -> None:
    """Add the subcommand(s) to the ``jaxdamp`` parser."""
    op = sub.add_parser(
        "optimize", help="optimise the box height Lz (DEM) or the gap (S3), or several design "
                         "variables, with an interval",
        description="Find the box height that optimises a design objective, with a 95 % "
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
        "differentiation of the one-period map) and stops with a message where there is none. "
        "Several design variables (--vars Lz,base,friction): 'spsa' (default) estimates the "
        "gradient from random +-c perturbation pairs, each pair its own direction and bed, all "
        "in one batch, and steps with optax Adam inside --bounds (the bed must fit under the "
        "lid); 'random' is the Latin hypercube of equal cost; 'batch' a Sobol start, a "
        "Gaussian process with each design's noise and batches drawn by Thompson sampling; the "
        "design is then confirmed on fresh beds next to the start. An operating envelope "
        "(--envelope-frequencies x --envelope-levels, every frequency at every base "
        "amplitude) scores a design by the worst (or mean) C_eq over its points, within "
        "--mass-budget and --volume-budget.",
        epilog=textwrap.dedent("""\
            examples:
              jaxdamp optimize --preset sanchez2012-optimal --replicates 4 --out opt.h5
                  DEM, 250 grains, C_eq at f0, S3 proposal + trust region
              jaxdamp optimize --preset sanchez2012-optimal --method scan --replicates 4
              jaxdamp optimize --preset sanchez2012-impact --quick --out s3_opt.h5
              jaxdamp optimize --preset sanchez2012-impact --objective band --band 14,15.16,16
              jaxdamp optimize --preset sanchez2012-optimal --vars Lz,base,friction \\
                  --replicates 2 --budget 400 --out design.h5
                  three variables: SPSA gradients (all perturbations and beds in one batch)
                  fed to Adam, then the design confirmed on fresh beds next to the preset's
              jaxdamp optimize --preset sanchez2012-optimal --vars Lz,mass_ratio \\
                  --envelope-frequencies 13.5,15.16,16.5 --envelope-levels 0.0015,0.0045 \\
                  --mass-budget 0.12 --out envelope.h5
                  an operating envelope: the largest worst-point C_eq over the band and the
                  levels within a mass budget, by the batched search (Sobol start, Gaussian
                  process with the replicates' noise, Thompson batches; designs of other
                  grain counts run in batches of their own), confirmed on fresh beds

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
            an HDF5 log (schema in docs/output.md) with the status (attribute convergence).

            status (one rule, jaxdamp/design/status.py): "optimum" only when the search
            converged — an exact gradient puts the stationary point within xtol (Newton step
            with the secant curvature), an estimated one is not significant against its
            standard error for 3 iterates, or the design sits on a bound with the objective
            improving beyond it (scan, trust: the response surface locates an interior
            optimum, or the best value is on a bound). Otherwise "NOT CONVERGED after N
            iterations (why); best iterate ..." (exit status 0; a random search is always a
            sample, not converged), or "FAILED: why" for a non-finite objective, e.g. no stable
            periodic orbit (exit status 3)."""),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_config_options(op, "sanchez2012-optimal (DEM) or sanchez2012-impact (S3), ...")
    op.add_argument("--objective", choices=["damping", "amplitude", "band", "dissipation"],
                    default="damping", help="what to optimise (default damping, C_eq)")
    op.add_argument("--frequency", type=positive_float, metavar="HZ",
                    help="frequency of damping/amplitude/dissipation (default: the primary's f0)")
    op.add_argument("--band", metavar="F1,F2,...", help="frequencies of the band objective [Hz]")
    op.add_argument("--method", choices=["trust", "scan", "gradient", "spsa", "random", "batch"],
                    help="search (Lz: DEM default trust, S3 default gradient; several --vars: "
                         "spsa (default), random (a Latin hypercube of equal cost) or batch "
                         "(Sobol start, Gaussian process, Thompson batches; the envelope's "
                         "default))")
    op.add_argument("--vars", metavar="NAMES", default="Lz",
                    help="design variables, comma separated: Lz (box height [m]), base (side "
                         "of the square base Lx = Ly, or a cylinder's radius [m]), friction "
                         "(grains' Coulomb coefficient), mass_ratio (the fill: grains' mass / "
                         "M), radius (the grains' radius [m], the fill kept by mass); default Lz")
    op.add_argument("--bounds", metavar="NAME=LO:HI,...",
                    help="ranges of the --vars (default Lz 0.07:0.25, base 0.8-1.25x the "
                         "preset's, friction 0.05:0.8, mass_ratio 0.02:0.2, radius 0.67-1.33x)")
    op.add_argument("--envelope-frequencies", metavar="F1,F2,...",
                    help="an operating envelope: the frequencies [Hz] the design must meet, "
                         "at every --envelope-levels; the score is C_eq at each point")
    op.add_argument("--envelope-levels", metavar="U1,U2,...",
                    help="the envelope's base amplitudes U [m]")
    op.add_argument("--statistic", choices=["worst", "mean"],
                    help="envelope: maximise the worst point's C_eq (default) or the mean")
    op.add_argument("--mass-budget", type=positive_float, metavar="MU",
                    help="envelope: largest grains' mass over the primary's mass M")
    op.add_argument("--volume-budget", type=positive_float, metavar="M3",
                    help="envelope: largest cavity volume, every cell [m^3]")
    op.add_argument("--x0", metavar="V1,V2,...",
                    help="--vars: start design in the order of --vars (default the preset's)")
    op.add_argument("--replicates", type=positive_int, metavar="R",
                    help="DEM: independent beds per evaluation (default 4; quick 2)")
    op.add_argument("--budget", type=positive_float, metavar="SECONDS",
                    help="gradient and spsa: stop before exceeding this many simulated "
                         "system-seconds; random: what the Latin hypercube may spend")
    op.add_argument("--lz0", type=float,
                    help="starting box height [m] (trust: the S3 surrogate descends from "
                         "here, default its dense-scan optimum; gradient: default 0.07)")
    op.add_argument("--gap0", type=float, help="S3: starting gap [m] (default lz0 - h_bed)")
    op.add_argument("--lo", type=float, metavar="LZ", help="lowest Lz [m] (default bed + 5 mm)")
    op.add_argument("--hi", type=float, metavar="LZ", help="highest Lz [m] (default 0.4 DEM)")
    op.add_argument("--lr", type=positive_float, help="gradient: initial learning rate [m]")
    op.add_argument("--max-iter", type=positive_int,
                    help="gradient, spsa: most iterates; batch: batches after the start")
    op.add_argument("--estimator", choices=["steady", "windows"], default="steady",
                    help="DEM gradient: replicated steady states (default) or pathwise "
                         "derivatives over short windows (biased on the chaotic bed; kept for "
                         "the experiment)")
    op.add_argument("--h", type=positive_float, metavar="M",
                    help="DEM: half-step of the central difference [m] (0.005)")
    op.add_argument("--duration", type=positive_float, metavar="S",
                    help="simulated time per evaluation [s] (DEM 3, quick 0.6; S3 run 3)")
    op.add_argument("--out", metavar="FILE.h5", help="log (HDF5)")
    add_overwrite(op)
    op.add_argument("--quick", action="store_true",
                    help="small settings for a demo (S3 ~30 s; DEM 2 replicates, 0.6 s runs)")
    add_no_progress(op)
    op.set_defaults(func=cmd_optimize)
