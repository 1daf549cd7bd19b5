"""What drives the system: the base motion of S1 and the prescribed box motion of S2 (docs/physics.md §1).

Each motion in its JAX form (of :class:`~jaxdamp.physics.model.Params`) and, next to it, its numba
scalar form for the native kernel (:mod:`jaxdamp.engine.native`); ``Ω = 2πf`` [rad/s].
"""

from __future__ import annotations

import math

import jax.numpy as jnp

from jaxdamp.physics.contact import scalar_form
from jaxdamp.physics.model import Params


def base_motion(t, p: Params):
    """Base displacement ``u = U cos Ωt`` [m] and velocity ``u' = -U Ω sin Ωt`` [m/s] of S1."""
    ph = p.omega * t
    return p.U * jnp.cos(ph), -p.U * p.omega * jnp.sin(ph)


@scalar_form
def base_motion_scalar(t, U, omega):
    """Scalar form of :func:`base_motion`: ``(u, u')`` at time ``t`` [s]."""
    ph = omega * t
    return U * math.cos(ph), -U * omega * math.sin(ph)


def drive_motion(t, p: Params):
    """Box position ``z_offset + A_d cos Ωt`` [m], velocity [m/s], acceleration [m/s²] of S2."""
    ph = p.omega * t
    c, s = jnp.cos(ph), jnp.sin(ph)
    return (
        p.z_offset + p.amplitude * c,
        -p.amplitude * p.omega * s,
        -p.amplitude * p.omega**2 * c,
    )


@scalar_form
def drive_motion_scalar(t, z_offset, amplitude, omega):
    """Scalar form of :func:`drive_motion`: ``(z, z', z'')`` at time ``t`` [s]."""
    ph = omega * t
    c = math.cos(ph)
    return z_offset + amplitude * c, -amplitude * omega * math.sin(ph), -amplitude * omega**2 * c
