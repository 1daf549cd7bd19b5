"""The tangential spring with contact history (Mindlin–Deresiewicz, no-slip form, incremental):
one contact's step, in both engines' forms (docs/physics.md §2, issue 39).

jaxdamp's tangential force has been the thesis' viscous force capped by Coulomb
(:func:`jaxdamp.physics.contact.contact_force`), with no memory of the contact. Every peer code
(EDEM, Rocky, Chrono DEM-Engine, LAMMPS ``tangential mindlin``) also has a tangential spring: a
contact remembers what its surfaces' relative tangential displacement has loaded, so that
friction can hold a contact at rest (stick) and release elastic energy, not only dissipate.
This module is that spring, one contact and one time step at a time. Its history is the
spring's *force* ``F_s`` (LAMMPS ``tangential mindlin_rescale/force``), grown incrementally,
``dF_s = −k_t du``, rather than ``F_s = −k_t s`` of a stored displacement ``s`` (with which a
changing stiffness changes the force, and the energy, without any displacement):

1. the stored force (in the contact plane of the last step) is turned into the present plane:
   its normal part removed and its length kept; where the overlap shrank, it is scaled down
   with the contact (``F_s ← F_s k_t/k_t^{old} = F_s sqrt(ξ/ξ_old)``, LAMMPS
   ``mindlin_rescale/force``): an unloading contact cannot hold the tangential force of a
   larger one, and a spring held at constant force while ``k_t → 0`` would store an energy
   ``|F_s|²/(2 k_t)`` without bound;
2. it grows by the stiffness times this step's displacement of the surfaces:
   ``F_s ← F_s − k_t u dt`` (``u`` the tangential velocity of grain ``i``'s surface against
   its partner's at the contact point over the step);
3. the force on ``i`` is the spring and a dashpot, ``F_t = F_s − γ_t v_s``;
4. where ``|F_t| > μ F_n`` the contact slips: ``F_t`` is cut to ``μ F_n`` along itself, by a
   factor ``c < 1``, and the spring and the dashpot with it: ``F_s ← c F_s``.

The spring's elastic energy is ``|F_s|²/(2 k_t)``. Out of contact the history is zero. The
stiffness is Mindlin's for a Hertz contact,

    k_t = 8 G* sqrt(R* ξ),    1/G* = (2 − ν_i)/G_i + (2 − ν_j)/G_j,    G = λ E / (2 (1 + ν)),

so that ``k_t`` over the normal law's tangent stiffness ``dF_n/dξ = 2 E* sqrt(R* ξ)`` is
``2 (1 − ν)/(2 − ν)`` for like materials (0.82 at ν = 0.3), at every overlap (:func:`stiffness`,
:func:`jaxdamp.physics.contact.shear_compliance`).

**Energy.** Velocity Verlet moves the grains by ``u dt`` over a step under the mean of the old
and the new force, so the spring takes from them ``W = −(F_a + F_s')·u dt / 2`` (``F_a`` the
turned old spring force, ``F_s'`` the new one). Of that it stores ``E' − E_a`` (``E_a =
|F_a|²/(2 k_t)`` at the new stiffness) and the rest is the slip's loss (:attr:`Spring.slip`):
while it sticks, ``F_s' − F_a = −k_t u dt`` and the loss is exactly zero (the discrete spring
is conservative, as the continuous one); where it slips, with ``G = F_a − k_t u dt`` and
``F_s' = c G``, the loss is ``(1 − c)(F_a·G + c |G|²)/(2 k_t)``, ≥ 0 unless a single step's
displacement reverses a spring more than twice the slip limit. The dashpot loses
``c γ_t |v_s|²`` (:attr:`Spring.damping`). Between steps the stiffness changes with the
overlap at constant force, which changes the stored energy without any work done:
``|F|²/(2 k_t) − |F|²/(2 k_t^{old})`` (:attr:`Spring.turned` is ``E_a``; the sum over contacts
less the last step's total spring energy is that work, a channel of the energy balance; at a
contact's end it takes the spring's remaining energy) — the known incompleteness of the no-slip
model, named instead of hidden.

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

from jaxdamp.physics.contact import (
    ContactForce,
    Law,
    Vec,
    normal_force_scalar,
    normal_part,
    safe_sqrt,
    scalar_form,
    slide_scalar,
)


def damping(kt, k, g):
    """The spring's dashpot ``γ_t = τ k_t`` [kg/s], with the relaxation time of the Hertz
    normal law, ``τ = γ_n sqrt(ξ) / (dF_n/dξ) = γ_n / (1.5 k_n)`` (``k``, ``g``: the normal
    law's ``k_n`` and ``γ_n``, :attr:`jaxdamp.physics.contact.Law.pair_jax`): the tangential
    dashpot relaxes the tangential spring as fast as the normal one relaxes the normal spring,
    at every overlap. For the Kuwabara–Kono form of the paper ``τ = A``. Elementwise; also the
    scalar form (arithmetic only)."""
    return kt * g / (1.5 * k)


damping_scalar = scalar_form(damping)


def unloading(xi, xi_old):
    """``(ξ_step, rescale)`` of a contact whose overlap went from ``ξ_old ≥ 0`` to ``ξ > 0``
    over a step: the overlap at which the step's stiffness is taken, the mean
    ``(ξ + ξ_old)/2`` (a contact new in the step started at ``ξ_old = 0``), and the factor
    ``sqrt(ξ/ξ_old)`` on the stored force where the contact shrank (1 where it grew).
    JAX arrays, safe under ``jax.grad``. (The native kernel, when it gets the spring, needs
    a scalar form beside it; :func:`oblique_impact` forms the same from its ``kt_of``.)"""
    shrank = xi_old > xi
    ratio = xi / jnp.where(shrank, xi_old, 1.0)
    return 0.5 * (xi + xi_old), jnp.where(shrank, jnp.sqrt(jnp.where(shrank, ratio, 1.0)), 1.0)


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
      history: the spring's force ``F_s'`` after the step [N], a :class:`Vec` in the contact
        plane (zero where not touching).
      energy: the spring's elastic energy ``|F_s'|²/(2 k_t)`` after the step [J].
      turned: the energy the step starts the spring with [J]: the last step's spring force,
        turned and rescaled (``F_a``), at this step's stiffness, ``|F_a|²/(2 k_t)``, plus the
        work ``(F_s − F_a)·u dt/2`` that the part the rescaling took off does over the step
        (the grains move under the old force ``F_s`` at the step's start; zero where nothing
        was rescaled; a contact that ended in the step has all of it taken off: ``F_s·u dt/2``).
        The engines book the sum of it over contacts less the last step's spring energy as the
        stiffness work (module docstring).
      damping: the dashpot's loss ``c γ_t |v_s|²`` [W] (``c``: the Coulomb cut, 1 in stick).
      slip: the slip's loss [W] (module docstring; zero in stick).
      sliding: whether the contact slipped (``|F_t|`` cut to ``μ F_n``).
    """

    force: Vec
    history: Vec
    energy: jnp.ndarray
    turned: jnp.ndarray
    damping: jnp.ndarray
    slip: jnp.ndarray
    sliding: jnp.ndarray


def spring_jax(fs: Vec, n: Vec, v_slide: Vec, dt, kt, gt, f_normal, mu, touching,
               step_slide: Vec | None = None, rescale=1.0) -> Spring:
    """One time step of tangential springs (module docstring), JAX form.

    Args:
      fs: the stored spring forces [N] (the last step's :attr:`Spring.history`), :class:`Vec`.
      n: unit normals from the partner to grain ``i``, :class:`Vec`.
      v_slide: tangential velocity of ``i``'s surface against its partner's at the contact
        point [m/s] (in the plane normal to ``n``), :class:`Vec`: the dashpot's.
      dt: the time step [s].
      kt: tangential stiffness [N/m] (:func:`stiffness`), > 0 where ``touching``.
      gt: tangential damping [kg/s].
      f_normal: normal force magnitude ``F_n ≥ 0`` [N].
      mu: Coulomb coefficient [-].
      touching: ``ξ > 0``; elsewhere force, history and energy are zero.
      step_slide: the sliding velocity ``u`` the spring grows with over the step (``None``:
        ``v_slide``). The engines pass the contact points' mean velocity over the step (from
        the half-step velocities of velocity Verlet, with which the positions advance).
      rescale: the factor ``≤ 1`` on the stored force of a shrinking contact,
        ``sqrt(ξ/ξ_old)`` where ``ξ < ξ_old`` (:func:`unloading`).

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
    fr = fs - n.scale(fs.dot(n))
    old2, new2 = fs.dot(fs), fr.dot(fr)
    turned = new2 > 0
    keep = jnp.where(turned, safe_sqrt(old2, turned) / safe_sqrt(new2, turned), 1.0)
    ft = fr.scale(keep)  # the old force, turned
    fa = ft.scale(jnp.where(touching, rescale, 0.0))  # a contact that ended: all of it off
    # 2. grown by this step's displacement
    u = v_slide if step_slide is None else step_slide
    g = fa - u.scale(kt * dt)
    # 3. spring and dashpot; 4. cut to the Coulomb limit where it slips
    f = g - v_slide.scale(gt)
    f2 = f.dot(f)
    cap = mu * f_normal
    sliding = touching & (f2 > cap * cap)
    cut = jnp.where(touching, jnp.where(sliding, cap / safe_sqrt(f2, sliding), 1.0), 0.0)
    f = f.scale(cut)
    f_new = g.scale(cut)  # the spring cut with the force (zero where not touching)
    inv_k = jnp.where(touching, 1.0 / jnp.where(touching, kt, 1.0), 0.0)
    # the spring's work over the step (trapezoid rule) less what it stores (docstring)
    slip = -0.5 * (fa + f_new).dot(u + (f_new - fa).scale(inv_k / dt))
    return Spring(force=f, history=f_new, energy=0.5 * inv_k * f_new.dot(f_new),
                  turned=0.5 * inv_k * fa.dot(fa) + 0.5 * dt * (ft - fa).dot(u),
                  damping=cut * gt * v_slide.dot(v_slide),
                  slip=jnp.where(touching, slip, 0.0), sliding=sliding)


@scalar_form
def spring_scalar(fx, fy, fz, nx, ny, nz, vx, vy, vz, ux, uy, uz, dt, kt, gt, f_normal, mu,
                  shrunk, peak):
    """Scalar form of :func:`spring_jax` for one touching contact (``kt > 0``), its
    ``step_slide`` ``(ux, uy, uz)`` given (``v_slide`` for none) and its ``rescale`` as
    ``sqrt(shrunk/peak)`` (``0 < shrunk ≤ peak``; equal: none; for Mindlin's stiffness ``ξ`` and
    ``max(ξ_old, ξ)``, :func:`unloading`).

    Returns the force on ``i`` ``(tx, ty, tz)``, the new history (spring force) ``(hx, hy,
    hz)``, the spring's energy, the turned energy, the damping and slip losses and whether it
    slipped (:class:`Spring`).

    The same arithmetic as :func:`spring_jax` in fewer of the divider's operations (the
    native kernel's cost per contact, issue 39): the turn's length factor and the rescaling
    share one division, ``q = |F_s|²/(|F_r|² peak)``, ``keep = sqrt(q peak)``, ``keep ·
    rescale = sqrt(q shrunk)``, and neither branches (an unloading contact is as likely as a
    loading one: a branch on it is mispredicted half the time). A fresh spring (``F_s = 0``)
    turns to zero through the same arithmetic (``|F_r|²`` floored at 1e-200 N²)."""
    fn_ = fx * nx + fy * ny + fz * nz
    rx, ry, rz = fx - fn_ * nx, fy - fn_ * ny, fz - fn_ * nz
    old2 = fx * fx + fy * fy + fz * fz
    new2 = rx * rx + ry * ry + rz * rz
    q = old2 / (max(new2, 1e-200) * peak)
    keep = math.sqrt(q * peak)
    kr = math.sqrt(q * shrunk)  # keep · rescale
    ax, ay, az = rx * kr, ry * kr, rz * kr
    # the rescaled-off part's work over the step (see Spring.turned)
    off = 0.5 * dt * (keep - kr) * (rx * ux + ry * uy + rz * uz)
    kd = kt * dt
    gx, gy, gz = ax - kd * ux, ay - kd * uy, az - kd * uz
    tx, ty, tz = gx - gt * vx, gy - gt * vy, gz - gt * vz
    t2 = tx * tx + ty * ty + tz * tz
    cap = mu * f_normal
    sliding = t2 > cap * cap
    cut = 1.0
    if sliding:
        cut = cap / math.sqrt(t2)
        tx, ty, tz = tx * cut, ty * cut, tz * cut
        gx, gy, gz = gx * cut, gy * cut, gz * cut
    inv_k = 1.0 / kt
    w = inv_k / dt
    slip = -0.5 * ((ax + gx) * (ux + (gx - ax) * w) + (ay + gy) * (uy + (gy - ay) * w)
                   + (az + gz) * (uz + (gz - az) * w))
    return (tx, ty, tz, gx, gy, gz, 0.5 * inv_k * (gx * gx + gy * gy + gz * gz),
            0.5 * inv_k * (ax * ax + ay * ay + az * az) + off,
            cut * gt * (vx * vx + vy * vy + vz * vz), slip, sliding)


@scalar_form
def mindlin_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx, sy, sz, qx, qy, qz, px, py, pz, k, g,
                   G_star, r_eff, mu, dt, hx, hy, hz):
    """Scalar form of :func:`contact_force` for one contact that touches (``ξ > 0``) or held a
    spring at the last step (``h ≠ 0``; ``ξ ≤ 0``: the contact ended, its spring gone), the
    native kernel's: normal ``n`` (unit, from the partner to ``i``), relative velocity ``v``
    and spin ``s`` (as :func:`jaxdamp.physics.contact.contact_scalar`'s), the same over the
    step ``q``, ``p`` (the half-step velocities, :class:`Mindlin`), the normal law's ``k``,
    ``g``, the spring's ``G*``, ``R*``, ``μ``, the time step and the stored spring force
    ``h``.

    Returns the force on ``i`` ``(fx, fy, fz)``, its tangential part ``(tx, ty, tz)`` (the
    torque on a body of radius ``R`` is ``−R n × F_t``), the elastic energy (the spring's
    included), the normal and friction losses [W], the new history ``(hx, hy, hz)``, the
    turned energy, the slip loss [W] and the spring's energy (:class:`Spring`)."""
    # the contact point's tangential velocity over the step, with which the spring grows
    ux, uy, uz = slide_scalar(nx, ny, nz, qx, qy, qz, px, py, pz)
    if xi <= 0.0:  # ended: the old force, turned into the plane, does its work (Spring.turned)
        fn_ = hx * nx + hy * ny + hz * nz
        rx, ry, rz = hx - fn_ * nx, hy - fn_ * ny, hz - fn_ * nz
        new2 = rx * rx + ry * ry + rz * rz
        keep = math.sqrt(hx * hx + hy * hy + hz * hz) / math.sqrt(new2) if new2 > 0.0 else 1.0
        return (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
                0.5 * dt * keep * (rx * ux + ry * uy + rz * uz), 0.0, 0.0)
    _, xi_dot, f_el, f_n, e_el = normal_force_scalar(law, xi, nx, ny, nz, vx, vy, vz, k, g)
    wx, wy, wz = slide_scalar(nx, ny, nz, vx, vy, vz, sx, sy, sz)
    # the step's stiffness and the rescaling of an unloading contact (:func:`unloading`):
    # sqrt(ξ/ξ_old) where the contact shrank, without a branch
    xi_old = max(xi - dt * xi_dot, 0.0)
    kt = stiffness_scalar(G_star, r_eff, 0.5 * (xi + xi_old))
    (tx, ty, tz, gx, gy, gz, e_s, turned, damp, slip, _) = spring_scalar(
        hx, hy, hz, nx, ny, nz, wx, wy, wz, ux, uy, uz, dt, kt, damping_scalar(kt, k, g), f_n,
        mu, xi, max(xi_old, xi))
    return (f_n * nx + tx, f_n * ny + ty, f_n * nz + tz, tx, ty, tz, e_el + e_s,
            (f_n - f_el) * xi_dot, damp + slip, gx, gy, gz, turned, slip, e_s)


#: :func:`mindlin_scalar` compiled apart and called (not inlined): the native kernel's wall
#: contacts, one call per wall a grain touches, instead of a copy in every wall of every
#: container of every compiled pass over the walls (the kernel's cold compile; the kernel keys
#: its cache on the sources it calls, :func:`jaxdamp.engine.native._cache_on_sources`).
mindlin_called = scalar_form(mindlin_scalar.py_func, inline=False) if hasattr(
    mindlin_scalar, "py_func") else mindlin_scalar


class Mindlin(NamedTuple):
    """What :func:`contact_force` needs of the tangential springs of contacts (shape ``S``):
    their stored forces ``history`` [N] (:class:`Vec`), the time step ``dt`` [s], the pairs'
    shear modulus ``G_star`` [Pa] (:data:`jaxdamp.physics.contact.G_STAR`) and effective radius
    ``r_eff`` [m] (wall: the grain's, or a curved wall's effective radius); ``v_rel``,
    ``spin``: the relative velocity and spin (as :func:`contact_force`'s) over the step, with
    which the springs grow (the half-step velocities of velocity Verlet: the contact points'
    displacement over the step; ``None``: those of the force evaluation)."""

    history: Vec
    dt: jnp.ndarray
    G_star: jnp.ndarray
    r_eff: jnp.ndarray
    v_rel: Vec | None = None
    spin: Vec | None = None


def contact_force(law: Law, xi, n: Vec, v_rel: Vec, spin: Vec, radius_i, k, g, mu,
                  spring: Mindlin) -> ContactForce:
    """Force, torque and losses of a sphere contact with the tangential spring (the normal
    part of :func:`jaxdamp.physics.contact.normal_part`, arguments as
    :func:`jaxdamp.physics.contact.contact_force`'s; ``γ_s`` is not used, the spring's damping
    follows the normal law's, :func:`damping`), JAX form. The spring's stiffness is taken at
    the mean overlap of the step and an unloading contact's force rescaled
    (:func:`unloading`; the overlap at the step's start from the rate ``ξ'``)."""
    c = normal_part(law, xi, n, v_rel, spin, k, g)
    xi_old = jnp.where(c.touching, jnp.maximum(c.xi - spring.dt * c.xi_dot, 0.0), 0.0)
    xi_step, rescale = unloading(c.xi, xi_old)
    kt = stiffness(spring.G_star, spring.r_eff, jnp.where(c.touching, xi_step, 0.0))
    step_slide = None
    if spring.v_rel is not None:
        u = spring.v_rel - spring.spin.cross(n)
        step_slide = u - n.scale(u.dot(n))
    sp = spring_jax(spring.history, n, c.v_slide, spring.dt, kt, damping(kt, k, g),
                    c.f_normal, mu, c.touching, step_slide, rescale)
    return ContactForce(
        force=n.scale(c.f_normal) + sp.force,
        torque=n.scale(-radius_i).cross(sp.force),
        normal=c.f_normal,
        elastic_energy=c.e_elastic + sp.energy,
        normal_loss=c.loss(),
        friction_loss=sp.damping + sp.slip,
        touching=c.touching,
        history=sp.history,
        turned=sp.turned,
        slip_loss=sp.slip,
        spring_energy=sp.energy,
    )


class Impact(NamedTuple):
    """The outcome of :func:`oblique_impact`: velocities after the contact — normal ``vn``
    (away from the wall), tangential ``vt``, the surface speed of the spin ``R ω`` and the
    contact point's tangential velocity ``u = v_t − R ω`` [m/s] — and the books of the
    tangential force [J]: its work on the sphere (the spring's by the trapezoid rule, as the
    engines' velocity Verlet moves the grains, and the dashpot's ``−c γ_t |v_s|² dt``), the
    damping and slip losses, the stiffness work (:class:`Spring`), the spring's energy left
    (zero: the contact ended) and at its peak; ``steps`` in contact."""

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
    (:func:`spring_scalar`) of stiffness ``kt_of(ξ)`` [N/m] (taken over each step as the engines
    do, :func:`unloading`), damping ``gt`` [kg/s] and Coulomb
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
    xi_old = 0.0
    for _ in range(50 * steps):
        xi = R - z
        fx = fz = 0.0
        if xi > 0.0:
            fn = normal(xi)
            u = vx - R * wy  # the contact point's tangential velocity (along x)
            xi_step = 0.5 * (xi + xi_old)  # as the engines (:func:`unloading`), any kt_of
            kt = kt_of(xi)  # the rescaling (kt/kt_old)² of an unloading contact
            kt_peak = max(kt_of(xi_old), kt) if xi_old > xi else kt
            (fx, _, _, s0, s1, s2, en, turned, damp, sl, _) = spring_scalar(
                s[0], s[1], s[2], 0.0, 0.0, 1.0, u, 0.0, 0.0, u, 0.0, 0.0, dt, kt_of(xi_step),
                gt, fn, mu, kt * kt, kt_peak * kt_peak)
            work += (0.5 * (s[0] + s0) * u - damp) * dt
            s = (s0, s1, s2)
            xi_old = xi
            fz = fn
            damping += damp * dt
            slip += sl * dt
            stiffness += turned - spring
            spring = en
            peak = max(peak, en)
            n_contact += 1
        else:
            u = vx - R * wy
            gone = 0.5 * dt * s[0] * u  # the old force's work over the step it ended in
            work += gone
            s = (0.0, 0.0, 0.0)
            xi_old = 0.0
            stiffness += gone - spring  # the spring's energy, gone with the contact
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
