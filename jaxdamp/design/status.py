"""Whether an optimiser's answer is an optimum: the one convergence rule of :mod:`jaxdamp.design`.

Every search reports a :class:`Status` — ``converged``, ``not converged`` or ``failed`` — with
the reason in words; ``jaxdamp optimize`` prints "optimum" only for a converged result, stores
the status in its log (:func:`jaxdamp.io.optimisation.write_status`) and exits with
:data:`EXIT_FAILED` for a failed one.

**The rule for gradient iterations** (:class:`ConvergenceRule`, used by
:func:`~jaxdamp.design.optimizer.optimize` and :func:`~jaxdamp.design.spsa.spsa`), checked at
every evaluated iterate ``x`` with gradient ``g`` (of the minimised objective; maximised ones
are negated) and its standard error ``s`` (0: exact, NaN: unknown), per component of ``x``:

1. **FAILED** — the objective or its gradient is not finite (no stable periodic orbit, a run
   that went non-finite): nothing after it can be trusted.
2. **on a bound** — ``x`` lies within ``xtol`` of a bound and ``−g`` points out of the feasible
   range (significantly, ``|g| > se_factor·s``, for an estimated gradient): the projected
   gradient is zero there, a constrained optimum (KKT).
3. **stationary** — every other component is stationary:

   * exact gradient (``s = 0``): the Newton distance to the stationary point, ``|g / H|`` with
     the curvature ``H`` from the secant of the last two iterates, is at most ``xtol`` and
     ``H`` has the sign of an optimum of the right kind (or ``g = 0``). The gradient tolerance
     is thus ``|H|·xtol``: the optimiser's own resolution of the design variable, in objective
     units — no scale of the objective is assumed;
   * estimated gradient (``s > 0``): ``|g| ≤ se_factor·s`` for ``patience`` consecutive
     iterates — the gradient cannot be told from zero; more iterates would only follow the
     noise (more replicates would narrow it);
   * no error estimate (``s`` NaN, e.g. one replicate): never stationary by the gradient.

Stopping for any other reason — the iteration cap, the budget, steps below ``xtol`` only
because the learning rate decayed — is **NOT CONVERGED**: the best iterate is reported as such,
not as an optimum.

**Searches without a gradient** (:func:`~jaxdamp.design.search.trust_region`,
:func:`~jaxdamp.design.search.adaptive_scan`) converge when their response surface locates an
interior optimum (narrower than the search's tolerance, or inside a stencil at the smallest
radius) or the best value sits on a bound with no interior optimum; a non-finite value is
FAILED, the round cap NOT CONVERGED. A Latin-hypercube sample is a sample: NOT CONVERGED.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

CONVERGED = "converged"
NOT_CONVERGED = "not converged"
FAILED = "failed"
STATES = (CONVERGED, NOT_CONVERGED, FAILED)
#: Exit status of ``jaxdamp optimize`` when its result FAILED: the command line's status for a
#: computation that went non-finite (:mod:`jaxdamp.cli`). Converged and NOT CONVERGED exit 0.
EXIT_FAILED = 3


@dataclass(frozen=True)
class Status:
    """``state`` (:data:`STATES`), ``reason`` in words, ``iterations`` evaluated."""

    state: str
    reason: str
    iterations: int = 0

    def __post_init__(self):
        if self.state not in STATES:
            raise ValueError(f"state = {self.state!r}: expected one of {STATES}")

    @property
    def converged(self) -> bool:
        return self.state == CONVERGED

    @property
    def failed(self) -> bool:
        return self.state == FAILED

    def headline(self) -> str:
        """``"converged"``, ``"NOT CONVERGED after N iterations"`` or ``"FAILED"``."""
        if self.state == CONVERGED:
            return "converged"
        if self.state == FAILED:
            return "FAILED"
        n = self.iterations
        return f"NOT CONVERGED after {n} iteration{'' if n == 1 else 's'}"

    def __str__(self) -> str:
        return f"{self.headline()}: {self.reason}"

    def as_dict(self) -> dict:
        return {"state": self.state, "reason": self.reason, "iterations": int(self.iterations)}


def non_finite(values) -> bool:
    """Whether any of ``values`` (scalars or arrays) is not finite."""
    return not all(np.all(np.isfinite(np.asarray(v, float))) for v in values)


class ConvergenceRule:
    """The convergence rule of gradient iterations (module doc), fed one iterate at a time.

    Args:
      lo, hi: bounds of the design variable(s) (scalars or ``(d,)``).
      xtol: resolution of the design variable: distance to a bound that counts as on it, and
        the largest Newton distance of a stationary point.
      maximise: the objective is maximised (its gradient is negated).
      patience: consecutive iterates of a not-significant estimated gradient.
      se_factor: ``|g| ≤ se_factor·s`` is not significant.
      names: the variables' names, for the reasons; unit: of the variables (e.g. ``"m"``).
    """

    def __init__(self, lo, hi, xtol: float, maximise: bool, patience: int = 3,
                 se_factor: float = 1.0, names=("x",), unit: str = ""):
        self.lo = np.atleast_1d(np.asarray(lo, float))
        self.hi = np.atleast_1d(np.asarray(hi, float))
        self.xtol = float(xtol)
        self.sign = -1.0 if maximise else 1.0
        self.patience = int(patience)
        self.se_factor = float(se_factor)
        self.names = tuple(names)
        self.unit = f" {unit}" if unit else ""
        self._previous = None
        self._quiet = 0

    def _name(self, i: int) -> str:
        return self.names[i] if i < len(self.names) else f"x[{i}]"

    def check(self, x, grad, grad_se) -> str:
        """The reason why the iterate ``x`` (with ``grad``, ``grad_se``) is an optimum by the
        rule, or ``""``. Call once per evaluated iterate, in order (the secant curvature and
        the patience count come from the previous calls). Non-finite input is the caller's
        FAILED (:func:`non_finite`)."""
        x = np.atleast_1d(np.asarray(x, float))
        q = self.sign * np.atleast_1d(np.asarray(grad, float))
        s = np.broadcast_to(np.atleast_1d(np.asarray(grad_se, float)), q.shape)
        previous, self._previous = self._previous, (x, q)
        exact = s == 0
        significant = exact | (np.abs(q) > self.se_factor * np.where(np.isnan(s), 0.0, s))
        at_lo = (x <= self.lo + self.xtol) & (q > 0) & significant
        at_hi = (x >= self.hi - self.xtol) & (q < 0) & significant
        active = at_lo | at_hi
        free = ~active
        edge = np.where(at_lo, self.lo, self.hi)
        bound = [f"{self._name(i)} on its {'lower' if at_lo[i] else 'upper'} bound "
                 f"{edge[i]:.5g}{self.unit} with the objective still improving beyond it (a "
                 "constrained optimum)" for i in np.flatnonzero(active)]
        if not free.any():
            self._quiet = 0
            return "; ".join(bound)
        noisy = free & ~exact
        if np.any(np.isnan(s[free])):
            self._quiet = 0
            return ""
        if noisy.any():
            quiet = np.all(np.abs(q[noisy]) <= self.se_factor * s[noisy])
            self._quiet = self._quiet + 1 if quiet else 0
            if self._quiet < self.patience:
                return ""
        stationary = []
        for i in np.flatnonzero(free & exact):
            if q[i] == 0:
                stationary.append(f"{self._name(i)}: gradient 0")
                continue
            if previous is None or previous[0][i] == x[i]:
                return ""
            H = (q[i] - previous[1][i]) / (x[i] - previous[0][i])
            distance = abs(q[i] / H) if H > 0 else math.inf
            if distance > self.xtol:
                return ""
            stationary.append(f"{self._name(i)}: gradient {self.sign * q[i]:.3g} and secant "
                              f"curvature {self.sign * H:.3g} put the stationary point "
                              f"{distance:.2g}{self.unit} away, within xtol = "
                              f"{self.xtol:g}{self.unit}")
        if noisy.any():
            stationary.append(f"gradient not significant (|g| ≤ {self.se_factor:g}·SE) for "
                              f"{self.patience} iterates: stationary within its noise")
        return "; ".join(bound + stationary)
