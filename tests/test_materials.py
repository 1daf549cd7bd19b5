"""The material table (:mod:`jaxdamp.materials`): complete, sane and sourced entries; names
resolved in TOML, dicts and ``--set`` to the same configuration as the explicit table; unknown
names refused with the known ones; fills stated by mass with a named material; the mapping of
"restitution against steel" onto jaxdamp's calibration (docs/materials.md)."""

import dataclasses
import math
import tomllib

import pytest

from jaxdamp import cli, materials
from jaxdamp.cases import presets
from jaxdamp.cases.filling import resolve
from jaxdamp.config import (
    ConfigError,
    Material,
    apply_overrides,
    from_dict,
    from_json,
    load_toml,
    named_material,
)
from jaxdamp.validation import validate

THESIS = presets.get("sanchez2012-optimal")  # 250 grains of 3 mm, M = 2.37 kg, box 0.03675²


@pytest.mark.parametrize("name", materials.names())
def test_every_entry_is_complete_sane_and_sourced(name):
    entry = materials.lookup(name)
    data = entry.data()
    assert set(data) == {"density", "E", "nu", "restitution", "mu"}
    for field, datum in data.items():
        assert isinstance(datum.value, float) and math.isfinite(datum.value), field
        assert datum.status in materials.STATUSES, field
        if datum.status == materials.ESTIMATE:  # says what is missing, and why this number
            assert "no " in datum.source and "found" in datum.source, (name, field)
        else:  # quotes the number it read
            assert any(ch.isdigit() for ch in datum.source), (name, field)
    assert entry.density.value > 0 and entry.E.value > 0
    assert 0.0 <= entry.nu.value < 0.5
    assert 0.0 < entry.restitution.value <= 1.0 and entry.v_ref > 0
    assert entry.mu.value >= 0
    mat = named_material(name)
    assert mat.gamma_s > 0 and mat.gamma_n is None and mat.calibration_radius is None
    # as grains and as walls, it passes every check a run makes before compute
    cfg = apply_overrides(THESIS, {"grains.0.material": name, "box.wall": name})
    assert validate(cfg).grains[0].material == mat == cfg.box.wall


def test_the_tangential_constant_is_the_thesis_steels_carried_by_similarity():
    """The reference numbers are the thesis preset's; thesis steel gives back its γ_s; the
    rule γ_s ∝ E*^{3/5} ρ^{2/5} keeps c_s = γ_s v^{1/5}/(k^{3/5} m*^{2/5}) of a like pair at
    equal radius (computed here from k and m* directly)."""
    st = presets.SANCHEZ_STEEL
    assert (materials.THESIS_E, materials.THESIS_NU, materials.THESIS_DENSITY,
            materials.THESIS_GAMMA_S) == (st.E, st.nu, st.density, st.gamma_s)
    assert materials.tangential_damping(st.E, st.nu, st.density) == pytest.approx(st.gamma_s,
                                                                                  rel=1e-14)

    def c_s(mat, R=0.003, v=1.0):
        k = 4.0 / 3.0 * mat.E / (2 * (1 - mat.nu**2)) * math.sqrt(R / 2)
        m = mat.density * 4.0 / 3.0 * math.pi * R**3 / 2
        return mat.gamma_s * v**0.2 / (k**0.6 * m**0.4)

    for name in materials.names():
        assert c_s(named_material(name)) == pytest.approx(c_s(st), rel=1e-12)


