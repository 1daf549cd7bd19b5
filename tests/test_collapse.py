"""Inelastic collapse of two particles at a wall (thesis §5.2, fig. 5.1): the event-driven
sequence with the S3 collision rule against the analytic cycle map."""

import math

import numpy as np
import pytest

from jaxdamp.s3.collapse import E_CRITICAL, collapse_sequence, critical_restitution, cycle_ratio


@pytest.mark.parametrize("e", [0.01, 0.05, 0.1, 0.15])
def test_cycle_durations_shrink_by_the_eigenvalue_ratio(e):
    """Below e_c the collisions never stop; successive wall-to-wall cycles shrink by
    λ₂/λ₁ of the cycle map to 1e-4 relative, and t∞ extrapolated from a late cycle with that
    ratio is the time of the last event to 1e-9 relative."""
    s = collapse_sequence(e)
    assert s.outcome == "collapsed"
    r = cycle_ratio(e)
    assert s.ratio == pytest.approx(r, rel=1e-4)
    tw = s.wall_times
    k = len(tw) // 3  # a late, well-resolved cycle
    t_inf = tw[k] + (tw[k] - tw[k - 1]) * r / (1 - r)
    assert t_inf == pytest.approx(s.t_end, rel=1e-9)
    # the kinds alternate wall, pair, wall, ... for ever
    assert np.all(s.kind[::2] == "W") and np.all(s.kind[1::2] == "P")


@pytest.mark.parametrize("e, tol", [(0.01, 1e-4), (0.05, 3e-3), (0.1, 2e-2)])
def test_thesis_formula_holds_for_small_restitution(e, tol):
    """t∞ − t₀ = (t₂ − t₀)/(1 − 4e²) (thesis, for e ≪ 1): within 0.01 % at e = 0.01, 0.3 %
    at 0.05 and 2 % at 0.1 (measured: 8e-6, 1.2e-3, 1.3e-2)."""
    s = collapse_sequence(e)
    t2 = s.wall_times[1]
    assert t2 / (1 - 4 * e * e) == pytest.approx(s.t_end, rel=tol)
    assert cycle_ratio(e) == pytest.approx(4 * e * e, rel=10 * e)  # λ₂/λ₁ = 4e² (1 + O(e))


def test_critical_restitution_is_three_minus_two_root_two():
    """Bisection on the simulated outcome finds e_c = 3 − 2√2 to 1e-5; just above it the
    particles escape after finitely many collisions."""
    assert critical_restitution(tol=1e-6) == pytest.approx(E_CRITICAL, abs=1e-5)
    above = collapse_sequence(E_CRITICAL + 1e-3)
    assert above.outcome == "escaped" and math.isnan(cycle_ratio(E_CRITICAL + 1e-3))
    assert above.v2[-1] >= above.v1[-1] >= 0  # both move away, the far one faster


def test_bad_restitution_is_refused():
    with pytest.raises(ValueError, match="restitution"):
        collapse_sequence(1.0)
