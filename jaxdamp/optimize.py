"""Gradient-based optimisation of the box height ``Lz`` (S1, DEM) or the gap (S3) with optax.

Objectives (functions of a configuration and the design variable; :data:`OBJECTIVES`):

* ``dissipation`` — granular dissipation per drive period [J] at one frequency (default: the
  primary's ``f0 = sqrt(K/M)/2π``); maximised.
* ``amplitude`` — steady-state amplitude ``Z`` [m] of the primary at one frequency; minimised.
  Differentiable surrogates: S3 the first-harmonic amplitude of ``z`` over the analysis window
  (least-squares ``cos``/``sin``/constant fit); DEM ``sqrt(2 <(z - z_s)²>)`` over the ensemble
  of windows (``z_s = -m_p g/K`` the static position; equal to ``Z`` for a harmonic ``z`` when
  the windows' phases cover the period evenly, which the stratified start times ensure).
* ``band`` — a smooth maximum of ``Z`` over a band of frequencies: the p-norm
  ``(Σ_f Z_f^p)^(1/p)`` (``p = 16``: between ``max Z`` and ``F^(1/p) max Z``); minimised.

S3 (:class:`S3Problem`): the smooth penalty model of :mod:`jaxdamp.impact` with the gap
``gap = Lz - h_bed`` as design variable; one long run per frequency (``vmap``), exact reverse-mode
gradients (``jax.grad`` through the whole scan; it is short and the model is smooth).

DEM (:class:`DEMProblem`): the long-trajectory derivative of a chaotic bed explodes (SPEC §6),
so the gradient is estimated **pathwise over an ensemble of short windows**: a forward run
(native engine) at the current ``Lz`` reaches a steady state (``burn_in``) and provides
``n_windows`` start states spaced by ``(1 + 1/K)`` drive periods (start phases stratified over
the period); from each, ``window`` seconds are simulated with the differentiable JAX engine
(``chunk_fn(..., remat=True, engine="jax")``, ``jax.checkpoint`` per block of
``record_every`` steps) and the window's objective is differentiated w.r.t. ``Lz`` — all windows
as one ``vmap``-ed batch. Reported: the ensemble mean of objective and derivative with their
standard errors (``std/sqrt(K)``). The derivative is that of the *truncated* objective (the
start states are held fixed): it sees how the lid changes the next ``window`` seconds, not how
the steady state itself moves with ``Lz`` (a bias that the experiment measures).
``mode="forward"`` (default; ``jax.jvp``, one tangent for the one parameter) or
``"reverse"`` (``jax.grad`` with rematerialisation); both give the same numbers — see
``experiments/gap_optimisation/summary.md`` for their measured time and memory.

**The estimator that works for the DEM** (:class:`SteadyProblem`, the default of
:func:`make_problem` and ``jaxdamp optimize``): the designer's objective is a steady-state
average, which the bed reaches only after it has forgotten its start — tens of periods, far
beyond the ~8 ms over which pathwise derivatives stay finite. So the derivative is taken by
central differences ``Lz ± h`` of steady-state runs with common random numbers (the pair starts
from the same settled bed and differs only in the lid), both members and all frequencies as one
batch, with standard errors from batch means. Exact ``jax.grad`` stays the tool for the smooth
S3 model; the pathwise window estimator stays available (``estimator="windows"``) and the
experiment shows why it fails on the DEM.

Moving ``Lz`` moves the lid: the start states at a new ``Lz`` come from a forward run at that
``Lz``, warm-started from the previous iterate's last state if every grain fits under the new lid
(else from the settled bed); :func:`check_states` refuses states with grains above the lid.

The optimiser (:func:`optimize`): optax Adam with an exponentially decaying learning rate,
projection onto ``[lo, hi]`` (``lo`` = bed height + margin), stopping rules (gradient not
significant against its standard error, small steps, maximum iterations), a tqdm progress bar
and an HDF5 log of every iterate (schema in ``docs/output.md``).
"""

from __future__ import annotations

import dataclasses
import json
import math
import time
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from . import __version__
from .config import Config, ConfigError, apply_overrides
from .model import primary_frequency

