"""The container registry (jaxdamp.physics.containers): each container's JAX, scalar and
host-side forms agree with one another, and the settled-bed cache is keyed by exclusion."""

import dataclasses
import json

import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.config import Container, apply_overrides
from jaxdamp.physics import containers
from jaxdamp.physics.containers import CONTAINERS, container
from jaxdamp.studies.grid import BED_FREE, geometry_key


@pytest.mark.parametrize("name", sorted(CONTAINERS))
def test_the_scalar_and_jax_forms_of_every_container_agree(name):
    """Grains at 120 random places near the side walls (mid-height: no floor or lid), moving
    and spinning: the wall forces, torques, energies and losses of the JAX form
    (``walls.wall_forces``) equal the container's scalar form, which the compiled kernel
    inlines, grain by grain; the JAX form's distances and normals are consistent (the normal
    points into the cavity and the distance grows by a step along it)."""
    import jax.numpy as jnp

    from jaxdamp.physics.contact import LAWS
    from jaxdamp.physics.model import build
    from jaxdamp.physics.walls import wall_forces

    cfg = _example(name)
    vessel = CONTAINERS[name]
    assert container(cfg) is vessel
    model, p = build(cfg)
    section = np.asarray(vessel.section(cfg))
    np.testing.assert_array_equal(np.asarray(p.section), section)
    # the kernel holds the section numbers in registers (section_scalar): all of them fit
    assert 1 <= len(section) <= containers.MAX_SECTION
    sec = containers.section_scalar(section)
    assert len(sec) == containers.MAX_SECTION and list(sec[:len(section)]) == list(section)
    x0, x1, y0, y1 = vessel.extent(cfg)
    R = float(p.radius[0])
    rng = np.random.default_rng(0)
    x = rng.uniform(x0, x1, 20000)
    y = rng.uniform(y0, y1, 20000)
    keep = vessel.inside(x, y, 0.3 * R, cfg) & ~vessel.inside(x, y, 1.5 * R, cfg)
    assert vessel.inside(x, y, 0.0, cfg).mean() > 0.5  # the extent bounds the section tightly
    x, y = x[keep][:120], y[keep][:120]
    n = len(x)
    r = np.column_stack([x, y, np.full(n, 0.5 * vessel.height(cfg))])
    v = rng.normal(0, 0.3, (n, 3))
    w = rng.normal(0, 50.0, (n, 3))
    law = LAWS[model.law]
    row = np.asarray(p.wall_table)[0]
    kappa = containers.side_curvature_scalar(vessel.id, section)
    assert kappa == vessel.curvature(cfg)
    k, g = law.pair_scalar(row, containers.effective_radius(R, kappa), float(p.mass[0]))
    wk = np.array([[k, g, row[0], row[1]]])
    touching = 0
    for i in range(n):
        one = dataclasses.replace(model, n=1, species=())
        pi = dataclasses.replace(p, radius=p.radius[:1], mass=p.mass[:1], origin=p.origin[:1])
        f = wall_forces(jnp.asarray(r[i:i + 1]), jnp.asarray(v[i:i + 1]), jnp.asarray(w[i:i + 1]),
                        0.0, 0.0, pi, one)
        acc = containers.side_contacts_scalar(
            vessel.id, law.id, x[i], y[i], sec, R, wk, 0, v[i, 0],
            v[i, 1], v[i, 2], R * w[i, 0], R * w[i, 1], R * w[i, 2], 0.0, 0.0, 1.0,
            (0.0,) * 11, None, None)
        jax_side = np.concatenate([np.asarray(f.force)[0], np.asarray(f.torque)[0],
                                   [float(f.elastic_energy), float(f.normal_loss),
                                    float(f.friction_loss), float(f.box_z)]])
        np.testing.assert_allclose(acc[:10], jax_side, rtol=1e-9,
                                   atol=1e-12 * (1 + abs(jax_side).max()))
        # the side walls' own count and loss (the grain is far from floor and lid)
        assert acc[10] == int(f.n_side) and int(f.n_floor) == int(f.n_lid) == 0
        np.testing.assert_allclose(np.asarray(f.group_loss), [0.0, 0.0, acc[7] + acc[8]],
                                   rtol=1e-9, atol=1e-300)
        touching += acc[6] > 0
    assert touching > n // 3  # the comparison saw contacts, not only zeros
    gaps, (nx, ny), kappa = vessel.sides_jax(x, y, section)
    nx = np.broadcast_to(np.asarray(nx, float), (n, len(gaps)))
    ny = np.broadcast_to(np.asarray(ny, float), (n, len(gaps)))
    h = 1e-7
    for j, gap in enumerate(gaps):
        np.testing.assert_allclose(np.hypot(nx[:, j], ny[:, j]), 1.0, rtol=1e-12)
        moved = vessel.sides_jax(x + h * nx[:, j], y + h * ny[:, j], section)[0][j]
        np.testing.assert_allclose(np.asarray(moved) - np.asarray(gap), h, rtol=1e-5)
    assert vessel.curvature(cfg) == pytest.approx(max(float(c) for c in kappa), abs=0)


