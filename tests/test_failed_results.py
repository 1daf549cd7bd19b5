"""Results that are not results: FRF fits the data do not determine (one rule, printed, stored
and drawn by it), optimisers that did not converge or failed (one rule, printed with the status
and stored), refused empty options, and the FRF plot of a replicated sweep."""

import json
import re
import warnings

import h5py
import numpy as np
import pytest

from jaxdamp import cli
from jaxdamp.analysis.response import (
    FIT_MAX_RELATIVE_SE,
    fit_failure,
    fit_frf,
    fit_frf_replicates,
    frf_amplitude,
)
from jaxdamp.cases import presets

U, K, M, C = 0.0045, 21500.0, 2.37, 7.6
#: Z(f) [m] of `jaxdamp frf --preset sanchez2012-optimal --quick` (one bed, 6 frequencies; the
#: steady or fixed-window amplitudes that command fits): a peak at 17 Hz, none sampled near it.
QUICK_F = [5.0, 9.0, 13.0, 17.0, 21.0, 25.0]
QUICK_Z = [0.00536127, 0.00892596, 0.01390365, 0.02395848, 0.00546017, 0.00272614]


def _no_runtime_warning(fn):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn()
    assert not [w for w in caught if issubclass(w.category, RuntimeWarning)], \
        [str(w.message) for w in caught]
    return out


# -- FRF fits ------------------------------------------------------------------------------
@pytest.mark.parametrize("n", [1, 2])
def test_fit_without_degrees_of_freedom_is_failed_without_a_warning(n):
    """One or two frequencies for two parameters: no residual variance, so no error — FAILED
    with the reason, for both weightings, and no RuntimeWarning (was: `invalid value
    encountered in sqrt` and a relative fit printed as `M_ef = 2.597 ± 58`)."""
    f = [12.0, 15.0][:n]
    Z = frf_amplitude(f, 2.6, K, 8.0, U)
    for w in ("relative", "absolute"):
        fit = _no_runtime_warning(lambda: fit_frf_replicates(f, Z, U, K, M, C, residuals=w))
        assert fit["points"] == n
        assert fit_failure(fit) == (f"no degrees of freedom: {n} frequenc"
                                    f"{'y' if n == 1 else 'ies'} for 2 parameters, need at "
                                    "least 3")


def test_fit_whose_error_exceeds_the_limit_is_failed():
    """The quick DEM FRF (no sample near its peak) gives C_ef = 2.3 ± 130 N s/m (relative) and
    14 ± 15 (absolute): both FAILED by the relative-error limit, with the numbers in the
    reason. A well-sampled FRF with 1 % noise passes, and its errors are the classic
    ``sqrt(diag((JᵀJ)⁻¹) s²)``."""
    for w in ("relative", "absolute"):
        fit = fit_frf_replicates(QUICK_F, QUICK_Z, U, K, M, C, residuals=w)
        why = fit_failure(fit)
        assert why.startswith("C_ef = ") and "(fit error)" in why, why
        assert fit["fit_se_C"] > FIT_MAX_RELATIVE_SE * fit["C_ef"]
        assert "not determined by the data" in why and "limit of 50 %" in why
    f = np.linspace(10, 20, 11)
    noise = 0.01 * np.random.default_rng(1).standard_normal(11)
    Z = frf_amplitude(f, 2.6, K, 20.0, U) * (1 + noise)
    Mf, Cf, dM, dC = fit_frf(f, Z, U, K, M, C)
    assert fit_failure(fit_frf_replicates(f, Z, U, K, M, C)) == ""
    eps = 1e-7  # the Jacobian of the relative residuals by central differences
    r = lambda m, c: frf_amplitude(f, m, K, c, U) / Z - 1.0
    J = np.stack([(r(Mf + eps, Cf) - r(Mf - eps, Cf)) / (2 * eps),
                  (r(Mf, Cf + eps) - r(Mf, Cf - eps)) / (2 * eps)], axis=1)
    s2 = np.sum(r(Mf, Cf) ** 2) / (len(f) - 2)
    ref = np.sqrt(np.diag(np.linalg.inv(J.T @ J)) * s2)
    assert np.allclose([dM, dC], ref, rtol=1e-3), ([dM, dC], ref)


