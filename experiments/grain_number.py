"""The number of grains at equal mass (thesis §3.1, figs. 3.1–3.4, tables 3.1–3.2; issue 13
item 7), with replicates.

    python experiments/grain_number.py            # full mode (see summary.md for its wall time)
    python experiments/grain_number.py --quick    # test-sized

The thesis' §3.1 damper (``sanchez2012-sec31-n{250,500,1000}``: M = 25 kg, K = 2.62e5 N/m,
ξ = 0.058, U = 5 mm; E = 2.06e8 Pa as in the thesis) holds about 2.07 kg of steel as N = 250,
500 or 1000 grains (radii ±4 %). Two parts, every point with ``R`` independently poured beds
(seeds 0…R−1) and its steady state detected by MSER on the per-period amplitude and
dissipation (a run never detected stationary falls back to its final 10 % and is counted):

1. **Box-height scan per N** (figs. 3.1, 3.2; claims A2–A10 of the scoreboard): one batched
   sweep per N over the thesis' heights × frequencies around the resonance. Per bed and
   height, the resonant amplitude ``Z_res`` (:func:`jaxdamp.analysis.response.resonance`,
   parabola in log Z through the largest sample) and the loss per cycle split into
   collisions (normal, pp + pw) and friction (tangential, pp + pw) at the frequency sample
   nearest the resonance. The optimal height per N is the vertex of a parabola in
   ``log Lz`` through the smallest ``Z_res`` and its neighbours, per bed; the beds' vertices
   give a t-interval, and the optima of two N are compared by Welch's interval.
   ``Z_res`` of two N at one height is compared by Welch's interval of the difference; "does
   not depend on N" is judged by equivalence: the 95 % interval of the relative difference
   lies inside ±:data:`EQUIVALENCE` (a stated tolerance). FRF fits (U, K fixed, absolute
   residuals — the thesis' fit) give ``M_ef`` per height against ``M`` and ``M + m_p``.
   The settled beds' heights (top of the highest grain, and twice the centres' mean height)
   are set against the thesis' table 3.2.
2. **Frequency response of N = 500 at Lz = 0.11 m** (figs. 3.3, 3.4; claims A11, A12): the loss
   split from 5 to 22 Hz and the bed's motion at the thesis' six frequencies, measured by the
   fraction of time no grain touches the floor (the bed is airborne), the fraction of time a
   grain touches the lid, lid and floor impacts per period (episodes of contact, those closer
   than a tenth of a period merged: :func:`jaxdamp.analysis.impacts.count_episodes`), the
   bed's extent (highest minus lowest centre) against its extent at rest, and the
   stroboscopic spread of the centre of mass (0 for a period-1 orbit;
   :func:`jaxdamp.analysis.dynamics.strobe_spread`).

**Choices, recorded in every file and summary.** The base: the stated 0.02 × 0.02 m cannot
hold the bed; with 0.09 × 0.09 m (the presets' choice) our poured beds stand 0.059–0.062 m
high (top grain), so the thesis' smallest box (0.052 m) would not close. :data:`BASE` =
0.102 m is the smallest round base at which every bed fits it; the bed heights at that base are
reported against table 3.2 as a finding, not a fit. The time step: :data:`DT` = 5 µs (the
thesis: 1 µs), at most t_c/50 of the smallest grains' Hertz collision at 6 m/s relative speed
(twice the largest box speed seen near resonance); the energy balance of every run is
reported.

Writes ``data.h5``, ``figure.png`` (Z_res and its loss split versus Lz per N; the optimum's
intervals), ``fig3_3_3_4.png`` (the loss split versus f and the band plots at six frequencies)
and ``summary.md``; raw sweeps (every time series, resumable) in ``--out/raw`` (not committed).
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
from jaxdamp.config import apply_overrides
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

NS = (250, 500, 1000)
#: The thesis' heights [m] (SPEC §5) but 0.15 and 0.33 m, left out to afford three beds per
#: point for N = 1000 on two cores.
LZ_FULL = (0.052, 0.067, 0.085, 0.095, 0.11, 0.12, 0.13, 0.167, 0.265, 0.55)
#: Frequencies [Hz] around the resonances of M + m_p (15.66 Hz) and M (16.29 Hz).
F_SCAN = (14.0, 15.0, 15.5, 16.0, 16.5, 17.0, 18.0)
#: Part 2: N = 500 at Lz = 0.11 m from 5 to 22 Hz, the thesis' fig. 3.4 frequencies included.
F_RESPONSE = (5.0, 7.5, 10.5, 12.0, 13.5, 15.5, 17.0, 18.5, 19.5, 22.0)
FIG34_F = (5.0, 10.5, 13.5, 15.5, 18.5, 19.5)
LZ_RESPONSE = 0.11
N_RESPONSE = 500
BASE = 0.102  # [m], Lx = Ly; see the module doc
DT = 5e-6  # [s]
#: Equivalence tolerance for "does not depend on N": the 95 % interval of the relative
#: difference of Z_res must lie within ± this.
EQUIVALENCE = 0.05
#: A loss channel is "appreciable" when it carries at least this share of the granular loss.
APPRECIABLE = 0.10
#: The thesis' table 3.2: settled bed height [m] per N.
THESIS_BED = {250: 0.0512, 500: 0.0517, 1000: 0.0499}
COLL = ("pp_normal", "pw_normal")
FRIC = ("pp_friction", "pw_friction")
#: The bed-motion measures of :func:`run_measures` in the summary's tables.
MOTION = ("airborne", "lid_touch", "free", "lid_impacts", "floor_impacts")


def settings(quick: bool) -> dict:
    if quick:
        return dict(ns=(250, 500), lz=(0.067, 0.11, 0.265), freqs=(15.0, 16.0, 17.0),
                    resp_freqs=(5.0, 15.5), fig34=(5.0, 15.5), duration=0.3, settle=0.15, R=2,
                    record_dt=5e-4)
    return dict(ns=NS, lz=LZ_FULL, freqs=F_SCAN, resp_freqs=F_RESPONSE, fig34=FIG34_F,
                duration=2.5, settle=1.5, R=3, record_dt=5e-4)


# ------------------------------------------------------------------------------ per-run measures


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
                free=float(np.mean((nf == 0) & (nl == 0))),
                wall_grains=float(np.mean(nf + nl) / n),
                lid_impacts=len(on_lid) / periods, floor_impacts=len(on_floor) / periods,
                lid_phase=circular_mean(phase(on_lid), degrees=True),
                floor_phase=circular_mean(phase(on_floor), degrees=True),
                # NaN without impacts on either wall
                lid_floor=circular_mean(phase(on_lid) - circular_mean(phase(on_floor)), True),
                opposite=(float(np.mean(vb[before] * vc[before] < 0)) if before.size
                          else math.nan),
                extent=float(np.mean(extent)),
                rest_extent=float(rec["z_highest"][0] - rec["z_lowest"][0]),
                strobe_spread=spread)


def _pm(x, digits=3) -> str:
    """Mean ± SE over the beds' finite values (:func:`scaffold.across`, :func:`scaffold.pm`)."""
    e = scaffold.across(x)
    return scaffold.pm(e.mean, e.se, digits)