def _example(name):
    """A configuration of each container: the thesis damper in it."""
    base = presets.get("sanchez2012-optimal")
    if name == "box":
        return base
    return dataclasses.replace(base, box=None, container=Container(name, 0.12, (("radius", 0.02),)))


def test_the_box_outline_extent_area_and_fit():
    cfg = presets.get("sanchez2012-optimal")
    box = container(cfg)
    L = cfg.box.Lx
    assert box.extent(cfg) == (0.0, L, 0.0, cfg.box.Ly)
    assert box.base_area(cfg) == pytest.approx(L * cfg.box.Ly, rel=1e-15)
    assert box.height(cfg) == cfg.box.Lz
    lines = box.outline(cfg, 0.5)
    pts = np.concatenate(lines)
    assert len(lines) == 12
    np.testing.assert_allclose(pts.min(axis=0), [0, 0, 0.5])
    np.testing.assert_allclose(pts.max(axis=0), [L, cfg.box.Ly, 0.5 + cfg.box.Lz])
    assert box.fit_error(cfg, 0.9 * L, "a grain") is None
    assert "does not fit box.Lx" in box.fit_error(cfg, 1.01 * L, "a grain")


def _leaves(d, path=""):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from _leaves(v, f"{path}.{k}" if path else k)
    elif isinstance(d, list) and d and isinstance(d[0], dict):
        for i, v in enumerate(d):
            yield from _leaves(v, f"{path}.{i}")
    else:
        yield path, d


def test_the_bed_cache_key_is_everything_but_the_lid_excitation_and_run_length():
    """The live bug of issue 34: a bed settled under another contact law or wall damping was
    reused. Now the key is the whole configuration except what may vary on a settled bed, so
    changing any other field — checked leaf by leaf — changes the key."""
    cfg = presets.get("sanchez2012-optimal")
    key = geometry_key(cfg)
    assert geometry_key(apply_overrides(cfg, {"contact_law": "linear",
                                              "grains.0.material.linear_stiffness": 1e5,
                                              "grains.0.material.restitution": 0.5})) != key
    assert geometry_key(apply_overrides(cfg, {"wall_damping": "calibrated"})) != key
    same = {"box.Lz": 0.2, "frequency": 20.0, "primary.U": 1e-3, "numerics.duration": 9.0,
            "numerics.record_dt": 1e-3, "direction": [0.0, 0.3, 1.0], "name": "other"}
    assert geometry_key(apply_overrides(cfg, same)) == key
    free = set(BED_FREE) | {container(cfg).lid_key}
    d = cfg.to_dict()
    checked = 0
    for path, value in _leaves(d):
        if any(path == f or path.startswith(f + ".") for f in free):
            continue
        if isinstance(value, str) or value is None or isinstance(value, list):
            continue  # texts and tables: the numbers below cover the mechanism
        changed = json.loads(json.dumps(d))
        node = changed
        *head, last = path.split(".")
        for part in head:
            node = node[int(part)] if isinstance(node, list) else node[part]
        node[last] = value * 1.01 + 1 if not isinstance(value, bool) else not value
        from jaxdamp.config import from_dict

        assert geometry_key(from_dict(changed)) != key, path
        checked += 1
    assert checked >= 20


