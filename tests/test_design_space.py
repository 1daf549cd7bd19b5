"""Several design variables: Points sweeps, the design space, replicated SPSA, the CLI."""

import json

import h5py
import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.cli import main
from jaxdamp.config import ConfigError, apply_overrides
from jaxdamp.design import Objective
from jaxdamp.design.space import DesignSpace
from jaxdamp.design.spsa import latin_hypercube, spsa, spsa_gradient
from jaxdamp.studies.grid import Points
from jaxdamp.studies.sweep import sweep

SMALL = {"grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "numerics.settle_time": 0.15,
         "primary.M": 0.3, "primary.K": 2720.0, "primary.C": 1.0}
SMALL_SET = [a for k, v in SMALL.items() for a in ("--set", f"{k}={v}")]


def _small(**extra):
    return apply_overrides(presets.get("sanchez2012-optimal"), dict(SMALL, **extra))


@pytest.mark.long  # half a minute (the marker's definition)
def test_points_sweep_equals_the_grid_it_lists():
    """The same two configurations as a 1 x 2 grid and as Points: identical records (the
    layout only decides which configurations run, not how)."""
    cfg = _small(**{"numerics.duration": 0.1})
    grid = sweep(cfg, {"box.Lz": [0.05, 0.07]}, progress=False, echo=None)
    pts = sweep(cfg, Points({"box.Lz": [0.05, 0.07], "numerics.seed": [0, 0]}),
                progress=False, echo=None)
    for k in ("t", "z_box", "work"):
        np.testing.assert_array_equal(grid.records[k], pts.records[k])
    with pytest.raises(ConfigError, match="same number"):
        Points({"box.Lz": [0.05, 0.07], "box.Lx": [0.02]})


def test_design_space_projection_and_bad_input():
    """Normalised coordinates round-trip; projection keeps the bed below the lid (with a
    narrower base the bed is taller: ``h_ref (b_ref/b)²``) and inside the box shrunk by the
    perturbation; bad names and ranges are refused naming the variable."""
    cfg = presets.get("sanchez2012-optimal")
    s = DesignSpace.of(cfg, ("Lz", "base", "friction"), h_ref=0.04, margin=0.01)
    x = np.array([0.12, 0.04, 0.3])
    np.testing.assert_allclose(s.to_x(s.to_u(x)), x)
    u = s.project(s.to_u([0.07, s.lo[1], 0.3]), shrink=0.05)
    xp = s.to_x(u)
    h = 0.04 * (cfg.box.Lx / s.to_x(np.maximum(u - 0.05, 0))[1]) ** 2
    assert xp[0] >= h + 0.01 - 1e-12 and np.all((u >= 0.05 - 1e-12) & (u <= 0.95 + 1e-12))
    for names, bounds, msg in ((("Lz", "width"), None, "width"),
                               (("Lz",), {"Lz": (0.2, 0.1)}, "lower 0.2 must be below"),
                               (("Lz",), {"friction": (0.1, 0.5)}, "not among --vars"),
                               (("friction",), {"friction": (0.1, 5.0)}, "above 2")):
        with pytest.raises(ConfigError, match=msg):
            DesignSpace.of(cfg, names, bounds)


class _Noisy:
    """An analytic stand-in for the DEM: ``J = 5 − |u − u*|²_A`` plus noise common to the two
    members of a pair (a bed's realisation, variance 1) and independent per system (0.01)."""

    objective = Objective("damping")

    def __init__(self, seed=0):
        self.space = DesignSpace.of(presets.get("sanchez2012-optimal"), ("Lz", "base", "friction"))
        self.rng = np.random.default_rng(seed)
        self.sim_seconds, self._s = 0.0, 0
        self.target = np.array([0.3, 0.7, 0.2])
        self.A = np.array([4.0, 1.0, 2.0])

    def seeds(self, n):
        self._s += n
        return np.arange(self._s - n, self._s)

    def cost_per_system(self):
        return 1.0

    def true(self, u):
        return 5.0 - ((np.atleast_2d(u) - self.target) ** 2 * self.A).sum(axis=1)

    def measure(self, X, seeds, pairs=False):
        u = self.space.to_u(X)
        common = {s: self.rng.standard_normal() for s in np.unique(seeds)}
        J = self.true(u) + np.array([common[s] for s in seeds]) \
            + 0.1 * self.rng.standard_normal(len(u))
        self.sim_seconds += len(X)
        return {"J": J, "sim_seconds": float(len(X))}


