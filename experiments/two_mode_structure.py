"""The thesis damper on a two-mode structure (issue 16: "multi-mode primary structures"): does a
mode gain more damping with the damper at its antinode?

    python experiments/two_mode_structure.py            # ~20 min on 2 cores
    python experiments/two_mode_structure.py --quick    # ~1 min, test-sized

``sanchez2012-chain`` (a 2-DOF chain; mode 1's antinode the upper mass, DOF 1, mode 2's the
lower, DOF 0) with the damper of ``sanchez2012-optimal`` on DOF 1 or 0 under random base motion,
``R`` realisations (beds and phases) each; per realisation a least-squares fit of ``H = 1 + Σ_k
A_k ω² / (ω_k² - ω² + 2i ζ_k ω_k ω)`` to the box's H1, weighted by the coherence; Welch 95 %
intervals between placements. Writes ``data.h5``, then ``figure.png`` and ``summary.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.linalg import eigh

from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.figures import random_figure
from jaxdamp.physics.structure import matrices
from jaxdamp.studies import random as rnd
from jaxdamp.studies import scaffold

try:
    from .horizontal_drive import verdict
except ImportError:  # run as a file: python experiments/<name>.py
    from horizontal_drive import verdict

PRESET = "sanchez2012-chain"


def empty_modes():
    """Natural frequencies [Hz] and damping ratios of the empty chain (stiffness-proportional
    damping): ``K φ = ω² M φ``, mass-normalised ``φ``, ``ζ_k = φ_kᵀ C φ_k / (2 ω_k)``."""
    M, K, C = matrices(presets.get(PRESET))[:3]
    lam, phi = eigh(K, M)
    w = np.sqrt(lam)
    return w / (2 * math.pi), np.einsum("ik,ij,jk->k", phi, C, phi) / (2 * w)


def settings(quick: bool) -> dict:
    if quick:
        return dict(band=(6.0, 28.0), S=2.0, resolution=1.0, duration=2.5, R=2, settle=0.3,
                    grains=120)
    return dict(band=(5.0, 30.0), S=2.0, resolution=0.25, duration=12.0, R=3, settle=None,
                grains=None)


def two_mode(w, p):
    """The fitted ``1 + Σ A_k ω²/(ω_k² − ω² + 2iζ_k ω_k ω)``, ``p = (A1, w1, z1, A2, w2, z2)``."""
    return sum((A * w**2 / (wk**2 - w**2 + 2j * zk * wk * w) for A, wk, zk in (p[:3], p[3:])),
               np.ones_like(w, dtype=complex))


def fit_modes(f, H, coh, guess):
    """Least-squares fit of :func:`two_mode` to ``H(f)`` weighted by ``coh``; returns
    ``(f_1, ζ_1, f_2, ζ_2, A_1, A_2)`` with the modes sorted by frequency."""
    from scipy.optimize import least_squares

    w, wt = 2 * math.pi * np.asarray(f), np.sqrt(np.clip(coh, 0, 1))

    def res(p):
        d = (two_mode(w, p) - H) * wt
        return np.concatenate([d.real, d.imag])

    p = least_squares(res, guess, x_scale="jac", max_nfev=4000).x
    (w1, z1, A1), (w2, z2, A2) = sorted([(abs(p[1]), abs(p[2]), p[0]),
                                         (abs(p[4]), abs(p[5]), p[3])])
    return w1 / (2 * math.pi), z1, w2 / (2 * math.pi), z2, A1, A2


def compute(quick: bool, log, ctx):
    s = settings(quick)
    base = presets.get(PRESET)
    over = {"primary.U": 0.0, "random.psd": [[s["band"][0], s["S"]], [s["band"][1], s["S"]]],
            "random.resolution": s["resolution"]}
    over.update({k: v for k, v in (("numerics.settle_time", s["settle"]),
                                   ("grains.0.count", s["grains"])) if v is not None})
    f_e, z_e = empty_modes()
    guess = [1.0, 2 * math.pi * f_e[0], 0.03, 0.3, 2 * math.pi * f_e[1], 0.03]
    runs = {}
    for dof in (1, 0):
        log(f"damper on DOF {dof}: {s['duration']} s, R = {s['R']}")
        cfg = apply_overrides(base, {**over, "structure.attach": dof})
        res = rnd.measure(cfg, [1.0], duration=s["duration"], replicates=s["R"], reuse=True,
                          out=ctx.raw(f"dof{dof}_R{s['R']}.h5"), progress=ctx.progress, echo=None)
        lev = res.levels[0]
        fits = np.array([fit_modes(lev["f"], h, lev["coherence"], guess) for h in lev["H_each"]])
        runs[dof] = dict(level=lev, fits=fits, wall=float(res.sweep.summary["wall_time"]),
                         a_rms=lev["a_rms"], y_rms=lev["y_rms"],
                         stationary=int(lev["stationary"].sum()))
    cmp = {mode: welch(runs[1]["fits"][:, col], runs[0]["fits"][:, col])  # DOF 1 − DOF 0
           for mode, col in ((1, 1), (2, 3))}
    result = dict(settings=s, f_empty=f_e, z_empty=z_e, runs=runs, cmp=cmp,
                  n_grains=int(apply_overrides(base, over).n_grains))
    return result, lambda o, prov: record(result, o, prov)


FIT = (("f1", "Hz"), ("zeta1", "1"), ("f2", "Hz"), ("zeta2", "1"), ("A1", "1"), ("A2", "1"))


def record(r, out, prov):
    M, K, C = matrices(presets.get(PRESET))[:3]
    with scaffold.data_file(out, prov, fit="H = 1 + sum_k A_k w^2 / (w_k^2 - w^2 + 2i z_k w_k "
                            "w), complex least squares weighted by sqrt(coherence), per "
                            "realisation", settings=r["settings"], n_grains=r["n_grains"],
                            chain=dict(m=M[1, 1], k=-K[0, 1], c=-C[0, 1])) as h5:  # kg, N/m, N s/m
        h5.create_dataset("f_empty", data=r["f_empty"]).attrs["units"] = "Hz"
        h5.create_dataset("zeta_empty", data=r["z_empty"]).attrs["units"] = "1"
        for dof, d in r["runs"].items():
            lev = d["level"]
            data = {k: (lev[k], "1") for k in ("coherence", "mag_se")}
            data.update(f=(lev["f"], "Hz"), H_re=(lev["H"].real, "1"), H_im=(lev["H"].imag, "1"))
            data.update({name: (d["fits"][:, j], unit) for j, (name, unit) in enumerate(FIT)})
            for name, (x, unit) in data.items():
                h5.create_dataset(f"dof{dof}/{name}", data=x).attrs["units"] = unit
            h5[f"dof{dof}"].attrs.update(a_rms=d["a_rms"], y_rms_mean=d["y_rms"].mean(),
                                         stationary=d["stationary"], wall_s=d["wall"])  # m/s², m, s


def report(data, out):
    s, prov, f_e, z_e = data.attrs["settings"], data.attrs, data["f_empty"], data["zeta_empty"]
    ch = prov["chain"]  # m [kg], k [N/m], c [N s/m]
    runs = {k: dict(g, **g.attrs, fits=np.column_stack([g[name] for name, _ in FIT]))
            for k, g in ((1, data["dof1"]), (0, data["dof0"]))}
    L = [*scaffold.head("The damper on a two-mode structure (issue 16)", prov),
         f"Structure: the preset `{PRESET}`, a 2-DOF chain, m = {ch['m']:g} kg each, k = "
         f"{ch['k']:g} N/m, c = {ch['c']:g} N s/m; empty modes at {f_e[0]:.3f} and {f_e[1]:.3f} "
         f"Hz with ζ = {100 * z_e[0]:.3f} % and {100 * z_e[1]:.3f} %. Damper: `sanchez2012-"
         f"optimal` ({prov['n_grains']} grains, Lz = 0.1225 m). Random base motion: flat "
         f"acceleration density {s['S']} (m/s²)²/Hz over {s['band'][0]:g}–{s['band'][1]:g} Hz "
         f"(a_rms {runs[1]['a_rms']:.3g} m/s²), lines every {s['resolution']} Hz, {s['duration']}"
         f" s per run, **{s['R']} realisations** per placement. Stationary start (MSER) in "
         + ", ".join(f"DOF {k}: {d['stationary']} of {s['R']}" for k, d in runs.items())
         + ". Compute: " + ", ".join(f"DOF {k} {d['wall_s']:.0f} s" for k, d in runs.items())
         + " (settling excluded). Added damping: ζ_k − ζ_k(empty), the empty chain's ratio at its "
         "own frequency. Verdict: Welch 95 % interval of DOF 1 − DOF 0 across realisations.", ""]
    pm, rows = scaffold.pm, []
    (m1, e1), (m0, e0) = (scaffold.mean_se(runs[k]["fits"], 0) for k in (1, 0))  # per column
    for mode, (cf, cz) in ((1, (0, 1)), (2, (2, 3))):  # the fits' columns f_mode, ζ_mode
        d, h, ze = *welch(runs[1]["fits"][:, cz], runs[0]["fits"][:, cz]), z_e[mode - 1]
        rows += [[f"f_{mode} [Hz]", f"{f_e[mode - 1]:.3f}", pm(m1[cf], e1[cf], ".3f"),
                  pm(m0[cf], e0[cf], ".3f"), f"{m1[cf] - m0[cf]:+.3f}", "–"],
                 [f"ζ_{mode} [%]", f"{100 * ze:.3f}", pm(m1[cz], e1[cz], ".3f", scale=100),
                  pm(m0[cz], e0[cz], ".3f", scale=100), pm(d, h, "+.3f", scale=100),
                  verdict(d, h, "same", "more on DOF 1", "more on DOF 0")],
                 [f"added ζ_{mode} [%]", "–", f"{100 * (m1[cz] - ze):.3f}",
                  f"{100 * (m0[cz] - ze):.3f}", "–", "–"]]
    L += scaffold.table(["quantity", "empty", "damper on DOF 1", "damper on DOF 0",
                         "DOF 1 − DOF 0", "verdict"], rows)
    L += ["", "RMS of the box's displacement relative to the base: " + ", ".join(
        f"DOF {k}: {1e3 * d['y_rms_mean']:.3g} mm" for k, d in runs.items()) + "."]
    scaffold.write_summary(out, L)
    if not all("mag_se" in d for d in runs.values()):  # stored before it was: figure.png stays
        return
    fig = random_figure([dict(d, H=d["H_re"] + 1j * d["H_im"]) for d in runs.values()],
                        [f"damper on DOF {k} (antinode of mode {2 - k}), H1 ± 2 SE" for k in runs],
                        title="thesis damper on a 2-DOF chain: at mode 1's vs mode 2's antinode")
    f_fine = np.linspace(s["band"][0], s["band"][1], 800)
    for k, line in zip(runs, fig.axes[0].get_lines()):
        f1, z1, f2, z2, A1, A2 = runs[k]["fits"].mean(axis=0)
        H = two_mode(2 * math.pi * f_fine, [A1, 2 * math.pi * f1, z1, A2, 2 * math.pi * f2, z2])
        fig.axes[0].plot(f_fine, np.abs(H), "-", lw=0.8, color=line.get_color(),
                         label=f"DOF {k}: two-mode fit (mean parameters)")
    fig.axes[0].legend(fontsize=7)
    fig.set_layout_engine("none")  # laid out by save_figure (tight), not constrained
    scaffold.save_figure(fig, out)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
