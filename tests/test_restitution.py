"""Restitution, collision time and damping calibration (numpy reference for the DEM tests)."""

import math

import numpy as np
import pytest

from jaxdamp import restitution as rst

# The 2023 paper's grains: steel, E = 2e9 Pa, ν = 0.3, ρ = 7850, R = 2.5 mm, like pair.
R = 2.5e-3
M = 7850 * 4 / 3 * math.pi * R**3
E_STAR = rst.effective_modulus(2e9, 0.3, 2e9, 0.3)
PAIR = dict(m_star=M / 2, R_star=R / 2, E_star=E_STAR)


def test_hertz_constant():
    """The exact constant of t_c = C (m*²/(R* E*² v))^{1/5} is 2.868 (literature: 2.87)."""
    assert rst.HERTZ_CONSTANT == pytest.approx(2.8683, abs=1e-4)
    # and the integrated undamped collision lasts exactly that long
    for v in (0.1, 1.0, 7.0):
        c = rst.collision(**PAIR, v=v, gamma_n=0.0)
        assert c.restitution == 1.0
        assert c.duration == pytest.approx(rst.collision_time(v=v, **PAIR), rel=1e-12)
    tiny = rst.collision(**PAIR, v=1.0, A=1e-12)  # numerical integration, nearly elastic
    assert tiny.duration == pytest.approx(rst.collision_time(v=1.0, **PAIR), rel=1e-6)
    assert tiny.restitution == pytest.approx(1.0, abs=1e-5)


def test_restitution_decreases_with_speed():
    A = rst.dissipative_constant(0.75, 1.0, **PAIR)
    eps = [rst.restitution(**PAIR, v=v, A=A) for v in (0.1, 0.5, 1.0, 2.0, 5.0)]
    assert all(a > b for a, b in zip(eps, eps[1:]))
    assert eps[2] == pytest.approx(0.75, abs=1e-10)


@pytest.mark.parametrize("target", [0.3, 0.75, 0.95])
def test_calibration_round_trip(target):
    A = rst.dissipative_constant(target, 1.0, **PAIR)
    assert rst.restitution(**PAIR, v=1.0, A=A) == pytest.approx(target, abs=1e-9)
    # gamma_n form is the same law: γ_n = 1.5 A k_n
    k = rst.hertz_stiffness(E_STAR, R / 2)
    assert rst.restitution(**PAIR, v=1.0, gamma_n=1.5 * A * k) == pytest.approx(target, abs=1e-9)


def test_paper_dissipative_constant():
    """ε = 0.75 at 1 m/s for the paper's grains; the value of A is recorded here."""
    A = rst.dissipative_constant(0.75, 1.0, **PAIR)
    print(f"A(ε=0.75, 1 m/s) = {A:.6g} s")
    assert 1e-6 < A < 1e-4


def test_numerics_agree_with_muller_poschel_pade():
    """The [1/4] Padé is accurate to ~1 % over ε ∈ [0.5, 1) (its stated range); the
    small-dissipation slope 1 - ε ≈ 1.15345 β v^{1/5} agrees to 1e-3."""
    worst = 0.0
    for target in np.linspace(0.5, 0.99, 12):
        A = rst.dissipative_constant(float(target), 1.0, **PAIR)
        for v in (0.3, 1.0, 3.0):
            exact = rst.restitution(**PAIR, v=v, A=A)
            pade = rst.restitution_pade(A, v=v, **PAIR)
            worst = max(worst, abs(pade - exact) / exact)
    print(f"largest relative Padé deviation: {worst:.3g}")
    assert worst < 0.01
    c = 1e-4
    eps = rst._dimensionless(c)[0]
    assert (1 - eps) / c == pytest.approx(1.15345, rel=1e-3)


def test_similarity_of_reduced_modulus():
    """E → λE with γ_n → γ_n λ^{3/5}: same ε at every speed, durations × λ^{-2/5}."""
    lam = 0.01
    g = 3660.0
    for v in (0.2, 1.0, 4.0):
        a = rst.collision(**PAIR, v=v, gamma_n=g)
        b = rst.collision(M / 2, R / 2, lam * E_STAR, v, gamma_n=rst.scale_damping(g, lam))
        assert b.restitution == pytest.approx(a.restitution, abs=1e-9)
        assert b.duration == pytest.approx(a.duration * lam**-0.4, rel=1e-8)


def test_bad_inputs_name_the_parameter():
    with pytest.raises(ValueError, match="restitution = 1.5"):
        rst.dissipative_constant(1.5, 1.0, **PAIR)
    with pytest.raises(ValueError, match="restitution = 0"):
        rst.dissipative_constant(0.0, 1.0, **PAIR)
    with pytest.raises(ValueError, match="v = -1"):
        rst.collision_time(M, R, E_STAR, -1)
    with pytest.raises(ValueError, match="exactly one"):
        rst.collision(**PAIR, v=1.0)