def run_sweep(n: int, s: dict, ctx, name: str, axes: dict, **over) -> dict:
    """A batched sweep of ``n`` grains (the thesis' damper on the base :data:`BASE`, time step
    :data:`DT`, and ``over``) over ``axes`` (frequency first) × ``R`` beds into
    ``raw/name`` (reused or resumed), every run's amplitude (:func:`steady_or_window`) and
    :func:`run_measures` (``{measure: grid + (R,)}``), each over its detected steady state or,
    where none was detected, the run's second half."""
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


# ------------------------------------------------------------------------------ part 1: Lz scans


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
    ns = sorted(scans)
    out = {"optimum": {}, "pairs": {}}
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


# ------------------------------------------------------------------------------ driver


def compute(quick: bool, log, ctx):
    s = settings(quick)
    scans = {}
    for n in s["ns"]:
        scans[n] = sc = scan(n, s, ctx)
        o = sc["opt"]["estimate"]
        log(f"N = {n}: optimum (smallest Z_res) {scaffold.pm(o.mean, o.ci95, '.4f', '.4f')} m "
            f"(95 %); {int(sc['stationary'].sum())}/{sc['stationary'].size} runs stationary")
    # part 2: N = 500 (or the largest quick N) at Lz = 0.11 m over resp_freqs
    n = N_RESPONSE if N_RESPONSE in s["ns"] else max(s["ns"])
    resp = run_sweep(n, s, ctx, f"response_N{n}_R{s['R']}.h5",
                     {"frequency": list(s["resp_freqs"])}, **{"box.Lz": LZ_RESPONSE})
    resp["f"] = np.asarray(s["resp_freqs"], float)
    result = dict(scans=scans, compare=compare(scans, s), response=resp, settings=s)
    return result, lambda path, prov: write(result, path, prov)


