"""The number of grains at equal mass (thesis §3.1, figs. 3.1–3.4, tables 3.1–3.2; issue 13
item 7), with replicates.

    python experiments/grain_number.py              # full mode (see summary.md for its wall time)
    python experiments/grain_number.py --quick      # test-sized
    python experiments/grain_number.py --from-data  # summary and figures from the stored data.h5

The thesis' §3.1 damper (``sanchez2012-sec31-n{250,500,1000}``: M = 25 kg, K = 2.62e5 N/m,
ξ = 0.058, U = 5 mm, E = 2.06e8 Pa) with 2.07 kg of steel as N = 250, 500 or 1000 grains, on a
base :data:`BASE` (the smallest at which every bed fits the 0.052 m box; the stated 0.02 m
cannot hold it), dt = :data:`DT` (thesis: 1 µs; ≤ t_c/50 at 6 m/s). ``R`` poured beds per
point, each averaged over its MSER-detected steady state (else its final 10 %; counted).

1. **Box-height scan per N** (figs. 3.1, 3.2; claims A2–A10): per bed and height, the resonant
   amplitude ``Z_res`` and, at the sample nearest the resonance, the loss split into
   collisions (normal) and friction (tangential) and the bed's motion; the optimal height is
   the vertex of a parabola in ``log Lz`` through the smallest ``Z_res``, per bed; FRF fits
   give ``M_ef``.
2. **N = 500 at Lz = 0.11 m from 5 to 22 Hz** (figs. 3.3, 3.4; claims A11, A12): the loss split
   and the bed's motion: time airborne (no grain on the floor) or on the lid, impacts per
   period (contacts closer than T/10 merged: :func:`jaxdamp.analysis.impacts.count_episodes`),
   the bed's extent against its extent at rest, the stroboscopic spread of the centre of mass.

Writes ``data.h5``, ``figure.png`` (Z_res and its loss split versus Lz), ``fig3_3_3_4.png``
(the loss split versus f, band plots) and ``summary.md``; raw sweeps in ``--out/raw``.
"""

from __future__ import annotations

import json
import math

import h5py
import numpy as np

from jaxdamp.analysis import dynamics as dyn
from jaxdamp.analysis.impacts import circular_mean, episode_onsets
from jaxdamp.analysis.impacts import count_episodes as impacts  # noqa: F401 - the study's name
from jaxdamp.analysis.response import first_harmonic, fit_frf_scan, resonances
from jaxdamp.analysis.stats import per_period, replicate_extrema, t_quantile, welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides, from_dict
from jaxdamp.figures import figure
from jaxdamp.figures.response import draw_interval, draw_replicates, draw_run_band
from jaxdamp.io.common import put
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

#: The thesis' heights [m] (SPEC §5) but 0.15 and 0.33 m (three beds of N = 1000 on two cores).
LZ_FULL = (0.052, 0.067, 0.085, 0.095, 0.11, 0.12, 0.13, 0.167, 0.265, 0.55)
LZ_RESPONSE, N_RESPONSE = 0.11, 500  # part 2
BASE, DT = 0.102, 5e-6  # [m] (Lx = Ly), [s]; see the module doc
EQUIVALENCE = 0.05  # "does not depend on N": Z_res's relative 95 % interval within ± this
APPRECIABLE = 0.10  # a loss channel with this share of the granular loss is "appreciable"
THESIS_BED = {250: 0.0512, 500: 0.0517, 1000: 0.0499}  # [m] settled bed per N, thesis tab. 3.2
COLL, FRIC = ("pp_normal", "pw_normal"), ("pp_friction", "pw_friction")
MOTION = ("airborne", "lid_touch", "free", "lid_impacts", "floor_impacts")  # bed-motion columns
BAND_PERIODS = 3  # drive periods of each band plot (fig. 3.4) kept in data.h5


