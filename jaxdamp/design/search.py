"""Batched searches for the optimum of one design variable, with confidence intervals.

Two methods share the problems' ``scan(xs) -> (mean, se, J)`` (every point of ``xs`` and every
replicate in one batch) and the response surface of :mod:`jaxdamp.design.surface`:

* :func:`adaptive_scan` — the baseline: a coarse batch over ``[lo, hi]``, then a finer batch
  inside the bracket around the best coarse point, and the quadratic optimum of the points in
  the bracket with its jackknife interval.
* :func:`trust_region` — a local search from a starting point (ideally the single-particle
  model's optimum, :func:`jaxdamp.design.surrogate.propose`: the multi-fidelity path): a
  3-point stencil of radius ``r`` around the centre, the quadratic optimum of every evaluated
  point within ``2r`` (all evaluations are pooled and reused), a move to it (at most ``2r``),
  and the radius halved once the optimum lies inside the stencil; it stops when the interval is
  narrower than ``tol`` or the radius below ``min_radius``.

Both report the optimum, its interval, every evaluated point, the simulated system-seconds
and the status by the convergence rule (:mod:`jaxdamp.design.status`): converged when the
response surface locates an interior optimum (scan; trust region: narrower than ``tol``, or
inside the stencil at the smallest radius) or the best value sits on a bound with no interior
optimum; FAILED on a value that is not finite; NOT CONVERGED otherwise (the trust region's
round cap, a scan's quadratic without an interior optimum).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.design.status import CONVERGED, FAILED, NOT_CONVERGED, Status, non_finite
from jaxdamp.design.surface import Optimum, quadratic_optimum


def scan_points(problem, xs):
    """``(mean (L,), se (L,), J (L, R))`` of ``problem`` at ``xs``; deterministic problems
    (a ``scan`` returning values only) get ``se = 0`` and ``R = 1``."""
    out = problem.scan(np.asarray(xs, float))
    if isinstance(out, tuple):
        return out
    v = np.asarray(out, float)
    return v, np.zeros_like(v), v[:, None]


@dataclass
class SearchResult:
    """``optimum`` (:class:`~jaxdamp.design.surface.Optimum`, design variable [m]); ``x``,
    ``mean``, ``se`` ``(n,)`` and ``J`` ``(n, R)``: every evaluated point in evaluation order;
    ``sim_seconds`` simulated system-seconds; ``wall`` [s]; ``at_bound``: the best point lies on
    a bound of the range (no interior optimum found there); ``rounds``: per-round log;
    ``status`` (:class:`~jaxdamp.design.status.Status`, iterations = rounds)."""

    optimum: Optimum
    x: np.ndarray
    mean: np.ndarray
    se: np.ndarray
    J: np.ndarray
    sim_seconds: float
    wall: float
    at_bound: bool
    method: str
    rounds: list = field(default_factory=list)
    status: Status | None = None


class _Pool:
    def __init__(self, problem):
        self.problem = problem
        self.x, self.J = [], []
        self.sim0 = getattr(problem, "sim_seconds", 0.0)
        self.sim = 0.0

    def add(self, xs):
        xs = [float(v) for v in xs if not any(abs(v - y) < 1e-9 for y in self.x)]
        if not xs:
            return
        before = getattr(self.problem, "sim_seconds", None)
        _, _, J = scan_points(self.problem, xs)
        if before is not None:
            self.sim += self.problem.sim_seconds - before
        else:  # deterministic S3 problem: one run per point and frequency
            self.sim += len(xs) * getattr(self.problem, "duration", 0.0) * len(self.problem.freqs)
        self.x.extend(xs)
        self.J.extend(list(np.asarray(J, float)))

    def arrays(self):
        x = np.asarray(self.x)
        J = np.asarray(self.J)
        R = J.shape[1]
        se = standard_error(J, axis=1) if R > 1 else np.zeros(len(x))
        return x, J.mean(axis=1), se, J

    def within(self, lo, hi):
        x, _, _, J = self.arrays()
        sel = (x >= lo - 1e-12) & (x <= hi + 1e-12)
        order = np.argsort(x[sel])
        return x[sel][order], J[sel][order]


def _result(pool, opt, t0, at_bound, method, rounds, state, reason):
    x, m, se, J = pool.arrays()
    if non_finite([J]) or opt is None or non_finite([opt.x, opt.value]):
        bad = x[~np.all(np.isfinite(J), axis=1)]
        var = getattr(pool.problem, "variable", "x")
        state, reason = FAILED, (f"non-finite objective at {var} = "
                                 + ", ".join(f"{v:.5g}" for v in bad) + " m" if len(bad) else
                                 "the response surface is not finite")
    return SearchResult(opt, x, m, se, J, pool.sim, time.perf_counter() - t0, at_bound, method,
                        rounds, Status(state, reason, max(len(rounds), 1)))


def _bound_reason(problem, opt, lo, hi) -> str:
    side = "lower" if abs(opt.x - lo) <= abs(opt.x - hi) else "upper"
    return (f"{problem.variable} on its {side} bound {lo if side == 'lower' else hi:.5g} m "
            "with no interior optimum: the objective improves up to the bound (a constrained "
            "optimum)")


def adaptive_scan(problem, lo: float, hi: float, n_coarse: int = 6, n_fine: int = 4,
                  echo=None) -> SearchResult:
    """Coarse batch of ``n_coarse`` points over ``[lo, hi]``, then ``n_fine`` more inside the
    bracket of the best one, and the quadratic optimum over the bracket (module doc)."""
    t0 = time.perf_counter()
    maximise = problem.objective.maximise
    pool = _Pool(problem)
    grid = np.linspace(lo, hi, n_coarse)
    pool.add(grid)
    x, m, _, _ = pool.arrays()
    if non_finite([m]):
        return _result(pool, None, t0, False, "adaptive scan", [], FAILED, "")
    k = int(np.argmax(m) if maximise else np.argmin(m))
    at_bound = k in (0, len(grid) - 1)
    a, b = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    if at_bound:  # bracket the edge with its neighbour and one more point
        a, b = (grid[0], grid[2]) if k == 0 else (grid[-3], grid[-1])
    rounds = [dict(points=list(map(float, grid)), best=float(grid[k]))]
    if echo:
        echo(f"coarse scan: best {problem.variable} = {grid[k]:.5g} m"
             + (" (on the bound)" if at_bound else ""))
    fine = np.linspace(a, b, n_fine + 2)[1:-1]
    pool.add(fine)
    rounds.append(dict(points=list(map(float, fine))))
    if non_finite([pool.arrays()[1]]):
        return _result(pool, None, t0, at_bound, "adaptive scan", rounds, FAILED, "")
    xs, J = pool.within(a, b)
    opt = quadratic_optimum(xs, J, maximise)
    if opt.interior:
        state, reason = CONVERGED, (f"interior optimum of the quadratic through the "
                                    f"{len(xs)} points of the bracket [{a:.5g}, {b:.5g}] m")
    elif at_bound:
        state, reason = CONVERGED, _bound_reason(problem, opt, lo, hi)
    else:
        state, reason = NOT_CONVERGED, ("the quadratic through the bracket has no interior "
                                        "optimum (wrong curvature or vertex outside)")
    return _result(pool, opt, t0, at_bound, "adaptive scan", rounds, state, reason)


def trust_region(problem, x0: float, lo: float, hi: float, radius: float = 0.01,
                 min_radius: float = 0.0025, tol: float = 0.003, max_rounds: int = 6,
                 echo=None) -> SearchResult:
    """Local stencil search with a pooled quadratic response surface (module doc).

    Args:
      x0: starting point [m] (e.g. the surrogate's proposal).
      lo, hi: feasible range [m].
      radius: initial stencil half-width [m].
      min_radius: stop once the radius is below this [m].
      tol: stop once the optimum's 95 % interval half-width is below this [m] (and the
        optimum is interior).
      max_rounds: most stencil rounds.
    """
    t0 = time.perf_counter()
    maximise = problem.objective.maximise
    pool = _Pool(problem)
    x, r = float(np.clip(x0, lo, hi)), float(radius)
    rounds, opt, at_bound = [], None, False
    state, reason = NOT_CONVERGED, f"max_rounds = {max_rounds} reached"
    for it in range(max_rounds):
        c = float(np.clip(x, lo + r, hi - r)) if hi - lo > 2 * r else 0.5 * (lo + hi)
        pool.add([c - r, c, c + r])
        if non_finite([pool.arrays()[1]]):
            return _result(pool, opt, t0, at_bound, "trust region", rounds, FAILED, "")
        xs, J = pool.within(c - 2 * r, c + 2 * r)
        opt = quadratic_optimum(xs, J, maximise)
        move = float(np.clip(opt.x, c - 2 * r, c + 2 * r)) if opt.interior else (
            float(xs[int(np.argmax(J.mean(1)) if maximise else np.argmin(J.mean(1)))]))
        if not opt.interior:  # no curvature yet: step towards the best point, keep the radius
            best = move
            move = float(np.clip(best + (best - c), lo, hi)) if best != c else c
        at_bound = (move <= lo + 1e-9) or (move >= hi - 1e-9)
        rounds.append(dict(centre=c, radius=r, optimum=opt.x, lo=opt.lo, hi=opt.hi,
                           interior=opt.interior, points=len(xs)))
        if echo:
            echo(f"round {it}: centre {c:.5g} m, radius {r:.3g} m -> optimum {opt.x:.5g} m "
                 f"[{opt.lo:.5g}, {opt.hi:.5g}]" + ("" if opt.interior else " (not interior)"))
        inside = opt.interior and abs(opt.x - c) <= r
        x = float(np.clip(move, lo, hi))
        if inside and opt.halfwidth <= tol:
            state, reason = CONVERGED, (
                f"the optimum's 95 % interval half-width {opt.halfwidth:.2g} m is within "
                f"tol = {tol:g} m, inside the stencil" if opt.replicates >= 2 else
                "the optimum lies inside the stencil (one realisation: no interval)")
            break
        if inside:
            r *= 0.5
            if r < min_radius:
                state, reason = CONVERGED, (f"the optimum lies inside the stencil at the "
                                            f"smallest radius (< {min_radius:g} m)")
                break
        if at_bound and not opt.interior:
            state, reason = CONVERGED, _bound_reason(problem, opt, lo, hi)
            break
    xs, J = pool.within(x - 2 * r, x + 2 * r)
    if len(xs) >= 3:
        opt = quadratic_optimum(xs, J, maximise)
    return _result(pool, opt, t0, at_bound, "trust region", rounds, state, reason)