OBJECTIVES = ("dissipation", "amplitude", "band")
#: Objectives that are maximised (the others are minimised).
MAXIMISE = ("dissipation",)
#: Exponent of the p-norm smooth maximum of the band objective.
BAND_P = 16.0


@dataclass(frozen=True)
class Objective:
    """What to optimise. ``kind`` in :data:`OBJECTIVES`; ``frequency`` [Hz] for
    ``dissipation``/``amplitude`` (``None``: the primary's ``f0``); ``band`` [Hz] the
    frequencies of the ``band`` objective (``None``: 9 points over ``f0 ± 10 %``);
    ``p`` the exponent of its smooth maximum."""

    kind: str = "dissipation"
    frequency: float | None = None
    band: tuple | None = None
    p: float = BAND_P

    def __post_init__(self):
        if self.kind not in OBJECTIVES:
            raise ConfigError(f"objective {self.kind!r}: expected one of {OBJECTIVES}")

    @property
    def maximise(self) -> bool:
        return self.kind in MAXIMISE

    def frequencies(self, config: Config) -> tuple:
        f0 = primary_frequency(config) or config.frequency
        if self.kind == "band":
            if self.band:
                return tuple(float(f) for f in self.band)
            return tuple(float(f) for f in np.linspace(0.9 * f0, 1.1 * f0, 9))
        return (float(self.frequency or f0),)

    def to_json(self, config: Config) -> str:
        return json.dumps({"kind": self.kind, "frequencies": list(self.frequencies(config)),
                           "p": self.p, "maximise": self.maximise})


def smooth_max(z, p=BAND_P):
    """``(Σ z^p)^(1/p)`` of positive ``z`` (computed in a scaled form, no overflow)."""
    z = jnp.asarray(z)
    s = jax.lax.stop_gradient(jnp.max(z))
    return s * jnp.sum((z / s) ** p) ** (1.0 / p)


@dataclass
class Estimate:
    """One evaluation: objective ``value`` and derivative ``grad`` w.r.t. the design variable
    (``Lz`` or gap, [m]) with standard errors (0 for exact S3 values); ``sim_seconds``: simulated
    system-seconds this evaluation cost (forward; gradient passes counted once); ``wall`` [s];
    ``extra``: per-window values etc."""

    value: float
    value_se: float
    grad: float
    grad_se: float
    sim_seconds: float
    wall: float
    extra: dict = field(default_factory=dict)


def _first_harmonic_amplitude(t, z, omega, weights):
    """Least-squares amplitude of ``z ≈ a cos Ωt + b sin Ωt + c`` over the weighted samples."""
    A = jnp.stack([jnp.cos(omega * t), jnp.sin(omega * t), jnp.ones_like(t)], axis=1)
    Aw = A * weights[:, None]
    coef = jnp.linalg.solve(Aw.T @ A, Aw.T @ z)
    return jnp.sqrt(coef[0] ** 2 + coef[1] ** 2)


# ---------------------------------------------------------------------------------------------
# S3: the smooth single-particle model, gap as design variable


