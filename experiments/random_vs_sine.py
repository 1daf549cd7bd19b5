"""Random excitation against stepped sine on the thesis damper (issue 16).

    python experiments/random_vs_sine.py            # ~30 min on 2 cores
    python experiments/random_vs_sine.py --quick    # ~2 min, test-sized

``sanchez2012-optimal`` (250 grains, Lz = 0.1225 m), ``R`` independently poured beds per level
and point, under **random** base motion (``jaxdamp random``: flat acceleration density over
10–20 Hz at several levels, random-phase multisine; H1 = G_uz/G_uu over whole periods after the
MSER-detected start, coherence, |H1| per realisation) and **stepped sine** (``jaxdamp frf``:
amplitudes ``U`` at 14–16 Hz, lines of the multisine). The FRF of this nonlinear damper depends
on the amplitude: a random level is compared with the ``U`` whose resonant Z is within 25 % of
√2 z_rms(random); verdict per pair and line: the Welch 95 % interval of |H1| − Z/U.

Writes ``data.h5``, ``figure.png``, ``summary.md``.
"""

from __future__ import annotations

import numpy as np

from jaxdamp.analysis.stats import welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.figures import random_figure
from jaxdamp.figures.response import draw_replicates
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
SPECTRA = ("f", "H", "mag_se", "coherence")  # each random level's H1 spectrum, for the figure


def settings(quick: bool) -> dict:
    if quick:
        return dict(band=(12.0, 17.0), S=1.0, resolution=1.0, scales=[20.0], random_s=2.5,
                    U=[0.0015], f=[14.0, 15.0], sine_s=0.5, R=2, settle=0.3)
    return dict(band=(10.0, 20.0), S=1.0, resolution=0.25, scales=[5.0, 20.0, 80.0],
                random_s=16.0, U=[0.00075, 0.0015, 0.003], f=[14.0, 14.5, 15.0, 15.5, 16.0],
                sine_s=2.5, R=3, settle=None)


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {} if s["settle"] is None
                          else {"numerics.settle_time": s["settle"]})
    rcfg = apply_overrides(cfg, {"random.psd": [[x, s["S"]] for x in s["band"]],
                                 "random.resolution": s["resolution"]})
    ran = rnd.measure(rcfg, s["scales"], duration=s["random_s"], replicates=s["R"],
                      out=ctx.raw(f"random_R{s['R']}.h5"), reuse=True, progress=ctx.progress,
                      echo=None)
    res = reuse_or_run(apply_overrides(cfg, {"numerics.duration": s["sine_s"]}),
                       {"primary.U": s["U"], "frequency": s["f"]},
                       ctx.raw(f"sine_R{s['R']}.h5"), progress=ctx.progress, echo=None,
                       replicates=s["R"])
    st = steady_replicates(res, "amplitude")
    Z, f, levels = st.values[0], np.asarray(s["f"]), ran.levels  # Z: (U, F, R)
    # random: |H1| per realisation at the sine's frequencies (lines of the multisine)
    lines = [[int(np.argmin(np.abs(lev["f"] - x))) for x in f] for lev in levels]
    assert all(np.allclose(lev["f"][k], f) for lev, k in zip(levels, lines)), "sine f: not lines"
    at = lambda key: np.array([lev[key][..., k] for lev, k in zip(levels, lines)])  # noqa: E731
    every = lambda key: np.array([lev[key] for lev in levels])  # noqa: E731
    result = dict(settings=s, f=f, U=np.asarray(s["U"]), Z=Z, scales=np.asarray(s["scales"]),
                  ratio=Z / np.asarray(s["U"])[:, None, None],
                  mag=np.abs(at("H_each")).transpose(0, 2, 1), mag_pooled=np.abs(at("H")),
                  coh=at("coherence"), z_rms=every("z_rms"), a_rms=every("a_rms"),
                  spectra={k: np.abs(every(k)) for k in SPECTRA},  # (level, line)
                  run_stats=dict(sine_stationary=int(st.stationary.sum()),
                                 random_stationary=int(every("stationary").sum()),
                                 segments=every("segments").tolist(), sine_wall_s=st.wall,
                                 random_wall_s=float(ran.sweep.summary["wall_time"])))
    return result, lambda out, prov: record(result, out, prov)


def record(r, out, prov):
    with scaffold.data_file(out, prov, settings=r["settings"], **r["run_stats"],
                            convention="amplitudes matched by the RMS of z: sqrt(2) "
                            "z_rms(random) vs the sine's resonant Z, within 25 %") as h:
        for k, unit in (("f", "Hz"), ("U", "m"), ("Z", "m"), ("ratio", "1"), ("mag", "1"),
                        ("mag_pooled", "1"), ("coh", "1"), ("z_rms", "m"), ("a_rms", "m/s^2"),
                        ("scales", "1")):
            h.create_dataset(k, data=r[k]).attrs["units"] = unit
        for k, unit in zip(SPECTRA, ("Hz", "1", "1", "1")):  # H: the pooled |H1|
            h.create_dataset(f"spectra/{k}", data=r["spectra"][k]).attrs.update(
                units=unit, dims="level, line")


