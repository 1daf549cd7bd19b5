"""The jaxdamp → LAMMPS contact mapping (:mod:`jaxdamp.peers.lammps`), checked with
short LAMMPS runs (a few seconds): binary restitution, sphere–wall restitution and the static
overlap on the walls (which catches the wall-modulus bug of the Debian LAMMPS 2021 build)."""

import shutil

import pytest

from jaxdamp.peers import lammps

needs_lmp = pytest.mark.skipif(
    shutil.which("lmp") is None,
    reason="LAMMPS (`lmp`, GRANULAR package) is not on PATH; apt-get install lammps to run "
    "the LAMMPS cross-check tests")


@pytest.fixture(scope="module")
def mapping():
    from jaxdamp.cases import presets

    return lammps.build_mapping(presets.get("varela2023-reference"))


def test_mapping_constants(mapping):
    """η_n0 = γ_n/(m* sqrt(R*)) = 2 A E*/m*; the wall gets E/(1+ν) against the LAMMPS bug."""
    mp = mapping
    assert mp.eta_pp == pytest.approx(2 * mp.A * mp.E_star_pp / (mp.mass / 2), rel=1e-12)
    assert mp.eta_pw == pytest.approx(2 * mp.A * mp.E_star_pw / mp.mass, rel=1e-12)
    assert mp.E_wall_lammps == pytest.approx(mp.E / (1 + mp.nu), rel=1e-12)
    assert mp.k_wall_lammps(mp.E_wall_lammps) == pytest.approx(mp.k_pw, rel=1e-12)


@needs_lmp
def test_binary_collision_restitution(mapping, tmp_path):
    """Head-on at 1 m/s in LAMMPS: ε = 0.75 within 1 % and jaxdamp's integrated law within 0.1 %."""
    from jaxdamp.physics.restitution import restitution

    r = lammps.pair_collision(mapping, 1.0, str(tmp_path))
    assert r["mass"] == pytest.approx(mapping.mass, rel=1e-12)
    assert r["restitution"] == pytest.approx(0.75, rel=0.01)
    ref = restitution(mapping.mass / 2, mapping.R / 2, mapping.E_star_pp, 1.0, A=mapping.A)
    assert r["restitution"] == pytest.approx(ref, rel=1e-3)


@needs_lmp
def test_static_wall_overlap(mapping, tmp_path):
    """A sphere resting on the floor and on a side wall: overlap (m g / k_n)^{2/3} within 1 %."""
    for wall in ("floor", "x1"):
        r = lammps.static(mapping, wall, str(tmp_path))
        assert r["ratio"] == pytest.approx(1.0, abs=0.01), (wall, r)
        assert r["speed"] < 1e-6


@needs_lmp
def test_wall_collision_restitution(mapping, tmp_path):
    """Sphere on the floor at 1 m/s: jaxdamp's grain–wall restitution within 1 %."""
    from jaxdamp.physics.restitution import restitution

    r = lammps.wall_collision(mapping, 1.0, str(tmp_path))
    ref = restitution(mapping.mass, mapping.R, mapping.E_star_pw, 1.0,
                      A=0.5 * (mapping.A + mapping.A_wall))
    assert r["restitution"] == pytest.approx(ref, rel=0.01)


def test_friction_mapping_constants():
    """The thesis bed (γ_n, γ_s, μ): LAMMPS' viscoelastic prefactor is γ_n/(m* sqrt(R*)) and its
    tangential damping multiplier γ_s/γ_n, the Coulomb coefficient μ, pairs and walls."""
    from jaxdamp.cases import presets

    cfg = presets.get("sanchez2012-optimal")
    mp = lammps.build_mapping(cfg)
    mat = cfg.grains[0].material
    lam = cfg.numerics.stiffness_scale ** 0.6  # the reduced modulus scales γ_n, γ_s alike
    assert mp.mu == mat.mu
    assert mp.xt_pp == pytest.approx(mat.gamma_s / mat.gamma_n, rel=1e-12)
    assert mp.xt_pw == pytest.approx(mat.gamma_s / mat.gamma_n, rel=1e-12)
    assert mp.eta_pp == pytest.approx(lam * mat.gamma_n / (mp.mass / 2 * (mp.R / 2) ** 0.5),
                                      rel=1e-12)
    assert f"linear_nohistory {mp.xt_pp!r} {mp.mu!r}" in lammps.pair_coeff(mp)


@needs_lmp
def test_sliding_sphere_rolls_at_five_sevenths_in_lammps(tmp_path):
    """The friction mapping in LAMMPS: a thesis-steel sphere launched sliding on the floor ends
    rolling at 5/7 of its speed (as in jaxdamp, experiments/contact_checks.py), within 1 %."""
    from jaxdamp.cases import presets

    mp = lammps.build_mapping(presets.get("sanchez2012-optimal"))
    R, dt, L, v0 = mp.R, mp.dt, 0.05, 0.1
    xi0 = (mp.mass * 9.8 / mp.k_pw) ** (2 / 3)
    steps = int(0.03 / dt)
    script = lammps.HEADER + f"""
region sim block -0.001 {L!r} -0.001 {L!r} -0.001 {L!r} units box
create_box 1 sim
create_atoms 1 single 0.01 0.025 {R - xi0!r} units box
set type 1 diameter {2 * R!r} density {mp.density!r}
velocity all set {v0!r} 0.0 0.0 units box
pair_style granular
{lammps.pair_coeff(mp)}
fix wall all wall/gran {lammps.wall_args(mp)} zplane 0.0 NULL
fix grav all gravity 9.8 vector 0 0 -1
fix integ all nve/sphere
timestep {dt!r}
compute om all property/atom omegay
variable vx equal vx[1]
variable wy equal c_om[1]
thermo_style custom step v_vx v_wy
thermo {steps}
run {steps}
print "RESULT $(v_vx:%.17g) $(v_wy:%.17g)"
"""
    log, _ = lammps.run(script, "sliding", str(tmp_path))
    vx, wy = lammps.printed(log, "RESULT")[-1]
    assert vx == pytest.approx(5 / 7 * v0, rel=0.01)
    assert R * wy == pytest.approx(vx, rel=0.01)