@pytest.mark.long
def test_a_sweep_settles_anew_for_another_wall_damping():
    """End to end through the sweep's bed cache: the same damper with its walls' damping
    calibrated gets a bed of its own (before the fix it reused the other bed)."""
    from jaxdamp.studies.sweep import sweep

    cfg = apply_overrides(presets.get("varela2023-reference"),
                          {"grains.0.count": 20, "numerics.duration": 0.005,
                           "numerics.settle_time": 0.02, "numerics.engine": "native"})
    beds: dict = {}
    sweep(cfg, {"frequency": [15.0]}, progress=False, echo=None, beds=beds)
    assert len(beds) == 1
    lin = apply_overrides(cfg, {"wall_damping": "calibrated"})
    sweep(lin, {"frequency": [15.0]}, progress=False, echo=None, beds=beds)
    assert len(beds) == 2
    sweep(dataclasses.replace(cfg, frequency=60.0), {"box.Lz": [0.07, 0.09]}, progress=False,
          echo=None, beds=beds)
    assert len(beds) == 2  # another lid and frequency: the same bed


# -- the cylinder: a concave wall in both engines ----------------------------------------------

from helpers import ENGINES, config, run_steps, start  # noqa: E402

from jaxdamp.config import Material, from_dict  # noqa: E402
from jaxdamp.physics import restitution as rst  # noqa: E402
from jaxdamp.physics.model import CH, build  # noqa: E402

R = 2.5e-3
RC = 4e-3  # R* = 2 R RC / (2 RC - R) = 1.45 R: the contact is ~7 % shorter than on a plane
PAPER = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, restitution=0.75, v_ref=1.0)
ELASTIC = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, gamma_n=0.0)


def _cylinder(cfg, radius=RC, Lz=0.05):
    return dataclasses.replace(cfg, box=None,
                               container=Container("cylinder", Lz, (("radius", radius),)))


def _radial_hit(mat, v, dt_fraction, engine, theta=0.7):
    """One grain (no gravity) thrown radially at the cylinder's wall at speed v: (ε, contact
    time, the wall's A)."""
    cfg = _cylinder(config(n=1, radius=R, material=mat, v_impact=v,
                           dt_per_collision=dt_fraction))
    model, params = build(cfg)
    dt = float(params.dt)
    e = np.array([np.cos(theta), np.sin(theta), 0.0])
    gap = 0.1 * R
    r0 = np.array([RC, RC, 0.025]) + (RC - R - gap) * e
    model, pb, st, nbrs = start(cfg, [r0], [v * e])
    n_steps = int((gap / v) / dt) + int(3 * dt_fraction)
    st, nbrs, rec = run_steps(model, pb, st, nbrs, n_steps, 1, engine=engine)
    v_out = np.asarray(st.v[0])[0]
    from jaxdamp.physics.model import contact_law

    A = float(params.wall_table[0, contact_law(cfg).column("A")])
    return -float(v_out @ e) / v, (rec["e_elastic"] > 0).sum() * dt, A, v_out


@pytest.mark.long
@pytest.mark.parametrize("engine", ENGINES)
def test_a_grain_bounces_off_the_cylinder_wall_as_hertz_with_the_concave_radius(engine):
    """Against the independent integration of one collision (scipy, restitution.py) with the
    concave wall's effective radius 1/R* = 1/R − 1/(2 R_c) (LAMMPS' wall radius −2 R_c):
    undamped, the contact lasts the Hertz time of R* within 2 % (a plane's is 7.8 % longer,
    a spherical cavity's R R_c/(R_c − R) 11 % shorter: the test tells them apart) and the grain
    leaves radially at its speed; damped (the paper's steel), ε within 0.5 %."""
    m = PAPER.density * 4 / 3 * np.pi * R**3
    E_wall = 1.0 / (2 * (1 - ELASTIC.nu**2) / ELASTIC.E)
    R_star = 2 * R * RC / (2 * RC - R)
    v = 1.0
    eps, t, _, v_out = _radial_hit(ELASTIC, v, 500, engine)
    assert t == pytest.approx(rst.collision_time(m, R_star, E_wall, v), rel=0.02)
    assert abs(t / rst.collision_time(m, R, E_wall, v) - 1) > 0.06
    assert abs(t / rst.collision_time(m, R * RC / (RC - R), E_wall, v) - 1) > 0.08
    assert eps == pytest.approx(1.0, abs=1e-3)
    assert abs(v_out[2]) < 1e-12
    eps, _, A, _ = _radial_hit(PAPER, v, 50, engine)
    expected = rst.collision(A=A, m_star=m, R_star=R_star, E_star=E_wall, v=v).restitution
    assert eps == pytest.approx(expected, rel=5e-3)


