"""The 2023 paper's results, replicated: dissipation efficiency of binary mixtures in a driven box.

    python experiments/binary_mixtures.py                  # full mode (see --help for cost)
    python experiments/binary_mixtures.py --quick          # test-sized: σ = 0.5, 2 amplitudes
    python experiments/binary_mixtures.py --sigmas 0.5,0.9 --low-sigmas 0.1 --replicates 3

The reference (300 steel grains, R = 2.5 mm) and binary mixtures of class a (equal mass), b
(equal number), c (equal number and mass) at size ratios σ (SPEC §5) in an 8 cm cube at 70 Hz,
A_d = 2–4 cm: per family one batched amplitude sweep of ``--replicates`` seeded beds
(:func:`jaxdamp.studies.efficiency.measure`; small σ on a shorter protocol), each bed's steady
state by MSER on its per-period ``E_d``, means over beds ± SE, Welch 95 % against the reference;
beyond the paper, the segregation index S and three normalisations. Writes ``data.h5``, from it
``summary.md``, ``claims.json`` (A_opt per bed) and the paper's figs. 2–12 (``efficiency``,
``segregation``, ``contacts_force``, ``phase_plots``, ``snapshots.png``); raw sweeps in ``raw/``.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides, from_dict
from jaxdamp.figures import save, snapshot_grid_figure
from jaxdamp.io.common import put, write_steady
from jaxdamp.physics.model import grain_radii, grain_species
from jaxdamp.studies import efficiency as ef
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import sweep

CLASS_NAMES = {"a": "class a (equal mass)", "b": "class b (equal number)",
               "c": "class c (equal number and mass)"}
#: The paper's transition amplitude [m], the threshold of its "above A_opt" claims.
A_PAPER = 0.028
#: The paper's claim for each class at σ = 0.5 against the reference above A_opt.
EXPECT = {"a": "above", "b": "above", "c": "below"}
#: The snapshots' quarter periods (the paper shows min (I, III) and max (II) speed).
CAPTIONS = {0: "(I/III) top, v = 0", 1: "(II) fastest, moving down", 2: "(III/I) bottom, v = 0"}
#: Units of the 3 cm phase features (:func:`at3_stats`) kept across beds.
AT3_UNITS = {"contacts_species": "1", "contacts_peak": "1", "force_peak": "N", "force_mean": "N",
             "vz_max": "m/s"}


def options(ap):
    def at_least_one(text):
        if int(text) < 1:
            raise argparse.ArgumentTypeError(f"{text}: at least 1 bed per amplitude")
        return int(text)

    sigmas = lambda t: [float(x) for x in t.split(",") if x]  # noqa: E731
    ap.add_argument("--sigmas", type=sigmas, default=[0.3, 0.5, 0.7, 0.9], help="size ratios, "
                    "full protocol (~6 min per σ and bed on 2 cores at σ = 0.5, ~10 at 0.3)")
    ap.add_argument("--low-sigmas", type=sigmas, default=[0.1], help="size ratios, 3 amplitudes")
    ap.add_argument("--replicates", type=at_least_one, default=3,
                    help="independently seeded beds per amplitude (≥ 2 for intervals)")
    for flag, default in (("--periods", 50), ("--transient", 10), ("--low-periods", 5),
                          ("--low-transient", 3)):
        ap.add_argument(flag, type=int, default=default)
    ap.add_argument("--classes", default="abc")


def compute(quick, log, ctx):
    a = ctx.args
    if quick:  # protocols: (amplitudes, periods, transient, settle time or None)
        full, low, sigmas, low_sigmas, R = ([0.025, 0.035], 2, 1, 0.02), None, [0.5], [], 2
    else:
        full = (list(np.round(np.linspace(0.02, 0.04, 9), 6)), a.periods, a.transient, None)
        low = ([0.02, 0.03, 0.04], a.low_periods, a.low_transient, None)
        sigmas, low_sigmas, R = a.sigmas, a.low_sigmas, a.replicates
    plan = [("reference", None, full)] + [
        (k, sigma, p) for k in a.classes
        for sigma, p in [(x, full) for x in sigmas] + [(x, low) for x in low_sigmas]]
    runs = []
    for klass, sigma, (amps, periods, transient, settle) in plan:  # one sweep, R beds per point
        cfg = presets.family(f"varela2023-{klass}", sigma)
        if settle is not None:  # quick mode: the transient period erases the start anyway
            cfg = apply_overrides(cfg, {"numerics.settle_time": settle})
        tag = klass + (f"_sigma{sigma:g}" if sigma is not None else "")
        path = ctx.raw(f"{tag}_a{len(amps)}_t{transient}_p{periods}_R{R}.h5")  # resumable
        r = ef.measure(cfg, amps, periods=periods, transient=transient, out=path,
                       progress=ctx.progress, echo=None, replicates=R)
        runs.append(dict(name=f"varela2023-{klass}", sigma=sigma, result=r, periods=periods,
                         transient=transient, klass=klass))
    drift = [] if quick else balance_drift(ctx.progress)
    return runs, lambda out, prov: record(out, prov, runs, drift)


def at3(amplitudes):
    return int(np.argmin(np.abs(np.asarray(amplitudes) - 0.03)))


def est(x):
    """``[mean, SE, n]`` across beds of per-bed values ``x`` (:func:`scaffold.across`)."""
    e = scaffold.across(x)
    return [float(e.mean), float(e.se), int(e.n)]


def versus(x, y):
    """``[difference, Welch 95 % half-width, verdict]`` of per-bed ``x`` against ``y``."""
    c = ef.compare_beds(x, y)
    return [float(c.diff), float(c.half), c.verdict]


def at3_stats(r, ref):
    """Each bed's phase features at 3 cm (:data:`AT3_UNITS`, from its own phase curves over its
    analysed periods) across beds (:func:`est`) and against the reference's (:func:`versus`)."""
    def bed_phase(r):  # (R,) or per species (R, S)
        ph, k = r.replicate_phase, at3(r.amplitudes)
        f = np.abs(np.asarray(ph["force_floor_lid"][k]))  # (R, spp)
        return dict(force_peak=f.max(axis=1), force_mean=f.mean(axis=1),
                    contacts_peak=np.asarray(ph["contacts"][k]).max(axis=1),
                    contacts_species=np.asarray(ph["contacts_species"][k]).mean(axis=1),
                    vz_max=np.abs(np.asarray(ph["vz_cm_species"][k])).max(axis=1))

    b = bed_phase(r)
    st = {k: [est(v) for v in b[k].T] if b[k].ndim == 2 else est(b[k]) for k in AT3_UNITS}
    if ref is not r:
        br = bed_phase(ref)
        st.update({f"{k}_vs_ref": versus(b[k], br[k]) for k in ("force_peak", "force_mean")},
                  vz_max_vs_ref=[versus(v, br["vz_max"][:, 0]) for v in b["vz_max"].T])
    return dict(st, units=AT3_UNITS)