def test_spsa_gradient_is_unbiased_with_a_calibrated_error():
    """Over 200 independent estimates at one point: the mean of the SPSA gradient matches the
    analytic gradient within 4 standard errors of that mean, and the reported standard errors
    are calibrated (z-score spread between 0.8 and 1.25). Common random numbers make the
    pair differences free of the bed noise (variance 1): the error comes from the random
    directions and the per-system noise only."""
    prob = _Noisy(1)
    u = np.array([0.5, 0.4, 0.6])
    g_true = -2 * prob.A * (u - prob.target)
    rng = np.random.default_rng(2)
    ests = [spsa_gradient(prob, u, pairs=8, c=0.05, rng=rng)
            for _ in range(200)]
    G = np.array([e.grad for e in ests])
    SE = np.array([e.grad_se for e in ests])
    assert np.all(np.abs(G.mean(axis=0) - g_true) < 4 * G.std(axis=0, ddof=1) / np.sqrt(200))
    z = (G - g_true) / SE
    assert np.all((z.std(axis=0) > 0.8) & (z.std(axis=0) < 1.25)), z.std(axis=0)


def test_spsa_reaches_the_optimum_of_a_noisy_bowl_and_beats_the_random_search():
    """Adam on replicated SPSA gradients (60 iterates of 4 pairs) from a corner of the noisy
    bowl ends within 0.08 (in normalised coordinates) of the optimum; a Latin hypercube given
    the same number of systems, 2 per design, picks a design of lower true objective (mean over
    5 seeds of both: its selection is swamped by the bed noise that common random numbers
    cancel in SPSA's differences)."""
    gaps, lhs, ours = [], [], []
    for seed in range(5):
        prob = _Noisy(seed)
        res = spsa(prob, prob.space.to_x([0.9, 0.1, 0.9]), pairs=4, max_iter=60, lr=0.08,
                   decay=0.97, seed=seed, progress=False)
        gaps.append(np.abs(res.u_average - prob.target).max())
        ours.append(prob.true(res.u_average)[0])
        n = int(prob.sim_seconds // 2)
        U = latin_hypercube(n, 3, np.random.default_rng(seed))
        noisy = prob.true(U) + np.random.default_rng(seed + 9).standard_normal(n) / np.sqrt(2)
        lhs.append(prob.true(U[np.argmax(noisy)])[0])
        assert res.history["sim_seconds"][-1] == pytest.approx(60 * 8)
    assert max(gaps) < 0.08, gaps
    assert np.mean(lhs) < np.mean(ours), (lhs, ours)


@pytest.mark.long
def test_cli_optimize_three_variables_small_bed(tmp_path, capsys):
    """``jaxdamp optimize --vars Lz,base,friction --quick`` on the small bed: SPSA iterates,
    the design confirmed on fresh beds next to the start, a ``jaxdamp-optimize/3`` log with
    units, the design inside its bounds; bad --x0 refused before any compute."""
    out = tmp_path / "d.h5"
    assert main(["optimize", "--preset", "sanchez2012-optimal", "--vars", "Lz,base,friction",
                 "--quick", *SMALL_SET, "--bounds", "Lz=0.03:0.1", "--out", str(out),
                 "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "confirmed on 2 fresh beds" in text and "simulated DEM system-seconds" in text
    with h5py.File(out) as h:
        assert h.attrs["format"] == "jaxdamp-optimize/3"
        assert json.loads(h.attrs["variables"]) == ["Lz", "base", "friction"]
        assert json.loads(h["confirmation/X"].attrs["units"]) == ["m", "m", ""]
        X = h["confirmation/X"][()]
        space = json.loads(h.attrs["problem"])["space"]
        assert np.all((X >= np.array(space["lo"])) & (X <= np.array(space["hi"])))
        assert len(h["iterations/u"]) == 2 and np.isfinite(h["confirmation/mean"][()]).all()
        assert h.attrs["sim_seconds"] > 0
    assert main(["optimize", "--preset", "sanchez2012-optimal", "--vars", "Lz,base",
                 "--x0", "0.5,0.03"]) == 2
    assert "--x0 Lz = 0.5: outside its bounds" in capsys.readouterr().err
