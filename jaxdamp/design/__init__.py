"""Design optimisation of a particle damper: objectives, problems, searches (``docs/physics.md`` §7).

* :mod:`~jaxdamp.design.objectives` — what a designer optimises (``damping`` = the grains'
  equivalent viscous damping ``C_eq`` by default; ``amplitude``, ``band``, ``dissipation``).
* Problems — an objective as a function of one design variable, evaluated in batches:
  :class:`~jaxdamp.design.s3.S3Problem` (the single-particle model, gap; exact orbit
  gradients), :class:`~jaxdamp.design.steady.SteadyProblem` (the DEM, ``Lz``; replicated
  steady states, central differences), :class:`~jaxdamp.design.windows.DEMProblem` (the
  pathwise window estimator, kept to show why it fails).
* Searches — :func:`~jaxdamp.design.optimizer.optimize` (optax on a gradient),
  :func:`~jaxdamp.design.search.adaptive_scan` (the batched baseline),
  :func:`~jaxdamp.design.search.trust_region` (a pooled response-surface search, started from
  the surrogate's proposal :func:`~jaxdamp.design.surrogate.propose`: multi-fidelity),
  all reporting an optimum with an interval (:mod:`~jaxdamp.design.surface`) and the simulated
  system-seconds they spent.
* Several variables — :mod:`~jaxdamp.design.space` (``Lz``, ``base``, ``friction``, the fill
  ``mass_ratio``, the grains' ``radius`` and ``material``, the ``cells``: the design space
  with projection, and :class:`~jaxdamp.design.space.DesignProblem`, one bed per design,
  designs of other grains in batches of their own), :mod:`~jaxdamp.design.spsa` (replicated
  SPSA gradients fed to optax Adam; the equal-budget Latin-hypercube baseline) and
  :mod:`~jaxdamp.design.bayes` (the batched search: Sobol start, a Gaussian process with the
  replicates' noise, Thompson batches).
* An operating envelope — :mod:`~jaxdamp.design.envelope` (a band of frequencies × base
  amplitudes, the worst or mean ``C_eq`` over it, mass and volume budgets, the damping–mass
  front).

:func:`make_problem` builds the problem of a configuration with the settings of
:data:`DEFAULTS`; ``jaxdamp optimize`` is its command line.
"""

from __future__ import annotations

from jaxdamp.config import Config, ConfigError, apply_overrides
from jaxdamp.design.objectives import DEFAULT, OBJECTIVES, Estimate, Objective, smooth_max
from jaxdamp.design.optimizer import OptimizeResult, optimize, scan_optimum
from jaxdamp.design.s3 import S3Problem
from jaxdamp.design.search import SearchResult, adaptive_scan, trust_region
from jaxdamp.design.steady import SteadyProblem
from jaxdamp.design.surface import Optimum, quadratic_optimum
from jaxdamp.design.windows import DEMProblem

__all__ = ["DEFAULT", "OBJECTIVES", "DEFAULTS", "DEMProblem", "Estimate", "Objective",
           "OptimizeResult", "Optimum", "S3Problem", "SearchResult", "SteadyProblem",
           "adaptive_scan", "make_problem", "optimize", "quadratic_optimum", "scan_optimum",
           "smooth_max", "trust_region"]

