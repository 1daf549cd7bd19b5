"""Design optimisation that beats the scan: DEM derivatives with error bars, searches with
intervals.

    python experiments/design_optimisation.py            # full mode (cost in summary.md)
    python experiments/design_optimisation.py --quick    # minutes: tiny settings, every part

Damper ``sanchez2012-optimal`` (250 grains, 1-DOF primary, f0 = 15.157 Hz); default objective
of ``jaxdamp optimize``: the equivalent viscous damping added by the grains at f0,
``C_eq = E / (π Ω Z²)`` [N s/m], maximised (``jaxdamp.design.objectives``). Every DEM number
comes from independent replicates (independently seeded settled beds) with the start of each
run's steady state detected by MSER (``jaxdamp.analysis.stats``).

1. **Reference derivative** ``dC_eq/dLz`` at Lz = 0.09, 0.11 and 0.14 m: ``R_ref`` beds ×
   ``Lz ± h`` (common random numbers inside each pair), with its 95 % interval.
2. **The DEM estimator** with fewer replicates (R = 4): at each of the three points, and
   repeated with disjoint seeds at 0.11 m to check that its standard error is calibrated
   (z-scores of the repetitions against the reference).
3. **The baseline**: a replicated batched adaptive scan over the feasible range (coarse batch,
   finer batch in the bracket, quadratic optimum with a jackknife interval).
4. **Multi-fidelity trust region**: the S3 surrogate (one particle, exact orbit objective)
   proposes, DEM stencils pooled into a response surface correct; several seed sets.
5. **Pure finite-difference optimiser** (optax Adam on the replicated central differences)
   from Lz0 = 0.07 and 0.25 m, with a budget.

Verdicts: the searches' optima against the scan's interval, and their simulated
system-seconds against the scan's. Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from jaxdamp.analysis.stats import t_quantile
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.design import Objective, SteadyProblem, adaptive_scan, optimize, trust_region
from jaxdamp.design.surrogate import propose
from jaxdamp.studies import scaffold

THESIS_LZ = 0.1225
OBJECTIVE = "C_eq = E/(pi Omega Z^2) at f0 [N s/m], maximised"
#: quick mode's damper: 24 grains in a 2 cm box on a light primary (design_starts_and_variables)
QUICK = {"grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "primary.M": 0.3,
         "primary.K": 2720.0, "primary.C": 1.0, "numerics.settle_time": 0.15}


def settings(quick: bool) -> dict:
    if quick:
        return dict(overrides=QUICK,
                    ref_lz=(0.03, 0.04), R_ref=3, ref_duration=0.4, R=2, duration=0.3,
                    reps=2, h=0.003, lo=0.03, hi=0.15, coarse=3, fine=1, trust_seeds=(100,),
                    fd_starts=(0.03,), fd_budget=3.0, radius=0.005, min_radius=0.002,
                    tol=0.004, seed_stride=1000, max_rounds=2, s3_gaps=11, s3_duration=1.5)
    return dict(overrides={"numerics.settle_time": 0.3},
                ref_lz=(0.09, 0.11, 0.14), R_ref=8, ref_duration=5.0, R=4, duration=3.0,
                reps=6, h=0.005, lo=None, hi=0.30, coarse=11, fine=4,
                trust_seeds=(100, 200, 300), fd_starts=(0.07, 0.25), fd_budget=150.0,
                radius=0.01, min_radius=0.0025, tol=0.003, seed_stride=1000, max_rounds=6,
                s3_gaps=41, s3_duration=3.0)


def damper(s):
    """``sanchez2012-optimal`` with the settings' overrides."""
    return apply_overrides(presets.get("sanchez2012-optimal"), s["overrides"])


def problem(base, s, seed, R=None, duration=None):
    """The steady C_eq problem from seed ``seed`` with ``R`` replicates of ``duration`` [s]
    (default ``s["R"]``, ``s["duration"]``)."""
    cfg = apply_overrides(base, {"numerics.seed": seed})
    return SteadyProblem(cfg, Objective("damping"), h=s["h"], replicates=R or s["R"],
                         duration=duration or s["duration"])


