"""Does the friction coefficient change the optimal damper's FRF? (thesis §5.3.1, seed line
1603: "hemos considerado distintas propiedades de los materiales, tales como el módulo de Young
y el coeficiente de fricción dinámica, sin embargo, no se obtienen cambios en la FRF").

    python experiments/friction_coefficient.py           # full mode (~8 min on 2 free cores)
    python experiments/friction_coefficient.py --quick   # test-sized

``sanchez2012-optimal`` as ``universality_limits`` runs it (1.5 s per run after settling, the
same six frequencies around the resonance, ``R`` poured beds per point, MSER steady means) at
μ = 0.1, 0.3 (the thesis') and 0.6 for the grains and the walls alike. Per μ: each bed's
resonance (:func:`jaxdamp.analysis.response.resonance`) and the loss per cycle at 15.25 Hz;
differences against μ = 0.3 with their 95 % (Welch) and 90 % (the equivalence test's)
intervals. Whether "unchanged" holds is decided by the scoreboard's rule (equivalence against
the systematic budget's margin: ``python -m experiments.scoreboard``, row D16). Writes ``data.h5``,
``figure.png``, ``summary.md``.

``--tangential-law mindlin`` asks the same question under the Hertz–Mindlin spring with history
instead of the thesis' viscous law (issue 39; ``--out`` another folder, e.g.
``experiments/friction_coefficient/mindlin``): the spring's sticking contacts hold a
tangential force the viscous law does not, so μ could matter where it did not.
"""

from __future__ import annotations

import numpy as np

from jaxdamp.analysis.stats import t_quantile, welch, welch_terms
from jaxdamp.figures.response import draw_replicates
from jaxdamp.io.common import put
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import Points, steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

try:
    from .universal_response import optimal
    from .universality_limits import peaks
except ImportError:  # run as a file: python experiments/<name>.py
    from universal_response import optimal
    from universality_limits import peaks

THESIS_MU = 0.3


def settings(quick: bool) -> dict:
    if quick:
        return dict(freqs=(14.5, 15.25), mus=(0.1, 0.3), duration=0.3, settle=0.15, R=2)
    return dict(freqs=(12.0, 13.5, 14.5, 15.25, 16.0, 18.5), mus=(0.1, 0.3, 0.6),
                duration=1.5, settle=0.3, R=3)


def options(ap):
    ap.add_argument("--tangential-law", default="viscous", choices=["viscous", "mindlin"],
                    help="the tangential law of every run (default: the thesis' viscous law)")


def compute(quick: bool, log, ctx):
    s = settings(quick)
    law = ctx.args.tangential_law
    over = {}
    if law != "viscous":  # (the viscous law's settings keep their stored form)
        s["tangential_law"] = law
        over["tangential_law"] = law
    mu, f = zip(*[(m, x) for m in s["mus"] for x in s["freqs"]])
    # the preset's walls are of the grains' material (box.wall unset), so μ is both
    axes = Points({"grains.0.material.mu": list(mu), "frequency": list(f)})
    tag = "" if law == "viscous" else f"_{law}"
    res = reuse_or_run(optimal(s, **over), axes, ctx.raw(f"sweep_mu_R{s['R']}{tag}.h5"),
                       progress=ctx.progress, replicates=s["R"])
    shape = (len(s["mus"]), len(s["freqs"]), s["R"])
    Z, fb_z = steady_or_window(res, "amplitude")
    E, fb_e = steady_or_window(res, "granular_loss_per_cycle")
    Z, E = Z.reshape(shape), E.reshape(shape)
    pk = np.array([peaks(np.asarray(s["freqs"], float), z) for z in Z])  # (mu, R, 2)
    stationary = int(np.asarray(res.steady["amplitude"]["stationary"]).sum())
    result = dict(Z=Z, E=E, f_peak=pk[..., 0], Z_peak=pk[..., 1], fallback=fb_z + fb_e,
                  stationary=stationary, runs=Z.size, wall=float(res.summary["wall_time"]))
    for m, z in zip(s["mus"], result["Z_peak"]):
        log(f"μ = {m:g}: resonant Z/U {z.mean() / 0.0045:.3f}")
    return result, lambda out, prov: record(result, s, out, prov)


def record(r, s, out, prov):
    with scaffold.data_file(out, dict(prov, sweep_wall_s=r["wall"]), settings=s,
                            stationary=r["stationary"], runs=r["runs"],
                            fallback=r["fallback"]) as h:
        put(h, "frequency", s["freqs"], "Hz")
        put(h, "mu", s["mus"], "1")
        dims = "mu, frequency, replicate"
        put(h, "amplitude", r["Z"], "m", dims=dims)
        put(h, "granular_loss_per_cycle", r["E"], "J", dims=dims)
        put(h, "f_peak", r["f_peak"], "Hz", dims="mu, replicate")
        put(h, "Z_peak", r["Z_peak"], "m", dims="mu, replicate")