class S3Problem:
    """Objectives of the smooth S3 model (:mod:`jaxdamp.impact`) as functions of the gap.

    ``config``: an S3 configuration (``system = "impact"``; ``impactor.method`` is ignored, the
    smooth model is used). ``duration`` [s] of each run (default ``numerics.duration``);
    the analysis window is its final ``numerics.analysis_window``. ``h_bed`` [m] converts the
    gap to a box height, ``Lz = gap + h_bed`` (default ``box.Lz - impactor.gap``: 0.039 m for
    the thesis' case).
    """

    variable = "gap"

    def __init__(self, config: Config, objective: Objective, duration: float | None = None,
                 h_bed: float | None = None):
        from . import impact

        if config.system != "impact":
            raise ConfigError("S3Problem needs an S3 configuration (system = 'impact')")
        if duration is not None:
            config = apply_overrides(config, {"numerics.duration": duration})
        config = apply_overrides(config, {"impactor.method": "smooth"})
        self.config = config
        self.objective = objective
        self.h_bed = float(config.box.Lz - config.impactor.gap) if h_bed is None else h_bed
        self.freqs = objective.frequencies(config)
        self.dt, self.record_every, self.n_rec = impact.smooth_schedule([config])
        self.duration = self.n_rec * self.record_every * self.dt
        p = impact.smooth_params(config, self.dt, self.duration)
        self.params = jax.tree_util.tree_map(
            lambda x: jnp.full((len(self.freqs),), x), p)
        self.params = dataclasses.replace(
            self.params, omega=jnp.asarray([2 * math.pi * f for f in self.freqs]))
        self._value = jax.jit(self._objective)
        self._value_and_grad = jax.jit(jax.value_and_grad(self._objective))
        self._scan = jax.jit(jax.vmap(self._objective))

    def _per_frequency(self, p):
        from . import impact

        kind = self.objective.kind
        if kind == "dissipation":
            return impact.smooth_window_loss(p, self.n_rec, self.record_every)
        _, rec = impact.smooth_run(p, self.n_rec, self.record_every)
        w = (rec["t"] >= p.t_window).astype(rec["t"].dtype)
        return _first_harmonic_amplitude(rec["t"], rec["z_box"], p.omega, w)

    def _objective(self, gap):
        p = dataclasses.replace(self.params, gap=jnp.full_like(self.params.gap, gap))
        vals = jax.vmap(self._per_frequency)(p)
        if self.objective.kind == "band":
            return smooth_max(vals, self.objective.p)
        return vals[0]

    def value(self, gap: float) -> float:
        return float(self._value(jnp.asarray(float(gap))))

    def per_frequency(self, gap: float) -> np.ndarray:
        """The objective's per-frequency values (``Z_f`` for the band) at one gap."""
        p = dataclasses.replace(self.params, gap=jnp.full_like(self.params.gap, float(gap)))
        return np.asarray(jax.jit(jax.vmap(self._per_frequency))(p))

    def scan(self, gaps) -> np.ndarray:
        """Objective at every gap of ``gaps`` (one ``vmap`` batch)."""
        return np.asarray(self._scan(jnp.asarray(np.asarray(gaps, float))))

    def evaluate(self, gap: float, state=None):
        """``(Estimate, state)``: exact value and derivative (standard errors 0)."""
        t0 = time.perf_counter()
        v, g = self._value_and_grad(jnp.asarray(float(gap)))
        est = Estimate(float(v), 0.0, float(g), 0.0, self.duration * len(self.freqs),
                       time.perf_counter() - t0)
        return est, state

    def bounds(self, margin: float | None = None, hi: float | None = None):
        """Feasible gaps: above ``margin`` (default 5 mm), below ``hi`` (default 0.3 m)."""
        return (0.005 if margin is None else margin), (0.3 if hi is None else hi)

    def to_lz(self, gap):
        return gap + self.h_bed

    def from_lz(self, lz):
        return lz - self.h_bed

    def describe(self) -> dict:
        return {"model": "S3 smooth", "duration": self.duration, "dt": self.dt,
                "h_bed": self.h_bed, "frequencies": list(self.freqs)}


