"""Free decay (``jaxdamp decay``): the log-decrement analysis against the linear oscillator, on
both engines, and the command line."""

import math
import subprocess
import sys

import h5py
import numpy as np
import pytest

from jaxdamp.analysis.decay import at_starting_peak, decay_curve, on_amplitudes, on_common_range
from jaxdamp.cases import presets
from jaxdamp.config import ConfigError, apply_overrides
from jaxdamp.studies import decay
from jaxdamp.validation import validate


def test_log_decrement_is_exact_for_a_viscous_oscillator():
    """Sampled at 1 ms, the parabola-refined peaks give ζ to 1e-3 relative and the damped
    frequency to 1e-4, from ζ = 0.001 to 0.3; replicates on a common grid average exactly."""
    wn = 2 * np.pi * 15.0
    t = np.arange(0.0, 3.0, 1e-3)
    for zeta in (0.001, 0.05, 0.3):
        x = 0.02 * np.exp(-zeta * wn * t) * np.cos(wn * math.sqrt(1 - zeta ** 2) * t + 0.3)
        c = decay_curve(t, 1.5 + x, z_eq=1.5, f_hint=15.0)
        assert len(c["Z"]) >= 3
        np.testing.assert_allclose(c["zeta"], zeta, rtol=1e-3)
        np.testing.assert_allclose(c["f"], 15.0 * math.sqrt(1 - zeta ** 2), rtol=1e-4)
        assert np.all(np.diff(c["Z"]) < 0)
    # the granular ratio from a loss record: for a linear oscillator the energy lost between
    # two peaks (where x' = 0) is ½K(X_k² − X_k+1²), so ΔW/(2πKZ²) = sinh(δ)/(2π) exactly
    K, m = 1e4, 1e4 / wn ** 2
    wd = wn * math.sqrt(1 - zeta ** 2)
    xd = 0.02 * np.exp(-zeta * wn * t) * (-zeta * wn * np.cos(wd * t + 0.3)
                                          - wd * np.sin(wd * t + 0.3))
    W = (0.5 * m * xd[0] ** 2 + 0.5 * K * x[0] ** 2) - (0.5 * m * xd ** 2 + 0.5 * K * x ** 2)
    c = decay_curve(t, x, 0.0, 15.0, loss=W, K=K)
    delta = np.log(c["Z"][:-1] / c["Z"][1:]).mean()
    np.testing.assert_allclose(c["zeta_g"], np.sinh(delta) / (2 * np.pi), rtol=2e-3)
    cur = on_amplitudes([c, c], np.geomspace(c["Z"].min(), c["Z"].max(), 5))
    np.testing.assert_allclose(cur["zeta"], 0.3, rtol=1e-3)
    assert np.all(cur["n"] == 2) and np.allclose(cur["zeta_se"], 0.0, atol=1e-12)