main = scaffold.entry(__file__, __doc__, compute)


def write(result, out, prov):
    s, scans, resp = result["settings"], result["scans"], result["response"]
    prov = dict(prov, sweep_wall_s=sum(x["wall"] for x in scans.values()) + resp["wall"])
    with scaffold.data_file(out, prov, settings=json.dumps(s)) as h:
        h.attrs.update(base=BASE, dt=DT, equivalence=EQUIVALENCE)
        for n, sc in scans.items():
            g = h.create_group(f"scan/N{n}")
            g.attrs.update(base_config=sc["cfg"].to_json(), grain_mass=sc["m_p"],
                           fallback=sc["fallback"], balance_error_max=sc["balance"])
            g.create_dataset("frequency", data=np.asarray(s["freqs"])).attrs["units"] = "Hz"
            g.create_dataset("Lz", data=np.asarray(s["lz"])).attrs["units"] = "m"
            for k, u, dims in (("Zr", "m", "frequency, Lz, replicate"),
                               ("Z_res", "m", "Lz, replicate"), ("f_res", "Hz", "Lz, replicate"),
                               ("coll", "J", "Lz, replicate"), ("fric", "J", "Lz, replicate"),
                               ("stationary", "1", "frequency, Lz, replicate"),
                               ("bed_top", "m", "replicate"), ("bed_cm", "m", "replicate")):
                g.create_dataset(k, data=np.asarray(sc[k])).attrs.update(units=u, dims=dims)
            g["coll"].attrs["what"] = "collisional loss per cycle (pp + pw normal) at resonance"
            g["fric"].attrs["what"] = "frictional loss per cycle (pp + pw tangential) at resonance"
            g["bed_cm"].attrs["what"] = "twice the mean height of the grain centres, settled bed"
            for k in MOTION + ("wall_grains", "strobe_spread", "lid_phase", "floor_phase",
                               "lid_floor", "opposite"):
                g.create_dataset(f"measures/{k}", data=sc["measures"][k]).attrs[
                    "dims"] = "frequency, Lz, replicate"
            g.create_dataset("M_ef_reps", data=np.array([x["M_reps"] for x in sc["fits"]])
                             ).attrs.update(units="kg", residuals="absolute")
            g.create_dataset("optimum_vertices", data=sc["opt"]["vertices"]).attrs["units"] = "m"
        g = h.create_group("response")
        g.attrs["base_config"] = resp["cfg"].to_json()
        g.create_dataset("frequency", data=resp["f"]).attrs["units"] = "Hz"
        g.create_dataset("amplitude", data=resp["Zr"]).attrs.update(units="m",
                                                                     dims="frequency, replicate")
        for k in ("collisional", "frictional") + MOTION + ("extent", "rest_extent",
                                                           "strobe_spread"):
            g.create_dataset(k, data=resp["measures"][k]).attrs["dims"] = "frequency, replicate"
        h.attrs["compare"] = json.dumps(result["compare"], default=float)
    _figure(result, out)
    _figure_response(result, out)
    _summary(result, out, prov)


