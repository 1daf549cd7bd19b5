"""Mounts: how the container moves, registered by name (:data:`MOUNTS`; docs/physics.md §1, §3).

The container moves rigidly along the excitation axis ``e``; its position ``z`` [m] along it
is set by its mount:

* ``"primary"`` — the 1-DOF primary system of S1, ``M z'' = -C (z' - u') - K (z - u) + F_gz``
  with the base at ``u(t)`` (:func:`jaxdamp.physics.excitation.base_motion`) and ``F_gz`` the
  grains' force on the box along ``e`` (``z = 0`` is the empty box's static equilibrium);
* ``"structure"`` — the box on one degree of freedom of a linear structure of ``n`` degrees
  of freedom (S1 with ``Config.structure``; :mod:`jaxdamp.physics.structure`), the others in
  ``State.y``;
* ``"driven"`` — the prescribed motion of S2, ``z = z_offset + A_d cos Ωt``
  (:func:`jaxdamp.physics.excitation.drive_motion`): its velocity is exact, not integrated.

Each mount gives, for one system, in its JAX form (arrays of ``State`` and ``Params``) and its
scalar form (the compiled kernel, parameters read by name from the packed row: ``prow[po.M]``):

* ``predict`` — the box's position and velocity at ``t + dt`` before the forces
  (velocity Verlet's predictor for the integrated mounts, the drive for a prescribed one);
* ``accelerate`` — ``(z'', y'')`` from the grains' forces ``f`` ``(dofs,)`` [N] on the
  degrees of freedom along ``e`` (``f[0]`` on the box; a structure's cells may load others,
  :func:`jaxdamp.physics.structure.cell_dofs`);
* ``powers`` — the power into the system from outside (``input``) and the loss in the mount's
  own damping (``primary_damping``) [W] (:data:`jaxdamp.physics.model.CHANNELS`);
* ``energy`` — the mount's mechanical energy [J] (0 for a prescribed motion).

:func:`jaxdamp.physics.integrate.step` and the native kernel (:mod:`jaxdamp.engine.native`)
are the same skeleton around these. Adding a mount is its functions here, its entry in
:data:`MOUNTS` and a branch in each scalar dispatch (:func:`predict_scalar`,
:func:`respond_scalar`, :func:`energy_scalar`); :func:`mount_of` says which mount a model has.

Example (the 1-DOF primary's acceleration and powers; JAX and scalar forms agree)::

    >>> from jaxdamp.physics.mounts import primary_acceleration, primary_acceleration_scalar
    >>> float(primary_acceleration(0.001, 0.0, 0.0, 0.0, 2.0, 2.0, 1e4, 5.0))
    -4.0
    >>> primary_acceleration_scalar(0.001, 0.0, 0.0, 0.0, 2.0, 2.0, 1e4, 5.0)
    -4.0
"""

from __future__ import annotations

import math
from typing import Callable, NamedTuple

import jax.numpy as jnp

from jaxdamp.physics import structure
from jaxdamp.physics.contact import scalar_form
from jaxdamp.physics.excitation import (
    base_motion,
    base_motion_scalar,
    drive_motion,
    drive_motion_scalar,
)

# -- the 1-DOF primary's arithmetic (one function for JAX arrays and, compiled, scalars) ------


def primary_acceleration(z, zd, u, ud, box_z, M, K, C):
    """``z'' = (-C (z' - u') - K (z - u) + F_gz) / M`` [m/s²] of the primary (S1), with the
    base at ``u`` [m], ``u'`` [m/s] and the grains' force on the box ``F_gz`` [N]."""
    return (-C * (zd - ud) - K * (z - u) + box_z) / M


def primary_powers(z, zd, u, ud, K, C):
    """Power of the base on the primary through spring and damper,
    ``-u' (K (z - u) + C (z' - u'))``, and the loss in the damper ``C (z' - u')²`` [W]."""
    return -ud * (K * (z - u) + C * (zd - ud)), C * (zd - ud) * (zd - ud)


primary_acceleration_scalar = scalar_form(primary_acceleration)
primary_powers_scalar = scalar_form(primary_powers)


# -- JAX forms (one system) -------------------------------------------------------------------


def _verlet_predict(z, zd, zdd, t1, dt, p):
    return z + dt * zd + 0.5 * dt * dt * zdd, zd + dt * zdd


def _dofs(z, y):
    """The structure's vector ``(z, y...)`` (the box first)."""
    return jnp.concatenate([jnp.reshape(z, (1,)), y])


def _primary_accelerate(z, zd, y, yd, t, f, p):
    u, ud = base_motion(t, p)
    return primary_acceleration(z, zd, u, ud, f[0], p.M, p.K, p.C), jnp.zeros_like(y)


def _primary_powers(f, z, zd, y, yd, t, p):
    u, ud = base_motion(t, p)
    return primary_powers(z, zd, u, ud, p.K, p.C)


def _primary_energy(z, zd, y, yd, t, p):
    u, _ = base_motion(t, p)
    return 0.5 * p.M * zd**2 + 0.5 * p.K * (z - u) ** 2


def _structure_accelerate(z, zd, y, yd, t, f, p):
    u, ud = base_motion(t, p)
    a = structure.acceleration(_dofs(z, y), _dofs(zd, yd), u, ud, f,
                               jnp.cos(p.omega * t), p)
    return a[0], a[1:]


def _structure_powers(f, z, zd, y, yd, t, p):
    u, ud = base_motion(t, p)
    return structure.powers(_dofs(z, y), _dofs(zd, yd), u, ud, jnp.cos(p.omega * t), p)


def _structure_energy(z, zd, y, yd, t, p):
    u, _ = base_motion(t, p)
    return structure.energy(_dofs(z, y), _dofs(zd, yd), u, p)