def snapshot_stats(r, ref):
    """Per snapshot (quarter points of every bed's last period) at 3 cm, across beds: the spread
    (std) of grain heights above the floor [cm], each species' mean height, spread vs ``ref``'s."""
    def heights(r):  # (R, Q, N)
        rows = at3(r.amplitudes) * r.replicates + np.arange(r.replicates)
        return (r.snapshots["r"][rows][..., 2] - r.snapshots["z_box"][rows][..., None]) * 100

    z, sp, f = heights(r), grain_species(r.config), r.config.frequency
    st = {"units": "cm", "quarter": [int(round((t * f % 1.0) * 4)) % 4 for t in r.snapshots["t"]],
          "spread": [est(x) for x in z.std(axis=2).T]}
    for i, key in enumerate(("h_large", "h_small")[: sp.max() + 1]):
        st[key] = [est(x) for x in z[..., sp == i].mean(axis=2).T]
    if ref is not r:
        st["spread_vs_ref"] = [versus(x, y)[2] for x, y in zip(z.std(axis=2).T,
                                                                  heights(ref).std(axis=2).T)]
    return st


def record(out, prov, runs, drift):
    ref = runs[0]["result"]
    groups = [run["name"] + (f"/sigma_{run['sigma']:g}" if run["sigma"] else "") for run in runs]
    attrs = dict(families=groups, balance_drift=drift) if drift else dict(families=groups)
    units = dict(summary=ef.SUMMARY_UNITS, phase=ef.PHASE_UNITS, per_period=ef.PER_PERIOD_UNITS)
    with scaffold.data_file(out, prov, E_max="4 m A_d^2 omega^2", **attrs) as h:
        for run, path in zip(runs, groups):
            r = run["result"]
            g = h.create_group(path)
            g.attrs.update(config=r.config.to_json(), periods=run["periods"],
                           transient_periods=run["transient"], replicates=r.replicates,
                           wall_time=r.wall_time, at_3cm=json.dumps(at3_stats(r, ref)))
            put(g, "amplitude", r.amplitudes, "m")
            a_opt = ef.optimal_amplitudes(r.amplitudes, r.steady["E_d_per_mass"]["values"])
            put(g, "A_opt", a_opt, "m")
            for part in [*units, "replicate_summary", "replicate_per_period"]:
                for k, v in getattr(r, part).items():
                    put(g, f"{part}/{k}", v, units[part.removeprefix("replicate_")].get(k, ""))
            write_steady(g, r.steady, r.replicates,
                         lambda q: "1/kg" if q.endswith("per_mass") else "1")
            if r.snapshots is not None and run["klass"] in ("reference", "a"):
                g.attrs["snapshots_3cm"] = json.dumps(snapshot_stats(r, ref))
                row = at3(r.amplitudes) * r.replicates  # the first bed at 3 cm, for the figure
                for k, u in (("t", "s"), ("r", "m"), ("z_box", "m")):
                    put(g, f"snapshots/{k}", r.snapshots[k][() if k == "t" else row], u)


