"""The DEM damper's objective as a function of ``Lz``, from replicated steady states.

The bed is chaotic: pathwise derivatives of a steady-state average do not exist in any useful
sense (tangents grow at 500–800 s⁻¹; ``docs/physics.md`` §6), so the DEM is evaluated by what
a designer can trust — steady-state averages over **independent replicates** (independently
seeded settled beds, :mod:`jaxdamp.analysis.stats`), all run in one batch through
:func:`jaxdamp.studies.sweep.sweep` (and so through the one driver):

* an evaluation at heights ``Lz_1..Lz_L`` and the objective's frequencies runs
  ``F × L × R`` systems for ``duration`` seconds; for every system the start of the steady state
  is detected from its per-period amplitude and dissipation (MSER), and the steady means of
  ``Z`` and ``E`` are taken over **one common window per bed** — from the latest start among
  the heights that bed runs at (:func:`jaxdamp.analysis.stats.shared_window`), so that the
  bed's shared transient cancels in differences (systems that never became stationary are
  counted in ``not_stationary``);
* the objective of every replicate is formed from its own ``Z_f, E_f``
  (:meth:`jaxdamp.design.objectives.Objective.combine`), so replicate values are independent
  and the standard error across them, ``s/√R``, is calibrated;
* the **derivative** is the central difference ``(J(Lz+h) − J(Lz−h)) / 2h`` with common random
  numbers inside each pair (both members start from the same settled bed and differ only in
  the lid) and independent pairs across replicates: its standard error is the spread of the
  ``R`` pair differences, ``s_g/√R``. Its bias is ``O(h²)`` (``J'''h²/6``).

Settled beds are cached (one per replicate seed), so repeated evaluations pay the settling once.
Every evaluation is kept (:attr:`SteadyProblem.evaluations`) for response surfaces and scans.
"""

from __future__ import annotations

import math
import time

import numpy as np

from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.config import Config, ConfigError, apply_overrides
from jaxdamp.design.objectives import Estimate, Objective


