"""What drives the system: the base motion of S1 and the prescribed box motion of S2."""

from __future__ import annotations

import jax.numpy as jnp

from .model import Params


def base_motion(t, p: Params):
    """Base displacement ``u = U cos Ωt`` [m] and velocity ``u'`` [m/s] of S1."""
    ph = p.omega * t
    return p.U * jnp.cos(ph), -p.U * p.omega * jnp.sin(ph)


def drive_motion(t, p: Params):
    """Box position ``z_offset + A_d cos Ωt`` [m], velocity [m/s], acceleration [m/s²] of S2."""
    ph = p.omega * t
    c, s = jnp.cos(ph), jnp.sin(ph)
    return (
        p.z_offset + p.amplitude * c,
        -p.amplitude * p.omega * s,
        -p.amplitude * p.omega**2 * c,
    )
