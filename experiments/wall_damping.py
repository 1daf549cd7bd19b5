"""The grain–wall damping convention and what it changes in the driven box (issue 13, item 5).

    python experiments/wall_damping.py            # full mode (~15 min on 2 cores)
    python experiments/wall_damping.py --quick    # test-sized

The 2023 paper does not say how its grain–wall damping was calibrated. ``Config.wall_damping``
offers two readings (``docs/physics.md`` §7): ``"mixed"`` — the wall's constant, calibrated on
2.5 mm grains, mixed with each grain's (a 1.25 mm grain then bounces off the wall with
ε ≈ 0.69 at 1 m/s, a 2.5 mm grain with ≈ 0.78) — and ``"calibrated"`` — every species'
grain–wall contact has ε = 0.75 at 1 m/s. Both are run on the paper's reference box (300 grains
of 2.5 mm) and on its class-a mixture at σ = 0.5 (equal mass of 2.5 mm and 1.25 mm grains), at
three drive amplitudes, with independent replicates (independently seeded beds) and the paper's
protocol (10 transient periods, 50 analysed; the steady state detected by MSER on the
per-period ``E_d``). Verdict per case: the relative change of ``⟨E_d⟩`` with its Welch 95 %
interval. Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import json
import math
import sys
import time

import numpy as np

from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics import restitution as rst
from jaxdamp.physics.model import build, contact_law
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies import scaffold

CONVENTIONS = ("mixed", "calibrated")


def settings(quick: bool) -> dict:
    if quick:
        return dict(families=(("varela2023-reference", None), ("varela2023-a", 0.5)),
                    amps=[0.03], periods=20, transient=1, R=2, settle=0.05)
    return dict(families=(("varela2023-reference", None), ("varela2023-a", 0.5)),
                amps=[0.02, 0.03, 0.04], periods=50, transient=10, R=4, settle=None)


def wall_restitution(cfg) -> list:
    """ε at 1 m/s of one grain of every species against the wall under ``cfg``'s convention
    (the force law integrated: :func:`jaxdamp.physics.restitution.collision`)."""
    _, p = build(cfg)
    law = contact_law(cfg)
    out = []
    for s, sp in enumerate(cfg.grains):
        row = np.asarray(p.wall_table[s])
        m = sp.material.density * 4 / 3 * math.pi * sp.radius ** 3
        out.append(rst.collision(A=float(row[law.column("A")]), m_star=m, R_star=sp.radius,
                                 E_star=float(row[law.column("E_star")]),
                                 v=1.0).restitution)
    return out


def run(s: dict, log) -> list:
    rows = []
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
                             eps_wall=wall_restitution(cfg), values=st["values"],
                             mean=st["mean"], se=st["se"], ci95=st["ci95"],
                             stationary=st["stationary"], wall=time.perf_counter() - t0,
                             mass=float(r.summary["mass"][0])))
            log(f"{name} {conv}: ε_wall = {np.round(rows[-1]['eps_wall'], 4)}, ⟨E_d⟩ = "
                + ", ".join(scaffold.pm(m, c, 4) for m, c in zip(st["mean"], st["ci95"]))
                + f" J ({time.perf_counter() - t0:.0f} s)")
    return rows


def verdicts(rows: list, amps) -> list:
    out = []
    for name in dict.fromkeys(r["family"] for r in rows):
        mix, cal = (next(r for r in rows if r["family"] == name and r["convention"] == c)
                    for c in CONVENTIONS)
        for i, a in enumerate(amps):
            x, y = (np.asarray(r["values"][i], float) for r in (cal, mix))
            x, y = x[np.isfinite(x)], y[np.isfinite(y)]  # stationary beds only
            row = dict(family=name, amplitude=a, mixed=float(np.mean(y)) if len(y) else math.nan,
                       calibrated=float(np.mean(x)) if len(x) else math.nan, n=(len(x), len(y)))
            if min(len(x), len(y)) < 2:
                out.append(dict(row, rel=math.nan, rel_ci=math.nan, significant=None))
                continue
            d, half = welch(x, y)
            out.append(dict(row, rel=float(d / y.mean()), rel_ci=float(half / y.mean()),
                            significant=bool(abs(d) > half)))
    return out


def write(rows, v, s, path, prov):
    with scaffold.data_file(path, prov, settings=s, verdicts=v) as h:
        for r in rows:
            g = h.create_group(f"{r['family']}/{r['convention']}")
            g.create_dataset("amplitude", data=np.asarray(s["amps"])).attrs["units"] = "m"
            for k in ("values", "mean", "se", "ci95"):
                g.create_dataset(k, data=r[k]).attrs["units"] = "J"
            g.create_dataset("stationary", data=r["stationary"])
            g.create_dataset("eps_wall", data=np.asarray(r["eps_wall"]))
            g.attrs.update(wall_time=r["wall"], mass=r["mass"], sigma=json.dumps(r["sigma"]))

    fams = list(dict.fromkeys(r["family"] for r in rows))
    fig, axes = scaffold.subplots(1, len(fams), figsize=(5 * len(fams), 3.8), squeeze=False)
    a = 100 * np.asarray(s["amps"])
    for ax, fam in zip(axes[0], fams):
        for k, r in enumerate(r for r in rows if r["family"] == fam):
            ax.errorbar(a + (k - 0.5) * 0.03, r["mean"], yerr=r["ci95"], fmt="o-", capsize=3,
                        label=f"wall_damping = {r['convention']} (ε_wall at 1 m/s: "
                              + ", ".join(f"{e:.3f}" for e in r["eps_wall"]) + ")")
        ax.set(xlabel="drive amplitude A_d [cm]", ylabel="⟨E_d⟩ per period [J]", title=fam)
        ax.legend(fontsize=7)
    scaffold.save_figure(fig, path)

    L = [*scaffold.head("Grain–wall damping convention: mixed vs calibrated (issue 13, item "
                         "5)", prov),
         f"Protocol: {s['transient']} transient + {s['periods']} analysed periods at 70 Hz, "
         f"{s['R']} independent beds per point; ⟨E_d⟩ = steady mean of the per-period "
         "dissipation after the MSER-detected start; intervals Student-t 95 % across beds, "
         "differences Welch 95 %.", ""]
    L += scaffold.table(
        ["family", "convention", "ε grain–wall at 1 m/s (per species)"]
        + [f"⟨E_d⟩ at {100 * a:g} cm [J]" for a in s["amps"]] + ["stationary beds"],
        [[r["family"], r["convention"], ", ".join(f"{e:.3f}" for e in r["eps_wall"])]
         + [scaffold.pm(m, c, 4) for m, c in zip(r["mean"], r["ci95"])]
         + [f"{int(np.sum(r['stationary']))} of {np.size(r['stationary'])}"] for r in rows])
    L += ["", "Relative change of ⟨E_d⟩, calibrated vs mixed:", ""]
    for d in v:
        if d["significant"] is None:
            L.append(f"- {d['family']} at {100 * d['amplitude']:g} cm: undetermined — "
                     f"stationary beds (calibrated, mixed) = {d['n']}, need ≥ 2 each.")
            continue
        L.append(f"- {d['family']} at {100 * d['amplitude']:g} cm: "
                 f"{scaffold.pm(d['rel'], d['rel_ci'], '+.2f', '.2f', '%', 100)} — "
                 + ("significant" if d["significant"] else "not significant at 95 %")
                 + f" ({d['n'][0]} and {d['n'][1]} stationary beds).")
    L += ["", "Every preset uses `wall_damping = \"mixed\"`; summaries of the driven box "
          "(binary mixtures, efficiency) depend on that choice by the amounts above."]
    scaffold.write_summary(path, L)


def compute(quick, log, _ctx):
    s = settings(quick)
    rows = run(s, log)
    v = verdicts(rows, s["amps"])
    return {"rows": rows, "verdicts": v}, lambda path, prov: write(rows, v, s, path, prov)


main = scaffold.entry(__file__, __doc__, compute)

if __name__ == "__main__":
    sys.exit(0 if main() else 1)
