"""Bed dynamics with long series, periodicity levels and twin runs (thesis ch. 4; issue 13).

    python experiments/bed_dynamics_long.py            # full mode (see summary.md)
    python experiments/bed_dynamics_long.py --beds 5   # 5 beds per frequency (default 3)
    python experiments/bed_dynamics_long.py --quick    # test-sized

``sanchez2012-optimal`` at the thesis' frequencies of interest on ``--beds`` poured beds, each
a **twin pair** (:func:`jaxdamp.studies.twin.twin_sweep`: one grain of the second run moved by
1e-9 m). Per bed, for ``z_box`` and ``z_cm``: **periodicity levels** (strobe spread, power at the
drive's lines), the classifier's verdict and Kantz exponent, and the **twin divergence**
(:func:`jaxdamp.analysis.dynamics.divergence_exponent`). Writes ``data.h5``, ``figure.png``,
``summary.md``; the raw twin sweeps in ``--out/raw``.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

from jaxdamp.analysis import dynamics as dyn
from jaxdamp.io.common import put
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import replicate_configs
from jaxdamp.studies.twin import twin_sweep

try:
    from . import bed_dynamics as bd
except ImportError:  # run as a file: python experiments/<name>.py
    import bed_dynamics as bd
F_FULL = (10.0, 10.5, 11.0, 13.0, 14.5, 21.0)
#: thesis ch. 4 at these frequencies (SPEC §6 / thesis fig. 4.1)
THESIS = {10.0: "period-2", 10.5: "torus, wrinkling", 11.0: "torus break-up → chaos",
          13.0: "chaotic (zone I)", 14.5: "periodic window (2 impacts per period)",
          21.0: "chaotic (zone II)"}
TOLERANCES = (0.01, 0.05)
DELTA = 1e-9  # [m]
SIGNALS = ("z_box", "z_cm")
BEDS = 3  # default number of independently poured beds per frequency
#: per-bed measures combined over the beds (mean ± SE): key -> value from one bed's analysis
MEASURES = {"s1": lambda d: d["spread1"], "s2": lambda d: d["spread2"],
            "off1": lambda d: 1 - d["harm1"], "off2": lambda d: 1 - d["harm2"],
            "kantz": lambda d: d["kantz_per_period"],
            "twin": lambda d: d["div_exponent"], "twin_per_period": lambda d: d["div_per_period"],
            "plateau_rel": lambda d: d["div_plateau_rel"],
            "t_sat": lambda d: (d["div_t_sat"] if d["div_saturated"] and not d["div_bound"]
                                else np.nan)}
DIVERGENCE = ("exponent", "per_period", "saturated", "t_sat", "grew")  # kept as div_<key>
COUNTS = ("beds", "labels", "bounds", "not_grown", "not_reached")  # over_beds/<signal> attrs


def settings(quick: bool) -> dict:
    return (dict(freqs=(14.5, 21.0), duration=1.2, t_perturb=0.4, transient=0.4, settle=0.15,
                 chunk=0.1) if quick else
            dict(freqs=F_FULL, duration=12.0, t_perturb=5.0, transient=3.0, settle=1.0, chunk=0.2))


def analyse_pair(t, ref: dict, twin: dict, f: float, s: dict) -> dict:
    keep = t >= s["transient"]
    out = {}
    for name in SIGNALS:
        x = ref[name][keep]
        scale = float(np.std(x))
        sec = dyn.poincare_section(t[keep], x, f)
        spread = dyn.strobe_spread(sec, scale, max_period=4)
        spec = dyn.power_spectrum(t[keep], x, f, method="periodogram")
        h1, h2 = (dyn.harmonic_fraction(spec, f, k) for k in (1, 2))
        c = dyn.classify(t[keep], x, f)
        lyap = c.lyapunov
        span = ((lyap.fit_range[1] - lyap.fit_range[0]) * lyap.dt * f) if lyap else np.nan
        div = dyn.divergence_exponent(t, ref[name] - twin[name], f, t_start=s["t_perturb"],
                                      d0=DELTA)
        out[name] = dict(scale=scale, spread1=float(spread[0]), spread2=float(spread[1]),
                         harm1=h1, harm2=h2, label=c.label, period=c.period or 0,
                         kantz_per_period=(c.exponent / f) if c.exponent is not None else np.nan,
                         kantz_span_periods=span, div_periods=div["periods_fitted"],
                         div_plateau_rel=div["plateau"] / scale, div_bound=div["lower_bound"],
                         **{f"div_{k}": div[k] for k in DIVERGENCE},
                         D=div["D"], t_D=div["t_D"], n_section=len(sec.t))
    return out


def within(spread: float, harm: float, tol: float) -> bool:
    """Period-k at tolerance ``tol``: the strobe spread and the off-line power both below it."""
    return bool(spread < tol and 1 - harm < tol)


def level(spread: float, harm: float) -> str:
    """Period-k verdict: the tightest tolerance within which it holds."""
    ok = [tol for tol in TOLERANCES if within(spread, harm, tol)]
    return f"within {100 * ok[0]:g} %" if ok else "no"


def combine(beds: list[dict]) -> dict:
    """One frequency's beds (:func:`analyse_pair`) per signal: each measure's values, mean, SE
    and count (:func:`scaffold.across`); counts of beds period-k at each tolerance, of twin
    exponents only lower bounds, not grown or not saturated; the classifier's labels."""
    out = {}
    for name in SIGNALS:
        ds = [b[name] for b in beds]
        c = {"beds": len(ds)}
        for key, fn in MEASURES.items():
            v = np.array([fn(d) for d in ds], float)
            e = scaffold.across(v)
            c[key] = dict(values=v, mean=e.mean, se=e.se, n=e.n)
        c.update({f"period{k}_{tol:g}": sum(within(d[f"spread{k}"], d[f"harm{k}"], tol)
                                            for d in ds) for k in (1, 2) for tol in TOLERANCES})
        c["labels"] = [bd.regime(d["label"], d["period"]) for d in ds]
        c["bounds"] = sum(bool(d["div_bound"]) for d in ds)
        c["not_grown"] = sum(not d["div_grew"] for d in ds)
        c["not_reached"] = sum(bool(d["div_grew"] and not d["div_saturated"]) for d in ds)
        out[name] = c
    return out


