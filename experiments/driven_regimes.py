"""The two regimes of the driven box on either side of the optimal amplitude (2023 paper §4,
§5.2; scoreboard row P11), with replicates.

    python experiments/driven_regimes.py            # full mode (minutes)
    python experiments/driven_regimes.py --quick    # test-sized

The paper: below the optimal amplitude A_opt only a small fraction of the grains hit the walls
per period (a gas-like bed), above it the centre of mass moves with the drive and the bed
collides with floor and lid as a whole ("collect-and-collide"). For the reference system
(``varela2023-reference``: 300 grains in an 8 cm cube at 70 Hz) at drive amplitudes around our
A_opt (2.57 ± 0.001 cm, `binary_mixtures`; the paper: ≈ 2.8 cm), ``R`` independently poured
beds per amplitude (one batch, :func:`jaxdamp.studies.efficiency.measure`), 10 transient and
30 analysed periods, each bed measured over the analysed periods:

- **wall contact**: the mean fraction of the grains touching floor or lid;
- **relative excursion** of the bed: half the peak-to-peak of the phase-averaged height of the
  centre of mass above the floor, over the largest it can be, ``(Lz − h_rest)/2`` with
  ``h_rest`` the bed height at rest — 0 for a bed that stays put in the box (a gas filling it,
  or a bed on the floor), 1 for a slug crossing the whole gap each half period;
- **c.o.m. with the drive**: the first-harmonic amplitude of the centre of mass's height in
  the lab frame over ``A_d`` and its phase against the box (0: moving with the box);
- ``⟨E_d⟩`` (mean over the analysed periods; the steady state detected per bed by MSER).

Values are means over the beds ± standard error; the two sides of A_opt are compared with
Welch 95 % intervals (the lowest and highest amplitude). Writes ``data.h5``, ``figure.png``,
``summary.md``; raw sweeps in ``--out/raw`` (not committed).
"""

from __future__ import annotations

import math

import h5py
import numpy as np

from jaxdamp.analysis.response import first_harmonic
from jaxdamp.analysis.stats import t_quantile, welch
from jaxdamp.cases import presets
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
    return dict(amps=(0.01, 0.015, 0.02, 0.025, 0.03, 0.035, 0.04), transient=10, periods=30,
                R=3)


def bed(c, rec: dict, periods: int, rest: float) -> dict:
    """One bed's :data:`MEASURES` from its records (config ``c``, bed height at rest ``rest``)."""
    a = ef.analyse(c, rec, periods)
    h_rel = a["phase"]["z_cm_species"][:, 0] - a["phase"]["z_box"]
    t = np.asarray(rec["t"])
    keep = t >= t[-1] - periods / c.frequency
    (amp_c, ph_c), (_, ph_b) = (first_harmonic(t[keep], np.asarray(rec[k])[keep], c.frequency)
                                for k in ("z_cm", "z_box"))
    return dict(contact=a["summary"]["contacts_mean"] / c.n_grains,
                excursion=0.5 * np.ptp(h_rel) / (0.5 * (c.box.Lz - rest)),
                com_amp=amp_c / c.drive.amplitude,
                com_phase=math.degrees(math.remainder(ph_c - ph_b, 2 * math.pi)),
                E_d=a["summary"]["E_d_mean"])


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
    comp = {k: dict(zip(("diff", "ci95"), welch(m[k][-1], m[k][0]))) for k in MEASURES}
    result = dict(s=s, m=m, comp=comp, rest=rest, cfg=cfg, res=res, n=cfg.n_grains,
                  balance=float(np.nanmax(np.abs(res.summary["balance_error"]))),
                  wall=float(res.summary["wall_time"]),
                  stationary=int(np.sum(res.steady["amplitude"]["stationary"]))
                  if res.steady else 0)
    for i, A in enumerate(s["amps"]):
        log(f"A_d = {A * 100:g} cm: contact {m['contact'][i].mean():.3f}, excursion "
            f"{m['excursion'][i].mean():.2f}, c.o.m. {m['com_amp'][i].mean():.2f} A_d")
    return result, lambda out, prov: write(result, out, prov)