def trust(prob, x0, lo, hi, s, echo=None):
    """The DEM trust region from ``x0`` with the settings' radii, tolerance and rounds."""
    return trust_region(prob, x0, lo, hi, radius=s["radius"], min_radius=s["min_radius"],
                        tol=s["tol"], max_rounds=s["max_rounds"], echo=echo)


def encode(x) -> str:
    """JSON of results holding numpy arrays and booleans (the verdicts, settings)."""
    return json.dumps(x, default=lambda y: y.tolist() if hasattr(y, "tolist")
                      else bool(y) if isinstance(y, np.bool_) else str(y))


def run(s: dict, log) -> dict:
    base = damper(s)
    out = {"settings": s, "reference": [], "estimator": [], "trust": [], "fd": []}

    # 1. the reference derivative (seeds 0 .. R_ref-1)
    ref = problem(base, s, 0, s["R_ref"], s["ref_duration"])
    for lz in s["ref_lz"]:
        e, _ = ref.evaluate(lz)
        g = (e.extra["plus"] - e.extra["minus"]) / (2 * ref.h)
        half = t_quantile(0.975, len(g) - 1) * e.grad_se
        out["reference"].append(dict(lz=lz, grad=e.grad, se=e.grad_se, half=half, pairs=g,
                                     value=e.value, value_se=e.value_se,
                                     not_stationary=e.extra["not_stationary"]))
        log(f"reference at Lz = {lz}: dC_eq/dLz = {scaffold.pm(e.grad, half, 4, 3)} (95 %), "
            f"C_eq = {scaffold.pm(e.value, e.value_se, 4)}; {e.extra['not_stationary']} runs not "
            "stationary")
    out["reference_sim"] = ref.sim_seconds

    # 2. the estimator with R replicates: at every point (seed set 1), and repetitions at the
    #    middle point with disjoint seed sets
    for k in range(s["reps"]):
        prob = problem(base, s, s["seed_stride"] * (k + 1))
        for lz in s["ref_lz"] if k == 0 else (s["ref_lz"][len(s["ref_lz"]) // 2],):
            e, _ = prob.evaluate(lz)
            out["estimator"].append(dict(rep=k, lz=lz, grad=e.grad, se=e.grad_se, value=e.value,
                                         sim=e.sim_seconds))
            log(f"estimator (R = {s['R']}, rep {k}) at {lz}: "
                f"{scaffold.pm(e.grad, e.grad_se, 4, 3)}")

    # 3. the baseline scan (seed set 50)
    scan_prob = problem(base, s, 50 * s["seed_stride"])
    lo, hi = scan_prob.bounds()[0] if s["lo"] is None else s["lo"], s["hi"]
    t0 = time.perf_counter()
    out["scan"] = sc = adaptive_scan(scan_prob, lo, hi, n_coarse=s["coarse"], n_fine=s["fine"],
                                     echo=log)
    out["scan_wall"] = time.perf_counter() - t0
    o = sc.optimum
    log(f"scan: optimum {o.x:.5g} m [{o.lo:.5g}, {o.hi:.5g}], {sc.sim_seconds:.4g} sim s")

    # 4. multi-fidelity trust region from the S3 proposal
    for seed in s["trust_seeds"]:
        prob = problem(base, s, seed * s["seed_stride"])
        p = propose(prob.config, prob.objective, prob.bed_height, lo, hi, n=s["s3_gaps"],
                    duration=s["s3_duration"])
        r = trust(prob, p["lz"], lo, hi, s, echo=log)
        out["trust"].append(dict(seed=seed, proposal=p["lz"], s3_sim=p["sim_seconds"], result=r))
        log(f"trust region (seed set {seed}): S3 proposes {p['lz']:.5g} m; optimum "
            f"{r.optimum.x:.5g} m [{r.optimum.lo:.5g}, {r.optimum.hi:.5g}], "
            f"{r.sim_seconds:.4g} DEM sim s")

    # 5. the pure finite-difference optimiser
    for lz0 in s["fd_starts"]:
        r = optimize(problem(base, s, 77 * s["seed_stride"]), lz0, lr=0.01, decay=0.85,
                     max_iter=20, xtol=5e-4, lo=lo, hi=hi, progress=False, budget=s["fd_budget"])
        out["fd"].append(dict(lz0=lz0, result=r))
        opt = r.optimum
        log(f"FD optimiser from {lz0}: {len(r.history['x'])} iterates ({r.reason}); average "
            f"{r.x_average:.5g} m" + (f", surface optimum {opt.x:.5g} [{opt.lo:.5g}, {opt.hi:.5g}]"
                                      if opt is not None else "") + f"; {r.sim_seconds:.4g} sim s")
    return out


def verdicts(out: dict) -> dict:
    """The claims, from intervals."""
    ref = {r["lz"]: r for r in out["reference"]}
    v = {"estimator_agrees": []}
    for e in out["estimator"]:
        if e["rep"] == 0:
            r = ref[e["lz"]]
            comb = np.hypot(e["se"], r["se"])
            v["estimator_agrees"].append(dict(lz=e["lz"], z=(e["grad"] - r["grad"]) / comb,
                                              inside=abs(e["grad"] - r["grad"]) <= 1.96 * comb))
    mid = out["reference"][len(out["reference"]) // 2]
    reps = [e for e in out["estimator"] if e["lz"] == mid["lz"]]
    v["calibration_z"] = z = np.array([(e["grad"] - mid["grad"]) / np.hypot(e["se"], mid["se"])
                                       for e in reps])
    v["calibration_spread"] = float(z.std(ddof=1)) if len(z) > 1 else float("nan")
    scan, sim = out["scan"].optimum, out["scan"].sim_seconds
    inside = lambda x: scan.lo <= x <= scan.hi  # noqa: E731 - inside the scan's interval
    v["scan"] = dict(x=scan.x, lo=scan.lo, hi=scan.hi, sim=sim)
    v["trust"] = []
    for t in out["trust"]:
        o = t["result"].optimum
        v["trust"].append(dict(seed=t["seed"], x=o.x, lo=o.lo, hi=o.hi, inside_scan_ci=inside(o.x),
                               overlaps=not (o.hi < scan.lo or o.lo > scan.hi),
                               dem_sim=t["result"].sim_seconds, s3_sim=t["s3_sim"],
                               ratio=t["result"].sim_seconds / sim))
    if v["trust"]:
        xs = np.array([t["x"] for t in v["trust"]])
        v["trust_mean"] = float(xs.mean())
        v["trust_mean_inside"] = bool(inside(xs.mean()))
        v["trust_sim_mean"] = float(np.mean([t["dem_sim"] for t in v["trust"]]))
    v["fd"] = [dict(lz0=f["lz0"], x=f["result"].x_average, sim=f["result"].sim_seconds,
                    reason=f["result"].reason, inside_scan_ci=inside(f["result"].x_average))
               for f in out["fd"]]
    return v


def write(out: dict, v: dict, path: str, prov: dict) -> None:
    with scaffold.data_file(path, prov, settings=out["settings"], verdicts=encode(v),
                            objective=OBJECTIVE) as h:
        for k in ("lz", "grad", "se", "half", "value", "value_se"):
            d = h.create_dataset(f"reference/{k}", data=np.array([r[k] for r in out["reference"]]))
            if k in ("lz", "grad", "se", "half"):
                d.attrs["units"] = "m" if k == "lz" else "N s/m^2"
        h.create_dataset("reference/pairs", data=np.stack([r["pairs"] for r in out["reference"]]))
        h["reference"].attrs["sim_seconds"] = out["reference_sim"]
        for k in ("rep", "lz", "grad", "se", "value", "sim"):
            h.create_dataset(f"estimator/{k}", data=np.array([e[k] for e in out["estimator"]]))
        for name, r in [("scan", out["scan"])] + [(f"trust_{t['seed']}", t["result"])
                                                  for t in out["trust"]]:
            g = h.create_group(name)
            for k, unit in (("x", "m"), ("mean", "N s/m"), ("se", "N s/m"), ("J", "N s/m")):
                g.create_dataset(k, data=getattr(r, k)).attrs["units"] = unit
            o = r.optimum
            g.attrs.update(optimum=o.x, lo=o.lo, hi=o.hi, se=o.se, interior=o.interior,
                           sim_seconds=r.sim_seconds, rounds=json.dumps(r.rounds))
        for f in out["fd"]:
            g = h.create_group(f"fd_{f['lz0']:g}")
            r = f["result"]
            for k, val in r.history.items():
                g.create_dataset(k, data=val)
            g.attrs.update(reason=r.reason, x_average=r.x_average, sim_seconds=r.sim_seconds)
    _figure(out, v, path)
    _summary(out, v, path, prov)


def _figure(out, v, path):
    fig, (a1, a2, a3) = scaffold.subplots(1, 3, figsize=(16, 4.5))
    sc = out["scan"]
    order = np.argsort(sc.x)
    a1.errorbar(sc.x[order], sc.mean[order], yerr=2 * sc.se[order], fmt="ko-", ms=3, capsize=2,
                label=f"replicated scan (R = {sc.J.shape[1]}, ± 2 SE)")
    a1.axvspan(v["scan"]["lo"], v["scan"]["hi"], color="k", alpha=0.15, label="scan optimum, 95 %")
    for t, c in zip(out["trust"], ("C0", "C1", "C2", "C3", "C4")):
        r = t["result"]
        a1.plot(r.x, r.mean, "s", color=c, ms=4, label=f"trust region, seeds {t['seed']}")
        a1.axvline(t["proposal"], color=c, ls=":", lw=0.8)
    a1.axvline(THESIS_LZ, color="g", ls="-.", lw=0.8, label="thesis 0.1225 m")
    a1.set(xlabel="box height Lz [m]", ylabel="C_eq at f0 [N s/m]")
    a1.legend(fontsize=7)
    ref = out["reference"]
    a2.errorbar([r["lz"] for r in ref], [r["grad"] for r in ref], yerr=[r["half"] for r in ref],
                fmt="ko", capsize=4, label=f"reference ({len(ref[0]['pairs'])} pairs, 95 %)")
    est = out["estimator"]
    a2.errorbar([e["lz"] + 0.001 * (e["rep"] + 1) for e in est], [e["grad"] for e in est],
                yerr=[1.96 * e["se"] for e in est], fmt="o", ms=3, capsize=2, color="C3",
                label=f"estimator R = {out['settings']['R']} (± 1.96 SE), repetitions")
    a2.axhline(0, color="0.6", lw=0.8)
    a2.set(xlabel="Lz [m]", ylabel="dC_eq/dLz [N s/m²]")
    a2.legend(fontsize=7)
    labels = (["scan"] + [f"trust {t['seed']}" for t in out["trust"]]
              + [f"FD from {f['lz0']:g}" for f in out["fd"]])
    sims = [r.sim_seconds for r in [out["scan"]] + [x["result"] for x in out["trust"] + out["fd"]]]
    a3.bar(range(len(sims)), sims,
           color=["k"] + ["C0"] * len(out["trust"]) + ["C3"] * len(out["fd"]))
    a3.set_xticks(range(len(sims)), labels, rotation=30, fontsize=7)
    a3.set_ylabel("DEM simulated system-seconds")
    fig.suptitle("sanchez2012-optimal: maximise C_eq at f0 over Lz", fontsize=9)
    scaffold.save_figure(fig, path)


def _summary(out, v, path, prov):
    s = out["settings"]
    L = [*scaffold.head("Design optimisation that beats the scan (issue 12)", prov),
         "Objective: the grains' equivalent viscous damping at f0, C_eq = E/(π Ω Z²) [N s/m], "
         "maximised. Every DEM value is a mean over independent replicates (independently seeded "
         "settled beds) of steady means after each run's MSER-detected start; derivatives are "
         "central differences Lz ± h with common random numbers inside each pair "
         f"(h = {s['h']} m). Intervals are Student-t 95 % across replicates; optimum intervals "
         "are jackknife-t over replicates of a quadratic response surface.", "",
         "## 1–2. Reference derivative and the estimator", ""]
    ref = {r["lz"]: r for r in out["reference"]}
    first = {e["lz"]: e for e in out["estimator"] if e["rep"] == 0}
    yes = lambda x: "yes" if x else "no"  # noqa: E731
    L += scaffold.table(
        ["Lz [m]", f"reference dC_eq/dLz ({s['R_ref']} pairs, {s['ref_duration']} s)",
         f"estimator (R = {s['R']}, {s['duration']} s)", "z", "within 95 %"],
        [[f"{a['lz']:g}", scaffold.pm(ref[a["lz"]]["grad"], ref[a["lz"]]["half"], 4, 3),
          scaffold.pm(first[a["lz"]]["grad"], 1.96 * first[a["lz"]]["se"], 4, 3),
          f"{a['z']:+.2f}", yes(a["inside"])] for a in v["estimator_agrees"]])
    z = v["calibration_z"]
    L += ["", f"Calibration at Lz = {out['reference'][len(out['reference']) // 2]['lz']:g} m: "
          f"{len(z)} repetitions with disjoint seeds, z = (estimate − reference)/√(SE² + "
          f"SE_ref²) = {', '.join(f'{x:+.2f}' for x in z)}; spread (std) "
          f"{v['calibration_spread']:.2f} (a calibrated error gives ≈ 1; with R = {s['R']} the "
          "t-distribution's spread is larger, √(3) for 3 degrees of freedom).", "",
          "## 3–5. Searches", ""]
    sc = v["scan"]
    L += scaffold.table(
        ["method", "optimum Lz [m]", "95 % interval [m]", "DEM system-seconds", "ratio to scan",
         "inside scan interval"],
        [[f"replicated adaptive scan ({s['coarse']} + {s['fine']} points)", f"{sc['x']:.4g}",
          f"[{sc['lo']:.4g}, {sc['hi']:.4g}]", f"{sc['sim']:.4g}", 1, "–"]]
        + [[f"trust region from S3 proposal, seeds {t['seed']}", f"{t['x']:.4g}",
            f"[{t['lo']:.4g}, {t['hi']:.4g}]", f"{t['dem_sim']:.4g} (+ {t['s3_sim']:.3g} S3)",
            f"{t['ratio']:.2f}", yes(t["inside_scan_ci"])] for t in v["trust"]]
        + [[f"FD Adam from {f['lz0']:g} m (iterate average; {f['reason']})", f"{f['x']:.4g}",
            "–", f"{f['sim']:.4g}", f"{f['sim'] / sc['sim']:.2f}", yes(f["inside_scan_ci"])]
           for f in v["fd"]])
    if v["trust"]:
        L += ["", f"Trust-region end points averaged over seed sets: {v['trust_mean']:.4g} m, "
              f"{'inside' if v['trust_mean_inside'] else 'outside'} the scan's interval; mean DEM "
              f"cost {v['trust_sim_mean']:.4g} system-seconds = "
              f"{v['trust_sim_mean'] / v['scan']['sim']:.2f} × the scan's."]
    L += ["", "Which to pick: for one design variable with a good surrogate, the trust region "
          "started from the S3 proposal needs the fewest DEM seconds; without a surrogate (or "
          "when it proposes a bound), the adaptive scan is the robust choice — it brackets "
          "the optimum from a coarse batch and costs a fixed, predictable amount. The "
          "finite-difference optimiser pays two replicated runs per iterate for a single "
          "direction and is the most expensive way to one variable's optimum; gradients pay "
          "off with several design variables (not done here).", "",
          "Conventions the verdicts depend on: residual weighting of the response surface = "
          "1/SE² of the replicate means; optimum interval = jackknife over replicates with "
          "t_{0.975, R−1}; steady state = MSER on per-period amplitude and dissipation (at "
          "least 1 period dropped, 5 kept)."]
    scaffold.write_summary(path, L)


def compute(quick, log, _ctx):
    out = run(settings(quick), log)
    v = verdicts(out)
    return {"out": out, "verdicts": v}, lambda path, prov: write(out, v, path, prov)


main = scaffold.entry(__file__, __doc__, compute)


if __name__ == "__main__":
    sys.exit(0 if main() else 1)
