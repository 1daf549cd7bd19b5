"""Does the damper's effective-field map predict the structure? The thesis' optimal damper
mapped alone, the map inserted into the thesis' primary by harmonic balance, against the
coupled DEM FRF of the same damper (issue 40).

    python experiments/effective_field.py          # 6 amplitudes x 6 frequencies x 3 beds,
                                                    # 5 + 15 periods at 12 Hz (~20 min on 2 cores)
    python experiments/effective_field.py --quick  # 2 x 2 x 2, 1 + 3 periods (minutes)
    python experiments/effective_field.py --amplitudes 7 10 14 18 20 22 24 26 28 30 33 \
        --out experiments/effective_field/dense     # every 2 mm over 18-30 mm (~25 min)

**The map** (:func:`jaxdamp.studies.maps.measure`): ``sanchez2012-optimal`` (``Lz`` = 0.1225
m), its box alone moved as ``z = A cos Ωt`` over the amplitudes the coupled box reaches near
resonance (7–33 mm) and ``gap_scan``'s frequencies from 12 to 18.5 Hz, 3 beds, one batch:
``E_diss``, ``m_eff``, ``c_eff``, ``ψ`` per point with mean ± SE.

**The prediction** (:func:`jaxdamp.analysis.harmonic_balance.predict`): each bed's map in the
thesis' primary (M = 2.37 kg, K = 21 500 N/m, U = 4.5 mm) at C = 7.6 and 26.3 N s/m: the box
amplitude at which the primary's motion and the damper's effective mass and damping agree,
every root (a multi-valued response has several).

**The reference**: the coupled DEM of the same damper at the same frequencies, 3 beds, 2.5 s
runs (``experiments/gap_scan/data.h5``, ``Lz`` = 0.1225 m; copied into this study's data).

**The rule, fixed before the run** (:func:`jaxdamp.analysis.verdicts.outcome`, ``equivalent``):
per frequency the relative difference map / DEM − 1 (Welch over the two sets of beds) agrees if
``|δ| + t₀.₉₅ SE ≤ m``, disagrees if ``|δ| − t₀.₉₅ SE > m``, else undecided; ``m`` the
systematic budget of an amplitude at a given frequency at the thesis point
(``experiments/systematics``: two DEM estimates of one amplitude are not told apart below it).
A frequency where some bed's balance has no single root is reported as such, not compared.

Writes ``data.h5``, ``figure.png`` (predicted and coupled FRFs), ``map.png`` (the maps) and
``summary.md`` in ``--out``; the map's sweep (resumable) in ``--out/raw``.
"""

from __future__ import annotations

import os

import numpy as np

from jaxdamp.analysis.harmonic_balance import Balance, predict
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.io import maps as map_file
from jaxdamp.io.common import put
from jaxdamp.studies import maps, scaffold

try:  # imported as experiments.effective_field (the tests), or run as a script
    from experiments import systematics as sy
except ImportError:
    import systematics as sy

THESIS = "sanchez2012-optimal"
GAP_SCAN = os.path.join(sy.HERE, "gap_scan", "data.h5")
LZ = 0.1225  # [m], the preset's
MAX_ROOTS = 3  # stored per bed and frequency (padded with NaN)


def settings(quick: bool) -> dict:
    if quick:
        return dict(quick_mode=True, amplitudes=(0.01, 0.03), frequencies=(14.5, 15.25),
                    periods=3, transient=1, R=2, settle=0.15, C=(7.6, 26.3))
    return dict(amplitudes=(0.007, 0.010, 0.014, 0.020, 0.026, 0.033),
                frequencies=(12.0, 13.5, 14.5, 15.25, 16.0, 18.5), periods=15, transient=5,
                R=3, settle=0.3, C=(7.6, 26.3))


def coupled(C: float, frequencies) -> np.ndarray:
    """The coupled DEM's box amplitude [m] ``(F, R)`` at ``Lz`` = 0.1225 m and the primary's
    ``C``, read from ``gap_scan``'s stored result at ``frequencies``."""
    from jaxdamp.io.study import load

    g = load(GAP_SCAN)[f"C_{C:g}"]
    f, lz = np.asarray(g["axes"]["frequency"]), list(np.asarray(g["axes"]["box.Lz"]))
    idx = [int(np.argmin(np.abs(f - x))) for x in frequencies]
    if not np.allclose(f[idx], frequencies):
        raise ValueError(f"gap_scan holds no run at {frequencies} Hz (it has {f.tolist()})")
    return np.asarray(g["amplitude"])[idx, lz.index(LZ), :]


