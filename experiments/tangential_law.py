"""Does the tangential law matter at the thesis optimum? The viscous law against the
Hertz–Mindlin spring with history, the scoreboard's systematic budget's tangential-law term
(issue 39).

    python experiments/tangential_law.py          # 3 frequencies x 3 beds x 2 laws, 2.5 s
                                                   # (~12 min on 2 cores)
    python experiments/tangential_law.py --quick   # 2 frequencies x 2 beds, 0.7 s (~3 min)

``sanchez2012-optimal`` (250 grains, μ = 0.3, Lz = 0.1225 m, C = 7.6 N s/m) near resonance,
with the systematic budget's protocol (``experiments/systematics.py``: its frequencies, beds,
settling and run length; steady means from the MSER start, else the final 10 %), once with the
thesis' viscous tangential force capped by Coulomb and once with ``tangential_law =
"mindlin"`` (its dashpot follows the normal one; the thesis' ``γ_s`` is unused). Per bed: the
resonant amplitude ``Z_res`` and frequency ``f_res`` (parabola in log Z through the largest
sample), the amplitude ``Z`` averaged over the frequencies, and the loss per cycle at 15 Hz.
The beds of the two laws share seeds but settle under their own law, so the comparison is
unpaired: the relative shift Mindlin / viscous − 1 with its Welch 95 % interval
(:func:`experiments.systematics.shift`). The scoreboard takes it as the budget's
``tangential_law`` term (:func:`experiments.systematics.budget` reads this study's
``data.h5``). It also answers, for this damper, whether the thesis' conclusions depend on the
tangential model.

Writes ``data.h5``, ``figure.png`` and ``summary.md`` in ``--out``; raw sweeps in
``--out/raw``.
"""

from __future__ import annotations

import numpy as np

from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.io.common import put
from jaxdamp.studies import scaffold
from jaxdamp.studies.sweep import reuse_or_run

try:  # imported as experiments.tangential_law (the tests), or run as a script
    from experiments import systematics as sy
except ImportError:
    import systematics as sy

LAWS = ("viscous", "mindlin")
#: per-bed quantities: name, unit, label
QUANTITIES = (("Z_res", "m", "resonant amplitude Z_res"),
              ("f_res", "Hz", "resonance frequency f_res"),
              ("Z", "m", "amplitude averaged over the frequencies Z"),
              ("loss", "J", "granular loss per cycle at the frequency nearest 15 Hz"))


def compute(quick: bool, log, ctx):
    s = sy.settings(quick)
    freqs, R = list(s["freqs"]), s["R"]
    k15 = int(np.argmin(np.abs(np.asarray(freqs) - 15.0)))
    out = {}
    for law in LAWS:
        cfg = sy.thesis_config(s, s["protocol"], tangential_law=law)
        res = reuse_or_run(cfg, {"frequency": freqs}, ctx.raw(f"thesis_{law}_R{R}.h5"),
                           progress=ctx.progress, replicates=R)
        Z = sy._protocol_values(res, freqs, "amplitude")
        f_res, Z_res = sy._peaks(freqs, Z)
        loss = sy._protocol_values(res, [freqs[k15]], "granular_loss_per_cycle")[0]
        out[law] = dict(Z=Z, Z_res=Z_res, f_res=f_res, Z_mean=Z.mean(axis=0), loss=loss)
        log(f"{law}: Z_res/U {Z_res.mean() / 0.0045:.3f}, f_res {f_res.mean():.3f} Hz")
    return out, lambda o, prov: record(out, s, o, prov)


def record(result: dict, s: dict, out: str, prov: dict) -> None:
    with scaffold.data_file(out, prov, settings=s, preset=sy.THESIS) as h:
        put(h, "frequency", s["freqs"], "Hz")
        for law, r in result.items():
            g = h.create_group(law)
            put(g, "Z", r["Z"], "m", dims="frequency, replicate")
            for k, unit in (("Z_res", "m"), ("f_res", "Hz"), ("Z_mean", "m"), ("loss", "J")):
                put(g, k, r[k], unit, dims="replicate")


