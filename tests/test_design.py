"""Design optimisation: objectives, the S3 problem, the DEM estimators, searches, the CLI."""

import json
import math

import h5py
import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.cli import main
from jaxdamp.config import apply_overrides
from jaxdamp.design import (
    DEMProblem,
    Objective,
    S3Problem,
    SteadyProblem,
    adaptive_scan,
    quadratic_optimum,
    scan_optimum,
    smooth_max,
    trust_region,
)
from jaxdamp.design.objectives import equivalent_damping


def _s3(kind, duration=1.5, gradient="transient", **kw):
    cfg = apply_overrides(presets.get("sanchez2012-impact"), {"numerics.analysis_window": 0.5})
    return S3Problem(cfg, Objective(kind, **kw), duration=duration, gradient=gradient)


def test_equivalent_damping_of_a_dashpot():
    """A dashpot C moving as Z cos Ωt dissipates π C Ω Z² per period: C_eq recovers C, and
    the damping objective is that number."""
    C, Z, f = 7.6, 0.02, 15.0
    E = math.pi * C * 2 * math.pi * f * Z**2
    assert equivalent_damping(E, Z, f) == pytest.approx(C, rel=1e-12)
    assert float(Objective("damping", frequency=f).combine([Z], [E])) == pytest.approx(C)
    assert Objective().kind == "damping" and Objective().maximise


@pytest.mark.parametrize("kind,gaps", [("dissipation", (0.05, 0.0835)), ("amplitude", (0.06,)),
                                       ("damping", (0.0835,))])
def test_s3_transient_gradient_matches_finite_differences(kind, gaps):
    """jax.grad through a whole smooth S3 run w.r.t. the gap vs central differences (1 %), in
    the periodic regime."""
    prob = _s3(kind)
    for gap in gaps:
        est, _ = prob.evaluate(gap)
        h = 1e-5
        fd = (prob.value(gap + h) - prob.value(gap - h)) / (2 * h)
        assert np.isfinite(est.grad) and est.grad_se == 0.0
        assert est.grad == pytest.approx(fd, rel=0.01), (kind, gap)
        assert est.value == pytest.approx(prob.value(gap), rel=1e-12)


def test_smooth_max_bounds():
    z = np.array([1.0, 3.0, 2.0])
    s = float(smooth_max(z, 16.0))
    assert 3.0 <= s <= 3.0 * 3 ** (1 / 16)
    assert scan_optimum([0.0, 1.0, 2.0, 3.0], [0.0, 2.0, 2.0, 0.0], True) == pytest.approx(1.5)


class _Noisy:
    """An analytic objective with replicate noise (a test function for the searches, not a
    stand-in for a simulation): J_r(x) = 1 − 100 (x − 0.11)² + a_r + ε, correlated along x
    through the per-replicate offset a_r as common random numbers make it."""

    variable = "Lz"

    def __init__(self, R=6, seed=0):
        self.objective = Objective("damping")
        self.R, self.rng, self.sim_seconds, self.freqs = R, np.random.default_rng(seed), 0.0, (15,)
        self.offset = 0.01 * self.rng.standard_normal(R)

    def scan(self, xs):
        xs = np.asarray(xs, float)
        J = (1 - 100 * (xs[:, None] - 0.11) ** 2 + self.offset
             + 0.002 * self.rng.standard_normal((len(xs), self.R)))
        self.sim_seconds += len(xs) * self.R
        return J.mean(1), J.std(1, ddof=1) / np.sqrt(self.R), J


def test_searches_find_an_analytic_optimum_with_an_interval():
    """The adaptive scan and the trust region both bracket the true optimum (0.11 m) in their
    95 % intervals; the trust region started near it spends fewer evaluations; an objective
    increasing to the bound is flagged as not interior."""
    scan = adaptive_scan(_Noisy(), 0.05, 0.30)
    trust = trust_region(_Noisy(seed=1), 0.12, 0.05, 0.30)
    for r in (scan, trust):
        assert r.optimum.lo <= 0.11 <= r.optimum.hi and r.optimum.interior, r.optimum
        assert r.optimum.halfwidth < 0.01
    assert trust.sim_seconds < scan.sim_seconds

    class Rising(_Noisy):
        def scan(self, xs):
            m, s, J = super().scan(xs)
            return m + 100 * np.asarray(xs), s, J + 100 * np.asarray(xs)[:, None]

    up = adaptive_scan(Rising(), 0.05, 0.30)
    assert up.at_bound


