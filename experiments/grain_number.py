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
   grain touches the lid, lid and floor impacts per period (:func:`impacts`: episodes of
   contact, those closer than a tenth of a period merged), the bed's
   extent (highest minus lowest centre) against its extent at rest, and the stroboscopic
   spread of the centre of mass (0 for a period-1 orbit; :func:`jaxdamp.analysis.dynamics.
   strobe_spread`).

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
from jaxdamp.analysis.response import (
    first_harmonic,
    fit_frf_replicates,
    parabolic_extremum,
    resonance,
)
from jaxdamp.analysis.stats import per_period, t_quantile, welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

try:
    from . import scaffold
except ImportError:  # run as a file: python experiments/<name>.py
    import scaffold

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


def settings(quick: bool) -> dict:
    if quick:
        return dict(ns=(250, 500), lz=(0.067, 0.11, 0.265), freqs=(15.0, 16.0, 17.0),
                    resp_freqs=(5.0, 15.5), fig34=(5.0, 15.5), duration=0.3, settle=0.15, R=2,
                    record_dt=5e-4)
    return dict(ns=NS, lz=LZ_FULL, freqs=F_SCAN, resp_freqs=F_RESPONSE, fig34=FIG34_F,
                duration=2.5, settle=1.5, R=3, record_dt=5e-4)


def base_config(n: int, s: dict, **over):
    return apply_overrides(presets.get(f"sanchez2012-sec31-n{n}"), {
        "box.Lx": BASE, "box.Ly": BASE, "numerics.dt": DT, "numerics.duration": s["duration"],
        "numerics.settle_time": s["settle"], "numerics.record_dt": s["record_dt"],
        "numerics.chunk": 0.1, **over})


# ------------------------------------------------------------------------------ per-run measures


def steady_start(res, g: int, r: int, duration: float) -> tuple[float, bool]:
    """Start [s] of the window a run is averaged over: its detected steady state, or the
    second half of the run where none was detected; and whether it was detected."""
    st = res.steady["amplitude"]
    start = np.asarray(st["start"]).reshape(-1, res.replicates)[g, r]
    ok = bool(np.asarray(st["stationary"]).reshape(-1, res.replicates)[g, r])
    return (float(start) if ok and np.isfinite(start) else duration / 2), ok


def run_measures(rec: dict, f: float, t0: float, n: int) -> dict:
    """Per-run measures over ``t >= t0`` of one run's samples ``rec`` (see the module doc):
    loss per cycle by channel [J], contact and flight fractions, impacts per period, extents."""
    t = np.asarray(rec["t"])
    keep = t >= t0
    series = per_period({k: rec[k] for k in ("t", "z_box", "work")}, f, channels=COLL + FRIC)
    k0 = int(np.searchsorted(series["t_start"], t0 - 1e-12))
    loss = {c: float(np.mean(series[f"{c}_per_cycle"][k0:])) for c in COLL + FRIC}
    nf = np.asarray(rec["n_floor"])[keep]
    nl = np.asarray(rec["n_lid"])[keep]
    periods = max((t[keep][-1] - t[keep][0]) * f, 1e-9)
    gap = max(int(round(0.1 / (f * (t[1] - t[0])))), 1)  # samples in a tenth of a period
    extent = np.asarray(rec["z_highest"])[keep] - np.asarray(rec["z_lowest"])[keep]
    # impact phases against the box motion, and the velocities just before each impact
    tk = t[keep]
    _, ph_box = first_harmonic(tk, np.asarray(rec["z_box"])[keep], f)
    on_lid = impact_onsets(nl > 0, gap)
    on_floor = impact_onsets(nf > 0, gap)
    phase = lambda i: 2 * np.pi * f * tk[i] - ph_box  # noqa: E731
    vb = np.asarray(rec["v_box"])[keep]
    vc = np.asarray(rec["vz_cm"])[keep]
    before = np.maximum(np.r_[on_lid, on_floor] - 1, 0)
    zc = np.asarray(rec["z_cm"])
    sec = dyn.poincare_section(t, zc, f, t_start=t0)
    spread = (float(dyn.strobe_spread(sec, float(np.std(zc[keep])), max_period=2)[0])
              if len(sec.t) >= 4 else math.nan)
    return dict(loss=loss, collisional=loss["pp_normal"] + loss["pw_normal"],
                frictional=loss["pp_friction"] + loss["pw_friction"],
                airborne=float(np.mean(nf == 0)), lid_touch=float(np.mean(nl > 0)),
                free=float(np.mean((nf == 0) & (nl == 0))),
                wall_grains=float(np.mean(nf + nl) / n),
                lid_impacts=impacts(nl > 0, gap) / periods,
                floor_impacts=impacts(nf > 0, gap) / periods,
                lid_phase=circular_mean_deg(phase(on_lid)),
                floor_phase=circular_mean_deg(phase(on_floor)),
                lid_floor=(circular_mean_deg(phase(on_lid) - circular_mean_rad(phase(on_floor)))
                           if on_lid.size and on_floor.size else math.nan),
                opposite=(float(np.mean(vb[before] * vc[before] < 0)) if before.size
                          else math.nan),
                extent=float(np.mean(extent)),
                rest_extent=float(rec["z_highest"][0] - rec["z_lowest"][0]),
                strobe_spread=spread)