def shifts(out: str) -> tuple[dict, dict]:
    """``(values, shifts)`` of the ``data.h5`` in ``out``: per law the per-bed values of
    :data:`QUANTITIES` (:func:`experiments.systematics._stored_tangential`, the budget's own
    reader) and, per quantity, Mindlin against viscous (:func:`experiments.systematics.shift`,
    unpaired)."""
    import os

    v = sy._stored_tangential(os.path.join(out, "data.h5"))
    return v, {q: sy.shift(v["mindlin"][q], v["viscous"][q], paired=False)
               for q, _, _ in QUANTITIES}


def report(data, out) -> None:
    s, f = data.attrs["settings"], np.asarray(data["frequency"])
    values, sh = shifts(out)
    U = 0.0045
    fig, (a1, a2) = scaffold.subplots(1, 2, figsize=(11, 4.2))
    for j, law in enumerate(LAWS):
        Z = np.asarray(data[law]["Z"]) / U
        for r in range(Z.shape[1]):
            a1.plot(f + 0.02 * (j - 0.5), Z[:, r], "os"[j] + "-", color=f"C{j}", ms=4, lw=0.8,
                    label=law if r == 0 else None)
    a1.set(xlabel="excitation frequency f [Hz]", ylabel="amplitude ratio Z / U [-]")
    a1.set_title(f"{sy.THESIS}: every bed, both tangential laws", fontsize=9)
    a1.legend()
    names = [q for q, _, _ in QUANTITIES]
    a2.errorbar(range(len(names)), [100 * sh[q]["delta"] for q in names],
                yerr=[100 * sh[q]["ci95"] for q in names], fmt="D", capsize=4)
    a2.axhline(0, color="0.5", lw=0.8)
    a2.set_xticks(range(len(names)), names)
    a2.set(ylabel="Mindlin / viscous − 1 [%] (Welch 95 %)")
    a2.set_title("the shift of each quantity", fontsize=9)
    scaffold.save_figure(fig, out)

    pm = scaffold.pm
    L = scaffold.head("Does the tangential law matter at the thesis optimum?", data.attrs)
    L += [f"`{sy.THESIS}`, frequencies {list(s['freqs'])} Hz, {s['R']} beds per law (seeds "
          f"0…{s['R'] - 1}, each law's beds settled under that law), {s['protocol']} s runs "
          f"after {s['settle']} s of settling: the systematic budget's protocol. Steady means "
          "from the MSER start (else the final 10 %). Shift = Mindlin / viscous − 1, Welch 95 %"
          " interval over beds (unpaired).", ""]
    rows = []
    for q, unit, label in QUANTITIES:
        v, m = (values[law][q] for law in LAWS)
        scale = 1e3 if unit == "m" else 1.0
        u = "mm" if unit == "m" else unit
        rows.append([label, pm(v.mean() * scale, standard_error(v) * scale, 4, unit=u),
                     pm(m.mean() * scale, standard_error(m) * scale, 4, unit=u),
                     pm(100 * sh[q]["delta"], 100 * sh[q]["ci95"], "+.2f", ".2f", unit="%"),
                     "yes" if abs(sh[q]["delta"]) > sh[q]["ci95"] else "no"])
    L += scaffold.table(["quantity", "viscous (mean ± SE)", "Mindlin (mean ± SE)",
                         "shift (95 %)", "resolved (interval excludes 0)"], rows)
    L += ["", "## Per bed", ""]
    L += scaffold.table(
        ["law", "bed", "Z_res / U", "f_res [Hz]", "loss nearest 15 Hz [J]"],
        [[law, r, f"{data[law]['Z_res'][r] / U:.4f}", f"{data[law]['f_res'][r]:.3f}",
          f"{data[law]['loss'][r]:.4g}"] for law in LAWS for r in range(s["R"])])
    L += ["", "## Verdict", ""]
    z = sh["Z_res"]
    L.append(f"- The resonant amplitude shifts by "
             f"{pm(100 * z['delta'], 100 * z['ci95'], '+.2f', '.2f')} % with the spring; it "
             "enters the scoreboard's thesis rows as the standard uncertainty "
             f"u = sqrt(δ² + SE²) = {100 * z['u']:.2f} % "
             "(`experiments/systematics.py`, term `tangential_law`).")
    fr = sh["f_res"]
    L.append(f"- The resonance frequency shifts by "
             f"{pm(100 * fr['delta'], 100 * fr['ci95'], '+.2f', '.2f')} % "
             f"(u = {100 * fr['u']:.2f} %).")
    L += scaffold.quick_note(s)
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