def settings(quick: bool) -> dict:
    if quick:
        return dict(ns=(250, 500), lz=(0.067, 0.11, 0.265), freqs=(15.0, 16.0, 17.0),
                    resp_freqs=(5.0, 15.5), fig34=(5.0, 15.5), duration=0.3, settle=0.15, R=2,
                    record_dt=5e-4)
    # around the resonances of M + m_p (15.66 Hz) and M (16.29 Hz); part 2 with fig. 3.4's
    return dict(ns=(250, 500, 1000), lz=LZ_FULL, freqs=(14.0, 15.0, 15.5, 16.0, 16.5, 17.0, 18.0),
                resp_freqs=(5.0, 7.5, 10.5, 12.0, 13.5, 15.5, 17.0, 18.5, 19.5, 22.0),
                fig34=(5.0, 10.5, 13.5, 15.5, 18.5, 19.5), duration=2.5, settle=1.5, R=3,
                record_dt=5e-4)


def run_measures(rec: dict, f: float, t0: float, n: int) -> dict:
    """Per-run measures over ``t >= t0`` of one run's samples ``rec`` (see the module doc):
    loss per cycle by channel [J], contact and flight fractions, impacts per period, extents."""
    t = np.asarray(rec["t"])
    keep = t >= t0
    series = per_period({k: rec[k] for k in ("t", "z_box", "work")}, f, channels=COLL + FRIC)
    k0 = int(np.searchsorted(series["t_start"], t0 - 1e-12))
    loss = {c: float(np.mean(series[f"{c}_per_cycle"][k0:])) for c in COLL + FRIC}
    tk, nf, nl = t[keep], np.asarray(rec["n_floor"])[keep], np.asarray(rec["n_lid"])[keep]
    periods = max((tk[-1] - tk[0]) * f, 1e-9)
    gap = max(int(round(0.1 / (f * (t[1] - t[0])))), 1)  # samples in a tenth of a period
    extent = np.asarray(rec["z_highest"])[keep] - np.asarray(rec["z_lowest"])[keep]
    # impact phases against the box motion, and the velocities just before each impact
    _, ph_box = first_harmonic(tk, np.asarray(rec["z_box"])[keep], f)
    on_lid, on_floor = episode_onsets(nl > 0, gap), episode_onsets(nf > 0, gap)
    phase = lambda i: 2 * np.pi * f * tk[i] - ph_box  # noqa: E731
    vb, vc = np.asarray(rec["v_box"])[keep], np.asarray(rec["vz_cm"])[keep]
    before = np.maximum(np.r_[on_lid, on_floor] - 1, 0)
    zc = np.asarray(rec["z_cm"])
    sec = dyn.poincare_section(t, zc, f, t_start=t0)
    spread = (float(dyn.strobe_spread(sec, float(np.std(zc[keep])), max_period=2)[0])
              if len(sec.t) >= 4 else math.nan)
    return dict(collisional=loss["pp_normal"] + loss["pw_normal"],
                frictional=loss["pp_friction"] + loss["pw_friction"],
                airborne=float(np.mean(nf == 0)), lid_touch=float(np.mean(nl > 0)),
                free=float(np.mean((nf == 0) & (nl == 0))), wall_grains=float(np.mean(nf + nl) / n),
                lid_impacts=len(on_lid) / periods, floor_impacts=len(on_floor) / periods,
                lid_phase=circular_mean(phase(on_lid), degrees=True),
                floor_phase=circular_mean(phase(on_floor), degrees=True),
                # NaN without impacts on either wall
                lid_floor=circular_mean(phase(on_lid) - circular_mean(phase(on_floor)), True),
                opposite=float(np.mean(vb[before] * vc[before] < 0)) if before.size else math.nan,
                extent=float(np.mean(extent)), strobe_spread=spread,
                rest_extent=float(rec["z_highest"][0] - rec["z_lowest"][0]))


