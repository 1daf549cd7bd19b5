"""Steady-state statistics: per-period series, MSER detection, replicate errors (jaxdamp.analysis.stats)."""

import numpy as np
import pytest

from jaxdamp.analysis import stats
from jaxdamp.physics.model import CH, N_CHANNELS


def test_mser_finds_the_end_of_a_transient():
    """An exponential transient (time constant 5 periods) on white noise: the detected start
    lies where the transient has fallen below the noise (between 2 and 6 time constants),
    and the retained mean is within 3 standard errors of the true level."""
    rng = np.random.default_rng(1)
    n = 200
    k = np.arange(n)
    for trial in range(5):
        x = 1.0 + 0.5 * np.exp(-k / 5.0) + 0.01 * rng.standard_normal(n)
        d = stats.mser(x)
        assert d.stationary
        assert 10 <= d.start <= 30, d
        tail = x[d.start:]
        assert abs(tail.mean() - 1.0) < 3 * 0.01 / np.sqrt(len(tail))


def test_mser_refuses_a_drifting_series():
    """A linear drift never becomes stationary; a series too short to keep 5 periods neither."""
    x = np.linspace(1.0, 2.0, 100) + 1e-3 * np.random.default_rng(0).standard_normal(100)
    assert not stats.mser(x).stationary
    assert not stats.mser(np.ones(4)).stationary
    assert stats.mser(np.ones(50)).stationary  # a constant is stationary from the start


def test_replicate_standard_error_is_calibrated():
    """Over 2000 synthetic experiments of R = 4 replicates, (mean - truth)/SE follows Student's
    t with 3 degrees of freedom: the 95 % interval covers the truth 95 % ± 1.5 % of the time."""
    rng = np.random.default_rng(3)
    cover = 0
    for _ in range(2000):
        e = stats.across(2.0 + 0.1 * rng.standard_normal(4))
        cover += abs(e.mean - 2.0) <= e.ci95
    assert cover / 2000 == pytest.approx(0.95, abs=0.015)
    one = stats.across([1.0])
    assert one.n == 1 and np.isnan(one.se)
    part = stats.across([1.0, 2.0, 3.0], stationary=[True, False, True])
    assert part.n == 2 and part.mean == 2.0 and np.isnan(part.values[1])


def test_batch_means_error_of_white_noise():
    """Batch means of white noise: the squared standard error is unbiased for sigma²/n
    (2000 series; its relative spread is 1.6 %, the tolerance 10 %)."""
    rng = np.random.default_rng(0)
    se = np.array([stats.batch_means_se(rng.standard_normal(500), 5) for _ in range(2000)])
    assert np.mean(se**2) == pytest.approx(1 / 500, rel=0.1)


def test_per_period_of_a_harmonic_signal():
    """z = Z cos(Ωt + φ) sampled 200 times a period, work growing at a constant power: every
    period gives amplitude Z (to the sampling resolution), phase φ and the energy P/f."""
    f, Z, phi, P = 12.0, 0.03, -0.7, 5.0
    t = np.arange(0, 2.0, 1 / (200 * f))
    work = np.zeros((len(t), N_CHANNELS))
    work[:, CH["pp_normal"]] = P * t
    work[:, CH["input"]] = 2 * P * t
    rec = {"t": t, "z_box": Z * np.cos(2 * np.pi * f * t + phi), "work": work}
    s = stats.per_period(rec, f, channels=("input",))
    assert len(s["amplitude"]) == 23  # whole periods inside [0, 2) s sampled up to t[-1]
    np.testing.assert_allclose(s["amplitude"], Z, rtol=2e-4)
    np.testing.assert_allclose(s["phase"], phi, atol=1e-9)
    np.testing.assert_allclose(s["granular_loss_per_cycle"], P / f, rtol=1e-9)
    np.testing.assert_allclose(s["input_per_cycle"], 2 * P / f, rtol=1e-9)
    est = stats.steady([s, s])
    assert est["amplitude"].n == 2 and est["amplitude"].se == 0.0


