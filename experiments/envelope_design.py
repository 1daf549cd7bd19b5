"""Design for the operating envelope: the single-point optimum against the envelope design
(issue 41).

    python experiments/envelope_design.py            # full mode (cost in summary.md)
    python experiments/envelope_design.py --quick    # a minute: tiny settings, every part

The thesis damper (``sanchez2012-optimal``) is optimal at one point: its box height Lz
maximises the grains' equivalent damping ``C_eq = E / (π Ω Z²)`` at f0 = 15.16 Hz and the
thesis' base amplitude U = 4.5 mm (``experiments/design_optimisation``: the replicated scan's
optimum). A designer's requirement is an **envelope** (:mod:`jaxdamp.design.envelope`): the
mode may sit anywhere in a band of frequencies and the base may shake at several levels.

A. **The envelope design**: the box height that maximises the *worst* ``C_eq`` over the
   envelope's points, found by the batched search (:func:`jaxdamp.design.bayes.batch_search`:
   a Sobol start, a Gaussian process with the replicates' noise, batches by Thompson sampling),
   each design on its own beds, its points sharing them.
B. **Confirmation on fresh beds**: the single-point optimum and the envelope design, each on
   ``confirm`` new beds at every point of the envelope: per point mean ± SE, the worst point
   and the envelope mean. Verdict (stated rule): the envelope design *wins on the worst case*
   when the Welch 95 % interval of (its worst-point values − the single-point design's
   worst-point values) lies above zero; *loses* when below; else undecided.
C. **Why this search** (a measurement, not the DEM): on a known noisy 2-D function with a
   secondary peak and noise growing across the range, the search's recommendation against
   the best observed design of a Latin hypercube of the same budget, over seeds: regret
   ``f_max − f(recommended)``.

Writes ``data.h5``, ``figure.png``, ``summary.md``.

**Run-length check** (``--recheck S --out DIR``): the two designs of a stored result
(``--designs``, default this study's ``data.h5``) confirmed again on fresh beds with runs of
``S`` seconds, each point's C_eq set beside the stored one (Welch 95 %: the run length's
systematic) and the verdict retaken; it writes its own ``data.h5``, ``figure.png`` and
``summary.md`` into ``DIR`` (not the stored result's folder).
"""

from __future__ import annotations

import os

import numpy as np

from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.design.bayes import ToyProblem, batch_search
from jaxdamp.design.envelope import Envelope, EnvelopeProblem
from jaxdamp.design.spsa import random_search
from jaxdamp.io.study import load
from jaxdamp.studies import scaffold

try:
    from . import design_optimisation as do
except ImportError:  # run as a file: python experiments/<name>.py
    import design_optimisation as do

SCAN_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "design_optimisation",
                         "data.h5")
DATA_FILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "envelope_design", "data.h5")
LABELS = ["single-point optimum", "envelope design"]


def settings(quick: bool) -> dict:
    if quick:
        return dict(overrides=do.QUICK, frequencies=(14.0, 15.16), levels=(0.002, 0.0045),
                    bounds={"Lz": (0.03, 0.1)}, duration=0.3, n_start=3, batch=2, rounds=1,
                    replicates=2, confirm=2, single=None, toy_seeds=3, seed=7000)
    return dict(overrides={"numerics.settle_time": 0.3}, frequencies=(13.5, 15.16, 16.5),
                levels=(0.0015, 0.003, 0.0045), bounds={"Lz": (0.07, 0.25)}, duration=3.0,
                n_start=6, batch=3, rounds=2, replicates=2, confirm=6, single="scan",
                toy_seeds=20, seed=7000)


def single_point(s, base) -> tuple[float, str]:
    """The single-point optimum's Lz: design_optimisation's scan (full mode), else the
    configuration's own."""
    if s["single"] == "scan" and os.path.exists(SCAN_FILE):
        return (float(load(SCAN_FILE)["scan"].attrs["optimum"]),
                "experiments/design_optimisation/data.h5 (the replicated scan at f0, U = 4.5 mm)")
    return float(base.box.Lz), "the configuration's Lz"


def toy(u):
    """Part C's known function on the unit square: a main peak at (0.62, 0.35), maximum 1, and
    a secondary one of 0.4 at (0.15, 0.85)."""
    u = np.atleast_2d(u)
    return (np.exp(-((u[:, 0] - 0.62) ** 2 / 0.05 + (u[:, 1] - 0.35) ** 2 / 0.1))
            + 0.4 * np.exp(-((u[:, 0] - 0.15) ** 2 + (u[:, 1] - 0.85) ** 2) / 0.02))