def _pm(x, digits=3) -> str:
    """Mean ± SE over the beds' finite values (:func:`scaffold.across`, :func:`scaffold.pm`)."""
    e = scaffold.across(x)
    return scaffold.pm(e.mean, e.se, digits)


def run_sweep(n: int, s: dict, ctx, name: str, axes: dict, **over) -> dict:
    """A batched sweep of ``n`` grains (``over`` the thesis' damper, :data:`BASE`, :data:`DT`)
    over ``axes`` (frequency first) × ``R`` beds into ``raw/name``: every run's amplitude and
    :func:`run_measures` over its steady state (else its second half)."""
    cfg = apply_overrides(presets.get(f"sanchez2012-sec31-n{n}"), {
        "box.Lx": BASE, "box.Ly": BASE, "numerics.dt": DT, "numerics.duration": s["duration"],
        "numerics.settle_time": s["settle"], "numerics.record_dt": s["record_dt"],
        "numerics.chunk": 0.1, **over})
    res = reuse_or_run(cfg, axes, ctx.raw(name), progress=ctx.progress, replicates=s["R"])
    Zr, fallback = steady_or_window(res, "amplitude")
    stationary = np.asarray(res.steady["amplitude"]["stationary"], bool)
    t0 = np.where(stationary, np.asarray(res.steady["amplitude"]["start"], float),
                  s["duration"] / 2)
    f, measures = np.asarray(res.axes["frequency"], float), {}
    for idx in np.ndindex(stationary.shape):
        row = res.point(int(np.ravel_multi_index(idx[:-1], stationary.shape[:-1])), idx[-1])
        m = run_measures({k: v[row] for k, v in res.records.items()}, f[idx[0]], t0[idx], n)
        for k, x in m.items():
            measures.setdefault(k, np.full(stationary.shape, np.nan))[idx] = x
    return dict(n=n, cfg=cfg, res=res, Zr=Zr, fallback=fallback, measures=measures,
                stationary=stationary, m_p=grain_mass(cfg), wall=float(res.summary["wall_time"]),
                balance=float(np.nanmax(np.abs(res.summary["balance_error"]))))


def scan(n: int, s: dict, ctx) -> dict:
    """Part 1 for ``n`` grains: the batched (frequency × Lz × bed) sweep and its measures."""
    sc = run_sweep(n, s, ctx, f"scan_N{n}_R{s['R']}.h5",
                   {"frequency": list(s["freqs"]), "box.Lz": list(s["lz"])})
    f, lz, R = np.asarray(s["freqs"], float), np.asarray(s["lz"], float), s["R"]
    f_res, Z_res = resonances(f, sc["Zr"])  # (L, R)
    # the loss at the frequency sample nearest each bed's resonance
    at = np.argmin(np.abs(f[:, None, None] - f_res), axis=0)[None]  # (1, L, R)
    coll, fric = (np.take_along_axis(sc["measures"][k], at, 0)[0]
                  for k in ("collisional", "frictional"))
    v = replicate_extrema(lz, Z_res, "min", log_x=True, log_y=True)
    opt = dict(vertices=v.x, estimate=v.estimate, grid_best=lz[v.best],
               interior=(v.best > 0) & (v.best < len(lz) - 1),
               # the same vertices with the parabola in Lz: the interpolation's own systematic
               linear=replicate_extrema(lz, Z_res, "min").x)
    with h5py.File(sc["res"].path, "r") as h:  # the first grid point's R beds
        bed_top, settled = (np.asarray(h[f"settle/{k}"]).reshape(-1, R)[0]
                            for k in ("bed_height", "settled"))
    rec, rows = sc["res"].records, [sc["res"].point(0, r) for r in range(R)]
    return dict(sc, f_res=f_res, Z_res=Z_res, coll=coll, fric=fric, opt=opt, bed_top=bed_top,
                fits=fit_frf_scan(f, sc["Zr"], sc["cfg"].primary, "absolute"), settled=settled,
                bed_cm=np.array([2 * (rec["z_cm"][k][0] - rec["z_box"][k][0]) for k in rows]),
                # per height, the frequency sample nearest its mean resonance
                near=[int(np.argmin(np.abs(f - np.mean(f_res[j])))) for j in range(len(lz))])


