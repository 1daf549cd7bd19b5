"""The mount registry (jaxdamp.physics.mounts): every mount's JAX forms and the scalar forms
the compiled kernel inlines agree, state by state, with parameters read by name from the
kernel's packed row."""

import jax.numpy as jnp
import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.engine import native
from jaxdamp.physics import mounts
from jaxdamp.physics.model import build

CASES = {  # a configuration of each mount
    "primary": ("sanchez2012-random", {}),
    "structure": ("sanchez2012-chain", {"structure.force": 3.0}),
    "driven": ("varela2023-reference", {"drive.amplitude": 0.01}),
}


def _packed(params):
    batched = type(params)(**{k: jnp.asarray(v)[None] for k, v in vars(params).items()})
    row = np.asarray(native.pack(batched))[0]
    lay = native.layout(batched)
    return row, native.ParamOffsets(*native.offsets(lay, native.PARAM_FIELDS))


@pytest.mark.parametrize("name", sorted(mounts.MOUNTS))
def test_the_jax_and_scalar_forms_of_every_mount_agree(name):
    preset, over = CASES[name]
    model, p = build(apply_overrides(presets.get(preset), over))
    mount = mounts.mount_of(model)
    assert mount.name == name
    row, po = _packed(p)
    n = model.dofs
    n_lines = int(np.asarray(p.lines).shape[0])
    rng = np.random.default_rng(3)
    xs, xds, acc, tmp = np.empty(n), np.empty(n), np.zeros(n), np.empty(n)
    for _ in range(20):
        t, dt = rng.uniform(0, 2), 1e-5
        z, zd, zdd = rng.normal(0, [1e-3, 0.1, 10.0])
        y, yd = rng.normal(0, 1e-3, n - 1), rng.normal(0, 0.1, n - 1)
        f = rng.normal(0, 5.0, n)  # the grains' forces on every degree of freedom
        pj = mount.predict(z, zd, zdd, t + dt, dt, p)
        ps = mounts.predict_scalar(mount.id, t + dt, dt, z, zd, zdd, row, po)
        np.testing.assert_allclose(ps, [float(v) for v in pj], rtol=1e-13, atol=1e-15)
        a_j, ay_j = mount.accelerate(z, zd, jnp.asarray(y), jnp.asarray(yd), t, jnp.asarray(f),
                                     p)
        pin_j, pc_j = mount.powers(jnp.asarray(f), z, zd, jnp.asarray(y), jnp.asarray(yd), t, p)
        a_s, pin_s, pc_s = mounts.respond_scalar(mount.id, t, z, zd, y, yd, f, row, po,
                                                 n_lines, xs, xds, acc, tmp)
        np.testing.assert_allclose([a_s, pin_s, pc_s], [float(a_j), float(pin_j), float(pc_j)],
                                   rtol=1e-12, atol=1e-12)
        if name == "structure":
            np.testing.assert_allclose(acc[1:], np.asarray(ay_j), rtol=1e-12, atol=1e-12)
        e_j = mount.energy(z, zd, jnp.asarray(y), jnp.asarray(yd), t, p)
        e_s = mounts.energy_scalar(mount.id, t, z, zd, y, yd, row, po, n_lines, xs, xds)
        assert e_s == pytest.approx(float(e_j), rel=1e-12, abs=1e-15)
    if mount.prescribed:  # the drive: its velocity is the derivative of its position
        h, t = 1e-7, 0.3013
        _, v0 = mount.predict(0.0, 0.0, 0.0, t, 0.0, p)
        za, _ = mount.predict(0.0, 0.0, 0.0, t - h, 0.0, p)
        zb, _ = mount.predict(0.0, 0.0, 0.0, t + h, 0.0, p)
        assert float((zb - za) / (2 * h)) == pytest.approx(float(v0), rel=1e-6)


def test_the_primary_mount_is_the_thesis_equation():
    """``M z'' = -C (z' - u') - K (z - u) + F_gz`` and the energy ½ M z'² + ½ K (z - u)²,
    by hand at one state (the base at rest: U = 0)."""
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {"primary.U": 0.0})
    model, p = build(cfg)
    M, K, C = cfg.primary.M, cfg.primary.K, cfg.primary.C
    mount = mounts.mount_of(model)
    z, zd, F = 2e-3, -0.05, 7.0
    a, _ = mount.accelerate(z, zd, jnp.zeros(0), jnp.zeros(0), 0.1, jnp.asarray([F]), p)
    assert float(a) == pytest.approx((-C * zd - K * z + F) / M, rel=1e-14)
    e = mount.energy(z, zd, jnp.zeros(0), jnp.zeros(0), 0.1, p)
    assert float(e) == pytest.approx(0.5 * M * zd**2 + 0.5 * K * z**2, rel=1e-14)
    p_in, p_c = mount.powers(jnp.asarray([F]), z, zd, jnp.zeros(0), jnp.zeros(0), 0.1, p)
    assert float(p_in) == 0.0 and float(p_c) == pytest.approx(C * zd**2, rel=1e-14)
