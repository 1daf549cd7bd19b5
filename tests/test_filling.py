"""Filling a cavity as a designer states it (:mod:`jaxdamp.cases.filling`): a count, a mass
ratio or a fill fraction at random packing; the random-packing relation against an
independent correlation; impossible fills refused by name and limit before any compute."""

import dataclasses
import math

import numpy as np
import pytest

from jaxdamp import cli
from jaxdamp.cases import presets
from jaxdamp.cases.filling import (
    fill_fraction,
    mean_grain_volume,
    packing_fraction,
    random_packing_fraction,
)
from jaxdamp.config import Config, ConfigError, Container, apply_overrides, from_dict, load_toml
from jaxdamp.validation import validate

THESIS = presets.get("sanchez2012-optimal")  # 250 grains of radius 3 mm, M = 2.37 kg


def _cylinder(cfg, radius, Lz):
    return dataclasses.replace(cfg, box=None,
                               container=Container("cylinder", Lz, (("radius", radius),)))


def test_random_packing_is_dixons_and_agrees_with_an_independent_correlation():
    """Dixon (1988) at D/d = 5, 10, 20 (hand-computed φ = 1 − ε), continuous at its branch
    points, → 0.60 in a wide cavity; within 0.012 of Benyahia & O'Neill (2005),
    ε = 0.390 + 1.740/(D/d + 1.140)², over D/d = 5–20 (the span the issue asks for)."""
    for D_over_d, phi in ((5, 1 - 0.4265), (10, 1 - 0.409120), (20, 1 - 0.403530)):
        assert random_packing_fraction(1 / D_over_d) == pytest.approx(phi, abs=1e-4)
    for x in (0.5, 0.536):
        assert random_packing_fraction(x - 1e-9) == pytest.approx(
            random_packing_fraction(x + 1e-9), abs=1e-3)
    assert random_packing_fraction(0.0) == pytest.approx(0.60, abs=1e-12)
    ratios = np.linspace(5, 20, 61)
    benyahia = 1 - (0.390 + 1.740 / (ratios + 1.140) ** 2)
    dixon = np.array([random_packing_fraction(1 / r) for r in ratios])
    assert np.max(np.abs(dixon - benyahia)) < 0.012
    assert np.all(np.diff(dixon) > 0)  # looser in narrower cavities


def test_the_mean_grain_volume_of_a_radius_spread():
    """(4/3)π R³ (1 + s²) for radii uniform in R[1 − s, 1 + s], against quadrature."""
    sp = dataclasses.replace(THESIS.grains[0], radius_spread=0.3)
    r = np.linspace(0.7, 1.3, 200001) * sp.radius
    quad = np.trapezoid(4 / 3 * np.pi * r**3, r) / (r[-1] - r[0])
    assert mean_grain_volume(sp) == pytest.approx(quad, rel=1e-9)


def test_a_mass_ratio_gives_the_thesis_count_and_the_stated_mass():
    """μ = 0.0958 of M = 2.37 kg in 3 mm steel grains: the thesis' 250; any μ gives the count
    whose mass is within half a grain of μ M; the statement stays beside the count."""
    assert validate(apply_overrides(THESIS, {"grains.0.mass_ratio": 0.0958})).grains[0].count \
        == 250
    for mu in (0.02, 0.05, 0.1):
        sp = validate(apply_overrides(THESIS, {"grains.0.mass_ratio": mu})).grains[0]
        m = sp.material.density * mean_grain_volume(sp)
        assert abs(sp.count * m - mu * THESIS.primary.M) <= m / 2
        assert sp.mass_ratio == mu and sp.fill_fraction is None


def test_a_fill_fraction_gives_the_bed_of_that_fraction_of_the_cavity():
    """f = 0.3, 0.6 of a cylinder of radius 20 mm (D/d = 6.7) and of the thesis box: the
    count's bed at random packing fills f of the cavity within one grain."""
    for cfg in (THESIS, _cylinder(THESIS, 0.02, 0.1)):
        for f in (0.3, 0.6):
            res = validate(apply_overrides(cfg, {"grains.0.fill_fraction": f}))
            sp = res.grains[0]
            one = fill_fraction(res, sp, 1)
            assert abs(fill_fraction(res, sp, sp.count) - f) <= one / 2 + 1e-12
    V = math.pi * 0.02**2 * 0.1
    cyl = _cylinder(THESIS, 0.02, 0.1)
    n = validate(apply_overrides(cyl, {"grains.0.fill_fraction": 1.0})).grains[0].count
    assert n == round(packing_fraction(cyl, cyl.grains[0]) * V / mean_grain_volume(cyl.grains[0]))


def test_a_change_of_mass_or_cavity_derives_the_count_again():
    """Over a mass-ratio or fill-fraction configuration, an override of M or Lz (or a TOML file
    setting them) derives the count again; setting count replaces the statement."""
    mu = validate(apply_overrides(THESIS, {"grains.0.mass_ratio": 0.05}))
    heavier = validate(apply_overrides(mu, {"primary.M": 4.74}))
    assert heavier.grains[0].count in (2 * mu.grains[0].count - 1, 2 * mu.grains[0].count,
                                       2 * mu.grains[0].count + 1)
    f = validate(apply_overrides(THESIS, {"grains.0.fill_fraction": 0.4}))
    taller = validate(apply_overrides(f, ["box.Lz=0.245"]))
    assert abs(taller.grains[0].count / f.grains[0].count - 2) < 0.01
    counted = validate(apply_overrides(mu, {"grains.0.count": 77}))
    assert counted.grains[0].count == 77 and counted.grains[0].mass_ratio is None
    assert validate(from_dict(mu.to_dict())) == mu  # stored and read back
    assert validate(mu) == mu