def impact_onsets(touching, gap: int) -> np.ndarray:
    """Sample indices where contact episodes start (see :func:`impacts`)."""
    idx = np.flatnonzero(touching)
    if idx.size == 0:
        return idx
    return idx[np.r_[True, np.diff(idx) > gap]]


def impacts(touching, gap: int) -> int:
    """Number of contact episodes in a sampled boolean series (a wall touched by any grain):
    runs of ``True`` samples, two runs closer than ``gap`` samples counted as one (a bed
    landing is many grain contacts within a short time; ``gap`` merges them into one impact).
    A series touching from its first sample counts that episode too.

    >>> impacts(np.array([0, 1, 1, 0, 1, 0, 0, 0, 0, 1], bool), gap=2)
    2
    """
    return len(impact_onsets(touching, gap))


def circular_mean_rad(angles) -> float:
    """Circular mean [rad] of angles [rad]."""
    return float(np.angle(np.mean(np.exp(1j * np.asarray(angles, float)))))


def circular_mean_deg(angles) -> float:
    """Circular mean [deg] of angles [rad] (NaN for none)."""
    a = np.asarray(angles, float)
    return float(np.degrees(np.angle(np.mean(np.exp(1j * a))))) if a.size else math.nan


def _pm(x, digits=3) -> str:
    """Mean ± SE over the beds' finite values (:func:`scaffold.across`, :func:`scaffold.pm`)."""
    e = scaffold.across(x)
    return scaffold.pm(e.mean, e.se, digits)


# ------------------------------------------------------------------------------ part 1: Lz scans