# ---------------------------------------------------------------------------------------------
# DEM: ensemble of short windows from steady states


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
        from .model import build
        from .packing import settle
        from .validation import validate

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
        self.z_static = -self.m_grains * self.config.gravity / self.config.primary.K
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
        from . import driver

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
        from . import driver
        from .runner import initial_box_position

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
            z0 = initial_box_position(self.config, self.m_grains)
            r0 = np.broadcast_to(self.bed.r + np.array([0.0, 0.0, z0]), (F,) + self.bed.r.shape)
            rep = lambda a: np.broadcast_to(a, (F,) + a.shape)  # noqa: E731
            states = driver.start(self.model, params, r0, rep(self.bed.v), rep(self.bed.w),
                                  rep(self.bed.q), np.full((F,), z0), np.zeros(F),
                                  engine=self.engine).states
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
        from .driver import stack, take

        out = [self._advance(jax.tree_util.tree_map(lambda x: x[i:i + 1], states),
                             jax.tree_util.tree_map(lambda x: x[i:i + 1], params), s)
               for i, s in enumerate(seconds)]
        return stack([take(o, 0) for o in out])

    # -- window objectives ------------------------------------------------------------------

    def _window_values(self, fn, states, nbrs, params, lz_vec):
        """Per-window raw quantity: dissipation per cycle, or mean (z - z_s)² (amplitude)."""
        from .energy import granular_loss

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
            from .simulate import chunk_fn

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
        from . import driver
        from .simulate import chunk_fn

        lz = ens.lz if lz is None else lz
        key = ("values", engine, self.n_rec, self.record_every)
        if key not in self._fns:
            fn = chunk_fn(self.model, self.n_rec, self.record_every, engine=engine)
            self._fns[key] = jax.jit(
                lambda lz_vec, s, n, p: self._window_values(fn, s, n, p, lz_vec))
        batch = self._windows(ens)
        B = ens.states.t.shape[0]
        while True:
            v, ovf = self._fns[key](jnp.full((B,), float(lz)), ens.states, batch.nbrs, ens.params)
            if not bool(ovf):
                return np.asarray(v)
            batch = driver.grow(batch)

    def window_derivatives(self, ens: Ensemble, mode: str | None = None):
        """Per-window raw values and their derivatives w.r.t. ``Lz`` at ``ens.lz`` (``(F·K,)``
        each) through the JAX engine; neighbour lists re-allocated and redone on overflow."""
        from . import driver

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

    def _windows(self, ens: Ensemble):
        """The ensemble's start states as a driver batch (neighbour lists for the windows)."""
        from . import driver

        return driver.attach(self.model, ens.params, ens.states, engine="jax",
                             multiplier=self.config.numerics.capacity_multiplier, at_least=12)

    def combine(self, raw, draw):
        """Objective value, its derivative and their standard errors from per-window raw
        values ``(F·K,)`` and derivatives (delta method for the square root and the p-norm)."""
        F, K = len(self.freqs), self.n_windows
        raw = np.asarray(raw, float).reshape(F, K)
        draw = np.asarray(draw, float).reshape(F, K)
        m, dm = raw.mean(axis=1), draw.mean(axis=1)
        sm = raw.std(axis=1, ddof=1) / math.sqrt(K) if K > 1 else np.full(F, np.nan)
        sdm = draw.std(axis=1, ddof=1) / math.sqrt(K) if K > 1 else np.full(F, np.nan)
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


