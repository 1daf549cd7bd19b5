"""Binary mixtures (jaxdamp.cases.mixtures): the paper's classes a, b, c, per-species damping, the time
step from the smallest grains, and size-aware neighbour lists on a tenfold size ratio."""

import dataclasses
import math

import jax.numpy as jnp
import numpy as np
import pytest

from jaxdamp.cases import mixtures, presets
from jaxdamp.config import ConfigError
from jaxdamp.engine import neighbors as nb
from jaxdamp.physics import restitution as rst
from jaxdamp.physics.model import build, contact_law
from jaxdamp.physics.pairs import all_pairs, pair_forces
from jaxdamp.validation import validate

REF = presets.get("varela2023-reference")
N_REF, R_REF = 300, 2.5e-3


def _mass(cfg):
    return sum(sp.count * sp.radius**3 for sp in cfg.grains)  # same density throughout


@pytest.mark.parametrize("sigma", [0.1, 0.3, 0.5, 0.7, 0.9, 1.0])
def test_class_builders_counts_radii_and_conserved_quantities(sigma):
    ref_mass = N_REF * R_REF**3
    a = validate(mixtures.binary(REF, "a", sigma))
    (la, sa) = a.grains
    n = round(N_REF / (1 + sigma**3))
    assert (la.count, sa.count) == (n, n)
    assert (la.radius, sa.radius) == (R_REF, pytest.approx(sigma * R_REF, rel=1e-15))
    # equal mass up to rounding the count to whole grains: at most half a pair of grains
    assert abs(_mass(a) / ref_mass - 1) <= (1 + sigma**3) / (2 * N_REF) + 1e-15

    b = validate(mixtures.binary(REF, "b", sigma))
    assert [sp.count for sp in b.grains] == [150, 150] and b.n_grains == N_REF
    assert [sp.radius for sp in b.grains] == [R_REF, pytest.approx(sigma * R_REF, rel=1e-15)]

    c = validate(mixtures.binary(REF, "c", sigma))
    assert [sp.count for sp in c.grains] == [150, 150] and c.n_grains == N_REF
    assert c.grains[0].radius == pytest.approx((2 - sigma**3) ** (1 / 3) * R_REF, rel=1e-15)
    assert c.grains[1].radius == pytest.approx(sigma * R_REF, rel=1e-15)
    assert _mass(c) == pytest.approx(ref_mass, rel=1e-14)  # number and mass exactly
    for cfg in (a, b, c):
        assert [sp.name for sp in cfg.grains] == ["large", "small"]
        assert cfg.box == dataclasses.replace(REF.box) and cfg.drive == REF.drive


def test_class_a_exact_numbers_and_presets():
    # σ = 0.5: N_tot = 600 / 1.125 = 533.3 -> 267 + 267 grains, mass +0.125 %
    a = presets.get("varela2023-a")
    assert [sp.count for sp in a.grains] == [267, 267]
    assert _mass(a) / (N_REF * R_REF**3) - 1 == pytest.approx(267 * 1.125 / 300 - 1, abs=1e-14)
    assert mixtures.granulate_mass(REF) == pytest.approx(0.154, abs=5e-4)  # the paper's 0.154 kg
    for name in ("varela2023-b", "varela2023-c"):
        assert presets.get(name) == presets.family(name, 0.5)


def test_builder_errors_name_the_parameter():
    with pytest.raises(ConfigError, match=r"sigma = 0.*\(0, 1\]"):
        mixtures.binary(REF, "a", 0.0)
    with pytest.raises(ConfigError, match="sigma = 1.2"):
        mixtures.binary(REF, "b", 1.2)
    with pytest.raises(ConfigError, match="class 'd' is unknown"):
        mixtures.binary(REF, "d", 0.5)
    odd = REF.replace(grains=(dataclasses.replace(REF.grains[0], count=301),))
    with pytest.raises(ConfigError, match="even"):
        mixtures.binary(odd, "c", 0.5)
    with pytest.raises(ConfigError, match="one-species"):
        mixtures.binary(presets.get("varela2023-a"), "a", 0.5)
    with pytest.raises(ConfigError, match="not a binary-mixture family"):
        presets.family("sanchez2012-optimal")


