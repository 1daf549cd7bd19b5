"""Does the damper's effective-field map predict the structure? The thesis' optimal damper
mapped alone, the map inserted into the thesis' primary by harmonic balance, against the
coupled DEM FRF of the same damper (issue 40).

    python experiments/effective_field.py          # 6 amplitudes x 6 frequencies x 3 beds,
                                                    # 5 + 15 periods at 12 Hz (~20 min on 2 cores)
    python experiments/effective_field.py --quick  # 2 x 2 x 2, 1 + 3 periods (minutes)
    python experiments/effective_field.py --amplitudes 7 10 14 18 20 22 24 26 28 30 33 \
        --out experiments/effective_field/dense     # every 2 mm over 18-30 mm (~25 min)
    python experiments/effective_field.py --structure chain \
        --out experiments/effective_field/chain     # a 2-DOF structure's mode 1 (~40 min)

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

**A multi-DOF structure** (``--structure chain``): the same damper on the upper mass of
``sanchez2012-chain`` (two 2.37 kg masses, 21 500 N/m, 7.6 N s/m; empty mode 1 at 9.37 Hz,
its antinode the upper mass). The damper is mapped over the amplitudes the upper mass reaches
around mode 1 (12–85 mm) at 8–10.5 Hz, the map balanced in the 2-DOF matrices (the augmented
linear solve), and the reference is the coupled DEM of the chain run here (same frequencies, 3
beds, 4 s runs: mode 1's decay time 1/(ζ ω) is under 1 s).

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
from jaxdamp.studies.grid import steady_or_window
from jaxdamp.studies.sweep import reuse_or_run

try:  # imported as experiments.effective_field (the tests), or run as a script
    from experiments import systematics as sy
except ImportError:
    import systematics as sy

THESIS = "sanchez2012-optimal"
CHAIN = "sanchez2012-chain"  # the same damper on a 2-DOF structure
GAP_SCAN = os.path.join(sy.HERE, "gap_scan", "data.h5")
LZ = 0.1225  # [m], the preset's
MAX_ROOTS = 3  # stored per bed and frequency (padded with NaN)


def settings(quick: bool, structure: str = "thesis") -> dict:
    if structure == "chain":
        if quick:
            return dict(quick_mode=True, structure="chain", amplitudes=(0.02, 0.05),
                        frequencies=(9.25, 9.5), periods=3, transient=1, R=2, settle=0.15,
                        duration=0.6)
        return dict(structure="chain",
                    amplitudes=(0.012, 0.016, 0.021, 0.027, 0.034, 0.043, 0.054, 0.068, 0.085),
                    frequencies=(8.0, 8.75, 9.25, 9.5, 9.75, 10.5), periods=15, transient=5,
                    R=3, settle=0.3, duration=4.0)
    if quick:
        return dict(quick_mode=True, amplitudes=(0.01, 0.03), frequencies=(14.5, 15.25),
                    periods=3, transient=1, R=2, settle=0.15, C=(7.6, 26.3))
    return dict(amplitudes=(0.007, 0.010, 0.014, 0.020, 0.026, 0.033),
                frequencies=(12.0, 13.5, 14.5, 15.25, 16.0, 18.5), periods=15, transient=5,
                R=3, settle=0.3, C=(7.6, 26.3))


def cases(s: dict) -> list[str]:
    """The structures the map is inserted into: their groups in ``data.h5``."""
    if s.get("structure", "thesis") == "chain":
        return ["chain"]
    return [f"C_{C:g}" for C in s["C"]]


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


def chain_config(s: dict):
    """``sanchez2012-chain`` with the coupled runs' timing."""
    return apply_overrides(presets.get(CHAIN), {
        "numerics.duration": s["duration"], "numerics.record_dt": 1e-3,
        "numerics.settle_time": s["settle"], "numerics.chunk": 0.1})


def coupled_chain(s: dict, ctx) -> tuple[np.ndarray, float]:
    """The coupled DEM of the chain at the map's frequencies: the box's steady amplitude [m]
    ``(F, R)`` and the sweep's compute time [s] (its raw file resumable)."""
    res = reuse_or_run(chain_config(s), {"frequency": list(s["frequencies"])},
                       ctx.raw(f"chain_R{s['R']}.h5"), progress=ctx.progress, replicates=s["R"])
    return steady_or_window(res, "amplitude")[0], float(res.summary["wall_time"])