def compute(quick: bool, log, ctx):
    s = settings(quick)
    s["beds"] = ctx.args.beds
    cfg = bd.optimal_config(s["duration"], s["settle"], chunk=s["chunk"])
    bed_cfgs = replicate_configs([cfg], s["beds"])  # the package's replicate seeds
    s["seeds"] = [int(c.numerics.seed) for c in bed_cfgs]
    rows = {f: dict(beds=[], identical_before=[]) for f in s["freqs"]}
    wall, balance = 0.0, []
    for r, bc in enumerate(bed_cfgs):
        raw = ctx.raw(f"twin_t{s['duration']:g}_f{len(s['freqs'])}_seed{bc.numerics.seed}.h5")
        log(f"bed {r + 1} of {s['beds']} (seed {bc.numerics.seed}): {raw}")
        res = twin_sweep(bc, s["freqs"], s["t_perturb"], raw, delta=DELTA, progress=ctx.progress)
        wall += float(res.summary["wall_time"])
        balance.append(np.ravel(res.summary["balance_error"]))
        rec = res.records
        for i, f in enumerate(s["freqs"]):
            ref, twin = ({k: rec[k][j] for k in ("t", *SIGNALS)} for j in (2 * i, 2 * i + 1))
            pre = ref["t"] < s["t_perturb"] - 1e-9
            rows[f]["identical_before"].append(
                float(np.max(np.abs(ref["z_box"][pre] - twin["z_box"][pre]))))
            rows[f]["beds"].append(an := analyse_pair(ref["t"], ref, twin, f, s))
            log(f"  {f:g} Hz: twin exponent of z_box {an['z_box']['div_exponent']:.3g} 1/s")
    for row in rows.values():
        row["stats"] = combine(row["beds"])
    result = dict(rows=rows, config=cfg, wall=wall, balance=np.concatenate(balance),
                  beds=s["beds"], seeds=s["seeds"])
    return result, lambda path, prov: record(result, s, path, prov)


