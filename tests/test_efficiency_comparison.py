"""Two families compared across their beds and each bed's optimal amplitude
(:mod:`jaxdamp.studies.efficiency`: ``compare_beds``, ``optimal_amplitudes``), on answers
known in advance."""

import math

import numpy as np
import pytest

from jaxdamp.analysis.stats import t_quantile
from jaxdamp.studies.efficiency import compare_beds, optimal_amplitudes


def test_compare_beds_ratio_difference_and_verdicts():
    """Ratio of means with the delta-method SE, the Welch difference and its verdict."""
    c = compare_beds([2.0, 2.2, 2.1, np.nan], [1.0, 1.1, 1.2])  # NaN: a bed left out
    se = 0.1 / math.sqrt(3)  # both samples: s = 0.1, n = 3
    assert c.ratio == pytest.approx(2.1 / 1.1, rel=1e-12)
    assert c.ratio_se == pytest.approx(2.1 / 1.1 * math.hypot(se / 2.1, se / 1.1), rel=1e-12)
    assert c.diff == pytest.approx(1.0, rel=1e-12)
    # equal variances and counts: Welch's dof is 2 (n − 1) = 4
    assert c.half == pytest.approx(t_quantile(0.975, 4) * math.sqrt(2) * se, rel=1e-9)
    assert c.verdict == "above"
    assert compare_beds([1.0, 1.1, 1.2], [2.0, 2.2, 2.1]).verdict == "below"
    assert compare_beds([1.0, 1.2, 1.1], [1.05, 1.15, 1.1]).verdict == "not significant"
    one = compare_beds([1.0], [1.0, 2.0])
    assert one.verdict == "undetermined" and one.diff == pytest.approx(-0.5)
    ratio, ratio_se, diff, half, verdict = c  # unpacks as a tuple
    assert verdict == "above"


def test_optimal_amplitudes_is_each_beds_parabola_vertex():
    """Exact on parabolas; the end sample at the range's edge; NaN for a bed with a NaN and
    for every bed with fewer than 3 amplitudes."""
    A = np.round(np.linspace(0.02, 0.04, 9), 6)
    Y = 5.0 - 1e4 * (A[:, None] - np.array([0.0257, 0.0281, 0.05, 0.03])) ** 2
    Y[4, 3] = np.nan  # bed 3 not stationary at 3 cm
    a = optimal_amplitudes(A, Y)
    np.testing.assert_allclose(a[:2], [0.0257, 0.0281], rtol=1e-9)
    assert a[2] == 0.04 and np.isnan(a[3])
    assert np.isnan(optimal_amplitudes(A[:2], Y[:2])).all()