def balance_drift(progress, amplitude=0.03, periods=5, transient=2, replicates=3):
    """The reference's balance residual gained over the analysed periods / their dissipation,
    and ⟨E_d⟩, across beds at dt = t_c/50 (default) and t_c/100 (Verlet: ~5.7× less error)."""
    rows, e_ds = [], []
    for n in (50, 100):
        cfg = ef.protocol(apply_overrides(presets.family("varela2023-reference"), {
            "drive.amplitude": amplitude, "numerics.dt_per_collision": n}), periods, transient)
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
        e_ds.append(e_d)
        rows.append(dict(dt_per_collision=n, drift=est(drift), E_d=est(e_d),
                         wall=time.perf_counter() - t0))
    return dict(units={"drift": "1", "E_d": "1", "wall": "s"}, amplitude=amplitude,
                transient=transient, periods=periods, beds=replicates, rows=rows,
                E_d_difference=versus(*e_ds))


def families(data):
    """The stored families in run order: dicts of ``g`` (group), ``klass``, ``sigma``, ``config``,
    ``amps``, ``periods``, ``transient``, ``R``, ``wall``, ``label`` (tables), ``legend``."""
    out = []
    for path in data.attrs["families"]:
        name, _, sub = path.partition("/")
        g, sigma = (data[name][sub], float(sub[6:])) if sub else (data[name], None)
        periods, transient = g.attrs["periods"], g.attrs["transient_periods"]
        short = f" ({transient} + {periods} periods)" if periods != 50 else ""
        out.append(dict(g=g, klass=name.split("-")[1], sigma=sigma, periods=periods,
                        transient=transient, config=from_dict(g.attrs["config"]),
                        amps=g["amplitude"], R=g.attrs["replicates"], wall=g.attrs["wall_time"],
                        label=name.split("-")[1] + (f" σ={sigma:g}" if sub else ""),
                        legend=f"σ = {sigma:g}{short}" if sub else "reference (σ = 1)"))
    return out