class SteadyProblem:
    """Objective of ``Lz`` for an S1 DEM damper from ``R`` replicated steady states.

    Args:
      config: an S1 configuration (``system = "primary"``), e.g. ``sanchez2012-optimal``.
      objective: what to optimise (:class:`~jaxdamp.design.objectives.Objective`).
      h: half-step of the central difference [m].
      replicates: independent beds ``R`` (≥ 2 for error bars).
      duration: simulated time per system and evaluation [s] (transient + steady part; the
        transient's end is detected).
      margin: the lowest feasible ``Lz`` is the highest settled bed plus ``margin`` [m].
      progress: progress bars of the settling and of every evaluation's sweep (tqdm, as the
        runs', :func:`jaxdamp.engine.driver.run_chunks`).
    """

    variable = "Lz"

    def __init__(self, config: Config, objective: Objective, h: float = 0.005,
                 replicates: int = 4, duration: float = 3.0, margin: float = 0.005,
                 progress: bool = False):
        from jaxdamp.engine.packing import settle_many
        from jaxdamp.physics.model import build
        from jaxdamp.studies.grid import geometry_key, replicate_configs
        from jaxdamp.validation import validate

        if config.system != "primary":
            raise ConfigError("SteadyProblem needs an S1 configuration (system = 'primary')")
        for name, value, ok in (("h", h, h > 0), ("replicates", replicates, replicates >= 1),
                                ("duration", duration, duration > 0)):
            if not ok:
                raise ConfigError(f"SteadyProblem: {name} = {value} must be > 0")
        self.config = validate(apply_overrides(config, {"numerics.duration": float(duration)}))
        self.objective = objective
        self.freqs = objective.frequencies(self.config)
        self.h, self.R, self.duration = float(h), int(replicates), float(duration)
        self.margin = float(margin)
        self.progress = progress
        self.beds: dict = {}
        self.sim_seconds = 0.0
        self.evaluations: list[dict] = []
        cfgs = replicate_configs([self.config], self.R)
        model, _ = build(self.config)
        t0 = time.perf_counter()
        settled = settle_many(cfgs, model, [build(c)[1] for c in cfgs],
                              progress=(f"settling {len(cfgs)} bed(s) of {model.n} grains"
                                        if progress and model.n else None))
        self.settle_wall = time.perf_counter() - t0
        self.beds.update({geometry_key(c): b for c, b in zip(cfgs, settled)})
        self.bed_height = max(b.height for b in settled)

    def bounds(self, margin: float | None = None, hi: float | None = None):
        """Feasible ``Lz`` for the centre of a pair: ``[bed + margin + h, hi − h]``."""
        m = self.margin if margin is None else margin
        return self.bed_height + m + self.h, (0.4 if hi is None else hi) - self.h

    def measure(self, lzs) -> dict:
        """Replicated steady-state objective at every height of ``lzs`` (one batch).

        Returns ``{"lz": (L,), "J": (L, R), "Z": (F, L, R), "E": (F, L, R), "start": (F, R)
        (the common window's start per bed [s]), "not_stationary": int (runs),
        "sim_seconds": float, "wall": float}``."""
        from jaxdamp.analysis import stats
        from jaxdamp.studies.sweep import sweep

        lzs = [float(x) for x in np.atleast_1d(lzs)]
        lo = self.bed_height + 0.5 * self.margin
        if min(lzs) <= lo:
            raise ConfigError(f"box.Lz = {min(lzs):.5g} m: below the feasible range "
                              f"(settled bed {self.bed_height:.5g} m + margin)")
        t0 = time.perf_counter()
        res = sweep(self.config, {"frequency": list(self.freqs), "box.Lz": lzs},
                    replicates=self.R, beds=self.beds, progress=self.progress, echo=None)
        F, L, R = len(self.freqs), len(lzs), self.R
        Z, E, start = np.empty((F, L, R)), np.empty((F, L, R)), np.empty((F, R))
        not_stationary = 0
        for f, freq in enumerate(self.freqs):
            for r in range(R):  # one bed at every height: one common window (module doc)
                w = stats.rows_window(res.records,
                                      [res.point(f * L + li, r) for li in range(L)], freq)
                start[f, r] = w["t_start"]
                Z[f, :, r] = w["amplitude"]
                E[f, :, r] = w["granular_loss_per_cycle"]
                not_stationary += 0 if w["stationary"] else L
        J = np.asarray(self.objective.combine(Z, E, self.freqs), float)  # (L, R)
        cost = len(self.freqs) * len(lzs) * self.R * self.duration
        self.sim_seconds += cost
        out = {"lz": np.asarray(lzs), "J": J, "Z": Z, "E": E, "start": start,
               "not_stationary": not_stationary,
               "sim_seconds": cost, "wall": time.perf_counter() - t0}
        self.evaluations.append(out)
        return out

    def scan(self, lzs):
        """``(mean (L,), se (L,), J (L, R))`` of the objective over ``lzs``."""
        m = self.measure(lzs)
        J = m["J"]
        se = standard_error(J, axis=1) if self.R > 1 else np.full(len(J), np.nan)
        return J.mean(axis=1), se, J

    def evaluate(self, lz: float, state=None):
        """``(Estimate, None)`` at ``lz``: value and central-difference derivative with their
        standard errors across the ``R`` independent pairs."""
        m = self.measure([lz - self.h, lz + self.h])
        J = m["J"]
        v_r = 0.5 * (J[0] + J[1])
        g_r = (J[1] - J[0]) / (2 * self.h)
        R = self.R
        se = (lambda x: float(standard_error(x))) if R > 1 else (lambda x: math.nan)
        return Estimate(float(v_r.mean()), se(v_r), float(g_r.mean()), se(g_r),
                        m["sim_seconds"], m["wall"],
                        extra={"minus": J[0], "plus": J[1],
                               "not_stationary": m["not_stationary"]}), None

    def pooled(self, centre: float, width: float | None = None):
        """Response-surface optimum (:func:`jaxdamp.design.surface.quadratic_optimum`) of
        every evaluated point within ``width`` (default ``6 h``, at least the 3 nearest points)
        of ``centre``, pooling all evaluations so far; ``None`` with fewer than 3 points."""
        from jaxdamp.design.surface import quadratic_optimum

        if not self.evaluations:
            return None
        x = np.concatenate([e["lz"] for e in self.evaluations])
        J = np.concatenate([e["J"] for e in self.evaluations])
        w = 6 * self.h if width is None else width
        sel = np.abs(x - centre) <= w
        if sel.sum() < 3:
            sel = np.zeros(len(x), bool)
            sel[np.argsort(np.abs(x - centre))[:3]] = True
        if len(np.unique(np.round(x[sel], 12))) < 3:
            return None
        order = np.argsort(x[sel])
        return quadratic_optimum(x[sel][order], J[sel][order], self.objective.maximise)

    def to_lz(self, x):
        return x

    def from_lz(self, lz):
        return lz

    def describe(self) -> dict:
        return {"model": "DEM", "estimator": "replicated steady states, central differences",
                "h": self.h, "replicates": self.R, "duration": self.duration,
                "bed_height": self.bed_height, "frequencies": list(self.freqs),
                "detection": "MSER on per-period amplitude and dissipation"}
