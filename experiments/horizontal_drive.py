"""The thesis damper driven horizontally against the same damper driven vertically (issue 16).

    python experiments/horizontal_drive.py            # ~10 min on 2 cores
    python experiments/horizontal_drive.py --quick    # ~1 min, test-sized

``sanchez2012-optimal`` driven along ``z`` or ``x`` (``Config.direction``; gravity along −z): per
direction a stepped-sine FRF on ``R`` independently poured beds, per bed a 1-DOF fit (``M_ef``,
``C_ef``, thesis eq. 2.1.21; relative residuals) and the peak (parabola through the three
largest points), compared by the Welch 95 % interval. Writes ``data.h5``, figure, summary.
"""

from __future__ import annotations

import numpy as np

from jaxdamp.analysis.response import fit_frf_replicates, frf_amplitude
from jaxdamp.analysis.stats import replicate_extrema, welch
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.figures.response import draw_replicates
from jaxdamp.physics.model import grain_mass
from jaxdamp.studies import scaffold
from jaxdamp.studies.grid import steady_replicates
from jaxdamp.studies.sweep import reuse_or_run

DIRECTIONS = {"vertical": (0.0, 0.0, 1.0), "horizontal": (1.0, 0.0, 0.0)}
#: per-bed quantities compared between the directions: label, key, unit, scale in the summary
QUANTITIES = (("M_ef [kg]", "M_ef", "kg", 1.0), ("C_ef [N s/m]", "C_ef", "N s/m", 1.0),
              ("peak Z [mm]", "Z_peak", "m", 1e3), ("peak frequency [Hz]", "f_peak", "Hz", 1.0))


def settings(quick: bool) -> dict:
    if quick:
        return dict(f=[13.0, 15.0, 17.0], duration={"vertical": 0.5, "horizontal": 0.5}, R=2,
                    settle=0.3)
    # horizontal: ~3x less damped (envelope ~ 0.5 s); at 2.5 s only 10 of 30 runs were steady
    return dict(f=[11.0, 12.0, 13.0, 14.0, 14.5, 15.0, 15.5, 16.0, 17.0, 19.0],
                duration={"vertical": 2.5, "horizontal": 6.0}, R=3, settle=None)


def verdict(d, h, same="same", above="higher", below="lower") -> str:
    """``same`` where the 95 % interval ``d ± h`` holds 0, else ``above``/``below`` by sign."""
    if not np.isfinite(h):
        return "no interval"
    return same if abs(d) <= h else above if d > 0 else below


def compare(runs) -> dict:
    """Per quantity horizontal − vertical across beds and its Welch 95 % half-width."""
    return {k: welch(runs["horizontal"][k], runs["vertical"][k]) for _, k, _, _ in QUANTITIES}


def compute(quick: bool, log, ctx):
    s = settings(quick)
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {} if s["settle"] is None else {"numerics.settle_time": s["settle"]})
    p, m_p, f, runs = cfg.primary, grain_mass(cfg), np.asarray(s["f"]), {}
    for name, d in DIRECTIONS.items():
        T = s["duration"][name]
        c = apply_overrides(cfg, {"direction": list(d), "numerics.duration": T})
        res = reuse_or_run(c, {"frequency": s["f"]}, ctx.raw(f"{name}_{T:g}s_R{s['R']}.h5"),
                           progress=ctx.progress, echo=None, replicates=s["R"])
        st = steady_replicates(res, "amplitude", "granular_loss_per_cycle")
        Z, W = st.values  # (F, R)
        fit = fit_frf_replicates(f, Z, p.U, p.K, p.M + m_p, p.C, residuals="relative")
        peak = replicate_extrema(f, Z, "max")
        runs[name] = dict(Z=Z, W=W, fit=fit, M_ef=fit["M_reps"], C_ef=fit["C_reps"],
                          stationary=int(st.stationary.sum()), f_peak=peak.x, Z_peak=peak.y,
                          wall=st.wall)
    result = dict(settings=s, f=f, primary=dict(M=p.M, K=p.K, C=p.C, U=p.U, m_p=m_p), runs=runs,
                  cmp=compare(runs))
    return result, lambda o, prov: record(result, o, prov)