def scan(n: int, s: dict, ctx) -> dict:
    """Part 1 for ``n`` grains: the batched (frequency × Lz × bed) sweep and its measures."""
    cfg = base_config(n, s)
    res = reuse_or_run(cfg, {"frequency": list(s["freqs"]), "box.Lz": list(s["lz"])},
                       ctx.raw(f"scan_N{n}_R{s['R']}.h5"), progress=ctx.progress,
                       replicates=s["R"])
    f = np.asarray(s["freqs"], float)
    lz = np.asarray(s["lz"], float)
    F, L, R = len(f), len(lz), s["R"]
    Zr, fallback = steady_or_window(res, "amplitude")  # (F, L, R)
    peaks = np.array([[resonance(f, Zr[:, j, r]) for r in range(R)] for j in range(L)])
    f_res, Z_res = peaks[..., 0], peaks[..., 1]  # (L, R)
    measures = [[[None] * R for _ in range(L)] for _ in range(F)]
    stationary = np.zeros((F, L, R), bool)
    for i in range(F):
        for j in range(L):
            for r in range(R):
                g = i * L + j
                t0, ok = steady_start(res, g, r, s["duration"])
                stationary[i, j, r] = ok
                row = res.point(g, r)
                measures[i][j][r] = run_measures({k: v[row] for k, v in res.records.items()},
                                                 f[i], t0, n)
    # the loss at the frequency sample nearest each bed's resonance
    at_res = [[measures[int(np.argmin(np.abs(f - f_res[j, r])))][j][r] for r in range(R)]
              for j in range(L)]
    coll = np.array([[m["collisional"] for m in row] for row in at_res])  # (L, R)
    fric = np.array([[m["frictional"] for m in row] for row in at_res])
    p = cfg.primary
    fits = [fit_frf_replicates(f, Zr[:, j], p.U, p.K, M0=p.M, C0=max(p.C, 1.0),
                               residuals="absolute") for j in range(L)]
    v = [parabolic_extremum(np.log(lz), np.log(Z_res[:, r]), "min") for r in range(R)]
    opt = dict(vertices=np.exp([x[0] for x in v]), grid_best=np.array([lz[x[2]] for x in v]),
               interior=np.array([0 < x[2] < L - 1 for x in v]),
               # the same vertices with the parabola in Lz: the interpolation's own systematic
               linear=np.array([parabolic_extremum(lz, Z_res[:, r], "min")[0]
                                for r in range(R)]))
    with h5py.File(res.path, "r") as h:
        bed_top = np.asarray(h["settle/bed_height"]).reshape(F * L, R)[0]
        settled = np.asarray(h["settle/settled"]).reshape(F * L, R)[0]
    rows = [res.point(j, r) for j in range(1) for r in range(R)]  # first point: one per bed
    bed_cm = np.array([2 * (res.records["z_cm"][k][0] - res.records["z_box"][k][0])
                       for k in rows])
    bal = float(np.nanmax(np.abs(res.summary["balance_error"])))
    return dict(n=n, cfg=cfg, res=res, Zr=Zr, fallback=fallback, f_res=f_res, Z_res=Z_res,
                coll=coll, fric=fric, measures=measures, stationary=stationary, fits=fits,
                opt=opt, bed_top=bed_top, bed_cm=bed_cm, settled=settled, balance=bal,
                m_p=grain_mass(cfg), wall=float(res.summary["wall_time"]))


def compare(scans: dict, s: dict) -> dict:
    """Across N: optima (Welch), Z_res per height (Welch, equivalence), the crossover."""
    ns = sorted(scans)
    lz = np.asarray(s["lz"], float)
    out = {"optimum": {}, "pairs": {}}
    for n in ns:
        e = scaffold.across(scans[n]["opt"]["vertices"])
        out["optimum"][n] = dict(mean=e.mean, se=e.se, ci95=e.ci95,
                                 interior=bool(scans[n]["opt"]["interior"].all()))
    for a, b in zip(ns[:-1], ns[1:]):
        d, h = welch(scans[b]["opt"]["vertices"], scans[a]["opt"]["vertices"])
        out["optimum"][f"{b}-{a}"] = dict(diff=d, ci95=h)
    for a, b in [(ns[0], ns[-1])] + list(zip(ns[:-1], ns[1:])):
        rows = []
        for j, L in enumerate(lz):
            za, zb = scans[a]["Z_res"][j], scans[b]["Z_res"][j]
            d, h = welch(zb, za)
            ref = float(np.mean(za))
            rows.append(dict(Lz=float(L), diff=d, ci95=h, rel=d / ref, rel_ci=h / ref,
                             sign=(0 if not np.isfinite(h) or abs(d) <= h else int(np.sign(d))),
                             equivalent=bool(np.isfinite(h) and abs(d) + h <= EQUIVALENCE * ref)))
        out["pairs"][f"{b}-{a}"] = rows
    return out


# ------------------------------------------------------------------------------ part 2: f response


def response(s: dict, ctx) -> dict:
    """Part 2: N = 500 (or the largest quick N) at Lz = 0.11 m over ``resp_freqs``."""
    n = N_RESPONSE if N_RESPONSE in s["ns"] else max(s["ns"])
    cfg = base_config(n, s, **{"box.Lz": LZ_RESPONSE})
    res = reuse_or_run(cfg, {"frequency": list(s["resp_freqs"])},
                       ctx.raw(f"response_N{n}_R{s['R']}.h5"), progress=ctx.progress,
                       replicates=s["R"])
    f = np.asarray(s["resp_freqs"], float)
    R = s["R"]
    measures, stationary = [], np.zeros((len(f), R), bool)
    for i in range(len(f)):
        row = []
        for r in range(R):
            t0, ok = steady_start(res, i, r, s["duration"])
            stationary[i, r] = ok
            k = res.point(i, r)
            row.append(run_measures({kk: v[k] for kk, v in res.records.items()}, f[i], t0, n))
        measures.append(row)
    Zr, fallback = steady_or_window(res, "amplitude")
    return dict(n=n, cfg=cfg, res=res, f=f, measures=measures, stationary=stationary, Zr=Zr,
                fallback=fallback, balance=float(np.nanmax(np.abs(res.summary["balance_error"]))),
                wall=float(res.summary["wall_time"]))


