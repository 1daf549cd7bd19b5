"""Gradient-based optimisation of one design variable with optax (S3 exact, DEM estimated).

:func:`optimize`: Adam (optax) with an exponentially decaying learning rate, projection onto
``[lo, hi]`` after every update, stopping rules (gradient not significant against its standard
error, small steps, a budget of iterations or of simulated system-seconds), a progress bar and
an HDF5 log of every iterate (``docs/output.md``). The result is the average of the last
iterates (iterate averaging: the noise of an estimated gradient averages out) with, for
replicated problems, a confidence interval from the response surface of every evaluation
(:func:`jaxdamp.design.surface.quadratic_optimum`).

Every result carries its :class:`~jaxdamp.design.status.Status` by the one convergence rule
(:mod:`jaxdamp.design.status`): converged (stationary, or on a bound with the objective
improving beyond it), NOT CONVERGED (the iteration cap, the budget, or a learning rate that
decayed below the step tolerance) or FAILED (an estimate that is not finite, e.g. the orbit
method finding no stable periodic orbit: the optimiser stops there with the reason).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from jaxdamp.analysis.uncertainty import pm
from jaxdamp.config import ConfigError
from jaxdamp.design.status import (
    CONVERGED,
    FAILED,
    NOT_CONVERGED,
    ConvergenceRule,
    Status,
    non_finite,
)
from jaxdamp.io import optimisation as optimisation_file


@dataclass
class OptimizeResult:
    """``x`` the final design variable (``Lz`` or gap) [m], ``lz`` the box height,
    ``history`` dict of arrays (one entry per iterate), ``reason`` why it stopped,
    ``sim_seconds`` simulated system-seconds in total, ``wall`` [s], ``path`` the log file;
    ``x_average`` the mean of the last ``average`` iterates; ``optimum`` the response-surface
    optimum with its interval (:class:`~jaxdamp.design.surface.Optimum`) for problems that
    pool their evaluations (``None`` otherwise); ``status`` by the convergence rule
    (:class:`~jaxdamp.design.status.Status`; its reason is ``reason``); ``best`` the iterate
    with the best finite objective ``{"x", "value", "value_se", "iterate"}`` (``None``
    without one); ``design`` the answer: the converged (last) iterate for an exact gradient,
    ``x_average`` for an estimated one (averaging removes the gradient's noise)."""

    x: float
    lz: float
    value: float
    history: dict
    reason: str
    sim_seconds: float
    wall: float
    path: str | None
    x_average: float = math.nan
    optimum: object = None
    status: Status | None = None
    best: dict | None = None
    design: float = math.nan




def optimize(problem, x0: float, lr: float = 0.01, decay: float = 0.9, max_iter: int = 30,
             b1: float = 0.7, b2: float = 0.9,
             xtol: float = 2e-4, patience: int = 3, se_factor: float = 1.0,
             lo: float | None = None, hi: float | None = None, out: str | None = None,
             progress: bool = True, config_json: str | None = None, echo=None,
             budget: float | None = None, average: int = 3):
    """Optimise ``problem`` (an S3, steady or windows problem of :mod:`jaxdamp.design`) from
    ``x0``; ``budget``: stop before an evaluation would exceed this many simulated
    system-seconds; ``average``: iterates averaged for ``x_average``.

    Adam (optax; moment decays ``b1``, ``b2`` shorter than the usual 0.9/0.999 because the
    gradient's scale changes by orders of magnitude between the start and the optimum, and a
    long second-moment memory then freezes the steps before the first moment has turned)
    with learning rate ``lr·decay^k`` [m]; after each
    update the iterate is projected onto ``[lo, hi]`` (default ``problem.bounds()``). Stops
    when an iterate meets the convergence rule (:class:`~jaxdamp.design.status.ConvergenceRule`
    with ``xtol``, ``patience``, ``se_factor``: converged), when an estimate is not finite
    (FAILED), or NOT CONVERGED: after ``max_iter`` iterates, before an evaluation would exceed
    the budget, or once the learning rate decayed below ``xtol`` [m] and the last ``patience``
    steps were all below it (the iterate can no longer move). Small steps alone are no
    evidence of convergence: Adam's steps shrink while its momentum turns. Objectives marked
    maximise are maximised.
    Writes every iterate and the status to ``out`` (HDF5, ``docs/output.md``).
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
    hist = {k: [] for k in optimisation_file.LOG_FIELDS}
    h5 = optimisation_file.open_log(out, problem, x0, lo, hi, dict(lr=lr, decay=decay, b1=b1, b2=b2, max_iter=max_iter,
                   xtol=xtol, patience=patience, se_factor=se_factor), config_json)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=max_iter, unit="it", desc=f"optimise {problem.variable}")
    t_start = time.perf_counter()
    rule = ConvergenceRule(lo, hi, xtol, problem.objective.maximise, patience=patience,
                           se_factor=se_factor, names=(problem.variable,), unit="m")
    state, sim_total = None, 0.0
    outcome, reason = NOT_CONVERGED, f"max_iter = {max_iter} reached"
    last_cost = 0.0
    small_steps = 0
    best = None  # the iterate with the best finite objective so far
    exact = True  # every gradient so far exact (standard error 0)
    try:
        for k in range(max_iter):
            if budget is not None and k > 0 and sim_total + last_cost > budget:
                reason = f"budget of {budget:g} simulated system-seconds reached"
                break
            est, state = problem.evaluate(x, state)
            sim_total += est.sim_seconds
            last_cost = est.sim_seconds
            if non_finite([est.value, est.grad]):
                why = est.extra.get("reason", "")
                outcome = FAILED
                reason = (f"non-finite objective or gradient at {problem.variable} = {x:.6g}"
                          + (f": {why}" if why else ""))
                optimisation_file.log(h5, hist, x, problem, est, 0.0, float(sched(k)), t_start, sim_total)
                break
            exact = exact and est.grad_se == 0
            if best is None or (est.value > best["value"]) == problem.objective.maximise:
                best = {"x": x, "value": est.value, "value_se": est.value_se, "iterate": k}
            converged = rule.check(x, est.grad, est.grad_se)
            if converged:
                optimisation_file.log(h5, hist, x, problem, est, 0.0, float(sched(k)), t_start,
                                      sim_total)
                outcome, reason = CONVERGED, converged
            else:
                updates, opt_state = opt.update(jnp.asarray(sign * est.grad), opt_state)
                x_new = float(np.clip(x + float(updates), lo, hi))
                step = x_new - x
                optimisation_file.log(h5, hist, x, problem, est, step, float(sched(k)), t_start,
                                      sim_total)
            if bar is not None:
                bar.update(1)
                ci = 1.96 * best["value_se"] if best["value_se"] > 0 else np.nan
                bar.set_postfix({problem.variable: f"{x:.5f}",
                                 "best": f"{pm(best['value'], ci, 4, compact=True)} at "
                                         f"{best['x']:.5f}",
                                 "grad": pm(est.grad, est.grad_se, 3, compact=True)})
            if echo:
                echo(f"{k:3d} {problem.variable} = {x:.6f} m  objective = "
                     f"{pm(est.value, est.value_se, 6)}  gradient = {pm(est.grad, est.grad_se)}")
            if converged:
                break
            small_steps = small_steps + 1 if abs(step) < xtol else 0
            x = x_new
            if small_steps >= patience and float(sched(k)) < xtol:
                reason = (f"the learning rate decayed to {float(sched(k)):.2g} m, below xtol = "
                          f"{xtol:g} m, before the convergence rule was met")
                break
    finally:
        if bar is not None:
            bar.close()
    hist = {k: np.asarray(v) for k, v in hist.items()}
    n_it = len(hist["x"])
    status = Status(outcome, reason, n_it)
    # the result: the last iterate (x after the final update is not evaluated); the average
    # of the last finite iterates
    finite = np.isfinite(hist["objective"]) if n_it else np.zeros(0, bool)
    x_final = float(hist["x"][-1]) if n_it else x
    x_avg = float(np.mean(hist["x"][finite][-average:])) if finite.any() else x
    optimum = None
    if hasattr(problem, "pooled") and finite.any():
        optimum = problem.pooled(x_avg)
    res = OptimizeResult(x=x_final, lz=float(problem.to_lz(x_final)),
                         value=float(hist["objective"][-1]) if n_it else float("nan"),
                         history=hist, reason=reason, sim_seconds=sim_total,
                         wall=time.perf_counter() - t_start, path=out, x_average=x_avg,
                         optimum=optimum, status=status, best=best,
                         design=(math.nan if outcome == FAILED else x_final if exact
                                 else x_avg))
    if h5 is not None:
        h5.attrs["status"] = "finished"
        h5.attrs["reason"] = reason
        result = {"x": res.x, "lz": res.lz, "objective": res.value, "x_average": x_avg,
                  "design": res.design, "sim_seconds": res.sim_seconds,
                  "wall_time": res.wall, "iterations": n_it}
        if best is not None:
            result.update(best_x=best["x"], best_objective=best["value"],
                          best_iterate=best["iterate"])
        if optimum is not None:
            result.update(optimum=optimum.x, optimum_lo=optimum.lo, optimum_hi=optimum.hi,
                          optimum_se=optimum.se, optimum_interior=bool(optimum.interior))
        h5.attrs["result"] = json.dumps(result)
        optimisation_file.write_status(h5, status)
        h5.close()
    return res


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