def _beds(text: str) -> int:
    if int(text) < 1:
        raise argparse.ArgumentTypeError(f"{text}: need at least one bed per frequency")
    return int(text)


def options(ap):
    ap.add_argument("--beds", type=_beds, default=BEDS, metavar="R",
                    help=f"independently poured beds per frequency (default {BEDS}; ≥ 2: SE)")


def record(r, s, out, prov):
    with scaffold.data_file(out, dict(prov, sweep_wall_s=r["wall"]), settings=json.dumps(s),
                            config=r["config"].to_json()) as h:
        h.attrs.update(delta=DELTA, beds=r["beds"], seeds=r["seeds"],
                       balance_error_max=float(np.max(r["balance"])))
        for f, row in r["rows"].items():
            g = h.create_group(f"f_{f:g}")
            g.attrs.update(frequency=f, identical_before_perturbation=row["identical_before"])
            for name, c in row["stats"].items():
                gs = g.create_group(f"over_beds/{name}")
                gs.attrs["what"] = ("per-bed values (dataset), mean, SE over the beds and count "
                                    "of finite values (attributes); period-k counts of beds")
                for key in MEASURES:
                    ds = gs.create_dataset(key, data=c[key]["values"])
                    ds.attrs.update(mean=c[key]["mean"], se=c[key]["se"], n=c[key]["n"])
                gs.attrs.update({k: c[k] for k in c if k.startswith("period") or k in COUNTS})
            for b, (bed, seed) in enumerate(zip(row["beds"], r["seeds"])):
                gb = g.create_group(f"bed_{b}")
                gb.attrs.update(seed=seed, identical_before_perturbation=row["identical_before"][b])
                for name, d in bed.items():
                    gg = gb.create_group(name)
                    gg.attrs.update({k: v for k, v in d.items() if np.ndim(v) == 0})
                    put(gg, "twin_distance", d["D"], "m",
                        what="per-period maximum of |reference − perturbed|")
                    put(gg, "twin_t", d["t_D"], "s")


