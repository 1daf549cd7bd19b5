"""Designing for an operating envelope (issue 41): the envelope's statistics and budgets, the
design variables that change the grains, the batched search."""

import math

import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.cases.filling import cavity_volume, mass_ratio
from jaxdamp.config import ConfigError, apply_overrides
from jaxdamp.design.bayes import ToyProblem, _gp, batch_search
from jaxdamp.design.envelope import Envelope, EnvelopeProblem, front, summarise
from jaxdamp.design.space import DesignProblem, DesignSpace, stated_by_mass
from jaxdamp.validation import validate

#: a 24-grain damper on a light primary (experiments/design_optimisation's quick damper)
SMALL = {"grains.0.count": 24, "box.Lx": 0.02, "box.Ly": 0.02, "primary.M": 0.3,
         "primary.K": 2720.0, "primary.C": 1.0, "numerics.settle_time": 0.1}


def small():
    return apply_overrides(presets.get("sanchez2012-optimal"), SMALL)


@pytest.mark.parametrize("kw, words", [
    (dict(frequencies=(), levels=(0.001,)), "envelope frequencies"),
    (dict(frequencies=(15.0, -1.0), levels=(0.001,)), "each > 0 Hz"),
    (dict(frequencies=(15.0,), levels=(0.0,)), "base amplitude U, each > 0 m"),
    (dict(frequencies=(15.0,), levels=(0.001,), statistic="median"), "worst, mean"),
    (dict(frequencies=(15.0,), levels=(0.001,), mass_budget=-0.1), "mass_budget = -0.1"),
    (dict(frequencies=(15.0,), levels=(0.001,), volume_budget=math.inf), "volume_budget"),
])
def test_an_envelope_refuses_bad_input_naming_it(kw, words):
    with pytest.raises(ConfigError, match=words):
        Envelope(**kw)


def test_envelope_points_are_every_frequency_at_every_level():
    env = Envelope((13.0, 15.0), (0.001, 0.002, 0.004))
    assert env.points == [(13.0, 0.001), (15.0, 0.001), (13.0, 0.002), (15.0, 0.002),
                          (13.0, 0.004), (15.0, 0.004)]
    assert env.conditions()[3] == {"frequency": 15.0, "primary.U": 0.002}


def test_summarise_worst_and_mean_by_hand():
    """Three points, two designs, three beds: the worst point is the one of smallest mean
    over beds (not the smallest single value), its ± that point's standard error; the mean is
    each bed's envelope average, mean ± SE over beds."""
    rng = np.random.default_rng(0)
    C = rng.normal(10.0, 1.0, (3, 2, 3))
    C[1, 0] = [2.0, 4.0, 6.0]     # design 0: worst at point 1 (mean 4, SE 2/sqrt(3))
    C[2, 1] = [5.0, 5.5, 6.0]     # design 1: worst at point 2 (mean 5.5) ...
    C[0, 1, 0] = 1.0              # ... though its smallest single value is at point 0
    C[0, 1, 1:] = 30.0
    s = summarise(C, "worst")
    assert list(s["worst_point"]) == [1, 2]
    assert s["value"] == pytest.approx([4.0, 5.5])
    assert s["se"] == pytest.approx([2.0 / math.sqrt(3), 0.5 / math.sqrt(3)])
    assert s["ci95"][0] == pytest.approx(4.302653 * 2.0 / math.sqrt(3), rel=1e-6)  # t(0.975, 2)
    m = summarise(C, "mean")
    per_bed = C.mean(axis=0)
    assert m["value"] == pytest.approx(per_bed.mean(axis=1))
    assert m["se"] == pytest.approx(per_bed.std(axis=1, ddof=1) / math.sqrt(3))
    assert np.isnan(summarise(C[:, :, :1], "worst")["se"]).all()  # one bed: no error bar


def test_front_keeps_the_designs_no_other_beats_in_both():
    mass = [0.05, 0.05, 0.10, 0.12, 0.20, 0.20]
    value = [10.0, 12.0, 11.0, 20.0, 20.0, 25.0]
    assert list(front(mass, value)) == [1, 3, 5]  # 0 beaten by 1, 2 by 1, 4 by 3 (and 5)


