"""A design search that uses the batch: space-filling start, noise-aware Gaussian process, batched
Thompson sampling.

A DEM evaluation of a damper design is noisy (each bed is one realisation) and comes cheapest
in large batches: many designs × beds in one run. :func:`batch_search` spends a budget of such
batches on a :class:`~jaxdamp.design.space.DesignProblem` (or
:class:`~jaxdamp.design.envelope.EnvelopeProblem`: anything with ``space``, ``evaluate(X, R)
-> {"mean", "se", ...}``, ``objective.maximise`` and optionally ``feasible(x) -> (ok, ...)``):

1. **Start**: ``n_start`` designs of a scrambled Sobol sequence in the normalised coordinates
   ``u ∈ [0, 1]^d`` (projected onto the feasible set, :meth:`DesignSpace.project`; designs
   outside the budgets replaced by further Sobol points), each on ``replicates`` beds.
2. **Surrogate**: a Gaussian process on ``u`` (scikit-learn's ``GaussianProcessRegressor``:
   a constant × Matérn-5/2 kernel with one length scale per variable, plus a white-noise term
   for what the replicates do not show) with **heteroscedastic noise**: each design's squared
   standard error over its beds on the kernel's diagonal (``alpha``). Two or three beds give a
   poor variance; each is shrunk half-way to the pooled one, ``(s_i² + s̄²) / 2``.
3. **Batched acquisition**: ``batch`` draws of the posterior over ``candidates`` feasible
   Sobol points (and the designs already run); each draw's best point is a design of the next
   batch (batch Thompson sampling: a batch spread where the surrogate is uncertain or good,
   no hand-tuned exploration weight); duplicates give way to the upper confidence bound.
4. After ``rounds`` batches the **recommendation** is the run design of best posterior mean
   (not the best observed mean: a best-of-``n`` is biased, the winner's curse); a caller
   confirms it on fresh beds (:meth:`evaluate` again) before reporting it.
5. **Refinement where it matters** (:func:`refine`, one continuous variable): the trust region
   of :mod:`jaxdamp.design.search` from the recommendation — 3-point stencils pooled into a
   quadratic response surface, the radius halved once the optimum is inside — which ends with
   an optimum *and its 95 % interval* (jackknife over beds). The global surrogate finds the
   basin; the local quadratic, where the objective is smooth, locates the optimum within it.
   On the ``worst`` statistic the jackknife runs over each bed's worst point (the surface of
   ``E[min_p C_p]``, not of ``min_p E[C_p]``), and where the worst point changes inside the
   stencil the objective has a kink a quadratic does not follow: read its interval with that
   in mind.

Why a library: scikit-learn's Gaussian process is a maintained implementation (kernel
hyper-parameters by maximum marginal likelihood with restarts, per-point noise, posterior
draws); what it costs here is milliseconds per fit at the tens of designs a DEM budget buys.
Its search is measured against the equal-budget Latin hypercube
(:func:`jaxdamp.design.spsa.random_search`) on a known noisy function in
``experiments/envelope_design.py`` (part C) and ``tests/test_envelope.py``.

Example (a noisy 1-D problem with its optimum at x = 0.3)::

    >>> import numpy as np
    >>> from jaxdamp.design.bayes import batch_search, ToyProblem
    >>> res = batch_search(ToyProblem(lambda u: -(u[:, 0] - 0.3) ** 2, noise=0.01),
    ...                    n_start=6, batch=3, rounds=3, replicates=2, seed=1)
    >>> abs(float(res.best_x[0]) - 0.3) < 0.1
    True
"""

from __future__ import annotations

import time
import warnings
from dataclasses import dataclass, field

import numpy as np

from jaxdamp.analysis.stats import t_quantile
from jaxdamp.analysis.uncertainty import standard_error
from jaxdamp.config import ConfigError
from jaxdamp.design.status import FAILED, NOT_CONVERGED, Status

#: Lower bound of each normalised length scale and the noise floor (in units of the
#: objective's spread): keeps the fit away from interpolating a noisy design exactly.
LENGTH_BOUNDS = (0.03, 10.0)
NOISE_FLOOR = 1e-6


@dataclass
class BatchSearchResult:
    """``best_x``/``best_u`` the recommended design (physical / normalised), ``best_pred`` and
    ``best_pred_sd`` the surrogate's mean and sd there; ``X``, ``U``, ``mean``, ``se`` every
    evaluated design in order with its mean ± SE over its beds, ``round_of`` its batch
    (0: the start); ``evaluations``: each batch's full ``evaluate`` output; ``kernel``: the
    last fit's kernel; ``sim_seconds``, ``wall``."""

    best_x: np.ndarray
    best_u: np.ndarray
    best_pred: float
    best_pred_sd: float
    X: np.ndarray
    U: np.ndarray
    mean: np.ndarray
    se: np.ndarray
    round_of: np.ndarray
    kernel: str
    sim_seconds: float
    wall: float
    evaluations: list = field(default_factory=list)
    status: Status | None = None