def report(data, out):
    """Figure and summary from ``data.h5``: its beds as :func:`analyse_pair` gave them."""
    a = data.attrs
    s, R, rows = a["settings"], a["beds"], {}
    for f in s["freqs"]:
        g = data[f"f_{f:g}"]
        beds = [{name: dict(g[f"bed_{b}"][name].attrs, D=g[f"bed_{b}"][name]["twin_distance"],
                            t_D=g[f"bed_{b}"][name]["twin_t"]) for name in SIGNALS}
                for b in range(R)]
        rows[f] = dict(beds=beds, stats=combine(beds),
                       identical_before=list(g.attrs["identical_before_perturbation"]))
    fig, axs = scaffold.subplots(1, 3, figsize=(15, 4.6))
    for j, (f, row) in enumerate(rows.items()):
        for b, bed in enumerate(row["beds"]):
            for name, ax in zip(SIGNALS, axs[:2]):
                ax.semilogy(bed[name]["t_D"], bed[name]["D"], color=f"C{j}",
                            ls=("-", "--", ":", "-.")[b % 4], lw=0.9,
                            label=f"{f:g} Hz" if b == 0 else None)
    for name, ax in zip(SIGNALS, axs[:2]):
        ax.axvline(s["t_perturb"], color="k", lw=0.6, ls=":")
        ax.set(xlabel="time t [s]", ylabel=f"twin distance |Δ{name}| per period (max) [m]")
        ax.set_title(f"{name}: twins, one grain moved {DELTA:g} m at t = {s['t_perturb']:g} s;"
                     f"\n{R} beds (line styles)", fontsize=9)
        ax.legend(fontsize=7)
    x = np.arange(len(rows))
    for dx, key, mk, lab in ((-0.15, "s1", "o", "strobe spread s₁"),
                             (0.0, "s2", "s", "strobe spread s₂"),
                             (0.15, "off1", "^", "power off the drive's lines, 1 − h₁")):
        cs = [row["stats"]["z_box"][key] for row in rows.values()]
        axs[2].semilogy(np.repeat(x + dx, R), np.maximum([c["values"] for c in cs], 1e-8).ravel(),
                        mk, color="0.6", ms=4, mfc="none")
        m = np.array([max(c["mean"], 1e-8) for c in cs])
        e = np.array([c["se"] if np.isfinite(c["se"]) else 0.0 for c in cs])
        axs[2].errorbar(x + dx, m, yerr=[np.minimum(e, m * 0.999), e], fmt=mk, capsize=3,
                        label=f"{lab} (mean ± SE; grey: beds)")
    for tol in TOLERANCES:
        axs[2].axhline(tol, color="0.5", lw=0.7, ls="--")
    axs[2].set_xticks(x, [f"{f:g}" for f in rows])
    axs[2].set(xlabel="drive frequency f [Hz]",
               ylabel="periodicity level of z_box [-] (dashed: 1 %, 5 % tolerances)")
    axs[2].set_title(f"distance from a period-1 / period-2 orbit, {R} beds", fontsize=9)
    axs[2].legend(fontsize=7)
    scaffold.save_figure(fig, out, "figure.png")
    _summary(a, rows, out)


def over_beds(c: dict, digits: int = 2, bound: bool = False) -> str:
    """``mean ± SE`` of a combined measure (``≥``: over lower bounds; n where not all beds)."""
    if not np.isfinite(c["mean"]):
        return "n/a"
    n = ("" if np.isfinite(c["se"]) and c["n"] == len(c["values"]) else f" (n = {c['n']})")
    return ("≥ " if bound else "") + scaffold.pm(c["mean"], c["se"], digits) + n


def counts(c: dict, k: int) -> str:
    """Period-k verdict as counts of beds, e.g. ``within 1 % on 3 of 3 beds``."""
    R = c["beds"]
    n1, n5 = (c[f"period{k}_{tol:g}"] for tol in TOLERANCES)
    return (f"within 1 % on {R} of {R} beds" if n1 == R else f"no bed within 5 % (0 of {R})"
            if n5 == 0 else f"within 1 % on {n1}, within 5 % on {n5} of {R} beds")


def saturation(c: dict) -> str:
    parts = [over_beds(c["t_sat"], 3)] if np.isfinite(c["t_sat"]["mean"]) else []
    parts += [f"{text} on {c[k]}" for k, text in (("bounds", "within the first period"), (
        "not_reached", "not reached"), ("not_grown", "did not grow")) if c[k]]
    return "; ".join(parts)


def _bed_cell(d: dict, key: str) -> str:
    v = MEASURES[key](d)
    if key == "twin" or key == "twin_per_period":
        return ("≥ " if d["div_bound"] else "") + f"{v:.3g}"
    if key == "t_sat":
        return ("1st period" if d["div_bound"] else f"{v:.2f}" if np.isfinite(v) else
                "not reached" if d["div_grew"] else "no growth")
    return f"{v:.2g}"


