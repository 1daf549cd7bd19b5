"""Sphere–wall contacts with the six flat walls of the box (docs/physics.md §2).

The box spans ``[0, Lx] × [0, Ly] × [0, Lz]`` shifted by ``e z_box``: it moves rigidly along
the excitation axis ``e = (ex, ey, ez)`` (``Params``; vertical by default), with velocity
``e zd_box``. Walls use the same contact law as grain pairs with
``R* = R_i``, ``m* = m_i`` and the constants of the grain's species against the wall material
(a row of ``Params.wall_table``, mixed when the model was built).
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxdamp.physics.contact import GAMMA_S, LAWS, MU, Vec, contact_force, force_dtype

#: Inward unit normals of floor, lid, x=0, x=Lx, y=0, y=Ly (pointing from the wall to a grain).
_NORMALS = np.array(
    [[0, 0, 1], [0, 0, -1], [1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], dtype=np.float64
)
FLOOR, LID = 0, 1


class WallForces(NamedTuple):
    """Wall forces on the grains and what they do to the box.

    Attributes:
      force, torque: on each grain [N], [N m], ``(N, 3)``.
      box_z: force of the grains on the whole box along the excitation axis ``e`` [N] (for a
        vertical axis their weight is carried here).
      floor_lid_z: vertical force of the grains on floor + lid only [N].
      n_floor, n_lid: number of grains touching floor / lid.
      elastic_energy: [J]; normal_loss, friction_loss: dissipated power [W] (all walls).
    """

    force: jnp.ndarray
    torque: jnp.ndarray
    box_z: jnp.ndarray
    floor_lid_z: jnp.ndarray
    n_floor: jnp.ndarray
    n_lid: jnp.ndarray
    elastic_energy: jnp.ndarray
    normal_loss: jnp.ndarray
    friction_loss: jnp.ndarray


def wall_forces(r, v, w, z_box, zd_box, p, model) -> WallForces:
    """Contacts of grains ``(N, 3)`` with the six walls of a box at ``e z_box``.

    Args:
      r, v, w: positions [m], velocities [m/s], angular velocities [rad/s], ``(N, 3)``.
      z_box, zd_box: box position [m] and velocity [m/s] along the axis ``e`` (scalars).
      p: :class:`jaxdamp.physics.model.Params`.
      model: :class:`jaxdamp.physics.model.Model` (the law and the grains' species).
    """
    # Signed distance of each centre to each wall plane, (N, 6).
    x, y, floor = r[:, 0] - p.ex * z_box, r[:, 1] - p.ey * z_box, r[:, 2] - p.ez * z_box
    dist = jnp.stack(
        (floor, p.Lz - floor, x, p.Lx - x, y, p.Ly - y), axis=-1
    )
    hi, lo = r.dtype, force_dtype(model)
    xi = (p.radius[:, None] - dist).astype(lo)  # the overlap in the state's precision
    R = p.radius[:, None].astype(lo)
    law = LAWS[model.law]
    table = p.wall_table.astype(lo)
    if table.shape[0] == 1:
        row = table[0]  # (F,): one species
    else:
        row = table[jnp.asarray(model.species_index())][:, None, :]  # (N, 1, F)
    stiffness, damping = law.pair_jax(row, R, p.mass[:, None].astype(lo))
    normals = Vec(*(jnp.asarray(_NORMALS[:, k], lo) for k in range(3)))  # (6,) each
    # the walls move with e zd_box
    v_rel = Vec(*((v[:, k:k + 1] - e * zd_box).astype(lo)
                  for k, e in enumerate((p.ex, p.ey, p.ez))))
    Rw = R * w.astype(lo)
    spin = Vec(Rw[:, 0:1], Rw[:, 1:2], Rw[:, 2:3])
    c = contact_force(law, xi, normals, v_rel, spin, R, stiffness, damping, row[..., GAMMA_S],
                      row[..., MU])

    f = Vec(*(x.astype(hi) for x in c.force))  # (N, 6): force of wall on grain
    return WallForces(
        force=f.sum(axis=1).stack(),
        torque=c.torque.sum(axis=1).stack().astype(hi),
        box_z=-(p.ex * f.x.sum() + p.ey * f.y.sum() + p.ez * f.z.sum()),
        floor_lid_z=-(f.z[:, FLOOR] + f.z[:, LID]).sum(),
        n_floor=c.touching[:, FLOOR].sum(),
        n_lid=c.touching[:, LID].sum(),
        elastic_energy=c.elastic_energy.astype(hi).sum(),
        normal_loss=c.normal_loss.astype(hi).sum(),
        friction_loss=c.friction_loss.astype(hi).sum(),
    )