def _gp(U, y, se, seed):
    """The fitted Gaussian process of module doc item 2 and the scale ``(mean, sd)`` of ``y``."""
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import ConstantKernel, Matern, WhiteKernel

    mu, sd = float(np.mean(y)), float(np.std(y)) or 1.0
    yn = (y - mu) / sd
    s2 = (np.asarray(se, float) / sd) ** 2
    pooled = np.nanmean(s2) if np.isfinite(s2).any() else 0.0
    alpha = np.where(np.isfinite(s2), 0.5 * (s2 + pooled), pooled) + NOISE_FLOOR
    d = U.shape[1]
    kernel = (ConstantKernel(1.0, (1e-2, 1e2)) * Matern(np.full(d, 0.3), LENGTH_BOUNDS, nu=2.5)
              + WhiteKernel(1e-3, (NOISE_FLOOR, 1.0)))
    gp = GaussianProcessRegressor(kernel, alpha=alpha, normalize_y=False,
                                  n_restarts_optimizer=4, random_state=seed)
    with warnings.catch_warnings():  # a bound reached by a hyper-parameter is reported, not fatal
        warnings.simplefilter("ignore")
        gp.fit(U, yn)
    return gp, mu, sd


def _feasible_sobol(space, problem, n, sampler):
    """``n`` feasible points of the Sobol ``sampler``: points the projection would move (a bed
    that does not fit) or outside a budget are skipped, so the points stay spread over the
    feasible set instead of piling onto its edge; after many skips the projected point is
    taken."""
    out, tries = [], 0
    while len(out) < n:
        tries += 1
        if tries > 50 * n + 100:
            raise ConfigError("the design search found no feasible design in its range within "
                              "the budgets: widen the bounds or the budgets")
        raw = sampler.random(1)[0]
        u = space.project(raw)
        if not np.allclose(u, raw) and tries < 20 * n + 50:
            continue
        if hasattr(problem, "feasible") and not problem.feasible(space.to_x(u))[0]:
            continue
        out.append(u)
    return np.asarray(out)


def batch_search(problem, n_start: int = 8, batch: int = 4, rounds: int = 3,
                 replicates: int = 2, seed: int = 0, candidates: int = 512,
                 progress=None) -> BatchSearchResult:
    """Spend ``n_start + rounds × batch`` designs × ``replicates`` beds on ``problem``
    (module doc). ``progress``: a callable taking one line per batch, or ``None``."""
    from scipy.stats import qmc

    if n_start < 2 or batch < 1 or rounds < 0 or replicates < 1 or candidates < batch:
        raise ConfigError(f"batch search: n_start = {n_start} (≥ 2), batch = {batch} (≥ 1), "
                          f"rounds = {rounds} (≥ 0), replicates = {replicates} (≥ 1), "
                          f"candidates = {candidates} (≥ batch)")
    t0 = time.perf_counter()
    space = problem.space
    sign = 1.0 if problem.objective.maximise else -1.0
    sampler = qmc.Sobol(space.dim, scramble=True, seed=seed)
    U = _feasible_sobol(space, problem, n_start, sampler)
    mean, se, rnd, evals = [], [], [], []
    sim0 = getattr(problem, "sim_seconds", 0.0)

    def run(Ub, r):
        ev = problem.evaluate(space.to_x(Ub), replicates)
        evals.append(ev)
        mean.extend(np.asarray(ev["mean"], float))
        se.extend(np.asarray(ev["se"], float))
        rnd.extend([r] * len(Ub))
        if progress is not None:
            progress(f"batch {r}: {len(Ub)} designs × {replicates} beds, best mean "
                     f"{(max if sign > 0 else min)(ev['mean']):.4g}")

    run(U, 0)
    gp = None
    for r in range(1, rounds + 1):
        y = sign * np.asarray(mean)
        gp, mu, sd = _gp(U, y, np.asarray(se), seed + r)
        cand = np.vstack([_feasible_sobol(space, problem, candidates, sampler), U])
        draws = gp.sample_y(cand, batch, random_state=seed + 1000 + r)  # (candidates, batch)
        m, s = gp.predict(cand, return_std=True)
        ucb = np.argsort(-(m + 2.0 * s))
        chosen: list = []
        for k in range(batch):
            i = int(np.argmax(draws[:, k]))
            if any(np.allclose(cand[i], c) for c in chosen):  # a repeat: the next UCB point
                i = next(int(j) for j in ucb if not any(np.allclose(cand[j], c) for c in chosen))
            chosen.append(cand[i])
        Ub = np.asarray(chosen)
        run(Ub, r)
        U = np.vstack([U, Ub])
    if not np.isfinite(mean).all():
        bad = int((~np.isfinite(mean)).sum())
        return BatchSearchResult(
            best_x=space.to_x(U[0]), best_u=U[0], best_pred=np.nan, best_pred_sd=np.nan,
            X=space.to_x(U), U=U, mean=np.asarray(mean), se=np.asarray(se),
            round_of=np.asarray(rnd), kernel="", wall=time.perf_counter() - t0,
            sim_seconds=getattr(problem, "sim_seconds", 0.0) - sim0, evaluations=evals,
            status=Status(FAILED, f"{bad} design(s) with a non-finite objective", rounds + 1))
    y = sign * np.asarray(mean)
    gp, mu, sd = _gp(U, y, np.asarray(se), seed + rounds + 1)
    m, s = gp.predict(U, return_std=True)
    best = int(np.argmax(m))
    status = Status(NOT_CONVERGED, f"a budget of {len(U)} designs in {rounds + 1} batches "
                    "(no convergence test): the surrogate's best run design is a candidate, "
                    "to be confirmed on fresh beds", rounds + 1)
    return BatchSearchResult(
        best_x=space.to_x(U[best]), best_u=U[best], best_pred=float(sign * (mu + sd * m[best])),
        best_pred_sd=float(sd * s[best]), X=space.to_x(U), U=U, mean=np.asarray(mean),
        se=np.asarray(se), round_of=np.asarray(rnd), kernel=str(gp.kernel_),
        sim_seconds=getattr(problem, "sim_seconds", 0.0) - sim0,
        wall=time.perf_counter() - t0, evaluations=evals, status=status)


