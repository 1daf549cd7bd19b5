"""Gradient-based optimisation of one design variable with optax (S3 exact, DEM estimated).

:func:`optimize`: Adam (optax) with an exponentially decaying learning rate, projection onto
``[lo, hi]`` after every update, stopping rules (gradient not significant against its standard
error, small steps, a budget of iterations or of simulated system-seconds), a progress bar and
an HDF5 log of every iterate (``docs/output.md``). The result is the average of the last
iterates (iterate averaging: the noise of an estimated gradient averages out) with, for
replicated problems, a confidence interval from the response surface of every evaluation
(:func:`jaxdamp.design.surface.quadratic_optimum`).

An estimate that is not finite (e.g. the orbit method finding no stable periodic orbit) stops
the optimiser with the reason.
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass

import jax.numpy as jnp
import numpy as np

from jaxdamp.config import ConfigError
from jaxdamp.io import optimisation as optimisation_file


@dataclass
class OptimizeResult:
    """``x`` the final design variable (``Lz`` or gap) [m], ``lz`` the box height,
    ``history`` dict of arrays (one entry per iterate), ``reason`` why it stopped,
    ``sim_seconds`` simulated system-seconds in total, ``wall`` [s], ``path`` the log file;
    ``x_average`` the mean of the last ``average`` iterates; ``optimum`` the response-surface
    optimum with its interval (:class:`~jaxdamp.design.surface.Optimum`) for problems that
    pool their evaluations (``None`` otherwise)."""

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
    hist = {k: [] for k in optimisation_file.LOG_FIELDS}
    h5 = optimisation_file.open_log(out, problem, x0, lo, hi, dict(lr=lr, decay=decay, b1=b1, b2=b2, max_iter=max_iter,
                   xtol=xtol, patience=patience, se_factor=se_factor), config_json)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=max_iter, unit="it", desc=f"optimise {problem.variable}")
    t_start = time.perf_counter()
    state, sim_total, reason = None, 0.0, f"max_iter = {max_iter} reached"
    last_cost = 0.0
    small_steps = noisy = 0
    best = None  # (x, value, se) of the best iterate so far, for the progress bar
    try:
        for k in range(max_iter):
            if budget is not None and k > 0 and sim_total + last_cost > budget:
                reason = f"budget of {budget:g} simulated system-seconds reached"
                break
            est, state = problem.evaluate(x, state)
            sim_total += est.sim_seconds
            last_cost = est.sim_seconds
            if not (np.isfinite(est.value) and np.isfinite(est.grad)):
                why = est.extra.get("reason", "")
                reason = (f"non-finite objective or gradient at {problem.variable} = {x:.6g}"
                          + (f": {why}" if why else ""))
                optimisation_file.log(h5, hist, x, problem, est, 0.0, float(sched(k)), t_start, sim_total)
                break
            updates, opt_state = opt.update(jnp.asarray(sign * est.grad), opt_state)
            x_new = float(np.clip(x + float(updates), lo, hi))
            step = x_new - x
            optimisation_file.log(h5, hist, x, problem, est, step, float(sched(k)), t_start, sim_total)
            if best is None or (est.value > best[1]) == problem.objective.maximise:
                best = (x, est.value, est.value_se)
            if bar is not None:
                bar.update(1)
                ci = f"±{1.96 * best[2]:.2g}" if np.isfinite(best[2]) and best[2] > 0 else ""
                bar.set_postfix({problem.variable: f"{x:.5f}",
                                 "best": f"{best[1]:.4g}{ci} at {best[0]:.5f}",
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
    x_avg = float(np.mean(hist["x"][-average:])) if len(hist["x"]) else x
    optimum = None
    if hasattr(problem, "pooled") and len(hist["x"]):
        optimum = problem.pooled(x_avg)
    res = OptimizeResult(x=x_final, lz=float(problem.to_lz(x_final)),
                         value=float(hist["objective"][-1]) if len(hist["x"]) else float("nan"),
                         history=hist, reason=reason, sim_seconds=sim_total,
                         wall=time.perf_counter() - t_start, path=out, x_average=x_avg,
                         optimum=optimum)
    if h5 is not None:
        h5.attrs["status"] = "finished"
        h5.attrs["reason"] = reason
        result = {"x": res.x, "lz": res.lz, "objective": res.value, "x_average": x_avg,
                  "sim_seconds": res.sim_seconds, "wall_time": res.wall,
                  "iterations": len(hist["x"])}
        if optimum is not None:
            result.update(optimum=optimum.x, optimum_lo=optimum.lo, optimum_hi=optimum.hi,
                          optimum_se=optimum.se, optimum_interior=bool(optimum.interior))
        h5.attrs["result"] = json.dumps(result)
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
