"""Design optimisation from two starts, and with three design variables (issue 12).

    python experiments/design_starts_and_variables.py            # full mode (cost in summary.md)
    python experiments/design_starts_and_variables.py --quick    # minutes: tiny settings

Damper, objective (C_eq at f0, maximised), estimates and intervals of
``experiments/design_optimisation.py``. A. **The multi-fidelity optimiser from Lz0 = 0.07 and
0.25 m, 5 seed sets each**: the single-particle surrogate descends from Lz0 on exact orbit
gradients, then the DEM trust region corrects it; judged against design_optimisation's
replicated adaptive scan (quick mode runs its own). B. **Three design variables** — box height
``Lz``, square base side ``Lx = Ly``, grain friction ``μ``: replicated SPSA gradients fed to
Adam from the thesis' design, against a Latin-hypercube search given the same simulated
system-seconds; both found designs and the thesis' design confirmed together on fresh beds
(Welch 95 % intervals of the differences). Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import os

import numpy as np

from jaxdamp.analysis.stats import welch
from jaxdamp.design import Objective, adaptive_scan
from jaxdamp.design.space import DesignProblem
from jaxdamp.design.spsa import random_search, spsa
from jaxdamp.design.surrogate import descend
from jaxdamp.io.study import load
from jaxdamp.studies import scaffold

try:
    from . import design_optimisation as do
except ImportError:  # run as a file: python experiments/<name>.py
    import design_optimisation as do

SCAN_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "design_optimisation",
                         "data.h5")
VARS = ("Lz", "base", "friction")
LABELS = ["thesis design", "SPSA (average of last 3 iterates)", "best of the Latin hypercube"]


def settings(quick: bool) -> dict:
    """design_optimisation's damper, DEM problem, trust region and scan, and this study's."""
    s = do.settings(quick)
    if quick:
        return dict(s, starts=(0.03, 0.12), seeds=(1,), lo=0.025, own_scan=True,
                    s3=dict(max_iter=6, duration=1.5), bounds={"Lz": (0.03, 0.1)},
                    spsa=dict(pairs=2, replicates=2, max_iter=2, duration=0.3), confirm=2)
    return dict(s, starts=(0.07, 0.25), seeds=(400, 500, 600, 700, 800), own_scan=False, s3={},
                bounds=None, spsa=dict(pairs=4, replicates=2, max_iter=10, duration=3.0),
                confirm=8)


def part_a(base, s, log) -> dict:
    first = do.problem(base, s, s["seeds"][0] * 1000)
    lo, hi = first.bounds()[0] if s["lo"] is None else s["lo"], s["hi"]
    if s["own_scan"] or not os.path.exists(SCAN_FILE):
        sc = adaptive_scan(do.problem(base, s, 50_000), lo, hi, n_coarse=s["coarse"],
                           n_fine=s["fine"], echo=log)
        scan = dict(x=sc.optimum.x, lo=sc.optimum.lo, hi=sc.optimum.hi,
                    sim_seconds=sc.sim_seconds, source="run here")
    else:
        a = load(SCAN_FILE)["scan"].attrs
        scan = dict(x=a["optimum"], lo=a["lo"], hi=a["hi"], sim_seconds=a["sim_seconds"],
                    source="experiments/design_optimisation/data.h5 (seed set 50000)")
    log(f"scan: {scan['x']:.5g} m, {scan['sim_seconds']:.4g} DEM s ({scan['source']})")
    runs = []
    for lz0 in s["starts"]:
        d = descend(first.config, first.objective, first.bed_height, lz0, lo, hi, s["s3"])
        log(f"S3 from {lz0}: {d['lz']:.5g} m, {d['iterates']} iterates ({d['reason']})")
        for seed in s["seeds"]:
            prob = (first if seed == s["seeds"][0] and not runs
                    else do.problem(base, s, seed * 1000))
            r = do.trust(prob, d["lz"], lo, hi, s)
            o = r.optimum
            runs.append(dict(lz0=lz0, seed=seed, s3_lz=d["lz"], s3_sim=d["sim_seconds"],
                             s3_iterates=d["iterates"], s3_fallbacks=d["fallbacks"],
                             x=o.x, lo=o.lo, hi=o.hi, interior=bool(o.interior),
                             sim=r.sim_seconds, rounds=len(r.rounds)))
            log(f"  seeds {seed}: {o.x:.5g} m, {len(r.rounds)} rounds, {r.sim_seconds:.4g} DEM s")
    return {"scan": scan, "runs": runs, "lo": lo, "hi": hi}


def part_b(base, s, log) -> dict:
    sp = s["spsa"]
    prob = DesignProblem(base, Objective("damping"), VARS, bounds=s["bounds"],
                         duration=sp["duration"], seed=900_000)
    x_thesis = np.clip(prob.space.value(), prob.space.lo, prob.space.hi)
    res = spsa(prob, x_thesis, pairs=sp["pairs"], max_iter=sp["max_iter"], progress=False,
               seed=1, echo=log)
    spsa_cost = res.sim_seconds
    log(f"SPSA: {res.x_average} after {len(res.history['u'])} iterates, {spsa_cost:.4g} DEM s")
    before = prob.sim_seconds
    rs = random_search(prob, spsa_cost, replicates=sp["replicates"], seed=2)
    rs_cost = prob.sim_seconds - before
    log(f"random search: {len(rs.X)} designs, best {rs.best}, {rs_cost:.4g} DEM s")
    X = np.stack([x_thesis, res.x_average, np.asarray(rs.best["x"])])
    conf = prob.evaluate(X, s["confirm"])
    log(f"confirmation ({s['confirm']} beds): " + ", ".join(
        scaffold.pm(m, h, ".4g", ".2g") for m, h in zip(conf["mean"], conf["ci95"])))
    return {"space": prob.space.describe(), "spsa": res, "spsa_cost": spsa_cost, "random": rs,
            "random_cost": rs_cost, "confirm": conf, "X": X, "labels": LABELS}


def verdicts(a: dict, b: dict) -> dict:
    v, sc = {"starts": {}}, a["scan"]
    for lz0 in sorted({r["lz0"] for r in a["runs"]}):
        rr = [r for r in a["runs"] if r["lz0"] == lz0]
        avg, sim = float(np.mean([r["x"] for r in rr])), float(np.mean([r["sim"] for r in rr]))
        v["starts"][str(lz0)] = dict(
            average=avg, inside=bool(sc["lo"] <= avg <= sc["hi"]),
            each_inside=sum(sc["lo"] <= r["x"] <= sc["hi"] for r in rr),
            each_interval_covers=sum(r["lo"] <= sc["x"] <= r["hi"] for r in rr), runs=len(rr),
            mean_dem_seconds=sim, ratio=sim / sc["sim_seconds"], s3_seconds=rr[0]["s3_sim"])
    J = b["confirm"]["J"]  # confirmed on independent beds: Welch 95 % of the differences
    (d_rs, h_rs), (d_th, h_th), (d_rt, h_rt) = (welch(J[i], J[j])
                                                for i, j in ((1, 2), (1, 0), (2, 0)))
    v["three"] = dict(spsa_minus_random=d_rs, spsa_minus_random_ci=h_rs,
                      at_least_as_good=bool(d_rs + h_rs >= 0),
                      better_than_random=bool(d_rs - h_rs > 0), spsa_minus_thesis=d_th,
                      spsa_minus_thesis_ci=h_th, better_than_thesis=bool(d_th - h_th > 0),
                      random_minus_thesis=d_rt, random_minus_thesis_ci=h_rt)
    return v


def record(a, b, v, path, prov):
    with scaffold.data_file(path, prov, objective=do.OBJECTIVE, verdicts=do.encode(v)) as h:
        g = h.create_group("starts")
        g.attrs["scan"] = do.encode(a["scan"])
        for k in ("lz0", "seed", "s3_lz", "s3_sim", "x", "lo", "hi", "sim", "rounds",
                  "s3_iterates", "s3_fallbacks", "interior"):
            d = g.create_dataset(k, data=np.array([r[k] for r in a["runs"]], float))
            if k in ("lz0", "s3_lz", "x", "lo", "hi", "sim"):
                d.attrs["units"] = "m" if k != "sim" else "s (simulated DEM system-seconds)"
        g = h.create_group("three_variables")
        g.attrs.update(space=do.encode(b["space"]), labels=do.encode(b["labels"]),
                       units=do.encode(b["space"]["units"]))
        it = g.create_group("spsa")
        for k, val in b["spsa"].history.items():
            it.create_dataset(k, data=val)
        it.attrs.update(settings=do.encode(b["spsa"].settings), reason=b["spsa"].reason,
                        sim_seconds=b["spsa_cost"])
        for k in ("X", "mean", "se", "J"):
            g.create_dataset(f"random/{k}", data=getattr(b["random"], k))
        g["random"].attrs["sim_seconds"] = b["random_cost"]
        g.create_dataset("confirmation/X", data=b["X"])
        for k in ("mean", "ci95", "J"):
            g.create_dataset(f"confirmation/{k}", data=b["confirm"][k]).attrs["units"] = "N s/m"


def report(data, out):
    v, st, tv = data.attrs["verdicts"], data["starts"], data["three_variables"]
    sc, sp, rs, c = st.attrs["scan"], tv["spsa"], tv["random"], tv["confirmation"]
    fig, (a1, a2, a3) = scaffold.subplots(1, 3, figsize=(15, 4.5))
    a1.axvspan(sc["lo"], sc["hi"], color="0.85", label="scan optimum, 95 %")
    for n, lz0 in enumerate(np.unique(st["lz0"])):
        x, lo, hi = (st[k][st["lz0"] == lz0] for k in ("x", "lo", "hi"))
        a1.errorbar(x, n + 0.1 * np.arange(len(x)), xerr=[x - lo, hi - x], fmt="o", ms=4,
                    label=f"from Lz0 = {lz0:g} m (seed sets)")
    a1.set(xlabel="optimum Lz [m]", ylabel="run",
           title="A. multi-fidelity optimiser, 95 % intervals")
    a1.legend(fontsize=8)
    a2.errorbar(np.arange(len(sp["value"])), sp["value"], yerr=1.96 * sp["value_se"], fmt="o-",
                label="SPSA iterates (pair averages ± 1.96 SE)")
    a2.axhline(c["mean"][0], color="k", ls="--", label="thesis design (confirmed)")
    a2.set(xlabel="iterate", ylabel="C_eq [N s/m]", title="B. three variables: SPSA")
    a2.legend(fontsize=8)
    a3.errorbar(np.arange(len(rs["mean"])), np.sort(rs["mean"])[::-1], fmt=".", color="0.5",
                label="Latin hypercube, sorted (in-search means)")
    a3.errorbar([-3, -2, -1], c["mean"], yerr=c["ci95"], fmt="s", color="C3",
                label="confirmed on fresh beds, 95 %")
    for x, m, t in zip([-3, -2, -1], c["mean"], ["thesis", "SPSA", "random best"]):
        a3.annotate(t, (x, m), textcoords="offset points", xytext=(4, 4), fontsize=8)
    a3.set(xlabel="design (rank)", ylabel="C_eq [N s/m]",
           title="B. equal-budget random search vs SPSA")
    a3.legend(fontsize=8)
    scaffold.save_figure(fig, out)
    L = [*scaffold.head("Design optimisation from two starts, and with three design variables "
                        "(issue 12)", data.attrs),
         "## A. Multi-fidelity optimiser (S3 descent from Lz0, then DEM trust region)", "",
         f"Reference: replicated adaptive scan, optimum {sc['x']:.4g} m [{sc['lo']:.4g}, "
         f"{sc['hi']:.4g}], {sc['sim_seconds']:.4g} DEM system-seconds ({sc['source']}).", ""]
    L += scaffold.table(
        ["Lz0 [m]", "seed set", "S3 optimum [m]", "DEM optimum [m]", "95 % interval [m]",
         "DEM system-seconds", "rounds"],
        [[f"{lz0:g}", int(seed), f"{s3:.4g}", f"{x:.4g}", f"[{lo:.4g}, {hi:.4g}]", f"{sim:.4g}",
          int(n)] for lz0, seed, s3, x, lo, hi, sim, n in zip(*(st[k] for k in (
              "lz0", "seed", "s3_lz", "x", "lo", "hi", "sim", "rounds")))])
    L += [""] + [f"- From {lz0} m: average end point {w['average']:.4g} m — "
                 f"{'inside' if w['inside'] else 'outside'} the scan's interval; {w['each_inside']}"
                 f" of {w['runs']} single end points inside it, {w['each_interval_covers']} of "
                 f"{w['runs']} intervals cover the scan's optimum; mean DEM cost "
                 f"{w['mean_dem_seconds']:.4g} s = {w['ratio']:.2f} × the scan's (+ "
                 f"{w['s3_seconds']:.4g} simulated s of the point-mass S3)."
                 for lz0, w in v["starts"].items()]
    t, space, ss = v["three"], tv.attrs["space"], sp.attrs["settings"]
    L += ["", "## B. Three design variables: " + ", ".join(space["variables"]), "",
          "Ranges: " + ", ".join(f"{n} [{lo:.4g}, {hi:.4g}]" for n, lo, hi in zip(
              space["variables"], space["lo"], space["hi"]))
          + f"; projection keeps Lz ≥ h_bed(base) + {space['margin']} m. SPSA: "
          f"{ss['pairs']} (direction, bed) pairs per iterate, c = {ss['c']}, Adam lr {ss['lr']} "
          f"(normalised coordinates); {len(sp['u'])} iterates ({sp.attrs['reason']}). Random "
          f"search: {len(rs['X'])} Latin-hypercube designs × {rs['J'].shape[1]} beds. Costs "
          "include settling (every design has its own beds).", ""]
    costs = ["–", f"{sp.attrs['sim_seconds']:.4g}", f"{rs.attrs['sim_seconds']:.4g}"]
    L += scaffold.table(
        ["design"] + space["variables"] + ["search DEM system-seconds",
                                    f"confirmed C_eq [N s/m] ({c['J'].shape[1]} fresh beds, 95 %)"],
        [[lab] + [f"{val:.4g}" for val in x] + [cost, scaffold.pm(m, h, 4)]
         for lab, x, cost, m, h in zip(tv.attrs["labels"], c["X"], costs, c["mean"], c["ci95"])])
    pm = lambda k: scaffold.pm(t[k], t[k + "_ci"], "+.3g", unit="N s/m")  # noqa: E731
    L += ["", f"- SPSA − random best: {pm('spsa_minus_random')} (Welch 95 %): SPSA "
          + ("better" if t["better_than_random"] else "at least as good (within the interval)"
             if t["at_least_as_good"] else "worse") + ".",
          f"- SPSA − thesis design: {pm('spsa_minus_thesis')}: "
          + ("better than the thesis' design" if t["better_than_thesis"]
             else "not significantly better than the thesis' design") + ".",
          f"- random best − thesis design: {pm('random_minus_thesis')}.", "",
          "Every verdict uses the confirmation on fresh beds: the random search's in-search best "
          "is a best-of-n mean, biased up (winner's curse)."]
    scaffold.write_summary(out, L)


def compute(quick, log, _ctx):
    s = settings(quick)
    base = do.damper(s)
    a, b = part_a(base, s, log), part_b(base, s, log)
    v = verdicts(a, b)
    return {"a": a, "b": b, "verdicts": v}, lambda path, prov: record(a, b, v, path, prov)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