class SteadyProblem(DEMProblem):
    """DEM objectives of ``Lz`` from **steady states**: central differences with common random
    numbers — the estimator that works where the pathwise one cannot (module doc).

    Each evaluation runs one batch of ``2 F`` systems — ``Lz ± h`` at each of the objective's
    ``F`` frequencies — from the *same* settled bed (common random numbers: the two members of
    a pair share every initial condition and differ only in the lid's height), lets them reach
    their steady states (``burn_in``) and averages the objective over ``average`` seconds,
    split into ``blocks`` consecutive blocks. Value: the mean of the pair; derivative
    ``(J(Lz+h) - J(Lz-h)) / 2h``; standard errors from the spread over blocks (batch means).
    The runs are long enough for the bed to forget its start (tens of periods), which the
    short pathwise windows are not, so the estimate is that of the steady-state objective the
    designer wants, at the price of ``2 F (burn_in + average)`` simulated seconds per iterate
    and a bias ``O(h²)`` from the differences.

    Args (beyond :class:`DEMProblem`'s ``config``, ``objective``, ``engine``, ``margin``):
      h: half-step of the central difference [m].
      burn_in: time from the settled bed to the steady state [s].
      average: averaging time [s] after the burn-in.
      blocks: number of blocks for the standard errors.
      samples_per_period: records per drive period (amplitude objective).
    """

    def __init__(self, config: Config, objective: Objective, h: float = 0.005,
                 burn_in: float = 1.0, average: float = 1.5, blocks: int = 5,
                 samples_per_period: int = 40, engine: str = "auto", margin: float = 0.005,
                 progress: bool = False):
        super().__init__(config, objective, burn_in=burn_in, engine=engine, margin=margin,
                         progress=progress)
        if not (h > 0 and average > 0 and blocks >= 2):
            raise ConfigError(f"SteadyProblem: need h > 0 (got {h}), average > 0 (got {average}) "
                              f"and blocks ≥ 2 (got {blocks})")
        self.h, self.average, self.blocks = float(h), float(average), int(blocks)
        period = 1.0 / max(self.freqs)
        self.sample_every = max(1, int(round(period / samples_per_period / self.dt)))

    def bounds(self, margin: float | None = None, hi: float | None = None):
        lo, hi_ = super().bounds(margin, hi)
        return lo + self.h, hi_ - self.h  # both members of a pair stay feasible

    def block_raw(self, lzs) -> np.ndarray:
        """Per-block raw quantity ``(F, len(lzs), blocks)`` of steady-state runs from the settled
        bed at every ``Lz`` of ``lzs`` and every frequency, as one batch: dissipation per cycle
        [J], or the mean of ``(z - z_s)²`` [m²] (amplitude objectives)."""
        from . import driver
        from .energy import granular_loss
        from .runner import initial_box_position

        F, L = len(self.freqs), len(lzs)
        ps = [dataclasses.replace(self.params, Lz=jnp.asarray(float(lz)),
                                  omega=jnp.asarray(2 * math.pi * f))
              for f in self.freqs for lz in lzs]
        params = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *ps)
        B = F * L
        z0 = initial_box_position(self.config, self.m_grains)
        rep = lambda a: np.broadcast_to(a, (B,) + a.shape)  # noqa: E731
        batch = driver.start(self.model, params, rep(self.bed.r + np.array([0.0, 0.0, z0])),
                             rep(self.bed.v), rep(self.bed.w), rep(self.bed.q),
                             np.full((B,), z0), np.zeros(B), engine=self.engine,
                             multiplier=self.config.numerics.capacity_multiplier)
        batch = driver.run_for(batch, self.burn_in, pieces=max(1, int(self.burn_in / 0.05)))
        n_samples = max(self.blocks, int(round(self.average / (self.sample_every * self.dt))))
        n_samples -= n_samples % self.blocks
        per_call = max(1, int(round(0.05 / (self.sample_every * self.dt))))
        loss0 = np.asarray(granular_loss(batch.states.work))
        zs, losses, done = [], [], 0
        while done < n_samples:
            k = min(per_call, n_samples - done)
            batch, rec = driver.advance(batch, k, self.sample_every)
            zs.append(rec["z_box"])
            losses.append(granular_loss(rec["work"]))
            done += k
        z = np.concatenate(zs, axis=1).reshape(F, L, self.blocks, -1)
        loss = np.concatenate(losses, axis=1).reshape(F, L, self.blocks, -1)
        if not (np.all(np.isfinite(z)) and np.all(np.isfinite(loss))):
            raise FloatingPointError("steady-state run went non-finite (try a smaller numerics.dt)")
        if self.objective.kind == "dissipation":
            start = np.concatenate([loss0.reshape(F, L, 1), loss[:, :, :-1, -1]], axis=2)
            block_time = loss.shape[-1] * self.sample_every * self.dt
            cycles = block_time * np.asarray(self.freqs)[:, None, None]
            return (loss[..., -1] - start) / cycles
        return np.mean((z - self.z_static) ** 2, axis=-1)

    def _transform(self, raw):
        """Objective from raw per-frequency means ``(F, ...)``."""
        if self.objective.kind == "dissipation":
            return raw[0]
        Z = np.sqrt(2.0 * raw)
        if self.objective.kind == "amplitude":
            return Z[0]
        return np.sum(Z**self.objective.p, axis=0) ** (1 / self.objective.p)

    def evaluate(self, lz: float, state=None):
        """``(Estimate, None)`` at ``lz`` from the pair ``lz ± h`` (see the class doc)."""
        t0 = time.perf_counter()
        raw = self.block_raw([lz - self.h, lz + self.h])  # (F, 2, blocks)
        minus, plus = self._transform(raw[:, 0]), self._transform(raw[:, 1])  # (blocks,)
        J_m, J_p = self._transform(raw[:, 0].mean(-1)), self._transform(raw[:, 1].mean(-1))
        value, grad = 0.5 * (J_m + J_p), (J_p - J_m) / (2 * self.h)
        nb_ = self.blocks
        value_se = float(np.std(0.5 * (minus + plus), ddof=1) / math.sqrt(nb_))
        grad_se = float(np.std((plus - minus) / (2 * self.h), ddof=1) / math.sqrt(nb_))
        sim = 2 * len(self.freqs) * (self.burn_in + self.average)
        return Estimate(float(value), value_se, float(grad), grad_se, sim,
                        time.perf_counter() - t0,
                        extra={"minus": float(J_m), "plus": float(J_p)}), None

    def describe(self) -> dict:
        return {"model": "DEM", "estimator": "steady", "h": self.h, "burn_in": self.burn_in,
                "average": self.average, "blocks": self.blocks, "dt": self.dt,
                "sample_every": self.sample_every, "bed_height": self.bed.height,
                "frequencies": list(self.freqs), "settle_time": self.bed.time}


