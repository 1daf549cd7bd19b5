"""Several design variables: a replicated SPSA gradient fed to optax, and its baseline.

**The gradient** (simultaneous perturbation, Spall 1992) of the replicated steady objective
``J(u)`` in the normalised coordinates ``u ∈ [0, 1]^d`` of a
:class:`~jaxdamp.design.space.DesignSpace`: for ``n`` pairs, each with its own random
Rademacher direction ``Δ_k ∈ {−1, +1}^d`` and its own bed,

    ĝ = 1/n Σ_k (J(u + cΔ_k; bed_k) − J(u − cΔ_k; bed_k)) / (2c) · Δ_k ,

unbiased for ``∇J`` up to ``O(c²)`` because ``E[Δ Δᵀ] = I``. Both members of a pair start from
beds of one seed (common random numbers: the difference is not swamped by the bed's
realisation). Every pair has its own direction *and* its own seed, so the ``n`` terms are
independent and the standard error of each component is their spread ``/ √n``. (Sharing a
direction between several beds would not do: the direction's own scatter, ``(gᵀΔ)Δ − g``, is
then common to those terms, and their spread underestimates the error — by 3× in the test
with 2 directions × 4 beds.) All ``2n`` systems run in one batch, whatever ``d`` is: this is
why a gradient pays off with many variables. The objective at ``u`` is the mean of the pair
averages, with its standard error across pairs.

**The optimiser** :func:`spsa` — Adam (optax, decaying learning rate) on ``ĝ`` in ``u``, each
iterate projected onto the feasible set shrunk by ``c`` (every perturbation stays feasible);
the design it returns is the average of the last iterates (iterate averaging removes the
gradient noise that Adam's steps carry). It runs ``max_iter`` iterates, or stops before an
iteration would exceed the ``budget`` of simulated system-seconds, or FAILED on a non-finite
estimate; the result is converged when its last iterate meets the convergence rule
(:class:`~jaxdamp.design.status.ConvergenceRule` in ``u``: every component of the gradient
not significant for ``patience`` iterates, or on its bound with the objective improving
beyond it), NOT CONVERGED otherwise.

**The baseline** :func:`random_search` — a Latin hypercube of designs, each on ``R`` beds, in
one batch, and the best mean. Both results should be confirmed on fresh beds
(:meth:`~jaxdamp.design.space.DesignProblem.evaluate`): a best-of-``n`` mean is biased towards
the lucky (winner's curse).

Example (a quadratic stand-in for the DEM; ``measure`` is all the optimiser needs)::

    >>> import numpy as np
    >>> from jaxdamp.design.spsa import spsa
    >>> from jaxdamp.design.space import DesignSpace
    >>> from jaxdamp.cases import presets
    >>> class Bowl:
    ...     objective = type("O", (), {"maximise": True})()
    ...     def __init__(self):
    ...         self.space = DesignSpace.of(presets.get("sanchez2012-optimal"), ("Lz", "friction"))
    ...         self.sim_seconds, self._s = 0.0, 0
    ...     def seeds(self, n):
    ...         self._s += n
    ...         return np.arange(self._s - n, self._s)
    ...     def cost_per_system(self):
    ...         return 1.0
    ...     def measure(self, X, seeds, pairs=False):
    ...         u = self.space.to_u(X)
    ...         self.sim_seconds += len(X)
    ...         return {"J": -((u - 0.6) ** 2).sum(axis=1), "sim_seconds": float(len(X))}
    >>> res = spsa(Bowl(), x0=[0.1, 0.2], max_iter=40, lr=0.1, decay=0.95, progress=False)
    >>> bool(np.allclose(res.u_average, 0.6, atol=0.05))
    True
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from jaxdamp.analysis.uncertainty import pm, standard_error
from jaxdamp.design.objectives import Estimate
from jaxdamp.design.status import (
    CONVERGED,
    FAILED,
    NOT_CONVERGED,
    ConvergenceRule,
    Status,
    non_finite,
)

#: Fields of one SPSA iterate in :attr:`SPSAResult.history`.
HISTORY = ("u", "x", "value", "value_se", "grad", "grad_se", "sim_seconds", "wall")


def spsa_gradient(problem, u, pairs: int, c: float, rng) -> Estimate:
    """The replicated SPSA estimate at ``u`` from ``pairs`` independent (direction, bed) pairs
    (module doc): ``value``/``value_se`` the objective and its SE, ``grad``/``grad_se``
    ``(d,)`` arrays in objective units per unit of ``u``; ``extra``: ``plus``, ``minus``
    ``(n,)``, ``delta`` ``(n, d)``."""
    space = problem.space
    n, d = int(pairs), space.dim
    delta = rng.choice([-1.0, 1.0], size=(n, d))
    X = np.concatenate([[space.to_x(u + c * dk), space.to_x(u - c * dk)] for dk in delta])
    seeds = np.repeat(problem.seeds(n), 2)
    m = problem.measure(X, seeds, pairs=True)
    J = np.asarray(m["J"], float).reshape(n, 2)
    plus, minus = J[:, 0], J[:, 1]
    g = ((plus - minus) / (2 * c))[:, None] * delta  # (n, d)
    v = 0.5 * (plus + minus)
    if n > 1:
        g_se, v_se = standard_error(g, axis=0), float(standard_error(v))
    else:
        g_se, v_se = np.full(d, np.nan), math.nan
    return Estimate(float(v.mean()), v_se, g.mean(axis=0), g_se, m["sim_seconds"],
                    m.get("wall", 0.0), extra={"plus": plus, "minus": minus, "delta": delta})


@dataclass
class SPSAResult:
    """``x_average`` the design (average of the last iterates; physical units, in the order
    of ``names``), ``u_average`` the same in normalised coordinates; ``history``
    ``{field: array}`` per iterate (:data:`HISTORY`); ``best`` the iterate with the best
    objective estimate ``{"x", "value", "ci95"}``; ``sim_seconds``; ``reason``; ``wall``;
    ``status`` (:class:`~jaxdamp.design.status.Status`, its reason is ``reason``)."""

    names: tuple
    x_average: np.ndarray
    u_average: np.ndarray
    history: dict
    best: dict
    sim_seconds: float
    reason: str
    wall: float
    settings: dict = field(default_factory=dict)
    status: Status | None = None


def spsa(problem, x0, pairs: int = 4, c: float = 0.08,
         lr: float = 0.08, decay: float = 0.92, max_iter: int = 10, budget: float | None = None,
         average: int = 3, seed: int = 0, b1: float = 0.7, b2: float = 0.9,
         progress: bool = True, echo=None, patience: int = 3, se_factor: float = 1.0,
         xtol: float = 1e-3) -> SPSAResult:
    """Adam on replicated SPSA gradients from ``x0`` (module doc).

    Args:
      problem: a :class:`~jaxdamp.design.space.DesignProblem` (or anything with ``space``,
        ``objective``, ``seeds``, ``measure``, ``cost_per_system``).
      x0: start design [physical units, ``problem.space.names`` order].
      pairs: independent (direction, bed) pairs per iterate (``2 × pairs`` systems).
      c: perturbation half-size in normalised coordinates.
      lr, decay: Adam's learning rate in normalised coordinates, decayed by ``decay`` per step.
      max_iter: most iterates; budget: simulated system-seconds not to exceed.
      average: iterates averaged for the design.
      seed: of the random directions (the beds' seeds come from the problem).
      progress: a bar showing the best objective so far ± its 95 % interval.
      patience, se_factor, xtol: of the convergence rule (``xtol`` in normalised coordinates:
        the distance to a bound that counts as on it).
    """
    import jax.numpy as jnp
    import optax

    from jaxdamp.analysis.stats import t_quantile
    from jaxdamp.config import ConfigError

    for name, val, ok in (("pairs", pairs, pairs >= 1), ("c", c, 0 < c < 0.5),
                          ("max_iter", max_iter, max_iter >= 1)):
        if not ok:
            raise ConfigError(f"spsa: {name} = {val} out of range (pairs, max_iter ≥ 1; "
                              "0 < c < 0.5)")
    space = problem.space
    rng = np.random.default_rng(seed)
    u = space.project(space.to_u(np.asarray(x0, float)), shrink=c)
    sign = -1.0 if problem.objective.maximise else 1.0
    sched = optax.exponential_decay(lr, transition_steps=1, decay_rate=decay)
    opt = optax.adam(sched, b1=b1, b2=b2)
    state = opt.init(jnp.zeros(space.dim))
    hist = {k: [] for k in HISTORY}
    per_iter = 2 * pairs * problem.cost_per_system()
    spent, reason, best = 0.0, f"max_iter = {max_iter} reached", None
    outcome, converged = NOT_CONVERGED, ""
    rule = ConvergenceRule(np.full(space.dim, c), np.full(space.dim, 1.0 - c), xtol,
                           problem.objective.maximise, patience=patience, se_factor=se_factor,
                           names=space.names)
    tq = math.nan if pairs < 2 else t_quantile(0.975, pairs - 1)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=max_iter, unit="it", desc=f"SPSA over {','.join(space.names)}")
    t0 = time.perf_counter()
    try:
        for k in range(max_iter):
            if budget is not None and spent + per_iter > budget:
                reason = f"budget of {budget:g} simulated system-seconds reached"
                break
            est = spsa_gradient(problem, u, pairs, c, rng)
            spent += est.sim_seconds
            if non_finite([est.value, est.grad]):
                outcome = FAILED
                reason = ("non-finite objective or gradient at "
                          + ", ".join(f"{n} = {v:.5g}" for n, v in zip(space.names,
                                                                      space.to_x(u))))
                break
            x = space.to_x(u)
            for key, val in zip(HISTORY, (u, x, est.value, est.value_se, est.grad,
                                          est.grad_se, spent, time.perf_counter() - t0)):
                hist[key].append(np.array(val, float))
            better = best is None or (est.value > best["value"]) == problem.objective.maximise
            if better:
                best = {"x": x.tolist(), "value": est.value, "ci95": tq * est.value_se,
                        "iterate": k}
            if bar is not None:
                bar.update(1)
                bar.set_postfix_str(f"best {pm(best['value'], best['ci95'], 4)} at "
                                    + ", ".join(f"{n}={v:.4g}" for n, v in zip(space.names,
                                                                               best["x"])))
            if echo:
                echo(f"{k:3d} " + ", ".join(f"{n} = {v:.5g}" for n, v in zip(space.names, x))
                     + f"  objective = {pm(est.value, est.value_se)}")
            converged = rule.check(u, est.grad, est.grad_se)
            upd, state = opt.update(jnp.asarray(sign * est.grad), state)
            u = space.project(u + np.asarray(upd), shrink=c)
    finally:
        if bar is not None:
            bar.close()
    hist = {k: np.asarray(v) for k, v in hist.items()}
    if outcome != FAILED and len(hist["u"]) and converged:
        outcome, reason = CONVERGED, converged
    if not len(hist["u"]) and outcome != FAILED:
        raise ConfigError(f"spsa: no iterate fits the budget ({budget} s; one iterate costs "
                          f"{per_iter:.3g} simulated system-seconds)")
    u_avg = (space.project(hist["u"][-average:].mean(axis=0), shrink=c) if len(hist["u"])
             else u)
    return SPSAResult(space.names, space.to_x(u_avg), u_avg, hist, best, spent, reason,
                      time.perf_counter() - t0,
                      dict(pairs=pairs, c=c, lr=lr,
                           decay=decay, max_iter=max_iter, budget=budget, average=average,
                           seed=seed, b1=b1, b2=b2, patience=patience, se_factor=se_factor,
                           xtol=xtol),
                      Status(outcome, reason, len(hist["u"])))


@dataclass
class RandomSearchResult:
    """``X`` ``(n, d)`` the designs, ``mean``, ``se`` ``(n,)`` and ``J`` ``(n, R)`` their
    replicated objective; ``best`` the best mean's design ``{"x", "value", "ci95"}``;
    ``sim_seconds``; ``status``: a sample is not a converged search — NOT CONVERGED (FAILED
    when no design has a finite mean)."""

    names: tuple
    X: np.ndarray
    mean: np.ndarray
    se: np.ndarray
    J: np.ndarray
    best: dict
    sim_seconds: float
    status: Status | None = None


def latin_hypercube(n: int, d: int, rng) -> np.ndarray:
    """``n`` points in ``[0, 1]^d``, one in each of ``n`` equal slices of every axis."""
    return (np.stack([rng.permutation(n) for _ in range(d)], axis=1)
            + rng.random((n, d))) / n


def random_search(problem, budget: float, replicates: int = 2, seed: int = 0) -> RandomSearchResult:
    """A Latin hypercube of as many designs as ``budget`` simulated system-seconds pay for,
    each on ``replicates`` fresh beds, projected onto the feasible set, all in one batch."""
    from jaxdamp.config import ConfigError

    space = problem.space
    n = int(budget // (replicates * problem.cost_per_system()))
    if n < 1:
        raise ConfigError(f"random search: budget {budget:g} s pays for no design "
                          f"({replicates} × {problem.cost_per_system():.3g} s each)")
    rng = np.random.default_rng(seed)
    U = np.array([space.project(u) for u in latin_hypercube(n, space.dim, rng)])
    X = space.to_x(U)
    ev = problem.evaluate(X, replicates)
    mean = np.asarray(ev["mean"], float)
    if not np.isfinite(mean).any():
        k, status = 0, Status(FAILED, f"no design of the {n} has a finite objective", 1)
    else:
        k = int(np.nanargmax(mean) if problem.objective.maximise else np.nanargmin(mean))
        bad = int((~np.isfinite(mean)).sum())
        status = Status(NOT_CONVERGED, f"a sample of {n} designs (Latin hypercube, one batch): "
                        "no convergence test, its best mean is a candidate"
                        + (f"; {bad} design(s) with a non-finite objective left out" if bad
                           else ""), 1)
    best = {"x": X[k].tolist(), "value": float(mean[k]), "ci95": float(ev["ci95"][k]),
            "index": k}
    return RandomSearchResult(space.names, X, ev["mean"], ev["se"], ev["J"], best,
                              ev["sim_seconds"], status)
