"""The 2023 paper's results, replicated: dissipation efficiency of binary mixtures in a driven box.

    python experiments/binary_mixtures.py                  # full mode (see --help for cost)
    python experiments/binary_mixtures.py --quick          # test-sized: σ = 0.5, 2 amplitudes
    python experiments/binary_mixtures.py --sigmas 0.5,0.9 --low-sigmas 0.1 --replicates 3

Families (SPEC §5; Varela-Rosales et al. 2023): the monodisperse reference (300 steel grains,
R = 2.5 mm) and binary mixtures of class a (equal mass), b (equal number) and c (equal number and
mass) at size ratios σ, in an 8 cm cube driven at 70 Hz over A_d = 2–4 cm. For every family and
σ one batched amplitude sweep with ``--replicates`` independently seeded beds per amplitude
(:func:`jaxdamp.studies.efficiency.measure`), 10 transient periods then 50 analysed (the
paper's 50). Each replicate's steady state is detected from its per-period ``E_d`` (MSER); the
estimates are means over the stationary replicates with their standard error, and every
comparison with the reference is a Welch 95 % interval of the difference across beds. Small σ
costs ~1/σ more steps (dt follows the smallest grains): the ``--low-sigmas`` run with
``--low-periods`` analysed periods at three amplitudes, stated in the summary, with the
projected cost of the full protocol.

What is measured beyond the paper: the time-resolved segregation index
``S = 2 (h_large − h_small)/(h_large + h_small)`` of the species' centre-of-mass heights above
the floor, per period (:func:`jaxdamp.studies.efficiency.segregation_index`), and every class
stated three ways — the paper's ⟨E_d⟩/m, ⟨E_d⟩ (per unit mass: E_max ∝ m already) and the
energy the damper dissipates per period.

Figures: ``efficiency.png`` (⟨E_d⟩/m vs A_d per class, 95 % intervals across beds; paper figs.
2, 6, 9), ``segregation.png`` (S per period at 3 cm), ``contacts_force.png`` (wall contacts and
wall force vs phase at 3 cm; figs. 4, 5, 7, 10, 11), ``phase_plots.png`` (centre-of-mass
v_z(z) per species, σ = 0.5, classes b and c; figs. 8, 12), ``snapshots.png`` (reference and
class a at the smallest σ at the drive's turning points and largest speed; fig. 3). Data:
``data.h5`` (every family's per-replicate summaries, steady estimates, per-period and phase
arrays); raw sweeps in ``raw/`` (re-running reuses finished sweeps and resumes partial ones).
``summary.md`` states each of the paper's claims with the numbers and the interval that
decides it.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import time

import numpy as np

from jaxdamp.cases import presets
from jaxdamp.figures import save, snapshot_grid_figure
from jaxdamp.physics.model import grain_radii, grain_species
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies import scaffold

CLASS_NAMES = {"a": "class a (equal mass)", "b": "class b (equal number)",
               "c": "class c (equal number and mass)"}
#: The paper's transition amplitude [m], the threshold of its "above A_opt" claims.
A_PAPER = 0.028
#: The paper's claim for each class at σ = 0.5 against the reference above A_opt.
EXPECT = {"a": "above", "b": "above", "c": "below"}
#: The snapshots' quarter periods (the paper shows min (I, III) and max (II) speed).
CAPTIONS = {0: "(I/III) top, v = 0", 1: "(II) fastest, moving down", 2: "(III/I) bottom, v = 0"}


def settings(args):
    if args.quick:
        return dict(amps=[0.025, 0.035], periods=2, transient=1, sigmas=[0.5], low_sigmas=[],
                    low_periods=0, low_transient=0, low_amps=[], replicates=2)
    return dict(amps=list(np.round(np.linspace(0.02, 0.04, 9), 6)), periods=args.periods,
                transient=args.transient, sigmas=args.sigmas, low_sigmas=args.low_sigmas,
                low_periods=args.low_periods, low_transient=args.low_transient,
                low_amps=[0.02, 0.03, 0.04], replicates=args.replicates)


def run_family(name, sigma, protocol, ctx, replicates):
    """One family's amplitude sweep with ``replicates`` beds per amplitude (resumable file);
    ``protocol``: ``(amplitudes, periods, transient, settle time or None)``."""
    amps, periods, transient, settle = protocol
    cfg = presets.family(name, sigma)
    if settle is not None:  # quick mode: the transient period erases the start anyway
        cfg = cfg.replace(numerics=dataclasses.replace(cfg.numerics, settle_time=settle))
    tag = name.split("-")[1] + (f"_sigma{sigma:g}" if sigma is not None else "")
    path = ctx.raw(f"{tag}_a{len(amps)}_t{transient}_p{periods}_R{replicates}.h5")
    r = ef.measure(cfg, amps, periods=periods, transient=transient, out=path,
                   progress=ctx.progress, echo=None, replicates=replicates)
    return dict(name=name, sigma=sigma, result=r, periods=periods, transient=transient,
                path=path, klass=name.split("-")[1])


def fam_label(run):
    return run["klass"] + (f" σ={run['sigma']:g}" if run["sigma"] is not None else "")


def plot_label(run):
    if run["sigma"] is None:
        return "reference (σ = 1)"
    return f"σ = {run['sigma']:g}" + (f" ({run['transient']} + {run['periods']} periods)"
                                      if run["periods"] != 50 else "")


def at3(r):
    return int(np.argmin(np.abs(r.amplitudes - 0.03)))


def quarters(r):
    """The quarter period (0: the box at its top) of each of the snapshots' times."""
    f = r.config.frequency
    return [int(round((t * f % 1.0) * 4)) % 4 for t in r.snapshots["t"]]