# ---------------------------------------------------------------------------------------------
# the optimiser


@dataclass
class OptimizeResult:
    """``x`` the final design variable (``Lz`` or gap) [m], ``lz`` the box height,
    ``history`` dict of arrays (one entry per iterate), ``reason`` why it stopped,
    ``sim_seconds`` simulated system-seconds in total, ``wall`` [s], ``path`` the log file."""

    x: float
    lz: float
    value: float
    history: dict
    reason: str
    sim_seconds: float
    wall: float
    path: str | None


LOG_FIELDS = {
    "x": "m", "lz": "m", "objective": "", "objective_se": "", "gradient": "1/m",
    "gradient_se": "1/m", "step": "m", "learning_rate": "m", "wall_time": "s",
    "sim_seconds": "s",
}


def optimize(problem, x0: float, lr: float = 0.01, decay: float = 0.9, max_iter: int = 30,
             b1: float = 0.7, b2: float = 0.9,
             xtol: float = 2e-4, patience: int = 3, se_factor: float = 1.0,
             lo: float | None = None, hi: float | None = None, out: str | None = None,
             progress: bool = True, config_json: str | None = None, echo=None):
    """Optimise ``problem`` (:class:`S3Problem` or :class:`DEMProblem`) from ``x0``.

    Adam (optax; moment decays ``b1``, ``b2`` shorter than the usual 0.9/0.999 because the
    gradient's scale changes by orders of magnitude between the start and the optimum, and a
    long second-moment memory then freezes the steps before the first moment has turned)
    with learning rate ``lr·decay^k`` [m]; after each
    update the iterate is projected onto ``[lo, hi]`` (default ``problem.bounds()``). Stops
    when ``max_iter`` iterates were evaluated, when the last ``patience`` steps were all below
    ``xtol`` [m], or when for ``patience`` consecutive iterates the gradient was not
    significant, ``|g| < se_factor·SE(g)`` (noisy estimators only). Objectives marked
    maximise are maximised. Writes every iterate to ``out`` (HDF5, ``docs/output.md``).
    """
    import optax

    lo_b, hi_b = problem.bounds()
    lo = lo_b if lo is None else lo
    hi = hi_b if hi is None else hi
    if not lo < hi:
        raise ConfigError(f"no feasible design: lower bound {lo:.5g} m ≥ upper bound {hi:.5g} m")
    x = float(np.clip(x0, lo, hi))
    sign = -1.0 if problem.objective.maximise else 1.0
    sched = optax.exponential_decay(lr, transition_steps=1, decay_rate=decay)
    opt = optax.adam(sched, b1=b1, b2=b2)
    opt_state = opt.init(jnp.zeros(()))
    hist = {k: [] for k in LOG_FIELDS}
    h5 = _open_log(out, problem, x0, lo, hi, dict(lr=lr, decay=decay, b1=b1, b2=b2, max_iter=max_iter,
                   xtol=xtol, patience=patience, se_factor=se_factor), config_json)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=max_iter, unit="it", desc=f"optimise {problem.variable}")
    t_start = time.perf_counter()
    state, sim_total, reason = None, 0.0, f"max_iter = {max_iter} reached"
    small_steps = noisy = 0
    try:
        for k in range(max_iter):
            est, state = problem.evaluate(x, state)
            sim_total += est.sim_seconds
            if not (np.isfinite(est.value) and np.isfinite(est.grad)):
                reason = f"non-finite objective or gradient at {problem.variable} = {x:.6g}"
                _log(h5, hist, x, problem, est, 0.0, float(sched(k)), t_start, sim_total)
                break
            updates, opt_state = opt.update(jnp.asarray(sign * est.grad), opt_state)
            x_new = float(np.clip(x + float(updates), lo, hi))
            step = x_new - x
            _log(h5, hist, x, problem, est, step, float(sched(k)), t_start, sim_total)
            if bar is not None:
                bar.update(1)
                bar.set_postfix({problem.variable: f"{x:.5f}", "obj": f"{est.value:.4g}",
                                 "grad": f"{est.grad:.3g}±{est.grad_se:.2g}"})
            if echo:
                echo(f"{k:3d} {problem.variable} = {x:.6f} m  objective = {est.value:.6g} "
                     f"± {est.value_se:.2g}  gradient = {est.grad:.5g} ± {est.grad_se:.2g}")
            small_steps = small_steps + 1 if abs(step) < xtol else 0
            noisy = noisy + 1 if abs(est.grad) <= se_factor * est.grad_se else 0
            x = x_new
            if small_steps >= patience:
                reason = f"{patience} steps below xtol = {xtol:g} m"
                break
            if noisy >= patience:
                reason = (f"gradient not significant (|g| < {se_factor:g}·SE) for {patience} "
                          "iterates")
                break
    finally:
        if bar is not None:
            bar.close()
    hist = {k: np.asarray(v) for k, v in hist.items()}
    # the result: the last iterate (x after the final update is not evaluated)
    x_final = float(hist["x"][-1]) if len(hist["x"]) else x
    res = OptimizeResult(x=x_final, lz=float(problem.to_lz(x_final)),
                         value=float(hist["objective"][-1]) if len(hist["x"]) else float("nan"),
                         history=hist, reason=reason, sim_seconds=sim_total,
                         wall=time.perf_counter() - t_start, path=out)
    if h5 is not None:
        h5.attrs["status"] = "finished"
        h5.attrs["reason"] = reason
        h5.attrs["result"] = json.dumps({"x": res.x, "lz": res.lz, "objective": res.value,
                                         "sim_seconds": res.sim_seconds, "wall_time": res.wall,
                                         "iterations": len(hist["x"])})
        h5.close()
    return res


