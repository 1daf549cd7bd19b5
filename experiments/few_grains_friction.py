"""Thesis fig. 5.4(b): with few grains, does the resonant amplitude fall as the tangential
damping γ_s rises? ``python experiments/few_grains_friction.py [--quick]`` (full: ~5 min).

The γ_s counterpart of ``universality_limits``' part 4 (which switches γ_n): N = 25, 50, 100,
250 grains of the same total mass (radius ∝ N^(-1/3)) in the optimal box, γ_s = 0 and the
thesis' 10980 at the thesis' γ_n, at the two resonance samples 14.5 and 15.25 Hz, ``R`` poured
beds per point, 1.5 s runs, MSER steady amplitudes. Per N and bed, Z_res is the larger of the
two samples (as part 4); the change from γ_s = 0 to 10980 with its Welch 95 % interval. The
thesis' claim (§5.3.3) is that Z_res falls as γ_n or γ_s rises when N is small, and does not
depend on them for N > 100; the scoreboard decides it (row D11). Writes ``data.h5``,
``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import numpy as np

from jaxdamp.cases import presets
from jaxdamp.io.common import put
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import Points

try:
    from .universality_limits import GN, GS, STATIONARITY, batch, optimal
except ImportError:  # run as a file: python experiments/<name>.py
    from universality_limits import GN, GS, STATIONARITY, batch, optimal


def settings(quick: bool) -> dict:
    if quick:
        return dict(res_freqs=(15.0,), ns=(25, 50), duration=0.3, settle=0.15, R=2)
    return dict(res_freqs=(14.5, 15.25), ns=(25, 50, 100, 250), duration=1.5, settle=0.3, R=3)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    r0 = presets.get("sanchez2012-optimal").grains[0].radius
    rows, first = [], len(STATIONARITY)  # batch() appends to the shared list
    for n in s["ns"]:
        radius = r0 * (250 / n) ** (1 / 3)
        cfg = optimal(s, **{"grains.0.count": n, "grains.0.radius": radius,
                            "grains.0.material.gamma_n": GN})
        axes = Points({"grains.0.material.gamma_s": [g for g in (0.0, GS)
                                                     for _ in s["res_freqs"]],
                       "frequency": list(s["res_freqs"]) * 2})
        res, Z = batch(s, ctx, cfg, axes, f"gs_N{n}", f"N = {n}")
        off, on = Z.reshape(2, -1, s["R"]).max(axis=1) / cfg.primary.U  # γ_s 0, thesis
        rows.append(dict(N=n, radius=radius, off=off, on=on,
                         wall=float(res.summary["wall_time"])))
        log(f"N = {n}: Z_res/U {off.mean():.3f} (γ_s = 0) → {on.mean():.3f} (γ_s = {GS:g})")
    stationary = STATIONARITY[first:]
    return rows, lambda path, prov: record(rows, s, stationary, path, prov)


def record(rows, s, stationary, path, prov):
    wall = sum(r["wall"] for r in rows)
    with scaffold.data_file(path, dict(prov, sweep_wall_s=wall), settings=s,
                            stationary=[[p, int(a), int(b)] for p, a, b in stationary]) as h:
        put(h, "N", [r["N"] for r in rows], "1")
        put(h, "radius", [r["radius"] for r in rows], "m")
        put(h, "Z_res_gamma_s_off", [r["off"] for r in rows], "1", dims="N, replicate",
            note="Z_res/U with gamma_s = 0")
        put(h, "Z_res_gamma_s_on", [r["on"] for r in rows], "1", dims="N, replicate",
            note=f"Z_res/U with gamma_s = {GS:g}")


def report(data, out):
    s, prov = data.attrs["settings"], data.attrs
    N = np.asarray(data["N"])
    off, on = np.asarray(data["Z_res_gamma_s_off"]), np.asarray(data["Z_res_gamma_s_on"])
    fig, ax = scaffold.subplots(figsize=(6, 4))
    for y, lab in ((off, "γ_s = 0"), (on, f"γ_s = {GS:g}")):
        m, se = scaffold.mean_se(y)
        ax.errorbar(N, m, yerr=2 * se, fmt="o-", capsize=3, label=lab)
    ax.set(xscale="log", xlabel="number of grains N (same total mass)",
           ylabel="resonant amplitude Z_res / U [-]")
    ax.set_title(f"γ_n = {GN:g}, {s['R']} beds ± 2 SE (thesis fig. 5.4b)", fontsize=9)
    ax.legend(fontsize=8)
    scaffold.save_figure(fig, out)
    from jaxdamp.analysis.stats import welch

    rows = []
    for i, n in enumerate(N):
        d, h = welch(on[i], off[i])
        rows.append([int(n), scaffold.pm(*scaffold.mean_se(off[i]), ".4f", ".2g"),
                     scaffold.pm(*scaffold.mean_se(on[i]), ".4f", ".2g"),
                     scaffold.pm(100 * d / off[i].mean(), 100 * h / off[i].mean(), "+.2f",
                                 ".2f", unit="%")])
    lines = scaffold.head("Few grains and the tangential damping γ_s (thesis fig. 5.4b)", prov,
                          prov["sweep_wall_s"])
    lines += [f"`sanchez2012-optimal`, N grains of the same total mass, γ_n = {GN:g}, γ_s = 0 and "
              f"{GS:g}, Z_res/U = the larger of the samples {list(s['res_freqs'])} Hz per bed, "
              f"**R = {s['R']} independently poured beds**, {s['duration']} s runs; ± = SE over "
              "beds, the change with its Welch 95 % half-width. Stationary runs (MSER): "
              + ", ".join(f"{p}: {a} of {b}" for p, a, b in prov["stationary"]) + ".", ""]
    lines += scaffold.table(["N", "Z_res/U, γ_s = 0", f"Z_res/U, γ_s = {GS:g}",
                             "change (95 %)"], rows)
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