#: Settings of ``jaxdamp optimize`` (full and ``--quick``) per problem. S3: run length [s],
#: learning rate and decay, iterations; steady (DEM): difference half-step, replicates,
#: duration per evaluation [s], settling; windows (DEM, pathwise): window [s], ensemble,
#: burn-ins [s]; design (several variables): SPSA pairs per iterate, beds per design of the
#: random search,
#: duration [s], Adam's rate and decay and the perturbation ``c`` (normalised coordinates),
#: iterations, beds of the confirmation run, settling; the batched search's Sobol start, its
#: batch size and batches after the start (:mod:`jaxdamp.design.bayes`). (S3 quick: 30
#: iterations, enough for the thesis' damper at f0 to meet the convergence rule,
#: :mod:`jaxdamp.design.status`, from the default start: it needs 26.)
DEFAULTS = {
    "s3": dict(duration=3.0, analysis_window=0.5, lr=0.015, decay=0.88, max_iter=40, xtol=5e-5),
    "s3-quick": dict(duration=3.0, analysis_window=0.5, lr=0.015, decay=0.88, max_iter=30,
                     xtol=5e-5),
    "steady": dict(h=0.005, replicates=4, duration=3.0, lr=0.01, decay=0.85, max_iter=10,
                   xtol=5e-4, settle_time=0.3),
    "steady-quick": dict(h=0.005, replicates=2, duration=0.6, lr=0.01, decay=0.85,
                         max_iter=2, xtol=5e-4, settle_time=0.2),
    "design": dict(pairs=4, replicates=2, duration=3.0, lr=0.08, decay=0.92, c=0.08,
                   max_iter=10, confirm=4, settle_time=0.3, n_start=8, batch=4, rounds=3),
    "design-quick": dict(pairs=2, replicates=2, duration=0.5, lr=0.08, decay=0.92,
                         c=0.08, max_iter=2, confirm=2, settle_time=0.2, n_start=3, batch=2,
                         rounds=1),
    "windows": dict(window=0.002, n_windows=8, burn_in=1.0, warm_burn_in=0.4, lr=0.02,
                    decay=0.85, max_iter=12, xtol=5e-4, settle_time=0.3),
    "windows-quick": dict(window=0.001, n_windows=4, burn_in=0.3, warm_burn_in=0.1, lr=0.02,
                          decay=0.85, max_iter=3, xtol=5e-4, settle_time=0.3),
}

_SETTINGS = ("lr", "decay", "max_iter", "xtol")


def make_problem(config: Config, objective: Objective, quick: bool = False, **overrides):
    """The problem of ``config`` (S3 for ``system = "impact"``; for S1 the
    :class:`SteadyProblem`, or with ``estimator="windows"`` the pathwise
    :class:`DEMProblem`) with :data:`DEFAULTS` (``overrides`` win; ``None`` values are
    ignored; keys that do not apply to the chosen problem are refused; ``progress``: the DEM
    problems' progress bars of settling and of every evaluation's sweep, ignored by S3).
    Returns ``(problem, optimiser settings)``."""
    over = {k: v for k, v in overrides.items() if v is not None}
    estimator = over.pop("estimator", "steady")
    if config.system == "impact":
        key = "s3"
    elif config.system == "primary" and estimator in ("steady", "windows"):
        key = estimator
    elif config.system == "primary":
        raise ConfigError(f"estimator = {estimator!r}: expected 'steady' or 'windows'")
    else:
        raise ConfigError(f"optimisation needs system 'primary' (S1) or 'impact' (S3), not "
                          f"{config.system!r}")
    s = dict(DEFAULTS[key + ("-quick" if quick else "")])
    progress = bool(over.pop("progress", False))
    unknown = [k for k in over if k not in s and k not in ("margin", "mode", "gradient")]
    if unknown:
        raise ConfigError(f"{', '.join(sorted(unknown))}: not a setting of the {key} problem "
                          f"(settings: {', '.join(sorted(s))})")
    s.update(over)
    if key == "s3":
        if objective.kind == "band" and "duration" not in over:
            s["duration"] = 2.0
        config = apply_overrides(config, {"numerics.analysis_window": s.pop("analysis_window")})
        prob = S3Problem(config, objective, duration=s.pop("duration"),
                         gradient=s.pop("gradient", "orbit"))
    elif key == "steady":
        config = apply_overrides(config, {"numerics.settle_time": s.pop("settle_time")})
        prob = SteadyProblem(config, objective, h=s.pop("h"), replicates=s.pop("replicates"),
                             duration=s.pop("duration"), margin=s.pop("margin", 0.005),
                             progress=progress)
    else:
        if objective.kind == "damping":
            raise ConfigError("the windows estimator has no 'damping' objective (it needs the "
                              "amplitude and the dissipation of one window); use the steady "
                              "estimator or --objective dissipation|amplitude|band")
        config = apply_overrides(config, {"numerics.settle_time": s.pop("settle_time")})
        prob = DEMProblem(config, objective, window=s.pop("window"),
                          n_windows=s.pop("n_windows"), burn_in=s.pop("burn_in"),
                          warm_burn_in=s.pop("warm_burn_in"), mode=s.pop("mode", "forward"),
                          margin=s.pop("margin", 0.005), progress=progress)
    return prob, {k: s[k] for k in _SETTINGS if k in s}
