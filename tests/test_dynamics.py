"""Nonlinear-dynamics toolbox (jaxdamp.analysis.dynamics) against systems whose answers are known.

Largest Lyapunov exponents: logistic map at r = 4 (ln 2 per iteration, exactly) and the
Lorenz system (σ=10, ρ=28, β=8/3; 0.906 per unit time, Wolf et al. 1985 / Sprott), from the
x component alone through the delay embedding. Whole file: ~10 s on 2 cores.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxdamp.analysis import dynamics as dyn

LORENZ_LAMBDA = 0.906  # [1/time unit]
DT_LORENZ = 0.01


@pytest.fixture(scope="module")
def lorenz_x():
    """x(t) of the Lorenz attractor, dt = 0.01, 300 time units after a 50-unit transient."""
    def rhs(t, s, sigma=10.0, rho=28.0, beta=8.0 / 3.0):
        x, y, z = s
        return [sigma * (y - x), x * (rho - z) - y, x * y - beta * z]

    t = np.arange(0.0, 350.0, DT_LORENZ)
    sol = solve_ivp(rhs, (0.0, t[-1]), [1.0, 1.0, 1.0], method="DOP853", rtol=1e-10,
                    atol=1e-10, t_eval=t)
    assert sol.success
    return sol.y[0][5000:]


@pytest.fixture(scope="module")
def logistic():
    x = np.empty(5100)
    x[0] = 0.3141
    for i in range(len(x) - 1):
        x[i + 1] = 4.0 * x[i] * (1.0 - x[i])
    return x[100:]


# drive-like synthetic signals: f = 2 Hz, 100 samples per period, 200 periods, small noise so
# that "repeats" are not exact round-off repeats
F = 2.0
DT = 0.005
T = np.arange(0.0, 100.0, DT)
W = 2 * np.pi * F
GOLD = (np.sqrt(5.0) - 1.0) / 2.0
_rng = np.random.default_rng(1)
NOISE = 1e-4 * _rng.standard_normal(T.size)
PERIOD1 = np.sin(W * T) + 0.3 * np.sin(2 * W * T + 1.0) + 0.1 * np.cos(3 * W * T) + NOISE
PERIOD2 = np.sin(W * T) + 0.6 * np.sin(W * T / 2 + 0.4) + NOISE  # response at f/2
QUASI = (np.sin(W * T) + 0.5 * np.sin(GOLD * W * T + 0.7)
         + 0.2 * np.sin(W * T) * np.sin(GOLD * W * T) + NOISE)


# --------------------------------------------------------------------------- section, spectrum


def test_poincare_section_samples_the_drive_phase():
    """x = cos(ωt + φ0) at t_k = (k + φ/2π)/f is cos(φ + φ0), x' = -ω sin(φ + φ0); the
    spline must give this to 1e-6 even though t_k fall between samples (φ = 1.3 rad)."""
    x = np.cos(W * T + 0.5)
    sec = dyn.poincare_section(T, x, F, phase=1.3)
    assert len(sec.t) == 200  # t_k = (k + 0.207)/2 for k = 0..199 inside [0, 99.995]
    np.testing.assert_allclose(np.diff(sec.t), 1 / F, rtol=1e-12)
    np.testing.assert_allclose(sec.x, np.cos(1.8), atol=1e-6)
    np.testing.assert_allclose(sec.dxdt, -W * np.sin(1.8), rtol=1e-4)
    P = sec.points("return")
    assert P.shape == (199, 2)
    np.testing.assert_array_equal(P[:, 1], sec.x[1:])
    late = dyn.poincare_section(T, x, F, phase=1.3, t_start=50.0)
    assert late.t[0] >= 50.0 and len(late.t) == 100


def test_power_spectrum_lines_and_parseval():
    """Peaks of the period-2 signal sit at f/2 and f; the PSD integrates to the variance
    (Hann-windowed Welch: within 2 %)."""
    for method in ("welch", "periodogram"):
        sp = dyn.power_spectrum(T, PERIOD2, F, method=method)
        df = sp.f[1] - sp.f[0]
        assert np.sum(sp.psd) * df == pytest.approx(np.var(PERIOD2), rel=0.02)
        order = np.argsort(sp.psd)[::-1]
        top_two = sorted({round(float(sp.f[i]), 6) for i in order[:2]})
        assert top_two == pytest.approx([F / 2, F], abs=df)
        lines = {lab: fl for lab, fl, _ in sp.lines}
        assert lines["f"] == F and lines["2f"] == 2 * F and lines["f/2"] == F / 2
        assert lines["f/3"] == pytest.approx(F / 3)
        # the line at f/2 is strong, the one at f/3 is not there
        p = {lab: pv for lab, _, pv in sp.lines}
        assert p["f/2"] > 1e3 * p["f/3"]


def test_line_fraction_separates_lines_from_broadband(lorenz_x):
    sp_q = dyn.power_spectrum(T, QUASI, F, method="periodogram")
    t_l = np.arange(lorenz_x.size) * DT_LORENZ
    sp_l = dyn.power_spectrum(t_l, lorenz_x, method="periodogram")
    assert dyn.line_fraction(sp_q.psd) > 0.99  # measured 0.99999
    assert dyn.line_fraction(sp_l.psd) < 0.6  # measured 0.44
    # masking the drive's harmonics leaves the second frequency and the combination lines
    mask = dyn.harmonic_mask(sp_q.f, F)
    assert mask.sum() > 0 and dyn.line_fraction(sp_q.psd, exclude=mask) > 0.99
    # one line is not all: the combination lines f(1 ± g) hold 7 % (measured 0.926)
    assert dyn.line_fraction(sp_q.psd, n_lines=1, exclude=mask) < 0.95


# --------------------------------------------------------------------------- embedding


def test_embed_layout():
    x = np.arange(10.0)
    y = dyn.embed(x, 3, 2)
    assert y.shape == (6, 3)
    np.testing.assert_array_equal(y[0], [0, 2, 4])
    np.testing.assert_array_equal(y[-1], [5, 7, 9])
    with pytest.raises(ValueError):
        dyn.embed(x, 6, 2)


def test_mutual_information_delay_and_fnn_on_lorenz(lorenz_x):
    """Measured: first AMI minimum at 18 samples = 0.18 time units (16 bins); FNN fractions
    ≈ [0.997, 0.085, 0.0005, 0, ...] → dimension 3."""
    delay, mi = dyn.mutual_information_delay(lorenz_x, 100)
    assert mi.shape == (101,) and mi[0] > mi[delay]
    assert 0.15 <= delay * DT_LORENZ <= 0.20
    frac, dim = dyn.false_nearest_neighbours(lorenz_x, delay, max_dim=6)
    assert dim == 3
    assert frac[0] > 0.9 and frac[1] > 0.03 and frac[2] < 0.01


def test_mutual_information_delay_of_a_sine():
    """For a sine the AMI's true first dip is at a quarter period (x and its derivative):
    100 samples per period → 25. The histogram estimate of a pure sine is jagged (measured
    spurious first minimum at 3 samples, prominence 5 % of the range); asking for a
    prominence of 20 % of the range finds 24."""
    x = np.sin(W * T + 0.1)
    plain, mi = dyn.mutual_information_delay(x, 80)
    assert plain < 10
    delay, _ = dyn.mutual_information_delay(x, 80, min_prominence=0.2)
    assert abs(delay - 25) <= 2


def test_fnn_of_the_logistic_map_is_one(logistic):
    """x_{n+1} is a function of x_n: no false neighbours already in one dimension."""
    frac, dim = dyn.false_nearest_neighbours(logistic, 1, max_dim=4)
    assert dim == 1 and frac[0] < 0.01


# --------------------------------------------------------------------------- Lyapunov


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_lyapunov_logistic_is_ln2(logistic, dim):
    """Measured 0.714, 0.707, 0.695 per iteration for m = 1, 2, 3 (truth ln 2 = 0.693)."""
    r = dyn.lyapunov_kantz(logistic, dim, 1, dt=1.0)
    assert r.exponent == pytest.approx(np.log(2.0), rel=0.10)
    i0, i1 = r.fit_range
    assert i1 - i0 >= 3 and r.S[i1] < np.mean(r.S[-5:])  # fit ends before the plateau


def test_lyapunov_lorenz_from_x_only(lorenz_x):
    """Embedding from the AMI delay and FNN dimension (18 samples, m = 3); measured 0.919 per
    time unit (truth 0.906); the automatic fit range skips the initial fast rise (S(Δn) slope
    ~2.3 for Δn·dt < 0.7) and stops before saturation."""
    delay, _ = dyn.mutual_information_delay(lorenz_x, 100)
    _, dim = dyn.false_nearest_neighbours(lorenz_x, delay, max_dim=6)
    r = dyn.lyapunov_kantz(lorenz_x, dim, delay, dt=DT_LORENZ)
    assert r.exponent == pytest.approx(LORENZ_LAMBDA, rel=0.10)
    i0, i1 = r.fit_range
    assert 0.3 < r.time[i0] < 1.2 and r.time[i1] - r.time[i0] > 1.5
    # the initial rise is steeper than the exponent: including it would bias the estimate
    early = np.polyfit(r.time[: i0 + 1], r.S[: i0 + 1], 1)[0]
    assert early > 1.5 * LORENZ_LAMBDA


def test_lyapunov_lorenz_other_embeddings(lorenz_x):
    """The estimate does not hinge on the chosen embedding: m = 4, τ = 10 and m = 6, τ = 6
    measured 0.937 and 0.925."""
    for dim, delay in [(4, 10), (6, 6)]:
        r = dyn.lyapunov_kantz(lorenz_x, dim, delay, dt=DT_LORENZ, max_steps=500)
        assert r.exponent == pytest.approx(LORENZ_LAMBDA, rel=0.10), (dim, delay)


def test_lyapunov_of_regular_signals_is_near_zero():
    """Control: a periodic signal (period 1.2345, not a whole number of samples) and a
    quasi-periodic one give |λ| < 0.03 per time unit (3 % of the Lorenz value; measured
    +0.0002 and -0.0074: S(Δn) never rises by ln 2, so the whole curve is fitted), whereas
    the same code gives 0.92 on Lorenz."""
    dt = 0.01
    t = np.arange(0.0, 200.0, dt)
    om = 2 * np.pi / 1.2345
    periodic = np.sin(om * t) + 0.4 * np.cos(2 * om * t + 0.3)
    quasi = np.sin(om * t) + 0.5 * np.sin(GOLD * om * t + 0.7)
    for x in (periodic, quasi):
        delay, _ = dyn.mutual_information_delay(x, 200)
        r = dyn.lyapunov_kantz(x, 3, delay, dt=dt, theiler=124)
        assert abs(r.exponent) < 0.03


def test_fixed_fit_range_is_honoured(logistic):
    r = dyn.lyapunov_kantz(logistic, 1, 1, dt=0.5, fit_range=(1, 5))
    assert r.fit_range == (1, 5)
    slope = np.polyfit(r.time[1:6], r.S[1:6], 1)[0]
    assert r.exponent == pytest.approx(slope)
    assert r.exponent == pytest.approx(2 * np.log(2.0), rel=0.10)  # dt = 0.5: per unit time


# --------------------------------------------------------------------------- classification


def test_classify_period_1():
    c = dyn.classify(T, PERIOD1, F)
    assert (c.label, c.period) == ("periodic", 1)
    assert c.evidence["return_distances"][0] < 1e-3


def test_classify_period_2():
    c = dyn.classify(T, PERIOD2, F)
    assert (c.label, c.period) == ("periodic", 2)
    d = c.evidence["return_distances"]
    assert d[0] > 0.5 and d[1] < 1e-3


def test_classify_quasi_periodic():
    c = dyn.classify(T, QUASI, F)
    assert c.label == "quasi-periodic" and c.period is None
    ev = c.evidence
    assert min(ev["return_distances"]) > 0.1  # no k ≤ 8 repeats
    assert abs(ev["lyapunov_per_period"]) < 0.02 and ev["line_fraction"] > 0.99
    assert ev["strongest_peak_ratio"] == pytest.approx(GOLD, abs=0.01)  # the second frequency


def test_classify_lorenz_is_chaotic(lorenz_x):
    """Lorenz has no drive: strobe once per time unit (f = 1)."""
    t = np.arange(lorenz_x.size) * DT_LORENZ
    c = dyn.classify(t, lorenz_x, 1.0)
    assert c.label == "chaotic"
    assert c.exponent == pytest.approx(LORENZ_LAMBDA, rel=0.10)
    assert c.evidence["line_fraction"] < 0.9


def test_classify_logistic_is_chaotic(logistic):
    """A map: one sample per 'drive period' (t = n, f = 1)."""
    c = dyn.classify(np.arange(logistic.size, dtype=float), logistic, 1.0)
    assert c.label == "chaotic" and c.period is None
    assert c.exponent == pytest.approx(np.log(2.0), rel=0.10)


def test_classify_driven_duffing_chaotic_and_periodic():
    """A driven system like the damper: Ueda's oscillator x'' + 0.05 x' + x³ = B cos t.
    B = 7.5 is chaotic (λ ≈ 0.1 per unit time in the literature; the stroboscopic section is
    the 'Japanese attractor'); B = 0.5 settles on a period-1 orbit."""
    period = 2 * np.pi
    t = np.arange(0.0, 300 * period, period / 64)

    def run(B):
        sol = solve_ivp(lambda tt, s: [s[1], -0.05 * s[1] - s[0] ** 3 + B * np.cos(tt)],
                        (0.0, t[-1]), [3.0, 4.0], method="DOP853", rtol=1e-9, atol=1e-9,
                        t_eval=t)
        return sol.y[0]

    chaotic = dyn.classify(t, run(7.5), 1 / period, t_start=50 * period)
    assert chaotic.label == "chaotic"
    assert 0.06 < chaotic.exponent < 0.14  # measured 0.096
    # with the drive's harmonics masked the rest of the spectrum is broadband (measured 0.57)
    assert chaotic.evidence["line_fraction"] < 0.8
    regular = dyn.classify(t, run(0.5), 1 / period, t_start=200 * period)
    assert (regular.label, regular.period) == ("periodic", 1)


def test_figures_write_files(tmp_path, logistic):
    from jaxdamp import figures

    sec = dyn.poincare_section(T, QUASI, F)
    sp = dyn.power_spectrum(T, PERIOD2, F)
    r = dyn.lyapunov_kantz(logistic, 1, 1)
    for name, fig in (("p", figures.poincare_figure(sec)),
                      ("r", figures.poincare_figure(sec, kind="return")),
                      ("s", figures.spectrum_figure(sp, fmax=5 * F)),
                      ("k", figures.kantz_figure(r))):
        p = figures.save(fig, tmp_path / f"{name}.png")
        assert p.exists() and p.stat().st_size > 5000
        ax = fig.axes[0]  # (fig.axes[1] of a section is its colour bar, "time t [s]")
        assert "[" in ax.get_xlabel() and "[" in ax.get_ylabel()
    # the return map has one point fewer than the section
    assert len(figures.poincare_figure(sec, kind="return").axes[0].collections[0].get_offsets()) \
        == len(sec.t) - 1


# --------------------------------------------------------------------------- periodicity levels


def test_strobe_spread_is_the_noise_level_of_a_period2_orbit():
    """A period-2 stroboscopic orbit ±1 with Gaussian noise σ: spread_2 = σ/scale within 10 %
    (400 points), spread_1 ≈ the orbit itself (≈ 1/scale), so period 2 is found at any
    tolerance between σ and 1."""
    rng = np.random.default_rng(3)
    sigma = 0.01
    x = np.tile([1.0, -1.0], 200) + sigma * rng.standard_normal(400)
    sec = dyn.PoincareSection(np.arange(400.0), x, np.zeros(400), 1.0, 0.0)
    sp = dyn.strobe_spread(sec, scale=1.0, max_period=4)
    assert sp[1] == pytest.approx(sigma, rel=0.1)
    assert sp[0] == pytest.approx(1.0, rel=0.02)
    assert sp[3] == pytest.approx(sigma, rel=0.15)  # period 4 contains period 2


def test_harmonic_fraction_tells_period1_from_period2_and_noise():
    f = 10.0
    t = np.arange(0, 20.0, 1e-3)
    x1 = np.cos(2 * np.pi * f * t) + 0.3 * np.cos(4 * np.pi * f * t)
    x2 = x1 + 0.5 * np.cos(np.pi * f * t)  # a subharmonic f/2: period 2
    noise = np.random.default_rng(0).standard_normal(t.size)
    h = lambda x, k: dyn.harmonic_fraction(dyn.power_spectrum(t, x, f, method="periodogram"), f, k)  # noqa: E731
    assert h(x1, 1) > 0.999
    assert h(x2, 1) < 0.85 and h(x2, 2) > 0.999
    assert h(noise, 1) < 0.05


def test_divergence_exponent_recovers_the_growth_rate_and_stops_at_saturation():
    """d(t) = 1e-9 e^{λt} |cos(2π f t)| capped at the orbit size 1e-3: the fitted exponent is λ
    within 3 %, the fit stops where d reaches a tenth of the size, over more than one period;
    a constant distance gives a zero exponent and no saturation."""
    f, lam = 10.0, 15.0
    t = np.arange(0, 3.0, 1e-3)
    d = np.minimum(1e-9 * np.exp(lam * t), 1e-3) * np.abs(np.cos(2 * np.pi * f * t)) + 1e-15
    r = dyn.divergence_exponent(t, d, f, saturation=1e-3)
    assert r["exponent"] == pytest.approx(lam, rel=0.03)
    assert r["saturated"] and r["grew"] and r["periods_fitted"] >= 2
    assert r["plateau"] == pytest.approx(1e-3, rel=0.05)
    assert r["t_sat"] == pytest.approx(np.log(1e-4 / 1e-9) / lam, abs=0.1)
    flat = dyn.divergence_exponent(t, np.full(t.size, 1e-9), f, saturation=1e-3)
    assert abs(flat["exponent"]) < 1e-6 and not flat["saturated"] and not flat["grew"]


def test_classify_fits_the_kantz_slope_over_more_than_one_drive_period():
    """On a chaotic flow sampled at 20 samples per drive period the automatic Kantz fit range
    of the classifier spans more than one drive period."""
    from scipy.integrate import solve_ivp

    def lorenz(_, u):
        return [10 * (u[1] - u[0]), u[0] * (28 - u[2]) - u[1], u[0] * u[1] - 8 / 3 * u[2]]

    dt = 0.01
    t = np.arange(0, 60, dt)
    x = solve_ivp(lorenz, (0, 60), [1, 1, 1], t_eval=t, rtol=1e-9, atol=1e-9).y[0]
    f = 1 / (20 * dt)  # a notional drive of 20 samples per period
    c = dyn.classify(t[1000:], x[1000:], f)
    assert c.lyapunov is not None
    i0, i1 = c.lyapunov.fit_range
    assert (i1 - i0) * dt > 1 / f


def test_divergence_exponent_from_the_perturbation_size_bounds_a_growth_within_one_period():
    """Twins that separate from d0 = 1e-9 to their plateau within the first drive period:
    judged from D_0 alone they 'did not grow'; with d0 they grew, saturated at once, and the
    exponent is the lower bound ln(D_0/d0)/T, which the true rate exceeds."""
    f, lam = 10.0, 400.0  # 1e-9 → 1e-3 in 35 ms, under one period (0.1 s)
    t = np.arange(0, 3.0, 1e-3)
    d = np.minimum(1e-9 * np.exp(lam * t), 1e-3) * (0.6 + 0.4 * np.abs(np.cos(2 * np.pi * f * t)))
    blind = dyn.divergence_exponent(t, d, f)
    assert not blind["grew"]
    r = dyn.divergence_exponent(t, d, f, d0=1e-9)
    assert r["grew"] and r["saturated"] and r["lower_bound"] and r["periods_fitted"] == 0
    assert r["exponent"] == pytest.approx(np.log(1e-3 / 1e-9) / 0.1, rel=0.05)
    assert r["exponent"] < lam
    slow = dyn.divergence_exponent(t, np.minimum(1e-9 * np.exp(15.0 * t), 1e-3), f, d0=1e-9)
    assert not slow["lower_bound"] and slow["exponent"] == pytest.approx(15.0, rel=0.03)