def _summary(a, by_f, out):
    R, s, seeds = a["beds"], a["settings"], ", ".join(str(x) for x in a["seeds"])
    ident = max(max(row["identical_before"]) for row in by_f.values())
    steady = s["duration"] - s["transient"]
    L = [*scaffold.head("Bed dynamics: long series, periodicity levels, twin runs "
                        "(thesis ch. 4)", a, a["sweep_wall_s"]),
         f"`sanchez2012-optimal`, **{R} independently poured beds** per frequency (seeds "
         f"{seeds}: the package's replicate seeds), one twin pair per bed and "
         f"frequency, {s['duration']:g} s per run (the thesis: ≈ 197 s), analysed after "
         f"t = {s['transient']:g} s ({steady:g} s = "
         + ", ".join(f"{steady * f:.0f}" for f in s["freqs"]) + " drive periods); one grain "
         f"moved by {DELTA:g} m at t = {s['t_perturb']:g} s in the second run of each pair "
         f"(before that the pairs agree to {ident:.1e} m). Energy balance error ≤ "
         f"{a['balance_error_max']:.1e}. Numbers: mean ± SE over the {R} beds (n = … "
         "where a bed gave no value); verdicts: counts of beds.", "",
         "s_k = RMS distance of the section from a period-k orbit over the orbit's std; h_k = "
         "power fraction at the lines n f/k; period-k at a tolerance (1 %: the classifier's; "
         "5 %) when s_k and 1 − h_k are below it. Kantz: fitted over > 1 period (nan where the "
         "classifier finds a period). Twins within a factor 10 of their plateau in the first "
         f"period give only a lower bound ln(D₀/{DELTA:g} m)/T (≥, also on a mean containing "
         "one); the plateau time averages the beds that saturated later. Grains that diverge "
         "at once while z_box stays within ~1 % of its orbit (plateau / orbit size) are "
         "chaotic at the grain level, nearly periodic at the damper's.", ""]
    levels = ["s₁", "s₂", "1 − h₁", "1 − h₂", "period-1", "period-2"]
    twin = ["twin λ [1/s]", "twin λ/f"]
    for name in SIGNALS:
        rows, per_bed = [], []
        for f, row in by_f.items():
            c = row["stats"][name]
            bound = c["bounds"] > 0
            rows.append([f"{f:g}", THESIS.get(f, ""),
                         *(over_beds(c[k]) for k in ("s1", "s2", "off1", "off2")),
                         counts(c, 1), counts(c, 2), bd.tally(c["labels"], ones=True),
                         over_beds(c["kantz"], 3), over_beds(c["twin"], 3, bound),
                         over_beds(c["twin_per_period"], 3, bound), saturation(c),
                         over_beds(c["plateau_rel"])])
            for b, (d, seed) in enumerate(zip((bed[name] for bed in row["beds"]), a["seeds"])):
                per_bed.append([f"{f:g}", f"{b} ({seed})",
                                *(_bed_cell(d, k) for k in ("s1", "s2", "off1", "off2")),
                                *(level(d[f"spread{k}"], d[f"harm{k}"]) for k in (1, 2)),
                                bd.regime(d["label"], d["period"]),
                                f"{d['kantz_per_period']:.3g} ({d['kantz_span_periods']:.1f})",
                                *(_bed_cell(d, k) for k in ("twin", "twin_per_period", "t_sat",
                                                            "plateau_rel"))])
        L += [f"## {name}", "", *scaffold.table(
            ["f [Hz]", "thesis", *levels, "classifier (beds)", "Kantz λ/f", *twin,
             "twin plateau at [s]", "plateau / orbit size"], rows), "", f"Per bed ({name}):", "",
            *scaffold.table(["f [Hz]", "bed (seed)", *levels, "classifier",
                             "Kantz λ/f (span [periods])", *twin, "plateau at [s]",
                             "plateau / orbit size"], per_bed), ""]
    L += ["The twin exponent is the whole system's largest (6N + 2 ≈ 1500 dimensions, no "
          "embedding): chaotic grains in a nearly periodic box give a positive one reaching "
          "z_box only as far as their forces do; it cannot tell chaos from amplified round-off."]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, options, report=report)


if __name__ == "__main__":
    main()