def test_quadratic_optimum_interval_is_calibrated():
    """Over 200 synthetic replicated curves (R = 4, noise correlated along x), the jackknife-t
    interval covers the true optimum in 95 % ± 5 % of the cases."""
    x = np.linspace(0.08, 0.14, 7)
    rng = np.random.default_rng(7)
    cover = 0
    for _ in range(200):
        J = (1 - 100 * (x[:, None] - 0.11) ** 2 + 0.002 * rng.standard_normal((7, 4))
             + 0.01 * rng.standard_normal((1, 4)))
        o = quadratic_optimum(x, J, True)
        cover += o.lo <= 0.11 <= o.hi
    assert 0.90 <= cover / 200 <= 1.0


def _small_bed(**extra):
    """24 grains in a 2 × 2 cm box on a primary scaled with the bed (M = 0.3 kg, f0 = 15.15 Hz,
    mass ratio ~0.07 as in the thesis' case): the contact law, time step and lid mechanics of
    sanchez2012-optimal at ~1/10 of the cost per step."""
    return apply_overrides(presets.get("sanchez2012-optimal"), dict({
        "grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "numerics.settle_time": 0.15,
        "primary.M": 0.3, "primary.K": 2720.0, "primary.C": 1.0}, **extra))


@pytest.mark.long
def test_dem_window_estimator_small_bed():
    """The pathwise window estimator: finite ensemble means with standard errors, and the
    derivative has the sign of central differences of the same averaged window objective
    (same start states) just above the bed (gap 1 cm) and in a tall box (gap 10 cm)."""
    prob = DEMProblem(_small_bed(), Objective("dissipation"), window=0.001, n_windows=8,
                      burn_in=0.2)
    lo, hi = prob.bounds()
    assert lo == pytest.approx(prob.bed.height + 0.005)
    for gap in (0.01, 0.1):
        lz = prob.bed.height + gap
        est, ens = prob.evaluate(lz)
        assert np.isfinite([est.value, est.value_se, est.grad, est.grad_se]).all()
        assert est.value > 0 and est.value_se > 0 and est.grad_se >= 0
        h = 1e-8
        fd = prob.central_difference(ens, h, lz)
        assert est.grad != 0.0, f"no lid contact in any window at gap {gap}"
        assert np.sign(est.grad) == np.sign(fd.mean()), (gap, est.grad, fd.mean())
        top = np.asarray(ens.states.r[..., 2] - ens.states.z[..., None]).max() + 0.003
        assert top < lz + 0.2 * 0.003


@pytest.mark.long
def test_steady_estimator_common_random_numbers_and_calibrated_error():
    """The replicated steady-state estimator on the small bed.

    * Lid out of reach: each pair Lz ± h shares its bed and never touches the lid, so every
      pair difference is exactly 0 (common random numbers) while the replicates differ (a
      positive standard error of the value).
    * Just above the bed, 24 independent pairs in one batch split into 6 groups of 4: the
      spread of the 6 group derivatives matches their reported standard errors: the ratio
      of their observed standard deviation to the RMS standard error is distributed as
      sqrt(F(5, 18)) for a calibrated error, whose central 95 % range is [0.40, 1.84]."""
    cfg = _small_bed(**{"primary.U": 0.0005})
    far = SteadyProblem(cfg, Objective("amplitude"), h=0.002, replicates=3, duration=0.3)
    est, _ = far.evaluate(0.39)
    assert np.all(est.extra["minus"] == est.extra["plus"])
    assert est.grad == 0.0 and est.grad_se == 0.0 and est.value_se > 0
    assert est.sim_seconds == pytest.approx(2 * 3 * 0.3)

    prob = SteadyProblem(cfg, Objective("damping"), h=0.003, replicates=24, duration=0.6)
    lz = prob.bed_height + 0.012
    est, _ = prob.evaluate(lz)
    g = (est.extra["plus"] - est.extra["minus"]) / (2 * prob.h)  # (24,) independent pairs
    assert np.isfinite(g).all() and np.any(g != 0)
    groups = g.reshape(6, 4)
    means = groups.mean(axis=1)
    ses = groups.std(axis=1, ddof=1) / 2.0
    ratio = means.std(ddof=1) / np.sqrt(np.mean(ses**2))
    assert 0.40 <= ratio <= 1.84, ratio
    assert est.grad == pytest.approx(g.mean()) and est.grad_se == pytest.approx(
        g.std(ddof=1) / np.sqrt(24))