# per-replicate quantities: arrays (P, R), NaN where a replicate is not stationary


def per_mass(run):
    """⟨E_d⟩/m [1/kg] of every replicate from its detected steady state, ``(P, R)``."""
    return run["result"].steady["E_d_per_mass"]["values"]


#: A class's dissipation three ways, ``(P, R)``: the paper's ⟨E_d⟩/m, ⟨E_d⟩ [1] (per unit
#: mass: E_max ∝ m) from each replicate's steady state, and the energy dissipated per period
#: [J] (E_pp + E_pw over the analysed periods).
NORMALISATIONS = {
    "⟨E_d⟩/m": per_mass, "⟨E_d⟩": lambda run: run["result"].steady["E_d"]["values"],
    "energy per period": lambda run: (np.asarray(run["result"].replicate_summary["E_pp"])
                                      + np.asarray(run["result"].replicate_summary["E_pw"]))}


def a_opt(run):
    """Each replicate's A_opt [m] (:func:`ef.optimal_amplitudes` of its ⟨E_d⟩/m), ``(R,)``;
    NaN where a replicate is not stationary at some amplitude or the family has < 3 amplitudes."""
    return ef.optimal_amplitudes(run["result"].amplitudes, per_mass(run))


def fmt(values, digits=3):
    """Mean ± SE across beds (:func:`scaffold.across`), the count where there is no SE."""
    e = scaffold.across(values)
    if not np.isfinite(e.mean):
        return "n/a"
    return scaffold.pm(e.mean, e.se, digits) + ("" if np.isfinite(e.se) else f" (n = {e.n})")


def per_species(r, x):
    """``x`` ``(R, S)`` per species, mean ± SE across beds, as text."""
    return ", ".join(f"{sp.name} {fmt(c)}" for sp, c in zip(r.config.grains, x.T))


def options(ap):
    sigmas = lambda t: [float(x) for x in t.split(",") if x]  # noqa: E731
    ap.add_argument("--sigmas", type=sigmas, default=[0.3, 0.5, 0.7, 0.9],
                    help="size ratios on the full protocol (~6 min per σ and bed on 2 cores "
                         "at σ = 0.5, ~10 min at 0.3)")
    ap.add_argument("--low-sigmas", type=sigmas, default=[0.1],
                    help="size ratios on the short protocol (3 amplitudes)")
    ap.add_argument("--replicates", type=_at_least_one, default=3,
                    help="independently seeded beds per amplitude (≥ 2 for intervals)")
    ap.add_argument("--periods", type=int, default=50)
    ap.add_argument("--transient", type=int, default=10)
    ap.add_argument("--low-periods", type=int, default=5)
    ap.add_argument("--low-transient", type=int, default=3)
    ap.add_argument("--classes", default="abc")


def _at_least_one(text):
    if int(text) < 1:
        raise argparse.ArgumentTypeError(f"{text}: at least 1 bed per amplitude")
    return int(text)


