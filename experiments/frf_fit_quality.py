"""How well does the 1-DOF FRF fit the damper at each box height? (thesis §3.2.1, fig. 3.5; B2)

    python experiments/frf_fit_quality.py   # reads experiments/gap_scan/data.h5 (--quick: same)

Per bed and height of ``gap_scan`` (C = 7.6 N s/m), the RMS misfit of that bed's own fit (U, K
fixed): ``absolute`` (the thesis') of ``(Z_model − Z)/U``, ``relative`` of ``Z_model/Z − 1``;
the intermediate heights (0.117, 0.162 m; "shoulders" in the thesis) against the extremes by
Welch 95 %. Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import os

import h5py
import numpy as np

from jaxdamp.analysis.response import RESIDUALS, frf_amplitude
from jaxdamp.analysis.stats import welch
from jaxdamp.config import from_json
from jaxdamp.figures.response import draw_replicates
from jaxdamp.studies import scaffold

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "gap_scan", "data.h5")
EXTREMES = (0.042, 0.372)
INTERMEDIATE = (0.117, 0.162)


def compute(quick: bool, log, ctx):
    with h5py.File(DATA, "r") as h:
        g = h["C_7.6"]
        cfg = from_json(g.attrs["base_config"])
        f, lz, Z = (np.asarray(g[k]) for k in ("axes/frequency", "axes/box.Lz", "amplitude"))
        fits = {w: tuple(np.asarray(g[f"fit_{w}/{k}_reps"]) for k in "MC") for w in RESIDUALS}
        source = dict(git=h.attrs.get("git", "?"), command=h.attrs.get("command", "?"))
    U, K = cfg.primary.U, cfg.primary.K
    Zh, mis = np.moveaxis(Z, 0, -1), {}  # (L, R, F)
    for w, (M, C) in fits.items():  # each bed's RMS misfit to its own fit, (L, R)
        model = frf_amplitude(f, M[..., None], K, C[..., None], U)
        res = (model - Zh) / U if w == "absolute" else model / Zh - 1.0
        mis[w] = np.sqrt(np.mean(res * res, axis=-1))
    ext, mid = ([int(np.argmin(abs(lz - h))) for h in hs] for hs in (EXTREMES, INTERMEDIATE))
    comp = {w: [dict(mid=float(lz[a]), ext=float(lz[b]), **dict(zip(("diff", "ci95"),
                welch(mis[w][a], mis[w][b])))) for a in mid for b in ext] for w in RESIDUALS}
    result = dict(lz=lz, f=f, Z=Z, mis=mis, comp=comp, U=U, K=K, source=source, fits=fits)
    return result, lambda out, prov: record(result, out, prov)


def record(r, out, prov):
    with scaffold.data_file(out, prov, source=r["source"], comparisons=r["comp"]) as h:
        for k, x, u, dims in (
                ("Lz", r["lz"], "m", None), ("frequency", r["f"], "Hz", None),
                ("misfit_absolute", r["mis"]["absolute"], "1 (per U)", "Lz, replicate"),
                ("misfit_relative", r["mis"]["relative"], "1", "Lz, replicate"),
                ("amplitude", r["Z"], "m", "frequency, Lz, replicate"),
                ("fit_absolute/M_ef", r["fits"]["absolute"][0], "kg", "Lz, replicate"),
                ("fit_absolute/C_ef", r["fits"]["absolute"][1], "N s/m", "Lz, replicate"),
                ("U", r["U"], "m", None), ("K", r["K"], "N/m", None)):
            h.create_dataset(k, data=x).attrs.update(units=u, **({"dims": dims} if dims else {}))


def report(data, out):
    lz, f, Z, U, mis = data["Lz"], data["frequency"], data["amplitude"], data["U"], {
        w: data[f"misfit_{w}"] for w in RESIDUALS}
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(12, 4.4))
    for w, ls in zip(RESIDUALS, ("-", "--")):
        draw_replicates(a1, lz, mis[w], fmt="o", ls=ls, label=f"{w} residuals")
    a1.set(xscale="log", xlabel="box height Lz [m]",
           ylabel="RMS misfit of the 1-DOF FRF [-] (per U, or relative)")
    fine = np.linspace(f.min(), f.max(), 400)
    for L in (0.042, 0.117, 0.162, 0.372):
        j = int(np.argmin(np.abs(lz - L)))
        line = a2.plot(f, Z[:, j].mean(-1) / U, "o", label=f"Lz = {L} m")
        M, C = (data["fit_absolute"][k][j].mean() for k in ("M_ef", "C_ef"))
        a2.plot(fine, frf_amplitude(fine, M, data["K"], C, U) / U, "-", lw=0.8,
                color=line[0].get_color())
    a2.set(xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U [-]")
    for a, title in ((a1, "misfit of each bed's own fit, mean of 3 beds ± 2 SE"),
                     (a2, "data (mean of the beds) and the absolute-residual fit")):
        a.set_title(title, fontsize=9)
        a.legend(fontsize=8)
    scaffold.save_figure(fig, out)

    fmt = lambda x: scaffold.pm(*scaffold.mean_se(x), 3)  # noqa: E731
    L = scaffold.head("How well the 1-DOF FRF describes the damper at each height (thesis "
                      "§3.2.1, fig. 3.5)", data.attrs)
    L += [f"Data: `experiments/gap_scan/data.h5` (at commit {data.attrs['source']['git']}: "
          f"C = 7.6 N s/m, {len(lz)} heights × {len(f)} frequencies {f.min():g}–{f.max():g} Hz "
          f"× **R = {mis['absolute'].shape[1]} independently poured beds**). ± is the standard "
          "error over the beds.", ""]
    L += scaffold.table(["Lz [m]", "RMS (Z_model − Z)/U, absolute fit (the thesis')",
                         "RMS Z_model/Z − 1, relative fit"],
                        [[f"{h:g}", fmt(mis["absolute"][j]), fmt(mis["relative"][j])]
                         for j, h in enumerate(lz)])
    L += ["", "**Intermediate against extreme heights** (Welch 95 % of the difference of the "
          "misfits; positive: the intermediate height fits worse):", ""]
    for w, comps in data.attrs["comparisons"].items():
        L.append(f"- {w}: " + "; ".join(
            f"{c['mid']:g} − {c['ext']:g} m: {scaffold.pm(c['diff'], c['ci95'], '+.3g')}"
            + (" (significant)" if abs(c["diff"]) > c["ci95"] else "") for c in comps) + ".")
    L += ["", "Limit: a shoulder narrower than the spacing of the frequencies "
          f"({np.diff(f).min():g}–{np.diff(f).max():g} Hz) is not resolved, so a small misfit "
          "does not exclude one.", ""]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