def test_a_name_in_a_toml_file_a_dict_or_an_override_is_the_explicit_table(tmp_path):
    """``material = "glass"`` (TOML), ``{"material": "glass"}`` (dict) and
    ``--set grains.0.material=glass`` build the configuration the full table builds; so do
    walls; a table naming an entry with one key replaces that field only."""
    glass = materials.lookup("glass").fields()
    explicit = apply_overrides(THESIS, {"grains.0.material": glass, "box.wall": glass})
    by_set = apply_overrides(THESIS, ["grains.0.material=glass", "box.wall=Glass"])
    assert by_set == explicit and by_set.grains[0].material == Material(**glass)
    d = THESIS.to_dict()
    d["grains"][0]["material"], d["box"]["wall"] = "glass", " glass "
    assert from_dict(d) == explicit
    path = tmp_path / "glass.toml"
    path.write_text('[[grains]]\ncount = 250\nradius = 0.003\nmaterial = "glass"\n'
                    'name = "beads"\n'
                    '[box]\nLx = 0.03675\nLy = 0.03675\nLz = 0.1225\nwall = "glass"\n')
    assert load_toml(str(path), base=THESIS) == apply_overrides(explicit,
                                                                {"grains.0.name": "beads"})
    path.write_text('[box.wall]\nname = "glass"\nmu = 0.1\n')  # over the base's full table
    over = load_toml(str(path), base=explicit.replace(box=dataclasses.replace(
        explicit.box, wall=named_material("lead"))))
    assert over.box.wall == Material(**{**glass, "mu": 0.1})
    one = apply_overrides(THESIS, ["grains.0.material=glass", "grains.0.material.mu=0.1"])
    assert one.grains[0].material == Material(**{**glass, "mu": 0.1})


def test_a_whole_toml_file_may_name_its_materials(tmp_path):
    """Without a preset, a file naming its grains' material lacks nothing."""
    path = tmp_path / "whole.toml"
    path.write_text('system = "primary"\nfrequency = 15.0\n'
                    '[primary]\nM = 2.37\nK = 21500.0\nC = 7.6\nU = 0.0045\n'
                    '[box]\nLx = 0.04\nLy = 0.04\nLz = 0.12\nwall = "steel"\n'
                    '[[grains]]\ncount = 100\nradius = 0.003\n[grains.material]\n'
                    'name = "abs"\nrestitution = 0.7\n')
    cfg = validate(load_toml(str(path)))
    assert cfg.grains[0].material == Material(**{**materials.lookup("abs").fields(),
                                                 "restitution": 0.7})
    assert cfg.box.wall == named_material("steel")


@pytest.mark.parametrize("build, where", [
    (lambda: apply_overrides(THESIS, ["grains.0.material=unobtainium"]), "grains.0.material"),
    (lambda: apply_overrides(THESIS, {"box.wall": "brass"}), "box.wall"),
    (lambda: apply_overrides(THESIS, {"grains.0.material": {"name": "brass", "mu": 0.2}}),
     "grains.0.material.name"),
])
def test_an_unknown_name_names_the_parameter_and_lists_the_known_ones(build, where):
    with pytest.raises(ConfigError) as err:
        build()
    msg = str(err.value)
    assert msg.startswith(f"{where} = ") and "not a material of the table" in msg
    assert all(name in msg for name in materials.names())


def test_other_mistakes_are_named():
    with pytest.raises(ConfigError, match=r"grains\.0\.material: expected a material name "
                                          r"\(steel, .*\) or a table"):
        apply_overrides(THESIS, {"grains.0.material": 7850})
    with pytest.raises(ConfigError, match=r"grains\.0\.material: unknown key\(s\) \['colour'\]"):
        apply_overrides(THESIS, {"grains.0.material": {"name": "steel", "colour": "grey"}})
    with pytest.raises(ConfigError, match=r"grains\.0\.material\.nu = 0\.5"):
        validate(apply_overrides(THESIS, ["grains.0.material=lead", "grains.0.material.nu=0.5"]))


def test_the_command_line_refuses_an_unknown_name_before_compute(capsys):
    assert cli.main(["run", "--preset", "sanchez2012-optimal", "--set",
                     "grains.0.material=unobtainium", "--out", "never.h5"]) == 2
    err = capsys.readouterr().err
    assert "grains.0.material = 'unobtainium': not a material of the table" in err
    assert "known materials: steel, stainless" in err


