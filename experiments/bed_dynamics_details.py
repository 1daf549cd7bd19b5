"""Three details of thesis ch. 4 at the optimum, with replicates: the 7.5 Hz flight without the
lid (C3), the torus lines at 8 Hz (C4) and the impacts of the periodic window at 14.5 Hz (C10,
C11). ``python experiments/bed_dynamics_details.py [--quick]`` (full: ~6 min on 2 cores).

``sanchez2012-optimal`` as ``bed_dynamics`` runs it (settled 1 s, the first 4 s dropped), 3
independently poured beds per frequency:

* **7.5 Hz** (8 s, 1 ms samples): regime of ``z_cm`` (``bed_dynamics.classify_one``), box
  acceleration over g, floor contacts, the smallest clearance between the lid and the highest
  grain, the fraction of samples with no grain on the floor;
* **8 Hz** (10 s, 1 ms samples): the periodogram of ``z_cm``; the strongest line that is not a
  harmonic of f, read as the torus' second frequency ``f₂`` (below f/2, else ``f − f₂``), and
  the share of the non-harmonic power (0–2f) within ±2 bins of ``f₂``, ``f − f₂``, ``f + f₂``;
* **14.5 Hz** (7 s, 0.5 ms samples): impact episodes on lid and floor per period (contact
  episodes with gaps shorter than T/10 merged, as ``grain_number``), the lid–floor phase
  separation, and the ratio of the bed's and the box's velocities just before each impact
  (< 0: opposite directions, C11); the force-state hit counts ``bed_dynamics`` uses, at the
  0.5 ms samples and every second one, to show that they count contact chatter.

Writes ``data.h5``, ``figure.png``, ``summary.md``; raw sweeps in ``--out/raw``.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import find_peaks

from jaxdamp.analysis import dynamics as dyn
from jaxdamp.analysis.impacts import circular_mean, episode_onsets, force_states
from jaxdamp.analysis.response import first_harmonic
from jaxdamp.io.common import put
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import reuse_or_run

try:
    from .bed_dynamics import classify_one, optimal_config
except ImportError:  # run as a file: python experiments/<name>.py
    from bed_dynamics import classify_one, optimal_config

SETTLE, TRANSIENT = 1.0, 4.0


def settings(quick: bool) -> dict:
    if quick:
        return dict(plan=[[7.5, 1.2, 1e-3], [8.0, 1.2, 1e-3], [14.5, 1.0, 5e-4]], R=2,
                    settle=0.2, transient=0.4)
    return dict(plan=[[7.5, 8.0, 1e-3], [8.0, 10.0, 1e-3], [14.5, 7.0, 5e-4]], R=3,
                settle=SETTLE, transient=TRANSIENT)


def torus_lines(t, z, f) -> dict:
    """``f₂`` [Hz] and the share of the non-harmonic power (0 < f' < 2f) within ±2 bins of
    ``f₂``, ``f − f₂`` and ``f + f₂`` (the lines of a torus with frequencies f, f₂)."""
    sp = dyn.power_spectrum(t, z, f, method="periodogram")
    fr, p = np.asarray(sp.f), np.asarray(sp.psd)
    df = fr[1] - fr[0]
    harm = np.zeros_like(fr, bool)
    for n in range(1, int(fr[-1] / f) + 1):
        harm |= np.abs(fr - n * f) <= 2 * df
    nh = np.where(~harm & (fr > 2 * df) & (fr < 2 * f), p, 0.0)
    idx, _ = find_peaks(nh)
    i2 = idx[np.argmax(nh[idx])]
    f2 = fr[i2] if fr[i2] < f / 2 else abs(f - fr[i2])
    sel = np.zeros_like(fr, bool)
    for x in (f2, f - f2, f + f2):
        sel |= np.abs(fr - x) <= 2 * df
    return dict(f2=float(f2), three_line_share=float(nh[sel].sum() / nh.sum()),
                resolution=float(df))


def impacts(rec, cfg, f, t0, step=1) -> dict:
    """Impact measures of one run from every ``step``-th sample after ``t0`` (module doc)."""
    t = rec["t"][::step]
    keep = t >= t0
    tk = t[keep]
    nl, nf = rec["n_lid"][::step][keep], rec["n_floor"][::step][keep]
    vb, vc = rec["v_box"][::step][keep], rec["vz_cm"][::step][keep]
    gap = max(int(round(0.1 / (f * (t[1] - t[0])))), 1)  # merge gaps shorter than T/10
    on_l, on_f = episode_onsets(nl > 0, gap), episode_onsets(nf > 0, gap)
    periods = (tk[-1] - tk[0]) * f
    fs = force_states(tk, rec["force_box"][::step][keep], grain_mass(cfg) * cfg.gravity, f)
    before = np.maximum(np.r_[on_l, on_f] - 1, 0)
    ratio = vc[before] / vb[before]
    _, ph = first_harmonic(tk, rec["z_box"][::step][keep], f)
    phase = lambda i: 2 * np.pi * f * tk[i] - ph  # noqa: E731
    sep = circular_mean(phase(on_l) - circular_mean(phase(on_f)), True) % 360.0  # [0, 360)
    return dict(lid_episodes=len(on_l) / periods, floor_episodes=len(on_f) / periods,
                lid_force_hits=fs["lid_hits_per_period"],
                floor_force_hits=fs["floor_hits_per_period"],
                opposite=float(np.mean(ratio < 0)), ratio_median=float(np.median(ratio)),
                ratio_max=float(np.max(ratio)), lid_floor_separation=float(sep))


def compute(quick: bool, log, ctx):
    s = settings(quick)
    out = {}
    for f, dur, rdt in s["plan"]:
        cfg = optimal_config(dur, s["settle"], rdt)
        res = reuse_or_run(cfg, {"frequency": [f]}, ctx.raw(f"f{f:g}_R{s['R']}.h5"),
                           progress=ctx.progress, replicates=s["R"])
        rows = []
        for r in range(s["R"]):
            rec = {k: np.asarray(v[res.point(0, r)]) for k, v in res.records.items()}
            keep = rec["t"] >= s["transient"]
            zb = rec["z_box"][keep]
            Z = 0.5 * (zb.max() - zb.min())
            res.weight = grain_mass(cfg) * cfg.gravity  # classify_one's force states
            c = classify_one(res, dict(transient=s["transient"]), 0, f, r)
            row = dict(
                d1=c["z_cm"]["d1"], period=c["z_cm"]["period"],
                periodic=float(c["z_cm"]["label"] == "periodic"),
                Z_over_U=Z / cfg.primary.U,
                a_over_g=Z * (2 * np.pi * f) ** 2 / cfg.gravity,
                free_fraction=c["free_fraction"],
                floor_hits=c["floor_hits_per_period"],
                lid_clearance_min=float(np.min(cfg.box.Lz - (rec["z_highest"] - rec["z_box"])[keep]
                                               - cfg.grains[0].radius)),
                floor_empty_fraction=float(np.mean(rec["n_floor"][keep] == 0)))
            if f == 8.0:
                row.update(torus_lines(rec["t"][keep], rec["z_cm"][keep], f))
            if f == 14.5:
                row.update({k: v for k, v in impacts(rec, cfg, f, s["transient"]).items()})
                row.update({f"{k}_coarse": v
                            for k, v in impacts(rec, cfg, f, s["transient"], 2).items()})
            rows.append(row)
        out[f] = dict(rows=rows, wall=float(res.summary["wall_time"]), duration=dur,
                      record_dt=rdt)
        log(f"{f:g} Hz: {out[f]['wall']:.0f} s")
    return out, lambda path, prov: record(out, s, path, prov)


def record(out, s, path, prov):
    wall = sum(v["wall"] for v in out.values())
    with scaffold.data_file(path, dict(prov, sweep_wall_s=wall), settings=s) as h:
        for f, v in out.items():
            g = h.create_group(f"f{f:g}")
            g.attrs.update(frequency=f, duration=v["duration"], record_dt=v["record_dt"])
            for k in v["rows"][0]:
                unit = ("Hz" if k in ("f2", "resolution") else "m" if k.startswith("lid_clear")
                        else "deg" if "separation" in k else "1")
                put(g, k, [row[k] for row in v["rows"]], unit, dims="replicate")


def report(data, out):
    s, prov = data.attrs["settings"], data.attrs
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(10, 4))
    g = data["f14.5"]
    x = np.arange(len(g["lid_episodes"]))
    for key, lab in (("lid_episodes", "lid episodes"), ("floor_episodes", "floor episodes"),
                     ("lid_force_hits", "lid force-state hits, 0.5 ms"),
                     ("lid_force_hits_coarse", "lid force-state hits, 1 ms")):
        a1.plot(x, g[key], "o-", label=lab)
    a1.set(xlabel="bed", ylabel="impacts per period [-]", xticks=x)
    a1.set_title("14.5 Hz: episodes against force-state counts", fontsize=9)
    a1.legend(fontsize=7)
    g8 = data["f8"]
    a2.bar(np.arange(len(g8["three_line_share"])), g8["three_line_share"])
    a2.set(xlabel="bed", ylabel="share of non-harmonic power in f₂, f−f₂, f+f₂ [-]",
           ylim=(0, 1))
    a2.set_title("8 Hz: the torus' lines", fontsize=9)
    scaffold.save_figure(fig, out)

    def cell(group, key, fmt=".3g"):
        return scaffold.pm(*scaffold.mean_se(np.asarray(data[group][key])), fmt, ".2g")

    lines = scaffold.head("Details of thesis ch. 4 at 7.5, 8 and 14.5 Hz, with replicates", prov,
                          prov["sweep_wall_s"])
    lines += [f"`sanchez2012-optimal` (Lz = 0.1225 m, C = 7.6 N s/m), {s['R']} independently "
              f"poured beds per frequency, settled {s['settle']} s, the first {s['transient']} s "
              "dropped; mean ± SE over the beds.", ""]
    lines += scaffold.table(
        ["f [Hz]", "run [s]", "Z/U", "a/g", "z_cm periodic (beds)", "d1", "free fraction",
         "floor hits/T", "smallest lid clearance [m]", "no grain on the floor"],
        [[f"{data[k].attrs['frequency']:g}", f"{data[k].attrs['duration']:g}",
          cell(k, "Z_over_U"), cell(k, "a_over_g"),
          f"{int(np.sum(data[k]['periodic']))} of {len(data[k]['periodic'])}", cell(k, "d1"),
          cell(k, "free_fraction"), cell(k, "floor_hits"), cell(k, "lid_clearance_min"),
          cell(k, "floor_empty_fraction")] for k in ("f7.5", "f8", "f14.5")])
    lines += ["", f"**8 Hz lines.** f₂ = {cell('f8', 'f2', '.4g')} Hz (resolution "
              f"{float(np.mean(g8['resolution'])):.3g} Hz); share of the non-harmonic power in "
              f"f₂, f − f₂, f + f₂: {cell('f8', 'three_line_share')}.", "",
              "**14.5 Hz impacts.** Episodes per period (gaps < T/10 merged): lid "
              f"{cell('f14.5', 'lid_episodes', '.4g')}, floor "
              f"{cell('f14.5', 'floor_episodes', '.4g')}; lid–floor separation "
              f"{cell('f14.5', 'lid_floor_separation', '.4g')}°; bed and box moving in "
              f"opposite directions just before {cell('f14.5', 'opposite')} of the impacts, "
              f"velocity ratio median {cell('f14.5', 'ratio_median', '.4g')}, largest "
              f"{cell('f14.5', 'ratio_max', '.3g')}. Force-state hits per period (the counter "
              f"of `bed_dynamics`): lid {cell('f14.5', 'lid_force_hits', '.3g')} at 0.5 ms "
              f"samples against {cell('f14.5', 'lid_force_hits_coarse', '.3g')} at 1 ms; "
              f"episodes {cell('f14.5', 'lid_episodes_coarse', '.4g')} at 1 ms: the force "
              "states count contact chatter that depends on the sampling, the episodes do not."]
    scaffold.write_summary(out, lines)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