def record(r, out, prov):
    with scaffold.data_file(out, prov, settings=r["settings"], primary=r["primary"],
                            fit="relative residuals (fit_frf_replicates), one fit per bed") as h5:
        h5.create_dataset("f", data=r["f"]).attrs["units"] = "Hz"
        for name, d in r["runs"].items():
            g = h5.create_group(name)
            g.attrs.update(direction=list(DIRECTIONS[name]), stationary=d["stationary"],
                           wall_time=d["wall"])
            for k, unit in [("Z", "m"), ("W", "J")] + [(k, u) for _, k, u, _ in QUANTITIES]:
                g.create_dataset(k, data=d[k]).attrs["units"] = unit


def report(data, out):
    s, p, f = data.attrs["settings"], data.attrs["primary"], data["f"]
    runs, M_dead = {name: data[name] for name in DIRECTIONS}, p["M"] + p["m_p"]
    fig, ax = scaffold.subplots()
    fine = np.linspace(f.min(), f.max(), 300)
    for name, d in runs.items():
        M_ef, C_ef = np.mean(d["M_ef"]), np.mean(d["C_ef"])  # fit_frf_replicates' M_ef, C_ef
        bar = draw_replicates(ax, f, 1e3 * d["Z"], fmt="o", ms=4, capsize=2,
                              label=f"{name} drive (mean of {d['Z'].shape[1]} beds ± 2 SE)")
        ax.plot(fine, 1e3 * frf_amplitude(fine, M_ef, p["K"], C_ef, p["U"]), "-", lw=1,
                color=bar[0].get_color(),
                label=f"{name}: fit M_ef {M_ef:.3g} kg, C_ef {C_ef:.3g} N s/m")
    ax.plot(fine, 1e3 * frf_amplitude(fine, M_dead, p["K"], p["C"], p["U"]), "k:", lw=1,
            label="grains as dead mass (M + m_p, C)")
    ax.set(xlabel="drive frequency f [Hz]", ylabel="amplitude of the primary Z [mm]")
    ax.set_title("thesis damper, U = 4.5 mm: vertical vs horizontal base motion", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    scaffold.save_figure(fig, out)
    cmp = compare(runs)
    L = [*scaffold.head("Horizontal against vertical base motion (issue 16)", data.attrs),
         f"`sanchez2012-optimal` (M = {p['M']} kg, K = {p['K']:g} N/m, C = {p['C']} N s/m, m_p "
         f"= {p['m_p']:.4g} kg; grains as dead mass: M + m_p = {M_dead:.4g} kg), U = "
         f"{1e3 * p['U']:g} mm along z or x (gravity along −z), **{s['R']} independently "
         "poured beds** per frequency; runs without a detected steady state use the final "
         "window (a lower bound while Z grows). Fits per bed, **relative residuals**.", ""]
    L += scaffold.table(["quantity", *runs, "horizontal − vertical", "verdict"], [
        [label] + [scaffold.pm(*scaffold.mean_se(d[key]), 4, scale=k) for d in runs.values()]
        + [scaffold.pm(*cmp[key], "+.3g", scale=k),
           verdict(*cmp[key], "same", "horizontal higher", "horizontal lower")]
        for label, key, _, k in QUANTITIES] + [
        [what, *(fmt(k, d) for k, d in runs.items()), "", ""] for what, fmt in (
            ("run length [s]", lambda k, d: f"{s['duration'][k]:g}"),
            ("steady state detected", lambda k, d: f"{d.attrs['stationary']} of {d['Z'].size}"),
            ("compute [s], settling excluded", lambda k, d: f"{d.attrs['wall_time']:.0f}"))])
    L += ["", "## Amplitude per frequency (mean ± SE over beds) [mm]", ""] + scaffold.table(
        ["f [Hz]", *runs], [[f"{x:g}", *(scaffold.pm(*scaffold.mean_se(d["Z"][j]), 4, scale=1e3)
                                      for d in runs.values())] for j, x in enumerate(f)])
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)

if __name__ == "__main__":
    main()
