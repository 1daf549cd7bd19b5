"""Binary collisions of the contact laws: restitution, duration, and damping calibration
(Hertz + viscoelastic; the linear spring–dashpot at the end of the module, in closed form).

Pure numpy/scipy (no JAX): used to set parameters before a run and as the independent
reference against which the DEM step is tested. SI units throughout.

For a head-on collision with effective mass ``m*`` [kg], Hertz stiffness
``k = (4/3) E* sqrt(R*)`` [N m^-3/2] and normal damping ``γ_n`` [kg s^-1 m^-1/2],
``m* ξ'' = -max(0, k ξ^{3/2} + γ_n sqrt(ξ) ξ')`` with ``ξ(0) = 0``, ``ξ'(0) = v``.
Scaling ``ξ = ξ0 X``, ``t = (ξ0 / v) T`` with ``ξ0 = (m* v² / k)^{2/5}`` gives

    X'' = -max(0, X^{3/2} + c X^{1/2} X'),   X(0) = 0, X'(0) = 1,
    c = γ_n v^{1/5} / (k^{3/5} m*^{2/5}) = β v^{1/5},   β = (3/2) A (k / m*)^{2/5}

with the paper's ``γ_n = (3/2) A k``. So the restitution depends on ``c`` alone — it is a
function of ``β v^{1/5}`` (Müller & Pöschel's ``v*² = β v^{1/5}``) — and every duration scales
as ``ξ0 / v ∝ (m*/k)^{2/5} v^{-1/5}``. (``ξ0`` differs from the elastic maximum overlap
``ξ_max = (5/4)^{2/5} ξ0`` only by a constant.) The dimensionless problem is integrated once per
``c`` (cached), so the result is equally accurate for any stiffness, mass or speed.

**Two durations.** With the clip ``max(0, ·)`` the force vanishes at ``X + c X' = 0``, while the
grains still overlap; they then separate at constant speed, so the restitution is fixed there.
:attr:`Collision.duration` is the time with overlap ``ξ > 0`` (what a DEM step counts as
contact; damping *lengthens* it: +1.2 % at ``c = 0.1``, +4.0 % at ``c = 0.3``, +16.6 % at
``c = 1``); :attr:`Collision.force_duration` is the time with a non-zero force (damping
*shortens* it: -1.9 %, -5.3 %, -14.5 % at the same ``c``).

**Similarity under a reduced modulus.** Multiplying every modulus by λ multiplies ``k`` by λ;
scaling ``γ_n`` (and ``γ_s``) by ``λ^{3/5}`` keeps ``c`` — hence the restitution at every
speed — unchanged; only durations change, by ``λ^{-2/5}``. See :func:`scale_damping`.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import NamedTuple

from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import beta as beta_fn

#: Exponent of the damping similarity rule: γ → γ λ^{3/5} when every modulus E → λ E.
similarity_damping_exponent = 0.6
SIMILARITY_EXPONENT = similarity_damping_exponent  # upper-case alias

#: ``I = ∫_0^1 dx / sqrt(1 - x^{5/2}) = (2/5) B(2/5, 1/2) ≈ 1.4716376`` (substitute u = x^{5/2}).
_I_HERTZ = 0.4 * float(beta_fn(0.4, 0.5))
#: Dimensionless duration of an elastic Hertz collision in units of ``ξ0 / v``:
#: ``2 I ξ_max / ξ0`` with ``ξ_max = (5/4)^{2/5} ξ0`` — ≈ 3.2180655.
_T_ELASTIC = 2.0 * _I_HERTZ * 1.25**0.4
#: ``t_c = HERTZ_CONSTANT (m*² / (R* E*² v))^{1/5}`` [-]: ``2 I (15/16)^{2/5} ≈ 2.8682657``
#: (the literature's 2.87 / 2.868).
HERTZ_CONSTANT = 2.0 * _I_HERTZ * (15.0 / 16.0) ** 0.4
#: Exact small-dissipation slope, ``1 - ε ≈ SMALL_DISSIPATION_SLOPE · β v^{1/5}``: first-order
#: energy loss along the elastic trajectory, ``(4/5)(5/4)^{3/5} B(3/5, 3/2) ≈ 1.1534489``
#: (Müller & Pöschel's b2 = 1.15345 rounds it).
SMALL_DISSIPATION_SLOPE = 0.8 * 1.25**0.6 * float(beta_fn(0.6, 1.5))

#: Müller & Pöschel (PRE 84, 021302, 2011) [1/4] Padé coefficients.
_PADE = dict(a1=0.501086, b2=1.15345, b3=0.577977, b4=0.532178)


def _real(name, value, *, positive=True):
    """``value`` as a finite float, > 0 (``positive``) or ≥ 0; else ValueError naming it."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} = {value!r}: must be a real number") from None
    if isinstance(value, bool) or not math.isfinite(x) or (x <= 0 if positive else x < 0):
        raise ValueError(f"{name} = {value!r}: must be a finite number {'>' if positive else '≥'} 0")
    return x