def options(ap):
    ap.add_argument("--amplitudes", type=float, nargs="+", metavar="MM",
                    help="the map's amplitudes [mm] instead of the default grid (e.g. every 2 mm "
                         "over 18-30 mm with --out experiments/effective_field/dense)")


def compute(quick: bool, log, ctx):
    s = settings(quick)
    if ctx.args.amplitudes:
        A = sorted(ctx.args.amplitudes)
        if A[0] <= 0:
            raise SystemExit(f"--amplitudes: {A[0]:g} mm: must be > 0")
        s["amplitudes"] = tuple(round(a * 1e-3, 9) for a in A)
    cfg = apply_overrides(presets.get(THESIS), {"numerics.settle_time": s["settle"]})
    field = maps.measure(cfg, s["amplitudes"], s["frequencies"], periods=s["periods"],
                         transient=s["transient"], replicates=s["R"],
                         out=ctx.raw(f"map_R{s['R']}.h5"), progress=ctx.progress)
    log(f"map: {field.wall_time:.0f} s compute, {int(field.stationary.sum())} of "
        f"{field.stationary.size} runs stationary")
    out = dict(field=field, C={})
    for C in s["C"]:
        p = predict(field, apply_overrides(cfg, {"primary.C": C}))
        out["C"][C] = dict(prediction=p, dem=coupled(C, s["frequencies"]))
    return out, lambda path, prov: record(out, s, path, prov)


def record(result: dict, s: dict, out: str, prov: dict) -> None:
    field = result["field"]
    prov = dict(prov, sweep_wall_s=field.wall_time)
    with scaffold.data_file(out, prov, settings=s) as h:
        map_file.put_map(h, field, periods=s["periods"], transient=s["transient"],
                         units=maps.UNITS, labels=maps.LABELS)
        for C, r in result["C"].items():
            c = h.create_group(f"C_{C:g}")
            roots = np.full((field.replicates, len(field.frequencies), MAX_ROOTS), np.nan)
            for k, row in enumerate(r["prediction"]["balances"]):
                for j, b in enumerate(row):
                    roots[k, j, :len(b.roots)] = b.roots[:MAX_ROOTS]
            put(c, "roots", roots, "m", dims="replicate, frequency, root",
                what="the consistent box amplitudes of each bed's map (harmonic balance)")
            c.attrs["where"] = [str(w) for w in r["prediction"]["where"].T.ravel()]
            put(c, "dem", r["dem"], "m", dims="frequency, replicate",
                what="the coupled DEM's steady box amplitude (experiments/gap_scan/data.h5, "
                     f"Lz = {LZ} m)")


def field_of(data) -> maps.EffectiveField:
    """The map stored in a ``data.h5`` (as :func:`jaxdamp.io.study.load` reads it)."""
    return maps.from_group(data["map"])


def prediction_of(data, C: float) -> dict:
    """The stored prediction at ``C`` as :func:`jaxdamp.analysis.harmonic_balance.predict`
    returns it (the figure's and the table's input)."""
    from jaxdamp.analysis.uncertainty import standard_error

    g = data[f"C_{C:g}"]
    roots = np.asarray(g["roots"])  # (R, F, MAX_ROOTS)
    R, F, _ = roots.shape
    where = np.asarray(g.attrs["where"]).reshape(R, F)
    bal = [[Balance(tuple(x for x in roots[k, j] if np.isfinite(x)), str(where[k, j]))
            for j in range(F)] for k in range(R)]
    Z = np.array([[b.single for b in row] for row in bal]).T
    ok = np.all(np.isfinite(Z), axis=1)
    return dict(frequency=np.asarray(data["map"]["frequency"]), balances=bal, amplitude=Z,
                mean=np.where(ok, Z.mean(axis=1), np.nan),
                se=np.where(ok, standard_error(Z, axis=1), np.nan))


def comparison(pred: dict, dem, margin: float) -> list[dict]:
    """Per frequency: the map's response against the coupled DEM's (module docstring's rule)."""
    rows = []
    for j, f in enumerate(pred["frequency"]):
        Z = pred["amplitude"][j]
        if not np.all(np.isfinite(Z)):
            rows.append(dict(f=f, result="no single root"))
            continue
        e = sy.equivalent_shift(Z, dem[j], margin)
        rows.append(dict(e, f=f, result={"pass": "agrees", "fail": "disagrees"}.get(
            e["outcome"], "undecided")))
    return rows


