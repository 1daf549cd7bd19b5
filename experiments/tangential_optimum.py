"""Does the tangential law move the thesis' optimum? The optimal box height and the equivalent
damping there, under the viscous law and under the Hertz–Mindlin spring with history (issue 39,
"does the choice matter?").

    python experiments/tangential_optimum.py          # 9 frequencies x 5 heights x 3 beds x 2
                                                       # laws, 2.5 s (about an hour on 2 cores)
    python experiments/tangential_optimum.py --quick   # 4 x 3 x 2 x 2, 0.4 s (minutes)

The box-height scan of ``experiments/gap_scan.py`` (its protocol, frequencies, fits and
optimum: :func:`experiments.gap_scan.analyse`) around the thesis' optimum (``Lz`` 0.1095–0.162
m, C = 7.6 N s/m), once per tangential law. Per bed: the optimum ``Lz*`` of the largest
``C_ef`` (absolute-residual 1-DOF fit, the thesis' weighting; parabola in ``log Lz``) with
``C_eq = C_ef(Lz*)`` there, and the height of the smallest resonant amplitude with that
amplitude. The beds of the two laws share seeds but settle under their own law, so the
comparison is unpaired: Mindlin / viscous − 1 with its Welch interval
(:func:`experiments.systematics.shift`).

**The rule, fixed before the run** (:func:`jaxdamp.analysis.verdicts.outcome`, ``equivalent``:
two one-sided tests at 5 % each): a quantity is *unchanged* by the law if ``|δ| + t₀.₉₅ SE ≤
m``, *changed* if ``|δ| − t₀.₉₅ SE > m``, else undecided. Margins: for the heights, the
resolution at which the thesis states its optimum — one of its grid heights, 0.1225 m, whose
nearer neighbour lies 4.5 % away — half of it, **2.2 %**; for ``C_eq`` and the resonant
amplitude, the systematic budget of ``Z_res`` at the thesis point (``experiments/systematics``;
``C_ef`` takes ``Z_res``'s budget) with its tangential-law term left out (it is what is
measured here).

Writes ``data.h5``, ``figure.png`` and ``summary.md`` in ``--out``; raw sweeps (resumable) in
``--out/raw``.
"""

from __future__ import annotations

import math
import os

import numpy as np

from jaxdamp.analysis.stats import replicate_extrema
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.io.common import put
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import reuse_or_run

try:  # imported as experiments.tangential_optimum (the tests), or run as a script
    from experiments import gap_scan as gs
    from experiments import systematics as sy
except ImportError:
    import gap_scan as gs
    import systematics as sy

LAWS = ("viscous", "mindlin")
#: The thesis' optimum as it states it: a grid height, and its nearer neighbour's distance.
HEIGHT_MARGIN = 0.5 * (1.0 - 0.117 / gs.THESIS_OPTIMUM)  # 2.2 %
#: Per bed: name, unit, label, and whether it is a height (margin HEIGHT_MARGIN).
QUANTITIES = (("Lz_opt", "m", "optimal height Lz* (largest C_ef)", True),
              ("C_eq", "N s/m", "C_eq = C_ef at Lz*", False),
              ("Lz_min_peak", "m", "height of the smallest resonant amplitude", True),
              ("Z_min_peak", "m", "the smallest resonant amplitude", False))


def settings(quick: bool) -> dict:
    if quick:
        return dict(quick_mode=True, lz=(0.087, 0.1225, 0.162), freqs=(12.0, 14.5, 15.25, 18.0),
                    C=7.6, duration=0.4, settle=0.15, R=2)
    return dict(lz=(0.1095, 0.117, 0.1225, 0.147, 0.162), freqs=gs.F_FULL, C=7.6,
                duration=2.5, settle=0.3, R=3)


def law_config(s: dict, law: str):
    """``gap_scan``'s configuration at ``s`` under tangential law ``law``."""
    return apply_overrides(presets.get("sanchez2012-optimal"), {
        "primary.C": s["C"], "numerics.duration": s["duration"], "numerics.record_dt": 1e-3,
        "numerics.settle_time": s["settle"], "numerics.chunk": 0.1, "tangential_law": law})


