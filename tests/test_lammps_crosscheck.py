"""The jaxdamp → LAMMPS contact mapping (:mod:`jaxdamp.peers.lammps`), checked with
short LAMMPS runs (a few seconds): binary restitution, sphere–wall restitution and the static
overlap on the walls (which catches the wall-modulus bug of the Debian LAMMPS 2021 build); the
cylinder's concave side (`zcylinder`) against jaxdamp's, and the cylinder study's quick mode."""

import shutil

import numpy as np
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


# -- the cylinder: LAMMPS' `fix wall/gran ... zcylinder` against jaxdamp's concave side wall


def _cylinder(preset: str, radius: float):
    """``preset``'s grains in an upright cylinder of ``radius``, Lz = 8 cm."""
    import dataclasses

    from jaxdamp.cases import presets
    from jaxdamp.config import Container

    cfg = presets.get(preset)
    wall = cfg.box.wall if cfg.box is not None else None
    return dataclasses.replace(cfg, box=None,
                               container=Container("cylinder", 0.08, (("radius", radius),),
                                                   wall=wall))


def test_cylinder_mapping_constants(mapping):
    """The side wall's constants: κ = 1/(2 R_c), R* = R/(1 − R κ) equal to LAMMPS'
    R R_w/(R + R_w) with R_w = −2 R_c (fix_wall_gran.cpp), k = (4/3) E* sqrt(R*); with the
    paper's A its LAMMPS prefactor is the planes' (damping ∝ sqrt(R*) in both codes), with the
    thesis' constant γ_n it is smaller by sqrt(R/R*); the box's sides are planes (R* = R)."""
    assert mapping.curvature == 0.0 and mapping.R_side == mapping.R
    assert mapping.eta_side == mapping.eta_pw and mapping.k_side == mapping.k_pw
    Rc = 0.045135
    mp = lammps.build_mapping(_cylinder("varela2023-reference", Rc))
    R, R_w = mp.R, -2.0 * Rc
    assert mp.curvature == pytest.approx(1.0 / (2.0 * Rc), rel=1e-14)
    assert mp.R_side == pytest.approx(R * R_w / (R + R_w), rel=1e-14)
    assert mp.k_side == pytest.approx(4 / 3 * mp.E_star_pw * mp.R_side**0.5, rel=1e-14)
    assert mp.k_wall_lammps(mp.E_wall_lammps, mp.R_side) == pytest.approx(mp.k_side, rel=1e-12)
    assert mp.eta_side == pytest.approx(mp.eta_pw, rel=1e-12)
    th = lammps.build_mapping(_cylinder("sanchez2012-optimal", 0.020734))
    assert th.gamma_side == pytest.approx(th.gamma_pw, rel=1e-14)  # γ_n does not scale
    assert th.eta_side == pytest.approx(th.eta_pw * (th.R / th.R_side) ** 0.5, rel=1e-12)
    assert th.xt_side == pytest.approx(th.xt_pw, rel=1e-12)
    assert f"zcylinder {Rc!r}" in lammps.cavity(_cylinder("sanchez2012-optimal", Rc)).walls(th)


def test_cylinder_frame_and_elastic_energy(tmp_path):
    """LAMMPS' frame of the cylinder is jaxdamp's box frame shifted by (R_c, R_c, 0) (its
    `zcylinder` axis is x = y = 0): the data file holds the shifted positions and bounds of
    ±R_c; the elastic energy of a grain pressed ξ into the side is jaxdamp's Hertz
    (2/5) k ξ^{5/2} at R*, and into the floor the plane's."""
    Rc = 0.03
    cfg = _cylinder("varela2023-reference", Rc)
    mp = lammps.build_mapping(cfg)
    cav = lammps.cavity(cfg)
    assert cav.shape == "cylinder" and list(cav.origin) == [Rc, Rc, 0.0]
    xi = 1e-6
    r = np.array([[Rc + (Rc - mp.R + xi), Rc, 0.04], [Rc, Rc, mp.R - xi]])  # box frame
    lammps.write_data(str(tmp_path / "bed.data"), r, np.zeros((2, 3)), mp, cfg)
    text = (tmp_path / "bed.data").read_text()
    assert f"{-Rc - 0.001!r} {Rc + 0.001!r} xlo xhi" in text
    atoms = np.array([[float(x) for x in line.split()[4:7]]
                      for line in text.split("Atoms # sphere")[1].split("Velocities")[0]
                      .strip().splitlines()])
    assert np.allclose(atoms, r - [Rc, Rc, 0.0], rtol=0, atol=1e-15)
    snap = np.column_stack([np.arange(1, 3), atoms, np.zeros((2, 3))])
    e = lammps.mechanical_energy(snap, mp, cav, 0.0)
    assert e["elastic"] == pytest.approx(0.4 * (mp.k_side + mp.k_pw) * xi**2.5, rel=1e-6)
    deck = lammps.box_deck(mp, cfg, 0.03, "bed.data")
    assert f"zcylinder {Rc!r}" in deck and "zplane 0.0 0.08" in deck and "xplane" not in deck


