"""The grain–wall damping convention and what it changes in the driven box (issue 13, item 5).

    python experiments/wall_damping.py            # full mode (~20 min on 2 cores)
    python experiments/wall_damping.py --quick    # test-sized

``Config.wall_damping`` (``docs/physics.md`` §7; the 2023 paper does not say which it used):
``"mixed"`` (the wall's constant, calibrated on 2.5 mm grains, mixed with each grain's) or
``"calibrated"`` (every species' grain–wall ε = 0.75 at 1 m/s), on the paper's reference box
and class-a mixture (σ = 0.5) at three drive amplitudes, independently seeded beds; ⟨E_d⟩ per
period after the MSER-detected start, compared by the Welch 95 % interval of its relative
change. Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np

from jaxdamp.analysis.stats import across, welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics import restitution as rst
from jaxdamp.physics.model import build, contact_law
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies import scaffold

CONVENTIONS = ("mixed", "calibrated")


def settings(quick: bool) -> dict:
    fams = (("varela2023-reference", None), ("varela2023-a", 0.5))
    if quick:
        return dict(families=fams, amps=[0.03], periods=20, transient=1, R=2, settle=0.05)
    return dict(families=fams, amps=[0.02, 0.03, 0.04], periods=50, transient=10, R=4, settle=None)


def wall_restitution(cfg) -> list:
    """ε at 1 m/s of one grain of every species against the wall under ``cfg``'s convention."""
    law, table = contact_law(cfg), np.asarray(build(cfg)[1].wall_table)
    return [rst.restitution(sp.material.density * 4 / 3 * math.pi * sp.radius ** 3, sp.radius,
                            float(row[law.column("E_star")]), 1.0, A=float(row[law.column("A")]))
            for sp, row in zip(cfg.grains, table)]


def verdicts(rows: list, amps) -> list:
    """Per family and amplitude: calibrated − mixed over the stationary beds, Welch 95 %."""
    out = []
    for name in dict.fromkeys(r["family"] for r in rows):
        mix, cal = (next(r for r in rows if r["family"] == name and r["convention"] == c)
                    for c in CONVENTIONS)
        for i, a in enumerate(amps):
            x, y = across(cal["values"][i]), across(mix["values"][i])
            d, half = welch(x.values, y.values)
            ok = bool(np.isfinite(half))
            out.append(dict(family=name, amplitude=a, mixed=y.mean, calibrated=x.mean,
                            n=(x.n, y.n), rel=d / y.mean if ok else math.nan,
                            rel_ci=half / y.mean if ok else math.nan,
                            significant=bool(abs(d) > half) if ok else None))
    return out


def record(rows, v, s, out, prov):
    with scaffold.data_file(out, prov, settings=s, verdicts=v) as h:
        for r in rows:
            g = h.create_group(f"{r['family']}/{r['convention']}")
            g.create_dataset("amplitude", data=np.asarray(s["amps"])).attrs["units"] = "m"
            for k in ("values", "mean", "se", "ci95"):
                g.create_dataset(k, data=r[k]).attrs["units"] = "J"
            g.create_dataset("stationary", data=r["stationary"])
            g.create_dataset("eps_wall", data=np.asarray(r["eps_wall"]))
            g.attrs.update(wall_time=r["wall"], mass=r["mass"], sigma=json.dumps(r["sigma"]))


def report(data, out):
    s, v = data.attrs["settings"], data.attrs["verdicts"]
    fams = [name for name, _ in s["families"]]
    rows = [dict(data[fam][conv], family=fam, convention=conv)
            for fam in fams for conv in CONVENTIONS]
    fig, axes = scaffold.subplots(1, len(fams), figsize=(5 * len(fams), 3.8), squeeze=False)
    for ax, fam in zip(axes[0], fams):
        for k, r in enumerate(r for r in rows if r["family"] == fam):
            ax.errorbar(100 * r["amplitude"] + (k - 0.5) * 0.03, r["mean"], yerr=r["ci95"],
                        fmt="o-", capsize=3, label=f"wall_damping = {r['convention']} (ε_wall "
                        "at 1 m/s: " + ", ".join(f"{e:.3f}" for e in r["eps_wall"]) + ")")
        ax.set(xlabel="drive amplitude A_d [cm]", ylabel="⟨E_d⟩ per period [J]", title=fam)
        ax.legend(fontsize=7)
    scaffold.save_figure(fig, out)
    L = [*scaffold.head("Grain–wall damping convention: mixed vs calibrated (issue 13, item "
                         "5)", data.attrs),
         f"Protocol: {s['transient']} transient + {s['periods']} analysed periods at 70 Hz, "
         f"{s['R']} independent beds per point; intervals Student-t 95 % across beds, "
         "differences Welch 95 %.", ""]
    L += scaffold.table(
        ["family", "convention", "ε grain–wall at 1 m/s (per species)"]
        + [f"⟨E_d⟩ at {100 * a:g} cm [J]" for a in s["amps"]] + ["stationary beds"],
        [[r["family"], r["convention"], ", ".join(f"{e:.3f}" for e in r["eps_wall"])]
         + [scaffold.pm(m, c, 4) for m, c in zip(r["mean"], r["ci95"])]
         + [f"{int(np.sum(r['stationary']))} of {np.size(r['stationary'])}"] for r in rows])
    L += ["", "Relative change of ⟨E_d⟩, calibrated vs mixed:", ""] + [
        f"- {d['family']} at {100 * d['amplitude']:g} cm: "
        + ("undetermined" if d["significant"] is None
           else scaffold.pm(d["rel"], d["rel_ci"], "+.2f", ".2f", "%", 100) + " — "
           + ("significant" if d["significant"] else "not significant at 95 %"))
        + f" ({d['n'][0]} and {d['n'][1]} stationary beds)." for d in v]
    L += ["", "Every preset uses `wall_damping = \"mixed\"`; summaries of the driven box "
          "(binary mixtures, efficiency) depend on that choice by the amounts above."]
    scaffold.write_summary(out, L)


def compute(quick, log, _ctx):
    s, rows = settings(quick), []
    for name, sigma in s["families"]:
        for conv in CONVENTIONS:
            cfg = apply_overrides(presets.family(name, sigma), {"wall_damping": conv})
            if s["settle"] is not None:
                cfg = apply_overrides(cfg, {"numerics.settle_time": s["settle"]})
            t0 = time.perf_counter()
            r = ef.measure(cfg, s["amps"], periods=s["periods"], transient=s["transient"],
                           replicates=s["R"], progress=False, echo=None)
            st = r.steady["E_d"]
            rows.append(dict(family=name, sigma=sigma, convention=conv,
                             eps_wall=wall_restitution(cfg), wall=time.perf_counter() - t0,
                             mass=float(r.summary["mass"][0]),
                             **{k: st[k] for k in ("values", "mean", "se", "ci95", "stationary")}))
            log(f"{name} {conv}: ⟨E_d⟩ = {np.round(st['mean'], 4)} J")
    v = verdicts(rows, s["amps"])
    return {"rows": rows, "verdicts": v}, lambda out, prov: record(rows, v, s, out, prov)


main = scaffold.entry(__file__, __doc__, compute, report=report)

if __name__ == "__main__":
    sys.exit(0 if main() else 1)
