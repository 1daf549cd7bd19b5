"""The pathwise DEM estimator: derivatives of short windows from steady start states.

Kept for the experiment that shows why it fails for steady-state objectives
(``experiments/gap_optimisation``): the long-trajectory derivative of a chaotic bed explodes
(``docs/physics.md`` §6), so the derivative is taken over an ensemble of short windows. A
forward run (native engine) at the current ``Lz`` reaches a steady state (``burn_in``) and
provides ``n_windows`` start states spaced by ``(1 + 1/K)`` drive periods; from each,
``window`` seconds are simulated with the differentiable JAX engine
(``chunk_fn(..., remat=True, engine="jax")``) and the window's objective is differentiated
w.r.t. ``Lz`` — all windows as one ``vmap``-ed batch (``mode="forward"``: ``jax.jvp``;
``"reverse"``: ``jax.grad`` with rematerialisation). The derivative is that of the
*truncated* objective (start states held fixed): it sees how the lid changes the next
``window`` seconds, not how the steady state moves with ``Lz`` — a bias the experiment
measures. The designer's estimator is :class:`jaxdamp.design.steady.SteadyProblem`.

Objectives here: ``dissipation`` (per cycle over the window), ``amplitude``
(``sqrt(2 <(z - z_s)²>)``, ``z_s = -m_p g/K``) and ``band``; ``damping`` needs both and is
not offered by this estimator.
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.config import Config, ConfigError
from jaxdamp.design.objectives import Estimate, Objective


@dataclass
class Ensemble:
    """Start states of the gradient windows at one ``Lz``: ``states`` batched ``(F·K, ...)``
    (frequency-major), the batched ``params``, the last state of every frequency's forward run
    (``last``, ``(F, ...)``, for warm starts), ``lz`` [m] and the simulated system-seconds
    spent (``sim_seconds``)."""

    lz: float
    states: object
    params: object
    last: object
    sim_seconds: float
    wall: float


def check_states(states, params, radius_max: float, margin: float = 0.0) -> None:
    """Raise ``ValueError`` unless every grain lies between floor and lid (box frame) with
    ``margin`` [m] to spare at the lid (negative: an overlap with the lid up to ``-margin``)."""
    top = np.asarray(states.r[..., 2] - states.z[..., None]) + radius_max
    lz = np.asarray(params.Lz)[..., None]
    if np.any(top > lz - margin) or np.any(np.asarray(states.r[..., 2] - states.z[..., None]) < 0):
        raise ValueError(f"states invalid for Lz = {np.unique(lz)}: highest grain top "
                         f"{top.max():.5g} m")


class DEMProblem:
    """Objectives of the DEM damper (S1) as functions of ``Lz``, estimated over short windows.

    Args:
      config: an S1 configuration (e.g. ``sanchez2012-optimal``); its grains and primary.
      objective: what to optimise (:class:`Objective`).
      window: length of each gradient window [s].
      n_windows: ensemble size ``K`` per frequency.
      burn_in: forward time before the first start state [s] (from the settled bed; warm
        starts use ``warm_burn_in``).
      warm_burn_in: forward time after a warm start (previous iterate's state) [s].
      record_every: steps per rematerialised block (and per amplitude sample) of a window.
      mode: ``"forward"`` (``jax.jvp``) or ``"reverse"`` (``jax.grad`` + ``jax.checkpoint``).
      engine: engine of the forward runs (``"auto"``: native on the CPU).
      margin: the lowest feasible ``Lz`` is the settled bed's height plus ``margin`` [m].
      progress: tqdm bars for the forward runs.
    """

    variable = "Lz"

    def __init__(self, config: Config, objective: Objective, window: float = 0.002,
                 n_windows: int = 8, burn_in: float = 1.0, warm_burn_in: float = 0.5,
                 record_every: int = 25, mode: str = "forward", engine: str = "auto",
                 margin: float = 0.005, progress: bool = False):
        from jaxdamp.engine.packing import settle
        from jaxdamp.physics.model import build
        from jaxdamp.validation import validate

        if config.system != "primary":
            raise ConfigError("DEMProblem needs an S1 configuration (system = 'primary')")
        if mode not in ("forward", "reverse"):
            raise ConfigError(f"mode {mode!r}: expected 'forward' or 'reverse'")
        self.config = validate(config)
        self.objective = objective
        self.freqs = objective.frequencies(config)
        self.model, p = build(self.config)
        self.dt = float(p.dt)
        self.params = dataclasses.replace(p, t_window=jnp.asarray(np.inf))
        self.window = float(window)
        self.n_windows = int(n_windows)
        self.burn_in = float(burn_in)
        self.warm_burn_in = float(warm_burn_in)
        self.record_every = int(record_every)
        self.n_rec = max(1, int(round(self.window / (self.dt * self.record_every))))
        self.mode = mode
        self.engine = engine
        self.margin = float(margin)
        self.progress = progress
        t0 = time.perf_counter()
        self.bed = settle(self.config, self.model, self.params)
        self.settle_wall = time.perf_counter() - t0
        self.radius_max = float(np.max(np.asarray(self.params.radius)))
        self.m_grains = float(np.sum(np.asarray(self.params.mass)))
        from jaxdamp.physics.model import excitation_axis

        self.z_static = (-self.m_grains * self.config.gravity
                         * float(excitation_axis(self.config)[2]) / self.config.primary.K)
        self._fns = {}

    # -- geometry ---------------------------------------------------------------------------

    def bounds(self, margin: float | None = None, hi: float | None = None):
        """Feasible ``Lz``: from the bed height + margin to ``hi`` (default 0.4 m)."""
        m = self.margin if margin is None else margin
        return self.bed.height + m, (0.4 if hi is None else hi)

    def _batched_params(self, lz: float, freqs):
        ps = [dataclasses.replace(self.params, Lz=jnp.asarray(float(lz)),
                                  omega=jnp.asarray(2 * math.pi * f)) for f in freqs]
        return jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *ps)

    # -- forward runs -----------------------------------------------------------------------

    def _advance(self, states, params, seconds: float, pieces: int = 1):
        """Forward ``seconds`` (whole steps) with the forward engine; returns the new states."""
        from jaxdamp.engine import driver

        batch = driver.attach(self.model, params, states, engine=self.engine,
                              multiplier=self.config.numerics.capacity_multiplier)
        return driver.run_for(batch, seconds, pieces=pieces).states

    def _fits(self, states, lz):
        top = np.asarray(states.r[..., 2] - states.z[..., None]).max(axis=-1) + self.radius_max
        return bool(np.all(top < lz - 0.25 * self.radius_max))

    def start_states(self, lz: float, warm: Ensemble | None = None) -> Ensemble:
        """Steady-state start states at ``lz``: burn in, then ``K`` states spaced by
        ``(1 + 1/K)`` periods per frequency. Warm-started from ``warm.last`` when every grain
        fits under the new lid (advanced at the old ``Lz`` by up to two periods until it does),
        else from the settled bed."""
        from jaxdamp.engine import driver
        from jaxdamp.studies.runner import bed_with_box, initial_structure

        t0 = time.perf_counter()
        F, K = len(self.freqs), self.n_windows
        params = self._batched_params(lz, self.freqs)
        sim = 0.0
        states = None
        if warm is not None:
            st = warm.last
            old = self._batched_params(warm.lz, self.freqs)
            period = 1.0 / max(self.freqs)
            for _ in range(33):
                if self._fits(st, lz):
                    states = st
                    break
                st = self._advance(st, old, period / 16)
                sim += F * period / 16
        if states is not None:
            burn = self.warm_burn_in  # the warm state continues under the new lid
        else:
            x0, xd0 = initial_structure(self.config, self.m_grains)
            r0 = np.broadcast_to(bed_with_box(self.config, self.bed.r, x0),
                                 (F,) + self.bed.r.shape)
            rep = lambda a: np.broadcast_to(a, (F,) + a.shape)  # noqa: E731
            states = driver.start(self.model, params, r0, rep(self.bed.v), rep(self.bed.w),
                                  rep(self.bed.q), rep(x0), rep(xd0), engine=self.engine).states
            burn = self.burn_in
        states = self._advance(states, params, burn, pieces=max(1, int(burn / 0.05)))
        sim += F * burn
        out = []
        for k in range(K):
            spacing = (1.0 + 1.0 / K) / np.asarray(self.freqs)
            # one spacing per frequency: advance each frequency's system by its own period
            states = self._advance_each(states, params, spacing)
            sim += float(np.sum(spacing))
            out.append(states)
        for st in out:  # grains may touch the lid (overlap ≪ R), never be above it
            check_states(st, params, self.radius_max, margin=-0.2 * self.radius_max)
        stacked = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs, axis=1), *out)  # (F, K, ...)
        flat = jax.tree_util.tree_map(lambda x: x.reshape((F * K,) + x.shape[2:]), stacked)
        pflat = jax.tree_util.tree_map(lambda x: jnp.repeat(x, K, axis=0), params)
        return Ensemble(lz=float(lz), states=flat, params=pflat, last=states, sim_seconds=sim,
                        wall=time.perf_counter() - t0)

    def _advance_each(self, states, params, seconds):
        """Advance system ``i`` of the batch by ``seconds[i]`` (equal seconds: one call)."""
        seconds = np.asarray(seconds, float)
        if np.allclose(seconds, seconds[0]):
            return self._advance(states, params, float(seconds[0]))
        from jaxdamp.engine.driver import stack, take

        out = [self._advance(jax.tree_util.tree_map(lambda x: x[i:i + 1], states),
                             jax.tree_util.tree_map(lambda x: x[i:i + 1], params), s)
               for i, s in enumerate(seconds)]
        return stack([take(o, 0) for o in out])

    # -- window objectives ------------------------------------------------------------------

    def _window_values(self, fn, states, nbrs, params, lz_vec):
        """Per-window raw quantity: dissipation per cycle, or mean (z - z_s)² (amplitude)."""
        from jaxdamp.physics.energy import granular_loss

        p = dataclasses.replace(params, Lz=lz_vec)
        out, out_nbrs, recs = fn(states, nbrs, p)
        overflow = jnp.any(out_nbrs.overflow)
        if self.objective.kind == "dissipation":
            cycles = self.n_rec * self.record_every * p.dt * p.omega / (2 * jnp.pi)
            return (granular_loss(out.work) - granular_loss(states.work)) / cycles, overflow
        return jnp.mean((recs["z_box"] - self.z_static) ** 2, axis=1), overflow

    def _derivative_fn(self, mode):
        key = (mode, self.n_rec, self.record_every)
        if key not in self._fns:
            from jaxdamp.engine.simulate import chunk_fn

            fn = chunk_fn(self.model, self.n_rec, self.record_every, remat=(mode == "reverse"),
                          engine="jax")

            def values(lz_vec, states, nbrs, params):
                return self._window_values(fn, states, nbrs, params, lz_vec)

            if mode == "reverse":
                def vg(lz_vec, states, nbrs, params):
                    v, pull, ovf = jax.vjp(lambda x: values(x, states, nbrs, params), lz_vec,
                                           has_aux=True)
                    return v, pull(jnp.ones_like(v))[0], ovf
            else:
                def vg(lz_vec, states, nbrs, params):
                    v, d, ovf = jax.jvp(lambda x: values(x, states, nbrs, params), (lz_vec,),
                                        (jnp.ones_like(lz_vec),), has_aux=True)
                    return v, d, ovf
            self._fns[key] = jax.jit(vg)
        return self._fns[key]

    def window_values(self, ens: Ensemble, lz: float | None = None, engine: str = "jax"):
        """Per-window raw values at ``lz`` (default ``ens.lz``) from the ensemble's start states
        — forward only (``engine="auto"``: native), for finite differences."""
        from jaxdamp.engine import driver
        from jaxdamp.engine.simulate import chunk_fn

        lz = ens.lz if lz is None else lz
        key = ("values", engine, self.n_rec, self.record_every)
        if key not in self._fns:
            fn = chunk_fn(self.model, self.n_rec, self.record_every, engine=engine)
            self._fns[key] = jax.jit(
                lambda lz_vec, s, n, p: self._window_values(fn, s, n, p, lz_vec))
        batch = self._windows(ens)
        B = ens.states.t.shape[0]
        while True:
            v, ovf = driver.call_chunk(self._fns[key], jnp.full((B,), float(lz)), ens.states,
                                       batch.nbrs, ens.params)
            if not bool(ovf):
                return np.asarray(v)
            batch = driver.grow(batch)

    def window_derivatives(self, ens: Ensemble, mode: str | None = None):
        """Per-window raw values and their derivatives w.r.t. ``Lz`` at ``ens.lz`` (``(F·K,)``
        each) through the JAX engine; neighbour lists re-allocated and redone on overflow."""
        from jaxdamp.engine import driver

        fn = self._derivative_fn(mode or self.mode)
        B = ens.states.t.shape[0]
        batch = self._windows(ens)
        while True:
            v, d, ovf = fn(jnp.full((B,), ens.lz), ens.states, batch.nbrs, ens.params)
            if not bool(ovf):
                break
            batch = driver.grow(batch)
        v, d = np.asarray(v), np.asarray(d)
        if not (np.all(np.isfinite(v)) and np.all(np.isfinite(d))):
            raise FloatingPointError("window objective or derivative is non-finite")
        return v, d

    def central_difference(self, ens: Ensemble, h: float, lz: float | None = None,
                           engine: str = "auto") -> np.ndarray:
        """Per-window central difference of the window values w.r.t. ``Lz`` at ``lz`` (default
        ``ens.lz``) from the ensemble's start states,
        ``(v(Lz + h) − v(Lz − h)) / 2h`` (truncation error ``O(h²)``, round-off
        ``~ ε |v| / h``): the check of :meth:`window_derivatives`, which differentiates the same
        truncated objective (start states held fixed). ``engine="auto"``: native forward runs.

        Example::

            ens = prob.start_states(0.12)
            v, d = prob.window_derivatives(ens)
            prob.central_difference(ens, 1e-8)  # ≈ d in short windows
        """
        lz = ens.lz if lz is None else lz
        return (self.window_values(ens, lz + h, engine=engine)
                - self.window_values(ens, lz - h, engine=engine)) / (2 * h)

    def derivative_cost(self, ens: Ensemble, mode: str | None = None) -> dict:
        """The cost of one call of the window derivatives in ``mode`` (default ``self.mode``):
        ``wall`` [s] of a compiled call (the second; the first compiles) and ``temp_bytes``,
        the compiled program's temporary memory (XLA's ``memory_analysis``; NaN where the
        backend reports none). Forward mode's memory does not grow with the window, reverse
        mode's does (a checkpoint every ``record_every`` steps). The neighbour lists as first
        allocated (no retry on overflow: a measurement, not a value).

        Example::

            ens = prob.start_states(0.12)
            prob.derivative_cost(ens, "forward")  # {'wall': 0.6, 'temp_bytes': 8e5}
        """
        fn = self._derivative_fn(mode or self.mode)
        B = ens.states.t.shape[0]
        args = (jnp.full((B,), ens.lz), ens.states, self._windows(ens).nbrs, ens.params)
        mem = fn.lower(*args).compile().memory_analysis()
        jax.block_until_ready(fn(*args))
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        return dict(wall=time.perf_counter() - t0,
                    temp_bytes=float(getattr(mem, "temp_size_in_bytes", np.nan)))

    def _windows(self, ens: Ensemble):
        """The ensemble's start states as a driver batch (neighbour lists for the windows)."""
        from jaxdamp.engine import driver

        return driver.attach(self.model, ens.params, ens.states, engine="jax",
                             multiplier=self.config.numerics.capacity_multiplier, at_least=12)

    def combine(self, raw, draw):
        """Objective value, its derivative and their standard errors from per-window raw
        values ``(F·K,)`` and derivatives (delta method for the square root and the p-norm)."""
        F, K = len(self.freqs), self.n_windows
        raw = np.asarray(raw, float).reshape(F, K)
        draw = np.asarray(draw, float).reshape(F, K)
        m, dm = raw.mean(axis=1), draw.mean(axis=1)
        sm = standard_error(raw, axis=1) if K > 1 else np.full(F, np.nan)
        sdm = standard_error(draw, axis=1) if K > 1 else np.full(F, np.nan)
        if self.objective.kind == "dissipation":
            return float(m[0]), float(sm[0]), float(dm[0]), float(sdm[0])
        Z = np.sqrt(2.0 * m)
        dZ, sZ, sdZ = dm / Z, sm / Z, sdm / Z
        if self.objective.kind == "amplitude":
            return float(Z[0]), float(sZ[0]), float(dZ[0]), float(sdZ[0])
        p = self.objective.p
        S = float(np.sum(Z**p) ** (1 / p))
        w = (Z / S) ** (p - 1)  # dS/dZ_f
        return (S, float(np.sqrt(np.sum((w * sZ) ** 2))), float(np.sum(w * dZ)),
                float(np.sqrt(np.sum((w * sdZ) ** 2))))

    def evaluate(self, lz: float, state: Ensemble | None = None):
        """``(Estimate, ensemble)`` at ``lz``: start states (warm from ``state``), window
        derivatives, ensemble means and standard errors."""
        t0 = time.perf_counter()
        ens = self.start_states(lz, warm=state)
        raw, draw = self.window_derivatives(ens)
        v, sv, g, sg = self.combine(raw, draw)
        sim = ens.sim_seconds + len(raw) * self.window_seconds
        return Estimate(v, sv, g, sg, sim, time.perf_counter() - t0,
                        extra={"raw": raw, "draw": draw, "forward_sim": ens.sim_seconds}), ens

    def set_window(self, window: float) -> None:
        """Change the gradient window length [s] (whole blocks of ``record_every`` steps)."""
        self.window = float(window)
        self.n_rec = max(1, int(round(self.window / (self.dt * self.record_every))))

    @property
    def window_seconds(self) -> float:
        return self.n_rec * self.record_every * self.dt

    def to_lz(self, x):
        return x

    def from_lz(self, lz):
        return lz

    def describe(self) -> dict:
        return {"model": "DEM", "window": self.window_seconds, "n_windows": self.n_windows,
                "record_every": self.record_every, "burn_in": self.burn_in,
                "warm_burn_in": self.warm_burn_in, "mode": self.mode, "dt": self.dt,
                "bed_height": self.bed.height, "frequencies": list(self.freqs),
                "settle_time": self.bed.time}
