"""The tangential spring with contact history (Mindlin–Deresiewicz, no-slip form): one contact's
step, in both engines' forms (docs/physics.md §2, issue 39).

jaxdamp's tangential force has been the thesis' viscous force capped by Coulomb
(:func:`jaxdamp.physics.contact.contact_force`), with no memory of the contact. Every peer code
(EDEM, Rocky, Chrono DEM-Engine, LAMMPS ``tangential mindlin``) also has a tangential spring: a
contact remembers how far its two surfaces have moved against each other while touching, so that
friction can hold a contact at rest (stick) and release elastic energy, not only dissipate. This
module is that spring, one contact and one time step at a time:

1. the stored displacement ``s`` (the contact's history, in the contact plane of the last step)
   is turned into the present plane: its normal part removed and its length kept;
2. it grows by the sliding velocity: ``s ← s + v_s dt`` (``v_s`` the tangential velocity of
   grain ``i``'s surface against its partner's at the contact point);
3. the force on ``i`` is the spring and a dashpot, ``F_t = −k_t s − γ_t v_s``;
4. where ``|F_t| > μ F_n`` the contact slips: ``F_t`` is cut to ``μ F_n`` along itself, by a
   factor ``c < 1``, and the spring and the dashpot with it: ``s ← c s`` (the energy of the cut
   part of the spring is dissipated by the slip). LAMMPS' ``tangential mindlin`` sets the spring
   to ``−(F_t + γ_t v_s)/k_t`` instead (the dashpot uncut); the two agree without damping, and
   the cut of both keeps the slip's loss from going negative (below).

The spring's elastic energy is ``k_t |s|² / 2``. Out of contact the history is zero.

**Energy.** With ``s_a`` the turned history (as long as ``s``), ``s'`` the new one and ``F_t``
the force, ``F_t = −k_t s' − c γ_t v_s`` holds in both regimes, so the power the grains give the
contact, ``−F_t·v_s``, splits exactly, step by step, into

* damping ``c γ_t |v_s|²`` [W] (:attr:`Spring.damping`; ``c = 1`` while it sticks);
* slip ``(k_t s'·v_s dt − k_t (|s'|² − |s_a|²)/2)/dt`` [W] (:attr:`Spring.slip`): the work the
  spring took and did not store; while it sticks, only the update's ``k_t |v_s dt|²/(2 dt)``
  (``O(dt)``, the discrete spring's own loss). With ``s' = c s_1`` (``s_1 = s_a + v_s dt``,
  ``x = |v_s dt|``) it is at least ``k_t ((1 − c²)|s_1|² − 2 (1 − c)|s_1| x + x²)/(2 dt)``, a
  quadratic in ``x`` whose discriminant ``−8 c (1 − c)|s_1|²`` is not positive: never
  negative;
* the spring's energy change at the new stiffness, ``k_t (|s'|² − |s_a|²)/2``;

and the change of stiffness between steps adds ``(k_t − k_t^{old}) |s|²/2`` to the spring's
energy without any force doing it (:attr:`Spring.turned` is ``k_t |s|²/2``, the old
displacement at the new stiffness: the sum over contacts less the last step's total spring
energy is that work, a channel of the balance; at separation it takes the spring's remaining
energy). The
stiffness is Mindlin's for a Hertz contact,

    k_t = 8 G* sqrt(R* ξ),    1/G* = (2 − ν_i)/G_i + (2 − ν_j)/G_j,    G = λ E / (2 (1 + ν)),

so that ``k_t`` over the normal law's tangent stiffness ``dF_n/dξ = 2 E* sqrt(R* ξ)`` is
``2 (1 − ν)/(2 − ν)`` for like materials (0.82 at ν = 0.3), at every overlap (:func:`stiffness`,
:func:`compliance`). Where the stiffness changes within a contact (it grows and falls with
``ξ``), ``k_t |s|²/2`` is not a potential: the force ``−k_t s`` does work that the spring's
energy does not account for — the known incompleteness of the no-slip form (Thornton, Cummins &
Cleary 2011), which the energy balance names as a channel of its own when the law is wired into
the engines.

The JAX form (:func:`spring_jax`) is safe under ``jax.grad`` (no division by a zero length);
the scalar form (:func:`spring_scalar`) is compiled by numba for the native kernel and runs the
same arithmetic. :func:`oblique_impact` runs a sphere's impact on a rigid flat wall through
the law alone, the reference the engines are checked against. ``tests/test_tangential.py``
checks it against analytic oblique impacts: the stick limit of a linear contact (the surfaces'
tangential velocity after the impact is ``cos(π sqrt(7 k_t / (2 k_n)))`` times the one
before), gross sliding (the tangential impulse is ``μ`` times the normal one) and an ODE
solver; ``experiments/oblique_impact.py`` draws the rebound against the impact angle.

All functions are pure; SI units.
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple

import jax.numpy as jnp

from jaxdamp.physics.contact import Vec, safe_sqrt, scalar_form


def compliance(E: float, nu: float, stiffness_scale: float = 1.0) -> float:
    """One body's shear compliance in Mindlin's ``1/G*``: ``(2 − ν)/G`` [1/Pa], with
    ``G = λ E / (2 (1 + ν))`` (``λ``: the model's ``stiffness_scale``, as for ``E*``)."""
    G = stiffness_scale * E / (2.0 * (1.0 + nu))
    return (2.0 - nu) / G


def stiffness(G_star, r_eff, xi):
    """Mindlin's tangential stiffness ``k_t = 8 G* sqrt(R* ξ)`` [N/m] at overlaps ``ξ``
    (zero where ``ξ ≤ 0``), JAX form."""
    return 8.0 * G_star * jnp.sqrt(r_eff * jnp.maximum(xi, 0.0))


@scalar_form
def stiffness_scalar(G_star, r_eff, xi):
    """Scalar form of :func:`stiffness`."""
    return 8.0 * G_star * math.sqrt(r_eff * max(xi, 0.0))


class Spring(NamedTuple):
    """One step of tangential springs. Shapes: leading axes ``S``.

    Attributes:
      force: tangential force on grain ``i`` [N], a :class:`Vec`.
      history: the spring's displacement after the step [m], a :class:`Vec` in the contact
        plane (zero where not touching).
      energy: the spring's elastic energy ``k_t |s'|² / 2`` after the step [J].
      turned: the last step's displacement at this step's stiffness, ``k_t |s|² / 2`` [J].
      damping: the dashpot's loss ``c γ_t |v_s|²`` [W] (``c``: the Coulomb cut, 1 in stick).
      slip: the slip's loss [W] (module docstring; ≥ 0).
      sliding: whether the contact slipped (``|F_t|`` cut to ``μ F_n``).
    """

    force: Vec
    history: Vec
    energy: jnp.ndarray
    turned: jnp.ndarray
    damping: jnp.ndarray
    slip: jnp.ndarray
    sliding: jnp.ndarray


def spring_jax(s: Vec, n: Vec, v_slide: Vec, dt, kt, gt, f_normal, mu, touching) -> Spring:
    """One time step of tangential springs (module docstring), JAX form.

    Args:
      s: the stored displacements [m] (the last step's :attr:`Spring.history`), :class:`Vec`.
      n: unit normals from the partner to grain ``i``, :class:`Vec`.
      v_slide: tangential velocity of ``i``'s surface against its partner's at the contact
        point [m/s] (in the plane normal to ``n``), :class:`Vec`.
      dt: the time step [s].
      kt: tangential stiffness [N/m] (:func:`stiffness`), > 0 where ``touching``.
      gt: tangential damping [kg/s].
      f_normal: normal force magnitude ``F_n ≥ 0`` [N].
      mu: Coulomb coefficient [-].
      touching: ``ξ > 0``; elsewhere force, history and energy are zero.

    Example::

        >>> import jax.numpy as jnp
        >>> from jaxdamp.physics.contact import Vec
        >>> z, one = jnp.zeros(()), jnp.ones(())
        >>> sp = spring_jax(Vec(z, z, z), Vec(z, z, one), Vec(one, z, z), 1e-3, 1e4, 0.0,
        ...                 1.0, 0.5, jnp.array(True))
        >>> float(sp.force.x), bool(sp.sliding)   # the spring's 10 N cut to μ F_n = 0.5 N
        (-0.5, True)
    """
    # 1. into the present contact plane, keeping the length
    sr = s - n.scale(s.dot(n))
    old2, new2 = s.dot(s), sr.dot(sr)
    turned = new2 > 0
    keep = jnp.where(turned, safe_sqrt(old2, turned) / safe_sqrt(new2, turned), 1.0)
    # 2. grown by the sliding of this step
    s1 = sr.scale(keep) + v_slide.scale(dt)
    # 3. spring and dashpot; 4. cut to the Coulomb limit where it slips
    f = Vec(-kt * s1.x - gt * v_slide.x, -kt * s1.y - gt * v_slide.y,
            -kt * s1.z - gt * v_slide.z)
    f2 = f.dot(f)
    cap = mu * f_normal
    sliding = touching & (f2 > cap * cap)
    cut = jnp.where(touching, jnp.where(sliding, cap / safe_sqrt(f2, sliding), 1.0), 0.0)
    f = f.scale(cut)
    s2 = s1.scale(cut)  # the spring cut with the force (zero where not touching)
    kt = jnp.where(touching, kt, 0.0)
    s22, sa2 = s2.dot(s2), old2  # |s_a| = |s|
    slip = kt * (s2.dot(v_slide) - 0.5 * (s22 - sa2) / dt)
    return Spring(force=f, history=s2, energy=0.5 * kt * s22, turned=0.5 * kt * sa2,
                  damping=cut * gt * v_slide.dot(v_slide), slip=slip, sliding=sliding)


@scalar_form
def spring_scalar(sx, sy, sz, nx, ny, nz, vx, vy, vz, dt, kt, gt, f_normal, mu):
    """Scalar form of :func:`spring_jax` for one touching contact (``kt > 0``).

    Returns the force on ``i`` ``(fx, fy, fz)``, the new history ``(sx, sy, sz)``, the
    spring's energy, the turned energy, the damping and slip losses and whether it slipped
    (:class:`Spring`)."""
    sn = sx * nx + sy * ny + sz * nz
    rx, ry, rz = sx - sn * nx, sy - sn * ny, sz - sn * nz
    old2 = sx * sx + sy * sy + sz * sz
    new2 = rx * rx + ry * ry + rz * rz
    keep = math.sqrt(old2) / math.sqrt(new2) if new2 > 0.0 else 1.0
    s1x, s1y, s1z = rx * keep + vx * dt, ry * keep + vy * dt, rz * keep + vz * dt
    fx, fy, fz = -kt * s1x - gt * vx, -kt * s1y - gt * vy, -kt * s1z - gt * vz
    f2 = fx * fx + fy * fy + fz * fz
    cap = mu * f_normal
    sliding = f2 > cap * cap
    cut = 1.0
    if sliding:
        cut = cap / math.sqrt(f2)
        fx, fy, fz = fx * cut, fy * cut, fz * cut
        s1x, s1y, s1z = s1x * cut, s1y * cut, s1z * cut
    s22 = s1x * s1x + s1y * s1y + s1z * s1z
    slip = kt * (s1x * vx + s1y * vy + s1z * vz - 0.5 * (s22 - old2) / dt)
    return (fx, fy, fz, s1x, s1y, s1z, 0.5 * kt * s22, 0.5 * kt * old2,
            cut * gt * (vx * vx + vy * vy + vz * vz), slip, sliding)


class Impact(NamedTuple):
    """The outcome of :func:`oblique_impact`: velocities after the contact — normal ``vn``
    (away from the wall), tangential ``vt``, the surface speed of the spin ``R ω`` and the
    contact point's tangential velocity ``u = v_t − R ω`` [m/s] — and the books of the
    tangential force [J]: its work on the sphere, the damping and slip losses, the stiffness
    work (:class:`Spring`), the spring's energy left (zero: the contact ended) and at its
    peak; ``steps`` in contact."""

    vn: float
    vt: float
    spin: float
    u: float
    work: float
    damping: float
    slip: float
    stiffness: float
    spring: float
    max_spring: float
    steps: int


def oblique_impact(normal: Callable, kt_of: Callable, m: float, R: float, vn: float, vt: float,
                   mu: float, gt: float = 0.0, steps: int = 20000) -> Impact:
    """A solid sphere (mass ``m`` [kg], radius ``R`` [m], ``I = (2/5) m R²``) arriving at a rigid
    flat wall with normal speed ``vn`` and tangential speed ``vt`` [m/s], not spinning, through
    its contact: normal force ``normal(ξ)`` [N] at overlap ``ξ``, the tangential spring
    (:func:`spring_scalar`) of stiffness ``kt_of(ξ)`` [N/m], damping ``gt`` [kg/s] and Coulomb
    coefficient ``mu``. Symplectic Euler with ``steps`` steps over the contact time of a
    linear spring as stiff as ``normal`` at ``ξ = 10 µm`` (a Hertz contact runs a few times
    longer). Plain Python over the scalar form: a reference, not a fast path."""
    k0 = normal(1e-5) / 1e-5
    dt = math.pi / math.sqrt(k0 / m) / steps
    inertia = 0.4 * m * R * R
    z, vz, vx, wy = R, -vn, vt, 0.0
    s = (0.0, 0.0, 0.0)
    work = damping = slip = stiffness = spring = peak = 0.0
    n_contact = 0
    for _ in range(50 * steps):
        xi = R - z
        fx = fz = 0.0
        if xi > 0.0:
            fn = normal(xi)
            u = vx - R * wy  # the contact point's tangential velocity (along x)
            (fx, _, _, s0, s1, s2, en, turned, damp, sl, _) = spring_scalar(
                s[0], s[1], s[2], 0.0, 0.0, 1.0, u, 0.0, 0.0, dt, kt_of(xi), gt, fn, mu)
            s = (s0, s1, s2)
            fz = fn
            work += fx * u * dt
            damping += damp * dt
            slip += sl * dt
            stiffness += turned - spring
            spring = en
            peak = max(peak, en)
            n_contact += 1
        else:
            s = (0.0, 0.0, 0.0)
            stiffness -= spring  # the spring's energy, gone with the contact
            spring = 0.0
            if vz > 0.0:
                break
        vz += dt * fz / m
        vx += dt * fx / m
        wy += dt * (-R * fx) / inertia  # the torque −R n × F_t, about y
        z += dt * vz
    else:
        raise RuntimeError(f"oblique_impact: the sphere did not leave the wall in {50 * steps} "
                           "steps")
    return Impact(vz, vx, R * wy, vx - R * wy, work, damping, slip, stiffness, spring, peak,
                  n_contact)
