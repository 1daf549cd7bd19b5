"""Oblique impact of an elastic sphere on a rigid wall through the tangential spring with history
(Hertz normal, Mindlin tangential, no damping): the rebound against the impact angle, the
benchmark of Thornton, Cummins & Cleary (2011, Powder Technol.), issue 39.

    python experiments/oblique_impact.py [--quick] [--out DIR] [--from-data]   # about 20 s

A thesis steel sphere (``sanchez2012-optimal``'s material, its real modulus, R = 3 mm) meets
the wall at 1 m/s normal speed and a tangential speed ``v_t = tan θ``, not spinning, through
:func:`jaxdamp.physics.tangential.oblique_impact` (the law alone, no engine). In Thornton's
normalisation, with ``κ = 2 (1 − ν)/(2 − ν)`` (Mindlin's tangential over normal stiffness),

    Ψ1 = κ u_i / (μ v_n),   Ψ2 = κ u_r / (μ v_n'),

``u`` the contact point's tangential velocity before (i) and after (r) the impact. Rigid-body
Coulomb theory (e = 1) gives two regimes. While the contact slides throughout (``Ψ1 ≥ 7κ``)
the tangential impulse is ``μ`` times the normal one: ``Ψ2 = Ψ1 − 7κ`` and ``R ω = 5 μ v_n``.
Below that the surfaces end rolling: ``Ψ2 = 0`` and ``R ω = (5/7) u_i``. The elastic spring
departs from the second regime. The contact's tangential compliance stores energy and gives
it back, and the contact point oscillates along the wall while the contact lasts, so ``u_r``
does not vanish. For the small-angle (no-slip) limit the continuous equations of the
incremental spring (``ξ'' = −F_n/m``, ``F_s' = −k_t u`` and, while unloading,
``+ F_s ξ'/(2ξ)``, ``u' = (7/2) F_s/m``) are solved independently with scipy's adaptive
Runge–Kutta. (Near the contact's end ``F_n → 0`` faster than the rescaled spring force, so the
discrete contact always slips a little there: at Ψ1 = 0.05 it ends 3.8e-4 of ``u_i`` below
the no-slip ODE, converged in the step count.)

The spring is the incremental force form (:mod:`jaxdamp.physics.tangential`; until
2026-12-06 it stored a displacement, ``F_s = −k_t s``, which gave Ψ2/Ψ1 = 0.975 in the no-slip
limit instead of 0.541: with a stored displacement the growing and shrinking stiffness creates
and destroys tangential force, and energy, without any displacement; LAMMPS offers both forms.
Which of the two Maw, Barber & Fawcett's curves favour is not checked here: see below).

Not compared: the curves of Maw, Barber & Fawcett (1976, 1981). They are numerical solutions of
the partial-slip integral equations, and no table of them is available here. The no-slip
Mindlin spring is known to differ from them in the transition (Thornton et al. 2011).

Writes ``data.h5``, ``figure.png`` (Ψ2 and the rebound spin against Ψ1) and ``summary.md``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp

from jaxdamp.cases import presets
from jaxdamp.io.common import put
from jaxdamp.physics import tangential as tg
from jaxdamp.physics.contact import hertz_normal_scalar, shear_compliance
from jaxdamp.studies import scaffold

R, VN = 3e-3, 1.0  # [m], [m/s]


def _material():
    steel = presets.get("sanchez2012-optimal").grains[0].material
    E_star = steel.E / (1.0 - steel.nu**2)  # against a rigid wall
    G_star = 1.0 / shear_compliance(steel.E, steel.nu)
    m = steel.density * 4.0 / 3.0 * math.pi * R**3
    return steel, E_star, G_star, m


def _laws(E_star, G_star):
    """The contact's normal force ``F_n(ξ)`` (the Hertz law, elastic: ``R* = R`` on a wall)
    and tangential stiffness ``k_t(ξ)`` (:func:`tangential.stiffness_scalar`)."""
    k = (4.0 / 3.0) * E_star * math.sqrt(R)  # hertz_pair_scalar's k_n

    def normal(xi):
        return hertz_normal_scalar(xi, math.sqrt(xi), 0.0, k, 0.0)[0]

    def kt(xi):
        return tg.stiffness_scalar(G_star, R, xi)
    return normal, kt


def stick_limit(E_star, G_star, m) -> float:
    """``u_r / u_i`` of the continuous no-slip equations of the incremental spring (scipy,
    rtol 1e-10): ``F_s' = −k_t u``, and ``+ F_s ξ'/(2 ξ)`` while the contact unloads (the
    force scaled with ``k_t ∝ sqrt(ξ)``); the small-angle limit of ``Ψ2/Ψ1`` for ``e = 1``."""
    normal, kt = _laws(E_star, G_star)

    def rhs(t, y):
        xi, xid, f, u = y
        x = max(xi, 1e-300)
        df = -kt(x) * u + (0.5 * f * xid / x if xid < 0 else 0.0)
        return [xid, -normal(x) / m, df, 3.5 * f / m]

    def left(t, y):  # just before the end: the rate of F_s ∝ sqrt(ξ) is singular at 0
        return y[0] - 1e-14
    left.terminal, left.direction = True, -1
    sol = solve_ivp(rhs, (0.0, 1.0), [1e-13, VN, 0.0, 1.0], rtol=1e-10, atol=1e-16,
                    events=left)
    return float(sol.y_events[0][0][3])


def compute(quick: bool, log, ctx):
    steel, E_star, G_star, m = _material()
    nu, mu = steel.nu, steel.mu
    kappa = 2.0 * (1.0 - nu) / (2.0 - nu)
    psi1 = np.geomspace(0.05, 30.0, 12 if quick else 40)
    steps = 2000 if quick else 20000
    normal, kt = _laws(E_star, G_star)
    rows = []
    for p1 in psi1:
        vt = p1 * mu * VN / kappa
        out = tg.oblique_impact(normal, kt, m, R, VN, vt, mu, 0.0, steps)
        rows.append(out)
    limit = stick_limit(E_star, G_star, m)
    log(f"{len(rows)} impacts, {steps} steps per linear contact time; stick limit u_r/u_i = "
        f"{limit:.5f}")
    result = dict(psi1=psi1, rows=rows, kappa=kappa, mu=mu, nu=nu, E=steel.E, m=m,
                  steps=steps, limit=limit)
    return result, lambda out, prov: record(result, out, prov)


def record(result, out, prov):
    rows = result["rows"]
    with scaffold.data_file(out, prov, kappa=result["kappa"], mu=result["mu"], nu=result["nu"],
                            E=result["E"], mass=result["m"], radius=R, vn=VN,
                            steps=result["steps"], stick_limit=result["limit"]) as h:
        put(h, "psi1", result["psi1"], "1")
        for name in tg.Impact._fields:
            unit = {"steps": "1"}.get(name, "m/s" if name in ("vn", "vt", "spin", "u") else "J")
            put(h, f"impact/{name}", np.array([getattr(r, name) for r in rows]), unit)


def report(data, out):
    a = data.attrs
    kappa, mu = a["kappa"], a["mu"]
    psi1 = np.asarray(data["psi1"])
    imp = {k: np.asarray(data["impact"][k]) for k in tg.Impact._fields}
    vt0 = psi1 * mu * a["vn"] / kappa
    psi2 = kappa * imp["u"] / (mu * imp["vn"])
    spin = imp["spin"] / (mu * a["vn"])
    rigid2 = np.where(psi1 >= 7 * kappa, psi1 - 7 * kappa, 0.0)
    rigid_spin = np.where(psi1 >= 7 * kappa, 5.0, (5.0 / 7.0) * psi1 / kappa)

    fig, (ax1, ax2) = scaffold.subplots(1, 2, figsize=(10, 4))
    ax1.plot(psi1, psi2, "o-", ms=3, label="Hertz–Mindlin spring (this law)")
    ax1.plot(psi1, rigid2, "k:", lw=1, label="rigid body, Coulomb (e = 1)")
    near = psi1 <= 1.0  # the no-slip limit holds at small angles only
    ax1.plot(psi1[near], a["stick_limit"] * psi1[near], "--", color="0.5", lw=1.5,
             label=f"no-slip limit (ODE): Ψ2 = {a['stick_limit']:.3f} Ψ1")
    ax1.set(xscale="log", xlabel="normalised impact angle Ψ1 = κ u_i / (μ v_n) [-]",
            ylabel="normalised rebound angle Ψ2 = κ u_r / (μ v_n') [-]")
    ax1.legend(fontsize=8)
    ax2.plot(psi1, spin, "o-", ms=3, label="Hertz–Mindlin spring")
    ax2.plot(psi1, rigid_spin, "k:", lw=1, label="rigid body, Coulomb")
    ax2.set(xscale="log", xlabel="normalised impact angle Ψ1 [-]",
            ylabel="rebound spin R ω / (μ v_n) [-]")
    ax2.legend(fontsize=8)
    fig.suptitle("elastic steel sphere on a rigid wall, v_n = 1 m/s", fontsize=9)
    scaffold.save_figure(fig, out)

    slide = psi1 >= 1.2 * 7 * kappa
    small = psi1 <= 0.1
    work = imp["work"]
    books = -work - (imp["damping"] + imp["slip"] + imp["spring"] - imp["stiffness"])
    ke_t = (0.5 * a["mass"] * (imp["vt"] ** 2 - vt0**2)
            + 0.5 * 0.4 * a["mass"] * imp["spin"] ** 2)
    L = [*scaffold.head("Oblique impact through the tangential spring with history", a),
         f"Steel sphere, R = {R * 1e3:g} mm, E = {a['E']:.3g} Pa, ν = {a['nu']}, μ = {mu}, "
         f"κ = 2(1 − ν)/(2 − ν) = {kappa:.4f}; rigid wall; no damping; {len(psi1)} impact "
         f"angles, {a['steps']} steps per linear contact time.", "",
         "## Against the two limits", ""]
    L += scaffold.table(
        ["regime", "impacts", "quantity", "ours", "reference", "largest |difference|"],
        [["sliding throughout (Ψ1 ≥ 1.2 · 7κ)", int(slide.sum()), "Ψ2 − (Ψ1 − 7κ)",
          "", "0", f"{np.abs(psi2 - rigid2)[slide].max():.2e}"],
         ["sliding throughout", int(slide.sum()), "R ω / (μ v_n)", "", "5",
          f"{np.abs(spin - 5.0)[slide].max():.2e}"],
         ["no slip (Ψ1 ≤ 0.1)", int(small.sum()), "Ψ2 / Ψ1",
          ", ".join(f"{x:.4f}" for x in (psi2 / psi1)[small]), f"{a['stick_limit']:.4f} (ODE)",
          f"{np.abs(psi2 / psi1 - a['stick_limit'])[small].max():.2e}"]])
    L += ["", "## The books of the tangential force", "",
          "Per impact, the work the sphere gave the contact equals damping + slip + the "
          "spring's energy left − the stiffness work (`tangential.Spring`); the sphere's "
          "tangential and rotational kinetic energy changed by the force's work, up to the "
          "integrator's error.", ""]
    L += scaffold.table(
        ["largest |books| / peak spring energy", "largest |ΔKE_t − work| / (½ m v_t²)",
         "slip loss at the largest Ψ1 [J]", "stiffness work at the smallest Ψ1 [J]"],
        [[f"{np.max(np.abs(books) / np.maximum(imp['max_spring'], 1e-300)):.1e}",
          f"{np.max(np.abs(ke_t - work) / (0.5 * a['mass'] * vt0**2)):.1e}",
          f"{imp['slip'][-1]:.3e}", f"{imp['stiffness'][0]:.3e}"]])
    L += ["", "The no-slip spring is elastic, but its stiffness falls to zero as the contact "
          "unloads, and the energy still in the spring at that moment is lost (the stiffness "
          "work). So even without slip or damping, an impact at a small angle loses part of "
          "its tangential energy.", "",
          "Not compared: Maw, Barber & Fawcett's partial-slip curves (no table available "
          "here).", ""]
    scaffold.write_summary(out, L)


main = scaffold.entry(__file__, __doc__, compute, report=report)


if __name__ == "__main__":
    main()