def _open_log(out, problem, x0, lo, hi, settings, config_json):
    if out is None:
        return None
    import h5py

    h5 = h5py.File(out, "w")
    h5.attrs["format"] = "jaxdamp-optimize/1"
    h5.attrs["jaxdamp_version"] = __version__
    h5.attrs["config"] = config_json or problem.config.to_json()
    h5.attrs["objective"] = problem.objective.to_json(problem.config)
    h5.attrs["variable"] = problem.variable
    h5.attrs["problem"] = json.dumps(problem.describe())
    h5.attrs["settings"] = json.dumps(dict(settings, x0=float(x0), lo=float(lo), hi=float(hi)))
    h5.attrs["status"] = "running"
    g = h5.create_group("iterations")
    for k, unit in LOG_FIELDS.items():
        g.create_dataset(k, shape=(0,), maxshape=(None,), dtype="f8").attrs["units"] = unit
    return h5


def _log(h5, hist, x, problem, est, step, lr, t_start, sim_total):
    row = {"x": x, "lz": float(problem.to_lz(x)), "objective": est.value,
           "objective_se": est.value_se, "gradient": est.grad, "gradient_se": est.grad_se,
           "step": step, "learning_rate": lr, "wall_time": time.perf_counter() - t_start,
           "sim_seconds": sim_total}
    for k, v in row.items():
        hist[k].append(float(v))
    if h5 is not None:
        g = h5["iterations"]
        for k, v in row.items():
            ds = g[k]
            ds.resize(ds.shape[0] + 1, axis=0)
            ds[-1] = v
        h5.flush()