def test_replicated_fit_needs_its_own_fit_error_below_the_limit():
    """Two replicates that agree (a tiny SE across them) on a curve that does not determine
    C_ef: the fit error of the mean FRF decides — FAILED, naming it."""
    Zr = np.stack([QUICK_Z, np.asarray(QUICK_Z) * 1.0001], axis=1)
    fit = fit_frf_replicates(QUICK_F, Zr, U, K, M, C)
    assert fit["se_C"] < 0.05 * fit["C_ef"]
    assert "(fit error of the mean FRF)" in fit_failure(fit)


def test_failed_fit_is_stored_and_not_drawn(tmp_path):
    """/fit/ok, /fit/failure, the fit's own errors and the rule's limit in the file; the figure
    draws no curve for the failed fit and says why."""
    from jaxdamp.figures import frf_figure
    from jaxdamp.io.sweepfile import write_fit

    fits = {w: [fit_frf_replicates(QUICK_F, QUICK_Z, U, K, M, C, residuals=w)]
            for w in ("relative", "absolute")}
    with h5py.File(tmp_path / "s.h5", "w") as h:
        write_fit(h, fits, "relative")
    with h5py.File(tmp_path / "s.h5") as h:
        assert h["fit/ok"][()].tolist() == [False] and h["fit/absolute/ok"][()].tolist() == [False]
        assert b"not determined by the data" in h["fit/failure"][0]
        assert h["fit/fit_se_C_ef"][0] == pytest.approx(fits["relative"][0]["fit_se_C"])
        assert h["fit"].attrs["max_relative_se"] == FIT_MAX_RELATIVE_SE
    why = fit_failure(fits["relative"][0])
    fig = frf_figure(np.asarray(QUICK_F), np.asarray(QUICK_Z)[:, None], [None],
                     presets.get("sanchez2012-optimal").primary, 0.2, [None], failures=[why])
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert not any(lab.startswith("fit: M_ef") for lab in labels)
    # the fitted value's last digits move with the libraries (2.3 in earlier environments,
    # 2.299 with scipy 1.17.1 and numpy 2.4.6): the label names it and its error
    named = [re.match(r"fit failed \(not a result\): C_ef = ([0-9.]+) ± 1\.3e\+02", lab)
             for lab in labels]
    assert [float(m[1]) for m in named if m] == [pytest.approx(2.3, rel=1e-3)], labels


def test_frf_cli_prints_a_fit_without_degrees_of_freedom_as_failed(tmp_path, capsys):
    """`jaxdamp frf --preset sanchez2012-impact --n 1` (quick): both fits FAILED with the
    reason, no M_ef printed as a result, no RuntimeWarning, the file flags it."""
    out = tmp_path / "f.h5"
    rc = _no_runtime_warning(lambda: cli.main(
        ["frf", "--preset", "sanchez2012-impact", "--quick", "--n", "1", "--out", str(out),
         "--no-progress"]))
    assert rc == 0
    text = capsys.readouterr()
    assert ("relative fit FAILED (no degrees of freedom: 1 frequency for 2 parameters, need "
            "at least 3): no M_ef, C_ef; absolute fit FAILED (no degrees") in text.out
    assert "M_ef = " not in text.out and "RuntimeWarning" not in text.err
    with h5py.File(out) as h:
        assert h["fit/ok"][()].tolist() == [False]
        assert b"no degrees of freedom" in h["fit/failure"][0]


def test_frf_refuses_an_empty_frequency_list(capsys):
    assert cli.main(["frf", "--preset", "sanchez2012-impact", "--frequencies", ","]) == 2
    err = capsys.readouterr().err
    assert ("--frequencies ',': expected a comma-separated list of frequencies [Hz]" in err
            and len(err.splitlines()) == 1)