#: A class's dissipation per bed three ways, ``(P, R)`` (NaN: not stationary): the paper's
#: ⟨E_d⟩/m [1/kg], ⟨E_d⟩ (per unit mass: E_max ∝ m) and the energy dissipated per period [J].
NORMALISATIONS = {
    "⟨E_d⟩/m": lambda run: run["g"]["steady"]["E_d_per_mass"]["values"],
    "⟨E_d⟩": lambda run: run["g"]["steady"]["E_d"]["values"],
    "energy per period": lambda run: (run["g"]["replicate_summary"]["E_pp"]
                                      + run["g"]["replicate_summary"]["E_pw"])}


def show(e, digits=3):
    """A stored ``[mean, SE, n]`` as mean ± SE, the count where there is no SE."""
    mean, se, n = e
    if not np.isfinite(mean):
        return "n/a"
    return scaffold.pm(mean, se, digits) + ("" if np.isfinite(se) else f" (n = {n})")


def fmt(values, digits=3):
    """Mean ± SE across beds of per-bed ``values`` (:func:`est`)."""
    return show(est(values), digits)


def per_species(run, stats, digits=3):
    """Stored per-species ``[mean, SE, n]`` as text."""
    return ", ".join(f"{sp.name} {show(e, digits)}" for sp, e in zip(run["config"].grains, stats))


def segregation_at3(run):
    """S at 3 cm over each bed's analysed periods, its trend per period and the sign of S (its
    95 % interval against 0), as text (``sign`` None where S is not finite)."""
    win = run["g"]["replicate_per_period"]["segregation"][at3(run["amps"])][:, -run["periods"]:]
    if not np.isfinite(win).all():
        return {"S": "–", "trend": "–", "sign": None}
    e = scaffold.across(win.mean(axis=1))
    sign = ("large grains higher" if e.mean - e.ci95 > 0 else "large grains lower"
            if e.mean + e.ci95 < 0 else "not distinguishable from 0"
            ) if np.isfinite(e.ci95) else "undetermined"
    x = np.arange(win.shape[1])
    slopes = [np.polyfit(x, w, 1)[0] for w in win] if win.shape[1] > 1 else [np.nan]
    return {"S": fmt(win.mean(axis=1)), "trend": fmt(slopes, 2), "sign": sign}


def class_panels(out, name, title, classes, rows, width=5, height=4.2):
    """``name``: one column per class, one row per ``(xlabel, ylabel, draw, *args)`` of ``rows``
    (``draw(ax, klass, *args)``)."""
    n = max(len(classes), 1)
    fig, axes = scaffold.subplots(len(rows), n, figsize=(width * n, height), squeeze=False)
    for j, klass in enumerate(classes):
        for ax, (xlabel, ylabel, draw, *args) in zip(axes[:, j], rows):
            draw(ax, klass, *args)
            ax.set(xlabel=xlabel, ylabel=ylabel)
            ax.legend(fontsize=7)
        axes[0, j].set_title(f"{CLASS_NAMES[klass]}{title}", fontsize=9)
    scaffold.save_figure(fig, out, name)


