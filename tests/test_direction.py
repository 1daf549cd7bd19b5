"""Excitation along any axis (``Config.direction``): the box, the base and the primary move along
a unit vector ``e``, gravity stays along −z. Checked by symmetry, on both engines: the same
damper run in a rotated frame gives the rotated trajectory."""

import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.config import ConfigError, apply_overrides
from jaxdamp.engine import driver
from jaxdamp.physics.energy import granular_loss
from jaxdamp.physics.model import CH, LOSSES, build
from jaxdamp.validation import validate

L = 0.012  # cubic box [m]


def _config(system: str, direction, gravity: float):
    base = presets.get("sanchez2012-optimal")
    sets = {"grains.0.count": 27, "grains.0.radius": 1.5e-3, "box.Lx": L, "box.Ly": L,
            "box.Lz": L, "gravity": gravity, "direction": list(direction), "frequency": 40.0,
            "numerics.stiffness_scale": 0.01}
    if system == "driven":
        sets.update({"system": "driven", "drive.amplitude": 0.004})
    return validate(apply_overrides(base, sets))


def _gas(seed=3):
    """27 grains on a jittered lattice in the box frame, moving and spinning."""
    rng = np.random.default_rng(seed)
    g = (np.arange(3) + 0.5) * L / 3
    r = np.stack(np.meshgrid(g, g, g, indexing="ij"), -1).reshape(-1, 3)
    r = r + rng.uniform(-4e-4, 4e-4, r.shape)
    return r, rng.normal(0, 1.0, r.shape), rng.normal(0, 50.0, r.shape)


def _run(cfg, r_box, v, w, zd0, engine, steps=6000):
    model, params = build(cfg)
    e = np.array([params.ex, params.ey, params.ez], float)
    z0 = cfg.drive.amplitude if cfg.system == "driven" else 0.0
    pb = driver.batched(params)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (len(r_box), 1))
    b = driver.start(model, pb, (r_box + e * z0)[None], v[None], w[None], q[None],
                     np.array([z0]), np.array([zd0]), engine=engine)
    b, recs = driver.advance(b, steps // 100, 100)
    st = b.system(0)
    return (np.asarray(st.r), np.asarray(st.v), np.asarray(st.w), float(st.z),
            {k: v[0] for k, v in recs.items()})


@pytest.mark.parametrize("engine, system", [
    pytest.param("jax", "primary", marks=pytest.mark.long),  # half a minute
    ("jax", "driven"), ("native", "primary"), ("native", "driven")])
def test_drive_along_x_is_the_drive_along_z_rotated(engine, system):
    """No gravity: a gas of 27 grains in a cube driven along z, and the same gas rotated by
    the cyclic permutation (x, y, z) -> (z, x, y) (a proper rotation taking z to x) driven
    along x: after 6000 steps (~15 ms) with wall and grain collisions the grains, the box and every
    work channel of the balance agree to round-off."""
    r, v, w = _gas()
    P = np.array([[0, 0, 1], [1, 0, 0], [0, 1, 0]], float)  # r' = P r: z -> x
    zd0 = 0.3 if system == "primary" else 0.0
    ra, va, wa, za, reca = _run(_config(system, (0, 0, 1), 0.0), r, v, w, zd0, engine)
    rb, vb, wb, zb, recb = _run(_config(system, (1, 0, 0), 0.0), r @ P.T, v @ P.T, w @ P.T,
                                zd0, engine)
    loss = granular_loss(reca["work"])[-1]
    assert loss > 0 and abs(za) > 1e-4  # the grains collided; the box moved
    np.testing.assert_allclose(rb, ra @ P.T, atol=1e-12)
    np.testing.assert_allclose(vb, va @ P.T, atol=1e-9)
    np.testing.assert_allclose(wb, wa @ P.T, atol=1e-6)
    assert zb == pytest.approx(za, abs=1e-12)
    # the balance's channels agree; the wall groups do not, by design: rotated, the floor and
    # the lid are side walls of the box and two side walls its floor and lid
    kept = np.concatenate([[CH["input"]], LOSSES])
    np.testing.assert_allclose(recb["work"][:, kept], reca["work"][:, kept], rtol=1e-9,
                               atol=1e-12 * loss)
    groups = [CH["pw_floor"], CH["pw_lid"], CH["pw_side"]]
    np.testing.assert_allclose(recb["work"][:, groups].sum(-1), reca["work"][:, groups].sum(-1),
                               rtol=1e-9, atol=1e-12 * loss)
    np.testing.assert_allclose(recb["force_box"], reca["force_box"], rtol=1e-7, atol=1e-9)
    # the energy balance closes as for the vertical drive (velocity Verlet's error at
    # dt = t_c/50, ~1e-3 of the loss), and identically in both frames
    assert np.abs(recb["balance_residual"]).max() < 5e-3 * loss
    np.testing.assert_allclose(recb["balance_residual"], reca["balance_residual"], atol=1e-9 * loss)


@pytest.mark.parametrize("engine", ["jax", "native"])
def test_horizontal_drive_with_gravity_is_symmetric_about_the_vertical(engine):
    """Gravity on: a bed driven along x, and the same bed rotated by 90° about z (and moved
    back into the box) driven along y, agree to round-off."""
    r, v, w = _gas()
    R = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], float)  # about z: x -> y
    shift = np.array([L, 0.0, 0.0])
    ra, va, wa, za, reca = _run(_config("driven", (1, 0, 0), 9.8), r, v, w, 0.0, engine)
    rb, vb, wb, zb, recb = _run(_config("driven", (0, 1, 0), 9.8), r @ R.T + shift, v @ R.T,
                                w @ R.T, 0.0, engine)
    np.testing.assert_allclose(rb, ra @ R.T + shift, atol=1e-12)
    np.testing.assert_allclose(vb, va @ R.T, atol=1e-9)
    loss = granular_loss(reca["work"])[-1]
    np.testing.assert_allclose(recb["work"], reca["work"], rtol=1e-7, atol=1e-12 * loss)


