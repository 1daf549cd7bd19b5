"""Independent-DEM cross-check: the 2023 reference damper in LAMMPS and in jaxdamp.

    python experiments/lammps_crosscheck.py          # full: A_d = 2, 3, 4 cm, 10 + 50 periods,
                                                     # 5 beds
    python experiments/lammps_crosscheck.py --quick  # one amplitude (3 cm), 2 + 3 periods, 2 beds

System: preset ``varela2023-reference`` (S2: cube of 8 cm driven as ``z = A_d cos(2π f t)``,
f = 70 Hz, 300 frictionless steel spheres, R = 2.5 mm, E = 2e9 Pa, ν = 0.3, ε = 0.75 at 1 m/s).
Both codes start from the same settled bed (jaxdamp's ``packing.settle``, run inside
``jaxdamp.studies.runner.run``) and use the same time step (``params.dt`` of the run's
configuration).

**Replicates**: ``--replicates R`` independently poured beds per amplitude (seeds
``jaxdamp.analysis.stats.replicate_seed(preset seed, k)``); each bed is handed to both codes,
so the comparison is paired: per bed the difference LAMMPS − jaxdamp of the mean dissipation per
period over a window common to both codes (MSER start of the steady state, never before the
transient: ``stats.shared_window``), across beds its mean ± SE and Student-t 95 % interval.
Every bed's results are kept in ``--out/raw/beds/`` and reused by a re-run with the same
settings (the same ``--out``), so adding beds computes only the new ones.

**Mapping to LAMMPS** (``pair_style granular``, ``fix wall/gran granular``; the Debian
build's too-stiff walls compensated): :mod:`jaxdamp.peers.lammps`, where each constant is
derived.

The mapping is verified with LAMMPS before it is used: binary head-on collisions (restitution
at 1 m/s vs 0.75 and vs :func:`jaxdamp.physics.restitution.restitution` at several speeds, contact
duration), one sphere resting on each of the six walls under gravity (equilibrium overlap vs
``(m g / k_n)^{2/3}``; also without the compensation, to measure the bug), sphere–wall
collisions (restitution vs jaxdamp's grain–wall pair), and an energy-accounting closure test
(undamped bed: input work = Δ mechanical energy).

**The driven bed in LAMMPS** is simulated in the box frame
(:func:`jaxdamp.peers.lammps.box_deck`: static walls, gravity plus the inertial force of the
box's acceleration on every grain). The dissipated energy between two instants is the work of
the inertial force, ``W = ∫ M A_d ω² cos(ωt) v_cm,z dt`` (accumulated every step by
``fix ave/time ... ave running``), minus the change of kinetic + gravitational + elastic
(``(2/5) k_n ξ^{5/2}`` over grain pairs and walls) energy, evaluated from full-precision
snapshots written at the step nearest to every period boundary ``t = nT``.

**jaxdamp**: ``jaxdamp.studies.runner.run`` on the same cases; the per-period dissipation is the
cumulative granular loss (``jaxdamp.physics.energy.granular_loss`` of the recorded work channels)
interpolated at ``t = nT`` (samples every T/500).

Dissipation per period is reported per bed as mean ± std over the window's periods, across beds as
mean ± SE, and normalised as ``E_d = E / E_max`` with ``E_max = 4 m A_d² ω²`` (m the granulate
mass; SPEC §4).

Writes ``summary.md``, ``figure.png`` and ``data.h5`` in ``--out``; LAMMPS inputs, logs and
snapshots in ``--out/raw`` (git-ignored).
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from jaxdamp.analysis.uncertainty import ar1_standard_error, lag1_autocorrelation
from jaxdamp.io.common import put
from jaxdamp.peers import lammps
from jaxdamp.studies import scaffold

HERE = os.path.dirname(os.path.abspath(__file__))
PRESET = "varela2023-reference"
AMPLITUDES = (0.02, 0.03, 0.04)
REPLICATES = 5  # independently poured beds per amplitude


def settings(quick: bool) -> dict:
    if quick:
        return dict(amplitudes=(0.03,), transient=2, periods=3, settle_time=0.3, closure_periods=1,
                    replicates=2)
    return dict(amplitudes=AMPLITUDES, transient=10, periods=50, settle_time=None,
                closure_periods=2, replicates=REPLICATES)


# ---------------------------------------------------------------------------------------------
# jaxdamp


def case_config(amplitude: float, n_periods: int, settle_time=None, seed=None):
    """The reference preset at ``amplitude`` for ``n_periods`` (samples every T/500), its bed
    poured with ``numerics.seed = seed`` (``None``: the preset's seed)."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides

    base = presets.get(PRESET)
    T = 1.0 / base.frequency
    ov = {"drive.amplitude": amplitude, "numerics.duration": (n_periods + 0.02) * T,
          "numerics.chunk": T / 5, "numerics.record_dt": T / 500}
    if settle_time is not None:
        ov["numerics.settle_time"] = settle_time
    if seed is not None:
        ov["numerics.seed"] = int(seed)
    return apply_overrides(base, ov)


def jaxdamp_case(amplitude: float, n_periods: int, settle_time=None, progress=False, seed=None):
    """``jaxdamp.studies.runner.run`` of the reference preset at ``amplitude`` for ``n_periods``,
    the bed poured with ``seed`` (see :func:`case_config`)."""
    from jaxdamp.physics.energy import granular_loss
    from jaxdamp.studies import runner

    cfg = case_config(amplitude, n_periods, settle_time, seed)
    T = 1.0 / cfg.frequency
    t0 = time.perf_counter()
    res = runner.run(cfg, progress=progress, snapshots=False, echo=None)
    elapsed = time.perf_counter() - t0
    rec = res.records
    t = np.concatenate([[0.0], rec["t"]])
    loss = np.concatenate([[0.0], granular_loss(rec["work"])])
    tb = np.arange(n_periods + 1) * T
    if t[-1] < tb[-1] - 1e-12:
        raise RuntimeError(f"jaxdamp records end at {t[-1]} s < last boundary {tb[-1]} s")
    D = np.interp(tb, t, loss)
    inp = np.concatenate([[0.0], rec["work"][:, 0]])
    resid = np.asarray(rec["balance_residual"])
    return dict(config=cfg, result=res, t=tb, D=D, dt=float(res.summary["dt"]),
                wall=float(res.summary["wall_time"]), elapsed=elapsed,
                balance=float(res.summary["balance_error"]),
                residual=float(np.max(np.abs(resid))), residual_final=float(resid[-1]),
                input_final=float(inp[-1]), bed=res.bed, bed_r=np.asarray(res.bed.r),
                bed_v=np.asarray(res.bed.v), settled=bool(res.bed.settled),
                bed_height=float(res.bed.height), bed_max_speed=float(res.bed.max_speed),
                records={k: np.asarray(rec[k]) for k in ("t", "z_cm", "z_box")})


# ---------------------------------------------------------------------------------------------
# one bed in both codes, kept in raw/beds/ for a re-run with the same settings

JD_SCALARS = ("dt", "wall", "elapsed", "balance", "residual", "residual_final", "input_final",
              "settled", "bed_height", "bed_max_speed")
LM_ARRAYS = ("steps", "t", "W", "E", "D", "elastic", "kinetic", "thermo")
LM_SCALARS = ("wall", "loop_time", "n_steps")


def bed_key(amplitude: float, seed: int, s: dict) -> dict:
    """What a stored bed must match to be reused."""
    return dict(preset=PRESET, amplitude=float(amplitude), seed=int(seed),
                transient=int(s["transient"]), periods=int(s["periods"]),
                settle_time=s["settle_time"])


def bed_path(raw: str, amplitude: float, seed: int) -> str:
    return os.path.join(raw, "beds", f"A{amplitude * 100:g}cm_seed{seed}.npz")


def save_bed(path: str, key: dict, jd: dict, lm: dict) -> None:
    os.makedirs(os.path.dirname(path), exist_ok=True)
    meta = dict(key=key, jd={k: jd[k] for k in JD_SCALARS}, lm={k: lm[k] for k in LM_SCALARS})
    arrays = {f"lm_{k}": np.asarray(lm[k]) for k in LM_ARRAYS}
    arrays.update(jd_t=jd["t"], jd_D=jd["D"], bed_r=jd["bed_r"], bed_v=jd["bed_v"],
                  **{f"rec_{k}": v for k, v in jd["records"].items()})
    tmp = path + ".tmp.npz"
    np.savez(tmp, meta=json.dumps(meta), **arrays)
    os.replace(tmp, path)


def load_bed(path: str, key: dict):
    """``(jd, lm)`` of a stored bed with this ``key``, else None."""
    if not os.path.exists(path):
        return None
    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        if meta["key"] != key:
            return None
        jd = dict(meta["jd"], t=z["jd_t"], D=z["jd_D"], bed_r=z["bed_r"], bed_v=z["bed_v"],
                  records={k: z[f"rec_{k}"] for k in ("t", "z_cm", "z_box")})
        lm = dict(meta["lm"], **{k: z[f"lm_{k}"] for k in LM_ARRAYS})
    jd["config"] = case_config(key["amplitude"], key["transient"] + key["periods"],
                               key["settle_time"], key["seed"])
    return jd, lm


def run_bed(amplitude: float, seed: int, s: dict, raw: str, exe, progress: bool, log) -> dict:
    """One bed poured by jaxdamp with ``seed``, driven at ``amplitude`` in jaxdamp and, from
    the same settled state, in LAMMPS; reused from ``raw/beds`` when stored with the same
    settings."""
    n_total = s["transient"] + s["periods"]
    key = bed_key(amplitude, seed, s)
    path = bed_path(raw, amplitude, seed)
    got = load_bed(path, key)
    if got is not None:
        jd, lm = got
        log(f"A_d = {amplitude * 100:g} cm, seed {seed}: reused {path}")
        return dict(seed=seed, jd=jd, lm=lm, mp=lammps.build_mapping(jd["config"]), reused=True)
    # jaxdamp first: its settled bed is the initial state of both codes
    log(f"A_d = {amplitude * 100:g} cm, seed {seed}: jaxdamp ...")
    jd = jaxdamp_case(amplitude, n_total, s["settle_time"], progress=progress, seed=seed)
    cfg = jd["config"]
    mp = lammps.build_mapping(cfg)
    assert abs(mp.dt - jd["dt"]) < 1e-15
    log(f"  jaxdamp: dt = {jd['dt']:.6g} s, {jd['wall']:.1f} s stepping "
        f"({jd['elapsed']:.1f} s with settling)")
    log(f"A_d = {amplitude * 100:g} cm, seed {seed}: LAMMPS ...")
    lm = lammps.driven_bed(mp, cfg, amplitude, jd["bed_r"], jd["bed_v"], n_total, raw, exe=exe,
                           tag=f"_seed{seed}")
    log(f"  LAMMPS: {lm['wall']:.1f} s")
    save_bed(path, key, jd, lm)
    return dict(seed=seed, jd=jd, lm=lm, mp=mp, reused=False)


# ---------------------------------------------------------------------------------------------
# analysis, outputs


def per_period(D: np.ndarray, transient: int) -> np.ndarray:
    return np.diff(D)[transient:]


def phase_average(t, y, T, n_bins=50, t0=0.0):
    """Mean of ``y`` in ``n_bins`` phase bins of the drive over samples with ``t >= t0``."""
    t, y = np.asarray(t), np.asarray(y)
    keep = t >= t0
    ph = np.mod(t[keep] / T, 1.0)
    idx = np.minimum((ph * n_bins).astype(int), n_bins - 1)
    s = np.bincount(idx, y[keep], n_bins)
    c = np.bincount(idx, None, n_bins)
    return (np.arange(n_bins) + 0.5) / n_bins, s / np.maximum(c, 1)


def options(ap) -> None:
    ap.add_argument("--replicates", type=int, default=None,
                    help="independently poured beds per amplitude (default 5; quick: 2)")
    ap.add_argument("--amplitudes", type=float, nargs="+", default=None,
                    help="drive amplitudes [m] (default 0.02 0.03 0.04; quick: 0.03)")
    ap.add_argument("--lmp", default=None, help="LAMMPS executable (default: lmp on PATH)")


def compute(quick: bool, log, ctx):
    args = ctx.args
    s = settings(quick)
    if args.replicates is not None:
        s["replicates"] = args.replicates
    if args.amplitudes is not None:
        s["amplitudes"] = tuple(args.amplitudes)
    if s["replicates"] < 2:
        raise SystemExit("--replicates must be at least 2 (an error bar needs two beds)")
    exe = args.lmp or lammps.executable()
    if exe is None:
        raise SystemExit("LAMMPS (`lmp`) is not on PATH: apt-get install lammps")
    raw = ctx.raw("")

    from jaxdamp.analysis.stats import replicate_seed
    from jaxdamp.cases import presets

    version = lammps.version(exe)
    log(f"LAMMPS: {version}")
    base = presets.get(PRESET)
    T = 1.0 / base.frequency
    omega = 2 * math.pi * base.frequency
    seeds = [replicate_seed(base.numerics.seed, k) for k in range(s["replicates"])]

    # 1-2. the mapping, verified with LAMMPS at the time step of the default amplitude
    mp0 = lammps.build_mapping(base)
    t0 = time.perf_counter()
    checks = lammps.mapping_checks(mp0, os.path.join(raw, "checks"), exe)
    checks_wall = time.perf_counter() - t0
    for r in checks["pair"]:
        log(f"pair v={r['v']:g}: e_LAMMPS={r['restitution']:.5f} e_ref={r['ref_restitution']:.5f}"
            f" duration {r['duration']:.4g} vs {r['ref_duration']:.4g} s")
    for r in checks["wall"]:
        log(f"wall v={r['v']:g}: e_LAMMPS={r['restitution']:.5f} "
            f"e_ref={r['ref_restitution']:.5f}")
    for r in checks["static"] + [checks["static_uncompensated"]]:
        log(f"static {r['wall']} ({'compensated' if r['compensated'] else 'E as is'}): "
            f"overlap/Hertz = {r['ratio']:.5f}")

    cases = {}
    for A in s["amplitudes"]:
        beds = []
        for seed in seeds:
            b = run_bed(A, seed, s, raw, exe, ctx.progress, log)
            b["d_lammps_all"] = np.diff(b["lm"]["D"])
            b["d_jaxdamp_all"] = np.diff(b["jd"]["D"])
            log(f"  dissipation per period after the transient: LAMMPS "
                f"{b['d_lammps_all'][s['transient']:].mean():.4g} J, jaxdamp "
                f"{b['d_jaxdamp_all'][s['transient']:].mean():.4g} J")
            beds.append(b)
        mp = beds[0]["mp"]
        m_gran = mp.mass * beds[0]["jd"]["config"].grains[0].count
        cases[A] = dict(beds=beds, mp=mp, e_max=4 * m_gran * A**2 * omega**2, m=m_gran)

    # accounting closure: undamped bed (the first seed's), input work = Δ(mechanical energy)
    A_c = 0.03 if 0.03 in cases else s["amplitudes"][0]
    c = cases[A_c]["beds"][0]
    clo = lammps.driven_bed(c["mp"], c["jd"]["config"], A_c, c["jd"]["bed_r"], c["jd"]["bed_v"],
                            s["closure_periods"], raw, damped=False, exe=exe,
                            tag=f"_seed{c['seed']}")
    dE = float(np.max(np.abs(clo["E"] - clo["E"][0])))
    closure = dict(amplitude=A_c, seed=c["seed"], periods=s["closure_periods"],
                   D=clo["D"].tolist(), W=clo["W"].tolist(), E=clo["E"].tolist(),
                   relative=float(np.max(np.abs(clo["D"])) / max(dE, 1e-300)))
    log(f"closure (undamped, {s['closure_periods']} periods): max |W - ΔE| = "
        f"{np.max(np.abs(clo['D'])):.3g} J, max |ΔE| = {dE:.3g} J")
    amps = sorted(cases)
    table = {A: analyse_amplitude(A, cases[A], s, T) for A in amps}
    run = dict(cases=cases, checks=checks, closure=closure, mapping=mp0, settings=s,
               table=table, version=version, checks_wall=checks_wall, T=T, seeds=seeds)
    return run, lambda out, prov: write(run, out, prov)


main = scaffold.entry(__file__, __doc__, compute, options)


def within_run(d) -> tuple[float, float, float]:
    """Mean, standard deviation and the within-run standard error (serial correlation
    allowed for: :func:`jaxdamp.analysis.uncertainty.ar1_standard_error`) of a per-period
    series."""
    d = np.asarray(d, float)
    sd = float(d.std(ddof=1)) if len(d) > 1 else math.nan
    return float(d.mean()), sd, ar1_standard_error(d)


KEY = "granular_loss_per_cycle"


def analyse_bed(b: dict, s: dict, T: float) -> dict:
    """One bed in both codes: the common analysis window (MSER on both per-period series, never
    before the transient: :func:`jaxdamp.analysis.stats.shared_window`), each code's mean over
    it, their difference, and the within-run figures of the single-bed comparison."""
    from jaxdamp.analysis import stats as jstats

    dl_all, dj_all = np.asarray(b["d_lammps_all"]), np.asarray(b["d_jaxdamp_all"])
    n = len(dl_all)
    t_start = np.arange(n) * T
    keep = min(5, s["periods"])
    series = [{"t_start": t_start, KEY: dl_all}, {"t_start": t_start, KEY: dj_all}]
    w = jstats.shared_window(series, keys=(KEY,), min_discard=s["transient"], min_keep=keep)
    dets = [jstats.detect(x, min_discard=s["transient"], min_keep=keep) for x in series]
    start = int(w["start"])
    dl, dj = dl_all[start:], dj_all[start:]
    ml, sl, el = within_run(dl)
    mj, sj, ej = within_run(dj)
    corr = float(np.corrcoef(dl, dj)[0, 1]) if len(dl) > 2 else float("nan")
    close = np.abs(dl - dj) <= 0.01 * np.abs(dj)
    first_apart = int(np.argmin(close)) if not close.all() else len(dl)
    half = max(1, len(dl) // 2)
    tab = b["lm"]["thermo"]
    t0 = start * T
    _, zl = phase_average(tab[:, 1], tab[:, 2], T, t0=t0)
    rec = b["jd"]["records"]
    _, zj = phase_average(rec["t"], np.asarray(rec["z_cm"]) - np.asarray(rec["z_box"]), T, t0=t0)
    n0 = s["transient"]
    return dict(seed=b["seed"], start=start, kept=len(dl), stationary=bool(w["stationary"]),
                start_l=dets[0].period, start_j=dets[1].period,
                stat_l=dets[0].stationary, stat_j=dets[1].stationary,
                ml=ml, sl=sl, el=el, mj=mj, sj=sj, ej=ej, diff=ml - mj, comb=math.hypot(el, ej),
                rel=(ml - mj) / mj, corr=corr, first_apart=first_apart,
                lag_l=lag1_autocorrelation(dl), lag_j=lag1_autocorrelation(dj),
                zcm_diff=float(np.max(np.abs(zl - zj))),
                zcm_span=float(zl.max() - zl.min()),
                transient_l=float(b["lm"]["D"][n0]), transient_j=float(b["jd"]["D"][n0]),
                el_max=float(np.max(b["lm"]["elastic"])), residual=b["jd"]["residual"],
                resid_rate=b["jd"]["residual_final"] / (len(b["jd"]["t"]) - 1),
                halves_l=(float(dl[:half].mean()), float(dl[half:].mean())),
                halves_j=(float(dj[:half].mean()), float(dj[half:].mean())),
                us_l=b["lm"]["wall"] / b["lm"]["n_steps"] * 1e6,
                us_j=b["jd"]["wall"] / b["lm"]["n_steps"] * 1e6,
                wall_l=b["lm"]["wall"], loop_l=b["lm"]["loop_time"], wall_j=b["jd"]["wall"],
                elapsed_j=b["jd"]["elapsed"], dt=b["mp"].dt, steps=b["lm"]["n_steps"],
                balance=b["jd"]["balance"], settled=bool(b["jd"]["settled"]),
                max_speed=float(b["jd"]["bed_max_speed"]),
                reused=bool(b["reused"]))


def analyse_amplitude(A: float, c: dict, s: dict, T: float) -> dict:
    """Across the beds of one amplitude: each code's mean ± SE of the beds' means, and the
    per-bed (paired) difference LAMMPS − jaxdamp with its Student-t 95 % interval; the
    unpaired Welch interval of the two codes' bed means alongside."""
    from jaxdamp.analysis import stats as jstats

    beds = [analyse_bed(b, s, T) for b in c["beds"]]
    ok = np.array([r["stationary"] for r in beds])
    ml = np.array([r["ml"] for r in beds])
    mj = np.array([r["mj"] for r in beds])
    el = jstats.across(ml, stationary=ok)
    ej = jstats.across(mj, stationary=ok)
    ed = jstats.across(ml - mj, stationary=ok)
    wd, wh = jstats.welch(ml[ok], mj[ok])
    agree = bool(np.isfinite(ed.ci95) and abs(ed.mean) <= ed.ci95)
    return dict(A=A, e_max=c["e_max"], beds=beds, R=len(beds), n=ed.n,
                ml=el.mean, sel=el.se, mj=ej.mean, sej=ej.se,
                sdl=float(np.std(ml[ok], ddof=1)) if ok.sum() > 1 else float("nan"),
                sdj=float(np.std(mj[ok], ddof=1)) if ok.sum() > 1 else float("nan"),
                within_l=float(np.mean([r["el"] for r in beds])),
                within_j=float(np.mean([r["ej"] for r in beds])),
                d=ed.mean, sed=ed.se, hw=ed.ci95, welch_d=wd, welch_hw=wh, agree=agree,
                rel=ed.mean / ej.mean, rel_hw=ed.ci95 / ej.mean)


def write(run: dict, out: str, prov: dict) -> None:
    """``data.h5``, ``figure.png`` and ``summary.md`` of a finished :func:`compute`."""
    _write_data(run, out, prov)
    _figure(run, out)
    _summary(run, out, prov)


def _write_data(run: dict, out: str, prov: dict) -> None:
    cases, table, s, seeds = run["cases"], run["table"], run["settings"], run["seeds"]
    amps = sorted(cases)
    J = "J per period"
    with scaffold.data_file(
            out, prov, lammps_version=run["version"], preset=PRESET,
            mapping=run["mapping"].as_dict(), checks=run["checks"], closure=run["closure"],
            paired="both codes start from the same bed: the difference is taken per bed, its "
                   "interval is the Student-t 95 % one over the beds") as h:
        h.attrs.update(transient_periods=s["transient"], periods=s["periods"],
                       replicates=s["replicates"], seeds=np.asarray(seeds))
        put(h, "amplitude", amps, "m")
        for A in amps:
            c, r = cases[A], table[A]
            g = h.create_group(f"A_{A * 100:g}cm")
            g.attrs["mapping"] = json.dumps(c["mp"].as_dict())
            g.attrs.update(dt=c["mp"].dt, e_max=c["e_max"], granulate_mass=c["m"],
                           n_stationary=r["n"], lammps_mean=r["ml"], lammps_se=r["sel"],
                           jaxdamp_mean=r["mj"], jaxdamp_se=r["sej"], difference_mean=r["d"],
                           difference_se=r["sed"], difference_ci95=r["hw"],
                           welch_difference=r["welch_d"], welch_ci95=r["welch_hw"],
                           agree=r["agree"])
            bs = r["beds"]
            g.create_dataset("seed", data=np.asarray(seeds))
            g.create_dataset("stationary", data=np.asarray([x["stationary"] for x in bs]))
            put(g, "window_start", [x["start"] for x in bs], "periods")
            for key, name in (("ml", "lammps/mean_per_bed"), ("mj", "jaxdamp/mean_per_bed"),
                              ("diff", "difference_per_bed")):
                put(g, name, [x[key] for x in bs], J)
            for k, (b, x) in enumerate(zip(c["beds"], bs)):
                gb = g.create_group(f"bed_{k}")
                gb.attrs["config"] = b["jd"]["config"].to_json()
                gb.attrs.update(seed=b["seed"], window_start=x["start"],
                                stationary=x["stationary"], lammps_wall_time=x["wall_l"],
                                jaxdamp_wall_time=x["wall_j"], jaxdamp_elapsed=x["elapsed_j"],
                                jaxdamp_balance_error=x["balance"], bed_settled=x["settled"])
                for code, key in (("lammps", "d_lammps_all"), ("jaxdamp", "d_jaxdamp_all")):
                    put(gb, f"{code}/dissipation_per_period", b[key], "J",
                        note="every period from t = 0; the window starts at window_start")
                lm, jd = b["lm"], b["jd"]
                for name, data, unit in (
                        ("lammps/cumulative_dissipation", lm["D"], "J"),
                        ("lammps/input_work", lm["W"], "J"),
                        ("lammps/mechanical_energy", lm["E"], "J"),
                        ("lammps/elastic_energy", lm["elastic"], "J"),
                        ("lammps/boundary_time", lm["t"], "s"),
                        ("jaxdamp/cumulative_dissipation", jd["D"], "J"),
                        ("jaxdamp/boundary_time", jd["t"], "s")):
                    put(gb, name, data, unit)
                if k == 0:  # the figure's bed (the others' thermo series stay in raw/beds)
                    gb.create_dataset("lammps/thermo", data=lm["thermo"], compression="gzip",
                                      shuffle=True).attrs["columns"] = \
                        "step time z_cm vz_cm W (box frame)"


def _figure(run: dict, out: str) -> None:
    cases, table, T, seeds = run["cases"], run["table"], run["T"], run["seeds"]
    amps = sorted(cases)
    fig, axs = scaffold.subplots(2, 3, (17, 9))
    axs = axs.ravel()
    rows = [table[A] for A in amps]
    a = np.array(amps) * 100
    tq = [r["hw"] / r["sed"] if r["sed"] > 0 else float("nan") for r in rows]  # t quantile
    ax = axs[0]
    for off, key, se, mk, lab in ((-0.04, "ml", "sel", "o", "LAMMPS"),
                                  (0.04, "mj", "sej", "s", "jaxdamp")):
        line = ax.errorbar(a + off, [r[key] for r in rows],
                           yerr=[r[se] * q for r, q in zip(rows, tq)], fmt=mk, capsize=4,
                           label=f"{lab}: mean ± 95 % over beds")[0]
        for A, r in zip(a, rows):
            ax.plot(np.full(r["R"], A + off + 0.02), [x[key] for x in r["beds"]], ".",
                    color=line.get_color(), alpha=0.5, ms=4)
    ax.plot(a, [r["e_max"] for r in rows], "k^--", lw=0.8, ms=4, label="E_max = 4 m A² ω²")
    ax.set_xlabel("A_d [cm]")
    ax.set_ylabel("dissipated energy per period [J]")
    ax.set_title(f"{PRESET}: {rows[0]['R']} beds per amplitude (dots: each bed)")
    ax.legend(fontsize=8)
    ax = axs[1]
    ax.errorbar(a - 0.04, [r["ml"] / r["e_max"] for r in rows],
                yerr=[r["sel"] / r["e_max"] for r in rows], fmt="o", capsize=4, label="LAMMPS")
    ax.errorbar(a + 0.04, [r["mj"] / r["e_max"] for r in rows],
                yerr=[r["sej"] / r["e_max"] for r in rows], fmt="s", capsize=4, label="jaxdamp")
    ax.set_xlabel("A_d [cm]")
    ax.set_ylabel("E_d = E / E_max")
    ax.set_title("dissipation efficiency (mean ± SE over beds)")
    ax.legend(fontsize=8)
    ax = axs[2]
    ax.axhline(0, color="k", lw=0.8)
    ax.errorbar(a, [r["rel"] * 100 for r in rows], yerr=[r["rel_hw"] * 100 for r in rows],
                fmt="D", capsize=5, color="C3", label="mean ± 95 % (paired t over beds)")
    for A, r in zip(a, rows):
        ax.plot(np.full(r["R"], A + 0.05), [x["diff"] / r["mj"] * 100 for x in r["beds"]],
                ".", color="C3", alpha=0.5, ms=5)
    ax.set_xlabel("A_d [cm]")
    ax.set_ylabel("LAMMPS − jaxdamp [% of jaxdamp's mean]")
    ax.set_title("paired difference per bed (dots) and over beds")
    ax.legend(fontsize=8)
    ax = axs[3]
    for A in amps:
        b, x = cases[A]["beds"][0], table[A]["beds"][0]
        k = np.arange(1, len(b["d_lammps_all"]) + 1)
        line, = ax.plot(k, b["d_lammps_all"], "o-", ms=2, lw=0.7, label=f"LAMMPS {A * 100:g} cm")
        ax.plot(k, b["d_jaxdamp_all"], "s--", ms=2, lw=0.7, color=line.get_color(),
                label=f"jaxdamp {A * 100:g} cm")
        ax.axvline(x["start"] + 0.5, color=line.get_color(), lw=0.6, ls=":")
    ax.set_xlabel("period index n (dissipation over [(n-1)T, nT])")
    ax.set_ylabel("dissipated energy in the period [J]")
    ax.set_title(f"per-period series, bed seed {seeds[0]} (dotted: window start)")
    ax.legend(fontsize=7, ncol=2)
    ax = axs[4]
    for A in amps:
        b, x = cases[A]["beds"][0], table[A]["beds"][0]
        tab = b["lm"]["thermo"]
        t0 = x["start"] * T
        ph, zl = phase_average(tab[:, 1], tab[:, 2], T, t0=t0)
        rec = b["jd"]["records"]
        ph2, zj = phase_average(rec["t"], np.asarray(rec["z_cm"]) - np.asarray(rec["z_box"]), T,
                                t0=t0)
        line, = ax.plot(ph, zl * 100, "-", label=f"LAMMPS {A * 100:g} cm")
        ax.plot(ph2, zj * 100, "--", color=line.get_color(), label=f"jaxdamp {A * 100:g} cm")
    ax.set_xlabel("drive phase t/T mod 1 (box at its top at 0)")
    ax.set_ylabel("centre of mass above the floor [cm]")
    ax.set_title(f"phase-averaged bed height (window), bed seed {seeds[0]}")
    ax.legend(fontsize=7)
    ax = axs[5]
    w_ = 0.18
    ax.bar(a - 1.5 * w_, [r["sdl"] for r in rows], w_, label="LAMMPS: std of bed means")
    ax.bar(a - 0.5 * w_, [r["within_l"] for r in rows], w_, label="LAMMPS: within-run SE (mean)")
    ax.bar(a + 0.5 * w_, [r["sdj"] for r in rows], w_, label="jaxdamp: std of bed means")
    ax.bar(a + 1.5 * w_, [r["within_j"] for r in rows], w_, label="jaxdamp: within-run SE (mean)")
    ax.set_xlabel("A_d [cm]")
    ax.set_ylabel("J per period")
    ax.set_title("spread between beds vs one run's standard error")
    ax.legend(fontsize=7)
    scaffold.save_figure(fig, out, dpi=110)


def _summary(run: dict, out: str, prov: dict) -> None:
    cases, table, s, seeds = run["cases"], run["table"], run["settings"], run["seeds"]
    checks, closure, mp0 = run["checks"], run["closure"], run["mapping"]
    amps = sorted(cases)
    beds = [x for A in amps for x in table[A]["beds"]]
    L = []
    w = L.append
    w("# LAMMPS cross-check of the 2023 reference damper\n")
    w(scaffold.provenance_line(prov) + " LAMMPS serial (one MPI rank, `OMP_NUM_THREADS=1`), "
      "jaxdamp on the same machine (engine "
      f"`{cases[amps[0]]['beds'][0]['jd']['config'].numerics.engine}`); "
      f"{sum(x['reused'] for x in beds)} of {len(beds)} beds read back from `raw/beds` (their "
      f"own compute: jaxdamp {sum(x['elapsed_j'] for x in beds):.0f} s including settling, "
      f"LAMMPS {sum(x['wall_l'] for x in beds):.0f} s).\n")
    w(f"LAMMPS: `{run['version']}` (`lmp -h`, Debian package, GRANULAR).\n")
    w(f"System: preset `{PRESET}` — cube 8 cm, f = 70 Hz, 300 frictionless steel spheres "
      f"R = {mp0.R * 1e3:g} mm (m = {mp0.mass:.6g} kg each, granulate "
      f"{mp0.mass * 300:.5g} kg), E = {mp0.E:.3g} Pa, ν = {mp0.nu:g}, ε = 0.75 at 1 m/s "
      f"(A = {mp0.A:.6g} s), walls of the same material. {s['transient'] + s['periods']} "
      f"periods per run, of which the first {s['transient']} are always discarded.\n")
    w(f"**Replicates.** R = {s['replicates']} independently poured beds per amplitude: bed k is "
      f"settled by jaxdamp with `numerics.seed` = {', '.join(str(x) for x in seeds)} "
      "(`jaxdamp.analysis.stats.replicate_seed`: an independently jittered lattice, settled "
      "anew), and that same settled bed is the initial state of both codes, which use the same "
      "dt (jaxdamp's `params.dt` per amplitude). The comparison is therefore **paired**: per "
      "bed, the difference LAMMPS − jaxdamp of the two codes' mean dissipation per period over "
      "one common window; across beds, the mean ± SE of these differences and the Student-t "
      "95 % interval (R − 1 degrees of freedom). The beds are independent of each other; the "
      "two codes on one bed are not. The unpaired Welch 95 % interval of the two codes' bed "
      "means is given alongside.\n")
    w("**Window and stationarity.** Per bed, the start of the steady state is detected by MSER "
      "(`jaxdamp.analysis.stats.mser`, never before the transient periods, searched up to half "
      "the run) on each code's per-period dissipation; the window common to both codes starts at "
      "the later of the two (`stats.shared_window`) and runs to the end. A bed counts only if "
      "both series are stationary (the MSER minimum lies inside the search range).\n")
    w("## Mapping (jaxdamp → LAMMPS)\n")
    dts = ", ".join(f"{cases[A]['mp'].dt:.6g} s ({A * 100:g} cm)" for A in amps)
    L += scaffold.table(("quantity", "jaxdamp", "LAMMPS input"), [
        ("grain–grain", f"k_n = (4/3) E* sqrt(R/2) = {mp0.k_pp:.6g} N m^-3/2, γ_n = 1.5 A k_n = "
         f"{mp0.gamma_pp:.6g}", f"`hertz/material {mp0.E:.6g} η_n0 {mp0.nu:g}`, η_n0 = "
         f"γ_n/(m* sqrt(R*)) = 2 A E*/m* = {mp0.eta_pp:.6g} 1/(s m), m* = m/2"),
        ("grain–wall", f"k_n = (4/3) E* sqrt(R) = {mp0.k_pw:.6g}, γ_n = 1.5 A k_n = "
         f"{mp0.gamma_pw:.6g}", f"`fix wall/gran granular hertz/material "
         f"{mp0.E_wall_lammps:.6g} η_n0 {mp0.nu:g}` (E/(1+ν): bug compensated), η_n0 = "
         f"2 A E*/m = {mp0.eta_pw:.6g}, m* = m"),
        ("E* (both)", f"1/(c_i + c_j) = {mp0.E_star_pp:.6g} Pa",
         "LAMMPS pair: 1/(2(1-ν²)/E); wall: E_w/(2(1-ν)) with E_w = E/(1+ν)"),
        ("tangential", "none (μ = 0, γ_s = 0)", "`tangential linear_nohistory 0 0`"),
        ("clipping", "F_n = max(0, ·)", "`limit_damping` (pair and walls)"),
        ("time step", "params.dt", f"same: {dts}"),
        ("drive", "walls move, z = A cos ωt",
         "box frame: static walls, `fix gravity` with g_eff = g − A ω² cos(ω t)")])
    w("")
    w("LAMMPS' viscoelastic damping force is η_n0 · a · m* · ξ' with a = sqrt(R* ξ) "
      "(pair_granular docs, `damping viscoelastic`; the same expression `damp_normal = a*meff` "
      "in `fix_wall_gran.cpp`), so η_n0 = γ_n / (m* sqrt(R*)) reproduces γ_n sqrt(ξ) ξ' exactly.\n")
    w(f"## Mapping checks (LAMMPS runs, dt = {mp0.dt:.6g} s; {run['checks_wall']:.1f} s wall)\n")
    collisions = ("v [m/s]", "ε LAMMPS", "ε reference", "rel. diff", "overlap time LAMMPS [µs]",
                  "reference [µs]")
    for kind, what in (("pair", "Binary head-on collisions (reference: "
                        "`jaxdamp.physics.restitution.collision`, the exact integral of the force "
                        "law):\n"),
                       ("wall", "\nSphere–floor collisions (reference: grain–wall pair, m* = m, "
                        "R* = R):\n")):
        w(what)
        L += scaffold.table(collisions, [
            (f"{r['v']:g}", f"{r['restitution']:.5f}", f"{r['ref_restitution']:.5f}",
             f"{(r['restitution'] / r['ref_restitution'] - 1) * 100:+.3f} %",
             f"{r['duration'] * 1e6:.2f}", f"{r['ref_duration'] * 1e6:.2f}")
            for r in checks[kind]])
    w("\nStatic test: one sphere pressed on a wall by g = 9.8 m/s², damped to rest (0.1 s); "
      "equilibrium overlap vs Hertz (m g / k_n)^{2/3} = "
      f"{checks['static'][0]['hertz']:.6g} m:\n")
    u = checks["static_uncompensated"]
    L += scaffold.table(("wall", "overlap [m]", "overlap / Hertz", "residual speed [m/s]"), [
        (name, f"{r['overlap']:.6g}", f"{r['ratio']:.5f}", f"{r['speed']:.2g}") for name, r in
        [(r["wall"], r) for r in checks["static"]]
        + [("floor, wall given E as is (uncompensated)", u)]])
    w(f"\nWithout the compensation the floor is stiffer by (ratio)^(-3/2) = "
      f"{u['ratio'] ** -1.5:.4f} (expected from the `E/(2(1-ν))` formula: 1+ν = "
      f"{1 + mp0.nu:g}).\n")
    w(f"Energy accounting closure (LAMMPS, undamped bed — η_n0 = 0 for pairs and walls — "
      f"A_d = {closure['amplitude'] * 100:g} cm, {closure['periods']} periods from the settled "
      "bed): "
      f"input work − Δ(kinetic + gravitational + elastic) = "
      f"{', '.join(f'{x:.3g}' for x in closure['D'][1:])} J at the period boundaries, "
      f"{closure['relative'] * 100:.2g} % of the largest |ΔE| "
      f"({max(abs(x - closure['E'][0]) for x in closure['E']):.4g} J) and "
      f"{max(abs(x) for x in closure['D']) / table[closure['amplitude']]['ml']:.1e} "
      "of the damped bed's dissipation per period at that amplitude.\n")
    w("## Dissipation per period across beds\n")
    w("Per amplitude, over the R beds: each code's mean ± SE (s/sqrt(R)) of the beds' window "
      "means, the paired difference LAMMPS − jaxdamp (mean ± SE of the per-bed differences, "
      "[Student-t 95 % half-width]), its share of jaxdamp's mean, the unpaired Welch 95 % "
      "interval of the two codes' bed means, and E_d = E / E_max (E_max = 4 m A_d² ω², SPEC §4; "
      "energy per period, not power) ± SE.\n")
    pm = scaffold.pm
    L += scaffold.table(
        ("A_d [cm]", "beds (stationary)", "E_max [J]", "LAMMPS [J]", "jaxdamp [J]",
         "LAMMPS − jaxdamp, paired [J]", "in % of jaxdamp", "Welch 95 % (unpaired) [J]",
         "E_d LAMMPS", "E_d jaxdamp", "interval"),
        [(f"{A * 100:g}", f"{r['R']} ({r['n']})", f"{r['e_max']:.4g}", pm(r["ml"], r["sel"], 4),
          pm(r["mj"], r["sej"], 4), f"{pm(r['d'], r['sed'], '+.3g')} [{r['hw']:.2g}]",
          pm(r["rel"], r["rel_hw"], "+.2f", ".2f", "%", 100),
          pm(r["welch_d"], r["welch_hw"], "+.3g"),
          pm(r["ml"] / r["e_max"], r["sel"] / r["e_max"], ".4f"),
          pm(r["mj"] / r["e_max"], r["sej"] / r["e_max"], ".4f"),
          "contains 0" if r["agree"] else "excludes 0") for A, r in table.items()])
    w("\nSpread between beds against one run's error: the standard deviation of the beds' means "
      "(what a single run's mean scatters by) next to the mean within-run standard error of one "
      "bed's window mean (std over periods / sqrt(N), inflated by sqrt((1+ρ)/(1-ρ)) for a positive "
      "lag-1 autocorrelation ρ):\n")
    L += scaffold.table(
        ("A_d [cm]", "LAMMPS: std of bed means [J]", "LAMMPS: within-run SE [J]",
         "jaxdamp: std of bed means [J]", "jaxdamp: within-run SE [J]"),
        [[f"{A * 100:g}"] + [f"{r[k]:.3g}" for k in ("sdl", "within_l", "sdj", "within_j")]
         for A, r in table.items()])
    w(f"\n(With R = {s['replicates']} beds the standard deviation of the bed means is itself "
      "uncertain by tens of percent.)\n")
    w("## Per bed\n")
    w("Window: the periods n of the common window (period n is [(n−1)T, nT]; in brackets the "
      "first steady period detected in LAMMPS' / jaxdamp's series) and their number. Means ± "
      "standard deviation over the window's "
      "periods (in brackets: the within-run standard error as above). Cross-correlation of the "
      "two codes' per-period values, the number of leading window periods that agree within "
      "1 %, and each series' lag-1 autocorrelation: the bed is chaotic, so the two codes' "
      "trajectories decorrelate and the comparison of one bed is statistical.\n")
    L += scaffold.table(
        ("A_d [cm]", "seed", "window (starts L / J)", "stationary", "LAMMPS [J]", "jaxdamp [J]",
         "LAMMPS − jaxdamp [J]", "/ combined within-run SE", "cross-corr.",
         "leading within 1 %", "lag-1 L / J"),
        [(f"{A * 100:g}", x["seed"], f"{x['start'] + 1}–{x['start'] + x['kept']} "
          f"({x['start_l'] + 1} / {x['start_j'] + 1}), {x['kept']}",
          "yes" if x["stationary"] else "NO",
          f"{pm(x['ml'], x['sl'], 4, 3)} ({x['el']:.2g})",
          f"{pm(x['mj'], x['sj'], 4, 3)} ({x['ej']:.2g})",
          f"{x['diff']:+.3g} ({x['rel'] * 100:+.2f} %)",
          f"{abs(x['diff']) / x['comb'] if x['comb'] > 0 else float('nan'):.2g}",
          f"{x['corr']:.3f}", f"{x['first_apart']} of {x['kept']}",
          f"{x['lag_l']:.2f} / {x['lag_j']:.2f}")
         for A, r in table.items() for x in r["beds"]])
    w("\nOther observables per bed: largest difference between the codes of the phase-averaged "
      "centre-of-mass height (50 phase bins, window) and its swing over a period; dissipation "
      f"during the first {s['transient']} periods; mean dissipation per period in the first / "
      "second half of the window; largest elastic energy at a LAMMPS period boundary (included "
      "in the balance).\n")
    L += scaffold.table(
        ("A_d [cm]", "seed", "z_cm difference [mm]", "z_cm swing [mm]", "transient L / J [J]",
         "halves LAMMPS [J]", "halves jaxdamp [J]", "elastic max [J]"),
        [(f"{A * 100:g}", x["seed"], f"{x['zcm_diff'] * 1e3:.2f}", f"{x['zcm_span'] * 1e3:.1f}",
          f"{x['transient_l']:.4g} / {x['transient_j']:.4g}",
          f"{x['halves_l'][0]:.4g} → {x['halves_l'][1]:.4g}",
          f"{x['halves_j'][0]:.4g} → {x['halves_j'][1]:.4g}", f"{x['el_max']:.3g}")
         for A, r in table.items() for x in r["beds"]])
    w("\nWall times (stepping only; both on one core of a shared 2-core machine; a bed read back "
      "from `raw/beds` keeps the times of the run that made it):\n")
    L += scaffold.table(
        ("A_d [cm]", "seed", "dt [s]", "steps", "LAMMPS [s]", "LAMMPS loop [s]",
         "LAMMPS [µs/step]", "jaxdamp stepping [s]", "jaxdamp [µs/step]",
         "jaxdamp incl. settling + compile [s]", "jaxdamp balance error",
         "jaxdamp max abs(residual) [J]", "jaxdamp residual per period [J]"),
        [[f"{A * 100:g}", x["seed"], f"{x['dt']:.5g}", x["steps"]]
         + [f"{x[k]:.1f}" for k in ("wall_l", "loop_l", "us_l", "wall_j", "us_j", "elapsed_j")]
         + [f"{x['balance']:.2g}", f"{x['residual']:.3g}",
            f"{x['resid_rate']:+.3g} ({x['resid_rate'] / x['mj'] * 100:+.2g} % of its "
            "dissipation)"] for A, r in table.items() for x in r["beds"]])
    w("\nLAMMPS wall time includes its input parsing, the one-period `run` segments and the "
      "snapshot writes; 'loop' is the sum of LAMMPS' own loop times. jaxdamp stepping is "
      "`summary['wall_time']` (chunks only; samples every T/500 here, which costs extra "
      "host round trips with the native engine); its balance error is the runner's "
      "`balance_error` (largest energy-balance residual / final input + losses); residual per "
      "period: final residual E − E0 + losses − input divided by the simulated periods (a "
      "steady drift, positive: the loss channels plus the energy change exceed the input). "
      "LAMMPS' dissipation is defined by its energy balance, so it has no such residual; its "
      "accounting closes to the closure test above."
      + ("" if all(x["settled"] for x in beds) else
         f" {sum(not x['settled'] for x in beds)} of {len(beds)} beds did not meet jaxdamp's "
         "settling criterion (fastest grain below `numerics.settle_speed`) within the settle "
         f"time: fastest grain at the end of settling {min(x['max_speed'] for x in beds):.2g}–"
         f"{max(x['max_speed'] for x in beds):.2g} m/s; both codes "
         "start from that same state, so the comparison is unaffected, and the transient "
         "periods are discarded."))
    w("\nFigure: `figure.png` — top: dissipation per period (mean ± 95 % over beds, dots: each "
      "bed), E_d (± SE over beds) and the paired difference LAMMPS − jaxdamp in % (dots: each "
      "bed, bar: paired 95 % interval); bottom: the per-period series of both codes and the "
      f"phase-averaged centre-of-mass height above the floor for the bed of seed {seeds[0]}, and "
      "the spread of the bed means against one run's standard error.\n")
    w("## Verdict\n")
    w(verdict(table, amps, s, checks))
    w("")
    w("Data: `data.h5` (per amplitude: the across-bed estimates as attributes, per-bed means, "
      "seeds, windows, stationarity; per bed: the per-period dissipation of both codes, LAMMPS "
      "cumulative input work / mechanical energy / dissipation at the boundaries; the thermo "
      f"series of the bed of seed {seeds[0]}; "
      "mapping and checks as JSON attributes). LAMMPS inputs, logs and snapshots, and every bed's "
      "results (`raw/beds/*.npz`, reused by a re-run with the same settings): `raw/` "
      "(git-ignored).")
    scaffold.write_summary(out, L)


def verdict(table, amps, s, checks) -> str:
    out = []
    pair_ok = all(abs(r["restitution"] / r["ref_restitution"] - 1) < 1e-3 for r in checks["pair"])
    wall_ok = all(abs(r["restitution"] / r["ref_restitution"] - 1) < 1e-3 for r in checks["wall"])
    static_ok = all(abs(r["ratio"] - 1) < 1e-3 for r in checks["static"])
    out.append("- Mapping: LAMMPS reproduces jaxdamp's contact law "
               + ("(binary and wall restitution within 0.1 % at 1, 5, 20 m/s; static wall overlaps "
                  "within 0.1 % of Hertz once the wall-modulus bug is compensated)."
                  if pair_ok and wall_ok and static_ok else
                  "only partly — see the check tables above (a check missed 0.1 %)."))
    for A in amps:
        r = table[A]
        pm = scaffold.pm
        out.append(
            f"- A_d = {A * 100:g} cm ({r['n']} of {r['R']} beds stationary): LAMMPS "
            f"{pm(r['ml'], r['sel'], 4, unit='J')}, jaxdamp {pm(r['mj'], r['sej'], 4, unit='J')} "
            f"per period; paired difference LAMMPS − jaxdamp {pm(r['d'], r['hw'], '+.3g')} J "
            f"(95 %; {pm(r['rel'], r['rel_hw'], '+.2f', '.2f', scale=100)} % of jaxdamp's mean): "
            + ("the interval contains 0 — no difference between the codes is resolved."
               if r["agree"] else
               "the interval EXCLUDES 0 — the codes differ, a finding to explain (mapping, "
               "integrator, accounting), not to tune.")
            + f" Welch (unpaired): {pm(r['welch_d'], r['welch_hw'], '+.3g', unit='J')}.")
    if all(table[A]["agree"] for A in amps):
        worst = max(table[A]["rel_hw"] for A in amps)
        out.append(f"- Overall: at every amplitude the paired 95 % interval of the difference "
                   f"contains 0 ({s['replicates']} beds each); its half-width, at most "
                   f"{worst * 100:.2g} % of the dissipation, bounds a systematic difference "
                   "between the codes.")
    else:
        out.append("- Overall: at least one amplitude's paired 95 % interval excludes 0.")
    if s["periods"] < 10:
        out.append(f"- Quick mode: {s['periods']} periods per window only — the estimates are "
                   "rough.")
    return "\n".join(out)


if __name__ == "__main__":
    main()