def figures(out, runs, classes):
    ref = runs[0]
    family = lambda klass: [r for r in runs if r["klass"] == klass]  # noqa: E731

    def efficiency(ax, klass):  # ⟨E_d⟩/m vs A_d (figs. 2, 6, 9)
        for run in [ref] + family(klass):
            st = run["g"]["steady"]["E_d_per_mass"]
            ax.errorbar(run["amps"] * 100, st["mean"], yerr=st["ci95"],
                        fmt="ks-" if run is ref else "o-", ms=3.5, capsize=2, label=run["legend"])
        ax.axvline(A_PAPER * 100, color="0.6", ls=":", lw=1)

    def segregation(ax, klass):  # segregation index per period at 3 cm
        for run in family(klass):
            seg = run["g"]["replicate_per_period"]["segregation"][at3(run["amps"])]  # (R, n)
            t = np.arange(1, seg.shape[1] + 1)
            m, se = seg.mean(axis=0), np.nan_to_num(scaffold.standard_error(seg, axis=0))
            (line,) = ax.plot(t, m, lw=1.2, label=run["legend"])
            ax.fill_between(t, m - se, m + se, color=line.get_color(), alpha=0.25, lw=0)
        ax.axhline(0.0, color="0.5", lw=0.8)

    def phase_curve(ax, klass, key):  # at 3 cm, mean over beds (figs. 4, 5, 7, 10, 11)
        for run in [ref] + family(klass):
            ph, k = run["g"]["phase"], at3(run["amps"])
            ax.plot(ph["phase"][k], ph[key][k], "k-" if run is ref else "-", lw=1,
                    label=run["legend"])

    def phase_plot(ax, klass):  # centre of mass v_z(z) per species at σ = 0.5 (figs. 8, 12)
        for run in [ref] + [r for r in family(klass) if r["sigma"] == 0.5]:
            ph, k = run["g"]["phase"], at3(run["amps"])
            zc, vc = ph["z_cm_species"][k], ph["vz_cm_species"][k]
            close = lambda a: np.append(a, a[:1])  # noqa: E731
            for sp, spec in enumerate(run["config"].grains):
                ax.plot(close(zc[:, sp]) * 100, close(vc[:, sp]),
                        "k-" if run is ref else ("-" if sp == 0 else "--"), lw=1.2,
                        label=f"{run['legend']}: {spec.name}")

    x_phase = "phase t/T [1] (box at its top at 0)"
    class_panels(out, "efficiency.png", "", classes, [(
        "drive amplitude A_d [cm] (dotted: the paper's A_opt)",
        "⟨E_d⟩ / m [1/kg] (mean, 95 % interval across beds)", efficiency)])
    class_panels(out, "segregation.png", ", A_d = 3 cm", classes, [(
        "drive period (transient first)", "segregation index S [1] (mean ± SE)", segregation)])
    class_panels(out, "contacts_force.png", ", A_d = 3 cm (mean over beds)", classes, [
        (x_phase, "grains touching floor or lid [1]", phase_curve, "contacts"),
        (x_phase, "vertical force on floor + lid [N]", phase_curve, "force_floor_lid")], height=7)
    class_panels(out, "phase_plots.png", ": centre of mass, A_d = 3 cm",
                 [k for k in "bc" if k in classes],
                 [("z [cm] (lab frame)", "v_z [m/s]", phase_plot)], width=6, height=4.5)

    shown = [ref] + sorted(family("a"), key=lambda r: r["sigma"])[:1]  # fig. 3: smallest σ
    if all("snapshots" in run["g"] for run in shown):
        rows = []
        for run in shown:
            sn, c, st = run["g"]["snapshots"], run["config"], run["g"].attrs["snapshots_3cm"]
            frames = [(f"t/T = {t * c.frequency:.2f}: {CAPTIONS[q]}", r, z) for t, q, r, z in zip(
                sn["t"], st["quarter"], sn["r"], sn["z_box"]) if q in CAPTIONS]
            rows.append((f"{'reference' if run is ref else 'class a, ' + run['legend']}, "
                         "A_d = 3 cm", frames, grain_radii(c), grain_species(c), c))
        save(snapshot_grid_figure(rows, "driven box at 70 Hz"), os.path.join(out, "snapshots.png"))