def test_the_stored_configuration_holds_the_resolved_material():
    """An output file's JSON holds the numbers (no name), and reads back to the same run."""
    cfg = validate(apply_overrides(THESIS, ["grains.0.material=tungsten-carbide",
                                            "box.wall=steel"]))
    stored = cfg.to_json()
    assert "tungsten" not in stored
    assert '"restitution": 0.89' in stored and '"v_ref": 2.0' in stored  # the grains' numbers
    assert '"restitution": 0.9,' in stored  # the steel wall's
    assert from_json(stored) == cfg


def test_a_mass_ratio_of_named_grains_gives_the_hand_computed_count():
    """μ = 0.02 of M = 2.37 kg in 3 mm grains: glass (ρ = 2520) N = round(0.0474 / (2520 ·
    1.13097e-7)) = round(166.3) = 166; lead (ρ = 11350) round(36.93) = 37."""
    for name, count in (("glass", 166), ("lead", 37)):
        cfg = apply_overrides(THESIS, {"grains.0.material": name, "grains.0.mass_ratio": 0.02})
        assert cfg.grains[0].count is None
        assert resolve(cfg).grains[0].count == count
        assert validate(cfg).grains[0].count == count


def _restitutions(cfg, R=0.003):
    """Like-pair and grain–wall restitution at v_ref of the first species, from the contact
    tables jaxdamp builds (:func:`jaxdamp.physics.model.contact_tables`)."""
    from jaxdamp.physics import restitution as rst
    from jaxdamp.physics.contact import HERTZ
    from jaxdamp.physics.model import contact_tables

    pair, wall = contact_tables(cfg)
    mat = cfg.grains[0].material
    m = mat.density * 4.0 / 3.0 * math.pi * R**3

    def e(m_star, r_star, row):
        E = row[HERTZ.column("E_star")]
        g = row[HERTZ.column("gamma_n")] + 1.5 * row[HERTZ.column("A")] \
            * rst.hertz_stiffness(E, r_star)
        return rst.restitution(m_star, r_star, E, mat.v_ref, gamma_n=g)

    return e(m / 2, R / 2, pair[0, 0]), e(m, R, wall[0])


def test_restitution_against_steel_maps_onto_the_calibrations_as_documented():
    """Lead grains (e = 0.2 against steel at 1 m/s) in a steel box, R = 3 mm: the like pair
    has 0.2; the steel wall gives 0.345 under the default mixing, 0.9 (steel's own) with
    wall_damping = "calibrated", and exactly the table's 0.2 with "calibrated" and the wall's
    restitution removed (docs/materials.md, "Mapping")."""
    cfg = apply_overrides(THESIS, {"grains.0.material": "lead", "box.wall": "steel"})
    pair, mixed = _restitutions(cfg)
    assert pair == pytest.approx(0.2, abs=1e-6)
    assert mixed == pytest.approx(0.345, abs=1e-3)
    _, own = _restitutions(cfg.replace(wall_damping="calibrated"))
    assert own == pytest.approx(0.9, abs=1e-6)
    exact = apply_overrides(cfg, ["wall_damping=calibrated", "box.wall.restitution=none"])
    assert exact.box.wall.restitution is None
    assert _restitutions(validate(exact))[1] == pytest.approx(0.2, abs=1e-6)


def test_the_listing_shows_every_name_and_shows_the_table_a_name_stands_for(capsys):
    assert cli.main(["materials"]) == 0
    out = capsys.readouterr().out
    assert all(f"\n{name} " in out for name in materials.names())
    for name in materials.names():
        assert cli.main(["materials", "--show", name]) == 0
        text = capsys.readouterr().out
        table = tomllib.loads(text)["grains"]["material"]
        assert Material(**table) == named_material(name)
    assert cli.main(["materials", "--show", "unobtainium"]) == 2
    assert "known materials: steel" in capsys.readouterr().err