def compute(quick, log, ctx):
    args = ctx.args
    s = settings(args)
    full = (s["amps"], s["periods"], s["transient"], 0.02 if quick else None)
    low = (s["low_amps"], s["low_periods"], s["low_transient"], None)
    plan = [("reference", None, full)] + [
        (k, sigma, p) for k in args.classes
        for sigma, p in [(x, full) for x in s["sigmas"]] + [(x, low) for x in s["low_sigmas"]]]
    runs = [run_family(f"varela2023-{k}", sigma, p, ctx, s["replicates"]) for k, sigma, p in plan]
    drift = [] if quick else balance_drift(ctx.progress)

    def write(out, prov):
        write_data(out, prov, runs)
        figures(out, runs, args.classes)
        write_summary(out, prov, s, runs, drift)
        log(f"wrote {out}/summary.md ({prov['elapsed_s']:.0f} s; sweeps "
            f"{sum(r['result'].wall_time for r in runs):.0f} s)")

    return runs, write


main = scaffold.entry(__file__, __doc__, compute, options)


def write_data(out, prov, runs):
    with scaffold.data_file(out, prov, E_max="4 m A_d^2 omega^2") as h:
        for run in runs:
            r = run["result"]
            g = h.create_group(run["name"] + (f"/sigma_{run['sigma']:g}" if run["sigma"] else ""))
            g.attrs.update(config=r.config.to_json(), periods=run["periods"],
                           transient_periods=run["transient"], replicates=r.replicates,
                           wall_time=r.wall_time)
            g.create_dataset("amplitude", data=r.amplitudes).attrs["units"] = "m"
            g.create_dataset("A_opt", data=a_opt(run)).attrs["units"] = "m"
            for part, units in (("summary", ef.SUMMARY_UNITS),
                                ("replicate_summary", ef.SUMMARY_UNITS),
                                ("phase", ef.PHASE_UNITS), ("per_period", ef.PER_PERIOD_UNITS),
                                ("replicate_per_period", ef.PER_PERIOD_UNITS)):
                for k, v in getattr(r, part).items():
                    g.create_dataset(f"{part}/{k}", data=v).attrs["units"] = units.get(k, "")
            for q, est in r.steady.items():
                for k, v in est.items():
                    d = g.create_dataset(f"steady/{q}/{k}", data=v)
                    if k in ("mean", "se", "ci95", "values", "batch_se"):
                        d.attrs["units"] = "1/kg" if q.endswith("per_mass") else "1"
                    elif k == "start":
                        d.attrs["units"] = "s"


def _family_runs(runs, klass):
    return [r for r in runs if r["klass"] == klass]


def _class_panels(classes, rows, title, width=5, height=4.2):
    """One column per class, one row per ``(xlabel, ylabel, draw)`` of ``rows``:
    ``draw(ax, klass)``, then the panel's labels and legend; the top panel's title the class
    and ``title``."""
    n = max(len(classes), 1)
    fig, axes = scaffold.subplots(len(rows), n, figsize=(width * n, height), squeeze=False)
    for j, klass in enumerate(classes):
        for ax, (xlabel, ylabel, draw) in zip(axes[:, j], rows):
            draw(ax, klass)
            ax.set(xlabel=xlabel, ylabel=ylabel)
            ax.legend(fontsize=7)
        axes[0, j].set_title(f"{CLASS_NAMES[klass]}{title}", fontsize=9)
    return fig


