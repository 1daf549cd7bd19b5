"""Friction with and without memory in two codes: the driven box with friction in LAMMPS and in
jaxdamp, under the viscous tangential law and under the Hertz–Mindlin spring (issue 39).

    python experiments/lammps_friction.py          # full: 2 cases x 2 laws, 10 + 50 periods,
                                                   # 5 beds each (~40 min on 2 cores)
    python experiments/lammps_friction.py --quick  # 2 + 3 periods, 2 beds each (~6 min)
    python experiments/lammps_friction.py --cases collisional --dt-per-collision 100 \
        --replicates 3 --out experiments/lammps_friction/dt_half   # the time-step study

The grains, walls and box of ``varela2023-reference`` (300 steel spheres, R = 2.5 mm, E = 2 GPa,
ε = 0.75 at 1 m/s, cube of 8 cm, f = 70 Hz) given steel's friction, μ = 0.23 (dynamic,
:mod:`jaxdamp.materials`), grains and walls, and for the viscous law the table's tangential
constant ``γ_s`` (:func:`jaxdamp.materials.tangential_damping`). Two regimes:

* ``collisional``: driven vertically at A_d = 3 cm (Γ = A_d ω²/g ≈ 590): a granular gas
  hitting floor and lid, where impacts dissipate and friction is a correction;
* ``gentle``: driven horizontally at A_d = 20 µm (Γ ≈ 0.39, the box's speed 9 mm/s): the bed
  stays on the floor, its contacts last, the loss is a few 10⁻⁵ J per period of slow contacts,
  rolling and sliding — where the tangential law should matter. (A bed that moves as one
  block needs many layers; this one is 1.7 grains deep: its grains roll. Explored in jaxdamp
  before the run, one bed each, 0.3 s: Mindlin − viscous −8 % at Γ ≈ 2, −15 % at Γ ≈ 0.39,
  −10 % at Γ ≈ 0.2 where the settling's remains dominate.)

Each tangential law is mapped onto LAMMPS' GRANULAR package (:func:`jaxdamp.peers.lammps.
tangential`): the viscous law as ``tangential linear_nohistory``, the spring as ``tangential
mindlin_rescale/force`` (history kept as the force, cut with the contact radius on unloading,
both as jaxdamp's). The mapping is checked first by oblique impacts (a grain on the floor, two
grains; sticking, partly slipping, sliding throughout) in both codes at the same time step. Per
case and law ``--replicates R`` beds, each poured by jaxdamp and the initial state (with its
spins) of both codes: per bed LAMMPS − jaxdamp of the mean dissipation per period over a window
common to both codes (:mod:`jaxdamp.peers.lammps`), across beds its Student-t 95 % interval.

Rules (stated before the run): **a law agrees between the codes within 1 %** where the paired
95 % interval of LAMMPS − jaxdamp lies inside ±1 % of jaxdamp's mean. **The laws' difference**
Mindlin − viscous is, in each code, the Welch 95 % interval of the two laws' bed means (the beds
of the two laws are poured separately), and **the codes agree on it** where the Welch 95 %
interval of the per-bed paired differences (LAMMPS − jaxdamp) of the spring's beds minus the
viscous law's contains 0 — its half-width says how small a disagreement could hide.

``--laws`` runs one law only (no difference between the laws is formed), ``--dt-per-collision``
sets both codes' time step (``numerics.dt_per_collision``; the preset's is 50): with 100, the
step halved, a difference between the codes that is the integrators' shrinks and one that is
the models' stays.

Writes ``data.h5``, ``figure.png`` and ``summary.md`` in ``--out``; LAMMPS inputs, logs,
snapshots and the beds' results in ``--out/raw`` (git-ignored; beds reused by a re-run with the
same settings).
"""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from jaxdamp.peers import lammps
from jaxdamp.studies import scaffold

