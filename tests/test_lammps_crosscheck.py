"""The jaxdamp → LAMMPS contact mapping of ``experiments/lammps_crosscheck.py``, checked with
short LAMMPS runs (a few seconds): binary restitution, sphere–wall restitution and the static
overlap on the walls (which catches the wall-modulus bug of the Debian LAMMPS 2021 build)."""

import importlib.util
import pathlib
import shutil
import sys

import pytest

needs_lmp = pytest.mark.skipif(
    shutil.which("lmp") is None,
    reason="LAMMPS (`lmp`, GRANULAR package) is not on PATH; apt-get install lammps to run "
    "the LAMMPS cross-check tests")

EXPERIMENT = pathlib.Path(__file__).parent.parent / "experiments" / "lammps_crosscheck.py"


@pytest.fixture(scope="module")
def lc():
    spec = importlib.util.spec_from_file_location("lammps_crosscheck", EXPERIMENT)
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up
    spec.loader.exec_module(mod)
    return mod


@pytest.fixture(scope="module")
def mapping(lc):
    from jaxdamp.cases import presets

    return lc.build_mapping(presets.get(lc.PRESET))


def test_mapping_constants(lc, mapping):
    """η_n0 = γ_n/(m* sqrt(R*)) = 2 A E*/m*; the wall gets E/(1+ν) against the LAMMPS bug."""
    mp = mapping
    assert mp.eta_pp == pytest.approx(2 * mp.A * mp.E_star_pp / (mp.mass / 2), rel=1e-12)
    assert mp.eta_pw == pytest.approx(2 * mp.A * mp.E_star_pw / mp.mass, rel=1e-12)
    assert mp.E_wall_lammps == pytest.approx(mp.E / (1 + mp.nu), rel=1e-12)
    assert mp.k_wall_lammps(mp.E_wall_lammps) == pytest.approx(mp.k_pw, rel=1e-12)


@needs_lmp
def test_binary_collision_restitution(lc, mapping, tmp_path):
    """Head-on at 1 m/s in LAMMPS: ε = 0.75 within 1 % and jaxdamp's integrated law within 0.1 %."""
    from jaxdamp.physics.restitution import restitution

    r = lc.lammps_pair_collision(mapping, 1.0, str(tmp_path))
    assert r["mass"] == pytest.approx(mapping.mass, rel=1e-12)
    assert r["restitution"] == pytest.approx(0.75, rel=0.01)
    ref = restitution(mapping.mass / 2, mapping.R / 2, mapping.E_star_pp, 1.0, A=mapping.A)
    assert r["restitution"] == pytest.approx(ref, rel=1e-3)


@needs_lmp
def test_static_wall_overlap(lc, mapping, tmp_path):
    """A sphere resting on the floor and on a side wall: overlap (m g / k_n)^{2/3} within 1 %."""
    for wall in ("floor", "x1"):
        r = lc.lammps_static(mapping, wall, str(tmp_path))
        assert r["ratio"] == pytest.approx(1.0, abs=0.01), (wall, r)
        assert r["speed"] < 1e-6


@needs_lmp
def test_wall_collision_restitution(lc, mapping, tmp_path):
    """Sphere on the floor at 1 m/s: jaxdamp's grain–wall restitution within 1 %."""
    from jaxdamp.physics.restitution import restitution

    r = lc.lammps_wall_collision(mapping, 1.0, str(tmp_path))
    ref = restitution(mapping.mass, mapping.R, mapping.E_star_pw, 1.0,
                      A=0.5 * (mapping.A + mapping.A_wall))
    assert r["restitution"] == pytest.approx(ref, rel=0.01)