def _check_positive(**kw):
    return [_real(name, value) for name, value in kw.items()]


def effective_modulus(E1, nu1, E2, nu2):
    """Effective modulus ``E*`` [Pa], ``1/E* = (1 - ν1²)/E1 + (1 - ν2²)/E2``.

    ``E1, E2`` are Young's moduli [Pa], ``nu1, nu2`` Poisson's ratios [-].
    """
    return 1.0 / ((1.0 - nu1**2) / E1 + (1.0 - nu2**2) / E2)


def hertz_stiffness(E_star, R_star):
    """Hertz stiffness ``k_n = (4/3) E* sqrt(R*)`` [N m^-3/2] (force ``k_n ξ^{3/2}``).

    ``E_star`` effective modulus [Pa], ``R_star`` effective radius [m].
    """
    return 4.0 / 3.0 * E_star * math.sqrt(R_star)


def collision_time(m_star, R_star, E_star, v):
    """Duration [s] of an elastic (undamped) Hertz collision at impact speed ``v`` [m/s].

    ``t = 2 I ξ_max / v`` with ``I = ∫_0^1 dx/sqrt(1 - x^{5/2})`` and
    ``ξ_max = (5 m* v² / (4 k_n))^{2/5}``, i.e.
    ``t = HERTZ_CONSTANT (m*² / (R* E*² v))^{1/5}`` with the exact constant
    ``2 I (15/16)^{2/5} = 2.8682657``. ``m_star`` [kg], ``R_star`` [m], ``E_star`` [Pa].
    """
    m_star, R_star, E_star, v = _check_positive(m_star=m_star, R_star=R_star, E_star=E_star, v=v)
    return HERTZ_CONSTANT * (m_star**2 / (R_star * E_star**2 * v)) ** 0.2


class Collision(NamedTuple):
    """Outcome of one head-on collision.

    Attributes:
      restitution: ``-ξ'(end) / v`` [-], ``ξ'`` taken when the force ends.
      duration: time with overlap ``ξ > 0`` [s] (what a DEM step counts as contact; ≥ the
        elastic :func:`collision_time`).
      force_duration: time from first touch until the force ends [s] (≤ the elastic time).
      c: the dimensionless damping ``β v^{1/5} = γ_n v^{1/5} / (k_n^{3/5} m*^{2/5})`` [-].
    """

    restitution: float
    duration: float
    force_duration: float
    c: float


def _integrate(c: float) -> tuple[float, float, float]:
    """Integrate ``X'' = -max(0, X^{3/2} + c X^{1/2} X')``, ``X(0) = 0``, ``X'(0) = 1``.

    Returns (restitution, overlap duration, force duration), durations in units of ``ξ0/v``.
    Always numerical (also for ``c = 0``, where it reproduces :data:`_T_ELASTIC` to ~1e-11).
    """

    def rhs(_, y):
        x, u = y
        s = math.sqrt(max(x, 0.0))
        return [u, -max(0.0, s * (x + c * u))]

    def force_ends(_, y):  # X + c X' crosses 0 downwards: the force clips to zero
        return y[0] + c * y[1]

    force_ends.terminal = True
    force_ends.direction = -1

    def overlap_ends(_, y):
        return y[0]

    overlap_ends.terminal = True
    overlap_ends.direction = -1

    sol = solve_ivp(rhs, (0.0, 50.0), [0.0, 1.0], method="DOP853", rtol=1e-11, atol=1e-13,
                    events=(force_ends, overlap_ends))
    hits = [(ts[0], ys[0]) for ts, ys in zip(sol.t_events, sol.y_events)
            if len(ts) and ts[0] > 1e-9]  # a start-point zero is not the end
    if not hits:
        raise RuntimeError(f"collision with c = {c} did not end within the integration window")
    t_force, (x, u) = min(hits, key=lambda h: h[0])
    eps = -float(u)
    t_overlap = t_force + (max(float(x), 0.0) / eps if eps > 0 else math.inf)
    return eps, float(t_overlap), float(t_force)


