"""Random excitation against stepped sine on the thesis damper (issue 16: "random vs stepped
sine").

    python experiments/random_vs_sine.py            # ~30 min on 2 cores
    python experiments/random_vs_sine.py --quick    # ~2 min, test-sized

The same damper (``sanchez2012-optimal``: 250 grains, Lz = 0.1225 m, on its 1-DOF primary)
under two lab excitations:

* **random** (``jaxdamp random``): band-limited random base motion, flat base acceleration
  density over 10–20 Hz at several levels, a random-phase multisine with lines every 0.25 Hz
  (period 4 s), ``R`` realisations per level (independently poured beds, each with its own
  phases); H1 = G_uz/G_uu pooled over whole periods after the stationary start detected by
  MSER, its coherence, and the SE of |H1| between realisations;
* **stepped sine** (``jaxdamp frf``): base amplitudes ``U`` at 14–16 Hz (lines of the random
  test), ``R`` beds per point, each run's steady state detected by MSER.

The damper is nonlinear: its FRF depends on the vibration amplitude, and a random response
has a distribution of amplitudes, not one. **Amplitude matching convention**: a random level
is set beside the sine amplitude ``U`` whose resonant response has the same RMS of the
primary's displacement ``z``, i.e. ``√2 z_rms(random) ≈ Z(sine, resonance)``; a pair is
compared when the two differ by less than 25 %. Verdict per matched pair and line: the Welch
95 % interval of |H1| − Z/U across realisations.

Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import os

import numpy as np

from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.studies import random as rnd
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_replicates
from jaxdamp.studies.sweep import reuse_or_run

try:
    from .horizontal_drive import verdict
except ImportError:  # run as a file: python experiments/<name>.py
    from horizontal_drive import verdict

#: amplitudes may differ by this fraction for a random level and a sine amplitude to be compared
MATCH = 0.25


def settings(quick: bool) -> dict:
    if quick:
        return dict(band=(12.0, 17.0), S=1.0, resolution=1.0, scales=[20.0], random_s=2.5,
                    U=[0.0015], f=[14.0, 15.0], sine_s=0.5, R=2, settle=0.3)
    return dict(band=(10.0, 20.0), S=1.0, resolution=0.25, scales=[5.0, 20.0, 80.0],
                random_s=16.0, U=[0.00075, 0.0015, 0.003], f=[14.0, 14.5, 15.0, 15.5, 16.0],
                sine_s=2.5, R=3, settle=None)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = presets.get("sanchez2012-optimal")
    if s["settle"] is not None:
        cfg = apply_overrides(cfg, {"numerics.settle_time": s["settle"]})
    lo, hi = s["band"]
    rcfg = apply_overrides(cfg, {"random.psd": [[lo, s["S"]], [hi, s["S"]]],
                                 "random.resolution": s["resolution"]})
    log(f"random: {lo}–{hi} Hz, S = {s['S']} (m/s²)²/Hz × {s['scales']}, "
        f"{s['random_s']} s, R = {s['R']}")
    ran = rnd.measure(rcfg, s["scales"], duration=s["random_s"], replicates=s["R"],
                      out=ctx.raw(f"random_R{s['R']}.h5"), reuse=True, progress=ctx.progress,
                      echo=None)
    log(f"stepped sine: U = {s['U']} m × f = {s['f']} Hz, {s['sine_s']} s, R = {s['R']}")
    res = reuse_or_run(apply_overrides(cfg, {"numerics.duration": s["sine_s"]}),
                       {"primary.U": s["U"], "frequency": s["f"]},
                       ctx.raw(f"sine_R{s['R']}.h5"), progress=ctx.progress, echo=None,
                       replicates=s["R"])
    st = steady_replicates(res, "amplitude")
    Z = st.values[0]  # (U, F, R)
    ratio = Z / np.asarray(s["U"])[:, None, None]
    f = np.asarray(s["f"])
    # random: |H1| per realisation at the sine's frequencies (lines of the multisine)
    lines = [[int(np.argmin(np.abs(lev["f"] - x))) for x in f] for lev in ran.levels]
    for lev, k in zip(ran.levels, lines):
        assert np.allclose(lev["f"][k], f), "the sine frequencies must be lines of the multisine"
    mag = np.array([np.abs(lev["H_each"][:, k]).T for lev, k in zip(ran.levels, lines)])
    mag_pooled = np.array([np.abs(lev["H"][k]) for lev, k in zip(ran.levels, lines)])
    coh = np.array([lev["coherence"][k] for lev, k in zip(ran.levels, lines)])
    z_rms = np.array([lev["z_rms"] for lev in ran.levels])  # (P, R)
    Z_res = Z.mean(axis=-1).max(axis=1)  # each U's resonant amplitude
    pairs = []
    for i, z in enumerate(z_rms):
        amp = np.sqrt(2.0) * z.mean()
        pairs += [dict(level=i, U=u, amp=amp, rows=[welch(mag[i, j], ratio[u, j])
                                                     for j in range(len(f))])
                  for u in range(len(s["U"])) if abs(amp / Z_res[u] - 1.0) <= MATCH]
    result = dict(settings=s, f=f, U=np.asarray(s["U"]), Z=Z, ratio=ratio, mag=mag,
                  mag_pooled=mag_pooled, coh=coh, z_rms=z_rms, a_rms=np.array(
                      [lev["a_rms"] for lev in ran.levels]), Z_res=Z_res,
                  j_res=Z.mean(axis=-1).argmax(axis=1), pairs=pairs,
                  stationary=int(st.stationary.sum()), runs=int(Z.size),
                  fallback=st.fallback[0],
                  random_stationary=int(sum(lev["stationary"].sum() for lev in ran.levels)),
                  segments=[lev["segments"] for lev in ran.levels], levels=ran.levels,
                  period=ran.period,
                  wall=dict(random=float(ran.sweep.summary["wall_time"]), sine=st.wall))
    return result, lambda out, prov: write(result, out, prov)


def write(r, out, prov):
    s, f = r["settings"], r["f"]
    with scaffold.data_file(out, prov, convention="amplitudes matched by the RMS of z: sqrt(2) "
                            "z_rms(random) vs the sine's resonant Z, within 25 %") as h:
        for k, unit in (("f", "Hz"), ("U", "m"), ("Z", "m"), ("ratio", "1"), ("mag", "1"),
                        ("mag_pooled", "1"), ("coh", "1"), ("z_rms", "m"), ("a_rms", "m/s^2")):
            h.create_dataset(k, data=r[k]).attrs["units"] = unit
        h.create_dataset("scales", data=np.asarray(s["scales"])).attrs["units"] = "1"
    from jaxdamp.figures import random_figure

    labels = [f"random, a_rms {r['a_rms'][i]:.3g} m/s², √2 z_rms "
              f"{1e3 * np.sqrt(2) * r['z_rms'][i].mean():.3g} mm" for i in range(len(r["levels"]))]
    fig = random_figure(r["levels"], labels, log=False,
                        title="thesis damper: H1 from random base motion vs stepped sine (± 2 SE)")
    ax = fig.axes[0]
    for u, U in enumerate(r["U"]):
        m, e = scaffold.mean_se(r["ratio"][u])
        ax.errorbar(r["f"], m, yerr=2 * np.nan_to_num(e), fmt="s", ms=4, capsize=2,
                    label=f"stepped sine, U = {1e3 * U:g} mm (resonant Z "
                          f"{1e3 * r['Z_res'][u]:.3g} mm)")
    ax.legend(fontsize=6.5)
    fig.savefig(os.path.join(out, "figure.png"), dpi=120)

    L = [*scaffold.head("Random excitation against stepped sine (issue 16)", prov),
         f"Damper: `sanchez2012-optimal` (250 grains, Lz = 0.1225 m). Random base motion: flat "
         f"acceleration density {s['S']} (m/s²)²/Hz × scale "
         f"{', '.join(f'{x:g}' for x in s['scales'])} "
         f"over {s['band'][0]:g}–{s['band'][1]:g} Hz, random-phase multisine with lines every "
         f"{s['resolution']} Hz (period {r['period']:g} s), {s['random_s']} s per run; stepped "
         f"sine at U = {', '.join(f'{1e3 * u:g}' for u in s['U'])} mm × f = "
         f"{', '.join(f'{x:g}' for x in f)} Hz, {s['sine_s']} s per run. **{s['R']} independent "
         f"realisations** per level and point (independently poured beds; each random "
         f"realisation its own phases). Random: stationary start detected (MSER on the mean "
         f"square of z − u) in {r['random_stationary']} of {len(s['scales']) * s['R']} runs; "
         f"periods averaged per level: {', '.join(map(str, r['segments']))}. Sine: steady "
         f"state detected in {r['stationary']} of {r['runs']} runs (the others: fixed final "
         f"window). Compute: random {r['wall']['random']:.0f} s, sine {r['wall']['sine']:.0f} s "
         "(settling excluded).", "",
         "Convention: amplitudes matched by the RMS of the primary's displacement, "
         f"√2 z_rms(random) against the sine's resonant Z, within {100 * MATCH:g} %; "
         "frequencies matched exactly (the sine's frequencies are lines of the multisine). "
         "Verdict: Welch 95 % interval of |H1| − Z/U across realisations (|H1| of each "
         "realisation from its own periods).", "",
         "## Random levels", ""]
    L += scaffold.table(["scale", "a_rms [m/s²]", "√2 z_rms [mm]"]
                        + [f"\\|H1\\| {x:g} Hz (γ²)" for x in f], [
        [f"{sc:g}", f"{r['a_rms'][i]:.3g}",
         scaffold.pm(*scaffold.mean_se(np.sqrt(2) * r["z_rms"][i]), 3, scale=1e3)]
        + [f"{scaffold.pm(m, e, 3)} ({c:.3f})"
           for m, e, c in zip(*scaffold.mean_se(r["mag"][i]), r["coh"][i])]
        for i, sc in enumerate(s["scales"])])
    L += ["", "## Stepped sine", ""]
    L += scaffold.table(["U [mm]", "resonant Z [mm]"] + [f"Z/U {x:g} Hz" for x in f], [
        [f"{1e3 * U:g}", f"{1e3 * r['Z_res'][u]:.3g}"]
        + [scaffold.pm(m, e, 3) for m, e in zip(*scaffold.mean_se(r["ratio"][u]))]
        for u, U in enumerate(s["U"])])
    L += ["", "## Matched pairs", ""]
    if not r["pairs"]:
        L.append(f"No random level's √2 z_rms lies within {100 * MATCH:g} % of a sine's "
                 "resonant Z: no matched pair (see the tables).")
    else:
        said = [[verdict(d, h, "agree", "random above", "random below") for d, h in p["rows"]]
                for p in r["pairs"]]
        L += scaffold.table(["scale", "U [mm]", "√2 z_rms / Z_res"]
                            + [f"{x:g} Hz: \\|H1\\| − Z/U" for x in f], [
            [f"{s['scales'][p['level']]:g}", f"{1e3 * s['U'][p['U']]:g}",
             f"{p['amp'] / r['Z_res'][p['U']]:.2f}"]
            + [f"{scaffold.pm(d, h, '+.3g')} ({v})" for (d, h), v in zip(p["rows"], said_p)]
            for p, said_p in zip(r["pairs"], said)])
        L += ["", "Matched lines that agree within the 95 % interval: "
              f"{sum(v.count('agree') for v in said)} of {sum(map(len, said))}."]
    L += ["", "Figure: `figure.png` (|H1| ± 2 SE of each random level with its coherence, sine "
          "points ± 2 SE). Data: `data.h5`."]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute)


if __name__ == "__main__":
    main()