def compare(scans: dict, s: dict) -> dict:
    """Across N: optima (Welch), Z_res per height (Welch, equivalence), the crossover."""
    ns, out = sorted(scans), {"optimum": {}, "pairs": {}}
    for n, e in ((n, scans[n]["opt"]["estimate"]) for n in ns):  # the beds' vertices
        out["optimum"][n] = dict(mean=e.mean, se=e.se, ci95=e.ci95,
                                 interior=bool(scans[n]["opt"]["interior"].all()))
    for a, b in zip(ns[:-1], ns[1:]):
        d, h = welch(scans[b]["opt"]["vertices"], scans[a]["opt"]["vertices"])
        out["optimum"][f"{b}-{a}"] = dict(diff=d, ci95=h)
    for a, b in [(ns[0], ns[-1])] + list(zip(ns[:-1], ns[1:])):
        rows = []
        for L, za, zb in zip(s["lz"], scans[a]["Z_res"], scans[b]["Z_res"]):
            d, h = welch(zb, za)
            ref = float(np.mean(za))
            rows.append(dict(Lz=float(L), diff=d, ci95=h, rel=d / ref, rel_ci=h / ref,
                             sign=(0 if not np.isfinite(h) or abs(d) <= h else int(np.sign(d))),
                             equivalent=bool(np.isfinite(h) and abs(d) + h <= EQUIVALENCE * ref)))
        out["pairs"][f"{b}-{a}"] = rows
    return out


def compute(quick: bool, log, ctx):
    s = settings(quick)
    scans = {n: scan(n, s, ctx) for n in s["ns"]}
    log("optimal Lz [m]: " + ", ".join(f"N = {n}: {sc['opt']['estimate'].mean:.4f}"
                                       for n, sc in scans.items()))
    n = N_RESPONSE if N_RESPONSE in s["ns"] else max(s["ns"])  # part 2 (quick: the largest N)
    resp = run_sweep(n, s, ctx, f"response_N{n}_R{s['R']}.h5",
                     {"frequency": list(s["resp_freqs"])}, **{"box.Lz": LZ_RESPONSE})
    resp["f"] = np.asarray(s["resp_freqs"], float)
    result = dict(scans=scans, compare=compare(scans, s), response=resp, settings=s)
    return result, lambda path, prov: record(result, path, prov)