def report(data, out):
    runs, prov, drift = families(data), data.attrs, data.attrs.get("balance_drift")
    figures(out, runs, sorted({run["klass"] for run in runs[1:]}))
    with open(os.path.join(out, "claims.json"), "w") as fh:
        json.dump({r["label"]: {"A_opt_cm": [float(x) for x in r["g"]["A_opt"] * 100]}
                   for r in runs}, fh, indent=1)
    ref, per_mass = runs[0], NORMALISATIONS["⟨E_d⟩/m"]
    amps, R, full = ref["amps"], ref["R"], ref["transient"] + ref["periods"]
    lines = []
    P = lines.append
    P("# Binary mixtures in a driven box — the 2023 paper's results, replicated\n")
    P(scaffold.provenance_line(prov) + " Float64, native engine; the sweeps' own compute time "
      "is listed per family below.\n")
    P(f"Grain–wall damping: `wall_damping = \"{ref['config'].wall_damping}\"` (the wall's "
      "constant, calibrated on 2.5 mm grains, mixed with each grain's; the paper does not say). "
      "Every contact calibrated to ε = 0.75 at 1 m/s instead changes ⟨E_d⟩ by −5 % at 2 cm and "
      "+0.5 to +1.5 % at 3–4 cm (experiments/wall_damping/summary.md).\n")
    P(f"Protocol: f = 70 Hz, {ref['transient']} transient then {ref['periods']} analysed "
      "periods (paper: 50); E_max = 4 m A_d² ω² (SPEC §4, our reading of Sack et al. 2013). "
      f"{R} independently seeded beds per amplitude and family, a bed left out where MSER on its "
      "per-period E_d finds no steady state; mean over beds ± SE, 'above'/'below' where the "
      "Welch 95 % interval excludes 0 (the paper's error bars: the spread over one run).\n")
    P("Stationary beds (detected / run, over all amplitudes): " + "; ".join(
        f"{r['label']} {int(np.sum(st))}/{st.size}"
        for r in runs for st in [r["g"]["steady"]["E_d"]["stationary"]]) + ".\n")
    P("## ⟨E_d⟩/m [1/kg] per family (mean ± SE across beds)\n")
    rows = []
    for run in runs:
        c, ao, wall = run["config"], run["g"]["A_opt"], run["wall"]
        cells = {round(a, 6): fmt(per_mass(run)[i]) for i, a in enumerate(run["amps"])}
        steps = (run["transient"] + run["periods"]) / c.frequency / c.numerics.dt
        rows.append([run["label"], c.n_grains, f"{run['g']['summary']['mass'][0]:.4f}",
                     f"{c.numerics.dt:.3g}", f"{run['transient']} + {run['periods']}"]
                    + [cells.get(round(a, 6), "–") for a in amps]
                    + [fmt(ao * 100) if np.isfinite(ao).any() else "–",
                       f"{wall:.0f} ({wall / steps / len(run['amps']) / R * 1e6:.1f}"
                       " µs/system-step)"])
    lines += scaffold.table(["family", "N", "m [kg]", "dt [s]", "periods"]
                            + [f"{a * 100:g} cm" for a in amps]
                            + ["A_opt [cm]", "sweep wall [s]"], rows)
    low = [run for run in runs if run["periods"] != ref["periods"]]
    if low:  # the full protocol projected at each run's cost per period
        P("\nSmall size ratios ran a shorter protocol (" + "; ".join(
            f"{run['label']}: {len(run['amps'])} amplitudes × {run['transient']} + "
            f"{run['periods']} periods × {R} beds in {run['wall']:.0f} s, the full protocol "
            f"(9 amplitudes × {ref['transient']} + {ref['periods']} periods × {R} beds) projected "
            f"at {run['wall'] * 9 / len(run['amps']) * full / n / 60:.0f} min"
            for run in low for n in [run["transient"] + run["periods"]]) + ").")
    worst = max(float(np.max(run["g"]["replicate_summary"]["balance_error"])) for run in runs)
    P("\nEnergy balance (max |residual| / max input work over the run), worst over all points "
      f"and beds: {worst:.2e}.\n")
    if drift:
        d, h, verdict = drift["E_d_difference"]
        P(f"Energy-balance drift vs time step (reference, A_d = {drift['amplitude'] * 100:g} cm, "
          f"{drift['transient']} + {drift['periods']} periods, {drift['beds']} beds per time "
          "step, mean ± SE across beds; residual gained over the analysed periods / energy "
          "dissipated in them): " + "; ".join(
              f"dt = t_c/{r['dt_per_collision']}: {show(r['drift'])} (⟨E_d⟩ "
              f"{show(r['E_d'], 4)}, {r['wall']:.0f} s wall)" for r in drift["rows"])
          + f". ⟨E_d⟩ at t_c/50 minus t_c/100: {scaffold.pm(d, h, '+.4f', '.4f')} "
          f"(Welch 95 %: {verdict}).\n")
    P("## The paper's claims\n")
    lines += [f"- {line}" for line in claims(runs)]
    P("\n## At A_d = 3 cm: wall contacts, wall force, centre-of-mass speed, segregation\n")
    P("Mean ± SE across beds; peaks and the largest centre-of-mass speed from each bed's own "
      "phase curve over its analysed periods.\n")
    rows = []
    for run in runs:
        k, rs, st, seg = (at3(run["amps"]), run["g"]["replicate_summary"],
                          run["g"].attrs["at_3cm"], segregation_at3(run))
        rows.append([run["label"], fmt(per_mass(run)[k]), fmt(rs["wall_fraction"][k]),
                     fmt(rs["contacts_mean"][k]), per_species(run, st["contacts_species"]),
                     show(st["contacts_peak"]), show(st["force_peak"], 4),
                     per_species(run, st["vz_max"]), seg["S"], seg["trend"]])
    lines += scaffold.table(["family", "⟨E_d⟩/m", "E_pw/(E_pp+E_pw)", "mean contacts",
                             "contacts per species", "peak contacts", "peak abs(F_z) [N]",
                             "max abs(v_z) COM per species [m/s]", "S", "S trend [1/period]"],
                            rows)
    P("\nS trend: each bed's least-squares slope of S per period; an interval including 0: S "
      "steady (not still segregating or mixing).\n")
    P("Figures: `efficiency.png` (figs. 2, 6, 9), `segregation.png`, `contacts_force.png` "
      "(figs. 4, 5, 7, 10, 11), `phase_plots.png` (figs. 8, 12), `snapshots.png` (fig. 3).")
    scaffold.write_summary(out, lines)