def test_cli_optimize_s3_reaches_the_dense_scan_optimum(tmp_path, capsys):
    """`jaxdamp optimize --preset sanchez2012-impact --quick` (default objective: C_eq at f0,
    exact orbit gradients) from gap0 = 0.031 m ends within 2 % of the optimum of a dense scan
    of the same orbit objective (0.075–0.095 m, 11 gaps, parabola through the best three); the
    log holds every iterate."""
    from jaxdamp.s3 import periodic

    out = tmp_path / "opt.h5"
    assert main(["optimize", "--preset", "sanchez2012-impact", "--quick", "--out", str(out),
                 "--no-progress"]) == 0
    with h5py.File(out) as h:
        assert h.attrs["format"] == "jaxdamp-optimize/1" and h.attrs["status"] == "finished"
        it = h["iterations"]
        x = it["x"][()]
        assert len(x) >= 5 and np.all(np.isfinite(it["gradient"][()]))
        gap = float(np.mean(x[-3:]))
    cfg = presets.get("sanchez2012-impact")
    obj = Objective("damping")
    gaps = np.linspace(0.075, 0.095, 11)
    vals = [periodic.objective_and_gradient(cfg, obj, gap=g, refine=2)[0] for g in gaps]
    best = scan_optimum(gaps, vals, True)
    assert abs(gap - best) / best < 0.02, (gap, best)
    assert "optimum Lz" in capsys.readouterr().out


def test_s3_orbit_gradient_refuses_irregular_motion():
    """At a gap of 0.15 m (irregular motion at f0) the orbit method returns no number and says
    why; the optimiser stops there with the reason instead of stepping on it."""
    from jaxdamp.design import optimize

    prob = _s3("damping", gradient="orbit")
    est, _ = prob.evaluate(0.15)
    assert np.isnan(est.grad) and "not a stable periodic orbit" in est.extra["reason"]
    res = optimize(prob, 0.15, max_iter=3, progress=False)
    assert "not a stable periodic orbit" in res.reason


@pytest.mark.long
def test_s3_descent_walks_out_of_the_irregular_region():
    """From Lz0 = 0.25 m (gap 0.21 m: no stable periodic orbit at f0) the surrogate's
    exact-gradient descent falls back to central differences of long averages, walks into the
    regular region and ends within 2 % of the dense orbit-scan optimum of the gap (as the
    S3 optimiser does from a regular start)."""
    from jaxdamp.design.surrogate import descend
    from jaxdamp.s3 import periodic

    h_bed = 0.0379
    d = descend(presets.get("sanchez2012-optimal"), Objective("damping"), h_bed, 0.25,
                0.05, 0.395)
    assert d["fallbacks"] >= 1 and np.isfinite(d["lz"])
    cfg = presets.get("sanchez2012-impact")
    gaps = np.linspace(0.075, 0.095, 11)
    vals = [periodic.objective_and_gradient(cfg, Objective("damping"), gap=g, refine=2)[0]
            for g in gaps]
    best = scan_optimum(gaps, vals, True)
    assert abs(d["lz"] - h_bed - best) / best < 0.02, (d, best)


@pytest.mark.long  # 40 s on 2 cores: CI's second step
def test_cli_optimize_default_objective_does_not_run_to_a_bound(tmp_path, capsys):
    """`jaxdamp optimize` on a DEM damper with no objective flag (C_eq at f0, trust region
    from the S3 proposal; small bed, --quick) ends at an interior optimum well inside the
    feasible range [bed + 5 mm, 0.395 m] and prints no bound warning."""
    out = tmp_path / "opt.h5"
    args = ["optimize", "--preset", "sanchez2012-optimal", "--quick", "--no-progress",
            "--out", str(out)]
    for k, v in {"grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02,
                 "numerics.settle_time": 0.15, "primary.M": 0.3, "primary.K": 2720.0,
                 "primary.C": 1.0}.items():
        args += ["--set", f"{k}={v}"]
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "maximise damping" in text and "warning: no interior optimum" not in text
    with h5py.File(out) as h:
        opt = json.loads(h.attrs["optimum"])
        assert h.attrs["format"] == "jaxdamp-optimize/2" and opt["interior"]
    assert 0.05 < opt["lz"] < 0.3, opt