@needs_lmp
def test_curved_wall_static_and_collision(tmp_path):
    """LAMMPS' `zcylinder` wall is jaxdamp's concave wall (R* = R/(1 − R/(2 R_c))): in a narrow
    cylinder (R_c = 5 R, where R* is 11 % above a plane's) a grain pressed on the side by a
    lateral body force rests at jaxdamp's Hertz overlap at R* within 1e-4 (3.5 % below a
    plane's), and a radial hit at 1 m/s has jaxdamp's restitution at R* within 0.05 % (0.5 %
    below the plane's)."""
    from jaxdamp.physics.restitution import collision

    mp0 = lammps.build_mapping(_cylinder("varela2023-reference", 0.045))
    Rc = 5 * mp0.R
    mp = lammps.build_mapping(_cylinder("varela2023-reference", Rc))
    st = lammps.static(mp, "side", str(tmp_path), Rc=Rc)
    assert st["ratio"] == pytest.approx(1.0, abs=1e-4), st
    assert st["ratio_plane"] < 0.97 and st["speed"] < 1e-6
    hit = lammps.wall_collision(mp, 1.0, str(tmp_path), Rc=Rc)
    A = 0.5 * (mp.A + mp.A_wall)
    ref = collision(mp.mass, mp.R_side, mp.E_star_pw, 1.0, A=A)
    plane = collision(mp.mass, mp.R, mp.E_star_pw, 1.0, A=A)
    assert hit["restitution"] == pytest.approx(ref.restitution, rel=5e-4)
    assert hit["restitution"] < plane.restitution * (1 - 3e-3)
    assert abs(hit["duration"] - ref.duration) <= 2 * mp.dt


@needs_lmp
@pytest.mark.examples
def test_lammps_cylinder_quick(tmp_path):
    """The cylinder cross-check at test size (3 cm, 2 + 3 periods, 2 beds, ~35 s): the curved
    wall's checks pass, two beds (own seeds) are run by both codes from one settled state, the
    paired difference has a finite interval and the codes agree within 5 % over 3 periods; the
    undamped bed's energy closes; data and figure are written and the summary is rewritten byte
    for byte from data.h5."""
    import h5py
    from helpers import load_experiment

    study = load_experiment("lammps_cylinder")
    res = study.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    side = [r for r in res["checks"]["static"] if r["wall"] == "side"]
    assert len(side) == 1 and side[0]["ratio"] == pytest.approx(1.0, abs=1e-4)
    assert all(abs(r["restitution"] / r["ref_restitution"] - 1) < 1e-3
               for r in res["checks"]["side"] + res["checks"]["wall"] + res["checks"]["pair"])
    beds = res["cases"][0.03]["beds"]
    assert [b["seed"] for b in beds] == [0, 1]
    assert not np.array_equal(beds[0]["jd"]["bed_r"], beds[1]["jd"]["bed_r"])
    assert beds[0]["jd"]["config"].container.shape == "cylinder"
    r = res["table"][0.03]
    assert r["R"] == 2 and r["n"] == 2 and np.isfinite(r["hw"]) and r["hw"] > 0
    assert abs(r["rel"]) < 0.05
    assert res["closure"]["relative"] < 5e-3
    with h5py.File(tmp_path / "data.h5") as h:
        assert h["A_3cm/difference_per_bed"].shape == (2,)
        assert h["A_3cm/bed_1/lammps/dissipation_per_period"].shape == (5,)
    first = (tmp_path / "summary.md").read_text()
    assert "zcylinder" in first and "R = 2 independently poured beds" in first
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    study.main(["--from-data", "--out", str(tmp_path)])
    assert (tmp_path / "summary.md").read_text() == first