def test_a_toml_states_the_fill_by_mass(tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text("[primary]\nM = 4.74\n")
    over = load_toml(str(path), base=validate(apply_overrides(THESIS,
                                                              {"grains.0.mass_ratio": 0.0958})))
    assert validate(over).grains[0].count in (499, 500, 501)
    path.write_text('[[grains]]\nmass_ratio = 0.0958\nradius = 0.003\nname = "steel"\n'
                    '[grains.material]\nE = 2.03e9\nnu = 0.3\ndensity = 8030.0\nmu = 0.3\n'
                    'gamma_n = 20.0\ngamma_s = 60.0\n')
    assert validate(load_toml(str(path), base=THESIS)).grains[0].count == 250


@pytest.mark.parametrize("change, words", [
    ({"grains.0.mass_ratio": -0.1}, "grains.0.mass_ratio = -0.1: must be a number > 0"),
    ({"grains.0.fill_fraction": 1.2}, "grains.0.fill_fraction = 1.2: must be in (0, 1]"),
    ({"grains.0.mass_ratio": 1e-6}, "is less than one grain"),
    ({"grains.0.mass_ratio": 0.1, "grains.0.fill_fraction": 0.3},
     "give one of mass_ratio and fill_fraction"),
    ({"grains.0.mass_ratio": 0.1, "grains.0.count": 300},
     "grains.0.count = 300 disagrees with grains.0.mass_ratio = 0.1, which gives 261 grains"),
    ({"grains.0.mass_ratio": 5.0}, "the most that fits is grains.0.mass_ratio ≤ 0.32"),
])
def test_impossible_or_ambiguous_fills_are_refused_by_name_and_limit(change, words):
    with pytest.raises(ConfigError) as err:
        validate(apply_overrides(THESIS, change))
    assert words in str(err.value)


def test_a_cavity_narrower_than_a_grain_is_named_before_the_fill_is_reckoned():
    """A cylinder narrower than one grain is the grain's misfit, not an overfull fill (the
    random-packing relation would be extrapolated far outside its range there)."""
    cyl = validate(presets.get("sanchez2012-cylinder"))
    for radius in (0.002, 0.003):
        with pytest.raises(ConfigError) as err:
            validate(apply_overrides(presets.get("sanchez2012-cylinder"),
                                     {"container.radius": radius}))
        assert str(err.value) == ("grains.0.radius = 0.003 (largest 0.003 m): a grain of "
                                  f"diameter 0.006 m does not fit container.radius = {radius} m")
    assert cyl.grains[0].count == 250


def test_the_largest_mass_ratio_named_fits_and_a_little_more_does_not():
    with pytest.raises(ConfigError) as err:
        validate(apply_overrides(THESIS, {"grains.0.mass_ratio": 5.0}))
    text = str(err.value)
    assert "random packing (φ = 0.581" in text and "Dixon 1988" in text
    limit = float(text.split("mass_ratio ≤ ")[1].split()[0])
    assert validate(apply_overrides(THESIS, {"grains.0.mass_ratio": 0.999 * limit}))
    with pytest.raises(ConfigError):
        validate(apply_overrides(THESIS, {"grains.0.mass_ratio": 1.01 * limit}))


def test_a_mass_ratio_needs_a_primary_and_a_fill_needs_a_statement():
    with pytest.raises(ConfigError, match="system = 'driven' has no primary; give count"):
        validate(apply_overrides(presets.get("varela2023-reference"),
                                 {"grains.0.mass_ratio": 0.1}))
    bare = dataclasses.replace(THESIS, grains=(dataclasses.replace(THESIS.grains[0],
                                                                   count=None),))
    with pytest.raises(ConfigError, match="grains.0: give its fill as count, mass_ratio or"):
        validate(bare)
    with pytest.raises(ConfigError, match="validate the configuration first"):
        Config.n_grains.fget(apply_overrides(THESIS, {"grains.0.mass_ratio": 0.1}))


def test_the_command_line_refuses_a_fill_that_does_not_fit(capsys):
    assert cli.main(["run", "--preset", "sanchez2012-optimal", "--set",
                     "grains.0.mass_ratio=5", "--out", "never.h5"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert "grains.0.mass_ratio ≤ 0.32" in err


def test_the_cylinder_preset_states_the_thesis_mass_ratio(tmp_path, capsys):
    """``sanchez2012-cylinder``: the thesis' 250 grains from μ = 0.0958 in a cylinder of the
    box's base area; ``jaxdamp presets --show`` prints the statement, and the printed TOML is
    the preset again."""
    cfg = validate(presets.get("sanchez2012-cylinder"))
    assert cfg.grains[0].count == 250 and cfg.container.shape == "cylinder"
    assert math.pi * cfg.container.dimension("radius") ** 2 == pytest.approx(0.03675**2,
                                                                              rel=1e-5)
    assert cli.main(["presets", "--show", "sanchez2012-cylinder"]) == 0
    text = capsys.readouterr().out
    assert "mass_ratio = 0.0958" in text and "# count = (unset)" in text
    (tmp_path / "c.toml").write_text(text)
    assert validate(load_toml(str(tmp_path / "c.toml"))) == cfg
