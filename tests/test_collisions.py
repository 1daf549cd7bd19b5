"""Binary collisions against the calibrated restitution and the Hertz collision time.

Reference values come from :mod:`jaxdamp.physics.restitution`, which integrates one collision of the
force law with scipy (an independent ODE solver): the DEM step must reproduce them.
"""

import math

import numpy as np
import pytest
from helpers import ENGINES, config, run_steps, start

from jaxdamp.config import Material
from jaxdamp.physics import restitution as rst
from jaxdamp.physics.model import build, contact_law

R = 2.5e-3
PAPER = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, restitution=0.75, v_ref=1.0)
ELASTIC = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, gamma_n=0.0)
SPEEDS = (0.3, 1.0, 3.0)


def _pair_constants(mat):
    m = mat.density * 4 / 3 * math.pi * R**3
    E_star = mat.E / (2 * (1 - mat.nu**2))
    return m, E_star


def _A(cfg, wall=False):
    """The (mixed) dissipative constant ``A`` of a like pair (or grain–wall) from the tables."""
    p, col = build(cfg)[1], contact_law(cfg).column("A")
    return float(p.wall_table[0, col] if wall else p.pair_table[0, 0, col])


def _head_on(mat, v, dt_fraction=50.0, engine="jax"):
    """Two grains approach along x at relative speed v; returns (measured ε, contact time, A)."""
    cfg = config(n=2, radius=R, material=mat, v_impact=v, dt_per_collision=dt_fraction)
    model, params = build(cfg)
    dt = float(params.dt)
    gap = 0.2 * R
    c = 0.025
    r = [[c - R - gap / 2, c, c], [c + R + gap / 2, c, c]]
    vel = [[v / 2, 0, 0], [-v / 2, 0, 0]]
    model, pb, st, nbrs = start(cfg, r, vel)
    n_steps = int((gap / v) / dt) + int(3 * dt_fraction)
    st, nbrs, rec = run_steps(model, pb, st, nbrs, n_steps, 1, engine=engine)
    v_out = np.asarray(st.v[0])
    eps = (v_out[1, 0] - v_out[0, 0]) / v
    touching = rec["e_elastic"] > 0
    return eps, touching.sum() * dt, _A(cfg)


def _on_floor(mat, v, dt_fraction=50.0, engine="jax"):
    """One grain hits the resting floor at speed v (no gravity); returns (ε, contact time)."""
    cfg = config(n=1, radius=R, material=mat, v_impact=v, dt_per_collision=dt_fraction)
    model, params = build(cfg)
    dt = float(params.dt)
    gap = 0.1 * R
    model, pb, st, nbrs = start(cfg, [[0.025, 0.025, R + gap]], [[0, 0, -v]])
    n_steps = int((gap / v) / dt) + int(3 * dt_fraction)
    st, nbrs, rec = run_steps(model, pb, st, nbrs, n_steps, 1, engine=engine)
    eps = float(st.v[0][0, 2]) / v
    return eps, (rec["e_elastic"] > 0).sum() * dt


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("v", SPEEDS)
def test_pair_restitution_matches_calibration(v, engine):
    """Measured ε of a head-on pair collision equals ε(A, v) of the force law within 0.5 %."""
    m, E_star = _pair_constants(PAPER)
    eps, _, A = _head_on(PAPER, v, engine=engine)
    expected = rst.collision(A=A, m_star=m / 2, R_star=R / 2, E_star=E_star, v=v).restitution
    assert eps == pytest.approx(expected, rel=5e-3)
    if v == 1.0:
        assert eps == pytest.approx(0.75, rel=5e-3)  # the calibration target itself


def test_restitution_decreases_with_speed():
    eps = [_head_on(PAPER, v)[0] for v in SPEEDS]
    assert eps[0] > eps[1] > eps[2]


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("v", (0.3, 3.0))
def test_wall_restitution_matches_calibration(v, engine):
    m, _ = _pair_constants(PAPER)
    E_star_wall = 1.0 / (2 * (1 - PAPER.nu**2) / PAPER.E)
    A = _A(config(n=1, radius=R, material=PAPER), wall=True)
    eps, _ = _on_floor(PAPER, v, engine=engine)
    expected = rst.collision(A=A, m_star=m, R_star=R, E_star=E_star_wall, v=v).restitution
    assert eps == pytest.approx(expected, rel=5e-3)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("v", (0.5, 2.0))