def test_mass_ratio_and_volume_invert_the_fill_statements():
    """The mass ratio of a validated configuration is the one stated, to one grain; the
    thesis' 250 grains are 0.0958 of M; a count stated as a mass ratio keeps the grains; the
    cavity's volume counts every cell."""
    thesis = presets.get("sanchez2012-optimal")
    assert mass_ratio(validate(thesis)) == pytest.approx(0.0958, abs=1e-4)
    cfg = validate(apply_overrides(thesis, {"grains.0.mass_ratio": 0.05}))
    grain = 0.0958 / 250
    assert abs(mass_ratio(cfg) - 0.05) <= grain / 2 + 1e-12
    restated = stated_by_mass(thesis)
    assert restated.grains[0].count is None and validate(restated).grains[0].count == 250
    bigger = validate(apply_overrides(restated, {"grains.0.radius": 0.0025}))
    assert bigger.grains[0].count == round(250 * (0.003 / 0.0025) ** 3)  # the mass kept
    cells = validate(presets.get("sanchez2012-cells"))
    assert cavity_volume(cells) == pytest.approx(4 * 0.03675 ** 2 * cells.box.Lz)


def test_the_fill_and_the_grain_size_are_design_variables():
    """``mass_ratio`` and ``radius`` read back from a configuration, have default ranges, and
    the bed's height scales with the fill."""
    cfg = stated_by_mass(presets.get("sanchez2012-optimal"))
    s = DesignSpace.of(cfg, ("Lz", "mass_ratio", "radius"), h_ref=0.04)
    assert s.value(cfg) == pytest.approx([0.1225, 0.0958, 0.003], rel=1e-3)
    assert s.lo[1:] == pytest.approx([0.02, 0.67 * 0.003]) and s.hi[1] == 0.2
    assert s.bed_height([0.12, 2 * s.mass_ref, 0.003]) == pytest.approx(0.08)
    assert s.overrides([0.12, 0.05, 0.0025]) == {"box.Lz": 0.12, "grains.0.mass_ratio": 0.05,
                                                 "grains.0.radius": 0.0025}
    mix = apply_overrides(cfg, {"grains": [dict(count=10, radius=0.003, material="steel"),
                                           dict(count=10, radius=0.002, material="steel")]})
    with pytest.raises(ConfigError, match="radius: one species only"):
        DesignProblem(mix, None, names=("radius",))


def test_budgets_refuse_a_design_before_any_compute(monkeypatch):
    """A design over the mass budget is refused by ``evaluate`` naming the budget, before a
    single system runs (the sweep is never called)."""
    import jaxdamp.studies.sweep as sw

    env = Envelope((15.0,), (0.002,), mass_budget=0.05, volume_budget=1e-3)
    prob = EnvelopeProblem(stated_by_mass(small()), env, names=("Lz", "mass_ratio"))
    b = prob.budgets([0.05, 0.08])
    assert b["mass_ratio"] == pytest.approx(0.08, abs=0.004)
    assert b["volume"] == pytest.approx(0.02 * 0.02 * 0.05)
    assert prob.feasible([0.05, 0.04]) == (True, {"mass_budget": True, "volume_budget": True})
    assert not prob.feasible([0.05, 0.08])[0]
    monkeypatch.setattr(sw, "sweep", lambda *a, **k: pytest.fail("ran a system"))
    with pytest.raises(ConfigError, match="mass_budget = 0.05 exceeded"):
        prob.evaluate([[0.05, 0.04], [0.05, 0.08]], 2)