def compute(quick: bool, log, ctx):
    s = settings(quick)
    out = {}
    for law in LAWS:
        cfg = law_config(s, law)
        res = reuse_or_run(cfg, {"frequency": list(s["freqs"]), "box.Lz": list(s["lz"])},
                           ctx.raw(f"sweep_{law}_R{s['R']}.h5"), progress=ctx.progress,
                           replicates=s["R"])
        a = gs.analyse(res, cfg, s)
        w = gs.THESIS_WEIGHTING
        out[law] = dict(cfg=cfg, wall=float(res.summary["wall_time"]), Zr=a["Zr"],
                        C_reps=np.array([fi["C_reps"] for fi in a["fits"][w]]),
                        M_reps=np.array([fi["M_reps"] for fi in a["fits"][w]]),
                        f_peak=a["f_peak"], Z_peak=a["Z_peak"],
                        stationary=a["stationary"], runs=a["runs"])
        o = a["optimum"][gs.OPT]
        log(f"{law}: Lz* {scaffold.pm(o['mean'], o['se'], 4, unit='m')}; "
            f"{a['stationary']}/{a['runs']} runs stationary")
    return out, lambda path, prov: record(out, s, path, prov)


def record(result: dict, s: dict, out: str, prov: dict) -> None:
    prov = dict(prov, sweep_wall_s=sum(r["wall"] for r in result.values()))
    with scaffold.data_file(out, prov, settings=s, weighting=gs.THESIS_WEIGHTING) as h:
        put(h, "frequency", s["freqs"], "Hz")
        put(h, "Lz", s["lz"], "m")
        for law, r in result.items():
            g = h.create_group(law)
            g.attrs.update(base_config=r["cfg"].to_json(), stationary=r["stationary"],
                           runs=r["runs"])
            put(g, "amplitude", r["Zr"], "m", dims="frequency, Lz, replicate",
                what="steady mean over the MSER-detected steady state")
            put(g, "C_ef", r["C_reps"], "N s/m", dims="Lz, replicate",
                what=f"{gs.THESIS_WEIGHTING}-residual 1-DOF fit per bed")
            put(g, "M_ef", r["M_reps"], "kg", dims="Lz, replicate")
            put(g, "f_peak", r["f_peak"], "Hz", dims="Lz, replicate")
            put(g, "Z_peak", r["Z_peak"], "m", dims="Lz, replicate")


def per_bed(data) -> dict:
    """Per law the per-bed values of :data:`QUANTITIES` from a stored ``data.h5``, and per
    optimum how many beds have it at an end of the grid (``at_edge``: not bracketed)."""
    lz = np.asarray(data["Lz"], float)
    out = {}
    for law in LAWS:
        g = data[law]
        c = replicate_extrema(lz, np.asarray(g["C_ef"]), "max", log_x=True)
        z = replicate_extrema(lz, np.asarray(g["Z_peak"]), "min", log_x=True, log_y=True)
        out[law] = dict(Lz_opt=c.x, C_eq=c.y, Lz_min_peak=z.x, Z_min_peak=z.y,
                        at_edge=dict(Lz_opt=c.at_edge, Lz_min_peak=z.at_edge))
    return out


def margins(budget_path=os.path.join(sy.HERE, "systematics", "data.h5")) -> dict:
    """The relative equivalence margins (module docstring): heights :data:`HEIGHT_MARGIN`;
    ``C_eq`` and the resonant amplitude ``Z_res``'s budget at the thesis point without its
    tangential-law term."""
    from jaxdamp.io.study import load

    terms = sy.budget(load(budget_path))["thesis_optimum"]["Z_res"]["terms"]
    z = math.sqrt(sum(t["u"] ** 2 for k, t in terms.items()
                      if isinstance(t, dict) and k != "tangential_law"))
    return {q: HEIGHT_MARGIN if height else z for q, _, _, height in QUANTITIES}


def verdicts(values: dict, m: dict) -> dict:
    """Per quantity: the shift Mindlin / viscous − 1 (Welch) and its outcome against its
    margin (module docstring)."""
    out = {}
    for q, *_ in QUANTITIES:
        e = sy.equivalent_shift(values["mindlin"][q], values["viscous"][q], m[q])
        out[q] = dict(e, result={"pass": "unchanged", "fail": "changed"}.get(e["outcome"],
                                                                             "undecided"))
    return out