@pytest.mark.parametrize("engine", ["jax", "native"])
def test_empty_box_decays_as_the_analytic_oscillator(engine):
    """No grains: the primary rings down from z0 (and from v0 alone) with ζ = C / (2√(KM)) and
    f = f_n √(1 − ζ²) to 0.2 %, on either engine (dt and sampling are the simulator's)."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          ["grains=[]", f"numerics.engine={engine!r}", "numerics.chunk=0.25"])
    p = cfg.primary
    zeta = p.C / (2 * math.sqrt(p.K * p.M))
    fd = math.sqrt(p.K / p.M) / (2 * math.pi) * math.sqrt(1 - zeta ** 2)
    for z0, v0 in (([0.01, -0.02], 0.0), ([0.0], 0.5)):
        res = decay.measure(cfg, z0, duration=1.0, v0=v0, progress=False, echo=None)
        assert res.zeta_struct == pytest.approx(zeta, rel=1e-12)
        for per in res.cycles:
            c = per[0]
            assert len(c["Z"]) >= 10
            np.testing.assert_allclose(c["zeta"], zeta, rtol=2e-3)
            np.testing.assert_allclose(c["f"], fd, rtol=2e-3)
        X0 = res.cycles[0][0]["Z"][0]
        if v0 == 0.0:  # released at a peak (t = 0, not counted): the first cycle is between
            # the next two, Z = √(X1 X2) = z0 exp(−1.5 δ)
            delta = 2 * math.pi * zeta / math.sqrt(1 - zeta ** 2)
            assert X0 == pytest.approx(abs(z0[0]) * math.exp(-1.5 * delta), rel=2e-3)


def test_bad_free_decay_input_is_refused_before_compute():
    cfg = presets.get("sanchez2012-optimal")
    with pytest.raises(ConfigError, match="nothing to decay"):
        decay.measure(cfg, [0.0], progress=False, echo=None)
    with pytest.raises(ConfigError, match="system 'primary'"):
        decay.measure(presets.family("varela2023-reference"), [0.01], progress=False, echo=None)
    with pytest.raises(ConfigError, match="primary.z0 = inf"):
        validate(apply_overrides(cfg, {"primary.z0": float("inf")}))
    with pytest.raises(ConfigError, match="single-particle"):
        validate(apply_overrides(presets.get("sanchez2012-impact"), {"primary.z0": 0.01}))


@pytest.mark.long  # 39 s on 2 cores: CI's second step
def test_decay_cli_quick_writes_curves_and_figure(tmp_path):
    """250 grains, 2 beds: the file holds each bed's cycles and the mean curve, the grains damp
    more than the empty box at some amplitude, the figure is written; bad input is refused
    with a one-line message naming the parameter."""
    out = tmp_path / "d.h5"
    cmd = [sys.executable, "-m", "jaxdamp", "decay", "--preset", "sanchez2012-optimal", "--quick",
           "--z0", "0.02", "--replicates", "2", "--out", str(out), "--no-progress"]
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    assert "base motion is switched off" in p.stdout and "ζ =" in p.stdout
    with h5py.File(out) as h:
        g = h["decay"]
        assert g["cycles/zeta"].shape[:2] == (1, 2) and g["cycles/Z"].attrs["units"] == "m"
        zeta = g["curve/zeta"][0]
        assert np.nanmax(zeta) > 1.5 * g.attrs["zeta_struct"]
        # the grains' own share, from their dissipated energy: positive, below the total
        zg = g["curve/zeta_g"][0]
        ok = np.isfinite(zg)
        assert ok.sum() > 10 and np.all(zg[ok] > 0) and np.nanmax(zg) < np.nanmax(zeta)
        assert np.all(zeta[np.isfinite(zeta)] > 0)
        assert h["records/z_box"].shape[0] == 2
    assert (tmp_path / "d.png").stat().st_size > 10_000
    for args, match in ((["--preset", "sanchez2012-optimal"], "nothing to decay"),
                        (["--preset", "varela2023-reference"], "system 'primary'"),
                        (["--preset", "sanchez2012-optimal", "--z0", "abc"], "--z0")):
        p = subprocess.run([sys.executable, "-m", "jaxdamp", "decay", *args],
                           capture_output=True, text=True, timeout=120)
        assert p.returncode == 2 and match in p.stderr and "Traceback" not in p.stderr, p.stderr


def test_at_starting_peak_moves_each_cycle_to_its_first_peak():
    """For peaks X0 = 1, X1 = e^{−δ}: Z = √(X0 X1) → X0, ζ_g(Z) → ζ_g(Z) Z²/X0²."""
    delta = 0.5
    zeta = delta / math.sqrt(4 * math.pi ** 2 + delta ** 2)
    Z = math.exp(-delta / 2)
    c = at_starting_peak({"Z": np.array([Z]), "zeta": np.array([zeta]),
                          "zeta_g": np.array([0.03]), "f": np.array([15.0])})
    assert c["Z"][0] == pytest.approx(1.0, rel=1e-12)
    assert c["zeta_g"][0] == pytest.approx(0.03 * Z ** 2, rel=1e-12)
    assert c["f"][0] == 15.0 and c["zeta"][0] == zeta


def test_on_common_range_is_the_overlap_of_the_replicates():
    """Log-spaced grid from the largest smallest Z to the smallest largest Z; a curve with
    fewer than two cycles is left out; the mean across replicates on the grid."""
    curve = lambda Z, z: {"Z": np.array(Z), "zeta": np.full(len(Z), z),  # noqa: E731
                          "f": np.ones(len(Z))}
    r = on_common_range([curve([1.0, 4.0], 0.1), curve([2.0, 8.0], 0.3), curve([3.0], 9.0)],
                        3)
    np.testing.assert_allclose(r["Z"], [2.0, 2 * math.sqrt(2), 4.0], rtol=1e-12)
    np.testing.assert_allclose(r["zeta"], 0.2, rtol=1e-12)
    assert r["n"].tolist() == [2, 2, 2]
