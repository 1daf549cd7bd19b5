"""Reverse-mode gradients through the DEM scan are finite and match finite differences."""

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import config, start

from jaxdamp.config import Material
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.energy import granular_loss

MAT = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=50.0, gamma_s=150.0)


def _setup():
    """8 grains falling in a driven box, two of them touching the lid within the horizon;
    contacts open and close, some grains have zero tangential speed (ω = 0, head-on)."""
    n, R = 8, 2e-3
    cfg = config(n=n, radius=R, material=MAT, box=(0.012, 0.012, 0.012), gravity=9.8,
                 frequency=50.0, amplitude=1e-3)
    rng = np.random.default_rng(0)
    grid = np.stack(np.meshgrid(*[np.arange(2)] * 3, indexing="ij"), -1).reshape(-1, 3)
    r = (grid + 0.5) * 0.006 + rng.uniform(-3e-4, 3e-4, (n, 3))
    v = rng.normal(0, 0.3, (n, 3))
    v[:2] = [[0, 0, 0.4], [0, 0, 0.4]]
    return start(cfg, r, v, dt=2e-6)


# remat: slow (CI's time budget); without it, in the default suite
@pytest.mark.parametrize("remat", [False, pytest.param(True, marks=pytest.mark.slow)])
def test_gradient_of_dissipation_wrt_lid_height(remat):
    model, pb, st, nbrs = _setup()
    fn = chunk_fn(model, 6, 50, remat=remat)

    def loss(Lz):
        p = dataclasses.replace(pb, Lz=jnp.full((1,), Lz))
        out, _, _ = fn(st, nbrs, p)
        return granular_loss(out.work)[0]

    Lz0 = 0.012
    value, grad = jax.value_and_grad(loss)(Lz0)
    assert np.isfinite(grad) and value > 0
    # central differences converge to the AD value only for small steps (h = 1e-7 m is still 1.5 %
    # off: contacts switch on and off); at h = 1e-9 m they agree to ~1e-6.
    h = 1e-9
    fd = (loss(Lz0 + h) - loss(Lz0 - h)) / (2 * h)
    assert grad == pytest.approx(float(fd), rel=1e-4)


@pytest.mark.long  # half a minute (the marker's definition)
def test_gradients_finite_for_every_parameter():
    """No NaN from sqrt or norms at zero overlap / zero sliding speed, for all parameters."""
    model, pb, st, nbrs = _setup()
    fn = chunk_fn(model, 3, 50)

    def loss(p):
        out, _, _ = fn(st, nbrs, p)
        return granular_loss(out.work)[0] + out.r[0, :, 2].sum()

    grads = jax.grad(loss)(pb)
    for name, g in dataclasses.asdict(grads).items():
        assert np.all(np.isfinite(np.asarray(g))), name


@pytest.mark.slow  # ~1-2 min: not in CI (its time budget): pytest -m slow
def test_float32_contact_laws_give_the_float64_gradient():
    """With ``numerics.precision = 'float32'`` (contact laws in float32, geometry, state and
    sums in float64) the reverse-mode gradient of the dissipation with respect to the lid
    height equals the float64 one to 1e-3 relative."""
    model, pb, st, nbrs = _setup()
    grads = {}
    for precision in ("float64", "float32"):
        m = dataclasses.replace(model, precision=precision)
        fn = chunk_fn(m, 6, 50)

        def loss(Lz, fn=fn):
            p = dataclasses.replace(pb, Lz=jnp.full((1,), Lz))
            out, _, _ = fn(st, nbrs, p)
            return granular_loss(out.work)[0]

        grads[precision] = jax.value_and_grad(loss)(0.012)
    (v64, g64), (v32, g32) = grads["float64"], grads["float32"]
    assert np.isfinite(g32) and v32 == pytest.approx(float(v64), rel=1e-4)
    print(f"float32/float64 - 1: value {float(v32 / v64 - 1):.2g}, gradient "
          f"{float(g32 / g64 - 1):.2g}")
    assert g32 == pytest.approx(float(g64), rel=1e-3)