def scan_optimum(xs, values, maximise: bool) -> float:
    """The optimum of a sampled objective: a parabola through the best sample and its two
    neighbours (the best sample itself at either end of the range)."""
    xs = np.asarray(xs, float)
    v = np.asarray(values, float)
    k = int(np.argmax(v) if maximise else np.argmin(v))
    if 0 < k < len(xs) - 1:
        c = np.polyfit(xs[k - 1:k + 2], v[k - 1:k + 2], 2)
        if (c[0] < 0) == maximise and c[0] != 0:
            xv = -c[1] / (2 * c[0])
            if xs[k - 1] <= xv <= xs[k + 1]:
                return float(xv)
    return float(xs[k])


# ---------------------------------------------------------------------------------------------
# one call from a configuration (the CLI's entry point)

#: Settings of ``jaxdamp optimize`` (full and ``--quick``) per model. S3: run length [s],
#: learning rate and decay, iterations; DEM: window [s], ensemble size, burn-ins [s], settling.
DEFAULTS = {
    "s3": dict(duration=3.0, analysis_window=0.5, lr=0.015, decay=0.88, max_iter=40, xtol=5e-5),
    "s3-quick": dict(duration=3.0, analysis_window=0.5, lr=0.015, decay=0.88, max_iter=25,
                     xtol=5e-5),
    "dem": dict(window=0.002, n_windows=8, burn_in=1.0, warm_burn_in=0.4, lr=0.02, decay=0.85,
                max_iter=12, xtol=5e-4, settle_time=0.3),
    "dem-quick": dict(window=0.001, n_windows=4, burn_in=0.3, warm_burn_in=0.1, lr=0.02,
                      decay=0.85, max_iter=3, xtol=5e-4, settle_time=0.3),
    "steady": dict(h=0.005, burn_in=1.0, average=1.5, blocks=5, lr=0.03, decay=0.9,
                   max_iter=12, xtol=5e-4, settle_time=0.3),
    "steady-quick": dict(h=0.005, burn_in=0.3, average=0.3, blocks=3, lr=0.03, decay=0.9,
                         max_iter=3, xtol=5e-4, settle_time=0.3),
}


def make_problem(config: Config, objective: Objective, quick: bool = False, **overrides):
    """The :class:`S3Problem` (``system = "impact"``), or for the DEM (``"primary"``) the
    :class:`SteadyProblem` (``estimator="steady"``, default) or the pathwise
    :class:`DEMProblem` (``estimator="windows"``), of ``config`` with the settings of
    :data:`DEFAULTS` (``overrides`` win; ``None`` values are ignored). Returns
    ``(problem, optimiser settings dict)``."""
    over = {k: v for k, v in overrides.items() if v is not None}
    if config.system == "impact":
        s = dict(DEFAULTS["s3-quick" if quick else "s3"], **over)
        if objective.kind == "band" and "duration" not in over:
            s["duration"] = 2.0  # longer runs: irregular response in the band, gradient explodes
        config = apply_overrides(config, {"numerics.analysis_window": s.pop("analysis_window")})
        prob = S3Problem(config, objective, duration=s.pop("duration"))
    elif config.system == "primary" and over.pop("estimator", "steady") == "steady":
        s = dict(DEFAULTS["steady-quick" if quick else "steady"],
                 **{k: v for k, v in over.items()
                    if k not in ("window", "n_windows", "mode", "duration", "warm_burn_in")})
        config = apply_overrides(config, {"numerics.settle_time": s.pop("settle_time")})
        prob = SteadyProblem(config, objective, h=s.pop("h"), burn_in=s.pop("burn_in"),
                             average=s.pop("average"), blocks=s.pop("blocks"),
                             margin=s.pop("margin", 0.005))
    elif config.system == "primary":
        s = dict(DEFAULTS["dem-quick" if quick else "dem"], **over)
        config = apply_overrides(config, {"numerics.settle_time": s.pop("settle_time")})
        prob = DEMProblem(config, objective, window=s.pop("window"),
                          n_windows=s.pop("n_windows"), burn_in=s.pop("burn_in"),
                          warm_burn_in=s.pop("warm_burn_in"), mode=s.pop("mode", "forward"),
                          margin=s.pop("margin", 0.005))
    else:
        raise ConfigError(f"optimisation needs system 'primary' (S1) or 'impact' (S3), not "
                          f"{config.system!r}")
    return prob, s