def test_direction_is_checked_before_compute():
    base = presets.get("sanchez2012-optimal")
    for bad in ([0, 0, 0], [1, 0], [float("nan"), 0, 1]):
        with pytest.raises(ConfigError, match="direction"):
            validate(apply_overrides(base, {"direction": bad}))
    with pytest.raises(ConfigError, match="vertical"):
        validate(apply_overrides(presets.get("sanchez2012-impact"), {"direction": [1, 0, 0]}))
    # a direction of any length is normalised
    _, p = build(validate(apply_overrides(base, {"direction": [0, 3, 4]})))
    assert (float(p.ex), float(p.ey), float(p.ez)) == pytest.approx((0, 0.6, 0.8))


def test_the_bed_starts_moved_with_the_box_along_the_axis():
    """A bed settled in the box at rest is moved with the box to its starting position along
    the excitation axis (not along z): horizontal axis, primary.z0 = 1 cm."""
    import numpy as np

    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies.runner import bed_with_box, initial_box_position

    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {"direction": [1.0, 0.0, 0.0], "primary.z0": 0.01})
    z0 = initial_box_position(cfg, 0.227)
    assert z0 == 0.01  # no weight along a horizontal axis
    r = np.random.default_rng(0).uniform(0, 0.03, (5, 3))
    np.testing.assert_allclose(bed_with_box(cfg, r, z0) - r, np.tile([0.01, 0.0, 0.0], (5, 1)),
                               rtol=0, atol=1e-15)
    vertical = apply_overrides(cfg, {"direction": [0.0, 0.0, 1.0]})
    np.testing.assert_array_equal(bed_with_box(vertical, r, 0.02), r + [0.0, 0.0, 0.02])
