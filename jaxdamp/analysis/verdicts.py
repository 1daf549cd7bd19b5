"""A verdict that follows from its interval: the one rule of the scoreboard
(``experiments/README.md``, records in ``experiments/scoreboard/``).

A claim of a source is tested by one or more **checks**. A check compares our estimate ``x``
(a mean over ``n`` independent realisations with standard error ``s``) with a value ``y``
(the source's number, or a reference such as 0 for a difference) in one of five ways:

* ``equal`` — the source gives a number: **pass** if ``|x − y| ≤ k u``, else **fail**;
* ``above`` / ``below`` — the claim is a direction (``x > y`` / ``x < y``): **pass** if the
  interval ``x ± k u`` lies wholly on the claimed side of ``y``, **fail** if wholly on the
  other, else **undecided** (the interval cannot tell);
* ``equivalent`` — the source says "unchanged" or "independent": two one-sided tests at 5 %
  each against the margin ``m`` (:func:`equivalence_margin`): **pass** if
  ``|x − y| + t₀.₉₅ s ≤ m``, **fail** if ``|x − y| − t₀.₉₅ s > m`` (the difference exceeds
  the margin significantly), else **undecided**. The margin is the systematic allowance, so
  here ``s`` is the statistical error alone;
* ``bounded`` — a deterministic computation against a stated tolerance ``tol``: **pass** if
  ``|x − y| ≤ tol``, else **fail``.

For ``equal``, ``above`` and ``below`` the uncertainty combines, in quadrature (GUM), the
statistical error ``s``, the systematic budget ``r × |level|`` (``r``: the relative standard
uncertainty of :mod:`experiments.systematics` at the row's calibrated point; ``level``: the
size of the compared quantity, ``|x|`` unless stated) and the source's own standard uncertainty
``u_y`` (its printed precision or scatter): ``u = sqrt(s² + (r level)² + u_y²)``. The coverage
factor ``k = t₀.₉₇₅(ν)`` uses the Welch–Satterthwaite degrees of freedom ``ν = u⁴ / (s⁴ /
(n − 1))`` (the systematic and source terms taken as exactly known). A check of one run
(``n < 2``) has no statistical error: it is decided on ``u`` without ``s`` (``k = 2``), and
the row it belongs to cannot be "reproduced". ``n ≥ 2`` beds that all gave the same value
(``s = 0``) are replicated: ``k = 1.96`` on the remaining terms.

A row's verdict follows from its checks (:func:`row_verdict`):

* **reproduced** — every check passes, each over ≥ 2 independent realisations, and the checks
  cover the whole claim;
* **partly** — some pass and some fail or are undecided; or all pass but part of the claim is
  untested (``complete = false``), or a check rests on one run ("partly (no error bar)"), or
  the row is a deterministic computation or an input ("partly (deterministic)", which cannot be
  replicated);
* **not reproduced** — no check passes and at least one fails;
* **undecided** — every check is undecided: the runs are too short or too few to tell;
* **not comparable** — the source gives nothing to set against ours (a lost figure, cited
  literature, another quantity or criterion).

Rows of kind ``method`` (checks of our own optimiser, not claims of a source) get **pass** /
**fail** / **undecided** by the same checks and are tallied apart.

Example::

    c = Check(test="equal", estimate=2.362, se=0.0003, n=3, target=2.37)
    outcome(c, systematic=0.03).result   # 'pass': 0.3 % from M within a 3 % budget
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from jaxdamp.analysis.stats import t_quantile

TESTS = ("equal", "above", "below", "equivalent", "bounded")
KINDS = ("claim", "input", "deterministic", "not comparable", "method")
VERDICTS = ("reproduced", "partly", "not reproduced", "undecided", "not comparable")
METHOD_VERDICTS = ("pass", "fail", "undecided")


@dataclass(frozen=True)
class Check:
    """One comparison of a row (see the module's docstring for the tests).

    Attributes:
      test: one of :data:`TESTS`.
      estimate: our value ``x``.
      se: its standard error over ``n`` independent realisations (0 for one run).
      n: the number of independent realisations.
      target: the value compared with ``y`` (the source's number, or 0 for a difference).
      target_u: the source's own standard uncertainty ``u_y``.
      level: the size the relative systematic acts on (default ``|estimate|``; for a
        difference of two of our values, their size, not the difference's).
      margin: ``equivalent`` only: the margin, absolute (default: :func:`equivalence_margin`
        of ``level``).
      tol: ``bounded`` only: the tolerance.
      systematics: the calibrated point whose budget applies (``thesis_optimum``,
        ``paper_reference``, ``far`` — the larger of the two — or ``none``).
      what: a short label.
    """

    test: str
    estimate: float
    se: float = 0.0
    n: int = 1
    target: float = 0.0
    target_u: float = 0.0
    level: float | None = None
    margin: float | None = None
    tol: float | None = None
    systematics: str = "none"
    what: str = ""

    def __post_init__(self):
        if self.test not in TESTS:
            raise ValueError(f"check {self.what!r}: test = {self.test!r}; one of {TESTS}")
        if self.test == "bounded" and self.tol is None:
            raise ValueError(f"check {self.what!r}: a 'bounded' check needs tol")
        if self.se < 0 or self.n < 1:
            raise ValueError(f"check {self.what!r}: se = {self.se} must be ≥ 0 and n = "
                             f"{self.n} ≥ 1")


@dataclass(frozen=True)
class Outcome:
    """A check's result: ``result`` (``pass``/``fail``/``undecided``), the difference
    ``d = x − y``, the combined standard uncertainty ``u``, the half-width ``h`` of the
    interval used (95 % two-sided, or the TOST 90 % one), the margin ``m`` (``equivalent``),
    and whether it rests on replicates (``replicated``)."""

    result: str
    d: float
    u: float
    h: float
    m: float | None = None
    replicated: bool = True
    notes: tuple = field(default_factory=tuple)


#: The smallest relative equivalence margin (1 %): below it no DEM protocol of ours is
#: calibrated (the thesis point's time-step and run-length terms are each ~1 %).
MIN_MARGIN = 0.01


def equivalence_margin(level: float, systematic: float, source_scatter: float = 0.0) -> float:
    """The margin of an equivalence test, fixed before any row is re-derived: the larger of the
    systematic budget and the source's own relative scatter, times the compared size
    ``level`` — ``max(systematic, source_scatter) × |level|``, and never below
    :data:`MIN_MARGIN` of it."""
    return max(systematic, source_scatter, MIN_MARGIN) * abs(level)


def outcome(c: Check, systematic: float = 0.0, source_scatter: float = 0.0) -> Outcome:
    """Decide one check (module docstring). ``systematic``: the relative standard uncertainty
    of the check's calibrated point; ``source_scatter``: the source's relative scatter (the
    equivalence margin's other candidate)."""
    d = float(c.estimate) - float(c.target)
    level = abs(c.estimate) if c.level is None else abs(c.level)
    replicated = c.n >= 2  # identical values over n beds (se = 0) are still replicated
    if c.test == "bounded":
        return Outcome("pass" if abs(d) <= c.tol else "fail", d, 0.0, float(c.tol),
                       replicated=False)
    if c.test == "equivalent":
        m = c.margin if c.margin is not None else equivalence_margin(
            level, systematic, source_scatter)
        if not replicated:
            return Outcome("pass" if abs(d) <= m else "fail", d, 0.0, 0.0, m, False)
        h = t_quantile(0.95, c.n - 1) * c.se  # 0 where every bed gave the same value
        result = ("pass" if abs(d) + h <= m else "fail" if abs(d) - h > m else "undecided")
        return Outcome(result, d, c.se, h, m, True)
    u_sys = systematic * level
    u = math.sqrt(c.se ** 2 + u_sys ** 2 + c.target_u ** 2)
    if replicated and c.se > 0:
        nu = u ** 4 / (c.se ** 4 / (c.n - 1))
        k = t_quantile(0.975, max(nu, 1.0))
    elif replicated:  # no spread over the beds: only the exactly known terms remain
        k = t_quantile(0.975, 1e9)
    else:
        k = 2.0
    h = k * u
    if c.test == "equal":
        result = "pass" if abs(d) <= h else "fail"
    else:
        sign = 1.0 if c.test == "above" else -1.0
        result = ("pass" if sign * d - h > 0 else "fail" if sign * d + h < 0 else "undecided")
    return Outcome(result, d, u, h, None, replicated)


def row_verdict(kind: str, outcomes: list[Outcome], complete: bool = True) -> str:
    """A row's verdict from its checks' outcomes (module docstring). ``kind``: one of
    :data:`KINDS`; ``complete``: whether the checks cover the whole claim."""
    if kind not in KINDS:
        raise ValueError(f"kind = {kind!r}; one of {KINDS}")
    if kind == "not comparable":
        return "not comparable"
    results = [o.result for o in outcomes]
    if kind == "method":
        if not results:
            raise ValueError("a method row needs at least one check")
        return ("fail" if "fail" in results else "pass" if all(r == "pass" for r in results)
                else "undecided")
    if kind in ("input", "deterministic"):
        return "not reproduced" if "fail" in results else "partly (deterministic)"
    if not results:
        raise ValueError("a claim row needs at least one check (or kind 'not comparable')")
    if all(r == "pass" for r in results):
        if not all(o.replicated for o in outcomes):
            return "partly (no error bar)"
        return "reproduced" if complete else "partly"
    one_run = not all(o.replicated for o in outcomes)
    if all(r == "undecided" for r in results):
        return "undecided"
    if "pass" not in results:
        return "not reproduced (single run)" if one_run else "not reproduced"
    return "partly (no error bar)" if one_run else "partly"


def base_verdict(verdict: str) -> str:
    """The tally's column of a verdict: ``partly (no error bar)`` → ``partly``."""
    return verdict.split(" (")[0]
