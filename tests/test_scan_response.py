"""Library pieces the box-height scans share (``experiments/gap_scan.py``,
``experiments/grain_number.py``), against cases whose answer is known."""

from __future__ import annotations

import doctest

import numpy as np

from jaxdamp.analysis import response as resp
from jaxdamp.config import Primary
from jaxdamp.figures import figure
from jaxdamp.figures.response import draw_interval, draw_replicates, draw_run_band

PRIMARY = Primary(M=2.37, K=2.14e4, C=7.6, U=0.005)


def test_resonances_of_log_parabolas_are_their_vertices():
    """Gaussian FRFs are parabolas in log Z: every column's vertex and peak come back exactly,
    in the shape of the columns (heights × replicates)."""
    f = np.array([10.0, 12.0, 14.0, 16.0, 18.0])
    f0 = np.array([[12.5, 13.0], [14.2, 15.9]])  # (L, R)
    Z = 3e-3 * np.exp(-0.1 * (f[:, None, None] - f0) ** 2)
    fp, Zp = resp.resonances(f, Z)
    assert fp.shape == Zp.shape == (2, 2)
    np.testing.assert_allclose(fp, f0, rtol=1e-12)
    np.testing.assert_allclose(Zp, 3e-3, rtol=1e-12)


def test_resonances_is_resonance_per_column():
    """Bit-identical to :func:`resonance` looped over the columns."""
    rng = np.random.default_rng(1)
    f = np.linspace(5.0, 25.0, 7)
    Z = rng.uniform(1e-3, 1e-2, (7, 3, 2))
    fp, Zp = resp.resonances(f, Z)
    loop = np.array([[resp.resonance(f, Z[:, j, r]) for r in range(2)] for j in range(3)])
    assert np.array_equal(fp, loop[..., 0]) and np.array_equal(Zp, loop[..., 1])


def test_fit_frf_scan_fits_the_model_back():
    """Amplitudes of the 1-DOF model with M_ef = 2.6 kg, C_ef = 12 N s/m (column 0) and
    2.9 kg, 30 N s/m (column 1), two identical replicates: both weightings recover them, with
    no spread between the replicates."""
    f = np.array([8.0, 12.0, 14.0, 15.0, 16.0, 18.0, 23.0])
    truth = [(2.6, 12.0), (2.9, 30.0)]
    Z = np.stack([resp.frf_amplitude(f, M, PRIMARY.K, C, PRIMARY.U) for M, C in truth], axis=1)
    Z = np.repeat(Z[:, :, None], 2, axis=2)
    for w in resp.RESIDUALS:
        fits = resp.fit_frf_scan(f, Z, PRIMARY, w)
        assert len(fits) == 2
        for fit, (M, C) in zip(fits, truth):
            assert abs(fit["M_ef"] - M) < 1e-6 * M and abs(fit["C_ef"] - C) < 1e-4 * C, w
            assert fit["residuals"] == w and len(fit["M_reps"]) == 2 and fit["se_M"] < 1e-9


def test_fit_frf_scan_is_fit_frf_replicates_per_column():
    rng = np.random.default_rng(2)
    f = np.array([10.0, 13.0, 14.5, 16.0, 20.0])
    Z = resp.frf_amplitude(f, 2.7, PRIMARY.K, 15.0, PRIMARY.U)[:, None, None] \
        * rng.uniform(0.95, 1.05, (5, 2, 3))
    fits = resp.fit_frf_scan(f, Z, PRIMARY, "absolute")
    for j, fit in enumerate(fits):
        ref = resp.fit_frf_replicates(f, Z[:, j], PRIMARY.U, PRIMARY.K, M0=PRIMARY.M,
                                      C0=PRIMARY.C, residuals="absolute")
        assert np.array_equal(fit["M_reps"], ref["M_reps"]) and fit["C_ef"] == ref["C_ef"]


def test_draw_replicates_draws_means_and_two_standard_errors():
    """Replicates (1, 3) and (2, 2): means 2 and 2, SE 1 and 0: bars 0…4 and 2…2."""
    ax = figure((4, 3)).subplots()
    c = draw_replicates(ax, [1.0, 2.0], [[1.0, 3.0], [2.0, 2.0]], label="x")
    np.testing.assert_array_equal(c.lines[0].get_ydata(), [2.0, 2.0])
    segs = c.lines[2][0].get_segments()
    np.testing.assert_allclose([s[:, 1] for s in segs], [[0.0, 4.0], [2.0, 2.0]])
    assert ax.get_legend_handles_labels()[1] == ["x"]


def test_draw_interval_shades_mean_plus_minus_half_width_or_nothing():
    ax = figure((4, 3)).subplots()
    p = draw_interval(ax, 0.12, 0.01, alpha=0.15)
    np.testing.assert_allclose([p.get_x(), p.get_x() + p.get_width()], [0.11, 0.13])
    assert draw_interval(ax, 0.12, float("nan")) is None
    assert len(ax.patches) == 1


def test_draw_run_band_draws_the_last_periods():
    """10 Hz sampled every ms over 1 s: the last 3 periods are t ≥ 0.7 s, 301 samples; the
    centre of mass is drawn only when asked."""
    t = np.arange(0.0, 1.0005, 1e-3)
    run = {"t": t, "z_box": 1e-3 * np.sin(20 * np.pi * t), "z_lowest": 0 * t + 1e-3,
           "z_highest": 0 * t + 2e-3, "z_cm": 0 * t + 1.5e-3}
    for centre, lines in ((True, 3), (False, 2)):
        ax = figure((4, 3)).subplots()
        m = draw_run_band(ax, run, 0.05, 10.0, centre=centre)
        assert m.sum() == 301 and t[m][0] >= 0.7 - 1e-12 and len(ax.lines) == lines
        np.testing.assert_allclose(ax.lines[1].get_ydata(), 1e3 * (run["z_box"][m] + 0.05))


def test_doctests():
    finder, runner = doctest.DocTestFinder(), doctest.DocTestRunner()
    for name in ("resonances",):
        for test in finder.find(getattr(resp, name), name, globs={"np": np, **vars(resp)}):
            runner.run(test)
    assert runner.failures == 0 and runner.tries >= 2
