"""The single-particle model (S3) as a design problem: the gap as design variable.

:class:`S3Problem` evaluates the objective on the smooth model of :mod:`jaxdamp.s3.impact`
(penalty contacts, ``jax``-differentiable) for every frequency of the objective in one
``vmap`` batch. Two derivatives:

* ``gradient="orbit"`` (default) — the exact steady-state derivative on the stable periodic
  orbit by implicit differentiation of the stroboscopic map (:mod:`jaxdamp.s3.periodic`): no
  transient, no horizon. Where the motion has no stable periodic orbit (irregular responses,
  bifurcations) it returns NaN and says why (``Estimate.extra["reason"]``): the optimiser
  then stops — or, with ``fallback=True``, takes the central difference of long averages
  (``fallback_duration`` runs, the last ``fallback_window`` seconds averaged, ``gap ± h``)
  and flags it (``extra["method"] = "fd-long-average"``): a number whose error is not known,
  good enough to step out of an irregular region towards the regular one.
* ``gradient="transient"`` — ``jax.grad`` through a whole run from rest, windowed objective;
  honest where the run has converged to a periodic orbit, meaningless where it has not (at a
  gap of 0.15 m it returned 8356 where finite differences scatter between −303 and +367).

The gap maps to a box height by ``Lz = gap + h_bed``.
"""

from __future__ import annotations

import dataclasses
import math
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.config import Config, ConfigError, apply_overrides
from jaxdamp.design.objectives import Estimate, Objective
from jaxdamp.physics.containers import container


def _first_harmonic_amplitude(t, z, omega, weights):
    """Least-squares amplitude of ``z ≈ a cos Ωt + b sin Ωt + c`` over the weighted samples."""
    A = jnp.stack([jnp.cos(omega * t), jnp.sin(omega * t), jnp.ones_like(t)], axis=1)
    Aw = A * weights[:, None]
    coef = jnp.linalg.solve(Aw.T @ A, Aw.T @ z)
    return jnp.sqrt(coef[0] ** 2 + coef[1] ** 2)