def test_contact_duration_is_hertz_time(v, engine):
    """Undamped contact lasts the Hertz collision time within 2 % (pair and wall).

    dt = t_c/500 here so that counting steps resolves the duration to 0.2 %.
    """
    m, E_star = _pair_constants(ELASTIC)
    eps, duration, _ = _head_on(ELASTIC, v, dt_fraction=500, engine=engine)
    t_c = rst.collision_time(m / 2, R / 2, E_star, v)
    assert duration == pytest.approx(t_c, rel=0.02)
    assert eps == pytest.approx(1.0, abs=1e-3)  # elastic

    eps_w, duration_w = _on_floor(ELASTIC, v, dt_fraction=500, engine=engine)
    E_star_wall = 1.0 / (2 * (1 - ELASTIC.nu**2) / ELASTIC.E)
    assert duration_w == pytest.approx(rst.collision_time(m, R, E_star_wall, v), rel=0.02)
    assert eps_w == pytest.approx(1.0, abs=1e-3)


WALL_PAPER = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, restitution=0.75, v_ref=1.0,
                      calibration_radius=2.5e-3)


def _floor_bounce(radius, v, wall_damping, engine):
    """ε of one grain of ``radius`` (paper steel, e = 0.75 at 1 m/s) hitting the floor of a
    box whose wall is the paper's steel calibrated at 2.5 mm, under ``wall_damping``."""
    import dataclasses

    from jaxdamp.config import Box

    cfg = dataclasses.replace(config(n=1, radius=radius, material=PAPER, v_impact=v),
                              box=Box(0.05, 0.05, 0.05, wall=WALL_PAPER),
                              wall_damping=wall_damping)
    model, params = build(cfg)
    dt = float(params.dt)
    gap = 0.1 * radius
    model, pb, st, nbrs = start(cfg, [[0.025, 0.025, radius + gap]], [[0, 0, -v]])
    st, nbrs, rec = run_steps(model, pb, st, nbrs, int((gap / v) / dt) + 150, 1, engine=engine)
    return float(st.v[0][0, 2]) / v


@pytest.mark.parametrize("engine", ENGINES)
def test_wall_damping_conventions(engine):
    """The two grain–wall conventions on both engines (docs/physics.md §7). 'mixed': the wall's
    constant (calibrated on 2.5 mm grains) mixed with each grain's, so at 1 m/s a 1.25 mm grain
    bounces off the wall with ε ≈ 0.69 and a 2.5 mm grain with ≈ 0.78 (not 0.75); 'calibrated':
    every size bounces with the wall's 0.75 at v_ref = 1 m/s, within 0.5 %. Away from v_ref the
    calibrated contact still follows the force law (ε falls with speed)."""
    mixed = [_floor_bounce(r, 1.0, "mixed", engine) for r in (1.25e-3, 2.5e-3)]
    assert mixed[0] == pytest.approx(0.69, abs=0.01) and mixed[1] == pytest.approx(0.78, abs=0.01)
    for r in (1.25e-3, 2.5e-3):
        assert _floor_bounce(r, 1.0, "calibrated", engine) == pytest.approx(0.75, rel=5e-3)
    assert _floor_bounce(1.25e-3, 3.0, "calibrated", engine) < 0.75


def test_wall_damping_bad_input():
    import dataclasses

    from jaxdamp.config import ConfigError
    from jaxdamp.validation import validate

    cfg = config(n=1, material=PAPER)
    with pytest.raises(ConfigError, match="wall_damping = 'sticky'"):
        validate(dataclasses.replace(cfg, wall_damping="sticky"))
    thesis = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, gamma_n=100.0)
    with pytest.raises(ConfigError, match="grains.0.material has no restitution"):
        validate(dataclasses.replace(config(n=1, material=thesis), wall_damping="calibrated"))