@lru_cache(maxsize=4096)
def _dimensionless(c: float) -> tuple[float, float, float]:
    """Cached :func:`_integrate`; exact (analytic) for ``c = 0``."""
    if c == 0.0:
        return 1.0, _T_ELASTIC, _T_ELASTIC
    return _integrate(c)


def _gamma(k, A, gamma_n):
    if (A is None) == (gamma_n is None):
        raise ValueError(f"give exactly one of A and gamma_n (got A = {A!r}, gamma_n = {gamma_n!r})")
    if A is not None:
        return 1.5 * _real("A", A, positive=False) * k
    return _real("gamma_n", gamma_n, positive=False)


def collision(m_star, R_star, E_star, v, A=None, gamma_n=None) -> Collision:
    """Integrate one head-on collision of the contact law (docs/physics.md §2).

    Force ``F_n = max(0, k_n ξ^{3/2} + γ_n sqrt(ξ) ξ')`` from ``ξ = 0``, ``ξ' = v``.

    Args:
      m_star: effective mass [kg]. R_star: effective radius [m].
      E_star: effective modulus [Pa]. v: impact (normal) speed [m/s].
      A: the paper's dissipative constant [s] (``γ_n = 1.5 A k_n``), or
      gamma_n: the thesis' damping [kg s^-1 m^-1/2]. Exactly one of them, ≥ 0.
    """
    m_star, R_star, E_star, v = _check_positive(m_star=m_star, R_star=R_star, E_star=E_star, v=v)
    k = hertz_stiffness(E_star, R_star)
    g = _gamma(k, A, gamma_n)
    c = g * v**0.2 / (k**0.6 * m_star**0.4)
    eps, t_overlap, t_force = _dimensionless(float(c))
    tau = (m_star * v**2 / k) ** 0.4 / v
    return Collision(float(eps), t_overlap * tau, t_force * tau, float(c))


def restitution(m_star, R_star, E_star, v, A=None, gamma_n=None) -> float:
    """Coefficient of restitution [-] of :func:`collision` (same arguments and units)."""
    return collision(m_star, R_star, E_star, v, A=A, gamma_n=gamma_n).restitution


def dissipative_constant(restitution, v, m_star, R_star, E_star) -> float:
    """The paper's ``A`` [s] for which the force law gives restitution ``restitution`` at ``v``.

    Args: ``restitution`` in (0, 1]; ``v`` reference impact speed [m/s]; ``m_star`` [kg],
    ``R_star`` [m], ``E_star`` [Pa]. ``ε = 1`` gives ``A = 0``.

    Solved by brentq on the dimensionless damping ``c = 1.5 A (k_n/m*)^{2/5} v^{1/5}`` of the
    integrated (exact) restitution, which decreases monotonically from 1 at ``c = 0``; the
    bracket ``[0, hi]`` doubles ``hi`` from 1 (ε(1) ≈ 0.39) until ε(hi) < target.
    """
    try:
        eps_target = float(restitution)
    except (TypeError, ValueError):
        raise ValueError(f"restitution = {restitution!r}: must be a number in (0, 1]") from None
    if isinstance(restitution, bool) or not (0.0 < eps_target <= 1.0):
        raise ValueError(f"restitution = {restitution!r}: must be in (0, 1]")
    v, m_star, R_star, E_star = _check_positive(v=v, m_star=m_star, R_star=R_star, E_star=E_star)
    if eps_target == 1.0:
        return 0.0
    hi = 1.0
    while _dimensionless(hi)[0] > eps_target:
        hi *= 2.0
        if hi > 1e7:
            raise ValueError(f"restitution = {restitution!r}: too small to reach (c > 1e7)")
    c = brentq(lambda c: _dimensionless(c)[0] - eps_target, 0.0, hi, xtol=1e-15, rtol=1e-13)
    k = hertz_stiffness(E_star, R_star)
    return c / (1.5 * (k / m_star) ** 0.4 * v**0.2)