@pytest.mark.long  # half a minute (the marker's definition)
def test_replicated_sweep_has_independent_beds_and_a_detected_steady_state():
    """A 1-point sweep of a small damper with R = 3 replicates: the beds differ (seeds
    0, 1, 2), replicate 0 is the unreplicated run to round-off, and every steady-state
    estimate carries R, a detected start and a flag."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies.sweep import sweep

    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          ["grains.0.count=20", "numerics.duration=0.4", "numerics.chunk=0.1",
                           "numerics.settle_time=0.05", "numerics.record_dt=1e-3",
                           "primary.C=60", "frequency=14"])
    rep = sweep(cfg, {}, progress=False, echo=None, replicates=3)
    one = sweep(cfg, {}, progress=False, echo=None)
    assert rep.records["z_box"].shape[0] == 3 and rep.replicate_summary["amplitude"].shape == (3,)
    np.testing.assert_allclose(rep.records["z_box"][0], one.records["z_box"][0], rtol=1e-9,
                               atol=1e-12)
    z = rep.records["z_cm"]
    assert np.abs(z[1] - z[0]).max() > 1e-5 and np.abs(z[2] - z[1]).max() > 1e-5
    a = rep.steady["amplitude"]
    assert a["values"].shape == (3,) and a["start"].shape == (3,)
    assert int(a["n"]) == int(np.sum(a["stationary"]))
    assert float(rep.summary["amplitude"]) == pytest.approx(
        rep.replicate_summary["amplitude"].mean())


def test_standard_error_and_the_one_formatter():
    """``standard_error`` equals scipy's ``sem`` (ddof 1) along any axis and is NaN for one
    realisation; ``pm`` writes value ± error with the stated digits, scaled, and leaves out an
    error that is not finite."""
    from scipy.stats import sem

    from jaxdamp.analysis.uncertainty import mean_se, pm, standard_error

    x = np.random.default_rng(3).normal(size=(4, 7))
    for axis in (0, 1, -1):
        np.testing.assert_allclose(standard_error(x, axis), sem(x, axis=axis), rtol=1e-14)
    assert np.isnan(standard_error([2.0]))
    assert np.isnan(standard_error(x[:, :1], axis=1)).all()
    m, e = mean_se(x, axis=0)
    np.testing.assert_allclose(m, x.mean(axis=0), rtol=1e-14)
    np.testing.assert_allclose(e, sem(x, axis=0), rtol=1e-14)
    assert pm(0.123456, 0.0012, unit="m") == "0.12346 ± 0.0012 m"
    assert pm(0.0314, 0.00201, ".3f", scale=100, unit="%") == "3.140 ± 0.2 %"
    assert pm(2.5, float("nan"), unit="Hz") == "2.5 Hz"
    assert pm(1.5, 0.25, 3, compact=True) == "1.5±0.25"


def test_ar1_standard_error_is_calibrated_on_correlated_series():
    """The within-run standard error of a serially correlated series: exact on a small case
    (ρ = 0.25 for 1, 2, 3, 4) and, on AR(1) series with φ = 0.6, its average over 400
    independent series matches the actual spread of their means within 10 % (the plain
    ``s/√n`` is 2× too small there)."""
    from jaxdamp.analysis.uncertainty import (
        ar1_standard_error,
        lag1_autocorrelation,
        standard_error,
    )

    assert lag1_autocorrelation([1.0, 2.0, 3.0, 4.0]) == pytest.approx(0.25, rel=1e-14)
    assert ar1_standard_error([1.0, 2.0, 3.0, 4.0]) == pytest.approx(
        standard_error([1.0, 2.0, 3.0, 4.0]) * np.sqrt(1.25 / 0.75), rel=1e-14)
    assert np.isnan(ar1_standard_error([1.0]))
    rng = np.random.default_rng(11)
    phi, n, m = 0.6, 400, 400
    e = rng.normal(size=(m, n))
    x = np.empty_like(e)
    x[:, 0] = e[:, 0] / np.sqrt(1 - phi**2)
    for k in range(1, n):
        x[:, k] = phi * x[:, k - 1] + e[:, k]
    spread = x.mean(axis=1).std(ddof=1)
    est = np.mean([ar1_standard_error(s) for s in x])
    assert est == pytest.approx(spread, rel=0.10)
    assert np.mean([standard_error(s) for s in x]) < 0.6 * spread


def test_replicate_extrema_refines_each_replicate_and_combines_them():
    """Parabolas through exact quadratics recover each replicate's vertex; log axes return
    values in the original units; a best sample at the grid's end is counted, not refined."""
    from jaxdamp.analysis.stats import replicate_extrema

    x = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    Y = np.stack([-(x - c) ** 2 for c in (2.4, 2.6, 3.1)], axis=1)
    e = replicate_extrema(x, Y, "max")
    np.testing.assert_allclose(e.x, [2.4, 2.6, 3.1], rtol=1e-12)
    np.testing.assert_allclose(e.y, 0.0, atol=1e-12)
    assert e.estimate.mean == pytest.approx(np.mean([2.4, 2.6, 3.1]), rel=1e-12)
    assert e.estimate.n == 3 and e.at_edge == 0
    # a minimum of exp((log x - log 2.5)^2) in log x: the vertex at x = 2.5, the value 1
    Z = np.exp((np.log(x) - np.log(2.5)) ** 2)[:, None]
    m = replicate_extrema(x, np.log(Z), "min", log_x=True)
    assert m.x[0] == pytest.approx(2.5, rel=1e-12)
    assert replicate_extrema(x, Z, "min", log_x=True, log_y=True).y[0] == pytest.approx(1.0)
    edge = replicate_extrema(x, x[:, None], "max")
    assert edge.at_edge == 1 and edge.x[0] == 5.0 and np.isnan(edge.estimate.se)
