"""Initial packing: grains on an FCC lattice (seeded jitter) or poured at random places
(``numerics.pour``), then settled under gravity.

Settling pours the grains into the box with its lid lifted out of the way (as a damper is
filled before it is closed), with the box at rest at its starting height and a viscous drag
on the grains that speeds up the settling. It stops once every grain is slower than
``numerics.settle_speed`` (or after ``numerics.settle_time``). Only the bed's geometry matters
here, so one settled bed serves every ``Lz`` above its height and every frequency. A damper
of several cells (``Config.cells``) is poured cell by cell, each cell's lattice the one-cell
pour at its own corner (:func:`poured`), and settles as one system.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxdamp.config import Config, ConfigError
from jaxdamp.engine import driver
from jaxdamp.physics.containers import container
from jaxdamp.physics.model import Model, Params

#: Lattice spacing is (1 + _GAP) grain diameters; jitter is ± _GAP/2 radii per coordinate.
_GAP = 0.05


def fcc_lattice(radii: np.ndarray, config: Config, seed: int) -> np.ndarray:
    """Box-frame positions ``(N, 3)`` [m] on an FCC lattice filling the container's section
    from the floor up (:mod:`jaxdamp.physics.containers`: its ``extent`` and ``inside``).

    Sites are taken layer by layer; radii are assigned to sites in a seeded random order (a
    mixture starts mixed) and each site is jittered by up to ``±_GAP/2`` of the largest radius.
    """
    n = len(radii)
    if n == 0:
        return np.zeros((0, 3))
    vessel = container(config)
    r_max = float(radii.max())
    margin = r_max * (1.0 + _GAP)
    h = 2.0 * r_max * (1.0 + _GAP) / math.sqrt(2.0)  # FCC = even sites of a cubic grid of step h
    x0, x1, y0, y1 = vessel.extent(config)
    nx = int(math.floor((x1 - x0 - 2 * margin) / h)) + 1
    ny = int(math.floor((y1 - y0 - 2 * margin) / h)) + 1
    gx = x0 + margin + h * np.arange(max(nx, 0))
    gy = y0 + margin + h * np.arange(max(ny, 0))
    ok = vessel.inside(gx[None, :], gy[:, None], margin - 1e-12 * r_max, config)  # (ny, nx)
    if x1 - x0 < 2 * margin or y1 - y0 < 2 * margin or not ok.any():
        raise ConfigError(f"{vessel.describe(config)} is too small for grains of radius "
                          f"{r_max}")
    sites = []
    k = 0
    while len(sites) < n:
        for j in range(ny):
            for i in range(nx):
                if (i + j + k) % 2 == 0 and ok[j, i]:
                    sites.append((x0 + margin + i * h, y0 + margin + j * h, margin + k * h))
        k += 1
        if k > 10 * n + 10:  # nx = ny = 1 gives one site per two layers; never loop forever
            raise ConfigError("could not place the grains on a lattice")
    sites = np.asarray(sites[:n])
    rng = np.random.default_rng(seed)
    sites = sites + rng.uniform(-0.5, 0.5, sites.shape) * _GAP * r_max
    order = rng.permutation(n)
    return sites[order]


#: The solid fraction of the loose column a random pour starts from: below the jamming limit of
#: random sequential addition of equal spheres (0.38, Torquato, Uche & Stillinger, Phys. Rev. E
#: 74:061308, 2006), so that a free site is found in a few draws.
LOOSE = 0.25

#: Settling runs in chunks of this nominal simulated time [s] (:func:`settle_many`), each of
#: :data:`SETTLE_RECORDS` samples of ``round(SETTLE_PIECE / SETTLE_RECORDS / dt)`` steps: the
#: beds' speeds are looked at after every chunk.
SETTLE_PIECE = 0.02
SETTLE_RECORDS = 4


def random_column(radii: np.ndarray, config: Config, seed: int) -> np.ndarray:
    """Box-frame positions ``(N, 3)`` [m] of non-overlapping grains at uniformly random places
    in a column of the container's section (random sequential addition, the largest grains
    first), the column ``V_grains / (LOOSE · A)`` high: a random pour, without the order a
    lattice leaves in the settled bed (``experiments/cylinder_packing.py``).

    Each grain is drawn uniformly in the section's bounding rectangle and the column's height
    until it lies inside the walls and clear of every grain placed before it (a grid of cells
    of the largest diameter finds its neighbours)."""
    n = len(radii)
    if n == 0:
        return np.zeros((0, 3))
    vessel = container(config)
    r_max = float(radii.max())
    x0, x1, y0, y1 = vessel.extent(config)
    area = vessel.base_area(config)
    height = float((4.0 / 3.0 * math.pi * radii**3).sum()) / (LOOSE * area) + 2.0 * r_max
    rng = np.random.default_rng(seed)
    cell = 2.0 * r_max
    grid: dict[tuple[int, int, int], list[int]] = {}
    out = np.empty((n, 3))
    order = np.argsort(-radii, kind="stable")
    for i in order:
        a = float(radii[i])
        for _ in range(100_000):
            p = rng.uniform((x0, y0, a), (x1, y1, a + height))
            if not vessel.inside(p[:1], p[1:2], a, config)[0]:
                continue
            c = tuple(int(v) for v in np.floor(p / cell))
            near = [j for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)
                    for j in grid.get((c[0] + dx, c[1] + dy, c[2] + dz), ())]
            if near:
                d2 = ((out[near] - p) ** 2).sum(axis=1)
                if (d2 < (radii[near] + a) ** 2).any():
                    continue
            out[i] = p
            grid.setdefault(c, []).append(int(i))
            break
        else:
            raise ConfigError("could not pour the grains at random: no free place found")
    return out


#: The pours by name (``numerics.pour``): ``(radii, config, seed) -> positions (N, 3)`` in the
#: box frame.
POURS = {"lattice": fcc_lattice, "random": random_column}


def poured(params: Params, model: Model, config: Config, seed: int) -> np.ndarray:
    """Box-frame positions ``(N, 3)`` [m] of every cell's grains before they settle
    (``Model.cells``): the one-cell pour of ``numerics.pour`` (:data:`POURS`, the same seed) of
    each cell's grains, shifted to its cell's corner ``Params.origin``; one cell: the pour
    itself."""
    radii = np.asarray(params.radius)
    pour = POURS[config.numerics.pour]
    if model.cells == 1:
        return pour(radii, config, seed)
    cell = model.cell_index()
    origin = np.asarray(params.origin)
    out = np.empty((len(radii), 3))
    for c in range(model.cells):
        sel = cell == c
        r = pour(radii[sel], config, seed)
        r[:, :2] += origin[sel]
        out[sel] = r
    return out


class SettledBed(NamedTuple):
    """A bed at rest. ``r``, ``v``, ``w``: ``(N, 3)``; ``q``: ``(N, 4)``; box-frame positions
    (floor at ``z = 0``). ``height`` [m] top of the highest grain above the floor;
    ``time`` [s] simulated settling time; ``max_speed`` [m/s] at the end; ``settled``: every
    grain came below ``numerics.settle_speed`` (false: ``numerics.settle_time`` ran out first,
    the bed was still moving — or ``settle_time = 0``, the lattice itself)."""

    r: np.ndarray
    v: np.ndarray
    w: np.ndarray
    q: np.ndarray
    height: float
    time: float
    max_speed: float
    settled: bool = True

    def unsettled_note(self, config: Config) -> str:
        """``""`` for a settled bed, else one sentence saying that (and what to change)."""
        if self.settled:
            return ""
        if self.time == 0.0:
            return ("numerics.settle_time = 0: the grains start on their lattice, NOT a settled "
                    "bed")
        return (f"the bed did NOT settle: after numerics.settle_time = "
                f"{config.numerics.settle_time:g} s its fastest grain still moves at "
                f"{self.max_speed:.3g} m/s > numerics.settle_speed = "
                f"{config.numerics.settle_speed:g} m/s (raise numerics.settle_time)")


def settle(config: Config, model: Model, params: Params, progress=None) -> SettledBed:
    """Drop the grains from where they were poured (``numerics.pour``) into the (lid-less) box
    and let them come to rest (``progress`` as in :func:`settle_many`)."""
    return settle_many([config], model, [params], progress)[0]


def settle_many(configs: list[Config], model: Model, params: list[Params],
                progress=None) -> list[SettledBed]:
    """Settle several beds of one model (e.g. independently seeded replicates) as one batch.

    Each bed is taken at the end of the first 20 ms chunk (:data:`SETTLE_PIECE`: 4 samples of
    ``round(5 ms / dt)`` steps) after which all its grains are slower than
    ``numerics.settle_speed`` (or once its chunks reach ``numerics.settle_time``, counted in
    chunks of a nominal 20 ms each: 0.02 s is one chunk, 0.03 s two), exactly as if it had
    settled alone; the batch runs until the last one is done. ``progress``: a string, the
    description of a tqdm bar over the simulated settling time (up to ``settle_time``, the
    largest speed of the beds still settling as its postfix; the same bars as the runs',
    :func:`jaxdamp.engine.driver.run_chunks`), or a callable ``progress(t, max_speed)`` called
    after every chunk, or ``None``."""
    n = model.n
    if n == 0:
        empty = np.zeros((0, 3))
        return [SettledBed(empty, empty, empty, np.zeros((0, 4)), 0.0, 0.0, 0.0)
                for _ in configs]
    radii = np.asarray(params[0].radius)
    settle_model = dataclasses.replace(model, system="driven")
    r0, ps = [], []
    for config, prm in zip(configs, params):
        r = poured(prm, model, config, config.numerics.seed)
        top = float((r[:, 2] + np.asarray(prm.radius)).max())
        r0.append(r)
        ps.append(dataclasses.replace(
            prm,
            Lz=jnp.asarray(top + 4 * radii.max()),  # lid out of reach: the bed ignores Lz
            amplitude=jnp.asarray(0.0),
            z_offset=jnp.asarray(0.0),
            drag=jnp.asarray(config.numerics.settle_drag),
            t_window=jnp.asarray(np.inf),
        ))
    B = len(configs)
    q0 = np.zeros((B, n, 4))
    q0[..., 0] = 1.0
    zeros = np.zeros((B, n, 3))
    num = configs[0].numerics
    batch = driver.start(settle_model, driver.stack(ps), np.stack(r0), zeros, zeros, q0,
                         np.zeros(B), np.zeros(B), engine=num.engine,
                         multiplier=num.capacity_multiplier)
    dt = float(params[0].dt)
    record_every = max(1, int(round(SETTLE_PIECE / SETTLE_RECORDS / dt)))
    limit = np.array([c.numerics.settle_time for c in configs])
    threshold = np.array([c.numerics.settle_speed for c in configs])
    done: list[SettledBed | None] = [None] * B
    for b in range(B):  # settle_time = 0: the lattice itself
        if limit[b] <= 0:
            rb = np.asarray(params[b].radius)
            done[b] = SettledBed(r=r0[b], v=zeros[b], w=zeros[b], q=q0[b],
                                 height=float((r0[b][:, 2] + rb).max()), time=0.0,
                                 max_speed=math.inf, settled=False)
    bar = None
    if isinstance(progress, str):
        from tqdm.auto import tqdm

        bar = tqdm(total=float(limit.max()), unit="s", desc=progress, leave=True,
                   bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.3f}/{total:.3f} s "
                              "simulated [{elapsed}<{remaining}{postfix}]")

        def progress(t, vmax):
            bar.update(min(t, bar.total) - bar.n)
            bar.set_postfix(v_max=f"{vmax:.3g} m/s", target=f"{threshold.min():g}")
    try:
        return _settle_loop(batch, done, params, record_every, limit, threshold, progress)
    finally:
        if bar is not None:
            bar.close()


def _settle_loop(batch, done, params, record_every, limit, threshold, progress):
    B = len(done)
    pieces = 0
    while any(d is None for d in done):
        try:
            batch, _ = driver.advance(batch, SETTLE_RECORDS, record_every)
        except driver.SimulationDiverged as e:
            raise driver.SimulationDiverged(f"settling: {e}") from None
        st = batch.states
        t = np.asarray(st.t)
        v = np.asarray(st.v)
        speed = np.sqrt((v**2).sum(axis=-1).max(axis=-1))
        r = np.asarray(st.r)
        pieces += 1
        # the limit in nominal chunks: a chunk's steps, round(5 ms / dt) per sample, may end a
        # little short of 20 ms (0.019997 s for the thesis bed), which must not cost a second
        # chunk at settle_time = 0.02 s
        reached = pieces * SETTLE_PIECE >= limit * (1.0 - 1e-9)
        for b in range(B):
            if done[b] is None and (speed[b] < threshold[b] or reached[b]):
                rb = np.asarray(params[b].radius)
                done[b] = SettledBed(r=r[b], v=v[b], w=np.asarray(st.w)[b],
                                     q=np.asarray(st.q)[b],
                                     height=float((r[b, :, 2] + rb).max()), time=float(t[b]),
                                     max_speed=float(speed[b]),
                                     settled=bool(speed[b] < threshold[b]))
        if progress is not None:
            left = [speed[b] for b in range(B) if done[b] is None]
            progress(float(t[0]), float(max(left)) if left else float(speed.max()))
    return done