def figures(out, runs, classes):
    ref = runs[0]

    def efficiency(ax, klass):  # ⟨E_d⟩/m vs A_d (figs. 2, 6, 9)
        for run in [ref] + _family_runs(runs, klass):
            st = run["result"].steady["E_d_per_mass"]
            ax.errorbar(run["result"].amplitudes * 100, st["mean"], yerr=st["ci95"],
                        fmt="o-" if run is not ref else "ks-", ms=3.5, capsize=2,
                        label=plot_label(run))
        ax.axvline(A_PAPER * 100, color="0.6", ls=":", lw=1)

    def segregation(ax, klass):  # segregation index per period at 3 cm
        for run in _family_runs(runs, klass):
            r = run["result"]
            seg = np.asarray(r.replicate_per_period["segregation"][at3(r)])  # (R, n)
            t = np.arange(1, seg.shape[1] + 1)
            m, se = seg.mean(axis=0), np.nan_to_num(scaffold.standard_error(seg, axis=0))
            (line,) = ax.plot(t, m, lw=1.2, label=plot_label(run))
            ax.fill_between(t, m - se, m + se, color=line.get_color(), alpha=0.25, lw=0)
        ax.axhline(0.0, color="0.5", lw=0.8)

    def phase_curve(key):  # contacts or force vs phase at 3 cm, replicate means
        def draw(ax, klass):
            for run in [ref] + _family_runs(runs, klass):
                r, k = run["result"], at3(run["result"])
                ax.plot(r.phase["phase"][k], r.phase[key][k], "k-" if run is ref else "-",
                        lw=1, label=plot_label(run))
        return draw

    def phase_plot(ax, klass):  # centre of mass v_z(z) per species at σ = 0.5
        for run in [ref] + [r for r in _family_runs(runs, klass) if r["sigma"] == 0.5]:
            r, k = run["result"], at3(run["result"])
            zc, vc = r.phase["z_cm_species"][k], r.phase["vz_cm_species"][k]
            close = lambda a: np.append(a, a[:1])  # noqa: E731
            for sp, spec in enumerate(r.config.grains):
                ax.plot(close(zc[:, sp]) * 100, close(vc[:, sp]),
                        "k-" if run is ref else ("-" if sp == 0 else "--"), lw=1.2,
                        label=f"{plot_label(run)}: {spec.name}")

    x_phase = "phase t/T [1] (box at its top at 0)"
    scaffold.save_figure(_class_panels(classes, [(
        "drive amplitude A_d [cm] (dotted: the paper's A_opt)",
        "⟨E_d⟩ / m [1/kg] (mean, 95 % interval across beds)", efficiency)], ""),
        out, "efficiency.png")
    scaffold.save_figure(_class_panels(classes, [(
        "drive period (transient first)", "segregation index S [1] (mean ± SE)", segregation)],
        ", A_d = 3 cm"), out, "segregation.png")
    scaffold.save_figure(_class_panels(classes, [  # figs. 4, 5, 7, 10, 11
        (x_phase, "grains touching floor or lid [1]", phase_curve("contacts")),
        (x_phase, "vertical force on floor + lid [N]", phase_curve("force_floor_lid"))],
        ", A_d = 3 cm (mean over beds)", height=7), out, "contacts_force.png")
    scaffold.save_figure(_class_panels(  # figs. 8, 12
        [k for k in "bc" if k in classes], [("z [cm] (lab frame)", "v_z [m/s]", phase_plot)],
        ": centre of mass, A_d = 3 cm", width=6, height=4.5), out, "phase_plots.png")

    # snapshots (fig. 3): reference and class a at the smallest σ run, first bed
    rows = []
    a_runs = _family_runs(runs, "a")
    for run in [ref] + ([min(a_runs, key=lambda r: r["sigma"])] if a_runs else []):
        r = run["result"]
        row = at3(r) * r.replicates  # replicates are the fastest axis of the snapshots
        f = r.config.frequency
        frames = [(f"t/T = {t * f:.2f}: {CAPTIONS[q]}", r.snapshots["r"][row, j],
                   r.snapshots["z_box"][row, j])  # top, fastest, bottom
                  for j, (t, q) in enumerate(zip(r.snapshots["t"], quarters(r)))
                  if q in CAPTIONS]
        rows.append((f"{'reference' if run is ref else 'class a, ' + plot_label(run)}, A_d = 3 cm",
                     frames, grain_radii(r.config), grain_species(r.config), r.config))
    save(snapshot_grid_figure(rows, "driven box at 70 Hz"), os.path.join(out, "snapshots.png"))


def balance_drift(progress, amplitude=0.03, periods=5, transient=2, replicates=3):
    """Energy-balance drift of the reference at 3 cm against the time step: the balance residual
    gained over the analysed periods, relative to the dissipation (E_pp + E_pw) in them, for
    dt = t_c/50 (the default) and t_c/100, on ``replicates`` independently poured beds each
    (one batch per time step). Velocity Verlet's energy error per Hertz collision falls as
    (dt/t_c)^2.5, so the drift should fall ~5.7× (tests/test_energy.py). Per time step: each
    bed's relative drift and ⟨E_d⟩ ``(R,)``."""
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies.sweep import sweep

    rows = []
    for n in (50, 100):
        cfg = apply_overrides(presets.family("varela2023-reference"),
                              {"drive.amplitude": amplitude, "numerics.dt_per_collision": n})
        cfg = ef.protocol(cfg, periods=periods, transient=transient)
        t0 = time.perf_counter()
        res = sweep(cfg, {"drive.amplitude": [amplitude]}, progress=progress, echo=None,
                    replicates=replicates)
        i0, i1 = transient * 100 - 1, (transient + periods) * 100 - 1  # 100 samples per period
        drift, e_d = [], []
        for r in range(replicates):
            rec = {k: v[res.point(0, r)] for k, v in res.records.items()}
            a = ef.analyse(res.configs[0], rec, periods)
            diss = float((a["per_period"]["E_pp"] + a["per_period"]["E_pw"])[transient:].sum())
            drift.append(float(rec["balance_residual"][i1] - rec["balance_residual"][i0]) / diss)
            e_d.append(a["summary"]["E_d_mean"])
        rows.append(dict(dt_per_collision=n, drift=np.asarray(drift), E_d=np.asarray(e_d),
                         wall=time.perf_counter() - t0))
    return rows