class S3Problem:
    """Objectives of the smooth S3 model as functions of the gap.

    Args:
      config: an S3 configuration (``system = "impact"``; the smooth model is used).
      objective: what to optimise.
      duration: length of each transient run [s] (default ``numerics.duration``); the
        analysis window is its final ``numerics.analysis_window``.
      h_bed: converts the gap to a box height, ``Lz = gap + h_bed`` (default
        ``box.Lz − impactor.gap``: 0.039 m for the thesis' case).
      gradient: ``"orbit"`` or ``"transient"`` (module doc).
      refine: orbit method: steps per contact time relative to the smooth model's default.
        At the default step the gap derivative oscillates with the gap (±25 % for dZ, up to
        46 % for dE at 0.095 m) while the values change by < 1e-4; ``refine = 2`` converges
        it to ~2e-3 (measured, :mod:`jaxdamp.s3.periodic`) for twice the cost.
    """

    variable = "gap"

    def __init__(self, config: Config, objective: Objective, duration: float | None = None,
                 h_bed: float | None = None, gradient: str = "orbit", refine: int = 2,
                 fallback: bool = False, h: float = 0.005, fallback_duration: float = 30.0,
                 fallback_window: float = 25.0):
        from jaxdamp.s3 import smooth

        if config.system != "impact":
            raise ConfigError("S3Problem needs an S3 configuration (system = 'impact')")
        if gradient not in ("orbit", "transient"):
            raise ConfigError(f"gradient = {gradient!r}: expected 'orbit' or 'transient'")
        if duration is not None:
            config = apply_overrides(config, {"numerics.duration": duration})
        config = apply_overrides(config, {"impactor.method": "smooth"})
        self.config = config
        self.objective = objective
        self.gradient = gradient
        self.refine = int(refine)
        self.fallback, self.h = bool(fallback), float(h)
        self._long = None
        self.fallbacks = 0  # evaluations that fell back to long averages
        self._long_settings = (float(fallback_duration), float(fallback_window))
        lid = container(config).height(config)
        self.h_bed = float(lid - config.impactor.gap) if h_bed is None else h_bed
        self.freqs = objective.frequencies(config)
        self.dt, self.record_every, self.n_rec = smooth.smooth_schedule([config])
        self.duration = self.n_rec * self.record_every * self.dt
        self.sim_seconds = 0.0
        p = smooth.smooth_params(config, self.dt, self.duration)
        self.params = jax.tree_util.tree_map(lambda x: jnp.full((len(self.freqs),), x), p)
        self.params = dataclasses.replace(
            self.params, omega=jnp.asarray([2 * math.pi * f for f in self.freqs]))
        self._value = jax.jit(self._objective)
        self._value_and_grad = jax.jit(jax.value_and_grad(self._objective))
        self._scan = jax.jit(jax.vmap(self._objective))

    def _per_frequency(self, p):
        """Amplitude ``Z`` [m] (first harmonic) and impact loss per period ``E`` [J] over the
        analysis window of one run."""
        from jaxdamp.s3 import smooth

        _, rec = smooth.smooth_run(p, self.n_rec, self.record_every)
        w = (rec["t"] >= p.t_window).astype(rec["t"].dtype)
        Z = _first_harmonic_amplitude(rec["t"], rec["z_box"], p.omega, w)
        i0 = jnp.argmax(rec["t"] >= p.t_window)
        cycles = (rec["t"][-1] - rec["t"][i0]) * p.omega / (2 * jnp.pi)
        E = (rec["work"][-1, 2] - rec["work"][i0, 2]) / cycles
        return Z, E

    def _objective(self, gap):
        p = dataclasses.replace(self.params, gap=jnp.full_like(self.params.gap, gap))
        Z, E = jax.vmap(self._per_frequency)(p)
        return self.objective.combine(Z, E, self.freqs)

    def value(self, gap: float) -> float:
        self.sim_seconds += self.duration * len(self.freqs)
        return float(self._value(jnp.asarray(float(gap))))

    def scan(self, gaps) -> np.ndarray:
        """Objective at every gap of ``gaps`` (one ``vmap`` batch)."""
        gaps = np.asarray(gaps, float)
        self.sim_seconds += self.duration * len(self.freqs) * len(gaps)
        return np.asarray(self._scan(jnp.asarray(gaps)))

    def evaluate(self, gap: float, state=None):
        """``(Estimate, state)``: value and derivative (standard errors 0; NaN with a reason
        where the orbit method finds no stable periodic orbit)."""
        t0 = time.perf_counter()
        if self.gradient == "orbit":
            from jaxdamp.s3 import periodic

            v, g, orbit = periodic.objective_and_gradient(
                self.config, self.objective, gap=float(gap), refine=self.refine,
                start=state if self._warm(state) else None)
            state = orbit
            extra = {"reason": getattr(orbit, "reason", ""), "orbit": orbit, "method": "orbit"}
            cost = getattr(orbit, "sim_seconds", 0.0)
            if self.fallback and not (np.isfinite(v) and np.isfinite(g)):
                v, g, c = self._long_difference(float(gap))
                extra.update(method="fd-long-average")
                self.fallbacks += 1
                cost += c
        else:
            v, g = self._value_and_grad(jnp.asarray(float(gap)))
            extra, cost = {}, self.duration * len(self.freqs)
        self.sim_seconds += cost
        return Estimate(float(v), 0.0, float(g), 0.0, cost, time.perf_counter() - t0,
                        extra=extra), state

    def _long_difference(self, gap: float):
        """Value and central difference ``± h`` of long averages (the fallback)."""
        if self._long is None:
            duration, window = self._long_settings
            cfg = apply_overrides(self.config, {"numerics.analysis_window": window})
            self._long = S3Problem(cfg, self.objective, duration=duration, h_bed=self.h_bed,
                                   gradient="transient")
        before = self._long.sim_seconds
        vm, v0, vp = self._long.scan([gap - self.h, gap, gap + self.h])
        return float(v0), float((vp - vm) / (2 * self.h)), self._long.sim_seconds - before

    def _warm(self, state) -> bool:
        """Warm-start Newton from the previous iterate's orbit (one frequency, stable)."""
        return state is not None and getattr(state, "stable", False) and len(self.freqs) == 1

    def bounds(self, margin: float | None = None, hi: float | None = None):
        """Feasible gaps: above ``margin`` (default 5 mm), below ``hi`` (default 0.3 m)."""
        return (0.005 if margin is None else margin), (0.3 if hi is None else hi)

    def to_lz(self, gap):
        return gap + self.h_bed

    def from_lz(self, lz):
        return lz - self.h_bed

    def describe(self) -> dict:
        return {"model": "S3 smooth", "duration": self.duration, "dt": self.dt,
                "h_bed": self.h_bed, "frequencies": list(self.freqs),
                "gradient": self.gradient, "refine": self.refine, "fallback": self.fallback}
