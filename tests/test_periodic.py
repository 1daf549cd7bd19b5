"""Steady-state gradients of S3 by implicit differentiation of the periodic orbit
(jaxdamp.s3.periodic): the orbit is a fixed point of the stroboscopic map with consistent Floquet
multipliers, the implicit derivative matches finite differences of re-solved orbits and of
long-time averages of the smooth model, and an irregular response is reported as such.

All at the preset's frequency, 15.16 Hz (sanchez2012-impact): gaps 0.04, 0.0835 and 0.095 m
are period-1 stable orbits there, 0.15 m is irregular."""

import dataclasses
import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides
from jaxdamp.s3 import periodic, smooth

F = 15.16  # Hz, the preset's frequency


@functools.lru_cache(maxsize=None)
def _cfg():
    cfg = presets.get("sanchez2012-impact")
    assert cfg.frequency == F
    return cfg


@functools.lru_cache(maxsize=None)
def _orbit(gap):
    return periodic.orbit(_cfg(), gap=gap)


def _richardson(f, x, h):
    """Central difference with Richardson extrapolation (error O(h⁴))."""
    d1 = (f(x + 2 * h) - f(x - 2 * h)) / (4 * h)
    d2 = (f(x + h) - f(x - h)) / (2 * h)
    return (4 * d2 - d1) / 3