# -- the tangential spring with history: LAMMPS' `tangential mindlin_rescale/force`


@needs_lmp
@pytest.mark.parametrize("psi", [0.5, 3.0, 10.0])
def test_mindlin_pair_impact_matches_lammps(psi, tmp_path):
    """Two like elastic spheres (thesis steel, μ = 0.3) collide obliquely, Ψ = v_t/(μ v_n):
    jaxdamp's JAX engine with ``tangential_law = "mindlin"`` and LAMMPS' ``pair granular
    hertz/material ... tangential mindlin_rescale/force NULL 0 μ`` (its stiffness ``8 G* a``
    from E and ν, the force as history, rescaled with the contact radius on unloading), from
    the same start: the grains' velocities and spins after the contact agree to 1e-3 of
    ``v_t`` (spins 2.5e-3). jaxdamp runs 200 steps per contact, LAMMPS 2 000: LAMMPS takes the
    step's stiffness at its end, jaxdamp at the step's mean overlap, and at 200 steps LAMMPS
    is off its own converged result by 2.3e-3 of ``v_t`` at Ψ = 0.5 (relative ``v_t`` 0.065104
    against 0.064934 m/s at 20 000 steps). Measured, relative ``v_t`` after the contact,
    jaxdamp / LAMMPS: 0.064921 / 0.064926 (Ψ = 0.5), 0.281087 / 0.280743 (3),
    1.204690 / 1.204690 m/s (10)."""
    import math
    import sys

    sys.path.insert(0, str(__import__("pathlib").Path(__file__).parent))
    import test_mindlin_engine as tm

    R, vn = tm.R, 0.5
    vt = psi * tm.STEEL.mu * vn
    m = tm.STEEL.density * 4.0 / 3.0 * math.pi * R**3
    t_c = tm._contact_time(0.5 * m, 0.5 * R, vn)
    dt = t_c / 200
    gap = 0.2 * vn * dt
    steps = int(2 * t_c / dt)
    fine = 10  # LAMMPS' steps per jaxdamp step
    mat = tm.STEEL
    z0, z1 = 0.02, 0.02 + 2 * R + gap
    script = lammps.HEADER + f"""
region sim block 0.0 0.05 0.0 0.05 0.0 0.05 units box
create_box 1 sim
create_atoms 1 single 0.025 0.025 {z0!r} units box
create_atoms 1 single 0.025 0.025 {z1!r} units box
set type 1 diameter {2 * R!r} density {mat.density!r}
velocity all set 0.0 0.0 0.0 units box
set atom 1 vx {0.5 * vt!r} vz {0.5 * vn!r}
set atom 2 vx {-0.5 * vt!r} vz {-0.5 * vn!r}
pair_style granular
pair_coeff * * hertz/material {mat.E!r} 0.0 {mat.nu!r} tangential mindlin_rescale/force NULL 0.0 {mat.mu!r} damping viscoelastic
neighbor {0.3 * R!r} bin
neigh_modify delay 0 every 1 check yes
fix integ all nve/sphere
timestep {dt / fine!r}
compute om all property/atom omegay
variable vx1 equal vx[1]
variable vx2 equal vx[2]
variable vz1 equal vz[1]
variable w1 equal c_om[1]
variable w2 equal c_om[2]
thermo_style custom step v_vx1 v_vx2 v_vz1 v_w1 v_w2
thermo_modify format float %.17g
thermo {steps * fine}
run {steps * fine}
"""  # noqa: E501
    log, _ = lammps.run(script, f"mindlin_pair_{psi:g}", str(tmp_path))
    vx1, vx2, vz1, w1, w2 = lammps.thermo_table(log)[-1, 1:]
    cfg = tm._mindlin(tm.config(n=2, radius=R, material=mat), dt=dt)
    model, pb, st, nbrs = tm.start(cfg, [[0.025, 0.025, z0], [0.025, 0.025, z1]],
                                   [[0.5 * vt, 0.0, 0.5 * vn], [-0.5 * vt, 0.0, -0.5 * vn]])
    st, _, _ = tm.run_steps(model, pb, st, nbrs, 1, steps)
    v, w = np.asarray(st.v[0]), np.asarray(st.w[0])
    print(f"Ψ = {psi}: relative v_t jaxdamp {v[0, 0] - v[1, 0]:.6f}, LAMMPS {vx1 - vx2:.6f}; "
          f"R ω {R * w[0, 1]:.6f}, {R * w1:.6f} m/s")
    assert abs(v[0, 0] - vx1) < 1e-3 * vt and abs(v[1, 0] - vx2) < 1e-3 * vt
    assert v[0, 2] == pytest.approx(vz1, abs=1e-4 * vn)
    assert abs(R * w[0, 1] - R * w1) < 2.5e-3 * vt and abs(R * w[1, 1] - R * w2) < 2.5e-3 * vt


