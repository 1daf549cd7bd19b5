"""Design quantities read off FRFs and Lz scans (jaxdamp.analysis.response), against independent results."""

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from jaxdamp.analysis.response import crossings, fit_frf, frf_amplitude, optimal_gap, resonance

M, K, C, U = 2.37, 21500.0, 26.3, 0.0045


def test_resonance_refines_the_peak_between_samples():
    """On a 0.25 Hz grid the parabolic refinement finds the analytic FRF's peak (located by
    scipy's bounded scalar minimiser) within 0.02 Hz and 0.5 % in amplitude; the largest
    sample alone is off by up to half a grid step."""
    best = minimize_scalar(lambda f: -frf_amplitude(f, M, K, C, U), bounds=(10, 20),
                           method="bounded", options={"xatol": 1e-9})
    f = np.arange(10.0, 20.0, 0.25) + 0.1
    fp, zp = resonance(f, frf_amplitude(f, M, K, C, U))
    assert fp == pytest.approx(best.x, abs=0.02)
    assert zp == pytest.approx(-best.fun, rel=5e-3)
    # samples in any order; a peak at the edge of the range is the edge sample
    perm = np.random.default_rng(0).permutation(len(f))
    assert resonance(f[perm], frf_amplitude(f[perm], M, K, C, U)) == pytest.approx((fp, zp))
    edge = np.array([16.0, 17.0, 18.0])
    assert resonance(edge, frf_amplitude(edge, M, K, C, U)) == pytest.approx(
        (16.0, float(frf_amplitude(16.0, M, K, C, U))))


def test_crossings_of_a_piecewise_linear_curve():
    x = np.array([0.04, 0.06, 0.1, 0.2, 0.4])
    y = np.array([2.5, 2.7, 2.4, 2.3, 2.37])
    got = crossings(x, y, 2.37)
    # exact linear interpolation: the curve falls through 2.37 between 0.1 and 0.2, and ends on it
    assert got == pytest.approx([0.1 + 0.03 / 0.1 * 0.1, 0.4])
    assert crossings(x, y + 10, 2.37) == []


def test_optimal_gap_criteria_on_a_synthetic_scan():
    """A scan built from the analytic FRF with known C_ef(Lz), M_ef(Lz): the criteria recover
    the planted optimum, and the fit returns the planted parameters (1e-6)."""
    lz = np.array([0.042, 0.057, 0.087, 0.1225, 0.162, 0.222, 0.372])
    c_ef = np.array([8.0, 12.0, 20.0, 30.0, 18.0, 12.0, 9.0])
    m_ef = np.array([2.6, 2.75, 2.5, 2.37, 2.3, 2.33, 2.36])
    f = np.linspace(8, 23, 16)
    peaks, fits = [], []
    for c, m in zip(c_ef, m_ef):
        Z = frf_amplitude(f, m, K, c, U)
        fits.append(fit_frf(f, Z, U, K, M0=2.37, C0=7.6)[:2])
        peaks.append(resonance(f, Z)[1])
    np.testing.assert_allclose(np.array(fits), np.stack([m_ef, c_ef], 1), rtol=1e-6)
    opt = optimal_gap(lz, np.array(fits)[:, 1], np.array(peaks), np.array(fits)[:, 0], 2.37)
    assert opt["max_C_ef"] == 0.1225 and opt["min_peak"] == 0.1225
    assert opt["M_ef_crosses_M"] == pytest.approx([0.1225], abs=1e-6)


def test_secondary_maxima_counts_only_peaks_that_stand_out_of_the_error():
    """A unimodal analytic FRF has no secondary maximum and roughness 1; a planted side peak
    (height 0.5 on the steep flank: prominence ≈ 0.3) counts against an error of 0.05 (threshold 2·√2·0.05 ≈ 0.14) but not
    against 0.2 (≈ 0.57); noise-free, every strict local maximum counts."""
    from jaxdamp.analysis.response import frf_amplitude, secondary_maxima

    f = np.linspace(5, 25, 81)
    Z = frf_amplitude(f, 2.37, 21500.0, 7.6, 0.0045) / 0.0045
    r = secondary_maxima(Z, 0.0)
    assert r["secondary"] == 0 and r["roughness"] == pytest.approx(1.0)
    bump = Z + 0.5 * np.exp(-0.5 * ((f - 21.0) / 0.3) ** 2)  # on the falling flank
    assert secondary_maxima(bump, 0.05)["secondary"] == 1
    assert secondary_maxima(bump, 0.2)["secondary"] == 0
    assert secondary_maxima(bump, 0.0)["roughness"] > 1.0