# -- FRF plot of a replicated sweep --------------------------------------------------------
def _replicated_sweep_file(path, R=2):
    """A sweep file as `jaxdamp frf --replicates R` writes it (the writer's own functions):
    axes {"frequency": …, "replicates": R}, per-replicate and steady amplitudes, /fit."""
    from jaxdamp.io.sweepfile import SweepFile, write_fit

    cfg = presets.get("sanchez2012-optimal")
    p = cfg.primary
    f = np.linspace(11.0, 19.0, 7)
    rng = np.random.default_rng(3)
    Zr = frf_amplitude(f, 2.55, p.K, 30.0, p.U)[:, None] * (1 + 0.03 * rng.standard_normal((7, R)))
    sf = SweepFile.create(str(path), cfg, {"frequency": f}, [cfg] * (7 * R), 1e-5, 1.0, "native",
                          replicates=R)
    stationary = np.ones((7, R), bool)
    stationary[0, 0] = False  # one replicate falls back to its fixed-window amplitude
    steady = {"amplitude": {"values": np.where(stationary, Zr, np.nan),
                            "stationary": stationary}}
    sf.write_summary({"amplitude": Zr.mean(1)}, {"amplitude": "m"}, {"amplitude": Zr}, steady,
                     replicates=R, steady_units=lambda q: "m")
    fits = {w: [fit_frf_replicates(f, Zr, p.U, p.K, p.M, max(p.C, 1.0), residuals=w)]
            for w in ("relative", "absolute")}
    write_fit(sf.h5, fits, "relative")
    sf.finish(1.0)
    sf.close()
    return f, Zr


def test_plot_frf_of_a_replicated_sweep_draws_the_error_bars(tmp_path):
    """`jaxdamp plot FILE --kind frf` on a sweep with replicates (was: TypeError on the axes'
    "replicates" entry): the replicate mean with ± 2 SE error bars and the fit."""
    from jaxdamp.figures import frf_from_file

    path = tmp_path / "frf.h5"
    f, Zr = _replicated_sweep_file(path)
    assert cli.main(["plot", str(path), "--kind", "frf", "--out", str(tmp_path / "f.png")]) == 0
    assert (tmp_path / "f.png").stat().st_size > 10_000
    ax = frf_from_file(str(path)).axes[0]
    [bars] = ax.containers
    segments = bars.lines[2][0].get_segments()
    U = presets.get("sanchez2012-optimal").primary.U
    half = np.array([abs(s[1, 1] - s[0, 1]) / 2 for s in segments])
    se = Zr.std(axis=1, ddof=1) / np.sqrt(2)
    assert np.allclose(half, 2 * se / U)
    dem = [line for line in ax.get_lines() if line.get_label() == "DEM"][0]
    assert np.allclose(dem.get_ydata(), Zr.mean(axis=1) / U)
    assert any(line.get_label().startswith("fit: M_ef") for line in ax.get_lines())