def write_summary(out, prov, s, runs, drift=()):
    ref = runs[0]
    amps = ref["result"].amplitudes
    R = ref["result"].replicates
    lines = []
    P = lines.append
    P("# Binary mixtures in a driven box — the 2023 paper's results, replicated\n")
    P(scaffold.provenance_line(prov) + " Float64, native engine; the sweeps' own compute time "
      "(kept across resumes) is listed per family below.\n")
    convention = presets.get("varela2023-reference").wall_damping
    P(f"Grain–wall damping: `wall_damping = \"{convention}\"` "
      "(the wall's constant, calibrated on 2.5 mm grains, mixed with each grain's; the paper does "
      "not say). The alternative, every contact calibrated to ε = 0.75 at 1 m/s, changes ⟨E_d⟩ "
      "by −5 % at 2 cm and +0.5 to +1.5 % at 3–4 cm (experiments/wall_damping/summary.md).\n")
    P(f"Protocol: f = 70 Hz, A_d = {', '.join(f'{a * 100:g}' for a in amps)} cm, "
      f"{s['transient']} transient periods then {s['periods']} analysed (paper: 50); "
      "E_max = 4 m A_d² ω² (SPEC §4, our reading of Sack et al. 2013).\n")
    P(f"**Realisations and uncertainty.** {R} independently seeded beds per amplitude and "
      "family (`--replicates`). Each bed's steady state starts where MSER on its per-period "
      "E_d says (over all simulated periods, transient included); a bed that is not detected "
      "stationary is left out and the count says so. Every value is the mean over beds ± its "
      "standard error across beds (s/√n); a difference is 'above'/'below' when its Welch 95 % "
      "interval excludes 0, otherwise 'not significant'. The paper's error bars are the spread "
      "over periods of one run; ours are not.\n")
    n_stat = {fam_label(r): r["result"].steady["E_d"]["stationary"] for r in runs}
    P("Stationary beds (detected / run, over all amplitudes): "
      + "; ".join(f"{k} {int(np.sum(st))}/{st.size}" for k, st in n_stat.items()) + ".\n")
    P("## ⟨E_d⟩/m [1/kg] per family (mean ± SE across beds)\n")
    rows = []
    for run in runs:
        r = run["result"]
        cells = {round(a, 6): fmt(per_mass(run)[i]) for i, a in enumerate(r.amplitudes)}
        steps = (run["transient"] + run["periods"]) / r.config.frequency / r.config.numerics.dt
        ao = a_opt(run)
        rows.append([fam_label(run), r.config.n_grains, f"{r.summary['mass'][0]:.4f}",
                     f"{r.config.numerics.dt:.3g}", f"{run['transient']} + {run['periods']}"]
                    + [cells.get(round(a, 6), "–") for a in amps]
                    + [fmt(ao * 100) if np.isfinite(ao).any() else "–",
                       f"{r.wall_time:.0f} ({r.wall_time / steps / len(r.amplitudes) / R * 1e6:.1f}"
                       " µs/system-step)"])
    lines += scaffold.table(["family", "N", "m [kg]", "dt [s]", "periods"]
                            + [f"{a * 100:g} cm" for a in amps]
                            + ["A_opt [cm]", "sweep wall [s]"], rows)

    def projected(run):  # minutes for the full protocol at this run's cost per period
        r = run["result"]
        return (r.wall_time * 9 / len(r.amplitudes) * (s["transient"] + s["periods"])
                / (run["transient"] + run["periods"]) / 60)

    low = [run for run in runs if run["periods"] != s["periods"]]
    if low:
        P("\nSmall size ratios ran a shorter protocol ("
          + "; ".join(f"{fam_label(run)}: {len(run['result'].amplitudes)} amplitudes × "
                      f"{run['transient']} + {run['periods']} periods × {R} beds in "
                      f"{run['result'].wall_time:.0f} s, the full protocol (9 amplitudes × "
                      f"{s['transient']} + {s['periods']} periods × {R} beds) projected at "
                      f"{projected(run):.0f} min"
                      for run in low) + ").")
    worst = max(float(np.max(run["result"].replicate_summary["balance_error"])) for run in runs)
    P("\nEnergy balance (max |residual| / max input work over the run), worst over all points "
      f"and beds: {worst:.2e}.\n")
    if drift:
        c = ef.compare_beds(drift[0]["E_d"], drift[1]["E_d"])
        P(f"Energy-balance drift vs time step (reference, A_d = 3 cm, 2 + 5 periods, "
          f"{len(drift[0]['drift'])} beds per time step, mean ± SE across beds; residual gained "
          "over the analysed periods / energy dissipated in them): "
          + "; ".join(f"dt = t_c/{d['dt_per_collision']}: {fmt(d['drift'])} (⟨E_d⟩ "
                      f"{fmt(d['E_d'], 4)}, {d['wall']:.0f} s wall)" for d in drift)
          + f". ⟨E_d⟩ at t_c/50 minus t_c/100: {scaffold.pm(c.diff, c.half, '+.4f', '.4f')} "
          f"(Welch 95 %: {c.verdict}).\n")
    P("## The paper's claims\n")
    lines += [f"- {line}" for line in claims(runs)]
    P("\n## At A_d = 3 cm: wall contacts, wall force, centre-of-mass speed, segregation\n")
    P("Every column: mean ± SE across beds. Mean contacts and S over the analysed periods; "
      "peak contacts, peak abs(F_z) and the largest centre-of-mass speed from each bed's own "
      "phase curve (averaged over its analysed periods).\n")
    rows = []
    for run in runs:
        r, k = run["result"], at3(run["result"])
        rs, b, seg = r.replicate_summary, bed_phase(run, k), segregation_at3(run)
        rows.append([fam_label(run), fmt(per_mass(run)[k]), fmt(rs["wall_fraction"][k]),
                     fmt(rs["contacts_mean"][k]), per_species(r, b["contacts_species"]),
                     fmt(b["contacts_peak"]), fmt(b["force_peak"], 4),
                     per_species(r, b["vz_max"]), seg["S"], seg["trend"]])
    lines += scaffold.table(["family", "⟨E_d⟩/m", "E_pw/(E_pp+E_pw)", "mean contacts",
                             "contacts per species", "peak contacts", "peak abs(F_z) [N]",
                             "max abs(v_z) COM per species [m/s]", "S", "S trend [1/period]"],
                            rows)
    P("\nS trend: each bed's least-squares slope of S over its analysed periods, mean ± SE "
      "across beds; a slope whose interval includes 0 means S is steady (the bed is not still "
      "segregating or mixing).\n")
    P("Figures: `efficiency.png` (figs. 2, 6, 9), `segregation.png` (S per period), "
      "`contacts_force.png` (figs. 4, 5, 7, 10, 11), `phase_plots.png` (figs. 8, 12), "
      "`snapshots.png` (fig. 3, first bed). Data: `data.h5`.")  # the file's last line
    scaffold.write_summary(out, lines)
    with open(os.path.join(out, "claims.json"), "w") as fh:
        json.dump({fam_label(r): {"A_opt_cm": [float(x) for x in a_opt(r) * 100]} for r in runs},
                  fh, indent=1)