def refine(problem, result: BatchSearchResult, replicates: int = 2, radius: float | None = None,
           min_radius: float | None = None, tol: float | None = None, max_rounds: int = 4,
           echo=None):
    """Module doc item 5: :func:`jaxdamp.design.search.trust_region` on ``problem`` (one
    continuous variable; its :meth:`~jaxdamp.design.space.DesignProblem.scan` on
    ``replicates`` fresh beds per design) from ``result``'s recommendation, over the feasible
    range. ``radius``, ``min_radius``, ``tol`` default to 5 %, 1.25 % and 1 % of that range.
    Returns the trust region's :class:`~jaxdamp.design.search.SearchResult` (its ``optimum``
    with the interval)."""
    from jaxdamp.design.search import trust_region

    space = problem.space
    if space.dim != 1 or any(v.kind != "real" for v in getattr(space, "variables", ())):
        raise ConfigError(f"refine: one continuous design variable (the space has "
                          f"{', '.join(space.names)}); with several, confirm the recommendation")
    lo = float(space.to_x(space.project(np.zeros(1)))[0])
    hi = float(space.hi[0])
    span = hi - lo
    problem.scan_replicates = int(replicates)
    return trust_region(problem, float(result.best_x[0]), lo, hi,
                        radius=radius or 0.05 * span, min_radius=min_radius or 0.0125 * span,
                        tol=tol or 0.01 * span, max_rounds=max_rounds, echo=echo)


class _UnitSpace:
    """The unit box ``[0, 1]^d`` as a design space (for :class:`ToyProblem`)."""

    def __init__(self, d):
        self.dim = d
        self.names = tuple(f"u{i}" for i in range(d))
        self.lo, self.hi = np.zeros(d), np.ones(d)

    def to_x(self, u):
        return np.asarray(u, float)

    def to_u(self, x):
        return np.asarray(x, float)

    def project(self, u):
        return np.clip(np.asarray(u, float), 0.0, 1.0)


class ToyProblem:
    """A known function ``f(u)`` of the unit box (maximised), observed on ``replicates``
    "beds" with Gaussian noise of sd ``noise × (1 + hetero × u_0)``: the searches' test bed
    (docs and ``tests/test_bayes.py``). ``sim_seconds`` counts evaluations."""

    def __init__(self, f, d: int = 1, noise: float = 0.1, hetero: float = 0.0, seed: int = 0):
        from jaxdamp.design.objectives import Objective

        self.f, self.noise, self.hetero = f, float(noise), float(hetero)
        self.space = _UnitSpace(d)
        self.objective = Objective("damping")  # maximised
        self.rng = np.random.default_rng(seed)
        self.sim_seconds = 0.0

    def evaluate(self, X, replicates):
        X = np.atleast_2d(np.asarray(X, float))
        true = np.asarray(self.f(X), float)
        sdv = self.noise * (1.0 + self.hetero * X[:, 0])
        J = true[:, None] + sdv[:, None] * self.rng.standard_normal((len(X), replicates))
        self.sim_seconds += len(X) * replicates
        se = standard_error(J, axis=1)  # NaN with one replicate
        half = t_quantile(0.975, replicates - 1) * se if replicates > 1 else se
        return {"mean": J.mean(axis=1), "se": se, "ci95": half, "J": J,
                "sim_seconds": float(len(X) * replicates)}

    def cost_per_system(self) -> float:
        """One "system-second" per design and replicate (the random search's budget)."""
        return 1.0

    scan_replicates = 2

    def scan(self, xs):
        """One variable: ``(mean, se, J)`` of ``xs`` on :attr:`scan_replicates` replicates."""
        ev = self.evaluate(np.asarray(xs, float)[:, None], self.scan_replicates)
        return ev["mean"], ev["se"], ev["J"]