def report(data, out):
    s, f, prov = data.attrs["settings"], data["f"], data.attrs
    U, scales, z_rms, ratio = data["U"], data["scales"], data["z_rms"], data["ratio"]
    R, Z_res = data["Z"].shape[-1], data["Z"].mean(axis=-1).max(axis=1)  # each U's resonant Z
    q = np.sqrt(2.0) * z_rms.mean(axis=1)[:, None] / Z_res  # (level, U): the amplitude match
    pairs = [(i, u, q[i, u], [welch(data["mag"][i, j], ratio[u, j]) for j in range(len(f))])
             for i, u in zip(*np.nonzero(np.abs(q - 1.0) <= MATCH))]
    if "spectra" in data:  # files before 2026-12-05 hold |H1| at the sine's lines only
        fig = random_figure(
            [{k: v[i] for k, v in data["spectra"].items()} for i in range(len(scales))],
            [f"random, a_rms {data['a_rms'][i]:.3g} m/s², √2 z_rms "
             f"{1e3 * np.sqrt(2) * z_rms[i].mean():.3g} mm" for i in range(len(scales))],
            log=False, title="thesis damper: H1 from random base motion vs stepped sine (± 2 SE)")
        for u, Uu in enumerate(U):
            draw_replicates(fig.axes[0], f, ratio[u], fmt="s", ms=4, capsize=2, label=f"stepped "
                            f"sine, U = {1e3 * Uu:g} mm (resonant Z {1e3 * Z_res[u]:.3g} mm)")
        fig.axes[0].legend(fontsize=6.5)
        fig.set_layout_engine("none")  # laid out by save_figure (tight), not constrained
        scaffold.save_figure(fig, out)

    join = lambda xs, k=1.0: ", ".join(f"{k * x:g}" for x in xs)  # noqa: E731
    L = [*scaffold.head("Random excitation against stepped sine (issue 16)", prov),
         f"Random base motion: flat acceleration density {s['S']} (m/s²)²/Hz × scale "
         f"{join(scales)} over {s['band'][0]:g}–{s['band'][1]:g} Hz, lines every "
         f"{s['resolution']} Hz (period {1 / s['resolution']:g} s), {s['random_s']} s per run; "
         f"stepped sine at U = {join(U, 1e3)} mm × f = {join(f)} Hz, {s['sine_s']} s per run. "
         f"**{R} independent realisations** per level and point. Random: stationary start "
         f"detected (MSER on the mean square of z − u) in {prov['random_stationary']} of "
         f"{len(scales) * R} runs; periods averaged per level: {join(prov['segments'])}. Sine: "
         f"steady state detected in {prov['sine_stationary']} of {data['Z'].size} runs (the "
         f"others: fixed final window). Compute: random {prov['random_wall_s']:.0f} s, sine "
         f"{prov['sine_wall_s']:.0f} s (settling excluded).", "",
         "Convention: amplitudes matched by the RMS of the primary's displacement, "
         f"√2 z_rms(random) against the sine's resonant Z, within {100 * MATCH:g} %; "
         "verdict: Welch 95 % interval of |H1| − Z/U across realisations.", "",
         "## Random levels", ""]
    L += scaffold.table(["scale", "a_rms [m/s²]", "√2 z_rms [mm]"]
                        + [f"\\|H1\\| {x:g} Hz (γ²)" for x in f], [
        [f"{sc:g}", f"{data['a_rms'][i]:.3g}",
         scaffold.pm(*scaffold.mean_se(np.sqrt(2) * z_rms[i]), 3, scale=1e3)]
        + [f"{scaffold.pm(m, e, 3)} ({c:.3f})"
           for m, e, c in zip(*scaffold.mean_se(data["mag"][i]), data["coh"][i])]
        for i, sc in enumerate(scales)])
    L += ["", "## Stepped sine", ""] + scaffold.table(
        ["U [mm]", "resonant Z [mm]"] + [f"Z/U {x:g} Hz" for x in f],
        [[f"{1e3 * Uu:g}", f"{1e3 * Z_res[u]:.3g}"]
         + [scaffold.pm(m, e, 3) for m, e in zip(*scaffold.mean_se(ratio[u]))]
         for u, Uu in enumerate(U)])
    said = lambda d, h: verdict(d, h, "agree", "random above", "random below")  # noqa: E731
    rows = [[f"{scales[i]:g}", f"{1e3 * U[u]:g}", f"{qi:.2f}"]
            + [f"{scaffold.pm(d, h, '+.3g')} ({said(d, h)})" for d, h in dh]
            for i, u, qi, dh in pairs]
    agree = sum(c.endswith("(agree)") for row in rows for c in row)
    L += ["", "## Matched pairs", ""] + (scaffold.table(
        ["scale", "U [mm]", "√2 z_rms / Z_res"] + [f"{x:g} Hz: \\|H1\\| − Z/U" for x in f], rows)
        + ["", "Matched lines that agree within the 95 % interval: "
              f"{agree} of {len(f) * len(rows)}."]
        if rows else [f"No random level's √2 z_rms lies within {100 * MATCH:g} % of a sine's "
                      "resonant Z: no matched pair (see the tables)."])
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