def report(data, out) -> None:
    from jaxdamp.figures.maps import draw_prediction, map_figure
    from jaxdamp.io.study import load

    s = data.attrs["settings"]
    field = field_of(data)
    U = presets.get(THESIS).primary.U  # the coupled runs' base amplitude
    margin = sy.relative_uncertainty(sy.budget(load(os.path.join(sy.HERE, "systematics",
                                                                 "data.h5"))),
                                     "thesis_optimum", "Z")
    fig, axes = scaffold.subplots(1, len(s["C"]), figsize=(6.0 * len(s["C"]), 4.3))
    axes = np.atleast_1d(axes)
    rows, verdicts = [], {}
    for ax, C in zip(axes, s["C"]):
        pred, dem = prediction_of(data, C), np.asarray(data[f"C_{C:g}"]["dem"])
        draw_prediction(ax, pred, U, dem=(pred["frequency"], dem), title=f"C = {C:g} N s/m")
        verdicts[C] = comparison(pred, dem, margin)
        for v in verdicts[C]:
            j = list(pred["frequency"]).index(v["f"])
            roots = "; ".join(", ".join(f"{z / U:.3f}" for z in b.roots) or b.where
                              for b in (row[j] for row in pred["balances"]))
            d = (scaffold.pm(100 * v["delta"], 100 * v["ci95"], "+.2f", ".2f", unit="%")
                 if "delta" in v else "—")
            rows.append([f"{C:g}", f"{v['f']:g}",
                         scaffold.pm(*scaffold.mean_se(dem[j] / U), 4),
                         scaffold.pm(pred["mean"][j] / U, pred["se"][j] / U, 4)
                         if np.isfinite(pred["mean"][j]) else "—", roots, d, v["result"]])
    scaffold.save_figure(fig, out)
    scaffold.save_figure(map_figure(field, f"{THESIS} alone (Lz = {LZ} m): effective fields, "
                                           f"mean ± SE over {field.replicates} beds"),
                         out, "map.png")

    pm = scaffold.pm
    L = scaffold.head("Does the damper's effective-field map predict the structure?", data.attrs,
                      sweep_wall=data.attrs.get("sweep_wall_s"))
    n = field.config.numerics
    system_s = field.stationary.size * n.duration
    L += [f"**The map**: `{THESIS}` alone (Lz = {LZ} m), z = A cos Ωt at A = "
          f"{', '.join(f'{a * 1e3:g}' for a in field.amplitudes)} mm × f = "
          f"{', '.join(f'{f:g}' for f in field.frequencies)} Hz, {field.replicates} beds, one "
          f"batch; {s['transient']} + {s['periods']} periods of {min(field.frequencies):g} Hz "
          f"({n.duration:.3g} s), dt = {n.dt:.3g} s. Steady state detected (MSER on per-period "
          f"losses) in {int(field.stationary.sum())} of {field.stationary.size} runs (the "
          "others: the whole periods of the final window). **Cost**: "
          f"{system_s:.0f} DEM system-seconds, {field.wall_time / 60:.1f} min compute on this "
          "machine (2 cores).", "",
          f"**The prediction**: each bed's map in the thesis' primary (M = 2.37 kg, K = 21 500 "
          f"N/m, U = {U * 1e3:g} mm) by harmonic balance; **the reference**: the coupled DEM "
          "of the same damper (`gap_scan`, 3 beds, 2.5 s runs). Rule: agrees if |δ| + t₀.₉₅ SE "
          f"≤ {100 * margin:.2f} % (the systematic budget of an amplitude at a given frequency "
          "at the thesis point), disagrees if |δ| − t₀.₉₅ SE exceeds it, else undecided.", ""]
    L += scaffold.table(["C [N s/m]", "f [Hz]", "coupled DEM Z/U", "map Z/U",
                         "roots per bed (Z/U)", "map / DEM − 1 (95 %)", "verdict"], rows)
    L += ["", "## The map (mean ± SE over beds)", ""]
    L += scaffold.table(
        ["f [Hz]", "A [mm]", "E_diss [J]", "E_input [J]", "m_eff [kg]", "c_eff [N s/m]",
         "c_force [N s/m]", "ψ"],
        [[f"{f:g}", f"{a * 1e3:g}"] + [pm(field.mean(q)[i, j], field.se(q)[i, j], 4)
                                       for q in ("E_diss", "E_input", "m_eff", "c_eff",
                                                 "c_force", "psi")]
         for j, f in enumerate(field.frequencies) for i, a in enumerate(field.amplitudes)])
    L += ["", "## Verdict", ""]
    for C, vs in verdicts.items():
        tally = {k: sum(v["result"] == k for v in vs)
                 for k in ("agrees", "disagrees", "undecided", "no single root")}
        L.append(f"- C = {C:g} N s/m: " + ", ".join(f"{k} at {n} frequenc"
                                                    f"{'y' if n == 1 else 'ies'}"
                                                    for k, n in tally.items() if n) + ".")
    L += scaffold.quick_note(s)
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, options=options, report=report)


if __name__ == "__main__":
    main()
