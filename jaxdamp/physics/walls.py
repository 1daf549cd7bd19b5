"""Sphere–wall contacts with the walls of the container (docs/physics.md §2): how the contact
law is mapped over a grain's walls.

The container (:mod:`jaxdamp.physics.containers`, ``model.container``) is a prism: the floor at
height 0, the lid at ``Lz`` and the side walls of its section, in its frame, shifted by
``e z_box``: it moves rigidly along the excitation axis ``e = (ex, ey, ez)`` (``Params``;
vertical by default), with velocity ``e zd_box``. A damper of several cells (``Model.cells``)
is one such container per cell, side by side in the box frame: a grain sees the walls of its
own cell, whose corner is at ``Params.origin`` (box frame; zeros for one cell). Walls use
the same contact law as grain pairs with ``m* = m_i``, ``R* = R_i`` for a plane (the
container's effective radius for a curved wall) and the constants of the grain's species
against the wall material (a row of ``Params.wall_table``, mixed when the model was built).
The walls are taken in the order floor, lid, then the container's sides.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxdamp.physics import tangential
from jaxdamp.physics.contact import G_STAR, GAMMA_S, LAWS, MU, Vec, contact_force, force_dtype
from jaxdamp.physics.containers import CONTAINERS, effective_radius

#: The floor's and the lid's places among a grain's walls (the sides follow).
FLOOR, LID = 0, 1


class WallForces(NamedTuple):
    """Wall forces on the grains and what they do to the box.

    Attributes:
      force, torque: on each grain [N], [N m], ``(N, 3)``.
      box_z: force of the grains on the whole box along the excitation axis ``e`` [N] (for a
        vertical axis their weight is carried here).
      floor_lid_z: vertical force of the grains on floor + lid only [N].
      n_floor, n_lid: number of grains touching floor / lid; n_side: contacts with the side
        walls.
      elastic_energy: [J]; normal_loss, friction_loss: dissipated power [W] (all walls);
      group_loss: ``(3,)`` the dissipated power (normal + friction) at the floor, the lid and
        the side walls [W] (:data:`jaxdamp.physics.model.WALL_GROUPS`).
      grain_loss: ``(N,)`` the dissipated power (normal + friction) of each grain's wall
        contacts [W].
      grain_box_z: ``(N,)`` each grain's force on its container along ``e`` [N] (``box_z``
        per grain: the cells' forces on their degrees of freedom).
      history: with tangential springs (``model.springs``), ``(N, 2 + W, 3)`` [N] each
        grain's spring with each wall after the step; without, ``(N, 0, 3)``.
      turned, spring_energy: [J], slip_loss: [W] the springs' totals
        (:class:`jaxdamp.physics.pairs.PairForces`); 0 without springs.
    """

    force: jnp.ndarray
    torque: jnp.ndarray
    box_z: jnp.ndarray
    floor_lid_z: jnp.ndarray
    n_floor: jnp.ndarray
    n_lid: jnp.ndarray
    n_side: jnp.ndarray
    elastic_energy: jnp.ndarray
    normal_loss: jnp.ndarray
    friction_loss: jnp.ndarray
    group_loss: jnp.ndarray
    grain_loss: jnp.ndarray
    grain_box_z: jnp.ndarray
    history: jnp.ndarray
    turned: jnp.ndarray
    slip_loss: jnp.ndarray
    spring_energy: jnp.ndarray


def wall_forces(r, v, w, z_box, zd_box, p, model, history=None, step_vw=None) -> WallForces:
    """Contacts of grains ``(N, 3)`` with the walls of a container at ``e z_box``.

    Args:
      r, v, w: positions [m], velocities [m/s], angular velocities [rad/s], ``(N, 3)``.
      z_box, zd_box: box position [m] and velocity [m/s] along the axis ``e``: scalars, or
        ``(N,)`` each grain's container's (cells on several degrees of freedom,
        :func:`jaxdamp.physics.model.grain_positions_of_boxes`).
      p: :class:`jaxdamp.physics.model.Params`.
      model: :class:`jaxdamp.physics.model.Model` (the laws, the container, the species).
      history: with tangential springs (``model.springs``), their forces
        ``(N, 2 + W, 3)`` [N] before the step (``None``: none yet); they advance by one step
        ``p.dt``. Ignored without springs.
      step_vw: with springs, ``(v, w, zd_box)`` over the step with which they grow
        (:class:`jaxdamp.physics.contact.Mindlin`; ``None``: ``v``, ``w``, ``zd_box``).
    """
    # Signed distance of each centre to each wall, (N, 2 + W): floor, lid, the sides; (x, y)
    # in the frame of the grain's own cell (its corner at p.origin in the box frame)
    x = r[:, 0] - p.ex * z_box - p.origin[:, 0]
    y = r[:, 1] - p.ey * z_box - p.origin[:, 1]
    floor = r[:, 2] - p.ez * z_box
    vessel = CONTAINERS[model.container]
    gaps, (snx, sny), curvature = vessel.sides_jax(x, y, p.section)
    dist = jnp.stack((floor, p.Lz - floor) + tuple(gaps), axis=-1)
    hi, lo = r.dtype, force_dtype(model)
    xi = (p.radius[:, None] - dist).astype(lo)  # the overlap in the state's precision
    R = p.radius[:, None].astype(lo)
    law = LAWS[model.law]
    table = p.wall_table.astype(lo)
    if table.shape[0] == 1:
        row = table[0]  # (F,): one species
    else:
        row = table[jnp.asarray(model.species_index())][:, None, :]  # (N, 1, F)
    R_contact = R
    if vessel.curved:  # a curved wall: its own effective radius (floor and lid are planes)
        kappa = jnp.concatenate([jnp.zeros(2, lo), jnp.stack(curvature).astype(lo)])
        R_contact = effective_radius(R, kappa)
    stiffness, damping = law.pair_jax(row, R_contact, p.mass[:, None].astype(lo))
    normals = Vec(*_normals(snx, sny, lo))  # (2 + W,) each, or (N, 2 + W) for curved sides
    def relative(v, w, zd_box):  # the walls move with e zd_box
        zd_col = jnp.reshape(zd_box, (-1, 1)) if jnp.ndim(zd_box) else zd_box
        v_rel = Vec(*((v[:, k:k + 1] - e * zd_col).astype(lo)
                      for k, e in enumerate((p.ex, p.ey, p.ez))))
        Rw = R * w.astype(lo)
        return v_rel, Vec(Rw[:, 0:1], Rw[:, 1:2], Rw[:, 2:3])

    v_rel, spin = relative(v, w, zd_box)
    spring = None
    if model.springs:
        s = jnp.zeros(xi.shape + (3,), lo) if history is None else history.astype(lo)
        v_step = spin_step = None
        if step_vw is not None:
            v_step, spin_step = relative(*step_vw)
        spring = tangential.Mindlin(Vec.of(s), p.dt.astype(lo), row[..., G_STAR], R_contact,
                                    v_step, spin_step)
        c = tangential.contact_force(law, xi, normals, v_rel, spin, R, stiffness, damping,
                                     row[..., MU], spring)
    else:
        c = contact_force(law, xi, normals, v_rel, spin, R, stiffness, damping,
                          row[..., GAMMA_S], row[..., MU])

    f = Vec(*(x.astype(hi) for x in c.force))  # (N, 2 + W): force of wall on grain
    per_contact = (c.normal_loss + c.friction_loss).astype(hi)  # (N, 2 + W)
    loss = per_contact.sum(axis=0)  # per wall
    along = -(p.ex * f.x.sum(axis=1) + p.ey * f.y.sum(axis=1) + p.ez * f.z.sum(axis=1))
    return WallForces(
        force=f.sum(axis=1).stack(),
        torque=c.torque.sum(axis=1).stack().astype(hi),
        box_z=-(p.ex * f.x.sum() + p.ey * f.y.sum() + p.ez * f.z.sum()),
        floor_lid_z=-(f.z[:, FLOOR] + f.z[:, LID]).sum(),
        n_floor=c.touching[:, FLOOR].sum(),
        n_lid=c.touching[:, LID].sum(),
        n_side=c.touching[:, LID + 1:].sum(),
        elastic_energy=c.elastic_energy.astype(hi).sum(),
        normal_loss=c.normal_loss.astype(hi).sum(),
        friction_loss=c.friction_loss.astype(hi).sum(),
        group_loss=jnp.stack([loss[FLOOR], loss[LID], loss[LID + 1:].sum()]),
        grain_loss=per_contact.sum(axis=1),
        grain_box_z=along,
        history=(c.history.stack().astype(hi) if spring is not None
                 else jnp.zeros((r.shape[0], 0, 3), hi)),
        turned=c.turned.astype(hi).sum() if spring is not None else jnp.zeros((), hi),
        slip_loss=c.slip_loss.astype(hi).sum() if spring is not None else jnp.zeros((), hi),
        spring_energy=(c.spring_energy.astype(hi).sum() if spring is not None
                       else jnp.zeros((), hi)),
    )


def _normals(snx, sny, dtype):
    """Inward unit normals ``(nx, ny, nz)`` of floor, lid and the sides (normals ``(nx, ny)``
    of the container): NumPy constants where the sides are planes, else arrays ``(N, 2 + W)``."""
    if isinstance(snx, np.ndarray) and isinstance(sny, np.ndarray):
        nx = np.concatenate(([0.0, 0.0], snx))
        ny = np.concatenate(([0.0, 0.0], sny))
        nz = np.concatenate(([1.0, -1.0], np.zeros(len(snx))))
        return tuple(jnp.asarray(a, dtype) for a in (nx, ny, nz))
    n = jnp.shape(snx)[0]
    ends = lambda a, b: jnp.broadcast_to(jnp.asarray([a, b], dtype), (n, 2))  # noqa: E731
    return (jnp.concatenate([ends(0.0, 0.0), jnp.asarray(snx, dtype)], axis=1),
            jnp.concatenate([ends(0.0, 0.0), jnp.asarray(sny, dtype)], axis=1),
            jnp.concatenate([ends(1.0, -1.0), jnp.zeros(jnp.shape(snx), dtype)], axis=1))