def _driven_predict(z, zd, zdd, t1, dt, p):
    z1, zd1, _ = drive_motion(t1, p)
    return z1, zd1


def _driven_accelerate(z, zd, y, yd, t, f, p):
    return drive_motion(t, p)[2], jnp.zeros_like(y)


def _driven_powers(f, z, zd, y, yd, t, p):
    p_in = -f[0] * zd  # the work of the moving walls on the grains
    return p_in, jnp.zeros_like(p_in)


def _driven_energy(z, zd, y, yd, t, p):
    return jnp.zeros(())


class Mount(NamedTuple):
    """A mount's JAX forms (module docstring); ``id``: its number in the scalar dispatch;
    ``prescribed``: its motion is given (the velocity is the drive's, not integrated)."""

    name: str
    id: int
    prescribed: bool
    predict: Callable
    accelerate: Callable
    powers: Callable
    energy: Callable


PRIMARY = Mount("primary", 0, False, _verlet_predict, _primary_accelerate, _primary_powers,
                _primary_energy)
DRIVEN = Mount("driven", 1, True, _driven_predict, _driven_accelerate, _driven_powers,
               _driven_energy)
STRUCTURE = Mount("structure", 2, False, _verlet_predict, _structure_accelerate,
                  _structure_powers, _structure_energy)

#: The mounts by name.
MOUNTS: dict[str, Mount] = {m.name: m for m in (PRIMARY, DRIVEN, STRUCTURE)}
_DRIVEN, _STRUCTURE = DRIVEN.id, STRUCTURE.id


def mount_of(model) -> Mount:
    """The mount of a :class:`~jaxdamp.physics.model.Model`: the prescribed drive of S2, the
    structure of S1 with more than one degree of freedom, else the 1-DOF primary."""
    if model.system == "driven":
        return DRIVEN
    return STRUCTURE if model.dofs > 1 else PRIMARY


# -- scalar forms (the native kernel; parameters read by name: prow[po.NAME]) -----------------


@scalar_form
def _base_scalar(t, prow, po, n_lines):
    """The base motion ``(u, u')`` at ``t`` from the packed parameters."""
    lines = prow[po.lines:po.lines + 3 * n_lines].reshape((n_lines, 3))
    return base_motion_scalar(t, prow[po.U], prow[po.omega], lines, prow[po.shock_a],
                              prow[po.shock_t0], prow[po.shock_T])


@scalar_form
def predict_scalar(mount, t1, dt, z, zd, zdd, prow, po):
    """Scalar form of ``predict``: ``(z(t + dt), z'(t + dt))`` before the forces."""
    if mount == _DRIVEN:
        z1, zd1, _ = drive_motion_scalar(t1, prow[po.z_offset], prow[po.amplitude],
                                         prow[po.omega])
        return z1, zd1
    return z + dt * zd + 0.5 * dt * dt * zdd, zd + dt * zdd


@scalar_form
def respond_scalar(mount, t, z, zd, y, yd, f, prow, po, n_lines, xs, xds, acc, tmp):
    """Scalar forms of ``accelerate`` and ``powers`` at one force evaluation (``f``: the
    grains' forces on the degrees of freedom): returns ``(z'', p_input, p_damping)`` and
    writes ``y''`` into ``acc[1:]`` (a structure; ``xs``, ``xds``, ``tmp``: scratch of its
    size)."""
    if mount == _DRIVEN:
        a = drive_motion_scalar(t, prow[po.z_offset], prow[po.amplitude], prow[po.omega])[2]
        return a, -f[0] * zd, 0.0
    u, ud = _base_scalar(t, prow, po, n_lines)
    if mount == _STRUCTURE:
        n = xs.shape[0]
        nd2 = n * n
        Minv = prow[po.s_Minv:po.s_Minv + nd2].reshape((n, n))
        K = prow[po.s_K:po.s_K + nd2].reshape((n, n))
        C = prow[po.s_C:po.s_C + nd2].reshape((n, n))
        r = prow[po.s_r:po.s_r + n]
        b = prow[po.s_b:po.s_b + n]
        cos_t = math.cos(prow[po.omega] * t)
        xs[0] = z
        xds[0] = zd
        for j in range(n - 1):
            xs[j + 1] = y[j]
            xds[j + 1] = yd[j]
        structure.acceleration_scalar(acc, xs, xds, u, ud, f, cos_t, Minv, K, C, r, b, tmp)
        p_in, p_c = structure.powers_scalar(xs, xds, u, ud, cos_t, K, C, r, b)
        return acc[0], p_in, p_c
    M, K, C = prow[po.M], prow[po.K], prow[po.C]
    a = primary_acceleration_scalar(z, zd, u, ud, f[0], M, K, C)
    p_in, p_c = primary_powers_scalar(z, zd, u, ud, K, C)
    return a, p_in, p_c


@scalar_form
def energy_scalar(mount, t, z, zd, y, yd, prow, po, n_lines, xs, xds):
    """Scalar form of ``energy`` [J]."""
    if mount == _DRIVEN:
        return 0.0
    u = _base_scalar(t, prow, po, n_lines)[0]
    if mount == _STRUCTURE:
        n = xs.shape[0]
        nd2 = n * n
        xs[0] = z
        xds[0] = zd
        for j in range(n - 1):
            xs[j + 1] = y[j]
            xds[j + 1] = yd[j]
        return structure.energy_scalar(xs, xds, u, prow[po.s_M:po.s_M + nd2].reshape((n, n)),
                                       prow[po.s_K:po.s_K + nd2].reshape((n, n)),
                                       prow[po.s_r:po.s_r + n])
    M, K = prow[po.M], prow[po.K]
    return 0.5 * M * zd * zd + 0.5 * K * (z - u) * (z - u)