def restitution_pade(A, m_star, R_star, E_star, v) -> float:
    """Müller & Pöschel's (PRE 84, 021302, 2011) [1/4] Padé approximant of ε [-].

    Their force is ``ρ (ξ^{3/2} + (3/2) A sqrt(ξ) ξ')`` with ``ρ = 2E sqrt(R*)/(3(1-ν²))``, which
    for equal materials is exactly ``k_n = (4/3) E* sqrt(R*)``; ``β = (3/2) A (ρ/m*)^{2/5}``,
    ``v* = sqrt(β) v^{1/10}``, ``ε = (1 + a1 v*)/(1 + a1 v* + b2 v*² + b3 v*³ + b4 v*⁴)``.
    ``A`` [s] ≥ 0, ``m_star`` [kg], ``R_star`` [m], ``E_star`` [Pa], ``v`` [m/s].

    Checked against the numerics (``tests/test_restitution.py``): with this β (i.e.
    ``γ_n = (3/2) A k_n``), ``v*²`` is exactly the module's dimensionless damping ``c``, and no
    extra factor is needed — the exact small-dissipation slope is
    :data:`SMALL_DISSIPATION_SLOPE` = 1.1534489 vs b2 = 1.15345. The Padé differs from the
    integrated law by < 1e-7 for ``c ≤ 0.01``, 5.3e-5 at ``c = 0.1``, 9.1e-4 at ``c = 0.3``
    (ε ≈ 0.72), 6.1e-3 at ``c = 0.7`` (ε ≈ 0.50), 1.2 % at ``c = 1`` and grows beyond
    (3.8 % at ε ≈ 0.21); the Padé always overestimates ε. A convention with ``γ_n = A k_n``
    (no 3/2) would put a factor 3/2 into β.
    """
    m_star, R_star, E_star, v = _check_positive(m_star=m_star, R_star=R_star, E_star=E_star, v=v)
    A = _real("A", A, positive=False)
    k = hertz_stiffness(E_star, R_star)
    vs = math.sqrt(1.5 * A * (k / m_star) ** 0.4 * v**0.2)
    p = _PADE
    num = 1.0 + p["a1"] * vs
    return num / (num + p["b2"] * vs**2 + p["b3"] * vs**3 + p["b4"] * vs**4)


def scale_damping(gamma, stiffness_scale):
    """``γ λ^{3/5}`` [same units as ``gamma``]: the damping that keeps every collision's outcome
    when all moduli are multiplied by ``λ = stiffness_scale`` [-].

    Proof (dimensional). Take a collision with normal speed ``v``, tangential contact-point
    speed ``w``, spins, masses and moments of inertia given. Scale ``ξ = ξ0 X``, time
    ``t = τ T`` with ``ξ0 = (m* v²/k)^{2/5}``, ``τ = ξ0/v``, and every velocity by ``v``. Then

    * normal: ``X'' = -max(0, X^{3/2} + c_n X^{1/2} X')``, ``c_n = γ_n v^{1/5}/(k^{3/5} m*^{2/5})``;
    * tangential: ``m dv_s/dt = -min(γ_s sqrt(ξ)|v_s|, μ F_n) v̂_s`` becomes
      ``dV_s/dT = -min(c_s X^{1/2}|V_s|, μ F̂_n) V̂_s`` with ``c_s = γ_s v^{1/5}/(k^{3/5} m*^{2/5})``
      and the dimensionless normal force ``F̂_n = F_n τ/(m* v)`` — the Coulomb term has no
      ``k`` left in it, and torques scale the same way (lever arms are radii, unchanged).

    The dimensionless problem depends on ``c_n, c_s, μ``, the mass/inertia ratios and the
    incidence ``w/v`` only; since ``c ∝ γ k^{-3/5}`` (equivalently ``β ∝ A k^{2/5}`` with
    ``γ_n = 1.5 A k``), ``k → λk`` with ``γ → γ λ^{3/5}`` leaves it unchanged. Hence all
    post-collision velocities — the restitution at every speed, the tangential restitution and
    spin — and every impulse ``m Δv`` (normal and tangential, viscous or Coulomb) are unchanged;
    only times and overlaps scale, by ``τ, ξ0 ∝ λ^{-2/5}``. (Exact for isolated binary
    collisions; forces acting during the contact, e.g. gravity or enduring contacts in a bed,
    are compared over a different duration and break it to order ``g τ / v``.)
    """
    return gamma * stiffness_scale**similarity_damping_exponent