def _friction_config(law: str):
    from helpers import load_experiment

    return load_experiment("lammps_friction").base_config(law)


def test_spring_mapping_constants():
    """``tangential_law = "mindlin"`` maps to ``tangential mindlin_rescale/force k_t x μ``:
    ``k_t = 8 G*`` (LAMMPS multiplies by the contact radius a = sqrt(R* ξ)) and ``x = 4 G*/E*``
    — for like materials ``2(1 − ν)/(2 − ν)`` — pairs, planes and the side alike; the viscous
    law keeps ``linear_nohistory``."""
    mp = lammps.build_mapping(_friction_config("mindlin"))
    nu = mp.nu
    G = mp.E / (2 * (1 + nu)) / (2 * (2 - nu))  # like materials: 1/G* = 2 (2 − ν)/G
    assert mp.kt_pp == pytest.approx(8 * G, rel=1e-12)
    assert mp.kt_pw == pytest.approx(8 * G, rel=1e-12)
    for x in (mp.xs_pp, mp.xs_pw, mp.xs_side):
        assert x == pytest.approx(2 * (1 - nu) / (2 - nu), rel=1e-12)
    assert (f"tangential mindlin_rescale/force {mp.kt_pp!r} {mp.xs_pp!r} {mp.mu!r}"
            in lammps.pair_coeff(mp))
    assert f"mindlin_rescale/force {mp.kt_pw!r} {mp.xs_pw!r} 0.23" in lammps.wall_args(mp)
    assert f"mindlin_rescale/force {mp.kt_pw!r} {mp.xs_side!r}" in lammps.side_args(mp)
    mv = lammps.build_mapping(_friction_config("viscous"))
    assert f"linear_nohistory {mv.xt_pp!r} 0.23" in lammps.pair_coeff(mv)


def test_horizontal_drive_deck_and_rotational_energy():
    """A drive along x becomes a second body force ``A ω² cos ωt`` along x beside gravity,
    and the input power follows the centre of mass along x (the vertical deck keeps its one
    effective gravity); a snapshot with spins counts their energy ``(1/5) m R² ω²``."""
    from jaxdamp.config import apply_overrides

    cfg = _friction_config("viscous")
    mp = lammps.build_mapping(cfg)
    vertical = lammps.bed_script(mp, cfg, 0.03, [0, 10], "bed.data", "snaps")
    assert "fix grav all gravity v_geff vector 0 0 -1" in vertical
    assert "*(vcm(all,z))" in vertical and "fix drive" not in vertical
    side = apply_overrides(cfg, {"direction": [1.0, 0.0, 0.0]})
    deck = lammps.bed_script(mp, side, 2e-5, [0, 10], "bed.data", "snaps")
    assert f"fix grav all gravity {cfg.gravity!r} vector 0 0 -1" in deck
    assert "fix drive all gravity v_ain vector 1.0 0.0 0.0" in deck
    assert "*(1.0*vcm(all,x))" in deck
    assert "omegax omegay omegaz" in deck
    snap = np.zeros((1, 10))
    snap[0, 1:4] = (0.04, 0.04, 0.04)
    snap[0, 8] = 100.0  # ω_y [rad/s]
    e = lammps.mechanical_energy(snap, mp, cfg, 0.0)
    assert e["kinetic"] == pytest.approx(0.2 * mp.mass * mp.R**2 * 100.0**2, rel=1e-12)