@pytest.mark.long  # ~20 s: three small batches
def test_designs_of_other_grains_run_in_their_own_batches_and_come_back_in_order():
    """Designs that change the grains (``radius``) are grouped into batches of one shape and
    their rows returned in the order asked: the same design on the same bed twice, around a
    design of other grains, gives the same numbers bit for bit; the envelope's points set the
    base amplitude (the primary moves about twice as far at twice the level), and ``C_eq`` is
    ``E / (π Ω Z²)`` of each point."""
    env = Envelope((15.16,), (0.002, 0.004))
    prob = EnvelopeProblem(small(), env, names=("Lz", "radius"), duration=0.4, seed=5)
    X = np.array([[0.05, 0.003], [0.05, 0.0025], [0.05, 0.003]])
    m = prob.measure(X, [11, 12, 11])
    assert m["Z"].shape == (2, 3)
    np.testing.assert_array_equal(m["Z"][:, 0], m["Z"][:, 2])
    np.testing.assert_array_equal(m["E"][:, 0], m["E"][:, 2])
    assert np.all(m["Z"][:, 1] != m["Z"][:, 0])
    assert np.all(m["Z"][1] / m["Z"][0] > 1.6) and np.all(m["Z"][1] / m["Z"][0] < 2.4)
    C = prob.damping(m["Z"], m["E"])
    assert C[1, 0] == pytest.approx(m["E"][1, 0] / (math.pi * 2 * math.pi * 15.16
                                                    * m["Z"][1, 0] ** 2))
    assert m["J"] == pytest.approx(C.min(axis=0))  # each bed's worst point
    ev = prob.evaluate(X[:2], 2)
    assert ev["C"].shape == (2, 2, 2) and ev["value"].shape == (2,)
    assert ev["budgets"][1]["mass_ratio"] == pytest.approx(ev["budgets"][0]["mass_ratio"],
                                                           rel=0.05)


def test_the_gaussian_process_takes_each_designs_noise():
    """Heteroscedastic noise: a design observed with a large standard error pulls the posterior
    mean less than one observed precisely."""
    U = np.array([[0.1], [0.3], [0.5], [0.7], [0.9]])
    y = np.array([0.0, 0.0, 1.0, 0.0, 0.0])
    sharp, *_ = _gp(U, y, np.array([0.01, 0.01, 0.01, 0.01, 0.01]), 0)
    loose, *_ = _gp(U, y, np.array([0.01, 0.01, 3.0, 0.01, 0.01]), 0)
    assert sharp.predict(U[2:3])[0] > loose.predict(U[2:3])[0] + 0.3


@pytest.mark.long  # ~12 s
def test_the_batched_search_beats_the_equal_budget_latin_hypercube():
    """On a known noisy 2-D function with a secondary peak (experiments/envelope_design.py,
    part C), 20 designs × 2 replicates: the search's recommendation has a smaller regret than
    the Latin hypercube's best observed design in most seeds and at the median."""
    from experiments.envelope_design import toy
    from jaxdamp.design.spsa import random_search

    g = np.stack(np.meshgrid(np.linspace(0, 1, 201), np.linspace(0, 1, 201)), -1).reshape(-1, 2)
    fmax = toy(g).max()
    gp, lhs = [], []
    for k in range(10):
        b = batch_search(ToyProblem(toy, d=2, noise=0.1, hetero=1.0, seed=k), n_start=8,
                         batch=4, rounds=3, replicates=2, seed=k)
        r = random_search(ToyProblem(toy, d=2, noise=0.1, hetero=1.0, seed=100 + k), 40,
                          replicates=2, seed=k)
        assert len(b.X) == len(r.X) == 20
        gp.append(fmax - toy(b.best_u)[0])
        lhs.append(fmax - toy(np.asarray(r.best["x"]))[0])
    gp, lhs = np.array(gp), np.array(lhs)
    assert (gp < lhs).sum() >= 7 and np.median(gp) < 0.5 * np.median(lhs)


def test_search_refuses_bad_settings():
    with pytest.raises(ConfigError, match="n_start = 1"):
        batch_search(ToyProblem(lambda u: u[:, 0]), n_start=1)


def test_the_base_of_a_cylinder_is_its_radius():
    """``base`` reads and writes a cylinder's radius (``container.radius``: a dimension of the
    container's own table, read by :func:`jaxdamp.config.get_path`)."""
    from jaxdamp.config import get_path

    cyl = presets.get("sanchez2012-cylinder")
    assert get_path(cyl, "container.radius") == 0.020734
    s = DesignSpace.of(cyl, ("Lz", "base"))
    assert s.value(cyl) == pytest.approx([0.1225, 0.020734])
    assert s.lo[1] == pytest.approx(0.8 * 0.020734)
    got = apply_overrides(cyl, s.overrides([0.1, 0.018]))
    assert got.container.dimension("radius") == 0.018 and got.container.Lz == 0.1