def claims(runs):
    """One line per claim of SPEC §5 with the numbers and the interval that decide it."""
    ref, amps = runs[0], runs[0]["amps"]
    full = [r for r in runs if len(r["amps"]) == len(amps)]  # ref first
    opt = [(run, e) for run in full for e in [scaffold.across(run["g"]["A_opt"])]
           if np.isfinite(e.mean)]
    inside = sum(bool(np.isfinite(e.ci95) and abs(e.mean - A_PAPER) <= e.ci95) for _, e in opt)
    out = ["**A_opt ≈ 2.8 cm for every σ** (each bed's largest ⟨E_d⟩/m, parabola through "
           "its top three amplitudes; mean ± SE across beds, cm): "
           + "; ".join(f"{run['label']} {scaffold.pm(e.mean, e.se, '.3f', '.3f', scale=100)}"
                       for run, e in opt)
           + f". The paper's 2.8 cm lies inside the 95 % interval for {inside} of "
           f"{len(opt)} families. Depends on E_max ∝ A_d² (our reading of the paper)."]
    above = np.flatnonzero(amps > A_PAPER + 1e-9)  # each class vs the reference above A_opt
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
        mass_ratio = run["g"]["summary"]["mass"][0] / ref["g"]["summary"]["mass"][0]
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
    c_ref = ref["g"]["replicate_summary"]["contacts_mean"][at3(ref["amps"])]
    st_ref = ref["g"].attrs["at_3cm"]

    def vs(x, y, cmp, unit, digits=4):  # stored [mean, SE, n] of both, [diff, half, verdict]
        return (f"{show(x, digits)} vs {show(y, digits)} {unit} (difference "
                f"{scaffold.pm(cmp[0], cmp[1], '+.4g')}, Welch 95 %: {cmp[2]})")

    out = []
    for run in runs[1:]:  # every class and σ (the paper shows σ = 0.5)
        klass, st = run["klass"], run["g"].attrs["at_3cm"]
        c = run["g"]["replicate_summary"]["contacts_mean"][at3(run["amps"])]
        cmp = ef.compare_beds(c, c_ref)
        want, word = ("above", "more") if klass == "a" else ("below", "fewer")
        text = (f"**class {klass} (σ = {run['sigma']:g}) at 3 cm, wall contacts**: {fmt(c)} "
                f"grains on floor or lid on average vs {fmt(c_ref)} for the reference (difference "
                f"{scaffold.pm(cmp.diff, cmp.half, '+.2f', '.2f')}, Welch 95 %: {cmp.verdict}; "
                f"paper: {word}; {'' if cmp.verdict == want else 'not '}as the paper); per species "
                + per_species(run, st["contacts_species"]))
        if klass in "ac":
            text += ("; **wall force** (each bed's phase curve) peak "
                     + vs(st["force_peak"], st_ref["force_peak"], st["force_peak_vs_ref"], "N")
                     + ", period mean " + vs(st["force_mean"], st_ref["force_mean"],
                                             st["force_mean_vs_ref"], "N")
                     + f" (paper: {'larger' if klass == 'a' else 'smaller'})")
        if klass in "bc":
            speeds = "; ".join(f"{sp.name} " + vs(v, st_ref["vz_max"][0], cmp, "m/s", 3)
                               for sp, v, cmp in zip(run["config"].grains, st["vz_max"],
                                                     st["vz_max_vs_ref"]))
            want_v = ("both species faster than the reference" if klass == "b"
                      else "large grains like the reference, small grains faster")
            text += (f"; **largest centre-of-mass speed** (each bed's phase curve) {speeds} "
                     f"(paper: {want_v})")
        out.append(text + ".")
    seg = [f"{run['label']} {sg['S']} ({sg['sign']})" for run in runs[1:]
           for sg in [segregation_at3(run)] if sg["sign"]]
    if seg:  # paper fig. 3: "size segregation appears"
        out.append("**Size segregation at 3 cm** (index S over the analysed periods, mean ± SE "
                   "across beds; 95 % interval against 0): " + "; ".join(seg) + ". In a "
                   "well-mixed bed of unequal radii S is not exactly 0 (small centres reach "
                   "R_large − R_small closer to the floor), so a small |S| is not segregation.")
    for run in [r for r in runs[1:] if "snapshots_3cm" in r["g"].attrs]:  # fig. 3: the spread
        sn = run["g"].attrs["snapshots_3cm"]
        out.append(f"fig. 3, class a σ = {run['sigma']:g} at 3 cm, snapshots of the last "
                   "period of every bed (phase: mean height of large / small grains above the "
                   "floor, spread (std) of all heights, mean ± SE across beds): " + "; ".join(
                       f"{q / 4:.2f}T: {show(hl)} / {show(hs)} cm, spread {show(s)} cm vs "
                       f"reference {show(s_ref)} cm ({v}, Welch 95 %)"
                       for q, hl, hs, s, s_ref, v in zip(
                           sn["quarter"], sn["h_large"], sn["h_small"], sn["spread"],
                           ref["g"].attrs["snapshots_3cm"]["spread"], sn["spread_vs_ref"])) + ".")
    return out


main = scaffold.entry(__file__, __doc__, compute, options, report=report)


if __name__ == "__main__":
    main()