# ---------------------------------------------------------------------------------------------
# The linear spring–dashpot law (``contact_law = "linear"``)
#
# ``m* ξ'' = -max(0, k ξ + γ ξ')``, ``γ = 2 ζ sqrt(k m*)``, from ``ξ(0) = 0``, ``ξ'(0) = v``:
# with ``ω_0 = sqrt(k/m*)`` the motion is ``ξ = (v/ω_d) exp(-ζ ω_0 t) sin(ω_d t)``,
# ``ω_d = ω_0 sqrt(1 - ζ²)`` (``ζ < 1``), independent of ``v`` up to the scale of ``ξ``, so the
# restitution does not depend on the impact speed. Because the force is never attractive the
# contact force ends where ``k ξ + γ ξ' = 0``, *before* the overlap does, at
# ``ω_d t_f = π - 2 arcsin ζ``; there ``ξ' = -v exp(-ζ ω_0 t_f)`` exactly (Schwager & Pöschel,
# Granular Matter 9, 465 (2007)), and the grains then separate freely, the overlap closing
# ``2ζ/ω_0`` later. The textbook ``e = exp(-π ζ / sqrt(1 - ζ²))`` and ``t_c = π/ω_d`` belong
# to the law *with* the attractive tail (overlap ends at ``ω_d t = π``): with the clip they are
# off at first order in ζ (e.g. ζ = 0.1: 0.7292 vs the clipped law's 0.7441).


def linear_restitution(zeta) -> float:
    """Restitution [-] of the clipped linear spring–dashpot with damping ratio ``zeta`` ≥ 0:

    ``e = exp(-ζ (π - 2 arcsin ζ) / sqrt(1 - ζ²))`` for ``ζ < 1``, ``exp(-2)`` at ``ζ = 1`` and
    ``exp(-2 ζ arccosh ζ / sqrt(ζ² - 1))`` above (overdamped; ``e → 1/(4ζ²)``).
    """
    z = _real("zeta", zeta, positive=False)
    if z == 0.0:
        return 1.0
    if z < 1.0:
        return math.exp(-z * (math.pi - 2.0 * math.asin(z)) / math.sqrt(1.0 - z * z))
    if z == 1.0:
        return math.exp(-2.0)
    return math.exp(-2.0 * z * math.acosh(z) / math.sqrt(z * z - 1.0))


def linear_damping_ratio(restitution) -> float:
    """The damping ratio ``ζ`` [-] for which the clipped linear law has restitution
    ``restitution`` in (0, 1] at every impact speed (inverse of :func:`linear_restitution`,
    which decreases monotonically from 1; brentq to 1e-15)."""
    try:
        e = float(restitution)
    except (TypeError, ValueError):
        raise ValueError(f"restitution = {restitution!r}: must be a number in (0, 1]") from None
    if isinstance(restitution, bool) or not (0.0 < e <= 1.0):
        raise ValueError(f"restitution = {restitution!r}: must be in (0, 1]")
    if e == 1.0:
        return 0.0
    hi = 1.0
    while linear_restitution(hi) > e:
        hi *= 2.0
    return brentq(lambda z: linear_restitution(z) - e, 0.0, hi, xtol=1e-15, rtol=1e-15)


class LinearCollision(NamedTuple):
    """Durations [s] of one collision of the clipped linear law (any impact speed).

    Attributes:
      restitution: :func:`linear_restitution` [-].
      force_duration: time with a non-zero force, ``(π - 2 arcsin ζ)/ω_d`` (``ζ < 1``;
        ``2/ω_0`` at ``ζ = 1``, ``2 arccosh(ζ)/(ω_0 sqrt(ζ² - 1))`` above).
      duration: time with overlap ``ξ > 0``: ``force_duration + 2ζ/ω_0``.
    """

    restitution: float
    force_duration: float
    duration: float


def linear_collision(k, m_star, zeta) -> LinearCollision:
    """One collision of ``m* ξ'' = -max(0, k ξ + 2 ζ sqrt(k m*) ξ')``: stiffness ``k`` [N/m],
    effective mass ``m_star`` [kg], damping ratio ``zeta`` [-] (≥ 0)."""
    k, m_star = _check_positive(k=k, m_star=m_star)
    z = _real("zeta", zeta, positive=False)
    w0 = math.sqrt(k / m_star)
    if z < 1.0:
        t_f = (math.pi - 2.0 * math.asin(z)) / (w0 * math.sqrt(1.0 - z * z))
    elif z == 1.0:
        t_f = 2.0 / w0
    else:
        t_f = 2.0 * math.acosh(z) / (w0 * math.sqrt(z * z - 1.0))
    return LinearCollision(linear_restitution(z), t_f, t_f + 2.0 * z / w0)
