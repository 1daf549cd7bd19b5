"""The driven box's two regimes either side of the optimal amplitude (2023 paper §4, §5.2; P11).

    python experiments/driven_regimes.py [--quick]   # full mode: minutes; --quick: test-sized

The paper: below A_opt few grains hit the walls per period (a gas-like bed), above it the bed
collides with floor and lid as a whole ("collect-and-collide"). ``varela2023-reference``, ``R``
poured beds per amplitude (one batch, :func:`jaxdamp.studies.efficiency.measure`), each over its
analysed periods: the fraction of grains touching floor or lid; the **relative excursion**,
half the peak-to-peak of the phase-averaged centre-of-mass height above the floor over
``(Lz − h_rest)/2`` (0: a bed staying put, 1: a slug crossing the gap); the centre of mass's
first harmonic over ``A_d`` and its phase against the box; ``⟨E_d⟩``; lowest against highest
amplitude by Welch 95 %. Writes ``data.h5``, ``figure.png``, ``summary.md``; raw: ``--out/raw``.
"""

from __future__ import annotations

import math

import h5py
import numpy as np

from jaxdamp.analysis.response import first_harmonic
from jaxdamp.analysis.stats import t_quantile, welch
from jaxdamp.cases import presets
from jaxdamp.figures.response import draw_replicates
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import reuse_or_run

A_OPT_OURS = 0.02567  # [m], reference system, binary_mixtures (3 beds)
A_OPT_PAPER = 0.028
#: Each bed's measures: name → (units, table column, figure axis or None: not drawn).
MEASURES = {
    "contact": ("1", "grains touching floor or lid", "grains touching floor or lid [fraction]"),
    "excursion": ("1", "relative excursion", "relative excursion of the bed [-]"),
    "com_amp": ("1", "c.o.m. harmonic / A_d", "c.o.m. first harmonic / A_d [-]"),
    "com_phase": ("deg", "c.o.m. phase vs box [deg]", None),
    "E_d": ("1", "⟨E_d⟩", "efficiency ⟨E_d⟩ [-]")}


def settings(quick: bool) -> dict:
    if quick:
        return dict(amps=(0.015, 0.035), transient=2, periods=4, R=2)
    return dict(amps=(0.01, 0.015, 0.02, 0.025, 0.03, 0.035, 0.04), transient=10, periods=30, R=3)


def bed(c, rec: dict, periods: int, rest: float) -> dict:
    """One bed's :data:`MEASURES` from its records (config ``c``, bed height at rest ``rest``)."""
    a = ef.analyse(c, rec, periods)
    h_rel = a["phase"]["z_cm_species"][:, 0] - a["phase"]["z_box"]
    t = np.asarray(rec["t"])
    keep = t >= t[-1] - periods / c.frequency
    (amp_c, ph_c), (_, ph_b) = (first_harmonic(t[keep], np.asarray(rec[k])[keep], c.frequency)
                                for k in ("z_cm", "z_box"))
    return dict(contact=a["summary"]["contacts_mean"] / c.n_grains, E_d=a["summary"]["E_d_mean"],
                excursion=np.ptp(h_rel) / (c.box.Lz - rest), com_amp=amp_c / c.drive.amplitude,
                com_phase=math.degrees(math.remainder(ph_c - ph_b, 2 * math.pi)))


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = ef.protocol(presets.get("varela2023-reference"), s["periods"], s["transient"], 100,
                      s["amps"])
    res = reuse_or_run(cfg, {"drive.amplitude": list(s["amps"])},
                       ctx.raw(f"reference_R{s['R']}.h5"), progress=ctx.progress,
                       replicates=s["R"], snapshots=0)
    with h5py.File(res.path, "r") as h:
        rest = np.asarray(h["settle/bed_height"]).reshape(len(s["amps"]), s["R"])
    beds = [[bed(c, {k: v[res.point(i, r)] for k, v in res.records.items()}, s["periods"],
                 rest[i, r]) for r in range(s["R"])] for i, c in enumerate(res.configs)]
    m = {k: np.array([[b[k] for b in row] for row in beds], float) for k in MEASURES}
    result = dict(s=s, m=m, rest=rest, cfg=cfg, res=res, wall=float(res.summary["wall_time"]),
                  balance=float(np.nanmax(np.abs(res.summary["balance_error"]))),
                  stationary=int(np.sum(res.steady["amplitude"]["stationary"]))
                  if res.steady else 0)
    return result, lambda out, prov: record(result, out, prov)