@pytest.mark.parametrize("argv, words", [
    (["--envelope-frequencies", "14,15"], "--envelope-frequencies needs --envelope-levels"),
    (["--mass-budget", "0.1"], "--mass-budget applies to an envelope"),
    (["--envelope-frequencies", "14,15", "--envelope-levels", "0.002", "--frequency", "15"],
     "--frequency is a single-point objective's"),
    (["--envelope-frequencies", "14,x", "--envelope-levels", "0.002"],
     "--envelope-frequencies"),
    (["--envelope-frequencies", "14", "--envelope-levels", "0.002", "--statistic", "worst",
      "--method", "batch", "--budget", "10"], "--budget applies to spsa and random"),
])
def test_cli_envelope_refuses_bad_input_in_one_line(argv, words, capsys):
    from jaxdamp.cli import main

    assert main(["optimize", "--preset", "sanchez2012-optimal", *argv]) == 2
    err = capsys.readouterr().err
    assert words in err and "Traceback" not in err


@pytest.mark.long  # ~40 s
def test_cli_optimize_an_envelope_by_the_batched_search(tmp_path, capsys):
    """``jaxdamp optimize`` with an envelope and a mass budget on the small bed: the batched
    search over Lz and the fill, the design confirmed on fresh beds with every point's C_eq
    and its added mass within the budget, a ``jaxdamp-optimize/3`` log naming the envelope."""
    import json

    import h5py

    from jaxdamp.cli import main

    out = tmp_path / "env.h5"
    sets = [a for k, v in SMALL.items() for a in ("--set", f"{k}={v}")]
    assert main(["optimize", "--preset", "sanchez2012-optimal", "--vars", "Lz,mass_ratio",
                 "--bounds", "Lz=0.04:0.1,mass_ratio=0.05:0.12", "--envelope-frequencies",
                 "14,15.16", "--envelope-levels", "0.002,0.0045", "--mass-budget", "0.09",
                 "--quick", "--duration", "0.3", *sets, "--out", str(out),
                 "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "maximise the worst C_eq [N s/m] over 4 points" in text
    assert "confirmed on 2 fresh beds (95 %): worst C_eq" in text and "per point (f, U)" in text
    with h5py.File(out) as h:
        assert h.attrs["method"] == "batch" and h.attrs["convergence"] == "not converged"
        prob = json.loads(h.attrs["problem"])
        assert prob["envelope"]["mass_budget"] == 0.09 and len(prob["envelope"]["points"]) == 4
        X = h["confirmation/X"][()]
        assert X.shape[1] == 2 and np.all(X[:, 1] <= 0.09 + 0.004)  # one grain's worth
        assert len(h["evaluations/X"]) == 2 * (3 + 2) + 2 * len(X)


def test_material_and_cells_are_whole_valued_design_variables():
    """A categorical variable (``material``, choices by name) and an integer one (``cells``):
    each value takes an equal share of its coordinate, ``to_u`` inverts ``to_x``, the
    overrides name the material before any friction, and the bed's height follows the
    density and the number of cells at a fixed mass."""
    from jaxdamp.design.space import parse_bounds

    cfg = stated_by_mass(apply_overrides(presets.get("sanchez2012-optimal"),
                                         {"grains.0.material": "steel"}))
    b = parse_bounds("material=steel/glass/lead,cells=1:4")
    assert b == {"material": ("steel", "glass", "lead"), "cells": (1.0, 4.0)}
    s = DesignSpace.of(cfg, ("friction", "material", "cells"), b, h_ref=0.04)
    assert s.value(cfg).tolist() == [0.23, 0.0, 1.0]
    xs = np.array([s.to_x([0.5, u, u]) for u in np.linspace(0, 1, 1201)])
    assert np.bincount(xs[:, 1].astype(int)).tolist() == [400, 400, 401]
    assert sorted(set(xs[:, 2])) == [1.0, 2.0, 3.0, 4.0]
    for x in ([0.3, 2.0, 3.0], [0.1, 0.0, 1.0]):
        np.testing.assert_allclose(s.to_x(s.to_u(x)), x)
    ov = s.overrides([0.3, 1.0, 2.0])
    assert list(ov) == ["grains.0.material", "grains.0.material.mu", "cells"]
    assert ov["grains.0.material"] == "glass" and ov["cells"] == 2
    got = validate(apply_overrides(cfg, ov))
    assert got.grains[0].material.mu == 0.3 and got.grains[0].material.density == 2520.0
    assert s.bed_height([0.3, 1.0, 2.0]) == pytest.approx(0.04 * 7810 / 2520 / 2)
    assert s.label([0.3, 2.0, 3.0]) == ["friction = 0.3", "material = lead", "cells = 3"]
    with pytest.raises(ConfigError, match="not an entry of the material table"):
        DesignSpace.of(presets.get("sanchez2012-optimal"), ("material",)).value()
    with pytest.raises(ConfigError, match="bounds of material"):
        DesignSpace.of(cfg, ("material",), {"material": ("steel", "unobtainium")})
    with pytest.raises(ConfigError, match="bounds of cells: whole numbers"):
        DesignSpace.of(cfg, ("cells",), {"cells": (1.5, 3.0)})


@pytest.mark.long  # ~25 s
def test_designs_of_other_materials_and_cells_run_and_keep_their_fill():
    """A batch of designs of two materials and one or two cells: each design's grains come
    out of its own group with the fill kept by mass (the glass bed has ~3.1× the grains of the
    steel one; two cells share the grains), and the rows come back in order (a repeat of the
    same design and bed equals the first bit for bit)."""
    cfg = apply_overrides(small(), {"grains.0.material": "steel"})
    env = Envelope((15.16,), (0.004,))
    prob = EnvelopeProblem(cfg, env, names=("Lz", "material", "cells"),
                           bounds={"material": ("steel", "glass"), "cells": (1, 2)},
                           duration=0.3, seed=3)
    X = np.array([[0.06, 0, 1], [0.06, 1, 1], [0.06, 0, 2], [0.06, 0, 1]], float)
    counts = [prob.design_config(x).grains[0].count * prob.design_config(x).cells for x in X]
    assert counts[1] == pytest.approx(counts[0] * 7810 / 2520, rel=0.05)
    assert abs(counts[2] - counts[0]) <= 1
    m = prob.measure(X, [21, 22, 23, 21])
    np.testing.assert_array_equal(m["Z"][:, 0], m["Z"][:, 3])
    assert np.all(np.isfinite(m["Z"])) and np.all(m["E"] > 0)
    assert len({tuple(np.round(z, 12)) for z in m["Z"].T}) == 3


def test_refine_locates_the_optimum_with_an_interval():
    """The batched search finds the basin; the trust region from its recommendation ends with
    an interior optimum within 0.02 of the true one of a noisy 1-D function in every seed, its
    95 % interval around it; more than one variable is refused. The interval held the true
    optimum in 4 of these 6 seeds (measured: the trust region's jackknife over 4 beds of a
    3-point stencil under-covers; noticed, not changed here)."""
    from jaxdamp.design.bayes import refine

    covered = 0
    for k in range(6):
        prob = ToyProblem(lambda u: 1.0 - 40.0 * (u[:, 0] - 0.37) ** 2, noise=0.02, seed=k)
        res = batch_search(prob, n_start=5, batch=2, rounds=1, replicates=2, seed=k)
        tr = refine(prob, res, replicates=4, max_rounds=5)
        o = tr.optimum
        assert o.interior and abs(o.x - 0.37) < 0.02 and o.lo < o.x < o.hi
        covered += o.lo <= 0.37 <= o.hi
    assert covered >= 4
    two = ToyProblem(lambda u: -u[:, 0], d=2)
    with pytest.raises(ConfigError, match="one continuous design variable"):
        refine(two, batch_search(two, n_start=3, rounds=0))