main = scaffold.entry(__file__, __doc__, compute)


def write(r, out, prov):
    s, m, R = r["s"], r["m"], r["s"]["R"]
    prov = dict(prov, sweep_wall_s=r["wall"])
    with scaffold.data_file(out, prov, settings=s, base_config=r["cfg"].to_json()) as h:
        h.create_dataset("amplitude", data=np.asarray(s["amps"])).attrs["units"] = "m"
        for k, (u, _, _) in MEASURES.items():
            h.create_dataset(k, data=m[k]).attrs.update(units=u, dims="amplitude, replicate")
        h.create_dataset("bed_height_rest", data=r["rest"]).attrs["units"] = "m"

    drawn = [(k, axis) for k, (_, _, axis) in MEASURES.items() if axis]
    fig, axs = scaffold.subplots(1, len(drawn), figsize=(16, 3.8))
    for ax, (k, axis) in zip(axs, drawn):
        ax.errorbar(np.asarray(s["amps"]) * 100, m[k].mean(-1),
                    yerr=2 * scaffold.standard_error(m[k]), fmt="o-", capsize=3)
        ax.axvline(A_OPT_OURS * 100, color="tab:green", ls="--", lw=0.8, label="our A_opt")
        ax.axvline(A_OPT_PAPER * 100, color="tab:red", ls=":", lw=0.8, label="paper's A_opt")
        ax.set(xlabel="drive amplitude A_d [cm]", ylabel=axis)
    axs[0].legend(fontsize=7)
    fig.suptitle(f"varela2023-reference, mean of R = {R} beds ± 2 SE", fontsize=9)
    scaffold.save_figure(fig, out)

    c = r["comp"]
    L = ["# The two regimes of the driven box (2023 paper §4, §5.2)", "",
         scaffold.provenance_line(prov, prov["sweep_wall_s"]) + " Native engine.", "",
         f"`varela2023-reference`, {len(s['amps'])} amplitudes × **R = {R} independently "
         f"poured beds**, {s['transient']} transient + {s['periods']} analysed periods at 70 Hz; "
         f"± = standard error over the beds; the lowest and highest amplitude compared by Welch "
         f"95 % (t = {t_quantile(0.975, max(R - 1, 1)):.2f} per side). Stationarity: "
         f"{r['stationary']} of {len(s['amps']) * R} runs detected stationary by MSER on the "
         f"per-period amplitude and dissipation (the measures below use the analysed periods "
         f"of every run). Energy balance error ≤ {r['balance']:.1e}.", ""]
    L += scaffold.table(["A_d [cm]"] + [col for _, col, _ in MEASURES.values()],
                        [[f"{a * 100:g}"] + [scaffold.pm(*scaffold.mean_se(m[k][i]), 3)
                                             for k in MEASURES] for i, a in enumerate(s["amps"])])
    L += ["", f"Highest minus lowest amplitude ({s['amps'][-1] * 100:g} − {s['amps'][0] * 100:g} "
          "cm), Welch 95 %: " + "; ".join(f"{k} {scaffold.pm(c[k]['diff'], c[k]['ci95'], '+.3g')}"
                                          for k in ("contact", "excursion", "com_amp")) + ".",
          "", f"Our A_opt for this system is {A_OPT_OURS * 100:g} cm (`binary_mixtures`, 3 beds); "
          f"the paper's ≈ {A_OPT_PAPER * 100:g} cm. 'Relative excursion' = half the peak-to-peak "
          "of the phase-averaged height of the centre of mass above the floor over "
          "(Lz − h_rest)/2.", ""]
    scaffold.write_summary(out, L)


if __name__ == "__main__":
    main()