def _arr(measures, key):
    """A measure of every run as an array (grid shape of ``measures`` + (R,))."""
    return np.array(measures_map(measures, lambda m: m[key]), float)


def measures_map(x, fn):
    return [measures_map(y, fn) for y in x] if isinstance(x, list) else fn(x)


# ------------------------------------------------------------------------------ driver


def compute(quick: bool, log, ctx):
    s = settings(quick)
    scans = {}
    for n in s["ns"]:
        scans[n] = scan(n, s, ctx)
        o = scaffold.across(scans[n]["opt"]["vertices"])
        log(f"N = {n}: optimum (smallest Z_res) {scaffold.pm(o.mean, o.ci95, '.4f', '.4f')} m "
            "(95 %); "
            f"{int(scans[n]['stationary'].sum())}/{scans[n]['stationary'].size} runs stationary")
    cmp_ = compare(scans, s)
    resp = response(s, ctx)
    result = dict(scans=scans, compare=cmp_, response=resp, settings=s)
    return result, lambda path, prov: write(result, path, prov)


def main(argv=None):
    return scaffold.main(__doc__, "grain_number", argv, compute)


def write(result, out, prov):
    s, scans, resp = result["settings"], result["scans"], result["response"]
    wall = sum(x["wall"] for x in scans.values()) + resp["wall"]
    prov = dict(prov, sweep_wall_s=wall)
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
            for k in ("airborne", "lid_touch", "free", "wall_grains", "lid_impacts",
                      "floor_impacts", "strobe_spread", "lid_phase", "floor_phase", "lid_floor",
                      "opposite"):
                g.create_dataset(f"measures/{k}", data=_arr(sc["measures"], k)).attrs[
                    "dims"] = "frequency, Lz, replicate"
            g.create_dataset("M_ef_reps", data=np.array([x["M_reps"] for x in sc["fits"]])
                             ).attrs.update(units="kg", residuals="absolute")
            g.create_dataset("optimum_vertices", data=sc["opt"]["vertices"]).attrs["units"] = "m"
        g = h.create_group("response")
        g.attrs["base_config"] = resp["cfg"].to_json()
        g.create_dataset("frequency", data=resp["f"]).attrs["units"] = "Hz"
        g.create_dataset("amplitude", data=resp["Zr"]).attrs.update(units="m",
                                                                     dims="frequency, replicate")
        for k in ("collisional", "frictional", "airborne", "lid_touch", "free", "lid_impacts",
                  "floor_impacts", "extent", "rest_extent", "strobe_spread"):
            g.create_dataset(k, data=_arr(resp["measures"], k)).attrs["dims"] = (
                "frequency, replicate")
        h.attrs["compare"] = json.dumps(result["compare"], default=float)
    _figure(result, out)
    _figure_response(result, out)
    _summary(result, out, prov)


def _se2(x):
    """Twice the standard error over the beds (the last axis): the figures' error bars."""
    return 2 * scaffold.standard_error(x)


