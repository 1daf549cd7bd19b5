"""Grain–grain contacts over a dense neighbour block (SPEC §2).

Each grain ``i`` sees its neighbours ``idx[i, :]`` (jax-md ``Dense`` format, padded with ``N``).
Every pair is evaluated from both sides and forces are summed per row: no scatter, and
Newton's third law holds to the last bit because the two sides run the same arithmetic on
negated inputs. Pair sums of energies and losses are therefore halved.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp

from .contact import contact_force, hertz_stiffness, mix

#: Where padding entries of the neighbour list point: far away, so they never touch.
_GHOST = 1.0e6


class PairForces(NamedTuple):
    """Grain–grain forces. ``force``, ``torque``: ``(N, 3)`` [N], [N m]; the rest are totals:
    ``elastic_energy`` [J], ``normal_loss``, ``friction_loss`` [W]."""

    force: jnp.ndarray
    torque: jnp.ndarray
    elastic_energy: jnp.ndarray
    normal_loss: jnp.ndarray
    friction_loss: jnp.ndarray


def _pad(x, value):
    return jnp.concatenate([x, jnp.full((1,) + x.shape[1:], value, x.dtype)], axis=0)


def pair_forces(r, v, w, idx, p, mixing: str) -> PairForces:
    """Contact forces between grains.

    Args:
      r, v, w: positions [m], velocities [m/s], angular velocities [rad/s], ``(N, 3)``.
      idx: neighbour indices ``(N, K)``, entries ``N`` are padding.
      p: :class:`jaxdamp.model.Params`.
      mixing: pair mixing rule.
    """
    n = r.shape[0]
    if n < 2 or idx.shape[1] == 0:
        zero = jnp.zeros_like(r)
        return PairForces(zero, zero, jnp.zeros(()), jnp.zeros(()), jnp.zeros(()))

    def gather(x, fill):
        return _pad(x, fill)[idx]

    r_j = gather(r, _GHOST)
    R_i = p.radius[:, None]
    R_j = gather(p.radius, 0.0)
    dr = r[:, None, :] - r_j
    dist2 = jnp.sum(dr * dr, axis=-1)
    dist = jnp.sqrt(dist2)  # > 0: grains never coincide, padding is far away
    xi = R_i + R_j - dist
    nrm = dr / dist[..., None]

    r_eff = R_i * R_j / (R_i + R_j + (R_j == 0))  # padding has R_j = 0
    k_n = hertz_stiffness(p.compliance[:, None] + gather(p.compliance, 1.0), r_eff)
    gamma_n = mix(p.gamma_n[:, None], gather(p.gamma_n, 0.0), mixing) + 1.5 * mix(
        p.A[:, None], gather(p.A, 0.0), mixing
    ) * k_n
    gamma_s = mix(p.gamma_s[:, None], gather(p.gamma_s, 0.0), mixing)
    mu = mix(p.mu[:, None], gather(p.mu, 0.0), mixing)
    v_rel = v[:, None, :] - gather(v, 0.0)
    spin = (p.radius[:, None] * w)[:, None, :] + gather(p.radius[:, None] * w, 0.0)

    c = contact_force(xi, nrm, v_rel, spin, R_i, k_n, gamma_n, gamma_s, mu)
    return PairForces(
        force=c.force.sum(axis=1),
        torque=c.torque.sum(axis=1),
        elastic_energy=0.5 * c.elastic_energy.sum(),
        normal_loss=0.5 * c.normal_loss.sum(),
        friction_loss=0.5 * c.friction_loss.sum(),
    )


def all_pairs(n: int) -> jnp.ndarray:
    """A neighbour block listing every other grain: ``(N, N-1)``, the brute-force reference."""
    import numpy as np

    full = np.arange(n)[None, :].repeat(n, axis=0)
    return jnp.asarray(full[~np.eye(n, dtype=bool)].reshape(n, n - 1), dtype=jnp.int32)