def part_c(s, log) -> dict:
    g = np.stack(np.meshgrid(np.linspace(0, 1, 401), np.linspace(0, 1, 401)), -1).reshape(-1, 2)
    fmax = float(toy(g).max())
    n = s["n_start"] + s["rounds"] * s["batch"]
    gp, lhs = [], []
    for k in range(s["toy_seeds"]):
        b = batch_search(ToyProblem(toy, d=2, noise=0.1, hetero=1.0, seed=k), n_start=8,
                         batch=4, rounds=3, replicates=2, seed=k)
        r = random_search(ToyProblem(toy, d=2, noise=0.1, hetero=1.0, seed=100 + k), 40,
                          replicates=2, seed=k)
        gp.append(fmax - float(toy(b.best_u)[0]))
        lhs.append(fmax - float(toy(np.asarray(r.best["x"]))[0]))
    gp, lhs = np.asarray(gp), np.asarray(lhs)
    log(f"C: regret, search median {np.median(gp):.3g}, Latin hypercube {np.median(lhs):.3g}")
    return dict(gp=gp, lhs=lhs, designs=20, dem_designs=n)


def options(ap):
    ap.add_argument("--recheck", type=float, metavar="S",
                    help="confirm a stored result's two designs again with runs of S seconds")
    ap.add_argument("--designs", default=DATA_FILE, metavar="DATA.h5",
                    help="the stored result whose designs --recheck runs (default: this "
                         "study's data.h5)")
    ap.add_argument("--beds", type=int, help="--recheck: fresh beds per design (default: the "
                                             "stored result's)")


def recheck(s, base, log, ctx):
    """The run-length check (module doc)."""
    from jaxdamp.io.study import load

    a = ctx.args
    if os.path.abspath(ctx.out) == os.path.dirname(os.path.abspath(a.designs)):
        raise SystemExit("--recheck writes its own result: give --out another folder than "
                         f"the one of {a.designs}")
    stored = load(a.designs)
    X = np.asarray(stored["confirmation"]["X"])
    old = np.asarray(stored["confirmation"]["C"])
    st = stored.attrs["settings"]
    env = Envelope(st["frequencies"], st["levels"], statistic="worst")
    R = a.beds or old.shape[2]
    prob = EnvelopeProblem(base, env, names=("Lz",), bounds={"Lz": tuple(st["bounds"]["Lz"])},
                           duration=a.recheck, seed=s["seed"] + 50_000, progress=ctx.progress)
    conf = prob.evaluate(X, R)
    conf.update(sim=prob.sim_seconds, X=X)
    log(f"recheck at {a.recheck} s: worst cases {conf['value']}")
    return conf, old, st, env


def compute(quick, log, ctx):
    s = settings(quick)
    if ctx.args.recheck:
        base = apply_overrides(presets.get("sanchez2012-optimal"), s["overrides"])
        conf, old, st, env = recheck(s, base, log, ctx)
        out = dict(conf=conf, old=old, st=st, env=env.describe(), duration=ctx.args.recheck,
                   source=os.path.relpath(ctx.args.designs, os.getcwd()))
        return out, lambda path, prov: record_recheck(out, path, prov)
    base = apply_overrides(presets.get("sanchez2012-optimal"), s["overrides"])
    env = Envelope(s["frequencies"], s["levels"], statistic="worst")
    prob = EnvelopeProblem(base, env, names=("Lz",), bounds=s["bounds"], duration=s["duration"],
                           seed=s["seed"], progress=ctx.progress)
    log(f"envelope: {len(env.points)} points; each design on {s['replicates']} beds")
    res = batch_search(prob, n_start=s["n_start"], batch=s["batch"], rounds=s["rounds"],
                       replicates=s["replicates"], seed=s["seed"], progress=log)
    log(f"A: envelope design Lz = {res.best_x[0]:.4g} m ({res.sim_seconds:.4g} DEM "
        f"system-seconds, {res.wall / 60:.1f} min)")
    lz1, source = single_point(s, base)
    X = np.array([[lz1], [float(res.best_x[0])]])
    sim0 = prob.sim_seconds
    conf = prob.evaluate(X, s["confirm"])
    conf["sim"] = prob.sim_seconds - sim0
    mean_stat = np.asarray([np.mean(conf["C"][:, i, :], axis=0) for i in range(2)])  # (2, R)
    pw = conf["worst_point"]
    d, h = welch(conf["C"][pw[1], 1, :], conf["C"][pw[0], 0, :])
    dm, hm = welch(mean_stat[1], mean_stat[0])
    verdict = ("wins" if d - h > 0 else "loses" if d + h < 0 else "undecided")
    log(f"B: worst case {conf['value'][0]:.4g} → {conf['value'][1]:.4g} N s/m: "
        f"difference {scaffold.pm(d, h, '+.3g', '.2g')} ({verdict})")
    c = part_c(s, log)
    out = dict(s=s, env=env.describe(), space=prob.space.describe(), res=res, X=X,
               source=source, conf=conf, mean_stat=mean_stat,
               verdicts=dict(worst_difference=d, worst_ci=h, worst=verdict,
                             mean_difference=dm, mean_ci=hm,
                             search_better_in=int((c["gp"] < c["lhs"]).sum()),
                             toy_seeds=len(c["gp"])),
               toy=c)
    return out, lambda path, prov: record(out, path, prov)