def _figure(result, out):
    s, scans = result["settings"], result["scans"]
    lz = np.asarray(s["lz"], float)
    R = s["R"]
    fig, (a1, a2, a3) = scaffold.subplots(1, 3, figsize=(16, 4.8))
    for n, sc in scans.items():
        U = sc["cfg"].primary.U
        line = a1.errorbar(lz, sc["Z_res"].mean(-1) / U, yerr=_se2(sc["Z_res"] / U), fmt="o-",
                           capsize=3, ms=4, label=f"N = {n}")
        o = result["compare"]["optimum"][n]
        if np.isfinite(o["ci95"]):
            a1.axvspan(o["mean"] - o["ci95"], o["mean"] + o["ci95"], alpha=0.15,
                       color=line[0].get_color())
        tot = sc["coll"] + sc["fric"]
        a2.errorbar(lz, tot.mean(-1), yerr=_se2(tot), fmt="o-", capsize=3, ms=4,
                    color=line[0].get_color(), label=f"N = {n}, total")
        share = sc["fric"] / tot
        a3.errorbar(lz, share.mean(-1), yerr=_se2(share), fmt="o-", capsize=3, ms=4,
                    color=line[0].get_color(), label=f"N = {n}")
    a1.set_ylabel("resonant amplitude Z_res / U [-]")
    a1.set_title(f"thesis fig. 3.2(a): mean of R = {R} beds ± 2 SE; band: 95 % interval of "
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
    from jaxdamp.figures import draw_band, figure

    s, resp = result["settings"], result["response"]
    res, f, R = resp["res"], resp["f"], s["R"]
    show = [x for x in s["fig34"] if x in list(f)]
    ncol = max(len(show), 3)
    fig = figure((2.6 * ncol, 7.5))
    gs = fig.add_gridspec(2, ncol, height_ratios=[1, 1.1])
    ax = fig.add_subplot(gs[0, :])
    for key, label in (("collisional", "collisions (pp + pw, normal)"),
                       ("frictional", "friction (pp + pw, tangential)")):
        x = _arr(resp["measures"], key)
        ax.errorbar(f, x.mean(-1), yerr=_se2(x), fmt="o-", capsize=3, label=label)
    ax.set(yscale="log", xlabel="frequency f [Hz]", ylabel="loss per cycle [J]")
    ax.set_title(f"thesis fig. 3.3: N = {resp['n']}, Lz = {LZ_RESPONSE} m, mean of R = {R} beds "
                 "± 2 SE", fontsize=9)
    ax.legend(fontsize=8)
    rec = res.records
    for c, fq in enumerate(show):
        i = list(f).index(fq)
        row = res.point(i, 0)
        t = rec["t"][row]
        m = t >= t[-1] - 3 / fq
        a = fig.add_subplot(gs[1, c])
        draw_band(a, t[m], rec["z_box"][row][m], rec["z_lowest"][row][m],
                  rec["z_highest"][row][m], rec["z_cm"][row][m], LZ_RESPONSE, fontsize=7)
        a.set_title(f"{fq:g} Hz (thesis fig. 3.4)", fontsize=8)
        a.tick_params(labelsize=6)
        if c:
            a.set_ylabel("")
        else:
            a.legend(fontsize=5, loc="upper left")
    scaffold.save_figure(fig, out, "fig3_3_3_4.png", dpi=110)


def _summary(result, out, prov):
    s, scans, cmp_, resp = (result[k] for k in ("settings", "scans", "compare", "response"))
    R = s["R"]
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
    U = next(iter(scans.values()))["cfg"].primary.U
    lines += ["", "## Resonant amplitude versus Lz (thesis fig. 3.2a)", ""]
    lines += scaffold.table(
        ["Lz [m]"] + [f"Z_res/U, N = {n}" for n in scans] + [f"f_res [Hz], N = {n}" for n in scans],
        [[L] + [_pm(sc["Z_res"][j] / U) for sc in scans.values()]
         + [_pm(sc["f_res"][j], 4) for sc in scans.values()] for j, L in enumerate(s["lz"])])
    lines += ["", "**The optimum (smallest Z_res; parabola in log Lz per bed, mean ± SE, "
              "95 % t-interval):**", ""]
    for n in scans:
        o = cmp_["optimum"][n]
        lines.append(f"- N = {n}: {scaffold.pm(o['mean'], o['se'], '.4f', '.4f', unit='m')} "
                     f"(95 %: ± {o['ci95']:.4f}; "
                     f"beds' vertices {', '.join(f'{x:.4f}' for x in scans[n]['opt']['vertices'])};"
                     " " + ("interior to the grid in every bed" if o["interior"]
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
        b, a = k.split("-")
        cells = []
        for r in rows:
            tag = {0: "n.s.", 1: "+", -1: "−"}[r["sign"]] + (" ≡" if r["equivalent"] else "")
            rel = scaffold.pm(r["rel"], r["rel_ci"], "+.1f", ".1f", unit="%", scale=100)
            cells.append(f"{r['Lz']:g}: {rel} {tag}")
        lines.append(f"- N = {b} vs N = {a}: " + "; ".join(cells) + ".")
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
    sc0 = next(iter(scans.values()))
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
    rows = []
    for n, sc in scans.items():
        for j, L in enumerate(s["lz"]):
            i = int(np.argmin(np.abs(f - np.mean(sc["f_res"][j]))))
            rows.append([n, f"{L} ({f[i]:g} Hz)"] + [
                _pm([m[k] for m in sc["measures"][i][j]], 2)
                for k in ("airborne", "lid_touch", "free", "lid_impacts", "floor_impacts",
                          "wall_grains", "strobe_spread")])
    lines += scaffold.table(
        ["N", "Lz [m]", "airborne", "lid touched", "free flight", "lid impacts / period",
         "floor impacts / period", "grains on floor or lid", "strobe spread"], rows)
    lines += ["", "## Impact timing (thesis ch. 6 and §4.2.4)", "",
              "At the frequency sample nearest each bed's resonance: mean phase of the lid and "
              "floor impacts (episode onsets) against the box's first harmonic [deg], their "
              "separation |lid − floor| (180°: counter-phase; per bed, then mean ± SE), and the "
              "fraction of impacts at which the centre of mass and the box move in opposite "
              "directions just before (the sample before the onset).", "",
              "| N | Lz [m] | Z_res/U | lid phase | floor phase | abs(lid − floor) [deg] | "
              "velocities opposite before impact |", "| --- | --- | --- | --- | --- | --- | --- |"]
    for n, sc in scans.items():
        U = sc["cfg"].primary.U
        sep = []
        for j, L in enumerate(s["lz"]):
            i = int(np.argmin(np.abs(f - np.mean(sc["f_res"][j]))))
            ms = sc["measures"][i][j]
            lf = np.abs([m["lid_floor"] for m in ms])
            sep.append(float(np.nanmean(lf)))
            lines.append(f"| {n} | {L} | {_pm(sc['Z_res'][j] / U)} | "
                         f"{_pm([m['lid_phase'] for m in ms], 3)} | "
                         f"{_pm([m['floor_phase'] for m in ms], 3)} | {_pm(lf, 3)} | "
                         f"{_pm([m['opposite'] for m in ms], 2)} |")
        j_best = int(np.argmin(sc["Z_res"].mean(-1)))
        sep = np.asarray(sep)
        j_cp = int(np.nanargmin(np.abs(sep - 180.0))) if np.isfinite(sep).any() else -1
        sc["timing"] = dict(best_lz=float(s["lz"][j_best]),
                            counterphase_lz=float(s["lz"][j_cp]) if j_cp >= 0 else math.nan)
        lines.append(f"| {n} | smallest Z_res at {s['lz'][j_best]} m; impacts nearest "
                     f"counter-phase at {s['lz'][j_cp] if j_cp >= 0 else 'none'} m | | | | | |")
    lines += ["", f"## Frequency response of N = {resp['n']} at Lz = {LZ_RESPONSE} m "
              "(thesis figs. 3.3, 3.4)", ""]
    U = resp["cfg"].primary.U
    rows = []
    for i, fq in enumerate(resp["f"]):
        ms = resp["measures"][i]
        col = np.array([m["collisional"] for m in ms])
        fr = np.array([m["frictional"] for m in ms])
        ext = np.array([m["extent"] / m["rest_extent"] for m in ms])
        rows.append([f"{fq:g}", _pm(resp["Zr"][i] / U), _pm(col), _pm(fr),
                     _pm(col / (col + fr), 2)]
                    + [_pm([m[k] for m in ms], 2) for k in
                       ("airborne", "lid_touch", "free", "lid_impacts", "floor_impacts")]
                    + [_pm(ext, 2), _pm([m["strobe_spread"] for m in ms], 2)])
    lines += scaffold.table(
        ["f [Hz]", "Z/U", "collisional loss/cycle [J]", "frictional [J]", "collisional share",
         "airborne", "lid touched", "free flight", "lid impacts / period",
         "floor impacts / period", "extent / extent at rest", "strobe spread"], rows)
    lines += ["", f"'Appreciable' collisional loss: a share of at least {APPRECIABLE:.0%} of the "
              "granular loss (a stated convention; the thesis gives no number).", ""]
    scaffold.write_summary(out, lines)


if __name__ == "__main__":
    main()