def bed_phase(run, k):
    """Each bed's phase features at amplitude index ``k`` (from its own phase curves, averaged
    over its analysed periods): ``force_peak``, ``force_mean`` the peak and the period mean of
    abs(F_z) on floor + lid [N] ``(R,)``; ``contacts_peak`` ``(R,)``; ``contacts_species`` the
    mean wall contacts per species ``(R, S)``; ``vz_max`` the largest abs(v_z) of each
    species' centre of mass [m/s] ``(R, S)``."""
    ph = run["result"].replicate_phase
    f = np.abs(np.asarray(ph["force_floor_lid"][k]))  # (R, spp)
    return dict(force_peak=f.max(axis=1), force_mean=f.mean(axis=1),
                contacts_peak=np.asarray(ph["contacts"][k]).max(axis=1),
                contacts_species=np.asarray(ph["contacts_species"][k]).mean(axis=1),
                vz_max=np.abs(np.asarray(ph["vz_cm_species"][k])).max(axis=1))


def segregation_at3(run):
    """S at 3 cm over each bed's analysed periods, and its trend per period, as text."""
    r = run["result"]
    win = np.asarray(r.replicate_per_period["segregation"][at3(r)])[:, -run["periods"]:]
    if not np.isfinite(win).all():
        return {"S": "–", "trend": "–", "values": None}
    x = np.arange(win.shape[1])
    slopes = [np.polyfit(x, w, 1)[0] for w in win] if win.shape[1] > 1 else [np.nan]
    return {"S": fmt(win.mean(axis=1)), "trend": fmt(slopes, 2), "values": win.mean(axis=1),
            "slopes": np.asarray(slopes)}