@pytest.mark.long
def test_frf_cli_with_replicates_then_plot(tmp_path, capsys):
    """The real command: `jaxdamp frf … --replicates 2 --out`, then `jaxdamp plot --kind frf`
    on its file (a tiny bed, 3 frequencies)."""
    out = tmp_path / "r2.h5"
    assert cli.main(["frf", "--preset", "sanchez2012-optimal", "--frequencies", "10,15,20",
                     "--replicates", "2", "--out", str(out), "--no-progress",
                     "--set", "grains.0.count=20", "--set", "numerics.duration=0.1",
                     "--set", "numerics.chunk=0.05", "--set", "numerics.settle_time=0.05"]) == 0
    capsys.readouterr()
    assert cli.main(["plot", str(out), "--kind", "frf", "--out", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").stat().st_size > 10_000


# -- optimisers ----------------------------------------------------------------------------
def test_convergence_rule():
    """The one rule: an exact gradient converges when the secant Newton distance is within
    xtol; on a bound when the objective improves beyond it; an estimated gradient when it is
    not significant for `patience` iterates; never without an error estimate."""
    from jaxdamp.design.status import ConvergenceRule

    rule = ConvergenceRule(0.0, 1.0, 1e-3, maximise=False)  # minimise (x - 0.5)²
    assert rule.check(0.3, 2 * (0.3 - 0.5), 0.0) == ""  # no curvature yet
    assert rule.check(0.45, 2 * (0.45 - 0.5), 0.0) == ""  # 0.05 away
    assert "within xtol" in rule.check(0.4995, 2 * (0.4995 - 0.5), 0.0)
    up = ConvergenceRule(0.0, 1.0, 1e-3, maximise=True)  # maximise x: optimum on the bound 1
    assert "upper bound 1 with the objective still improving" in up.check(1.0, 1.0, 0.0)
    assert up.check(0.5, 1.0, 0.0) == ""
    noisy = ConvergenceRule(0.0, 1.0, 1e-3, maximise=False, patience=3)
    assert [noisy.check(0.5, g, 1.0) for g in (0.5, -0.3, 2.0, 0.1, 0.2)][-1] == ""
    assert "not significant" in noisy.check(0.5, -0.4, 1.0)
    blind = ConvergenceRule(0.0, 1.0, 1e-3, maximise=False)
    assert all(blind.check(0.5, 0.0, np.nan) == "" for _ in range(5))
    spsa_like = ConvergenceRule([0.1, 0.1], [0.9, 0.9], 1e-3, maximise=True, patience=1,
                                names=("Lz", "friction"))
    why = spsa_like.check([0.9, 0.4], [5.0, 0.1], [1.0, 1.0])
    assert "Lz on its upper bound" in why and "not significant" in why


class _Bowl:
    """An exact 1-D objective for the optimiser: ``(x − x*)²`` minimised, NaN beyond
    ``wall``."""

    variable = "gap"

    def __init__(self, x_star=0.08, wall=np.inf):
        from jaxdamp.design import Objective

        self.objective = Objective("amplitude")
        self.x_star, self.wall = x_star, wall

    def evaluate(self, x, state=None):
        from jaxdamp.design import Estimate

        if x > self.wall:
            return Estimate(np.nan, 0.0, np.nan, 0.0, 1.0, 0.0, extra={"reason": "no orbit"}), None
        return Estimate((x - self.x_star) ** 2, 0.0, 2 * (x - self.x_star), 0.0, 1.0, 0.0), None

    def bounds(self):
        return 0.005, 0.3

    def to_lz(self, x):
        return x + 0.039


def test_optimizer_reports_its_status():
    """Converged (stationary; on a bound), NOT CONVERGED at the cap with its best iterate,
    FAILED on a non-finite objective — never an unqualified "result"."""
    from jaxdamp.design import optimize

    done = optimize(_Bowl(), 0.03, lr=0.01, decay=0.9, max_iter=60, xtol=2e-4, progress=False)
    assert done.status.converged and "within xtol" in done.status.reason
    assert abs(done.design - 0.08) < 2e-4 and done.status.iterations < 60
    cap = optimize(_Bowl(), 0.03, lr=0.01, decay=0.9, max_iter=3, xtol=1e-5, progress=False)
    assert cap.status.state == "not converged" and cap.reason == "max_iter = 3 reached"
    assert cap.status.headline() == "NOT CONVERGED after 3 iterations"
    assert cap.best["x"] == pytest.approx(cap.history["x"][-1])
    edge = optimize(_Bowl(x_star=0.5), 0.25, lr=0.05, decay=0.95, max_iter=40, xtol=1e-5,
                    progress=False)
    assert edge.status.converged and "upper bound 0.3" in edge.status.reason
    bad = optimize(_Bowl(wall=0.05), 0.03, lr=0.01, decay=0.9, max_iter=40, xtol=1e-5,
                   progress=False)
    assert bad.status.failed and "no orbit" in bad.reason
    assert bad.best["x"] <= 0.05 and np.isnan(bad.design)


def test_optimize_cli_failed_is_exit_3_and_stored(tmp_path, capsys):
    """S3 from a gap without a stable periodic orbit: `FAILED: …` with the reason, exit 3, no
    "optimum" line, the status in the log (was: exit 0 and "optimum Lz = … nan")."""
    out = tmp_path / "o.h5"
    assert cli.main(["optimize", "--preset", "sanchez2012-impact", "--quick", "--gap0", "0.15",
                     "--out", str(out), "--no-progress"]) == 3
    text = capsys.readouterr().out
    assert "FAILED: non-finite objective or gradient at gap = 0.15" in text
    assert "not a stable periodic orbit" in text and "optimum Lz" not in text
    with h5py.File(out) as h:
        assert h.attrs["convergence"] == "failed" and h.attrs["iterations"] == 1
        assert "not a stable periodic orbit" in h.attrs["convergence_reason"]


@pytest.mark.long
def test_optimize_cli_not_converged_at_the_cap(tmp_path, capsys):
    """The S3 quick optimisation stopped at 25 iterations (gradient -0.7 N s/m per m, the
    stationary point ~8e-5 m away): NOT CONVERGED with its best iterate, not "optimum"; with
    the default 30 it converges (after 26)."""
    out = tmp_path / "o.h5"
    assert cli.main(["optimize", "--preset", "sanchez2012-impact", "--quick", "--max-iter",
                     "25", "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert ("NOT CONVERGED after 25 iterations (max_iter = 25 reached; last gradient -0.695 "
            "N s/m per m); best iterate Lz = 0.12437 m (gap = 0.085375 m)") in text
    assert "optimum Lz" not in text
    with h5py.File(out) as h:
        assert h.attrs["convergence"] == "not converged"
        assert json.loads(h.attrs["result"])["best_iterate"] == 24
    assert cli.main(["optimize", "--preset", "sanchez2012-impact", "--quick",
                     "--no-progress"]) == 0
    assert "converged after 26 iterations" in capsys.readouterr().out


@pytest.mark.parametrize("band", [",", "", "0,15", "nan,15"])
def test_optimize_refuses_an_empty_or_invalid_band(band, capsys):
    """`--band ,` was silently the default 9-point band (row 55)."""
    assert cli.main(["optimize", "--preset", "sanchez2012-impact", "--quick", "--objective",
                     "band", "--band", band]) == 2
    err = capsys.readouterr().err
    assert f"--band {band!r}: expected a comma-separated list of frequencies" in err
    assert len(err.splitlines()) == 1


def test_search_status_on_the_bound_and_failed():
    """The scan converges on a bound with no interior optimum; a non-finite value is
    FAILED."""
    from jaxdamp.design import Objective, adaptive_scan

    class Rising:
        variable = "Lz"
        objective = Objective("damping")
        freqs = (15.0,)
        sim_seconds = 0.0

        def scan(self, xs):
            return np.asarray(xs, float) * 10.0

    up = adaptive_scan(Rising(), 0.05, 0.3)
    assert up.status.converged and "upper bound 0.3" in up.status.reason

    class Holes(Rising):
        def scan(self, xs):
            v = -(np.asarray(xs, float) - 0.1) ** 2
            return np.where(np.asarray(xs) > 0.2, np.nan, v)

    assert adaptive_scan(Holes(), 0.05, 0.3).status.failed


def test_dem_problem_shows_progress_bars(capsys):
    """`make_problem(..., progress=True)` (what `jaxdamp optimize` passes for the DEM's trust
    and scan methods unless --no-progress): the settling bar (tqdm, as the runs')."""
    from jaxdamp.config import apply_overrides
    from jaxdamp.design import Objective, make_problem

    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {"grains.0.count": 8, "box.Lx": 0.02, "box.Ly": 0.02})
    prob, _ = make_problem(cfg, Objective("damping"), quick=True, progress=True)
    assert prob.progress
    assert "settling 2 bed(s) of 8 grains" in capsys.readouterr().err