def record(o, path, prov):
    res, conf = o["res"], o["conf"]
    with scaffold.data_file(path, prov, settings=do.encode(o["s"]), envelope=do.encode(o["env"]),
                            space=do.encode(o["space"]), verdicts=do.encode(o["verdicts"]),
                            labels=do.encode(LABELS), single_source=o["source"]) as h:
        g = h.create_group("search")
        g.create_dataset("X", data=res.X).attrs["units"] = "m"
        for k in ("mean", "se"):
            g.create_dataset(k, data=res.mean if k == "mean" else res.se).attrs["units"] = \
                "N s/m (worst point's mean over beds)"
        g.create_dataset("round", data=res.round_of)
        g.attrs.update(best_x=res.best_x, best_pred=res.best_pred, best_pred_sd=res.best_pred_sd,
                       kernel=res.kernel, sim_seconds=res.sim_seconds, wall=res.wall)
        g = put_confirmation(h, o["X"], conf)
        g.create_dataset("stationary", data=conf["stationary"])
        g.create_dataset("envelope_mean", data=o["mean_stat"]).attrs["units"] = "N s/m"
        g = h.create_group("toy")
        for k in ("gp", "lhs"):
            g.create_dataset(k, data=o["toy"][k])
        g.attrs.update(designs=o["toy"]["designs"])


def put_confirmation(h, X, conf):
    """The group ``confirmation`` of a result file: the designs ``X`` and, per point, design
    and bed, C_eq, Z, E and whether the steady state was detected; its cost."""
    g = h.create_group("confirmation")
    g.create_dataset("X", data=X).attrs["units"] = "m"
    for k, unit in (("C", "N s/m"), ("Z", "m"), ("E", "J per period")):
        g.create_dataset(k, data=conf[k]).attrs["units"] = unit
    g.create_dataset("stationary_each", data=conf["stationary_each"])
    g.attrs.update(sim_seconds=conf["sim"])
    return g


def record_recheck(o, path, prov):
    with scaffold.data_file(path, prov, mode="recheck", settings=do.encode(o["st"]),
                            envelope=do.encode(o["env"]), labels=do.encode(LABELS),
                            duration=o["duration"], designs_from=o["source"]) as h:
        put_confirmation(h, o["conf"]["X"], o["conf"])
        h.create_dataset("stored_C", data=o["old"]).attrs["units"] = "N s/m"