def options(ap):
    ap.add_argument("--amplitudes", type=float, nargs="+", metavar="MM",
                    help="the map's amplitudes [mm] instead of the default grid (e.g. every 2 mm "
                         "over 18-30 mm with --out experiments/effective_field/dense)")
    ap.add_argument("--structure", choices=("thesis", "chain"), default="thesis",
                    help="the structure the map predicts: the thesis' 1-DOF primary at C = "
                         "7.6 and 26.3 N s/m (reference: gap_scan), or the 2-DOF chain "
                         f"{CHAIN} around its mode 1 (reference: coupled runs made here; "
                         "use its own --out, e.g. experiments/effective_field/chain)")


def compute(quick: bool, log, ctx):
    s = settings(quick, ctx.args.structure)
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
    out = dict(field=field, cases={}, dem_wall=0.0)
    if s.get("structure") == "chain":
        dem, out["dem_wall"] = coupled_chain(s, ctx)
        log(f"coupled chain: {out['dem_wall']:.0f} s compute")
        out["cases"]["chain"] = dict(prediction=predict(field, chain_config(s)), dem=dem)
    for C in s.get("C", ()):
        p = predict(field, apply_overrides(cfg, {"primary.C": C}))
        out["cases"][f"C_{C:g}"] = dict(prediction=p, dem=coupled(C, s["frequencies"]))
    return out, lambda path, prov: record(out, s, path, prov)


def record(result: dict, s: dict, out: str, prov: dict) -> None:
    field = result["field"]
    prov = dict(prov, sweep_wall_s=field.wall_time + result["dem_wall"])
    if result["dem_wall"]:
        prov["dem_wall_s"] = result["dem_wall"]
    with scaffold.data_file(out, prov, settings=s) as h:
        map_file.put_map(h, field, periods=s["periods"], transient=s["transient"],
                         units=maps.UNITS, labels=maps.LABELS)
        for name, r in result["cases"].items():
            c = h.create_group(name)
            roots = np.full((field.replicates, len(field.frequencies), MAX_ROOTS), np.nan)
            for k, row in enumerate(r["prediction"]["balances"]):
                for j, b in enumerate(row):
                    roots[k, j, :len(b.roots)] = b.roots[:MAX_ROOTS]
            put(c, "roots", roots, "m", dims="replicate, frequency, root",
                what="the consistent box amplitudes of each bed's map (harmonic balance)")
            c.attrs["where"] = [str(w) for w in r["prediction"]["where"].T.ravel()]
            put(c, "dem", r["dem"], "m", dims="frequency, replicate",
                what=f"the coupled DEM's steady box amplitude ({CHAIN}, run here)"
                if name == "chain" else "the coupled DEM's steady box amplitude "
                f"(experiments/gap_scan/data.h5, Lz = {LZ} m)")


def field_of(data) -> maps.EffectiveField:
    """The map stored in a ``data.h5`` (as :func:`jaxdamp.io.study.load` reads it)."""
    return maps.from_group(data["map"])


