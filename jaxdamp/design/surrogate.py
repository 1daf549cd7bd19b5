"""The single-particle model standing in for the bed: the cheap half of multi-fidelity design.

The thesis (§5.3.2) replaces the whole bed of an S1 damper by one particle of the bed's mass
with restitution ``e = 0`` moving in the free height ``gap = Lz − h_bed`` (``h_bed`` the settled
bed's height). :func:`s3_config` builds that S3 configuration from a DEM configuration;
:func:`propose` scans the surrogate's objective densely over the gap (one ``vmap`` batch of the
smooth model: seconds) and returns the box height of its optimum — a starting point for the
DEM search (:func:`jaxdamp.design.search.trust_region`), which corrects it with the DEM.
:func:`descend` gets there from a given start instead: optax Adam on the exact orbit
gradients, falling back to central differences of long averages where the surrogate's motion
has no stable periodic orbit (large gaps), so that a start in the irregular region still
walks out of it.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxdamp.config import Config, Impactor
from jaxdamp.design.objectives import Objective
from jaxdamp.physics.containers import container


def s3_config(config: Config, h_bed: float, restitution: float = 0.0) -> Config:
    """The S3 model of the S1 damper ``config`` with a settled bed ``h_bed`` [m] high:
    one particle of the granulate's mass, ``e = restitution``, gap ``Lz − h_bed``."""
    from jaxdamp.physics.model import grain_mass

    return dataclasses.replace(
        config, system="impact", grains=(), name=f"{config.name} (S3 surrogate)",
        impactor=Impactor(mass=grain_mass(config), restitution=restitution,
                          gap=container(config).height(config) - h_bed, method="smooth"))


def propose(config: Config, objective: Objective, h_bed: float, lo: float, hi: float,
            n: int = 41, duration: float = 3.0) -> dict:
    """The surrogate's optimum ``Lz`` over ``[lo, hi]`` [m] by a dense scan of ``n`` gaps.

    Returns ``{"lz": the proposal, "lz_grid", "values", "sim_seconds", "at_bound"}``."""
    from jaxdamp.config import apply_overrides
    from jaxdamp.design.s3 import S3Problem
    from jaxdamp.design.surface import quadratic_optimum

    cfg = apply_overrides(s3_config(config, h_bed), {"numerics.analysis_window": 0.5})
    prob = S3Problem(cfg, objective, duration=duration, h_bed=h_bed)
    lz = np.linspace(lo, hi, n)
    v = prob.scan(lz - h_bed)
    k = int(np.argmax(v) if objective.maximise else np.argmin(v))
    best = float(lz[k])
    if 0 < k < n - 1:
        best = quadratic_optimum(lz[k - 1:k + 2], v[k - 1:k + 2], objective.maximise).x
    return {"lz": best, "lz_grid": lz, "values": v, "sim_seconds": prob.sim_seconds,
            "at_bound": k in (0, n - 1)}


def descend(config: Config, objective: Objective, h_bed: float, lz0: float, lo: float,
            hi: float, settings: dict | None = None) -> dict:
    """The surrogate's optimum ``Lz`` found from ``lz0`` by the exact-gradient optimiser
    (:func:`jaxdamp.design.optimizer.optimize` on :class:`~jaxdamp.design.s3.S3Problem` with
    ``gradient="orbit", fallback=True``), within ``[lo, hi]`` [m].

    Returns ``{"lz", "iterates", "fallbacks" (iterates without a stable orbit), "reason",
    "status" (:class:`~jaxdamp.design.status.Status`), "sim_seconds"}``: ``lz`` is the
    optimiser's design (:attr:`~jaxdamp.design.optimizer.OptimizeResult.design`), or its best
    iterate when it did not converge."""
    from jaxdamp.config import apply_overrides
    from jaxdamp.design import DEFAULTS
    from jaxdamp.design.optimizer import optimize
    from jaxdamp.design.s3 import S3Problem

    # a slower decay than the S3 optimiser's default: the start may be ~0.2 m from the optimum
    s = {**DEFAULTS["s3"], "max_iter": 80, "decay": 0.95, **(settings or {})}
    cfg = apply_overrides(s3_config(config, h_bed),
                          {"numerics.analysis_window": s["analysis_window"]})
    prob = S3Problem(cfg, objective, duration=s["duration"], h_bed=h_bed, fallback=True)
    res = optimize(prob, lz0 - h_bed, lr=s["lr"], decay=s["decay"], max_iter=s["max_iter"],
                   xtol=s["xtol"], lo=lo - h_bed, hi=hi - h_bed, progress=False)
    x = res.design if res.status.converged or res.best is None else res.best["x"]
    return {"lz": float(x + h_bed), "iterates": len(res.history["x"]),
            "fallbacks": prob.fallbacks, "reason": res.reason, "status": res.status,
            "sim_seconds": prob.sim_seconds}
