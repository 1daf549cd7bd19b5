"""Gap optimisation: S3 gradients vs finite differences, the DEM window estimator, the CLI."""

import h5py
import numpy as np
import pytest

from jaxdamp import presets
from jaxdamp.cli import main
from jaxdamp.config import apply_overrides
from jaxdamp.optimize import DEMProblem, Objective, S3Problem, scan_optimum, smooth_max


def _s3(kind, duration=1.5, **kw):
    cfg = apply_overrides(presets.get("sanchez2012-impact"), {"numerics.analysis_window": 0.5})
    return S3Problem(cfg, Objective(kind, **kw), duration=duration)


@pytest.mark.parametrize("kind,gaps", [("dissipation", (0.05, 0.0835)), ("amplitude", (0.06,))])
def test_s3_gradient_matches_finite_differences(kind, gaps):
    """Exact jax.grad of the smooth S3 objective w.r.t. the gap vs central differences (1 %)."""
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


def test_dem_window_estimator_small_bed():
    """The DEM estimator on a small, fast bed: finite ensemble means with standard errors, and
    the pathwise derivative has the sign of central differences of the same averaged window
    objective (same start states) just above the bed (gap 1 cm) and in a tall box (gap 10 cm).

    24 grains in a 2 x 2 cm box on a primary scaled with the bed (M = 0.3 kg, K so that f0
    stays 15.15 Hz, mass ratio ~0.07 as in the thesis' case): the same contact law, time step
    and window mechanics as sanchez2012-optimal (grains hitting the lid during a window are
    what the derivative sees), at ~1/10 of the cost per step."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "numerics.settle_time": 0.15,
        "primary.M": 0.3, "primary.K": 2720.0, "primary.C": 1.0})
    prob = DEMProblem(cfg, Objective("dissipation"), window=0.001, n_windows=8, burn_in=0.2)
    lo, hi = prob.bounds()
    assert lo == pytest.approx(prob.bed.height + 0.005)
    for gap in (0.01, 0.1):
        lz = prob.bed.height + gap
        est, ens = prob.evaluate(lz)
        assert np.isfinite([est.value, est.value_se, est.grad, est.grad_se]).all()
        assert est.value > 0 and est.value_se > 0 and est.grad_se >= 0
        h = 1e-8
        fd = (prob.window_values(ens, lz + h, engine="auto")
              - prob.window_values(ens, lz - h, engine="auto")) / (2 * h)
        assert est.grad != 0.0, f"no lid contact in any window at gap {gap}"
        assert np.sign(est.grad) == np.sign(fd.mean()), (gap, est.grad, fd.mean())
        # moving the lid keeps the start states valid: no grain above it
        top = np.asarray(ens.states.r[..., 2] - ens.states.z[..., None]).max() + 0.003
        assert top < lz + 0.2 * 0.003


def test_cli_optimize_quick_s3_converges_to_scan(tmp_path, capsys):
    """`jaxdamp optimize --quick` on S3 (dissipation at f0 from Lz0 = 0.07 m, gap0 = 0.031 m)
    ends within 2 % of the optimum of a dense scan of the same objective; the log holds every
    iterate with the configuration."""
    out = tmp_path / "opt.h5"
    assert main(["optimize", "--preset", "sanchez2012-impact", "--quick", "--out", str(out),
                 "--no-progress"]) == 0
    with h5py.File(out) as h:
        assert h.attrs["format"] == "jaxdamp-optimize/1" and h.attrs["status"] == "finished"
        assert "sanchez2012-impact" in h.attrs["config"]
        it = h["iterations"]
        x = it["x"][()]
        assert len(x) >= 5 and np.all(np.isfinite(it["gradient"][()]))
        assert np.all(np.diff(it["wall_time"][()]) > 0)
        gap = x[-1]
    # the same objective (3 s runs, last half analysed), scanned over the periodic regime
    prob = _s3("dissipation", duration=3.0)
    gaps = np.linspace(0.085, 0.115, 31)
    best = scan_optimum(gaps, prob.scan(gaps), True)
    assert abs(gap - best) / best < 0.02, (gap, best)
    assert "gap =" in capsys.readouterr().out


def test_dem_steady_estimator_common_random_numbers_and_sign():
    """The steady-state estimator (central differences, common random numbers) on the small
    bed of the test above: with the lid out of reach the pair Lz ± h is bit-identical, so the
    derivative is exactly 0 ± 0 (the pair shares every initial condition); just above the bed,
    where the grains hit the lid, the pair differs: a finite, nonzero derivative with a finite
    standard error (the sign test against a scan is the experiment's, at full size)."""
    from jaxdamp.optimize import SteadyProblem

    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "numerics.settle_time": 0.15,
        "primary.M": 0.3, "primary.K": 2720.0, "primary.C": 1.0, "primary.U": 0.0005})
    prob = SteadyProblem(cfg, Objective("amplitude"), h=0.002, burn_in=0.1, average=0.2,
                         blocks=4)
    lo, hi = prob.bounds()
    assert lo == pytest.approx(prob.bed.height + 0.005 + 0.002)
    far, _ = prob.evaluate(0.39)
    assert np.isfinite([far.value, far.value_se]).all() and far.value > 0
    assert far.grad == 0.0 and far.grad_se == 0.0
    assert far.extra["minus"] == far.extra["plus"]
    assert far.sim_seconds == pytest.approx(2 * 0.3)
    near, _ = prob.evaluate(prob.bed.height + 0.008)
    assert np.isfinite([near.value, near.grad, near.grad_se]).all()
    assert near.grad != 0.0 and near.grad_se > 0