def claims(runs):
    """One line per claim of SPEC §5 with the numbers and the interval that decide it."""
    ref = runs[0]
    amps = ref["result"].amplitudes
    full = [r for r in runs if len(r["result"].amplitudes) == len(amps)]  # ref first
    # A_opt ≈ 2.8 cm for every σ
    est = [(run, e) for run in full for e in [scaffold.across(a_opt(run))] if np.isfinite(e.mean)]
    inside = sum(bool(np.isfinite(e.ci95) and abs(e.mean - A_PAPER) <= e.ci95) for _, e in est)
    out = ["**A_opt ≈ 2.8 cm for every σ** (each bed's largest ⟨E_d⟩/m, parabola through "
           "its top three amplitudes; mean ± SE across beds, cm): "
           + "; ".join(f"{fam_label(run)} {scaffold.pm(e.mean, e.se, '.3f', '.3f', scale=100)}"
                       for run, e in est)
           + f". The paper's 2.8 cm lies inside the 95 % interval for {inside} of "
           f"{len(est)} families. Depends on E_max ∝ A_d² (our reading of the paper)."]
    # class vs reference above A_opt, at every σ; the three normalisations
    above = np.flatnonzero(amps > A_PAPER + 1e-9)
    for run in full[1:]:
        klass, want = run["klass"], EXPECT[run["klass"]]
        parts = {name: [ef.compare_beds(fn(run)[i], fn(ref)[i]) for i in above]
                 for name, fn in NORMALISATIONS.items()}
        verdicts = [c.verdict for c in parts["⟨E_d⟩/m"]]
        head = (f"**class {klass} (σ = {run['sigma']:g}) vs the reference for A_d > 2.8 cm** "
                f"(paper, at σ = 0.5: {want}) — in the paper's ⟨E_d⟩/m: "
                f"{verdicts.count(want)} of {len(verdicts)} amplitudes {want} (Welch 95 %), the "
                "rest " + (", ".join(sorted({v for v in verdicts if v != want})) or "none")
                + "; ratio to the reference "
                + ", ".join(scaffold.pm(c.ratio, c.ratio_se, ".3f", ".3f")
                            for c in parts["⟨E_d⟩/m"])
                + f" at {', '.join(f'{a * 100:g}' for a in amps[above])} cm.")
        mass_ratio = run["result"].summary["mass"][0] / ref["result"].summary["mass"][0]
        plain = [f"{name} ratio {min(c.ratio for c in cs):.3f}–{max(c.ratio for c in cs):.3f} ("
                 + ", ".join(f"{[c.verdict for c in cs].count(v)} {v}"
                             for v in ("above", "below", "not significant")) + ")"
                 for name, cs in parts.items() if name != "⟨E_d⟩/m"]
        out.append(head + f" Mass ratio {mass_ratio:.4f}. Per unit mass (⟨E_d⟩; E_max ∝ m "
                   f"already): {plain[0]}. Per damper (J dissipated per period): {plain[1]}.")
    return out + diagnostics(runs)