def _figure(result, out):
    from jaxdamp.figures.response import draw_interval, draw_replicates

    s, scans = result["settings"], result["scans"]
    lz = np.asarray(s["lz"], float)
    fig, (a1, a2, a3) = scaffold.subplots(1, 3, figsize=(16, 4.8))
    for n, sc in scans.items():
        line = draw_replicates(a1, lz, sc["Z_res"] / sc["cfg"].primary.U, ms=4, label=f"N = {n}")
        c, o, tot = line[0].get_color(), result["compare"]["optimum"][n], sc["coll"] + sc["fric"]
        draw_interval(a1, o["mean"], o["ci95"], alpha=0.15, color=c)
        draw_replicates(a2, lz, tot, ms=4, color=c, label=f"N = {n}, total")
        draw_replicates(a3, lz, sc["fric"] / tot, ms=4, color=c, label=f"N = {n}")
    a1.set_ylabel("resonant amplitude Z_res / U [-]")
    a1.set_title(f"thesis fig. 3.2(a): mean of R = {s['R']} beds ± 2 SE; band: 95 % interval of "
                 "the optimum", fontsize=8)
    a2.set_ylabel("granular loss per cycle at resonance [J]")
    a2.set_title("thesis fig. 3.2(b)", fontsize=8)
    a3.axhline(0.5, color="0.5", lw=0.8)
    a3.set_ylabel("frictional share of the loss at resonance [-]")
    a3.set_ylim(0, 1)
    for a in (a1, a2, a3):
        a.set(xscale="log", xlabel="box height Lz [m]")
        a.legend(fontsize=7)
    scaffold.save_figure(fig, out)


def _figure_response(result, out):
    from jaxdamp.figures import figure
    from jaxdamp.figures.response import draw_replicates, draw_run_band

    s, resp = result["settings"], result["response"]
    res, f = resp["res"], resp["f"]
    show = [x for x in s["fig34"] if x in list(f)]
    ncol = max(len(show), 3)
    fig = figure((2.6 * ncol, 7.5))
    gs = fig.add_gridspec(2, ncol, height_ratios=[1, 1.1])
    ax = fig.add_subplot(gs[0, :])
    for key, label in (("collisional", "collisions (pp + pw, normal)"),
                       ("frictional", "friction (pp + pw, tangential)")):
        draw_replicates(ax, f, resp["measures"][key], label=label)
    ax.set(yscale="log", xlabel="frequency f [Hz]", ylabel="loss per cycle [J]")
    ax.set_title(f"thesis fig. 3.3: N = {resp['n']}, Lz = {LZ_RESPONSE} m, mean of R = "
                 f"{s['R']} beds ± 2 SE", fontsize=9)
    ax.legend(fontsize=8)
    for c, fq in enumerate(show):
        a = fig.add_subplot(gs[1, c])
        run = {k: v[res.point(list(f).index(fq), 0)] for k, v in res.records.items()}
        draw_run_band(a, run, LZ_RESPONSE, fq, fontsize=7)
        a.set_title(f"{fq:g} Hz (thesis fig. 3.4)", fontsize=8)
        a.tick_params(labelsize=6)
        if c:
            a.set_ylabel("")
        else:
            a.legend(fontsize=5, loc="upper left")
    scaffold.save_figure(fig, out, "fig3_3_3_4.png", dpi=110)