def report_recheck(data, out):
    from jaxdamp.design.envelope import summarise

    env, labels, S = data.attrs["envelope"], data.attrs["labels"], data.attrs["duration"]
    st = data.attrs["settings"]
    C, old = np.asarray(data["confirmation"]["C"]), np.asarray(data["stored_C"])
    new_s, old_s = summarise(C, "worst"), summarise(old, "worst")
    pts = env["points"]
    fig, ax = scaffold.subplots(1, 1, figsize=(9, 4.6))
    xs = np.arange(len(pts))
    for i, lab in enumerate(labels):
        for j, (ss, d, mk) in enumerate(((old_s, st["duration"], "o"), (new_s, S, "s"))):
            ax.errorbar(xs + 0.12 * (2 * i + j - 1.5), ss["point_mean"][:, i],
                        yerr=1.96 * ss["point_se"][:, i], fmt=mk, color=f"C{i}",
                        mfc="none" if j == 0 else f"C{i}", capsize=2, label=f"{lab}, {d:g} s runs")
    ax.set_xticks(xs, [f"{f:g} Hz\n{1e3 * u:g} mm" for f, u in pts], fontsize=7)
    ax.set(xlabel="envelope point (frequency, base amplitude U)", ylabel="C_eq [N s/m]",
           title="run length: stored confirmation against fresh beds with longer runs (± 1.96 SE)")
    ax.legend(fontsize=8)
    scaffold.save_figure(fig, out)
    each = np.asarray(data["confirmation"]["stationary_each"])
    L = [*scaffold.head(f"Envelope design: the confirmation with {S:g} s runs (run-length "
                        "check, issue 41)", data.attrs),
         f"The designs of {data.attrs['designs_from']} (confirmed there with {st['duration']:g} "
         f"s runs), on {C.shape[2]} fresh beds each with {S:g} s runs; cost "
         f"{data['confirmation'].attrs['sim_seconds']:.4g} DEM system-seconds. Steady state "
         f"detected at {int(each.sum())} of {each.size} (point, bed) runs.", ""]
    rows = []
    for p, (f, u) in enumerate(pts):
        row = [f"{f:g} Hz, {1e3 * u:g} mm"]
        for i in range(len(labels)):
            d, h = welch(C[p, i], old[p, i])
            row += [scaffold.pm(new_s["point_mean"][p, i], new_s["point_se"][p, i], ".4g", ".2g"),
                    scaffold.pm(d, h, "+.3g", ".2g")]
        rows.append(row)
    L += scaffold.table(["point (f, U)"] + [h for lab in labels for h in (
        f"{lab}: C_eq at {S:g} s [N s/m]", f"− at {st['duration']:g} s (Welch 95 %)")], rows)
    d, h = welch(C[new_s["worst_point"][1], 1], C[new_s["worst_point"][0], 0])
    verdict = "wins" if d - h > 0 else "loses" if d + h < 0 else "undecided"
    L += ["", "| design | worst point | worst-case C_eq [N s/m] |", "| --- | --- | --- |"]
    for i, lab in enumerate(labels):
        f, u = pts[int(new_s["worst_point"][i])]
        L.append(f"| {lab} | {f:g} Hz, {1e3 * u:g} mm | "
                 f"{scaffold.pm(new_s['value'][i], new_s['se'][i], '.4g', '.2g')} |")
    L += ["", f"- Worst case at {S:g} s, envelope − single-point (Welch 95 %): "
          f"{scaffold.pm(d, h, '+.3g', '.2g', unit='N s/m')}: the envelope design "
          f"**{verdict}** by the stored result's rule."]
    scaffold.write_summary(out, L)