def record(result, out, prov):
    s, scans, resp = result["settings"], result["scans"], result["response"]
    prov = dict(prov, sweep_wall_s=sum(x["wall"] for x in scans.values()) + resp["wall"])
    with scaffold.data_file(out, prov, settings=json.dumps(s)) as h:
        h.attrs.update(base=BASE, dt=DT, equivalence=EQUIVALENCE)
        for n, sc in scans.items():
            g = h.create_group(f"scan/N{n}")
            g.attrs.update(base_config=sc["cfg"].to_json(), grain_mass=sc["m_p"],
                           fallback=sc["fallback"], balance_error_max=sc["balance"],
                           beds_settled=int(np.sum(sc["settled"])))
            put(g, "frequency", s["freqs"], "Hz")
            put(g, "Lz", s["lz"], "m")
            for k, u, dims in (("Zr", "m", "frequency, Lz, replicate"),
                               ("Z_res", "m", "Lz, replicate"), ("f_res", "Hz", "Lz, replicate"),
                               ("coll", "J", "Lz, replicate"), ("fric", "J", "Lz, replicate"),
                               ("stationary", "1", "frequency, Lz, replicate"),
                               ("bed_top", "m", "replicate"), ("bed_cm", "m", "replicate")):
                put(g, k, sc[k], u, dims=dims)
            g["coll"].attrs["what"] = "collisional loss per cycle (pp + pw normal) at resonance"
            g["fric"].attrs["what"] = "frictional loss per cycle (pp + pw tangential) at resonance"
            g["bed_cm"].attrs["what"] = "twice the mean height of the grain centres, settled bed"
            for k in MOTION + ("wall_grains", "strobe_spread", "lid_phase", "floor_phase",
                               "lid_floor", "opposite"):
                put(g, f"measures/{k}", sc["measures"][k], dims="frequency, Lz, replicate")
            put(g, "M_ef_reps", [x["M_reps"] for x in sc["fits"]], "kg", residuals="absolute")
            put(g, "optimum_vertices", sc["opt"]["vertices"], "m")
        g = h.create_group("response")
        g.attrs.update(base_config=resp["cfg"].to_json(), balance_error_max=resp["balance"],
                       stationary_runs=int(resp["stationary"].sum()))
        put(g, "frequency", resp["f"], "Hz")
        put(g, "amplitude", resp["Zr"], "m", dims="frequency, replicate")
        for k in ("collisional", "frictional", *MOTION, "extent", "rest_extent", "strobe_spread"):
            put(g, k, resp["measures"][k], dims="frequency, replicate")
        h.attrs["compare"] = json.dumps(result["compare"], default=float)
        res, f = resp["res"], list(resp["f"])  # fig. 3.4: bed 0's last periods at s["fig34"]
        for fq in (x for x in s["fig34"] if x in f):
            run = {k: np.asarray(v[res.point(f.index(fq), 0)]) for k, v in res.records.items()}
            keep = run["t"] >= run["t"][-1] - BAND_PERIODS / fq
            for k in ("t", "z_box", "z_lowest", "z_highest", "z_cm"):
                put(g, f"band/{fq:g}/{k}", run[k][keep], "s" if k == "t" else "m")


def report(data, out):
    s, cmp_, resp = data.attrs["settings"], data.attrs["compare"], data["response"]
    f, lz, scans = np.asarray(s["freqs"], float), np.asarray(s["lz"], float), {}
    for n in s["ns"]:  # each scan as stored, with what the report derives from it
        g = data["scan"][f"N{n}"]
        near = [int(np.argmin(np.abs(f - np.mean(x)))) for x in g["f_res"]]  # as in scan()
        scans[n] = dict(g, **g.attrs, cfg=from_dict(g.attrs["base_config"]), near=near,
                        at={k: v[near, range(len(lz))] for k, v in g["measures"].items()},
                        o=cmp_["optimum"][str(n)],
                        linear=replicate_extrema(lz, g["Z_res"], "min").x)
    fig, (a1, a2, a3) = scaffold.subplots(1, 3, figsize=(16, 4.8))
    for n, sc in scans.items():
        line = draw_replicates(a1, lz, sc["Z_res"] / sc["cfg"].primary.U, ms=4, label=f"N = {n}")
        c, tot = line[0].get_color(), sc["coll"] + sc["fric"]
        draw_interval(a1, sc["o"]["mean"], sc["o"]["ci95"], alpha=0.15, color=c)
        draw_replicates(a2, lz, tot, ms=4, color=c, label=f"N = {n}, total")
        draw_replicates(a3, lz, sc["fric"] / tot, ms=4, color=c, label=f"N = {n}")
    a3.axhline(0.5, color="0.5", lw=0.8)
    a3.set_ylim(0, 1)
    for a, ylabel, title in (
            (a1, "resonant amplitude Z_res / U [-]", f"thesis fig. 3.2(a): mean of R = {s['R']} "
             "beds ± 2 SE; band: 95 % interval of the optimum"),
            (a2, "granular loss per cycle at resonance [J]", "thesis fig. 3.2(b)"),
            (a3, "frictional share of the loss at resonance [-]", "")):
        a.set(xscale="log", xlabel="box height Lz [m]", ylabel=ylabel)
        a.set_title(title, fontsize=8)
        a.legend(fontsize=7)
    scaffold.save_figure(fig, out)

    if "band" in resp:  # fig3_3_3_4.png (files written before the band data was kept: no)
        cfg, band = from_dict(resp.attrs["base_config"]), resp["band"]
        show = [x for x in s["fig34"] if f"{x:g}" in band]
        fig = figure((2.6 * max(len(show), 3), 7.5))
        gs = fig.add_gridspec(2, max(len(show), 3), height_ratios=[1, 1.1])
        ax = fig.add_subplot(gs[0, :])
        for key, label in (("collisional", "collisions (pp + pw, normal)"),
                           ("frictional", "friction (pp + pw, tangential)")):
            draw_replicates(ax, resp["frequency"], resp[key], label=label)
        ax.set(yscale="log", xlabel="frequency f [Hz]", ylabel="loss per cycle [J]")
        ax.set_title(f"thesis fig. 3.3: N = {cfg.grains[0].count}, Lz = {cfg.box.Lz} m, mean of "
                     f"R = {s['R']} beds ± 2 SE", fontsize=9)
        ax.legend(fontsize=8)
        for c, fq in enumerate(show):
            a = fig.add_subplot(gs[1, c])
            draw_run_band(a, band[f"{fq:g}"], cfg.box.Lz, fq, BAND_PERIODS, fontsize=7)
            a.set_title(f"{fq:g} Hz (thesis fig. 3.4)", fontsize=8)
            a.tick_params(labelsize=6)
            if c:
                a.set_ylabel("")
            else:
                a.legend(fontsize=5, loc="upper left")
        scaffold.save_figure(fig, out, "fig3_3_3_4.png", dpi=110)
    _summary(data, scans, out)