def _summary(result, out, prov):
    s, scans, cmp_, resp = (result[k] for k in ("settings", "scans", "compare", "response"))
    R, sc0 = s["R"], next(iter(scans.values()))
    n_st = sum(int(sc["stationary"].sum()) for sc in scans.values())
    n_runs = sum(sc["stationary"].size for sc in scans.values())
    lines = [
        "# The number of grains at equal mass (thesis §3.1, figs. 3.1–3.4, tables 3.1–3.2)", "",
        scaffold.provenance_line(prov, prov["sweep_wall_s"]) + " Native engine. Data "
        "`data.h5`; figures `figure.png`, `fig3_3_3_4.png`.", "",
        f"**Runs.** `sanchez2012-sec31-n{{250,500,1000}}` (M = 25 kg, K = 2.62e5 N/m, "
        f"ξ = 0.058, U = 5 mm, E = 2.06e8 Pa as in the thesis), base {BASE} × {BASE} m, "
        f"dt = {DT * 1e6:g} µs (thesis: 1 µs); part 1: {len(s['freqs'])} frequencies "
        f"{min(s['freqs'])}–{max(s['freqs'])} Hz × {len(s['lz'])} heights × "
        f"**R = {R} independently poured beds** (seeds 0…{R - 1}) per N; part 2: N = "
        f"{resp['n']} at Lz = {LZ_RESPONSE} m, {len(resp['f'])} frequencies × R = {R}; "
        f"{s['duration']} s simulated per run after settling (thesis: 8 s).", "",
        f"**Stationarity.** Every run is averaged over its steady state detected by MSER on the "
        f"per-period amplitude and dissipation: part 1, {n_st} of {n_runs} runs detected "
        f"stationary ("
        + ", ".join(f"N = {n}: {int(sc['stationary'].sum())}/{sc['stationary'].size}"
                    for n, sc in scans.items())
        + f"); part 2, {int(resp['stationary'].sum())} of {resp['stationary'].size}. The others "
        "use their final 10 % (amplitude) or second half (loss split, contacts).", "",
        "**Uncertainty.** ± is the standard error over the R beds; intervals are Student-t 95 % "
        f"(t = {t_quantile(0.975, max(R - 1, 1)):.2f}); differences between N are Welch 95 %. "
        f"Equivalence ('does not depend on N') means the 95 % interval of the relative "
        f"difference lies within ±{EQUIVALENCE:.0%}. Energy balance error ≤ "
        f"{max(max(sc['balance'] for sc in scans.values()), resp['balance']):.1e}.", "",
        "## Settled beds (thesis table 3.2)", ""]
    lines += scaffold.table(
        ["N", "thesis bed [m]", "top of highest grain [m]", "2 × mean centre height [m]",
         "beds settled", "grain mass [kg]"],
        [[n, THESIS_BED.get(n, math.nan), _pm(sc["bed_top"], 4), _pm(sc["bed_cm"], 4),
          f"{int(np.sum(sc['settled']))} of {len(sc['settled'])}", f"{sc['m_p']:.3f}"]
         for n, sc in scans.items()])
    U = sc0["cfg"].primary.U
    lines += ["", "## Resonant amplitude versus Lz (thesis fig. 3.2a)", ""]
    lines += scaffold.table(
        ["Lz [m]"] + [f"Z_res/U, N = {n}" for n in scans] + [f"f_res [Hz], N = {n}" for n in scans],
        [[L] + [_pm(sc["Z_res"][j] / U) for sc in scans.values()]
         + [_pm(sc["f_res"][j], 4) for sc in scans.values()] for j, L in enumerate(s["lz"])])
    lines += ["", "**The optimum (smallest Z_res; parabola in log Lz per bed, mean ± SE, "
              "95 % t-interval):**", ""]
    for n, o in ((n, cmp_["optimum"][n]) for n in scans):
        lines.append(f"- N = {n}: {scaffold.pm(o['mean'], o['se'], '.4f', '.4f', unit='m')} "
                     f"(95 %: ± {o['ci95']:.4f}; beds' vertices "
                     f"{', '.join(f'{x:.4f}' for x in scans[n]['opt']['vertices'])}; "
                     + ("interior to the grid in every bed" if o["interior"]
                        else "at an end of the grid in some bed") + ").")
    lines.append("- the interval is the beds' spread only: the same parabolas in Lz instead of "
                 "log Lz put the vertices at " + ", ".join(
                     f"{np.mean(sc['opt']['linear']):.4f} m (N = {n})"
                     for n, sc in scans.items())
                 + "; a difference of that size is the grid's systematic error (0.15 and 0.33 m "
                 "of the thesis' grid were left out).")
    for k, o in cmp_["optimum"].items():
        if isinstance(k, str):
            verdict = ("significant" if np.isfinite(o["ci95"]) and abs(o["diff"]) > o["ci95"]
                       else "not significant")
            lines.append(f"- optimum of N = {k.split('-')[0]} minus N = {k.split('-')[1]}: "
                         f"{scaffold.pm(o['diff'], o['ci95'], '+.4f', '.4f', unit='m')} "
                         f"(Welch 95 %, {verdict}).")
    lines += ["", "**Z_res between N at each height** (Welch 95 % of the difference, relative to "
              "the fewer grains; − / + : more grains give a significantly smaller / larger "
              "resonant amplitude, n.s.: not significant; ≡ : equivalent within the "
              "tolerance):", ""]
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
        [[L] + [scaffold.pm(sc["fits"][j]["M_ef"], sc["fits"][j]["se_M"], ".2f", ".2f")
                for sc in scans.values()] for j, L in enumerate(s["lz"])])
    lines += ["", f"M = {sc0['cfg'].primary.M} kg; M + m_p = "
              f"{sc0['cfg'].primary.M + sc0['m_p']:.2f} kg. The fit uses {len(s['freqs'])} "
              f"frequencies within {min(s['freqs'])}–{max(s['freqs'])} Hz only (around the "
              "resonance), so M_ef is the mass that places the peak, not a fit of the whole FRF.",
              ""]
    lines += ["## Bed motion in the scan (thesis fig. 3.1)", "",
              "At the frequency sample nearest the resonance, per N and height: fraction of time "
              "no grain touches the floor (airborne), fraction of time a grain touches the lid, "
              "fraction of time no grain touches floor or lid (free flight), "
              "lid and floor impacts per period, mean fraction of grains touching floor or lid, "
              "stroboscopic spread of z_cm (mean ± SE over beds).", ""]
    f = np.asarray(s["freqs"], float)
    lines += scaffold.table(
        ["N", "Lz [m]", "airborne", "lid touched", "free flight", "lid impacts / period",
         "floor impacts / period", "grains on floor or lid", "strobe spread"],
        [[n, f"{L} ({f[i]:g} Hz)"] + [_pm(sc["measures"][k][i, j], 2)
                                      for k in MOTION + ("wall_grains", "strobe_spread")]
         for n, sc in scans.items() for j, (L, i) in enumerate(zip(s["lz"], sc["near"]))])
    lines += ["", "## Impact timing (thesis ch. 6 and §4.2.4)", "",
              "At the frequency sample nearest each bed's resonance: mean phase of the lid and "
              "floor impacts (episode onsets) against the box's first harmonic [deg], their "
              "separation |lid − floor| (180°: counter-phase; per bed, then mean ± SE), and the "
              "fraction of impacts at which the centre of mass and the box move in opposite "
              "directions just before (the sample before the onset).", "",
              "| N | Lz [m] | Z_res/U | lid phase | floor phase | abs(lid − floor) [deg] | "
              "velocities opposite before impact |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for n, sc in scans.items():
        U, ms, sep = sc["cfg"].primary.U, sc["measures"], []
        for j, (L, i) in enumerate(zip(s["lz"], sc["near"])):
            lf = np.abs(ms["lid_floor"][i, j])
            sep.append(float(np.nanmean(lf)))
            lines.append(f"| {n} | {L} | {_pm(sc['Z_res'][j] / U)} | "
                         f"{_pm(ms['lid_phase'][i, j], 3)} | {_pm(ms['floor_phase'][i, j], 3)} | "
                         f"{_pm(lf, 3)} | {_pm(ms['opposite'][i, j], 2)} |")
        j_best = int(np.argmin(sc["Z_res"].mean(-1)))
        sep = np.asarray(sep)
        j_cp = int(np.nanargmin(np.abs(sep - 180.0))) if np.isfinite(sep).any() else -1
        sc["timing"] = dict(best_lz=float(s["lz"][j_best]),
                            counterphase_lz=float(s["lz"][j_cp]) if j_cp >= 0 else math.nan)
        lines.append(f"| {n} | smallest Z_res at {s['lz'][j_best]} m; impacts nearest "
                     f"counter-phase at {s['lz'][j_cp] if j_cp >= 0 else 'none'} m | | | | | |")
    lines += ["", f"## Frequency response of N = {resp['n']} at Lz = {LZ_RESPONSE} m "
              "(thesis figs. 3.3, 3.4)", ""]
    ms, U = resp["measures"], resp["cfg"].primary.U
    col, fr, ext = ms["collisional"], ms["frictional"], ms["extent"] / ms["rest_extent"]
    lines += scaffold.table(
        ["f [Hz]", "Z/U", "collisional loss/cycle [J]", "frictional [J]", "collisional share",
         "airborne", "lid touched", "free flight", "lid impacts / period",
         "floor impacts / period", "extent / extent at rest", "strobe spread"],
        [[f"{fq:g}", _pm(resp["Zr"][i] / U), _pm(col[i]), _pm(fr[i]),
          _pm(col[i] / (col[i] + fr[i]), 2)] + [_pm(ms[k][i], 2) for k in MOTION]
         + [_pm(ext[i], 2), _pm(ms["strobe_spread"][i], 2)] for i, fq in enumerate(resp["f"])])
    lines += ["", f"'Appreciable' collisional loss: a share of at least {APPRECIABLE:.0%} of the "
              "granular loss (a stated convention; the thesis gives no number).", ""]
    scaffold.write_summary(out, lines)


if __name__ == "__main__":
    main()