def test_the_cylinder_wall_contact_radius_is_the_mean_curvature_convention():
    """The side wall enters the contact with half its curvature, 1/(2 R_c) (both engines take it
    from the container module; the time step too): R* = 2 R R_c/(2 R_c − R), LAMMPS'
    convention. Against the equivalent radius √(R′R″) of the elliptical Hertz contact
    (principal relative radii R′ = 1/(1/R − 1/R_c), R″ = R; Johnson 1985 §4.2) it is within 1 %
    for R_c ≥ 5 R, and it approaches it as the wall flattens."""
    from jaxdamp.physics.containers import cylinder, effective_radius

    cfg = _cylinder(config(n=1, radius=R), radius=0.02)
    kappa = container(cfg).curvature(cfg)
    assert kappa == pytest.approx(1 / (2 * 0.02), rel=1e-15)
    assert float(cylinder.sides_jax(np.array([0.02]), np.array([0.01]),
                                    cylinder.section(cfg))[2][0]) == kappa
    errors = []
    for ratio in (5.0, 10.0, 20.0, 100.0):
        exact = np.sqrt(R / (1 / R - 1 / (ratio * R)))
        errors.append(abs(effective_radius(R, 1 / (2 * ratio * R)) / exact - 1))
    assert errors[0] < 0.01 and errors[1] < 0.003 and np.all(np.diff(errors) < 0)


def test_a_cylinder_is_a_container_table():
    """``[container]`` with ``shape = "cylinder"``: TOML-like dicts round-trip through the
    stored form, overrides reach its dimensions, and bad tables are refused by name."""
    from jaxdamp.validation import validate

    base = presets.get("sanchez2012-optimal")
    d = base.to_dict()
    d["box"] = None
    d["container"] = {"shape": "cylinder", "radius": 0.021, "Lz": 0.1225}
    cfg = validate(from_dict(d))
    assert container(cfg).name == "cylinder"
    assert cfg.to_dict()["container"] == {"shape": "cylinder", "Lz": 0.1225, "wall": None,
                                          "radius": 0.021}
    assert from_dict(json.loads(cfg.to_json())) == cfg
    assert apply_overrides(cfg, {"container.radius": 0.03}).container.dimension("radius") == 0.03
    from jaxdamp.config import ConfigError

    for change, words in (({"radius": None}, "lacks radius"), ({"side": 0.02}, "does not know"),
                          ({"shape": "sphere"}, "expected one of"),
                          ({"radius": 0.002}, "does not fit container.radius"),
                          ({"radius": 0.008}, "the grains cannot fit")):
        bad = json.loads(json.dumps(d))
        bad["container"].update(change)
        bad["container"] = {k: v for k, v in bad["container"].items() if v is not None}
        with pytest.raises(ConfigError, match=words):
            validate(from_dict(bad))
    both = json.loads(json.dumps(d))
    both["box"] = base.to_dict()["box"]
    with pytest.raises(ConfigError, match="exactly one of"):
        validate(from_dict(both))
    # from a box preset, on the command line and in a TOML file: the cylinder replaces the box
    cyl = validate(apply_overrides(base, ["container.shape=cylinder", "container.radius=0.021",
                                          "container.Lz=0.1225"]))
    assert cyl == cfg
    assert validate(apply_overrides(cyl, {"box.Lx": 0.04, "box.Ly": 0.04,
                                          "box.Lz": 0.12})).container is None


def test_a_cylinder_toml_over_a_box_preset(tmp_path):
    from jaxdamp.config import load_toml
    from jaxdamp.validation import validate

    path = tmp_path / "cyl.toml"
    path.write_text('[container]\nshape = "cylinder"\nradius = 0.021\nLz = 0.1225\n')
    cfg = validate(load_toml(str(path), presets.get("sanchez2012-optimal")))
    assert cfg.box is None and cfg.container.dimension("radius") == 0.021