@needs_lmp
@pytest.mark.long
@pytest.mark.parametrize("law", ["viscous", "mindlin"])
def test_oblique_impacts_match_jaxdamp(law, tmp_path):
    """The friction mapping of each tangential law, damped as in the study, against jaxdamp's
    engine at the same time step: a grain on the floor and two grains, sticking (v_t/v_n =
    0.1) and sliding throughout (2). Every velocity component and ωR after the impact agree to
    1e-3 of v_n on the floor and 3e-3 between grains: LAMMPS' pair torque has the lever arm
    R − ξ/2, jaxdamp's R, which alone moves the sliding pair's spin by ~0.5 % (measured:
    largest differences 1.8e-4 / 4.8e-5 (viscous floor), 6.3e-5 / 2.3e-3 (viscous pair),
    6.9e-4 / 4.8e-5 (Mindlin floor), 3.4e-4 / 2.3e-3 (Mindlin pair)); the sliding impacts'
    tangential rebound agrees to 1e-4."""
    cfg = _friction_config(law)
    rows = lammps.oblique_checks(cfg, lammps.build_mapping(cfg), str(tmp_path),
                                 ratios=(0.1, 2.0))
    for r in rows:
        assert r["difference"] < (1e-3 if r["kind"] == "wall" else 3e-3), r
        assert r["lammps"]["restitution"] == pytest.approx(r["jaxdamp"]["restitution"],
                                                           abs=2e-4)
        if r["vt"] > r["vn"]:
            assert r["lammps"]["tangential"] == pytest.approx(r["jaxdamp"]["tangential"],
                                                              abs=1e-4)


@pytest.mark.slow  # not in CI (its time budget): pytest -m slow
@needs_lmp
@pytest.mark.examples
def test_lammps_friction_quick(tmp_path):
    """The friction study at test size (both regimes, both laws, 2 beds, 2 + 3 periods, ~5
    min): each law's codes agree within 3 % over 3 periods, the codes agree on the laws'
    difference (its interval holds 0), the beds carry their spins into LAMMPS, and the
    summary is rewritten byte for byte from data.h5."""
    from helpers import load_experiment

    study = load_experiment("lammps_friction")
    res = study.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    for (case, law), c in res["runs"].items():
        r = c["table"]
        assert r["R"] == 2 and np.isfinite(r["hw"]) and abs(r["rel"]) < 0.03, (case, law)
        assert np.abs(c["beds"][0]["jd"]["bed_w"]).max() > 0
    first = (tmp_path / "summary.md").read_text()
    assert "mindlin_rescale/force" in first and "codes agree" in first
    assert (tmp_path / "figure.png").stat().st_size > 10_000
    study.main(["--from-data", "--out", str(tmp_path)])
    assert (tmp_path / "summary.md").read_text() == first


@needs_lmp
def test_lammps_runs_in_a_relative_folder(tmp_path, monkeypatch):
    """A study's ``--out`` may be relative: ``lmp`` runs in its folder, so the input and log
    paths must not be relative to the caller's (a relative ``--out`` failed with MPI_ABORT and
    no log before)."""
    monkeypatch.chdir(tmp_path)
    log, _ = lammps.run('print "RESULT 1.5"\n', "relative", "some/where")
    assert lammps.printed(log, "RESULT")[-1] == [1.5]
    assert (tmp_path / "some" / "where" / "log.relative").exists()


@needs_lmp
@pytest.mark.examples
def test_oblique_time_step_quick(tmp_path):
    """The oblique-impact time-step study at test size (the sticking impacts at dt and dt/2,
    both laws, ~1 min): with the spring, LAMMPS' rebound spin on the wall moves at least five
    times more than jaxdamp's when dt halves (its time-step error; measured 3.7e-3 against
    3.5e-4), the codes' difference shrinks, and the summary is rewritten byte for byte from
    data.h5."""
    from helpers import load_experiment

    from jaxdamp.io.study import load

    study = load_experiment("lammps_oblique_dt")
    study.main(["--quick", "--out", str(tmp_path), "--no-progress"])
    series = study._series(load(str(tmp_path / "data.h5")))
    s = series[("mindlin", "wall", 0.1)]
    moved = {c: abs(s[c]["spin"][1] - s[c]["spin"][0]) for c in ("lammps", "jaxdamp")}
    assert moved["lammps"] > 5 * moved["jaxdamp"] > 0
    gap = [abs(s["lammps"]["spin"][k] - s["jaxdamp"]["spin"][k]) for k in (0, 1)]
    assert gap[1] < 0.7 * gap[0]
    first = (tmp_path / "summary.md").read_text()
    study.main(["--from-data", "--out", str(tmp_path)])
    assert (tmp_path / "summary.md").read_text() == first
