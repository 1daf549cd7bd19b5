"""Initial packing: grains on an FCC lattice (seeded jitter), then settled under gravity.

Settling pours the grains into the box with its lid lifted out of the way (as a damper is
filled before it is closed), with the box at rest at its starting height and a viscous drag
on the grains that speeds up the settling. It stops once every grain is slower than
``numerics.settle_speed`` (or after ``numerics.settle_time``). Only the bed's geometry matters
here, so one settled bed serves every ``Lz`` above its height and every frequency.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from . import neighbors as nb
from .config import Config, ConfigError
from .model import Model, Params
from .simulate import advance, init_states

#: Lattice spacing is (1 + _GAP) grain diameters; jitter is ± _GAP/2 radii per coordinate.
_GAP = 0.05


def fcc_lattice(radii: np.ndarray, Lx: float, Ly: float, seed: int) -> np.ndarray:
    """Box-frame positions ``(N, 3)`` [m] on an FCC lattice filling the base from the floor up.

    Sites are taken layer by layer; radii are assigned to sites in a seeded random order (a
    mixture starts mixed) and each site is jittered by up to ``±_GAP/2`` of the largest radius.
    """
    n = len(radii)
    if n == 0:
        return np.zeros((0, 3))
    r_max = float(radii.max())
    margin = r_max * (1.0 + _GAP)
    h = 2.0 * r_max * (1.0 + _GAP) / math.sqrt(2.0)  # FCC = even sites of a cubic grid of step h
    nx = int(math.floor((Lx - 2 * margin) / h)) + 1
    ny = int(math.floor((Ly - 2 * margin) / h)) + 1
    if Lx < 2 * margin or Ly < 2 * margin:
        raise ConfigError(f"box base {Lx} × {Ly} m is too small for grains of radius {r_max}")
    sites = []
    k = 0
    while len(sites) < n:
        for j in range(ny):
            for i in range(nx):
                if (i + j + k) % 2 == 0:
                    sites.append((margin + i * h, margin + j * h, margin + k * h))
        k += 1
        if k > 10 * n + 10:  # nx = ny = 1 gives one site per two layers; never loop forever
            raise ConfigError("could not place the grains on a lattice")
    sites = np.asarray(sites[:n])
    rng = np.random.default_rng(seed)
    sites = sites + rng.uniform(-0.5, 0.5, sites.shape) * _GAP * r_max
    order = rng.permutation(n)
    return sites[order]


class SettledBed(NamedTuple):
    """A bed at rest. ``r``, ``v``, ``w``: ``(N, 3)``; ``q``: ``(N, 4)``; box-frame positions
    (floor at ``z = 0``). ``height`` [m] top of the highest grain above the floor;
    ``time`` [s] simulated settling time; ``max_speed`` [m/s] at the end."""

    r: np.ndarray
    v: np.ndarray
    w: np.ndarray
    q: np.ndarray
    height: float
    time: float
    max_speed: float


def settle(config: Config, model: Model, params: Params, progress=None) -> SettledBed:
    """Drop the grains from the lattice into the (lid-less) box and let them come to rest."""
    radii = np.asarray(params.radius)
    n = model.n
    if n == 0:
        empty = np.zeros((0, 3))
        return SettledBed(empty, empty, empty, np.zeros((0, 4)), 0.0, 0.0, 0.0)
    r0 = fcc_lattice(radii, config.box.Lx, config.box.Ly, config.numerics.seed)
    top = float((r0[:, 2] + radii).max())
    settle_model = dataclasses.replace(model, system="driven")
    p = dataclasses.replace(
        params,
        Lz=jnp.asarray(top + 4 * radii.max()),  # lid out of reach: the bed does not depend on Lz
        amplitude=jnp.asarray(0.0),
        z_offset=jnp.asarray(0.0),
        drag=jnp.asarray(config.numerics.settle_drag),
        t_window=jnp.asarray(np.inf),
    )
    batch = lambda x: jnp.asarray(x)[None]  # noqa: E731
    q0 = np.zeros((n, 4))
    q0[:, 0] = 1.0
    pb = jax_tree_batch(p)
    states = init_states(
        settle_model, pb, batch(r0), batch(np.zeros((n, 3))), batch(np.zeros((n, 3))),
        batch(q0), jnp.zeros(1), jnp.zeros(1),
    )
    nbrs = nb.allocate(settle_model, states.r, config.numerics.capacity_multiplier,
                       radius=pb.radius)
    dt = float(params.dt)
    record_every = max(1, int(round(0.005 / dt)))
    n_rec = 4
    t = 0.0
    max_speed = math.inf
    while t < config.numerics.settle_time:
        states, nbrs, _ = advance(
            settle_model, states, nbrs, pb, n_rec, record_every,
            config.numerics.capacity_multiplier, engine=config.numerics.engine,
        )
        t = float(states.t[0])
        max_speed = float(jnp.sqrt(jnp.max(jnp.sum(states.v[0] ** 2, axis=-1))))
        if progress is not None:
            progress(t, max_speed)
        if not math.isfinite(max_speed):
            raise FloatingPointError(f"settling diverged at t = {t:.4g} s (check numerics.dt)")
        if max_speed < config.numerics.settle_speed:
            break
    r = np.asarray(states.r[0])
    height = float((r[:, 2] + radii).max())
    return SettledBed(
        r=r, v=np.asarray(states.v[0]), w=np.asarray(states.w[0]), q=np.asarray(states.q[0]),
        height=height, time=t, max_speed=max_speed,
    )


def jax_tree_batch(tree):
    """Add a leading batch axis of size 1 to every leaf."""
    return jax.tree_util.tree_map(lambda x: jnp.asarray(x)[None], tree)