def record(r, out, prov):
    with scaffold.data_file(out, dict(prov, sweep_wall_s=r["wall"]), settings=r["s"],
                            base_config=r["cfg"].to_json(), stationary=r["stationary"],
                            balance_error_max=r["balance"]) as h:
        h.create_dataset("amplitude", data=np.asarray(r["s"]["amps"])).attrs["units"] = "m"
        for k, (u, _, _) in MEASURES.items():
            h.create_dataset(k, data=r["m"][k]).attrs.update(units=u, dims="amplitude, replicate")
        h.create_dataset("bed_height_rest", data=r["rest"]).attrs["units"] = "m"


def report(data, out):
    s, prov, amps, R = data.attrs["settings"], data.attrs, data["amplitude"], data["E_d"].shape[1]
    drawn = [(k, axis) for k, (_, _, axis) in MEASURES.items() if axis]
    fig, axs = scaffold.subplots(1, len(drawn), figsize=(16, 3.8))
    for ax, (k, axis) in zip(axs, drawn):
        draw_replicates(ax, amps * 100, data[k])
        ax.axvline(A_OPT_OURS * 100, color="tab:green", ls="--", lw=0.8, label="our A_opt")
        ax.axvline(A_OPT_PAPER * 100, color="tab:red", ls=":", lw=0.8, label="paper's A_opt")
        ax.set(xlabel="drive amplitude A_d [cm]", ylabel=axis)
    axs[0].legend(fontsize=7)
    fig.suptitle(f"varela2023-reference, mean of R = {R} beds ± 2 SE", fontsize=9)
    scaffold.save_figure(fig, out)

    L = ["# The two regimes of the driven box (2023 paper §4, §5.2)", "",
         scaffold.provenance_line(prov, prov["sweep_wall_s"]) + " Native engine.", "",
         f"`varela2023-reference`, {len(amps)} amplitudes × **R = {R} independently poured "
         f"beds**, {s['transient']} transient + {s['periods']} analysed periods at 70 Hz; ± = "
         "standard error over the beds; lowest and highest amplitude compared by Welch 95 % (t = "
         f"{t_quantile(0.975, max(R - 1, 1)):.2f} per side). Stationarity: {prov['stationary']} "
         f"of {len(amps) * R} runs detected stationary by MSER on the per-period amplitude and "
         f"dissipation. Energy balance error ≤ {prov['balance_error_max']:.1e}.", ""]
    L += scaffold.table(["A_d [cm]"] + [col for _, col, _ in MEASURES.values()],
                        [[f"{a * 100:g}"] + [scaffold.pm(*scaffold.mean_se(data[k][i]), 3)
                                             for k in MEASURES] for i, a in enumerate(amps)])
    L += ["", f"Highest minus lowest amplitude ({amps[-1] * 100:g} − {amps[0] * 100:g} cm), "
          "Welch 95 %: " + "; ".join(f"{k} {scaffold.pm(*welch(data[k][-1], data[k][0]), '+.3g')}"
                                     for k in ("contact", "excursion", "com_amp")) + ".", "",
          f"Our A_opt for this system is {A_OPT_OURS * 100:g} cm (`binary_mixtures`, 3 beds); "
          f"the paper's ≈ {A_OPT_PAPER * 100:g} cm.", ""]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
