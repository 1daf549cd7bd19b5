"""Energy conservation, the energy balance, and sliding-to-rolling at 5/7."""

import math

import numpy as np
import pytest
from helpers import ENGINES, ENGINES_UNSIMULATED, config, engine_overrides, gas, run_steps, start

from jaxdamp.cases import presets
from jaxdamp.config import Material, Primary, apply_overrides
from jaxdamp.physics.model import CH, build
from jaxdamp.studies.runner import run

ELASTIC = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=0.0, gamma_s=0.0)


@pytest.mark.parametrize("engine", ENGINES_UNSIMULATED)
def test_energy_conserved_without_damping(engine):
    """γ_n = γ_s = 0, no primary damping, a free box (K = C = U = 0): the total mechanical
    energy (grains + box) is conserved to 1e-6 relative over 1e5 steps with ~40 % of the
    samples inside collisions (27 grains in a 2 cm box).

    dt = t_c/400: velocity Verlet errs by ~(dt/t_c)^2.5 per Hertz collision (next test), so at
    the default t_c/50 the same run drifts by ~1e-4; between collisions the energy is
    conserved to < 1e-6 and inside them it fluctuates by < 5e-6 (no drift)."""
    n = 27
    cfg = config(n=n, radius=2e-3, material=ELASTIC, box=(0.02, 0.02, 0.02), system="primary",
                 primary=Primary(M=0.05, K=0.0, C=0.0, U=0.0), v_impact=1.0,
                 dt_per_collision=400)
    model, pb, st, nbrs = start(cfg, *gas(n))
    st, nbrs, rec = run_steps(model, pb, st, nbrs, 1000, 100, engine=engine)
    e0 = float(st.e_start[0])
    assert np.all(rec["work"] == 0.0)  # nothing dissipates, nothing drives
    err = np.abs(rec["balance_residual"]) / e0
    free = rec["e_elastic"] == 0
    print(f"relative energy error over 1e5 steps: {err[free].max():.3g} between collisions, "
          f"{err.max():.3g} overall; {1 - free.mean():.0%} of samples in contact")
    assert 0.2 < 1 - free.mean() and free.sum() > 100  # many collisions, many free samples
    assert err[free].max() < 1e-6
    assert err.max() < 5e-6
    assert np.abs(rec["e_rotational"] - rec["e_rotational"][0]).max() < 1e-12 * e0  # no friction


@pytest.mark.long  # 36 s on 2 cores
def test_collision_energy_error_converges_at_order_two_and_a_half():
    """Energy error of one elastic head-on collision vs dt: ~(dt/t_c)^2.5, 5e-5 at t_c/50."""
    R = 2.5e-3
    errors = []
    for frac in (50, 100, 200):
        cfg = config(n=2, radius=R, material=ELASTIC, v_impact=1.0, dt_per_collision=frac)
        dt = float(build(cfg)[1].dt)
        errs = []
        for offset in np.linspace(0, 1, 4, endpoint=False):  # contact onset within a step
            gap = 0.2 * R + offset * dt
            model, pb, st, nbrs = start(cfg, [[0.025 - R - gap / 2, 0.025, 0.025],
                                              [0.025 + R + gap / 2, 0.025, 0.025]],
                                        [[0.5, 0, 0], [-0.5, 0, 0]])
            st, nbrs, _ = run_steps(model, pb, st, nbrs, 1, int(gap / dt) + 3 * frac)
            v = np.asarray(st.v[0])
            errs.append(abs(0.5 * (v**2).sum() / 0.25 - 1))
        errors.append(np.mean(errs))
    order = np.log2(errors[0] / errors[1]), np.log2(errors[1] / errors[2])
    print("per-collision energy error at t_c/50, /100, /200:", errors, "order", order)
    assert errors[0] < 1e-4
    assert 2.2 < min(order) and max(order) < 3.0


@pytest.mark.parametrize("engine", ENGINES)
def test_sliding_sphere_ends_rolling_at_five_sevenths(engine):
    """A sphere launched sliding (ω = 0) on the floor with Coulomb friction ends rolling
    without slip at 5/7 of its initial speed (1 %)."""
    steel = presets.SANCHEZ_STEEL
    R, v0 = 3e-3, 0.1
    cfg = config(n=1, radius=R, material=steel, gravity=9.8, stiffness_scale=0.01)
    m = steel.density * 4 / 3 * math.pi * R**3
    E_star = 0.01 * steel.E / (2 * (1 - steel.nu**2))
    k_n = 4 / 3 * E_star * math.sqrt(R)
    xi0 = (m * 9.8 / k_n) ** (2 / 3)  # resting overlap
    model, pb, st, nbrs = start(cfg, [[0.01, 0.025, R - xi0]], [[v0, 0, 0]])
    dt = float(pb.dt[0])
    n_rec = 30
    every = int(0.001 / dt)  # 30 ms: sliding stops after 2/7 v0 / (μ g) ≈ 10 ms
    st, nbrs, rec = run_steps(model, pb, st, nbrs, n_rec, every, engine=engine)
    v = np.asarray(st.v[0][0])
    w = np.asarray(st.w[0][0])
    assert v[0] == pytest.approx(5 / 7 * v0, rel=0.01)
    # rolling without slip: contact point at rest, v_x = R ω_y
    assert R * w[1] == pytest.approx(v[0], rel=1e-3)
    loss = rec["work"][-1, CH["pw_friction"]]
    # friction dissipated the kinetic energy lost: ½ m v0² (1 - 5/7) within 2 %
    assert loss == pytest.approx(0.5 * m * v0**2 * 2 / 7, rel=0.02)


@pytest.mark.parametrize("engine", [  # float32 37 s, jax 50 s each on 2 cores: CI's second step
    pytest.param(e, marks=pytest.mark.long) if e in ("float32", "jax") else e
    for e in ENGINES_UNSIMULATED])
@pytest.mark.parametrize("system", ["primary", "driven"])
def test_energy_balance_closes_in_driven_damper(system, engine):
    """input work = Δ(mechanical energy) + all losses, to better than 1e-3 relative, for a
    damper (40 grains, friction and collisions) on the primary (S1) and in a driven box (S2)."""
    cfg = presets.get("sanchez2012-optimal")
    over = ["grains.0.count=40", "box.Lz=0.06", "numerics.duration=0.2",
            "numerics.chunk=0.1", "numerics.settle_time=0.3", *engine_overrides(engine)]
    if system == "driven":
        over += ["system='driven'", "drive.amplitude=0.004", "frequency=20"]
    cfg = apply_overrides(cfg, over)
    res = run(cfg, progress=False, echo=None)
    s = res.summary
    print({k: s[k] for k in ("balance_error", "granular_loss_per_cycle", "input_per_cycle")})
    assert s["granular_loss_per_cycle"] > 0
    assert s["pp_friction_per_cycle"] > 0 and s["pw_normal_per_cycle"] > 0
    assert s["balance_error"] < 1e-3