def prediction_of(data, case: str) -> dict:
    """The stored prediction of ``case`` (:func:`cases`: ``"C_7.6"``, ``"chain"``) as
    :func:`jaxdamp.analysis.harmonic_balance.predict` returns it (the figure's and the
    table's input)."""
    from jaxdamp.analysis.uncertainty import standard_error

    g = data[case]
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
    chain = s.get("structure", "thesis") == "chain"
    field = field_of(data)
    U = presets.get(THESIS).primary.U  # the coupled runs' base amplitude (the chain's too)
    margin = sy.relative_uncertainty(sy.budget(load(os.path.join(sy.HERE, "systematics",
                                                                 "data.h5"))),
                                     "thesis_optimum", "Z")
    names = cases(s)
    fig, axes = scaffold.subplots(1, len(names), figsize=(6.0 * len(names), 4.3))
    axes = np.atleast_1d(axes)
    rows, verdicts = [], {}
    for ax, name in zip(axes, names):
        label = "chain" if chain else name[2:]
        pred, dem = prediction_of(data, name), np.asarray(data[name]["dem"])
        draw_prediction(ax, pred, U, dem=(pred["frequency"], dem),
                        title=f"{CHAIN}: the damper on the upper mass (DOF 1)" if chain
                        else f"C = {label} N s/m")
        verdicts[label] = comparison(pred, dem, margin)
        for v in verdicts[label]:
            j = list(pred["frequency"]).index(v["f"])
            roots = "; ".join(", ".join(f"{z / U:.3f}" for z in b.roots) or b.where
                              for b in (row[j] for row in pred["balances"]))
            d = (scaffold.pm(100 * v["delta"], 100 * v["ci95"], "+.2f", ".2f", unit="%")
                 if "delta" in v else "—")
            rows.append(([] if chain else [label])
                        + [f"{v['f']:g}", scaffold.pm(*scaffold.mean_se(dem[j] / U), 4),
                           scaffold.pm(pred["mean"][j] / U, pred["se"][j] / U, 4)
                           if np.isfinite(pred["mean"][j]) else "—", roots, d, v["result"]])
    scaffold.save_figure(fig, out)
    scaffold.save_figure(map_figure(field, f"{THESIS} alone (Lz = {LZ} m): effective fields, "
                                           f"mean ± SE over {field.replicates} beds"),
                         out, "map.png")

    pm = scaffold.pm
    L = scaffold.head("Does the damper's effective-field map predict the structure?"
                      + (" A 2-DOF structure" if chain else ""), data.attrs,
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
          "machine (2 cores).", ""]
    if chain:
        dem = np.asarray(data["chain"]["dem"])
        L += [f"**The prediction**: each bed's map on the upper mass (DOF 1) of `{CHAIN}` "
              "(two 2.37 kg masses, springs 21 500 N/m and dampers 7.6 N s/m base–lower and "
              f"lower–upper; U = {U * 1e3:g} mm) by harmonic balance in its 2 × 2 matrices; "
              f"**the reference**: the coupled DEM of the chain with the same damper, "
              f"{dem.shape[1]} beds, {s['duration']:g} s runs at the map's frequencies "
              f"({dem.size * s['duration']:.0f} DEM system-seconds, "
              f"{data.attrs.get('dem_wall_s', 0.0) / 60:.1f} min compute). Rule: agrees if "
              f"|δ| + t₀.₉₅ SE ≤ {100 * margin:.2f} % (the systematic budget of an amplitude "
              "at a given frequency at the thesis point), disagrees if |δ| − t₀.₉₅ SE exceeds "
              "it, else undecided.", ""]
    else:
        L += [f"**The prediction**: each bed's map in the thesis' primary (M = 2.37 kg, K = "
              f"21 500 N/m, U = {U * 1e3:g} mm) by harmonic balance; **the reference**: the "
              "coupled DEM of the same damper (`gap_scan`, 3 beds, 2.5 s runs). Rule: agrees "
              f"if |δ| + t₀.₉₅ SE ≤ {100 * margin:.2f} % (the systematic budget of an "
              "amplitude at a given frequency at the thesis point), disagrees if |δ| − t₀.₉₅ "
              "SE exceeds it, else undecided.", ""]
    L += scaffold.table(([] if chain else ["C [N s/m]"])
                        + ["f [Hz]", "coupled DEM Z/U", "map Z/U", "roots per bed (Z/U)",
                           "map / DEM − 1 (95 %)", "verdict"], rows)
    L += ["", "## The map (mean ± SE over beds)", ""]
    L += scaffold.table(
        ["f [Hz]", "A [mm]", "E_diss [J]", "E_input [J]", "m_eff [kg]", "c_eff [N s/m]",
         "c_force [N s/m]", "ψ"],
        [[f"{f:g}", f"{a * 1e3:g}"] + [pm(field.mean(q)[i, j], field.se(q)[i, j], 4)
                                       for q in ("E_diss", "E_input", "m_eff", "c_eff",
                                                 "c_force", "psi")]
         for j, f in enumerate(field.frequencies) for i, a in enumerate(field.amplitudes)])
    L += ["", "## Verdict", ""]
    for label, vs in verdicts.items():
        tally = {k: sum(v["result"] == k for v in vs)
                 for k in ("agrees", "disagrees", "undecided", "no single root")}
        L.append(("- The chain's mode 1: " if chain else f"- C = {label} N s/m: ")
                 + ", ".join(f"{k} at {n} frequenc" f"{'y' if n == 1 else 'ies'}"
                             for k, n in tally.items() if n) + ".")
    L += scaffold.quick_note(s)
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, options=options, report=report)


if __name__ == "__main__":
    main()