@pytest.mark.long
def test_a_cylindrical_damper_settles_and_runs_on_both_engines():
    """The thesis damper's grains poured into a cylinder of the same base area: the bed lies
    inside the wall and a short drive balances its energy on both engines; from one settled
    bed the engines agree to rounding over 300 steps of the moving bed."""
    from jaxdamp.studies.runner import run

    base = presets.get("sanchez2012-optimal")
    rc = base.box.Lx / np.sqrt(np.pi)  # the same floor area
    out = {}
    for engine in ("native", "jax"):
        cfg = apply_overrides(_cylinder(base, rc, base.box.Lz),
                              {"numerics.duration": 0.02, "numerics.settle_time": 0.3,
                               "numerics.engine": engine})
        res = run(cfg, progress=False, echo=None)
        r = np.asarray(res.bed.r)
        rho = np.hypot(r[:, 0] - rc, r[:, 1] - rc)
        assert (rho < rc - 0.97 * base.grains[0].radius).all()
        scale = float(np.abs(res.records["work"][..., 0]).max()) + 1e-9
        assert np.abs(res.records["balance_residual"]).max() < 1e-3 * scale + 1e-9
        out[engine] = res
    bed = out["native"].bed
    cfg = apply_overrides(_cylinder(base, rc, base.box.Lz), {"system": "driven",
                                                            "drive": {"amplitude": 0.01}})
    vel = np.tile([0.3, -0.2, 0.5], (len(bed.r), 1))  # thrown at the wall, lid and each other
    ends, recs = [], []
    for engine in ("native", "jax"):
        model, pb, st, nbrs = start(cfg, bed.r, vel)
        st, _, rec = run_steps(model, pb, st, nbrs, 30, 10, engine=engine)
        ends.append(np.asarray(st.r[0]))
        recs.append(rec)
    assert np.abs(ends[0] - ends[1]).max() < 1e-12
    assert not np.allclose(ends[0], bed.r, atol=1e-4)  # it moved
    # the wall groups apart: counts and losses at the floor, the lid and the side wall,
    # the same on both engines, the losses adding up to the grain-wall channels
    for rec in recs:
        work = rec["work"]
        groups = work[:, [CH["pw_floor"], CH["pw_lid"], CH["pw_side"]]]
        total = work[:, CH["pw_normal"]] + work[:, CH["pw_friction"]]
        np.testing.assert_allclose(groups.sum(axis=1), total, rtol=1e-12, atol=1e-15)
        assert (groups[-1] > 0).all()  # the thrown bed hit all three
        assert rec["n_floor"].max() > 0 and rec["n_lid"].max() > 0 and rec["n_side"].max() > 0
    np.testing.assert_allclose(recs[0]["work"], recs[1]["work"], rtol=1e-9, atol=1e-15)
    for k in ("n_floor", "n_lid", "n_side"):
        np.testing.assert_array_equal(recs[0][k], recs[1][k])


def test_the_wall_groups_count_contacts_by_wall():
    """A grain pressed into the floor and the corner of the box touches the floor and two side
    walls (``n_side`` counts contacts, not grains); in a cylinder the same grain at the wall
    touches one. Moving straight down, it compresses the floor (a normal loss, the floor's)
    and slides along the side walls (a friction loss, the sides')."""
    import jax.numpy as jnp

    from jaxdamp.physics.walls import wall_forces

    base = presets.get("sanchez2012-optimal")
    one = apply_overrides(base, {"grains.0.count": 1})
    R = one.grains[0].radius
    for cfg, at, sides in ((one, [0.99 * R, 0.99 * R], 2),
                           (_cylinder(one, 0.02, one.box.Lz), [0.99 * R, 0.02], 1)):
        model, p = build(cfg)
        r = jnp.asarray([[at[0], at[1], 0.99 * R]])
        v = jnp.asarray([[0.0, 0.0, -0.1]])
        f = wall_forces(r, v, jnp.zeros((1, 3)), 0.0, 0.0, p, model)
        assert (int(f.n_floor), int(f.n_lid), int(f.n_side)) == (1, 0, sides)
        loss = np.asarray(f.group_loss)
        assert loss[0] > 0 and loss[1] == 0 and loss[2] > 0
        np.testing.assert_allclose(loss, [float(f.normal_loss), 0.0, float(f.friction_loss)],
                                   rtol=1e-14)