def test_per_species_damping_and_mixing_rule():
    """Each species' A gives ε = 0.75 at 1 m/s for its own like pair (paper); unlike pairs use
    the arithmetic mean (the config's rule); the walls keep the reference's A in every class."""
    cfg = presets.get("varela2023-c")  # radii σ̂ R_ref and σ R_ref: neither is the reference's
    model, p = build(cfg)
    law = contact_law(cfg)
    table = np.asarray(p.pair_table)
    A = table[:, :, law.column("A")]
    E_star = float(table[0, 0, law.column("E_star")])
    for s, species in enumerate(cfg.grains):
        R = species.radius
        m = 7850 * 4 / 3 * math.pi * R**3
        assert rst.restitution(0.5 * m, 0.5 * R, E_star, 1.0, A=A[s, s]) == pytest.approx(0.75, abs=1e-6)
    # A scales with the radius at fixed ε (β ∝ A / R): the small species' is smaller
    assert A[1, 1] / A[0, 0] == pytest.approx(cfg.grains[1].radius / cfg.grains[0].radius, rel=1e-6)
    assert A[0, 1] == pytest.approx(0.5 * (A[0, 0] + A[1, 1]), rel=1e-12)  # arithmetic mixing
    # the walls' A (mixed arithmetically with each species') is the reference's in every class
    ref_p = build(REF)[1]
    A_wall_ref = 2 * float(ref_p.wall_table[0, law.column("A")]) - float(ref_p.pair_table[0, 0, law.column("A")])
    wall_A = np.asarray(p.wall_table)[:, law.column("A")]
    np.testing.assert_allclose(2 * wall_A - np.diag(A), A_wall_ref, rtol=1e-12)
    assert cfg.mixing == "arithmetic"


def test_time_step_follows_the_smallest_grains_and_the_drive():
    """dt = t_c / 50 of the smallest like pair at the walls' relative speed 2 A_d ω."""
    dts = {}
    for sigma in (0.1, 0.5, 1.0):
        cfg = mixtures.binary(REF, "b", sigma)
        _, p = build(cfg)
        r = sigma * R_REF
        m = 7850 * 4 / 3 * math.pi * r**3
        v = 2 * 0.03 * 2 * math.pi * 70
        E_star = float(p.pair_table[0, 0, contact_law(cfg).column("E_star")])
        t_c = rst.collision_time(0.5 * m, 0.5 * r, E_star, v)
        assert float(p.dt) == pytest.approx(t_c / 50, rel=1e-12)
        dts[sigma] = float(p.dt)
    assert dts[0.1] / dts[1.0] == pytest.approx(0.1, rel=1e-9)  # t_c ∝ R at fixed material
    # a larger amplitude shortens collisions: dt ∝ (2 A_d ω)^(-1/5)
    louder = build(REF.replace(drive=dataclasses.replace(REF.drive, amplitude=0.04)))[1]
    assert float(louder.dt) / dts[1.0] == pytest.approx((3 / 4) ** 0.2, rel=1e-9)


def _mixture_positions(n_large, n_small, r_large, r_small, side, seed):
    """Large grains on a jittered lattice (overlapping), small grains scattered among them."""
    rng = np.random.default_rng(seed)
    k = int(np.ceil(n_large ** (1 / 3)))
    grid = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n_large]
    big = (grid + 0.5) * 1.9 * r_large + rng.uniform(-0.1, 0.1, (n_large, 3)) * r_large
    small = rng.uniform(r_small, k * 1.9 * r_large, (n_small, 3))
    return np.concatenate([big, small])


def _gentle_positions(n_large, n_small, r_large, r_small, seed):
    """Like :func:`_mixture_positions` but with overlaps below 5 % of the small radius, so that
    a few steps stay gentle (rejection sampling)."""
    rng = np.random.default_rng(seed)
    k = int(np.ceil(n_large ** (1 / 3)))
    grid = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n_large]
    pos = list((grid + 0.5) * 2.2 * r_large)
    rad = [r_large] * n_large
    while len(pos) < n_large + n_small:
        x = rng.uniform(r_small, k * 2.2 * r_large, 3)
        d = np.linalg.norm(np.asarray(pos) - x, axis=1) - np.asarray(rad) - r_small
        if d.min() > -0.05 * r_small:
            pos.append(x)
            rad.append(r_small)
    return np.asarray(pos)


