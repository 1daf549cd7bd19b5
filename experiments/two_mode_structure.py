"""The thesis damper on a two-mode structure: at the antinode of mode 1 against that of mode 2
(issue 16: "multi-mode primary structures").

    python experiments/two_mode_structure.py            # ~20 min on 2 cores
    python experiments/two_mode_structure.py --quick    # ~1 min, test-sized

The preset ``sanchez2012-chain``: a 2-DOF chain on the moving base, two equal masses m =
2.37 kg (the thesis primary's), springs k = 21500 N/m (base–lower and lower–upper), dampers
c = 7.6 N s/m likewise, so
``M = m I``, ``K = k [[2, -1], [-1, 1]]``, ``C = c [[2, -1], [-1, 1]]``: modes at 9.4 and 24.5 Hz
with shapes (0.618, 1) and (1, -0.618) — mode 1's antinode is the upper mass (DOF 1), mode
2's the lower one (DOF 0). The damper of ``sanchez2012-optimal`` (250 grains, Lz = 0.1225 m;
its box is part of the mass it sits on) is put on DOF 1 or on DOF 0; the structure is the same
in both placements. Random base motion over 5–30 Hz (both modes; random-phase multisine,
lines every 0.25 Hz), ``R`` realisations per placement (independent beds and phases).

**Each mode's damping** from the H1 FRF of the box, ``H = x_a/u``, by a least-squares fit of
the two-mode transmissibility of a classically damped chain,

    H(ω) = 1 + Σ_k A_k ω² / (ω_k² - ω² + 2i ζ_k ω_k ω)

(complex residuals weighted by the coherence; ``A_k``, ``ω_k``, ``ζ_k`` free — the grains add
mass and move the modes) per realisation; the damper's **added damping** of mode k is
``ζ_k - ζ_k(empty)`` with the empty structure's ratio ``ζ_k(empty) = c ω_k/(2k)`` (stiffness-
proportional; computed from the preset's matrices). Verdicts: Welch 95 % intervals across
realisations, placement against placement for each mode.

Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import math
import os

import numpy as np

from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics.structure import matrices
from jaxdamp.studies import random as rnd
from jaxdamp.studies import scaffold

try:
    from .horizontal_drive import verdict
except ImportError:  # run as a file: python experiments/<name>.py
    from horizontal_drive import verdict

#: the chain and the damper: the preset (one definition)
PRESET = "sanchez2012-chain"


def empty_modes():
    """Natural frequencies [Hz] and damping ratios of the empty chain: ``K φ = ω² M φ`` with
    mass-normalised ``φ``, ``ζ_k = φ_kᵀ C φ_k / (2 ω_k)`` (its damping is stiffness-
    proportional, so the modes are those of the damped chain; ``M``, ``K``, ``C`` of the
    preset's chain: :func:`jaxdamp.physics.structure.matrices`)."""
    from scipy.linalg import eigh

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
    """The fitted model ``1 + Σ A_k ω²/(ω_k² − ω² + 2iζ_k ω_k ω)``; ``p = (A1, w1, z1, A2, w2,
    z2)``."""
    h = np.ones_like(w, dtype=complex)
    for A, wk, zk in (p[:3], p[3:]):
        h += A * w**2 / (wk**2 - w**2 + 2j * zk * wk * w)
    return h


def fit_modes(f, H, coh, guess):
    """Least-squares fit of :func:`two_mode` to ``H(f)`` weighted by ``coh``; returns
    ``(f_1, ζ_1, f_2, ζ_2, A_1, A_2)`` with the modes sorted by frequency."""
    from scipy.optimize import least_squares

    w = 2 * math.pi * np.asarray(f)
    wt = np.sqrt(np.clip(coh, 0, 1))

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
        res = rnd.measure(apply_overrides(base, {**over, "structure.attach": dof}), [1.0],
                          duration=s["duration"], replicates=s["R"],
                          out=ctx.raw(f"dof{dof}_R{s['R']}.h5"), reuse=True,
                          progress=ctx.progress, echo=None)
        lev = res.levels[0]
        fits = np.array([fit_modes(lev["f"], h, lev["coherence"], guess) for h in lev["H_each"]])
        runs[dof] = dict(level=lev, fits=fits, wall=float(res.sweep.summary["wall_time"]),
                         a_rms=lev["a_rms"], y_rms=lev["y_rms"],
                         stationary=int(lev["stationary"].sum()))
    cmp = {mode: welch(runs[1]["fits"][:, col], runs[0]["fits"][:, col])  # DOF 1 − DOF 0
           for mode, col in ((1, 1), (2, 3))}
    result = dict(settings=s, f_empty=f_e, z_empty=z_e, runs=runs, cmp=cmp,
                  n_grains=int(apply_overrides(base, over).n_grains))
    return result, lambda o, prov: write(result, o, prov)


#: the columns of a realisation's fit (:func:`fit_modes`) and their units
FIT = (("f1", "Hz"), ("zeta1", "1"), ("f2", "Hz"), ("zeta2", "1"), ("A1", "1"), ("A2", "1"))


def write(r, out, prov):
    s, runs = r["settings"], r["runs"]
    with scaffold.data_file(out, prov, fit="H = 1 + sum_k A_k w^2 / (w_k^2 - w^2 + 2i z_k w_k "
                            "w), complex least squares weighted by sqrt(coherence), per "
                            "realisation") as h5:
        h5.create_dataset("f_empty", data=r["f_empty"]).attrs["units"] = "Hz"
        h5.create_dataset("zeta_empty", data=r["z_empty"]).attrs["units"] = "1"
        for dof, d in runs.items():
            lev = d["level"]
            data = {"f": (lev["f"], "Hz"), "H_re": (lev["H"].real, "1"),
                    "H_im": (lev["H"].imag, "1"), "coherence": (lev["coherence"], "1")}
            data.update({name: (d["fits"][:, j], unit) for j, (name, unit) in enumerate(FIT)})
            for name, (x, unit) in data.items():
                h5.create_dataset(f"dof{dof}/{name}", data=x).attrs["units"] = unit
    from jaxdamp.figures import random_figure

    dofs = list(runs)
    fig = random_figure([runs[k]["level"] for k in dofs],
                        [f"damper on DOF {k} (antinode of mode {2 - k}), H1 ± 2 SE" for k in dofs],
                        title="thesis damper on a 2-DOF chain: at mode 1's vs mode 2's antinode")
    ax = fig.axes[0]
    f_fine = np.linspace(s["band"][0], s["band"][1], 800)
    for k, line in zip(dofs, ax.get_lines()):
        p = runs[k]["fits"].mean(axis=0)
        ax.plot(f_fine, np.abs(two_mode(2 * math.pi * f_fine,
                                        [p[4], 2 * math.pi * p[0], p[1], p[5],
                                         2 * math.pi * p[2], p[3]])), "-", lw=0.8,
                color=line.get_color(), label=f"DOF {k}: two-mode fit (mean parameters)")
    ax.legend(fontsize=7)
    fig.savefig(os.path.join(out, "figure.png"), dpi=120)

    M, K, C = matrices(presets.get(PRESET))[:3]
    L = [*scaffold.head("The damper on a two-mode structure (issue 16)", prov),
         f"Structure: the preset `{PRESET}`, a 2-DOF chain, m = {M[1, 1]:g} kg each, "
         f"k = {-K[0, 1]:g} N/m, c = {-C[0, 1]:g} N s/m "
         f"(base–lower and lower–upper); empty modes at {r['f_empty'][0]:.3f} and "
         f"{r['f_empty'][1]:.3f} Hz with ζ = {100 * r['z_empty'][0]:.3f} % and "
         f"{100 * r['z_empty'][1]:.3f} %. Damper: `sanchez2012-optimal` ({r['n_grains']} "
         "grains, Lz = 0.1225 m), on DOF 1 (the upper mass, mode 1's antinode) or DOF 0 (the "
         f"lower mass, mode 2's antinode). Random base motion: flat acceleration density "
         f"{s['S']} (m/s²)²/Hz over {s['band'][0]:g}–{s['band'][1]:g} Hz (a_rms "
         f"{runs[1]['a_rms']:.3g} m/s²), lines every {s['resolution']} Hz, {s['duration']} s "
         f"per run, **{s['R']} realisations** per placement (independent beds and phases). "
         "Stationary start detected (MSER on the mean square of z − u) in "
         + ", ".join(f"DOF {k}: {d['stationary']} of {s['R']}" for k, d in runs.items())
         + ". Compute: " + ", ".join(f"DOF {k} {d['wall']:.0f} s" for k, d in runs.items())
         + " (settling excluded).", "",
         "Fit: H1 of the box per realisation against 1 + Σ_k A_k ω²/(ω_k² − ω² + 2iζ_kω_kω), "
         "complex residuals weighted by √coherence, all six parameters free. Added damping: "
         "ζ_k − ζ_k(empty) with the empty chain's ratio at its own frequency. Verdict: Welch "
         "95 % interval of DOF 1 − DOF 0 across realisations.", ""]
    rows = []
    for mode, (cf, cz) in ((1, (0, 1)), (2, (2, 3))):
        fe, ze = r["f_empty"][mode - 1], r["z_empty"][mode - 1]
        (m1, e1), (m0, e0) = (scaffold.mean_se(runs[k]["fits"][:, cf]) for k in (1, 0))
        rows.append([f"f_{mode} [Hz]", f"{fe:.3f}", scaffold.pm(m1, e1, ".3f"),
                     scaffold.pm(m0, e0, ".3f"), f"{m1 - m0:+.3f}", "–"])
        (m1, e1), (m0, e0) = (scaffold.mean_se(runs[k]["fits"][:, cz]) for k in (1, 0))
        d, h = r["cmp"][mode]
        rows += [[f"ζ_{mode} [%]", f"{100 * ze:.3f}", scaffold.pm(m1, e1, ".3f", scale=100),
                  scaffold.pm(m0, e0, ".3f", scale=100), scaffold.pm(d, h, "+.3f", scale=100),
                  verdict(d, h, "same", "more on DOF 1", "more on DOF 0")],
                 [f"added ζ_{mode} [%]", "–", f"{100 * (m1 - ze):.3f}", f"{100 * (m0 - ze):.3f}",
                  "–", "–"]]
    L += scaffold.table(["quantity", "empty", "damper on DOF 1", "damper on DOF 0",
                         "DOF 1 − DOF 0", "verdict"], rows)
    L += ["", "RMS of the box's displacement relative to the base: " + ", ".join(
        f"DOF {k}: {1e3 * d['y_rms'].mean():.3g} mm" for k, d in runs.items()) + ".", "",
        "Figure: `figure.png` (|H1| ± 2 SE per placement, the fitted two-mode curves, "
        "coherence). Data: `data.h5`."]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute)


if __name__ == "__main__":
    main()
