"""The contact laws between spheres and between a sphere and a flat wall (docs/physics.md §2), in one place
for both engines.

Every law is written twice, side by side: a JAX form (shape-polymorphic, safe under
``jax.grad``) used by :mod:`jaxdamp.physics.pairs` / :mod:`jaxdamp.physics.walls`, and a scalar form compiled
by numba (:func:`scalar_form`) that the native kernel (:mod:`jaxdamp.engine.native`) inlines. Laws
are registered by name in :data:`LAWS` and selected with ``Config.contact_law``.

Conventions: ``n`` is the unit normal pointing from the partner ``j`` (grain or wall) to the
grain ``i``; the overlap is ``ξ = R_i + R_j - |r_i - r_j|`` (wall: ``ξ = R_i - distance``) and
``ξ' = -(v_i - v_j)·n`` its rate (positive while approaching). Effective radius
``1/R* = 1/R_i + 1/R_j`` and mass ``1/m* = 1/m_i + 1/m_j`` (wall: ``R* = R_i``, ``m* = m_i``).

Every law has a normal force ``F_n = max(0, F_elastic(ξ) + F_damping(ξ, ξ'))`` (never
attractive) and shares the tangential force (thesis eq. 2.2.12, viscous and capped by Coulomb,
no spring)::

    F_t = -min(γ_s sqrt(ξ) |v_s|, μ F_n) v_s / |v_s|

**Constants.** What a law needs of a contact is split in two: the constants of the pair of
*materials* (mixed once, when the model is built: :meth:`Law.mix`, stored per species pair
in ``Params.pair_table`` ``(S, S, F)`` and per species against the walls in
``Params.wall_table`` ``(S, F)``, columns :attr:`Law.columns`), and the radius- and mass-
dependent part formed per contact from a table row (:meth:`Law.pair_jax` / ``pair_scalar``:
e.g. Hertz ``k_n = (4/3) E* sqrt(R*)``). The mixing rule (:func:`mix`) is applied only in
:meth:`Law.mix`. The first two columns of every table are ``γ_s`` and ``μ``
(:data:`GAMMA_S`, :data:`MU`).

**Hertz** (``"hertz"``; Kuwabara–Kono / Brilliantov et al. 1996)::

    F_n = max(0, k_n ξ^{3/2} + γ_n sqrt(ξ) ξ'),   k_n = (4/3) E* sqrt(R*),
    1/E* = (1-ν_i²)/(λE_i) + (1-ν_j²)/(λE_j),    γ_n = γ_n(thesis) + (3/2) A k_n

so both parameterisations (thesis ``γ_n``, paper ``A`` from a restitution) share one code
path; elastic energy ``(2/5) k_n ξ^{5/2}``.

**Linear spring–dashpot** (``"linear"``)::

    F_n = max(0, k ξ + γ ξ'),   γ = 2 ζ sqrt(k m*)

with the contact stiffness ``k`` [N/m] (``Material.linear_stiffness``) and the damping ratio
``ζ`` set from the material's ``restitution`` ``e`` so that every collision, at every speed,
has restitution exactly ``e``: ``e = exp(-ζ (π - 2 arcsin ζ)/sqrt(1 - ζ²))`` for the
never-attractive force (:func:`restitution.linear_restitution`; the textbook
``exp(-πζ/sqrt(1-ζ²))`` holds only with an attractive tail). The force acts for
``(π - 2 arcsin ζ)/ω_d``, ``ω_d = sqrt(k/m*) sqrt(1-ζ²)``, which sets the time step; elastic
energy ``k ξ²/2``.

All functions are pure; SI units.
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxdamp.config import ConfigError, Material
from jaxdamp.physics import restitution as rst

try:
    from numba import njit

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - numba is a dependency; keep the JAX engine usable
    HAVE_NUMBA = False

#: LLVM fast-math flags of the numba forms: contraction into FMAs, reassociation, reciprocals
#: and signed zeros. Not ``nnan``/``ninf``: the kernel tests for non-finite states and must
#: keep those tests (with them the compiler may assume every value finite and drop the checks).
FASTMATH = {"contract", "reassoc", "arcp", "nsz"}
#: The flags that keep a function's bits independent of where LLVM inlines it: contraction
#: (an FMA is the same in SIMD and scalar code) and signed zeros, not reassociation nor
#: reciprocals. With reassociation or reciprocals, a function's arithmetic may be re-ordered
#: after LLVM inlines it into a caller, and whether it does depends on numba's cache (a callee
#: loaded from the cache is linked as object code, one compiled in the process as IR): the
#: same step gave other quaternion bits in a batch than alone when the cache was written
#: mid-way (benchmarks/RESULTS.md, "Bits that depend on the cache"). For the kernel's
#: functions whose results are state (the corrector and the rotation).
FASTMATH_STABLE = {"contract", "nsz"}


def scalar_form(fn, inline: bool = True):
    """Compile ``fn`` as a numba scalar form: inlined into its (numba) callers (or, with
    ``inline=False``, compiled apart and called), float64, the kernel's fast-math flags.
    Without numba it stays a plain Python function (the JAX engine does not need it)."""
    if not HAVE_NUMBA:  # pragma: no cover
        return fn
    return njit(cache=True, inline="always" if inline else "never", error_model="numpy",
                fastmath=FASTMATH)(fn)


# ---------------------------------------------------------------------------------------------
# helpers


def mix(a: float, b: float, rule: str) -> float:
    """Combine per-material constants ``a`` and ``b`` of a pair (plain floats, at model build).

    ``rule`` is ``"arithmetic"`` (the 2023 paper), ``"harmonic"`` or ``"geometric"``.
    Harmonic and geometric means of zero are zero (a frictionless side makes the pair frictionless).
    """
    if rule == "arithmetic":
        return 0.5 * (a + b)
    if rule == "geometric":
        return math.sqrt(a * b)
    if rule == "harmonic":
        s = a + b
        return 2.0 * a * b / s if s > 0 else 0.0
    raise ValueError(f"mixing rule {rule!r}: expected 'arithmetic', 'harmonic' or 'geometric'")


#: ``numerics.precision`` values: the floating-point type the JAX engine evaluates the contact
#: laws in. The state, the geometry of a contact (its overlap and normal) and every sum of
#: energies and powers stay float64.
PRECISIONS = {"float64": jnp.float64, "float32": jnp.float32}


def force_dtype(model):
    """The dtype of the JAX engine's contact-law arithmetic for ``model``
    (:attr:`jaxdamp.physics.model.Model.precision`)."""
    return PRECISIONS[model.precision]


def safe_sqrt(x, mask):
    """``sqrt(x)`` where ``mask``, else 0, with finite gradients everywhere."""
    return jnp.where(mask, jnp.sqrt(jnp.where(mask, x, 1.0)), 0.0)


def safe_norm(x, axis=-1):
    """Euclidean norm along ``axis`` with a zero (not NaN) gradient at the origin."""
    s = jnp.sum(x * x, axis=axis)
    return safe_sqrt(s, s > 0)


class Vec(NamedTuple):
    """A field of 3-vectors stored as three equally shaped component arrays (structure of
    arrays): every operation is elementwise over contiguous arrays, which XLA vectorises far
    better than a trailing axis of size 3 (measured: pair kernel 2.2× faster)."""

    x: jnp.ndarray
    y: jnp.ndarray
    z: jnp.ndarray

    @classmethod
    def of(cls, a):
        """From an array ``(..., 3)``."""
        return cls(a[..., 0], a[..., 1], a[..., 2])

    def stack(self):
        """To an array ``(..., 3)``."""
        return jnp.stack((self.x, self.y, self.z), axis=-1)

    def __add__(self, o):
        return Vec(self.x + o.x, self.y + o.y, self.z + o.z)

    def __sub__(self, o):
        return Vec(self.x - o.x, self.y - o.y, self.z - o.z)

    def __neg__(self):
        return Vec(-self.x, -self.y, -self.z)

    def scale(self, s):
        return Vec(s * self.x, s * self.y, s * self.z)

    def dot(self, o):
        return self.x * o.x + self.y * o.y + self.z * o.z

    def cross(self, o):
        return Vec(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )

    def sum(self, axis):
        return Vec(self.x.sum(axis), self.y.sum(axis), self.z.sum(axis))


# ---------------------------------------------------------------------------------------------
# table layout

#: Columns every law's table starts with: tangential damping ``γ_s`` [kg s^-1 m^-1/2] and the
#: Coulomb coefficient ``μ`` [-].
COMMON_COLUMNS = ("gamma_s", "mu")
GAMMA_S, MU = (COMMON_COLUMNS.index(c) for c in ("gamma_s", "mu"))


def _columns(*own: str) -> tuple[str, ...]:
    return COMMON_COLUMNS + own


# ---------------------------------------------------------------------------------------------
# Hertz + viscoelastic

#: Table columns of the Hertz law: ``E*`` [Pa], thesis ``γ_n`` [kg s^-1 m^-1/2], paper ``A`` [s],
#: and Mindlin's shear modulus ``G*`` [Pa] of the tangential spring
#: (:mod:`jaxdamp.physics.tangential`; read only with ``tangential_law = "mindlin"``).
HERTZ_COLUMNS = _columns("E_star", "gamma_n", "A", "G_star")
_H_E, _H_GN, _H_A, _H_G = (HERTZ_COLUMNS.index(c) for c in ("E_star", "gamma_n", "A", "G_star"))
#: The column of ``G*`` in a Hertz table (the tangential spring's stiffness).
G_STAR = _H_G


def hertz_material(mat: Material, radius: float, stiffness_scale: float) -> dict:
    """Per-material constants of the Hertz law: compliance ``(1-ν²)/(λE)`` [1/Pa], the shear
    compliance of Mindlin's ``1/G*`` (:func:`shear_compliance`), ``A``
    [s], ``γ_n``, ``γ_s`` [kg s^-1 m^-1/2] (scaled by ``λ^{3/5}``,
    :func:`restitution.scale_damping`) and ``μ``. A ``restitution`` at ``v_ref`` is turned into
    ``A`` for a like-pair collision of grains of ``radius`` (or ``mat.calibration_radius``) —
    exact for this force law."""
    compliance = (1.0 - mat.nu**2) / (stiffness_scale * mat.E)
    scale = rst.scale_damping(1.0, stiffness_scale)
    out = dict(compliance=compliance, gamma_s=mat.gamma_s * scale, mu=mat.mu, A=0.0,
               gamma_n=(mat.gamma_n or 0.0) * scale,
               shear=shear_compliance(mat.E, mat.nu, stiffness_scale))
    if mat.restitution is not None:
        r = mat.calibration_radius if mat.calibration_radius is not None else radius
        m = mat.density * 4.0 / 3.0 * math.pi * r**3
        out["A"] = rst.dissipative_constant(mat.restitution, mat.v_ref, 0.5 * m, 0.5 * r,
                                            0.5 / compliance)
        out["gamma_n"] = 0.0
    return out


def shear_compliance(E: float, nu: float, stiffness_scale: float = 1.0) -> float:
    """One body's shear compliance in Mindlin's ``1/G*`` (the tangential spring,
    :mod:`jaxdamp.physics.tangential`): ``(2 − ν)/G`` [1/Pa], with ``G = λ E / (2 (1 + ν))``
    (``λ``: the model's ``stiffness_scale``, as for ``E*``)."""
    G = stiffness_scale * E / (2.0 * (1.0 + nu))
    return (2.0 - nu) / G


def hertz_mix(a: dict, b: dict, rule: str) -> tuple[float, ...]:
    """Table row of two materials: ``1/E* = c_a + c_b`` and ``1/G* = s_a + s_b`` (series
    compliances, exact), ``γ_s``, ``μ``, ``γ_n``, ``A`` by the mixing ``rule`` (the 2023 paper:
    arithmetic mean of ``A``)."""
    return (mix(a["gamma_s"], b["gamma_s"], rule), mix(a["mu"], b["mu"], rule),
            1.0 / (a["compliance"] + b["compliance"]), mix(a["gamma_n"], b["gamma_n"], rule),
            mix(a["A"], b["A"], rule), 1.0 / (a["shear"] + b["shear"]))


def calibrate_wall_row(law, row, restitution: float, v: float, m: float, r: float):
    """A grain–wall table row of the Hertz ``law`` with its damping replaced so that a grain of
    mass ``m`` [kg] and radius ``r`` [m] hitting the (immovable, flat) wall at ``v`` [m/s] has
    ``restitution`` (``Config.wall_damping = "calibrated"``): ``A`` from
    :func:`restitution.dissipative_constant` with ``m* = m``, ``R* = r`` and the row's ``E*``;
    thesis-form ``γ_n`` set to 0."""
    row = np.array(row, float)
    row[law.column("A")] = rst.dissipative_constant(restitution, v, m, r,
                                                    row[law.column("E_star")])
    row[law.column("gamma_n")] = 0.0
    return row


def hertz_pair_jax(row, r_eff, m_eff):
    """``(k_n, γ_n)`` of contacts from their table rows ``(..., F)``: ``k_n = (4/3) E* sqrt(R*)``
    [N m^-3/2], ``γ_n = γ_n + (3/2) A k_n`` [kg s^-1 m^-1/2]. ``m_eff`` is not needed."""
    k = (4.0 / 3.0) * row[..., _H_E] * jnp.sqrt(r_eff)
    return k, row[..., _H_GN] + 1.5 * row[..., _H_A] * k


@scalar_form
def hertz_pair_scalar(row, r_eff, m_eff):
    """Scalar form of :func:`hertz_pair_jax` for one table row ``(F,)``."""
    k = (4.0 / 3.0) * row[_H_E] * math.sqrt(r_eff)
    return k, row[_H_GN] + 1.5 * row[_H_A] * k


def hertz_normal_jax(xi, sqrt_xi, xi_dot, k, g):
    """Elastic force ``k ξ^{3/2}`` [N], damping force ``γ_n sqrt(ξ) ξ'`` [N] (before the
    clip) and elastic energy ``(2/5) k ξ^{5/2}`` [J] at overlaps ``ξ ≥ 0``."""
    f_el = k * xi * sqrt_xi
    return f_el, g * sqrt_xi * xi_dot, 0.4 * f_el * xi


@scalar_form
def hertz_normal_scalar(xi, sqrt_xi, xi_dot, k, g):
    """Scalar form of :func:`hertz_normal_jax`."""
    f_el = k * xi * sqrt_xi
    return f_el, g * sqrt_xi * xi_dot, 0.4 * f_el * xi


def hertz_collision_time(row, m_eff: float, r_eff: float, v: float) -> float:
    """Elastic Hertz collision time [s] at impact speed ``v`` (docs/physics.md §3,
    :func:`restitution.collision_time`; damping lengthens the overlap by 1–11 %)."""
    return rst.collision_time(m_eff, r_eff, float(row[_H_E]), v)


def hertz_check(mat: Material, name: str) -> None:
    """Material inputs of the Hertz law: ``gamma_n`` (thesis) or ``restitution`` at ``v_ref``."""
    if mat.gamma_n is not None and mat.restitution is not None:
        raise ConfigError(
            f"{name}: give either gamma_n (thesis) or restitution (paper), not both "
            f"(gamma_n = {mat.gamma_n}, restitution = {mat.restitution})"
        )
    if mat.gamma_n is not None and not (_finite(mat.gamma_n) and mat.gamma_n >= 0):
        raise ConfigError(f"{name}.gamma_n = {mat.gamma_n!r}: must be a finite number ≥ 0")
    if mat.restitution is not None:
        if not (_finite(mat.restitution) and 0.0 < mat.restitution <= 1.0):
            raise ConfigError(f"{name}.restitution = {mat.restitution!r}: must be in (0, 1]")
        if not (_finite(mat.v_ref) and mat.v_ref > 0):
            raise ConfigError(f"{name}.v_ref = {mat.v_ref!r}: must be a finite number > 0")
    if mat.calibration_radius is not None and not (
            _finite(mat.calibration_radius) and mat.calibration_radius > 0):
        raise ConfigError(
            f"{name}.calibration_radius = {mat.calibration_radius!r}: must be a finite number > 0")


def _finite(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


# ---------------------------------------------------------------------------------------------
# linear spring–dashpot

#: Table columns of the linear law: contact stiffness ``k`` [N/m], damping ratio ``ζ`` [-].
LINEAR_COLUMNS = _columns("k", "zeta")
_L_K, _L_Z = (LINEAR_COLUMNS.index(c) for c in ("k", "zeta"))


def linear_material(mat: Material, radius: float, stiffness_scale: float) -> dict:
    """Per-material constants of the linear law: ``k = λ linear_stiffness`` [N/m], the
    restitution ``e`` (``restitution``, or 1 if not given; ``v_ref`` plays no role: it holds at
    every speed), ``γ_s`` (scaled by ``λ^{3/5}`` as for Hertz) and ``μ``. ``radius`` is not
    needed."""
    return dict(k=stiffness_scale * mat.linear_stiffness,
                e=1.0 if mat.restitution is None else float(mat.restitution),
                gamma_s=mat.gamma_s * rst.scale_damping(1.0, stiffness_scale), mu=mat.mu)


def linear_mix(a: dict, b: dict, rule: str) -> tuple[float, ...]:
    """Table row of two materials: ``k``, ``e``, ``γ_s``, ``μ`` by the mixing ``rule``, and the
    damping ratio ``ζ`` that gives the mixed ``e`` exactly
    (:func:`restitution.linear_damping_ratio`)."""
    e = mix(a["e"], b["e"], rule)
    return (mix(a["gamma_s"], b["gamma_s"], rule), mix(a["mu"], b["mu"], rule),
            mix(a["k"], b["k"], rule), rst.linear_damping_ratio(e))


def linear_pair_jax(row, r_eff, m_eff):
    """``(k, γ)`` of contacts from their table rows ``(..., F)``: ``k`` [N/m] and
    ``γ = 2 ζ sqrt(k m*)`` [kg/s] (wall: ``m* = m_i``). ``r_eff`` is not needed."""
    k = row[..., _L_K]
    return k, 2.0 * row[..., _L_Z] * jnp.sqrt(k * m_eff)


@scalar_form
def linear_pair_scalar(row, r_eff, m_eff):
    """Scalar form of :func:`linear_pair_jax` for one table row ``(F,)``."""
    k = row[_L_K]
    return k, 2.0 * row[_L_Z] * math.sqrt(k * m_eff)


def linear_normal_jax(xi, sqrt_xi, xi_dot, k, g):
    """Elastic force ``k ξ`` [N], damping force ``γ ξ'`` [N] (before the clip) and elastic
    energy ``k ξ²/2`` [J] at overlaps ``ξ ≥ 0``."""
    f_el = k * xi
    return f_el, g * xi_dot, 0.5 * f_el * xi


@scalar_form
def linear_normal_scalar(xi, sqrt_xi, xi_dot, k, g):
    """Scalar form of :func:`linear_normal_jax`."""
    f_el = k * xi
    return f_el, g * xi_dot, 0.5 * f_el * xi


def linear_collision_time(row, m_eff: float, r_eff: float, v: float) -> float:
    """The time the force of a linear contact acts [s], at any speed:
    ``(π - 2 arcsin ζ)/ω_d``, ``ω_d = sqrt(k/m*) sqrt(1 - ζ²)`` (:func:`restitution.linear_collision`;
    ``π/ω_0`` without damping; the overlap lasts ``2ζ/ω_0`` longer)."""
    return rst.linear_collision(float(row[_L_K]), m_eff, float(row[_L_Z])).force_duration


def linear_check(mat: Material, name: str) -> None:
    """Material inputs of the linear law: ``linear_stiffness`` > 0, ``restitution`` in (0, 1]
    (or none: elastic); ``gamma_n`` (the Hertz law's damping) is refused."""
    k = mat.linear_stiffness
    if not (_finite(k) and k > 0):
        raise ConfigError(f"{name}.linear_stiffness = {k!r}: contact_law = 'linear' needs a "
                          "contact stiffness [N/m], a finite number > 0")
    if mat.gamma_n not in (None, 0, 0.0):
        raise ConfigError(f"{name}.gamma_n = {mat.gamma_n!r}: gamma_n is the Hertz law's damping; "
                          "with contact_law = 'linear' give the restitution instead")
    if mat.restitution is not None and not (_finite(mat.restitution)
                                            and 0.0 < mat.restitution <= 1.0):
        raise ConfigError(f"{name}.restitution = {mat.restitution!r}: must be in (0, 1]")


# ---------------------------------------------------------------------------------------------
# the registry


class Law(NamedTuple):
    """A normal contact law, in both engines' forms.

    Attributes:
      name: its name in ``Config.contact_law``.
      id: its number in the native kernel's dispatch (:func:`pair_scalar`, :func:`normal_scalar`).
      columns: the table columns (``γ_s``, ``μ`` first).
      material: ``(Material, radius, stiffness_scale) -> dict`` of one body's constants
        (``radius``: the like-pair radius of a calibration).
      mix: ``(dict, dict, rule) -> tuple`` a table row of two bodies, in ``columns`` order.
      pair_jax, pair_scalar: ``(row, R*, m*) -> (k, g)`` the per-contact stiffness and damping.
      normal_jax, normal_scalar: ``(ξ ≥ 0, sqrt ξ, ξ', k, g) -> (F_elastic, F_damping,
        elastic energy)``; the force is ``max(0, F_elastic + F_damping)`` while ``ξ > 0``.
      collision_time: ``(row, m*, R*, v) -> t_c`` [s] that sets the time step (docs/physics.md §3).
      check: ``(Material, name) -> None``, raises :class:`ConfigError` for bad inputs.
    """

    name: str
    id: int
    columns: tuple[str, ...]
    material: Callable
    mix: Callable
    pair_jax: Callable
    pair_scalar: Callable
    normal_jax: Callable
    normal_scalar: Callable
    collision_time: Callable
    check: Callable

    def column(self, name: str) -> int:
        """Index of column ``name`` in this law's tables."""
        return self.columns.index(name)


HERTZ = Law("hertz", 0, HERTZ_COLUMNS, hertz_material, hertz_mix, hertz_pair_jax,
            hertz_pair_scalar, hertz_normal_jax, hertz_normal_scalar, hertz_collision_time,
            hertz_check)

LINEAR = Law("linear", 1, LINEAR_COLUMNS, linear_material, linear_mix, linear_pair_jax,
             linear_pair_scalar, linear_normal_jax, linear_normal_scalar, linear_collision_time,
             linear_check)

#: The contact laws by name.
LAWS: dict[str, Law] = {law.name: law for law in (HERTZ, LINEAR)}
_LINEAR_ID = LINEAR.id


@scalar_form
def pair_scalar(law, row, r_eff, m_eff):
    """The native kernel's per-contact ``(k, g)`` of law number ``law`` (:attr:`Law.id`)."""
    if law == _LINEAR_ID:
        return linear_pair_scalar(row, r_eff, m_eff)
    return hertz_pair_scalar(row, r_eff, m_eff)


@scalar_form
def normal_scalar(law, xi, sqrt_xi, xi_dot, k, g):
    """The native kernel's normal force terms of law number ``law`` (:attr:`Law.id`); the law
    is the same for every contact of a call, so the branch is always predicted."""
    if law == _LINEAR_ID:
        return linear_normal_scalar(xi, sqrt_xi, xi_dot, k, g)
    return hertz_normal_scalar(xi, sqrt_xi, xi_dot, k, g)


# ---------------------------------------------------------------------------------------------
# the whole contact: normal law + Coulomb-capped viscous friction


class ContactForce(NamedTuple):
    """Force of one contact on grain ``i`` and its energetics. Shapes: leading axes ``S``.

    Attributes:
      force: total contact force on ``i`` [N], a :class:`Vec` of shape ``S``.
      torque: torque on ``i`` about its centre [N m], :class:`Vec` of shape ``S``.
      normal: normal force magnitude ``F_n`` [N], ``S``.
      elastic_energy: the law's elastic energy (Hertz ``(2/5) k_n ξ^{5/2}``) [J], ``S``.
      normal_loss: dissipated power of the normal force [W], ``S`` (≥ 0):
        ``(F_n - F_elastic) ξ'``, which is the damping force times ``ξ'`` while the force is
        not clipped and also counts the elastic energy lost when clipping to zero releases it.
      friction_loss: dissipated power of the tangential force [W], ``S`` (≥ 0): the viscous
        law's ``|F_t| |v_s|``; the spring's damping and slip losses (:class:`Mindlin`).
      touching: ``ξ > 0``, ``S``.
      history: with a tangential spring, its force after the step [N] (:class:`Vec`, the
        contact's history); else ``None``.
      turned: with a spring, the energy the step starts it with [J]
        (:attr:`jaxdamp.physics.tangential.Spring.turned`); else ``None``.
      slip_loss: with a spring, the slip's part of ``friction_loss`` [W]; else ``None``.
      spring_energy: with a spring, its ``|F_s|²/(2 k_t)`` after the step [J]; else ``None``.

    With a spring (:func:`jaxdamp.physics.tangential.contact_force`), ``elastic_energy`` holds
    the normal law's energy and the spring's.
    """

    force: Vec
    torque: Vec
    normal: jnp.ndarray
    elastic_energy: jnp.ndarray
    normal_loss: jnp.ndarray
    friction_loss: jnp.ndarray
    touching: jnp.ndarray
    history: Vec | None = None
    turned: jnp.ndarray | None = None
    slip_loss: jnp.ndarray | None = None
    spring_energy: jnp.ndarray | None = None


class Normal(NamedTuple):
    """The normal part of contacts (:func:`normal_part`), what both tangential laws start
    from. Shapes ``S``: ``touching`` (``ξ > 0``), ``xi`` the overlap where touching (else 0)
    [m], ``sqrt_xi``, ``xi_dot`` its rate [m/s], ``f_elastic`` [N], ``f_normal`` the normal
    force ``F_n ≥ 0`` [N], ``e_elastic`` the law's elastic energy [J], ``v_slide`` the
    tangential velocity of grain ``i``'s surface against its partner's at the contact point
    [m/s] (:class:`Vec`)."""

    touching: jnp.ndarray
    xi: jnp.ndarray
    sqrt_xi: jnp.ndarray
    xi_dot: jnp.ndarray
    f_elastic: jnp.ndarray
    f_normal: jnp.ndarray
    e_elastic: jnp.ndarray
    v_slide: Vec

    def loss(self):
        """The normal force's dissipated power ``(F_n − F_elastic) ξ'`` [W] (≥ 0)."""
        return (self.f_normal - self.f_elastic) * self.xi_dot


def normal_part(law: Law, xi, n: Vec, v_rel: Vec, spin: Vec, k, g) -> Normal:
    """The normal force of contacts and their sliding velocity (arguments as
    :func:`contact_force`'s), JAX form."""
    touching = xi > 0
    sqrt_xi = safe_sqrt(xi, touching)
    xi_pos = jnp.where(touching, xi, 0.0)
    xi_dot = -v_rel.dot(n)
    f_elastic, f_damping, e_elastic = law.normal_jax(xi_pos, sqrt_xi, xi_dot, k, g)
    f_normal = jnp.where(touching, jnp.maximum(f_elastic + f_damping, 0.0), 0.0)
    v_contact = v_rel - spin.cross(n)
    v_slide = v_contact - n.scale(v_contact.dot(n))
    return Normal(touching, xi_pos, sqrt_xi, xi_dot, f_elastic, f_normal, e_elastic, v_slide)


def contact_force(law: Law, xi, n: Vec, v_rel: Vec, spin: Vec, radius_i, k, g, gamma_s,
                  mu) -> ContactForce:
    """Force, torque and losses of a sphere contact with the viscous tangential force
    (docs/physics.md §2), JAX form. (The tangential spring with history is
    :func:`jaxdamp.physics.tangential.contact_force`, on the same normal part.)

    Args:
      law: the normal law (:data:`LAWS`).
      xi: overlap ``ξ`` [m], shape ``S`` (contacts are where ``ξ > 0``).
      n: unit normal from partner to grain ``i``, :class:`Vec` broadcastable to ``S``.
      v_rel: ``v_i - v_j`` [m/s], :class:`Vec`.
      spin: ``R_i ω_i + R_j ω_j`` [m/s] (wall: ``R_i ω_i``), :class:`Vec`.
      radius_i: ``R_i`` [m], broadcastable to ``S``.
      k, g: the law's stiffness and damping of the contacts (:attr:`Law.pair_jax`).
      gamma_s: tangential damping [kg s^-1 m^-1/2], broadcastable to ``S``.
      mu: Coulomb coefficient [-], broadcastable to ``S``.
    """
    c = normal_part(law, xi, n, v_rel, spin, k, g)
    speed2 = c.v_slide.dot(c.v_slide)
    sliding = c.touching & (speed2 > 0)
    speed = safe_sqrt(speed2, sliding)
    # |F_t| / |v_s| = min(γ_s sqrt(ξ), μ F_n / |v_s|): no division by a zero speed.
    drag = jnp.minimum(gamma_s * c.sqrt_xi, mu * c.f_normal / jnp.where(sliding, speed, 1.0))
    drag = jnp.where(sliding, drag, 0.0)
    f_tangent = c.v_slide.scale(-drag)

    return ContactForce(
        force=n.scale(c.f_normal) + f_tangent,
        torque=n.scale(-radius_i).cross(f_tangent),
        normal=c.f_normal,
        elastic_energy=c.e_elastic,
        normal_loss=c.loss(),
        friction_loss=drag * speed2,
        touching=c.touching,
    )


@scalar_form
def normal_force_scalar(law, xi, nx, ny, nz, vx, vy, vz, k, g):
    """The normal part of a touching contact (``ξ > 0``, unit normal ``n``, relative velocity
    ``v``; law number ``law``): ``(sqrt ξ, ξ', F_elastic, F_n = max(F_elastic + F_damping,
    0), elastic energy)`` — scalar form of :func:`normal_part`'s, for both tangential laws."""
    sq = math.sqrt(xi)
    xi_dot = -(vx * nx + vy * ny + vz * nz)
    f_el, f_damp, e_el = normal_scalar(law, xi, sq, xi_dot, k, g)
    return sq, xi_dot, f_el, max(f_el + f_damp, 0.0), e_el


@scalar_form
def slide_scalar(nx, ny, nz, vx, vy, vz, sx, sy, sz):
    """The tangential part of a contact point's relative velocity ``v − s × n`` (``v``: the
    centres' relative velocity, ``s``: the spin ``R_i ω_i + R_j ω_j``, ``n``: the unit
    normal) — scalar form of :attr:`Normal.v_slide`."""
    cx = vx - (sy * nz - sz * ny)
    cy = vy - (sz * nx - sx * nz)
    cz = vz - (sx * ny - sy * nx)
    cn = cx * nx + cy * ny + cz * nz
    return cx - cn * nx, cy - cn * ny, cz - cn * nz


@scalar_form
def contact_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx, sy, sz, k, g, gamma_s, mu):
    """Scalar form of :func:`contact_force` for one touching contact (``ξ > 0``).

    Returns force on i ``(fx, fy, fz)``, tangential force ``(tx, ty, tz)`` (the torque on a
    body of radius ``R`` is ``-R n × F_t``), elastic energy, normal loss, friction loss.
    Written without data-dependent branches where a ``min``/``max`` does (branch mispredictions
    dominated the dense-bed cost), and with the one division of the Coulomb cap only where the
    cap applies."""
    sq, xi_dot, f_el, f_n, e_el = normal_force_scalar(law, xi, nx, ny, nz, vx, vy, vz, k, g)
    tx, ty, tz = slide_scalar(nx, ny, nz, vx, vy, vz, sx, sy, sz)
    sp2 = tx * tx + ty * ty + tz * tz
    # |F_t| = min(γ_s sqrt(ξ) |v_s|, μ F_n): drag = |F_t| / |v_s|
    drag = gamma_s * sq
    cap = mu * f_n
    if drag * drag * sp2 > cap * cap:
        drag = cap / math.sqrt(sp2)
    ftx, fty, ftz = -drag * tx, -drag * ty, -drag * tz
    return (
        f_n * nx + ftx, f_n * ny + fty, f_n * nz + ftz, ftx, fty, ftz,
        e_el, (f_n - f_el) * xi_dot, drag * sp2,
    )