PRESET = "varela2023-reference"
MU = 0.23  # steel on steel, dynamic (jaxdamp.materials)
LAWS = ("viscous", "mindlin")
LABEL = {"viscous": "viscous", "mindlin": "Mindlin"}
#: name: (drive axis, amplitude [m], settling time [s] or None for the preset's)
CASES = {"collisional": ((0.0, 0.0, 1.0), 0.03, None),
         "gentle": ((1.0, 0.0, 0.0), 2e-5, 0.4)}
TARGET = 0.01  # a law's agreement between the codes: paired 95 % interval inside ±1 %


def settings(quick: bool) -> dict:
    if quick:
        return dict(transient=2, periods=3, replicates=2, ratios=(0.1, 2.0))
    return dict(transient=10, periods=50, replicates=5, ratios=(0.1, 0.5, 2.0))


def base_config(law: str):
    """The reference damper with friction (grains and walls: μ = :data:`MU`, the table's
    ``γ_s``) under tangential ``law``."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.materials import tangential_damping

    ref = presets.get(PRESET)
    m = ref.grains[0].material
    gs = tangential_damping(m.E, m.nu, m.density)
    return apply_overrides(ref, {"tangential_law": law, "grains.0.material.mu": MU,
                                 "box.wall.mu": MU, "grains.0.material.gamma_s": gs,
                                 "box.wall.gamma_s": gs})


def case_config(law: str, case: str, n_periods: int, seed: int, dt_per_collision=None):
    """:func:`base_config` driven as ``case`` (:data:`CASES`) for ``n_periods`` (samples every
    T/500), its bed poured with ``numerics.seed = seed`` (and ``numerics.dt_per_collision``
    where given)."""
    from jaxdamp.config import apply_overrides

    axis, A, settle = CASES[case]
    base = base_config(law)
    T = 1.0 / base.frequency
    ov = {"direction": list(axis), "drive.amplitude": A, "numerics.seed": int(seed),
          "numerics.duration": (n_periods + 0.02) * T, "numerics.chunk": T / 5,
          "numerics.record_dt": T / 500}
    if settle is not None:
        ov["numerics.settle_time"] = settle
    if dt_per_collision is not None:
        ov["numerics.dt_per_collision"] = float(dt_per_collision)
    return apply_overrides(base, ov)


def options(ap) -> None:
    ap.add_argument("--replicates", type=int, default=None,
                    help="independently poured beds per case and law (default 5; quick: 2)")
    ap.add_argument("--cases", nargs="+", choices=tuple(CASES), default=None,
                    help="the regimes to run (default: both)")
    ap.add_argument("--laws", nargs="+", choices=LAWS, default=None,
                    help="the tangential laws to run (default: both; with one, no difference "
                         "between the laws is formed)")
    ap.add_argument("--dt-per-collision", type=float, default=None,
                    help="numerics.dt_per_collision of both codes' runs (default: the "
                         "preset's 50): a time-step study of the codes' difference")
    ap.add_argument("--lmp", default=None, help="LAMMPS executable (default: lmp on PATH)")


def compute(quick: bool, log, ctx):
    from jaxdamp.analysis.stats import replicate_seed

    args, s = ctx.args, settings(quick)
    if args.replicates is not None:
        s["replicates"] = args.replicates
    if s["replicates"] < 2:
        raise SystemExit("--replicates must be at least 2 (an error bar needs two beds)")
    cases, laws = tuple(args.cases or CASES), tuple(args.laws or LAWS)
    dtc = args.dt_per_collision
    exe = args.lmp or lammps.executable()
    if exe is None:
        raise SystemExit("LAMMPS (`lmp`) is not on PATH: apt-get install lammps")
    raw = ctx.raw("")
    version = lammps.version(exe)
    log(f"LAMMPS: {version}")
    seeds = [replicate_seed(base_config("viscous").numerics.seed, k)
             for k in range(s["replicates"])]
    checks, t0 = {}, time.perf_counter()
    for law in laws:
        cfg = base_config(law)
        checks[law] = lammps.oblique_checks(cfg, lammps.build_mapping(cfg),
                                            os.path.join(raw, "checks", law), exe,
                                            ratios=s["ratios"])
        worst = max(r["difference"] for r in checks[law])
        log(f"oblique impacts, {law}: largest difference LAMMPS − jaxdamp {worst:.2g} of v_n")
    checks_wall = time.perf_counter() - t0
    n_total = s["transient"] + s["periods"]
    runs = {}
    for case in cases:
        for law in laws:
            beds = []
            for seed in seeds:
                cfg = case_config(law, case, n_total, seed, dtc)
                key = dict(preset=PRESET, case=case, law=law, mu=MU, seed=int(seed),
                           amplitude=cfg.drive.amplitude, direction=list(cfg.direction),
                           transient=s["transient"], periods=s["periods"])
                if dtc is not None:
                    key["dt_per_collision"] = dtc
                path = os.path.join(raw, "beds", f"{case}_{law}_seed{seed}.npz")
                beds.append(lammps.paired_bed(cfg, n_total, key, path, raw, exe, ctx.progress,
                                              log, tag=f"_{case}_{law}"))
            T = 1.0 / cfg.frequency
            c = lammps.driven_case(cfg.drive.amplitude, beds, s, T)
            c["table"] = lammps.analyse_amplitude(
                cfg.drive.amplitude,
                [lammps.analyse_bed(b["stored"], s, T, c["mp"].dt) for b in beds], c["e_max"])
            r = c["table"]
            log(f"{case}, {law}: LAMMPS − jaxdamp "
                f"{scaffold.pm(r['rel'], r['rel_hw'], '+.2f', '.2f', scale=100)} % (95 %)")
            runs[(case, law)] = c
    run = dict(runs=runs, checks=checks, checks_wall=checks_wall, version=version, settings=s,
               seeds=seeds, cases=cases, laws=laws, dt_per_collision=dtc)
    return run, lambda out, prov: record(run, out, prov)


def record(run: dict, out: str, prov: dict) -> None:
    s = run["settings"]
    with scaffold.data_file(out, prov, lammps_version=run["version"], preset=PRESET, mu=MU,
                            cases=json.dumps({k: CASES[k] for k in run["cases"]}),
                            checks=json.dumps(run["checks"], default=_plain),
                            checks_wall_time=run["checks_wall"],
                            attribute_units=lammps.ATTR_UNITS) as h:
        h.attrs.update(transient_periods=s["transient"], periods=s["periods"],
                       replicates=s["replicates"], seeds=np.asarray(run["seeds"]),
                       laws=json.dumps(run["laws"]))
        if run["dt_per_collision"] is not None:
            h.attrs["dt_per_collision"] = run["dt_per_collision"]
        for (case, law), c in run["runs"].items():
            g = h.require_group(f"{case}/{law}")
            g.attrs["mapping"] = json.dumps(c["mp"].as_dict())
            lammps.write_case(g, c["table"]["A"], c, c["table"], run["seeds"])


def _json(x):
    """An attribute stored as JSON, as the file layer gives it back (decoded or not)."""
    return json.loads(x) if isinstance(x, (str, bytes)) else x


def _plain(x):
    return x.tolist() if hasattr(x, "tolist") else str(x)


def laws_of(data) -> tuple:
    """The tangential laws a stored ``data.h5`` holds (both, where it does not say)."""
    return tuple(_json(data.attrs["laws"])) if "laws" in data.attrs else LAWS


def stored(data) -> tuple[dict, dict]:
    """``(settings, {(case, law): analysis})`` of a stored ``data.h5``."""
    a = data.attrs
    s = dict(transient=a["transient_periods"], periods=a["periods"], replicates=a["replicates"])
    table = {}
    for case in _json(a["cases"]):
        for law in laws_of(data):
            g = data[case][law]
            (name,) = [k for k in g if k.startswith("A_")]
            gA = g[name]
            T = float(gA["bed_0"]["jaxdamp"]["boundary_time"][1])
            table[(case, law)] = lammps.analyse_group(CASES[case][1], gA, s, T)
    return s, table


def law_difference(table: dict, case: str) -> dict:
    """Mindlin − viscous of ``case`` in each code (Welch 95 % over the laws' bed means, also in
    % of the viscous mean) and the codes' disagreement on it (Welch over the per-bed paired
    differences)."""
    from jaxdamp.analysis.stats import welch

    v, m = table[(case, "viscous")], table[(case, "mindlin")]
    ok = lambda r, k: np.array([b[k] for b in r["beds"] if b["stationary"]])  # noqa: E731
    out = {}
    for code, k in (("lammps", "ml"), ("jaxdamp", "mj")):
        d, hw = welch(ok(m, k), ok(v, k))
        base = float(np.mean(ok(v, k)))
        out[code] = dict(d=d, hw=hw, rel=d / base, rel_hw=hw / base)
    d, hw = welch(ok(m, "diff"), ok(v, "diff"))
    out["codes"] = dict(d=d, hw=hw, agree=bool(np.isfinite(hw) and abs(d) <= hw),
                        rel_hw=hw / abs(out["jaxdamp"]["d"]) if out["jaxdamp"]["d"] else math.nan)
    return out


def within_target(r: dict) -> bool:
    """Whether a law's paired 95 % interval lies inside ±:data:`TARGET` of jaxdamp's mean."""
    return lammps.within(r, TARGET)


def report(data, out) -> None:
    s, table = stored(data)
    checks = _json(data.attrs["checks"])
    cases = list(_json(data.attrs["cases"]))
    figure(table, cases, laws_of(data), out)
    summary(data, s, table, checks, cases, out)


def figure(table: dict, cases: list, laws: tuple, out: str) -> None:
    both = len(laws) == 2
    fig, axs = scaffold.subplots(1 + both, len(cases), (6.5 * len(cases), 4.5 + 4 * both),
                                 squeeze=False)
    for j, case in enumerate(cases):
        ax = axs[0, j]
        for i, law in enumerate(laws):
            r = table[(case, law)]
            tq = r["hw"] / r["sed"] if r["sed"] > 0 else math.nan
            for off, key, se, mk, code in ((-0.1, "ml", "sel", "o", "LAMMPS"),
                                           (0.1, "mj", "sej", "s", "jaxdamp")):
                x = i + off
                ax.errorbar(x, r[key] * 1e3, yerr=r[se] * tq * 1e3, fmt=mk, capsize=4,
                            color="C0" if code == "LAMMPS" else "C1",
                            label=code if i == 0 else None)
                ax.plot(np.full(r["R"], x + 0.04), [b[key] * 1e3 for b in r["beds"]], ".",
                        color="C0" if code == "LAMMPS" else "C1", alpha=0.5, ms=4)
        ax.set_xticks(range(len(laws)), laws)
        ax.set_ylabel("dissipation per period [mJ]")
        ax.set_title(f"{case}: A_d = {CASES[case][1] * 1e3:g} mm along "
                     f"{'xyz'[int(np.argmax(CASES[case][0]))]}; mean ± 95 % over beds")
        ax.legend()
        if not both:
            continue
        bx = axs[1, j]
        ld = law_difference(table, case)
        for k, code in enumerate(("lammps", "jaxdamp")):
            bx.errorbar(k, ld[code]["rel"] * 100, yerr=ld[code]["rel_hw"] * 100, fmt="D",
                        capsize=5, color=f"C{k}")
        bx.axhline(0, color="k", lw=0.8)
        bx.set_xticks([0, 1], ["LAMMPS", "jaxdamp"])
        bx.set_xlim(-0.6, 1.6)
        bx.set_ylabel("Mindlin − viscous [% of viscous]")
        bx.set_title(f"{case}: the laws' difference (Welch 95 %)")
    scaffold.save_figure(fig, out)


def summary(data, s: dict, table: dict, checks: dict, cases: list, out: str) -> None:
    pm = scaffold.pm
    a = data.attrs
    laws = laws_of(data)
    both = len(laws) == 2
    L = scaffold.head("Friction with and without memory: LAMMPS and jaxdamp (issue 39)",
                      dict(a))
    w = L.append
    w(f"\nLAMMPS: `{a['lammps_version']}` (serial). Grains and walls of `{PRESET}` with "
      f"μ = {MU} (steel, dynamic) and the table's γ_s; R = {s['replicates']} beds per case and "
      f"law, each poured by jaxdamp and the initial state of both codes (positions, velocities, "
      f"spins; no spring history: both codes start the drive with none); "
      f"{s['transient']} transient + {s['periods']} periods, the window common to both codes "
      "(MSER, never before the transient).\n")
    if "dt_per_collision" in a:
        w(f"Time step: `numerics.dt_per_collision = {a['dt_per_collision']:g}` in both codes "
          "(the preset's: 50), a time-step study of the codes' difference.\n")
    w("## The mapping of the tangential laws\n")
    mapping = {law: _json(data[cases[0]][law].attrs["mapping"]) for law in laws}
    rows = []
    if "viscous" in mapping:
        mv = mapping["viscous"]
        rows.append(("viscous", "F_t = −min(γ_s sqrt(ξ)|v_s|, μ F_n) v̂_s",
                     f"`tangential linear_nohistory x μ`, x = γ_s/g = {mv['xt_pp']:.4g}; "
                     f"{mv['xt_pw']:.4g}"))
    if "mindlin" in mapping:
        mp = mapping["mindlin"]
        rows.append(("Mindlin", "spring force history, k_t = 8 G* sqrt(R* ξ), γ_t = k_t γ_n/"
                     "(1.5 k_n), rescaled by sqrt(ξ/ξ_old) on unloading",
                     f"`tangential mindlin_rescale/force k_t x μ`, k_t = 8 G* = "
                     f"{mp['kt_pp']:.4g} Pa, x = 4 G*/E* = {mp['xs_pp']:.4g}; "
                     f"{mp['kt_pw']:.4g} Pa, {mp['xs_pw']:.4g}"))
    L += scaffold.table(("law", "jaxdamp", "LAMMPS (pairs; walls)"), rows)
    w("\nKnown differences of the two implementations (none tuned away): on slip LAMMPS sets "
      "the spring to the Coulomb force plus the dashpot's force, jaxdamp scales spring and "
      "dashpot by the same factor (equal total force, the spring differs while it slips); "
      "LAMMPS takes k_t at the present overlap, jaxdamp at the step's mean; LAMMPS' pair "
      "torque has the lever arm R − ξ/2 (its walls' R), jaxdamp's R.\n")
    w("## Oblique impacts (mapping check)\n")
    w("Grain 1 after the impact, both codes at the same dt: normal restitution, tangential "
      "velocity and spin ωR over the tangential velocity before; largest difference of any "
      "velocity component (or ωR) over v_n.\n")
    L += scaffold.table(
        ("law", "impact", "v_t/v_n", "restitution L / J", "tangential L / J", "spin L / J",
         "largest difference / v_n"),
        [(law, r["kind"], f"{r['vt'] / r['vn']:g}",
          f"{r['lammps']['restitution']:.5f} / {r['jaxdamp']['restitution']:.5f}",
          f"{r['lammps']['tangential']:.5f} / {r['jaxdamp']['tangential']:.5f}",
          f"{r['lammps']['spin']:.5f} / {r['jaxdamp']['spin']:.5f}", f"{r['difference']:.2g}")
         for law in laws for r in checks[law]])
    w("\n## Dissipation per period, per case and law\n")
    L += scaffold.table(
        ("case", "law", "beds (stationary)", "LAMMPS [J]", "jaxdamp [J]",
         "LAMMPS − jaxdamp, paired 95 % [J]", "in % of jaxdamp", "within ±1 %"),
        [(case, law, f"{r['R']} ({r['n']})", pm(r["ml"], r["sel"], 4),
          pm(r["mj"], r["sej"], 4), pm(r["d"], r["hw"], "+.3g"),
          pm(r["rel"], r["rel_hw"], "+.2f", ".2f", scale=100),
          "yes" if within_target(r) else "NO")
         for case in cases for law in laws for r in [table[(case, law)]]])
    rows, lds = [], {}
    for case in cases if both else ():
        ld = lds[case] = law_difference(table, case)
        rows.append((case, pm(ld["lammps"]["d"], ld["lammps"]["hw"], "+.3g"),
                     pm(ld["lammps"]["rel"], ld["lammps"]["rel_hw"], "+.2f", ".2f", scale=100),
                     pm(ld["jaxdamp"]["d"], ld["jaxdamp"]["hw"], "+.3g"),
                     pm(ld["jaxdamp"]["rel"], ld["jaxdamp"]["rel_hw"], "+.2f", ".2f", scale=100),
                     pm(ld["codes"]["d"], ld["codes"]["hw"], "+.3g"),
                     "yes" if ld["codes"]["agree"] else "NO"))
    if both:
        w("\n## Mindlin − viscous\n")
        L += scaffold.table(
            ("case", "LAMMPS [J]", "LAMMPS [%]", "jaxdamp [J]", "jaxdamp [%]",
             "LAMMPS − jaxdamp of the difference [J]", "codes agree (interval holds 0)"), rows)
    w("\n## Per bed\n")
    L += scaffold.table(
        ("case", "law", "seed", "window", "LAMMPS [J]", "jaxdamp [J]", "difference [%]",
         "LAMMPS [µs/step]", "jaxdamp [µs/step]", "jaxdamp balance error"),
        [(case, law, x["seed"], f"{x['start'] + 1}–{x['start'] + x['kept']}",
          f"{x['ml']:.4g}", f"{x['mj']:.4g}", f"{x['rel'] * 100:+.2f}",
          f"{x['us_l']:.1f}", f"{x['us_j']:.1f}", f"{x['jaxdamp_balance_error']:.2g}")
         for case in cases for law in laws for x in table[(case, law)]["beds"]])
    w("\nWall times on a shared 2-core machine: not benchmarks (`benchmarks/bench_spring.py` "
      "is). LAMMPS' dissipation is its energy balance at the period boundaries (input work − "
      "Δ(kinetic incl. rotation + gravitational + elastic)); the springs' stored energy, "
      "LAMMPS' contact history, is not in it — it enters a period's loss only through its "
      "change between two boundaries.\n")
    w("## Verdict\n")
    worst = {law: max(r["difference"] for r in checks[law]) for law in laws}
    w("- Oblique impacts: the codes' rebounds differ by at most "
      + " and ".join(f"{worst[law]:.2g} ({LABEL[law]})" for law in laws)
      + " of the normal speed.")
    for case in cases:
        for law in laws:
            r = table[(case, law)]
            w(f"- {case}, {law}: LAMMPS − jaxdamp "
              f"{pm(r['rel'], r['rel_hw'], '+.2f', '.2f', scale=100)} % (paired 95 %): "
              + ("within ±1 %." if within_target(r) else
                 "NOT shown within ±1 % (the interval reaches beyond it"
                 + (", and excludes 0: the codes differ" if abs(r["rel"]) > r["rel_hw"]
                    else "") + ")."))
        if not both:
            continue
        ld = lds[case]
        w(f"- {case}: Mindlin − viscous is "
          f"{pm(ld['jaxdamp']['rel'], ld['jaxdamp']['rel_hw'], '+.2f', '.2f', scale=100)} % in "
          f"jaxdamp and {pm(ld['lammps']['rel'], ld['lammps']['rel_hw'], '+.2f', '.2f', scale=100)}"
          " % in LAMMPS; " + ("the codes agree on it (the interval of their disagreement, "
                              f"{pm(ld['codes']['d'], ld['codes']['hw'], '+.3g')} "
                              "J, holds 0)." if ld["codes"]["agree"] else
                              "the codes DISAGREE on it (the interval "
                              f"{pm(ld['codes']['d'], ld['codes']['hw'], '+.3g')} "
                              "J excludes 0)."))
    if s["periods"] < 10:
        w(f"- Quick mode: {s['periods']} periods per window only — the estimates are rough.")
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, options, report=report)


if __name__ == "__main__":
    main()