def test_a_random_pour_places_grains_apart_inside_any_container_and_settles():
    """``numerics.pour = "random"``: every grain inside the walls and clear of every other, a
    loose column (solid fraction ``LOOSE`` over the section), the same places for the same
    seed and others for another; the bed then settles like a lattice pour."""
    from jaxdamp.engine.packing import LOOSE, POURS, random_column, settle
    from jaxdamp.validation import POURS as NAMES
    from jaxdamp.validation import validate

    assert set(POURS) == set(NAMES)
    base = presets.get("sanchez2012-optimal")
    for cfg in (base, _cylinder(base, 0.02, base.box.Lz)):
        cfg = validate(apply_overrides(cfg, {"grains.0.count": 120,
                                             "grains.0.radius_spread": 0.2}))
        model, p = build(cfg)
        radii = np.asarray(p.radius)
        r = random_column(radii, cfg, 3)
        vessel = container(cfg)
        assert vessel.inside(r[:, 0], r[:, 1], 0.0, cfg).all()
        for i in range(len(r)):
            assert vessel.inside(r[i:i + 1, 0], r[i:i + 1, 1], radii[i] * (1 - 1e-12), cfg)[0]
        d = np.linalg.norm(r[:, None] - r[None], axis=-1) + np.eye(len(r))
        assert (d >= radii[:, None] + radii[None] - 1e-12).all()
        assert (r[:, 2] >= radii * (1 - 1e-12)).all()
        column = (4 / 3 * np.pi * radii**3).sum() / (LOOSE * vessel.base_area(cfg))
        assert r[:, 2].max() <= column + 3 * radii.max()
        np.testing.assert_array_equal(random_column(radii, cfg, 3), r)
        assert not np.allclose(random_column(radii, cfg, 4), r)
    cfg = validate(apply_overrides(base, {"grains.0.count": 60, "numerics.pour": "random",
                                          "numerics.settle_time": 0.4}))
    model, p = build(cfg)
    radii = np.asarray(p.radius)
    top = float((random_column(radii, cfg, 0)[:, 2] + radii).max())  # the poured column
    bed = settle(cfg, model, p)
    assert bed.settled and bed.height < 0.7 * top
    from jaxdamp.config import ConfigError

    with pytest.raises(ConfigError, match=r"numerics.pour = 'rain': expected one of"):
        validate(apply_overrides(base, {"numerics.pour": "rain"}))


@pytest.mark.long
@pytest.mark.parametrize("engine", ("jax", "native"))
def test_an_elastic_grain_bouncing_in_a_cylinder_keeps_its_energy_to_second_order(engine):
    """One grain, ``e = 1``, no friction, under gravity, thrown obliquely in a cylinder: it hits
    the side wall and the floor again and again in 0.4 s. Its mechanical energy (kinetic,
    gravitational, elastic) stays within 1e-3 of its start at 50 steps per collision (3.6e-4
    measured), and halving the step divides the largest error by about 4 (5.2 measured):
    velocity Verlet's second order."""
    rc = 0.01
    errors = []
    for per_collision in (50.0, 100.0):
        cfg = _cylinder(config(n=1, radius=R, material=ELASTIC, gravity=9.81, v_impact=1.0,
                               dt_per_collision=per_collision, duration=0.4, chunk=0.02,
                               record_dt=2e-4), radius=rc)
        r0 = np.array([rc + 0.004, rc, 0.006])
        model, pb, st, nbrs = start(cfg, [r0], [[0.6, 0.35, 0.0]])
        n = int(round(0.4 / 2e-4))
        every = max(1, int(round(2e-4 / float(np.asarray(pb.dt).ravel()[0]))))
        st, _, rec = run_steps(model, pb, st, nbrs, n, every, engine=engine)
        energy = rec["e_kinetic"] + rec["e_gravitational"] + rec["e_elastic"]
        e0 = 0.5 * float(np.asarray(pb.mass).ravel()[0]) * (0.6**2 + 0.35**2) \
            + float(np.asarray(pb.mass).ravel()[0]) * 9.81 * 0.006
        side_hits = np.diff((rec["n_side"] > 0).astype(int)) == 1
        floor_hits = np.diff((rec["n_floor"] > 0).astype(int)) == 1
        assert side_hits.sum() >= 8 and floor_hits.sum() >= 4
        assert np.abs(rec["work"][:, CH["pw_normal"]]).max() < 1e-12 * e0  # no loss at all
        errors.append(float(np.abs(energy - e0).max() / e0))
    assert errors[0] < 1e-3
    assert 2.5 < errors[0] / errors[1] < 6.0