def report(data, out) -> None:
    s, lz = data.attrs["settings"], np.asarray(data["Lz"], float)
    values = per_bed(data)
    v = verdicts(values, margins())
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(11, 4.2))
    for j, law in enumerate(LAWS):
        for key, ax, scale in (("C_ef", a1, 1.0 / s["C"]), ("Z_peak", a2, 1.0 / 0.0045)):
            Y = np.asarray(data[law][key]) * scale
            for r in range(Y.shape[1]):
                ax.plot(lz * (1 + 0.004 * (j - 0.5)), Y[:, r], "os"[j] + "-", color=f"C{j}",
                        ms=4, lw=0.8, label=law if r == 0 else None)
        x = values[law]["Lz_opt"]
        a1.axvspan(x.min(), x.max(), color=f"C{j}", alpha=0.15)
    a1.axvline(gs.THESIS_OPTIMUM, color="0.5", lw=0.8, ls=":")
    a1.set(xlabel="box height Lz [m]", ylabel="C_ef / C [-]")
    a1.set_title(f"C_ef of each bed's {gs.THESIS_WEIGHTING}-residual fit; bands: the beds' "
                 "optima; dotted: the thesis'", fontsize=8)
    a1.legend()
    a2.set(xlabel="box height Lz [m]", ylabel="resonant amplitude Z_res / U [-]")
    a2.set_title("each bed's resonant amplitude", fontsize=8)
    scaffold.save_figure(fig, out)

    pm = scaffold.pm
    L = scaffold.head("Does the tangential law move the thesis' optimum?", data.attrs,
                      sweep_wall=data.attrs.get("sweep_wall_s"))
    L += [f"`sanchez2012-optimal`, C = {s['C']} N s/m, heights {list(s['lz'])} m, "
          f"{len(s['freqs'])} frequencies {s['freqs'][0]}–{s['freqs'][-1]} Hz, {s['R']} beds "
          f"per law (seeds 0…{s['R'] - 1}, each law's beds settled under that law), "
          f"{s['duration']} s runs after {s['settle']} s of settling (`gap_scan`'s protocol). "
          f"Stationary runs (MSER): viscous {data['viscous'].attrs['stationary']}, Mindlin "
          f"{data['mindlin'].attrs['stationary']} of {data['viscous'].attrs['runs']}; the "
          "others' means over the final 10 %.", "",
          "Shift = Mindlin / viscous − 1 (Welch, unpaired). Rule (stated before the run): "
          "unchanged if |δ| + t₀.₉₅ SE ≤ margin, changed if |δ| − t₀.₉₅ SE > margin, else "
          f"undecided; margins {100 * HEIGHT_MARGIN:.1f} % for the heights (half the thesis' "
          "grid step at its optimum), for C_eq and the amplitude the systematic budget of Z_res "
          f"without the tangential term ({100 * v['C_eq']['margin']:.2f} %).", ""]
    rows = []
    for q, unit, label, _ in QUANTITIES:
        a, b = (values[law][q] for law in LAWS)
        scale, u = (1e3, "mm") if unit == "m" else (1.0, unit)
        sh = v[q]
        rows.append([label, pm(*scaffold.mean_se(a * scale), 4, unit=u),
                     pm(*scaffold.mean_se(b * scale), 4, unit=u),
                     pm(100 * sh["delta"], 100 * sh["ci95"], "+.2f", ".2f", unit="%"),
                     f"{100 * (abs(sh['delta']) + sh['half']):.2f} % vs {100 * sh['margin']:.2f}"
                     f" %", sh["result"]])
    L += scaffold.table(["quantity", "viscous (mean ± SE)", "Mindlin (mean ± SE)",
                         "shift (95 %)", "|δ| + t₀.₉₅ SE vs margin", "verdict"], rows)
    L += ["", "## Per height (mean ± SE over beds)", ""]
    L += scaffold.table(
        ["Lz [m]"] + [f"C_ef/C {law}" for law in LAWS] + [f"Z_res/U {law}" for law in LAWS],
        [[f"{L_:g}"] + [pm(*scaffold.mean_se(np.asarray(data[law]["C_ef"][k]) / s["C"]), 4)
                        for law in LAWS]
         + [pm(*scaffold.mean_se(np.asarray(data[law]["Z_peak"][k]) / 0.0045), 4)
            for law in LAWS] for k, L_ in enumerate(lz)])
    L += ["", "## Per bed", ""]
    L += scaffold.table(["law", "bed"] + [q for q, *_ in QUANTITIES],
                        [[law, r] + [f"{values[law][q][r]:.5g}" for q, *_ in QUANTITIES]
                         for law in LAWS for r in range(s["R"])])
    L += ["", "## Verdict", ""]
    o, c = v["Lz_opt"], v["C_eq"]
    L.append(f"- The optimal height moves by {pm(100 * o['delta'], 100 * o['ci95'], '+.2f', '.2f')}"
             f" % under the spring: **{o['result']}** at the {100 * o['margin']:.1f} % margin; "
             f"C_eq there by {pm(100 * c['delta'], 100 * c['ci95'], '+.2f', '.2f')} %: "
             f"**{c['result']}** at {100 * c['margin']:.2f} %.")
    edges = [f"{law} {q}: {n} of {s['R']}" for law in LAWS
             for q, n in values[law]["at_edge"].items() if n]
    if edges:
        L.append("- Not bracketed by the heights (best sample at an end of the grid, the "
                 "optimum is that end): " + "; ".join(edges) + ".")
    L += scaffold.quick_note(s)
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
