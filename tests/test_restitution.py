"""Restitution, collision time and damping calibration (numpy reference for the DEM tests)."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from jaxdamp.physics import restitution as rst

# The 2023 paper's grains: steel, E = 2e9 Pa, ν = 0.3, ρ = 7850, R = 2.5 mm, like pair.
R = 2.5e-3
M = 7850 * 4 / 3 * math.pi * R**3
E_STAR = rst.effective_modulus(2e9, 0.3, 2e9, 0.3)
PAIR = dict(m_star=M / 2, R_star=R / 2, E_star=E_STAR)


def test_effective_modulus_and_stiffness():
    assert rst.effective_modulus(2e9, 0.3, 2e9, 0.3) == pytest.approx(2e9 / (2 * 0.91), rel=1e-14)
    # a rigid wall (E → ∞) leaves the grain's own compliance
    assert rst.effective_modulus(2e9, 0.3, 1e300, 0.0) == pytest.approx(2e9 / 0.91, rel=1e-14)
    # k_n = (4/3) E* sqrt(R*) is Müller & Pöschel's ρ = 2E sqrt(R*)/(3(1-ν²)) for a like pair
    rho = 2 * 2e9 * math.sqrt(R / 2) / (3 * (1 - 0.3**2))
    assert rst.hertz_stiffness(E_STAR, R / 2) == pytest.approx(rho, rel=1e-14)


def test_hertz_constant():
    """t_c = C (m*²/(R* E*² v))^{1/5}: C = 2 I (15/16)^{2/5} = 2.8682657 exactly."""
    I = quad(lambda x: 1 / math.sqrt(1 - x**2.5), 0, 1, limit=200)[0]
    assert rst.HERTZ_CONSTANT == pytest.approx(2 * I * (15 / 16) ** 0.4, rel=1e-10)
    assert rst.HERTZ_CONSTANT == pytest.approx(2.868, rel=1e-3)  # literature
    # the numerically integrated undamped collision lasts that long, and is elastic
    eps, t_overlap, t_force = rst._integrate(0.0)
    assert eps == pytest.approx(1.0, abs=1e-9)
    assert t_overlap == pytest.approx(rst._T_ELASTIC, rel=1e-6)
    assert t_force == pytest.approx(rst._T_ELASTIC, rel=1e-6)
    for v in (0.1, 1.0, 7.0):  # in SI units: ξ0/v · T_elastic == collision_time
        c = rst.collision(**PAIR, v=v, A=1e-15)  # numerical path (c > 0), nearly elastic
        t_c = rst.collision_time(v=v, **PAIR)
        assert c.duration == pytest.approx(t_c, rel=1e-6)
        assert c.restitution == pytest.approx(1.0, abs=1e-8)
        assert rst.collision(**PAIR, v=v, gamma_n=0.0).duration == pytest.approx(t_c, rel=1e-12)


def test_damping_lengthens_overlap_and_shortens_force():
    """c = 0.3 (ε ≈ 0.72): overlap +4.0 %, force -5.3 % relative to the elastic time."""
    eps, t_overlap, t_force = rst._integrate(0.3)
    assert eps == pytest.approx(0.7220854, abs=1e-6)
    assert t_overlap / rst._T_ELASTIC == pytest.approx(1.0401, abs=2e-4)
    assert t_force / rst._T_ELASTIC == pytest.approx(0.9469, abs=2e-4)


def test_restitution_decreases_with_speed():
    A = rst.dissipative_constant(0.75, 1.0, **PAIR)
    eps = [rst.restitution(**PAIR, v=v, A=A) for v in (0.1, 0.5, 1.0, 2.0, 5.0)]
    assert all(a > b for a, b in zip(eps, eps[1:]))
    assert eps[2] == pytest.approx(0.75, abs=1e-10)
    # ε depends on v through c = β v^{1/5} only
    assert eps[0] == pytest.approx(rst._dimensionless(rst.collision(**PAIR, v=0.1, A=A).c)[0])


@pytest.mark.parametrize("target", [0.3, 0.75, 0.95])
def test_calibration_round_trip(target):
    A = rst.dissipative_constant(target, 1.0, **PAIR)
    assert rst.restitution(**PAIR, v=1.0, A=A) == pytest.approx(target, abs=1e-8)
    # the gamma_n form is the same law: γ_n = 1.5 A k_n
    k = rst.hertz_stiffness(E_STAR, R / 2)
    assert rst.restitution(**PAIR, v=1.0, gamma_n=1.5 * A * k) == pytest.approx(target, abs=1e-8)
    # and at another reference speed
    A2 = rst.dissipative_constant(target, 0.2, **PAIR)
    assert rst.restitution(**PAIR, v=0.2, A=A2) == pytest.approx(target, abs=1e-8)
    assert rst.dissipative_constant(1.0, 1.0, **PAIR) == 0.0


def test_paper_dissipative_constant():
    """ε = 0.75 at 1 m/s for the paper's grains (like pair): A = 5.2698e-6 s."""
    A = rst.dissipative_constant(0.75, 1.0, **PAIR)
    print(f"A(ε=0.75, 1 m/s) = {A:.6g} s, c = {rst.collision(**PAIR, v=1.0, A=A).c:.6g}")
    assert A == pytest.approx(5.26983e-6, rel=1e-5)