def differences(x, ref) -> dict:
    """Relative difference of the means of ``x`` and ``ref`` (per-bed values) with its Welch
    95 % half-width, the equivalence test's 90 % half-width (t₀.₉₅ at the same
    Welch–Satterthwaite degrees of freedom ``dof``) and the standard error ``se``."""
    d, h95 = welch(x, ref)
    se, dof = welch_terms(x, ref)
    m = float(np.mean(ref))
    return dict(d=d / m, h95=h95 / m, h90=t_quantile(0.95, dof) * se / m, se=se / m, dof=dof)


def report(data, out):
    s, prov = data.attrs["settings"], data.attrs
    freqs, mus, U = s["freqs"], s["mus"], 0.0045
    i_ref = mus.index(THESIS_MU) if THESIS_MU in mus else 0
    k = int(np.argmin(np.abs(np.asarray(freqs) - 15.25)))
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(10, 4))
    for i, m in enumerate(mus):
        draw_replicates(a1, freqs, data["amplitude"][i] / U, label=f"μ = {m:g}")
        draw_replicates(a2, freqs, data["granular_loss_per_cycle"][i], label=f"μ = {m:g}")
    a1.set(xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U  [-]")
    a2.set(xlabel="excitation frequency f [Hz]", ylabel="granular loss per cycle [J]")
    a1.set_title(f"optimal box, grain and wall friction μ, R = {s['R']} beds ± 2 SE", fontsize=9)
    a2.set_title("energy dissipated by the grains per period", fontsize=9)
    for a in (a1, a2):
        a.legend(fontsize=7)
    scaffold.save_figure(fig, out)
    rows = []
    for i, m in enumerate(mus):
        zp, fp = np.asarray(data["Z_peak"][i]), np.asarray(data["f_peak"][i])
        e = np.asarray(data["granular_loss_per_cycle"][i, k])
        cells = [f"{m:g}", scaffold.pm(*scaffold.mean_se(zp / U), ".4f", ".4f"),
                 scaffold.pm(*scaffold.mean_se(fp), ".3f", ".3f"),
                 scaffold.pm(*scaffold.mean_se(e), ".3f", ".3f")]
        if i == i_ref:
            cells += ["reference"] * 3
        else:
            for x, ref in ((zp, data["Z_peak"][i_ref]), (fp, data["f_peak"][i_ref]),
                           (e, data["granular_loss_per_cycle"][i_ref, k])):
                d = differences(x, np.asarray(ref))
                cells.append(f"{100 * d['d']:+.2f} % (95 %: ± {100 * d['h95']:.2f}; "
                             f"90 %: ± {100 * d['h90']:.2f}; SE {100 * d['se']:.2f}, "
                             f"ν {d['dof']:.1f})")
        rows.append(cells)
    law = s.get("tangential_law", "viscous")
    title = "Friction coefficient and the FRF at the optimum (thesis §5.3.1)"
    lines = scaffold.head(title if law == "viscous" else
                          f"{title}, under the Hertz–Mindlin spring", prov, prov["sweep_wall_s"])
    if law != "viscous":
        lines += [f"Tangential law: `tangential_law = {law!r}` (the spring with history, "
                  "docs/physics.md §2; the materials' γ_s unused), not the thesis' viscous "
                  "law.", ""]
    lines += [f"`sanchez2012-optimal` (Lz = 0.1225 m, C = 7.6 N s/m, N = 250, E = 2.03e9), "
              f"grain and wall μ ∈ {list(mus)}, frequencies {list(freqs)} Hz × **R = {s['R']} "
              f"independently poured beds**, {s['duration']} s per run after settling; steady "
              f"means after the MSER-detected start ({prov['stationary']} of {prov['runs']} "
              "runs stationary; the others enter with their final-10 % value). ± = SE over "
              "the beds; differences relative to μ = 0.3 with Welch 95 % and the equivalence "
              "test's 90 % half-widths. The verdict ('unchanged' = equivalent within the "
              "systematic margin) is the scoreboard's (row D16).", ""]
    lines += scaffold.table(["μ", "resonant Z/U", "resonance [Hz]",
                             f"loss per cycle at {freqs[k]:g} Hz [J]", "change of Z_res",
                             "change of the resonance", "change of the loss"], rows)
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, options=options, report=report)


if __name__ == "__main__":
    main()