def report(data, out):
    from jaxdamp.design.envelope import summarise

    if data.attrs.get("mode") == "recheck":
        return report_recheck(data, out)

    env, v, labels = data.attrs["envelope"], data.attrs["verdicts"], data.attrs["labels"]
    c, sr, ty = data["confirmation"], data["search"], data["toy"]
    C = np.asarray(c["C"])
    s = summarise(C, "worst")
    pts = env["points"]
    fig, (a1, a2, a3) = scaffold.subplots(1, 3, figsize=(16, 4.6))
    xs = np.arange(len(pts))
    for i, lab in enumerate(labels):
        a1.errorbar(xs + 0.1 * (i - 0.5), s["point_mean"][:, i], yerr=1.96 * s["point_se"][:, i],
                    fmt="os"[i], capsize=3, label=f"{lab}, Lz = {c['X'][i][0]:.4g} m")
    a1.set_xticks(xs, [f"{f:g} Hz\n{1e3 * u:g} mm" for f, u in pts], fontsize=7)
    a1.set(xlabel="envelope point (frequency, base amplitude U)", ylabel="C_eq [N s/m]",
           title="B. confirmed on fresh beds (± 1.96 SE)")
    a1.legend(fontsize=8)
    X, m, se, rnd = (np.asarray(sr[k]) for k in ("X", "mean", "se", "round"))
    for r in np.unique(rnd):
        k = rnd == r
        a2.errorbar(X[k, 0], m[k], yerr=1.96 * se[k], fmt="o", capsize=2,
                    label="Sobol start" if r == 0 else f"batch {r} (Thompson)")
    a2.axvline(sr.attrs["best_x"][0], color="k", ls="--", label="recommended")
    a2.set(xlabel="Lz [m]", ylabel="worst-point C_eq [N s/m]",
           title="A. the batched search (in-search means ± 1.96 SE)")
    a2.legend(fontsize=8)
    gp, lhs = np.asarray(ty["gp"]), np.asarray(ty["lhs"])
    a3.plot(np.sort(lhs), np.arange(1, len(lhs) + 1) / len(lhs), label="Latin hypercube, best seen")
    a3.plot(np.sort(gp), np.arange(1, len(gp) + 1) / len(gp), label="GP + Thompson batches")
    a3.set(xlabel="regret f_max − f(recommended) [-]", ylabel="fraction of seeds",
           title=f"C. equal budget ({ty.attrs['designs']} designs × 2), known function")
    a3.legend(fontsize=8)
    scaffold.save_figure(fig, out)
    st = data.attrs["settings"]
    L = [*scaffold.head("Design for the operating envelope: single-point optimum vs envelope "
                        "design (issue 41)", data.attrs),
         f"Envelope: frequencies {env['frequencies']} Hz × base amplitudes "
         f"{[1e3 * u for u in env['levels']]} mm ({len(pts)} points), statistic: worst point "
         f"(min over points of the mean C_eq over beds). Runs of {st['duration']} s, steady "
         "state by MSER per bed.", "",
         "## A. The batched search (Lz)", "",
         f"{len(X)} designs × {st['replicates']} beds: Sobol start of {st['n_start']}, "
         f"{st['rounds']} batches of {st['batch']} by Thompson sampling on the Gaussian process "
         f"({sr.attrs['kernel']}). Recommended Lz = {sr.attrs['best_x'][0]:.4g} m (posterior "
         "worst-case C_eq "
         f"{scaffold.pm(sr.attrs['best_pred'], sr.attrs['best_pred_sd'], '.4g', '.2g')} N s/m); "
         f"cost {sr.attrs['sim_seconds']:.4g} DEM system-seconds (settling included), "
         f"{sr.attrs['wall'] / 60:.1f} min wall.", "",
         "## B. Confirmation on fresh beds", "",
         f"The single-point optimum from {data.attrs['single_source']}. "
         f"{C.shape[2]} fresh beds per design; cost {c.attrs['sim_seconds']:.4g} DEM "
         "system-seconds.", ""]
    L += scaffold.table(
        ["point (f, U)"] + [f"{lab} (Lz = {c['X'][i][0]:.4g} m) C_eq [N s/m]"
                            for i, lab in enumerate(labels)],
        [[f"{f:g} Hz, {1e3 * u:g} mm"] + [scaffold.pm(s["point_mean"][p, i], s["point_se"][p, i],
                                                        ".4g", ".2g") for i in range(2)]
         for p, (f, u) in enumerate(pts)])
    em = np.asarray(c["envelope_mean"])
    L += ["", "| design | worst point | worst-case C_eq [N s/m] | envelope mean C_eq [N s/m] |",
          "| --- | --- | --- | --- |"]
    for i, lab in enumerate(labels):
        f, u = pts[int(s["worst_point"][i])]
        L.append(f"| {lab} | {f:g} Hz, {1e3 * u:g} mm | "
                 f"{scaffold.pm(s['value'][i], s['se'][i], '.4g', '.2g')} | "
                 f"{scaffold.pm(*scaffold.mean_se(em[i]), '.4g', '.2g')} |")
    stat = np.asarray(c["stationary"])
    each = np.asarray(c["stationary_each"]) if "stationary_each" in c else None
    L += ["", f"- Worst case, envelope − single-point (Welch 95 % on each design's worst point): "
          f"{scaffold.pm(v['worst_difference'], v['worst_ci'], '+.3g', '.2g', unit='N s/m')}: "
          "the envelope design "
          f"**{v['worst']}** by the rule (interval above zero: wins; below: loses).",
          "- Envelope mean, envelope − single-point: "
          f"{scaffold.pm(v['mean_difference'], v['mean_ci'], '+.3g', '.2g', unit='N s/m')}.",
          f"- Steady state detected in {int(stat.sum())} of {stat.size} confirmation beds at "
          "every point" + ("" if each is None else f", at {int(each.sum())} of {each.size} "
                           "(point, bed) runs") + " (the rest: the final window's mean).", "",
          "## C. Why a surrogate-guided batch search", "",
          f"A known 2-D function (main peak 1 at (0.62, 0.35), secondary 0.4 at (0.15, 0.85); "
          f"noise sd 0.1 (1 + u₀), two replicates per design), {len(gp)} seeds, "
          f"{ty.attrs['designs']} designs each: regret of the recommendation, median "
          f"{np.median(gp):.3g} (search) against {np.median(lhs):.3g} (the Latin hypercube's best "
          f"observed design), mean {gp.mean():.3g} against {lhs.mean():.3g}; the search better "
          f"in {v['search_better_in']} of {v['toy_seeds']} seeds."]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, options=options, report=report)


if __name__ == "__main__":
    main()