def test_numerics_agree_with_muller_poschel_pade():
    """Padé vs integrated law (measured): rel. deviation < 1e-3 for β v^{1/5} ≤ 0.3, < 6.5e-3
    down to ε = 0.5 (c = 0.7); small-dissipation slope 1.15345 (exact 1.1534489)."""
    cs = np.linspace(0.0, 0.3, 16)[1:]
    k = rst.hertz_stiffness(**{"E_star": E_STAR, "R_star": R / 2})
    worst = 0.0
    for c in cs:
        for v in (0.3, 3.0):  # A chosen so that β v^{1/5} = c
            A = c / (1.5 * (k / PAIR["m_star"]) ** 0.4 * v**0.2)
            col = rst.collision(**PAIR, v=v, A=A)
            assert col.c == pytest.approx(c, rel=1e-12)
            pade = rst.restitution_pade(A, v=v, **PAIR)
            worst = max(worst, abs(pade - col.restitution) / col.restitution)
    print(f"largest relative Padé deviation for c ≤ 0.3: {worst:.3g}")
    assert 5e-4 < worst < 1e-3
    A = rst.dissipative_constant(0.5, 1.0, **PAIR)
    assert rst.restitution_pade(A, v=1.0, **PAIR) == pytest.approx(0.5, rel=6.5e-3)
    # small-dissipation limit: 1 - ε = S c - O(c²), S exact = 1.1534489
    assert rst.SMALL_DISSIPATION_SLOPE == pytest.approx(1.15345, abs=1e-5)
    c = 1e-5
    assert (1 - rst._integrate(c)[0]) / c == pytest.approx(rst.SMALL_DISSIPATION_SLOPE, rel=2e-5)


def test_similarity_of_reduced_modulus():
    """E → λE with γ_n → γ_n λ^{3/5}: same ε at every speed, durations × λ^{-2/5}."""
    lam = 0.01
    g = 3660.0
    assert rst.scale_damping(g, lam) == pytest.approx(g * lam**rst.similarity_damping_exponent)
    for v in (0.2, 1.0, 4.0):
        a = rst.collision(**PAIR, v=v, gamma_n=g)
        b = rst.collision(M / 2, R / 2, lam * E_STAR, v, gamma_n=rst.scale_damping(g, lam))
        assert a.restitution < 0.99  # a real test: damping matters at this γ_n
        assert b.restitution == pytest.approx(a.restitution, abs=1e-8)
        assert b.duration == pytest.approx(a.duration * lam**-0.4, rel=1e-6)
        assert b.force_duration == pytest.approx(a.force_duration * lam**-0.4, rel=1e-6)


def test_bad_inputs_name_the_parameter():
    with pytest.raises(ValueError, match="restitution = 1.5"):
        rst.dissipative_constant(1.5, 1.0, **PAIR)
    with pytest.raises(ValueError, match="restitution = 0"):
        rst.dissipative_constant(0.0, 1.0, **PAIR)
    with pytest.raises(ValueError, match="restitution = nan"):
        rst.dissipative_constant(float("nan"), 1.0, **PAIR)
    with pytest.raises(ValueError, match="v = -1"):
        rst.collision_time(M, R, E_STAR, -1)
    with pytest.raises(ValueError, match="m_star = 0"):
        rst.collision(0.0, R, E_STAR, 1.0, A=1e-6)
    with pytest.raises(ValueError, match="E_star = inf"):
        rst.dissipative_constant(0.75, 1.0, M, R, math.inf)
    with pytest.raises(ValueError, match="exactly one"):
        rst.collision(**PAIR, v=1.0)
    with pytest.raises(ValueError, match="exactly one"):
        rst.collision(**PAIR, v=1.0, A=1e-6, gamma_n=10.0)
    with pytest.raises(ValueError, match="gamma_n = -1"):
        rst.collision(**PAIR, v=1.0, gamma_n=-1.0)
    with pytest.raises(ValueError, match="A = -1e-06"):
        rst.restitution_pade(-1e-6, v=1.0, **PAIR)