def diagnostics(runs):
    """The paper's explanations at A_d = 3 cm (figs. 4, 5, 7, 8, 10–12), segregation and fig. 3."""
    ref = runs[0]
    rr = ref["result"]
    c_ref = rr.replicate_summary["contacts_mean"][at3(rr)]
    b_ref = bed_phase(ref, at3(rr))

    def versus(x, y, unit, digits=4):
        c = ef.compare_beds(x, y)
        return (f"{fmt(x, digits)} vs {fmt(y, digits)} {unit} (difference "
                f"{scaffold.pm(c.diff, c.half, '+.4g')}, Welch 95 %: {c.verdict})")

    out = []
    for run in runs[1:]:  # every class and σ (the paper shows σ = 0.5)
        r, k, klass = run["result"], at3(run["result"]), run["klass"]
        c = r.replicate_summary["contacts_mean"][k]
        cmp = ef.compare_beds(c, c_ref)
        want = "above" if klass == "a" else "below"
        b = bed_phase(run, k)
        text = (f"**class {klass} (σ = {run['sigma']:g}) at 3 cm, wall contacts**: {fmt(c)} "
                f"grains on floor or lid on average vs {fmt(c_ref)} for the reference (difference "
                f"{scaffold.pm(cmp.diff, cmp.half, '+.2f', '.2f')}, Welch 95 %: {cmp.verdict}; "
                f"paper: {'more' if want == 'above' else 'fewer'}; "
                f"{'as the paper' if cmp.verdict == want else 'not as the paper'}); per species "
                + per_species(r, b["contacts_species"]))
        if klass in "ac":
            text += ("; **wall force** (each bed's phase curve) peak "
                     + versus(b["force_peak"], b_ref["force_peak"], "N")
                     + ", period mean " + versus(b["force_mean"], b_ref["force_mean"], "N")
                     + f" (paper: {'larger' if klass == 'a' else 'smaller'})")
        if klass in "bc":
            vs = "; ".join(f"{sp.name} " + versus(v, b_ref["vz_max"][:, 0], "m/s", 3)
                           for sp, v in zip(r.config.grains, b["vz_max"].T))
            want_v = ("both species faster than the reference" if klass == "b"
                      else "large grains like the reference, small grains faster")
            text += (f"; **largest centre-of-mass speed** (each bed's phase curve) {vs} "
                     f"(paper: {want_v})")
        out.append(text + ".")
    # segregation (paper fig. 3: "size segregation appears")
    seg_rows = []
    for run in runs[1:]:
        sg = segregation_at3(run)
        if sg["values"] is None:
            continue
        e = scaffold.across(sg["values"])
        sign = ("large grains higher" if e.mean - e.ci95 > 0 else "large grains lower"
                if e.mean + e.ci95 < 0 else "not distinguishable from 0"
                ) if np.isfinite(e.ci95) else "undetermined"
        seg_rows.append(f"{fam_label(run)} {sg['S']} ({sign})")
    if seg_rows:
        out.append("**Size segregation at 3 cm** (index S over the analysed periods, mean ± SE "
                   "across beds; 95 % interval against 0): " + "; ".join(seg_rows) + ". In a "
                   "well-mixed bed of unequal radii S is not exactly 0 (small centres reach "
                   "R_large − R_small closer to the floor), so a small |S| is not segregation.")

    def spreads(run):
        """Per snapshot (phase): the quarter ``q``, and per bed the spread (std) of all grain
        heights and the mean heights of the two species above the floor ``(R,)`` [cm]."""
        r = run["result"]
        sp = grain_species(r.config)
        rows = at3(r) * r.replicates + np.arange(r.replicates)
        out = []
        for j, q in enumerate(quarters(r)):
            z = (r.snapshots["r"][rows, j, :, 2] - r.snapshots["z_box"][rows, j][:, None]) * 100
            out.append((q, z.std(axis=1), z[:, sp == 0].mean(axis=1),
                        z[:, sp == 1].mean(axis=1) if (sp == 1).any() else None))
        return out

    # fig. 3: spread in the snapshots (last period of every bed)
    if rr.snapshots is not None:
        ref_sp = spreads(ref)
        for run in runs:
            if run["sigma"] is None or run["result"].snapshots is None or run["klass"] != "a":
                continue
            rows = []
            for (q, std, hl, hs), (_, std_ref, _, _) in zip(spreads(run), ref_sp):
                rows.append(f"{q / 4:.2f}T: {fmt(hl)} / {fmt(hs)} cm, spread {fmt(std)} cm vs "
                            f"reference {fmt(std_ref)} cm ({ef.compare_beds(std, std_ref).verdict}"
                            ", Welch 95 %)")
            out.append(f"fig. 3, class a σ = {run['sigma']:g} at 3 cm, snapshots of the last "
                       "period of every bed (phase: mean height of large / small grains above "
                       "the floor, spread (std) of all heights, mean ± SE across beds): "
                       + "; ".join(rows) + ".")
    return out


if __name__ == "__main__":
    main()
