"""Binary collisions of the contact law: restitution, duration, and damping calibration.

Pure numpy/scipy (no JAX): used to set parameters before a run and as the independent
reference against which the DEM step is tested.

For a head-on collision with effective mass ``m*`` [kg], Hertz stiffness
``k = (4/3) E* sqrt(R*)`` [N m^-3/2] and normal damping ``γ_n`` [kg s^-1 m^-1/2],
``m* ξ'' = -max(0, k ξ^{3/2} + γ_n sqrt(ξ) ξ')`` with ``ξ(0) = 0``, ``ξ'(0) = v``.
Scaling ``ξ = ξ0 X``, ``t = (ξ0 / v) T`` with ``ξ0 = (m* v² / k)^{2/5}`` gives

    X'' = -max(0, X^{3/2} + c X^{1/2} X'),   X(0) = 0, X'(0) = 1,
    c = γ_n v^{1/5} / (k^{3/5} m*^{2/5}) = β v^{1/5},   β = (3/2) A (k / m*)^{2/5}

with the paper's ``γ_n = (3/2) A k``. So the restitution depends on ``c`` alone — it is a
function of ``β v^{1/5}`` (Müller & Pöschel's ``v*² = β v^{1/5}``) — and every duration scales
as ``ξ0 / v ∝ (m*/k)^{2/5} v^{-1/5}``.

**Similarity under a reduced modulus.** Multiplying every modulus by λ multiplies ``k`` by λ;
scaling ``γ_n`` (and ``γ_s``) by ``λ^{3/5}`` keeps ``c`` — hence the restitution at every
speed — unchanged, and the tangential impulse ``∫ γ_s sqrt(ξ) |v_s| dt ∝ γ_s ξ0^{1/2} ξ0/v``
scales as ``λ^{3/5} λ^{-1/5} λ^{-2/5} = 1``: unchanged too, as is the Coulomb impulse
``μ ∫ F_n dt``. Only durations change, by ``λ^{-2/5}``. See :func:`scale_damping`.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import beta as beta_fn

#: Exponent of the damping similarity rule: γ → γ λ^{3/5} when E → λ E.
SIMILARITY_EXPONENT = 0.6

#: Dimensionless duration of an elastic Hertz collision, T = 2 (5/4)^{2/5} (2/5) B(2/5, 1/2).
_T_ELASTIC = 2.0 * 1.25**0.4 * 0.4 * beta_fn(0.4, 0.5)
#: t_c = HERTZ_CONSTANT (m*² / (R* E*² v))^{1/5}; ≈ 2.868 (the literature's 2.87).
HERTZ_CONSTANT = _T_ELASTIC * 0.75**0.4

#: Müller & Pöschel (PRE 84, 021302, 2011) [1/4] Padé coefficients.
_PADE = dict(a1=0.501086, b2=1.15345, b3=0.577977, b4=0.532178)


def effective_modulus(E1, nu1, E2, nu2):
    """``E*`` [Pa] with ``1/E* = (1 - ν1²)/E1 + (1 - ν2²)/E2``."""
    return 1.0 / ((1.0 - nu1**2) / E1 + (1.0 - nu2**2) / E2)


def hertz_stiffness(E_star, R_star):
    """``k_n = (4/3) E* sqrt(R*)`` [N m^-3/2] (force ``k_n ξ^{3/2}``)."""
    return 4.0 / 3.0 * E_star * math.sqrt(R_star)


def _check_positive(**kw):
    for name, value in kw.items():
        if not (isinstance(value, (int, float, np.floating)) and math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value!r}: must be a finite number > 0")


def collision_time(m_star, R_star, E_star, v):
    """Duration [s] of an elastic Hertz collision at impact speed ``v`` [m/s]:
    ``2.868 (m*² / (R* E*² v))^{1/5}`` (exact constant :data:`HERTZ_CONSTANT`)."""
    _check_positive(m_star=m_star, R_star=R_star, E_star=E_star, v=v)
    return HERTZ_CONSTANT * (m_star**2 / (R_star * E_star**2 * v)) ** 0.2


class Collision(NamedTuple):
    """Outcome of one head-on collision.

    Attributes:
      restitution: ``-ξ'(end) / ξ'(0)`` [-].
      duration: time with overlap ``ξ > 0`` [s] (what a DEM step counts as contact).
      force_duration: time with a non-zero force [s] (shorter when the clip to zero acts).
      c: the dimensionless damping ``β v^{1/5}``.
    """

    restitution: float
    duration: float
    force_duration: float
    c: float


@lru_cache(maxsize=4096)
def _dimensionless(c: float) -> tuple[float, float, float]:
    """(restitution, overlap duration, force duration) of ``X'' = -max(0, X^1.5 + c X^.5 X')``."""
    if c == 0.0:
        return 1.0, _T_ELASTIC, _T_ELASTIC

    def rhs(_, y):
        x, u = y
        s = math.sqrt(max(x, 0.0))
        return [u, -max(0.0, s * (x + c * u))]

    def force_ends(_, y):  # X + c X' = 0 while separating: the force clips to zero
        return y[0] + c * y[1]

    force_ends.terminal = True
    force_ends.direction = -1

    def overlap_ends(_, y):
        return y[0]

    overlap_ends.terminal = True
    overlap_ends.direction = -1

    sol = solve_ivp(rhs, (0.0, 50.0), [0.0, 1.0], method="DOP853", rtol=1e-11, atol=1e-13,
                    events=(force_ends, overlap_ends))
    t_force = None
    for ev, ts in enumerate(sol.t_events):
        # skip the trivial event at t = 0 (X = 0, X + cX' = c > 0 is not a crossing anyway)
        ts = [t for t in ts if t > 1e-9]
        if ts:
            t_force = ts[0]
            x, u = sol.y_events[ev][-1]
            break
    if t_force is None:
        raise RuntimeError(f"collision with c = {c} did not end within the integration window")
    eps = -u
    t_overlap = t_force + (x / eps if eps > 0 else math.inf)
    return eps, t_overlap, t_force


def collision(m_star, R_star, E_star, v, A=None, gamma_n=None) -> Collision:
    """Integrate one head-on collision of the contact law (SPEC §2).

    Args:
      m_star: effective mass [kg]; R_star: effective radius [m]; E_star: effective modulus [Pa];
      v: impact speed [m/s].
      A: the paper's dissipative constant [s] (``γ_n = 1.5 A k``), or
      gamma_n: the thesis' damping [kg s^-1 m^-1/2]. Exactly one of them.
    """
    _check_positive(m_star=m_star, R_star=R_star, E_star=E_star, v=v)
    if (A is None) == (gamma_n is None):
        raise ValueError("give exactly one of A and gamma_n")
    k = hertz_stiffness(E_star, R_star)
    g = 1.5 * A * k if A is not None else gamma_n
    if g < 0:
        raise ValueError(f"{'A' if A is not None else 'gamma_n'} = {A if A is not None else gamma_n}: must be ≥ 0")
    c = g * v**0.2 / (k**0.6 * m_star**0.4)
    eps, t_overlap, t_force = _dimensionless(float(c))
    tau = (m_star * v**2 / k) ** 0.4 / v
    return Collision(eps, t_overlap * tau, t_force * tau, float(c))


def restitution(m_star, R_star, E_star, v, A=None, gamma_n=None) -> float:
    """Coefficient of restitution [-] of :func:`collision`."""
    return collision(m_star, R_star, E_star, v, A=A, gamma_n=gamma_n).restitution


def dissipative_constant(restitution, v, m_star, R_star, E_star) -> float:
    """The paper's ``A`` [s] that gives coefficient of restitution ``restitution`` at speed ``v``.

    Solved on the exact (numerically integrated) restitution of the force law; ``ε = 1`` gives 0.
    """
    if not (isinstance(restitution, (int, float)) and 0.0 < restitution <= 1.0):
        raise ValueError(f"restitution = {restitution!r}: must be in (0, 1]")
    _check_positive(v=v, m_star=m_star, R_star=R_star, E_star=E_star)
    if restitution == 1.0:
        return 0.0
    hi = 1.0
    while _dimensionless(hi)[0] > restitution:
        hi *= 2.0
        if hi > 1e6:
            raise ValueError(f"restitution = {restitution}: too small to reach")
    c = brentq(lambda c: _dimensionless(c)[0] - restitution, 0.0, hi, xtol=1e-14, rtol=1e-13)
    k = hertz_stiffness(E_star, R_star)
    return c / (1.5 * (k / m_star) ** 0.4 * v**0.2)


def restitution_pade(A, m_star, R_star, E_star, v) -> float:
    """Müller & Pöschel's [1/4] Padé approximant of ε for the force
    ``ρ ξ^{3/2} + (3/2) A ρ sqrt(ξ) ξ'`` with ``ρ = k_n``: ``v*² = β v^{1/5}`` with
    ``β = (3/2) A (ρ / m*)^{2/5}`` — exactly the ``c`` of this module (consistent with the
    numerics, see ``tests/test_restitution.py``)."""
    _check_positive(m_star=m_star, R_star=R_star, E_star=E_star, v=v)
    k = hertz_stiffness(E_star, R_star)
    vs = math.sqrt(1.5 * A * (k / m_star) ** 0.4 * v**0.2)
    p = _PADE
    num = 1.0 + p["a1"] * vs
    return num / (num + p["b2"] * vs**2 + p["b3"] * vs**3 + p["b4"] * vs**4)


def scale_damping(gamma, stiffness_scale):
    """``γ λ^{3/5}``: the damping that keeps every collision's outcome when moduli scale by λ
    (module docstring)."""
    return gamma * stiffness_scale**SIMILARITY_EXPONENT