def _summary(data, scans, out):
    s, resp, cmp_ = data.attrs["settings"], data["response"], data.attrs["compare"]
    R, cfg, sc0 = s["R"], from_dict(resp.attrs["base_config"]), next(iter(scans.values()))
    U, f = sc0["cfg"].primary.U, np.asarray(s["freqs"], float)
    balance = max([sc["balance_error_max"] for sc in scans.values()]
                  + [resp.attrs.get("balance_error_max", 0.0)])  # (not in older files)
    stationary = [sc["stationary"] for sc in scans.values()]
    lines = [
        *scaffold.head("The number of grains at equal mass (thesis §3.1, figs. 3.1–3.4, tables "
                       "3.1–3.2)", data.attrs, data.attrs["sweep_wall_s"]),
        f"**Runs.** Native engine; base {data.attrs['base']} × {data.attrs['base']} m, dt = "
        f"{data.attrs['dt'] * 1e6:g} µs; part 1: {len(f)} frequencies {f.min()}–{f.max()} Hz × "
        f"{len(s['lz'])} heights × **R = {R} beds** per N; part 2: N = {cfg.grains[0].count} at "
        f"Lz = {cfg.box.Lz} m, {len(resp['frequency'])} frequencies × R = {R}; "
        f"{s['duration']} s per run after settling (thesis: 8 s).", "",
        f"**Stationarity.** Part 1: {sum(int(x.sum()) for x in stationary)} of "
        f"{sum(x.size for x in stationary)} runs detected stationary ("
        + ", ".join(f"N = {n}: {int(x.sum())}/{x.size}" for n, x in zip(scans, stationary))
        + f"); part 2: {resp.attrs['stationary_runs']} of {resp['amplitude'].size}. The others "
        "use their final 10 % (amplitude) or second half (loss split, contacts).", "",
        "**Uncertainty.** ± is the standard error over the R beds; intervals are Student-t 95 % "
        f"(t = {t_quantile(0.975, max(R - 1, 1)):.2f}); differences between N are Welch 95 %; "
        f"equivalence: within ±{data.attrs['equivalence']:.0%}. Energy balance error ≤ "
        f"{balance:.1e}.", "", "## Settled beds (thesis table 3.2)", ""]
    lines += scaffold.table(
        ["N", "thesis bed [m]", "top of highest grain [m]", "2 × mean centre height [m]",
         "beds settled", "grain mass [kg]"],
        [[n, THESIS_BED.get(n, math.nan), _pm(sc["bed_top"], 4), _pm(sc["bed_cm"], 4),
          f"{sc['beds_settled']} of {len(sc['bed_top'])}", f"{sc['grain_mass']:.3f}"]
         for n, sc in scans.items()])
    lines += ["", "## Resonant amplitude versus Lz (thesis fig. 3.2a)", ""]
    lines += scaffold.table(
        ["Lz [m]"] + [f"Z_res/U, N = {n}" for n in scans] + [f"f_res [Hz], N = {n}" for n in scans],
        [[L] + [_pm(sc["Z_res"][j] / U) for sc in scans.values()]
         + [_pm(sc["f_res"][j], 4) for sc in scans.values()] for j, L in enumerate(s["lz"])])
    lines += ["", "**The optimum (smallest Z_res; parabola in log Lz per bed, mean ± SE, "
              "95 % t-interval):**", ""]
    lines += [f"- N = {n}: {scaffold.pm(sc['o']['mean'], sc['o']['se'], '.4f', '.4f', unit='m')} "
              f"(95 %: ± {sc['o']['ci95']:.4f}; beds' vertices "
              f"{', '.join(f'{x:.4f}' for x in sc['optimum_vertices'])}; "
              + ("interior to the grid in every bed" if sc["o"]["interior"]
                 else "at an end of the grid in some bed") + ")." for n, sc in scans.items()]
    lines.append("- the interval is the beds' spread only: parabolas in Lz instead put the "
                 "vertices at " + ", ".join(f"{np.mean(sc['linear']):.4f} m (N = {n})"
                                            for n, sc in scans.items())
                 + "; a difference of that size is the grid's systematic error.")
    for k, o in ((k, o) for k, o in cmp_["optimum"].items() if "-" in k):  # N = b minus N = a
        sig = np.isfinite(o["ci95"]) and abs(o["diff"]) > o["ci95"]
        lines.append("- optimum of N = {} minus N = {}: ".format(*k.split("-"))
                     + f"{scaffold.pm(o['diff'], o['ci95'], '+.4f', '.4f', unit='m')} (Welch 95 %, "
                     + ("significant" if sig else "not significant") + ").")
    lines += ["", "**Z_res between N at each height** (Welch 95 % of the difference, relative to "
              "the fewer grains; − / +: more grains give a significantly smaller / larger Z_res, "
              "n.s.: not significant; ≡: equivalent within the tolerance):", ""]
    for k, rows in cmp_["pairs"].items():
        cells = (f"{r['Lz']:g}: "
                 + scaffold.pm(r["rel"], r["rel_ci"], "+.1f", ".1f", unit="%", scale=100)
                 + f" {({0: 'n.s.', 1: '+', -1: '−'}[r['sign']])}" + " ≡" * r["equivalent"]
                 for r in rows)
        lines.append("- N = {} vs N = {}: ".format(*k.split("-")) + "; ".join(cells) + ".")
    lines += ["", "## Loss at resonance (thesis fig. 3.2b)", ""]
    lines += scaffold.table(
        ["Lz [m]"] + [f"loss/cycle [J], N = {n}" for n in scans]
        + [f"friction share, N = {n}" for n in scans],
        [[L] + [_pm(sc["coll"][j] + sc["fric"][j], 3) for sc in scans.values()]
         + [_pm(sc["fric"][j] / (sc["coll"][j] + sc["fric"][j]), 2) for sc in scans.values()]
         for j, L in enumerate(s["lz"])])
    lines += ["", "## Effective mass from the FRF fits (absolute residuals, U and K fixed)", ""]
    lines += scaffold.table(
        ["Lz [m]"] + [f"M_ef [kg], N = {n}" for n in scans],
        [[L] + [scaffold.pm(*scaffold.mean_se(sc["M_ef_reps"][j]), ".2f", ".2f")
                for sc in scans.values()] for j, L in enumerate(s["lz"])])
    lines += ["", f"M = {sc0['cfg'].primary.M} kg; M + m_p = "
              f"{sc0['cfg'].primary.M + sc0['grain_mass']:.2f} kg. Fitted within "
              f"{f.min()}–{f.max()} Hz only, M_ef is the mass that places the peak, not a fit of "
              "the whole FRF.", "", "## Bed motion in the scan (thesis fig. 3.1)", "",
              "At the frequency sample nearest the resonance; mean ± SE over beds.", ""]
    lines += scaffold.table(
        ["N", "Lz [m]", "airborne", "lid touched", "free flight", "lid impacts / period",
         "floor impacts / period", "grains on floor or lid", "strobe spread"],
        [[n, f"{L} ({f[i]:g} Hz)"] + [_pm(sc["at"][k][j], 2)
                                      for k in MOTION + ("wall_grains", "strobe_spread")]
         for n, sc in scans.items() for j, (L, i) in enumerate(zip(s["lz"], sc["near"]))])
    lines += ["", "## Impact timing (thesis ch. 6 and §4.2.4)", "",
              "At the frequency sample nearest each bed's resonance: mean phase [deg] of the lid "
              "and floor impact onsets against the box's first harmonic, their separation "
              "(180°: counter-phase; per bed, then mean ± SE), and the fraction of impacts with "
              "the centre of mass and the box moving in opposite directions just before.", ""]
    rows = []
    for n, sc in scans.items():
        at, lf = sc["at"], np.abs(sc["at"]["lid_floor"])
        rows += [[n, L, _pm(sc["Z_res"][j] / U), _pm(at["lid_phase"][j], 3),
                  _pm(at["floor_phase"][j], 3), _pm(lf[j], 3), _pm(at["opposite"][j], 2)]
                 for j, L in enumerate(s["lz"])]
        sep = np.array([float(np.nanmean(x)) for x in lf])
        j_cp = int(np.nanargmin(np.abs(sep - 180.0))) if np.isfinite(sep).any() else -1
        rows.append([n, f"smallest Z_res at {s['lz'][int(np.argmin(sc['Z_res'].mean(-1)))]} m; "
                     f"impacts nearest counter-phase at {s['lz'][j_cp] if j_cp >= 0 else 'none'} m",
                     "", "", "", "", ""])
    lines += scaffold.table(["N", "Lz [m]", "Z_res/U", "lid phase", "floor phase",
                             "abs(lid − floor) [deg]", "velocities opposite before impact"], rows)
    lines += ["", f"## Frequency response of N = {cfg.grains[0].count} at Lz = {cfg.box.Lz} m "
              "(thesis figs. 3.3, 3.4)", ""]
    col, fr, ext = resp["collisional"], resp["frictional"], resp["extent"] / resp["rest_extent"]
    lines += scaffold.table(
        ["f [Hz]", "Z/U", "collisional loss/cycle [J]", "frictional [J]", "collisional share",
         "airborne", "lid touched", "free flight", "lid impacts / period",
         "floor impacts / period", "extent / extent at rest", "strobe spread"],
        [[f"{fq:g}", _pm(resp["amplitude"][i] / cfg.primary.U), _pm(col[i]), _pm(fr[i]),
          _pm(col[i] / (col[i] + fr[i]), 2)] + [_pm(resp[k][i], 2) for k in MOTION]
         + [_pm(ext[i], 2), _pm(resp["strobe_spread"][i], 2)]
         for i, fq in enumerate(resp["frequency"])])
    lines += ["", f"'Appreciable' collisional loss: a share of at least {APPRECIABLE:.0%} of the "
              "granular loss (a stated convention; the thesis gives no number).", ""]
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