def test_tenfold_mixture_neighbour_list_equals_all_pairs_and_stays_small():
    """σ = 0.1: 27 large + 600 small grains, dense and overlapping. The size-aware list gives the
    all-pairs forces to 1e-12, holds every pair with a surface gap below the skin, and lists
    several times fewer neighbours than a uniform 2 R_max + skin cutoff would."""
    base = REF.replace(grains=(dataclasses.replace(REF.grains[0], count=54),))
    cfg = mixtures.binary(base, "b", 0.1)
    cfg = cfg.replace(grains=(dataclasses.replace(cfg.grains[0], count=27),
                              dataclasses.replace(cfg.grains[1], count=600)))
    model, p = build(cfg)
    r = _mixture_positions(27, 600, R_REF, 0.1 * R_REF, 0.02, seed=11)
    rng = np.random.default_rng(2)
    v, w = rng.normal(0, 0.3, r.shape), rng.normal(0, 100.0, r.shape)
    R = np.asarray(p.radius)
    nbrs = nb.allocate(model, jnp.asarray(r)[None], 1.0, radius=p.radius)
    idx = np.asarray(nbrs.idx[0])
    got = pair_forces(jnp.asarray(r), jnp.asarray(v), jnp.asarray(w), nbrs.idx[0], p, model)
    ref = pair_forces(jnp.asarray(r), jnp.asarray(v), jnp.asarray(w), all_pairs(model.n), p, model)
    scale = float(jnp.abs(ref.force).max())
    assert scale > 0
    np.testing.assert_allclose(got.force, ref.force, atol=1e-12 * scale)
    np.testing.assert_allclose(got.torque, ref.torque, atol=1e-12 * float(jnp.abs(ref.torque).max()))
    assert float(got.normal_loss) == pytest.approx(float(ref.normal_loss), rel=1e-12)
    # completeness: every pair whose gap is below the skin is listed (both directions)
    d = np.linalg.norm(r[:, None] - r[None], axis=-1)
    near = (d < R[:, None] + R[None] + model.skin) & ~np.eye(model.n, dtype=bool)
    listed = np.zeros_like(near)
    rows = np.repeat(np.arange(model.n), idx.shape[1])
    ok = idx.ravel() < model.n
    listed[rows[ok], idx.ravel()[ok]] = True
    assert np.all(listed[near])
    # efficiency: capacity and listed pairs against the uniform cutoff
    uniform = nb.allocate(model, jnp.asarray(r)[None], 1.0)
    n_aware = int((idx < model.n).sum())
    n_uniform = int((np.asarray(uniform.idx[0]) < model.n).sum())
    assert nb.capacity(nbrs) * 3 < nb.capacity(uniform)
    assert n_aware * 4 < n_uniform, (n_aware, n_uniform)


def test_native_engine_lists_the_same_contacts_on_a_tenfold_mixture():
    """The compiled engine's size-aware pair list: 20 steps on the σ = 0.1 mixture agree with the
    JAX engine (neighbour list as above) to round-off."""
    from jaxdamp.engine import native

    if not native.AVAILABLE:
        pytest.skip("numba is not installed")
    from helpers import advance, start

    base = REF.replace(grains=(dataclasses.replace(REF.grains[0], count=54),), gravity=9.8)
    cfg = mixtures.binary(base, "b", 0.1)
    cfg = cfg.replace(grains=(dataclasses.replace(cfg.grains[0], count=27),
                              dataclasses.replace(cfg.grains[1], count=300)))
    r = _gentle_positions(27, 300, R_REF, 0.1 * R_REF, seed=5)
    v = np.random.default_rng(3).normal(0, 0.5, r.shape)
    out = {}
    for engine in ("jax", "native"):
        model, pb, st, nbrs = start(cfg, r, v)
        b, rec = advance(model, st, nbrs, pb, 2, 10, engine=engine)
        out[engine] = (np.asarray(b.states.r[0]), np.asarray(rec["work"][0]))
    np.testing.assert_allclose(out["native"][0], out["jax"][0], rtol=0, atol=1e-13)
    np.testing.assert_allclose(out["native"][1], out["jax"][1], rtol=1e-9, atol=1e-15)
    assert out["jax"][1][-1, 2] > 0  # grain-grain contacts did dissipate