@pytest.mark.parametrize("gap", [0.04, 0.095])
def test_orbit_is_a_stable_fixed_point_with_consistent_floquet_multipliers(gap):
    orb = _orbit(gap)
    assert orb.converged and orb.stable and orb.k == 1, orb.reason
    assert orb.residual <= periodic.TOL
    x = jnp.asarray(orb.state)
    px = np.asarray(periodic.stroboscopic_map(x, orb.params, orb.n_steps))
    scale = np.asarray(periodic.state_scale(orb.params))
    assert np.max(np.abs(px - orb.state) / scale) <= periodic.TOL
    # the Newton start (3 s transient) is close to the orbit: it is the attractor reached
    assert orb.start_distance == pytest.approx(np.max(np.abs(orb.start - orb.state) / scale))
    assert orb.start_distance < 1e-3
    lam = orb.floquet
    assert np.max(np.abs(lam)) <= 1 - periodic.STABILITY_MARGIN
    # an independent monodromy matrix: jacfwd of the public map
    A = np.asarray(jax.jacfwd(lambda y: periodic.stroboscopic_map(y, orb.params,
                                                                   orb.n_steps))(x))
    # eigenvalues vs the invariants of the characteristic polynomial: trace, sum of the
    # principal 2x2 minors, determinant (≈ 0: the parasitic multipliers of the
    # predicted-velocity scheme and, with e = 0, the collapsed particle modes vanish)
    e1 = np.trace(A)
    e2 = 0.5 * (e1**2 - np.trace(A @ A))
    lam_e2 = sum(lam[i] * lam[j] for i in range(6) for j in range(i + 1, 6))
    np.testing.assert_allclose(np.sum(lam).real, e1, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(lam_e2.real, e2, rtol=1e-9, atol=1e-12)
    assert abs(np.sum(lam).imag) < 1e-12 and abs(lam_e2.imag) < 1e-12
    assert abs(np.prod(lam) - np.linalg.det(A)) < 1e-30
    assert np.sort(np.abs(lam))[:2].max() < 1e-6  # the two parasitic multipliers


@pytest.mark.parametrize("gap", [0.04, 0.095])
@pytest.mark.parametrize("kind", ["dissipation", "amplitude"])
def test_implicit_derivative_matches_finite_differences_of_resolved_orbits(gap, kind):
    """dJ/d gap by the implicit-function theorem vs a Richardson-extrapolated central
    difference of J(x*(gap ± h)), each orbit re-solved by Newton from the orbit at ``gap``.
    Measured agreement ~1e-8; required 1e-4."""
    orb = _orbit(gap)
    J, dJ, dx = periodic.implicit_derivative(orb, kind)
    assert np.all(np.isfinite(dx))

    def value(g):
        o = periodic.orbit(_cfg(), gap=g, start=orb)
        assert o.stable and o.k == 1 and o.residual <= periodic.TOL, o.reason
        return periodic.implicit_derivative(o, kind)[0]

    assert value(gap) == pytest.approx(J, rel=1e-12)
    fd = _richardson(value, gap, 1e-6)
    assert dJ == pytest.approx(fd, rel=1e-4)
    J2, dJ2, _ = periodic.objective_and_gradient(_cfg(), kind, gap=gap)
    assert (J2, dJ2) == pytest.approx((J, dJ), rel=1e-9)


@functools.partial(jax.jit, static_argnames=("n_rec", "record_every"))
def _long_loss(p, n_rec, record_every):
    return smooth.smooth_window_loss(p, n_rec, record_every)


def test_implicit_derivative_matches_finite_differences_of_long_time_averages():
    """The impact loss per period averaged over 30 s of the smooth model after a 5 s
    transient (:func:`jaxdamp.s3.smooth.smooth_window_loss`, same step dt = T/N) at gap ± h:
    its value is the orbit's, its central difference the implicit derivative (1e-4)."""
    gap, h = 0.0835, 1e-6
    orb = _orbit(gap)
    J, dJ, _ = periodic.implicit_derivative(orb, "dissipation")
    n = orb.n_steps
    burn, periods = 76, 455  # 5.0 s, 30.0 s
    p = dataclasses.replace(orb.params, t_window=(burn * n - 0.5) * orb.params.dt)
    gaps = jnp.asarray([gap, gap + h, gap - h])
    vals = jax.vmap(lambda g: _long_loss(dataclasses.replace(p, gap=g), burn + periods, n))(gaps)
    vals = np.asarray(vals)
    assert vals[0] == pytest.approx(J, rel=1e-9)
    fd = (vals[1] - vals[2]) / (2 * h)
    assert dJ == pytest.approx(fd, rel=1e-4)


def test_irregular_response_is_reported_not_a_number():
    """At 0.15 m the long-run response is irregular (the impact loss per period scatters by
    tens of %); the orbit search reports no stable periodic orbit, and the objective and its
    gradient are NaN."""
    gap = 0.15
    p, n = periodic.orbit_params(_cfg(), gap=gap)
    _, rec = smooth.smooth_run(p, 200, n)  # 13.2 s, one record per period
    per_period = np.diff(np.asarray(rec["work"])[:, 2])[66:]  # after 4.4 s
    assert np.std(per_period) / np.mean(per_period) > 0.1
    J, dJ, orb = periodic.objective_and_gradient(_cfg(), "dissipation", gap=gap, k_max=3)
    assert math.isnan(J) and math.isnan(dJ)
    assert not orb.stable
    assert orb.reason.startswith("not a stable periodic orbit")
    assert len(orb.attempts) == 3
    if orb.converged:  # an unstable orbit: a multiplier outside the unit circle
        assert orb.spectral_radius > 1 - periodic.STABILITY_MARGIN
    with pytest.raises(periodic.NoStableOrbit, match="not a stable periodic orbit"):
        orb.require()
    assert math.isnan(periodic.implicit_derivative(orb, "amplitude")[1])


def test_other_parameters_and_the_band_objective():
    """Any SmoothParams field: dJ/dC (primary damping) against a difference of re-solved
    orbits; the band objective (smooth maximum over frequencies) against its difference."""
    gap = 0.0835
    orb = _orbit(gap)
    _, dC, _ = periodic.implicit_derivative(orb, "amplitude", param="C")
    C0 = _cfg().primary.C

    def amp_c(c):
        cfg = apply_overrides(_cfg(), {"primary.C": c})
        o = periodic.orbit(cfg, gap=gap, start=orb)
        return periodic.implicit_derivative(o, "amplitude")[0]

    assert dC == pytest.approx(_richardson(amp_c, C0, 1e-4), rel=1e-4)
    # the drive frequency (omega; dt = 2π/(Ω N) follows, N fixed)
    _, dw, _ = periodic.implicit_derivative(orb, "dissipation", param="omega")

    def loss_f(f):
        o = periodic.orbit(_cfg(), gap=gap, frequency=f, start=orb, n_steps=orb.n_steps)
        return periodic.implicit_derivative(o, "dissipation")[0]

    assert 2 * math.pi * dw == pytest.approx(_richardson(loss_f, F, 1e-5), rel=1e-4)
    with pytest.raises(ValueError, match="dt"):
        periodic.implicit_derivative(orb, "amplitude", param="dt")
    freqs = (14.8, F, 15.5)
    J, dJ, orbs = periodic.objective_and_gradient(_cfg(), "band", frequency=freqs, gap=gap)
    assert len(orbs) == 3 and all(o.stable for o in orbs)

    def band(g):
        return periodic.objective_and_gradient(_cfg(), "band", frequency=freqs, gap=g,
                                               start=orbs)[0]

    assert dJ == pytest.approx(_richardson(band, gap, 1e-6), rel=1e-4)
    assert orbs.stable and orbs.reason == "" and orbs.sim_seconds > 0


@dataclasses.dataclass(frozen=True)
class _Damping:
    """A stand-in for jaxdamp.design.objectives.Objective: kind, frequencies, combine."""

    kind: str = "damping"

    def frequencies(self, config):
        return (config.frequency,)

    def combine(self, Z, E, frequencies):
        return E[0] / (math.pi * 2 * math.pi * jnp.asarray(frequencies)[0] * Z[0] ** 2)


def test_equivalent_damping_by_name_and_by_objective_object():
    """C_eq = E/(π Ω Z²) from the orbit averages, by name and through an objective's
    ``combine`` (jax.jvp of the per-frequency Z, E derivatives): the same value and
    derivative, and the chain rule of the amplitude and dissipation derivatives."""
    gap = 0.095
    orb = _orbit(gap)
    av = periodic.orbit_averages(orb)
    (Z, dZ), (E, dE), (C, dC) = av["amplitude"], av["dissipation"], av["damping"]
    w = 2 * math.pi * F
    assert C == pytest.approx(E / (math.pi * w * Z**2), rel=1e-12)
    assert dC == pytest.approx(C * (dE / E - 2 * dZ / Z), rel=1e-9)
    J, dJ, o = periodic.objective_and_gradient(_cfg(), _Damping(), gap=gap, start=orb)
    assert isinstance(o, periodic.Orbit) and o.stable
    assert (J, dJ) == pytest.approx((C, dC), rel=1e-9)
    assert periodic.objective_and_gradient(_cfg(), "damping", gap=gap, start=orb)[:2] == \
        pytest.approx((C, dC), rel=1e-9)


def test_subharmonic_orbit_is_found_and_differentiated():
    """At 10 Hz (gap 0.0835 m) the period-1 orbit is unstable (max |λ| ≈ 1.02) and the
    response is a stable period-2 orbit; its implicit derivative w.r.t. the primary's C
    matches the difference of re-solved period-2 orbits. (The particle does not reach the
    lid there, so the gap derivative is exactly 0.)"""
    gap, f = 0.0835, 10.0
    orb = periodic.orbit(_cfg(), gap=gap, frequency=f, k_max=2)
    assert orb.stable and orb.k == 2 and orb.residual <= periodic.TOL, orb.reason
    assert [a[0] for a in orb.attempts] == [1, 2]
    assert orb.attempts[0][1] and orb.attempts[0][3] > 1  # converged, unstable period 1
    assert periodic.implicit_derivative(orb, "dissipation")[1] == 0.0
    _, dC, _ = periodic.implicit_derivative(orb, "dissipation", param="C")

    def loss_c(c):
        cfg = apply_overrides(_cfg(), {"primary.C": c})
        o = periodic.orbit(cfg, gap=gap, frequency=f, start=orb)
        assert o.stable and o.k == 2
        return periodic.implicit_derivative(o, "dissipation")[0]

    assert dC == pytest.approx(_richardson(loss_c, _cfg().primary.C, 1e-4), rel=1e-4)


def test_gap_derivative_converges_with_the_step():
    """With 20 steps per contact (refine = 1) the gap derivative of the discrete model
    oscillates with the gap (period ~0.16 mm, ±25 % for the amplitude at 0.0835 m); at
    refine = 2 and 4 (40 and 80 steps per contact) it has converged (measured 6e-5 here, 1e-3
    at 0.095 m)."""
    d = [periodic.objective_and_gradient(_cfg(), "amplitude", gap=0.0835, refine=r)[1]
         for r in (2, 4)]
    assert d[0] == pytest.approx(d[1], rel=2e-3)