def test_a_grain_pressed_on_the_curved_wall_rests_at_the_hertz_overlap_of_the_concave_radius():
    """The static side of the convention, on both forms of the wall: a grain pressed into the
    cylinder's wall with force ``F`` is held by ``F`` at the overlap
    ``ξ = (F / ((4/3) E* √R*))^{2/3}`` with ``R* = 2 R R_c / (2 R_c − R)``; the force is radial
    and the same in the kernel's scalar form."""
    import jax.numpy as jnp

    from jaxdamp.physics.contact import LAWS
    from jaxdamp.physics.walls import wall_forces

    rc = 0.01
    cfg = _cylinder(config(n=1, radius=R, material=ELASTIC), radius=rc)
    model, p = build(cfg)
    E_star = 1.0 / (2 * (1 - ELASTIC.nu**2) / ELASTIC.E)
    R_star = 2 * R * rc / (2 * rc - R)
    F = 0.05  # [N], e.g. a lateral body force
    xi = (F / (4 / 3 * E_star * np.sqrt(R_star))) ** (2 / 3)
    theta = 0.4
    e = np.array([np.cos(theta), np.sin(theta)])
    centre = np.array([rc, rc]) + (rc - R + xi) * e
    r = jnp.asarray([[centre[0], centre[1], 0.025]])
    f = wall_forces(r, jnp.zeros((1, 3)), jnp.zeros((1, 3)), 0.0, 0.0, p, model)
    force = np.asarray(f.force)[0]
    np.testing.assert_allclose(force[:2], -F * e, rtol=1e-10)
    assert abs(force[2]) < 1e-15 and int(f.n_side) == 1
    law = LAWS[model.law]
    row = np.asarray(p.wall_table)[0]
    kappa = containers.side_curvature_scalar(containers.CYLINDER.id, np.array([rc]))
    k, g = law.pair_scalar(row, containers.effective_radius(R, kappa), float(p.mass[0]))
    acc = containers.side_contacts_scalar(
        containers.CYLINDER.id, law.id, centre[0], centre[1],
        containers.section_scalar(np.array([rc])), R, np.array([[k, g, row[0], row[1]]]), 0,
        0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, (0.0,) * 11, None, None)
    np.testing.assert_allclose(acc[:2], -F * e, rtol=1e-10)


def test_the_moving_tilted_cylinder_presses_with_the_relative_velocity_along_the_radius():
    """A cylinder shaken along a tilted axis ``e``: shifting the grain with the container
    (``r + e z_box``) leaves its wall force unchanged, the force stays radial in the
    container's frame, and a grain moving with the walls (``v = e ż_box``) loses nothing while
    one at rest in the lab is damped by the walls' velocity."""
    import jax.numpy as jnp

    from jaxdamp.physics.walls import wall_forces

    rc = 0.01
    axis = np.array([0.3, -0.2, 1.0]) / np.linalg.norm([0.3, -0.2, 1.0])
    cfg = dataclasses.replace(_cylinder(config(n=1, radius=R, material=PAPER, amplitude=0.002),
                                        radius=rc), direction=tuple(axis))
    model, p = build(cfg)
    e = np.array([np.cos(1.1), np.sin(1.1)])
    local = np.array([rc + (rc - 0.9 * R) * e[0], rc + (rc - 0.9 * R) * e[1], 0.02])
    out = []
    for z, zd, v in ((0.0, 0.0, np.zeros(3)), (0.0013, 0.4, 0.4 * axis),
                     (0.0013, 0.4, np.zeros(3))):
        r = jnp.asarray([local + axis * z])
        f = wall_forces(r, jnp.asarray([v]), jnp.zeros((1, 3)), z, zd, p, model)
        out.append((np.asarray(f.force)[0], float(f.normal_loss)))
    np.testing.assert_allclose(out[1][0], out[0][0], rtol=1e-12)
    assert out[1][1] == 0.0 and out[0][1] == 0.0
    radial = out[0][0][:2] / np.linalg.norm(out[0][0][:2])
    np.testing.assert_allclose(radial, -e, atol=1e-12)
    assert out[2][1] > 0  # the wall moving past a grain at rest: a relative velocity, a loss
