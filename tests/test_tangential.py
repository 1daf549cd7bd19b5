"""The tangential spring with history (:mod:`jaxdamp.physics.tangential`): a sphere's oblique
impact on a flat wall against analytic and independent results, and the JAX form against the
scalar form."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jaxdamp.physics import tangential as tg
from jaxdamp.physics.contact import Vec, shear_compliance

M, R = 0.01, 0.005  # the sphere [kg], [m]; I = (2/5) M R²
INERTIA = 0.4 * M * R * R
NU = 0.3
KAPPA = 2.0 * (1.0 - NU) / (2.0 - NU)  # Mindlin's k_t over the normal tangent stiffness


def _impact(normal, kt_of, vn, vt, mu, gt=0.0, steps=20000, energy=None):
    """:func:`tangential.oblique_impact` of the test's sphere: ``(vn, vt, R ω, u)`` after the
    contact; its books into the dict ``energy``."""
    out = tg.oblique_impact(normal, kt_of, M, R, vn, vt, mu, gt, steps)
    if energy is not None:
        energy.update(out._asdict())
    return out.vn, out.vt, out.spin, out.u


def _balance(e):
    """The spring's books: the work the grains gave the contact is its losses plus the
    energy it holds less what the stiffness changes gave it (to round-off)."""
    assert -e["work"] == pytest.approx(e["damping"] + e["slip"] + e["spring"] - e["stiffness"],
                                       rel=1e-9, abs=1e-12 * e["max_spring"])


def _tangential_ke(vx, rw):
    return 0.5 * M * vx**2 + 0.5 * INERTIA * (rw / R) ** 2


def test_stick_limit_of_a_linear_contact_is_a_tangential_oscillation():
    """A linear normal contact (``k_n``) and a constant tangential spring ``k_t = κ k_n``, no
    slip (μ huge), no damping: the contact point's tangential velocity ``u`` obeys
    ``ü = −(7/2)(k_t/m) u`` while the contact lasts ``π/ω_n``, so after the impact
    ``u/u_0 = cos(π sqrt(7 k_t/(2 k_n)))`` (0.582 at ν = 0.3: the tangential oscillation runs
    0.85 of its period while the contact lasts) — an elastic exchange between sliding and
    spin that the viscous law cannot produce (it only slows ``u``). The normal velocity is
    restored (elastic), and the tangential impulse ``J`` moves ``v_t`` by ``J/m`` and ``R ω``
    by ``−(5/2) J/m`` (a solid sphere)."""
    kn = 1.0e5
    e = {}
    vz, vx, rw, u = _impact(lambda xi: kn * xi, lambda xi: KAPPA * kn, 1.0, 0.5, 1e9, energy=e)
    want = math.cos(math.pi * math.sqrt(3.5 * KAPPA))
    assert u / 0.5 == pytest.approx(want, abs=2e-3)
    assert vz == pytest.approx(1.0, rel=1e-3)
    assert rw == pytest.approx(-2.5 * (vx - 0.5), rel=1e-9)
    # the books: no damping, no slip loss (it sticks: the discrete spring is conservative),
    # and the spring's energy at separation gone as stiffness work
    _balance(e)
    assert e["damping"] == 0.0 and abs(e["slip"]) < 1e-12 * e["max_spring"]
    assert e["spring"] == 0.0 and e["stiffness"] < 0.0
    # ... the sphere's tangential energy changed by the force's work (the integrator's error)
    ke0 = _tangential_ke(0.5, 0.0)
    assert _tangential_ke(vx, rw) - ke0 == pytest.approx(e["work"], abs=2e-3 * ke0)


def _hertz(E_star):
    return lambda xi: (4.0 / 3.0) * E_star * math.sqrt(R) * xi ** 1.5


E_STAR = 1.0e8 / (2.0 * (1.0 - NU**2))  # two like bodies of E = 100 MPa (the wall as rigid: 1)
G_STAR = 1.0 / (2.0 * shear_compliance(1.0e8, NU))


def test_gross_sliding_impulse_is_mu_times_the_normal_one():
    """Hertz normal and Mindlin tangential contact, tangential speed far above what friction
    can stop (``v_t/v_n = 5``, μ = 0.1: the rigid-body slip criterion ``(7/2) μ (1 + e) v_n <
    v_t`` holds with room): the contact slides throughout, so the tangential impulse is μ times
    the normal one: ``v_t' = v_t − 2 μ v_n`` and ``R ω' = 5 μ v_n`` (elastic: ``e = 1``)."""
    e = {}
    vz, vx, rw, _ = _impact(_hertz(E_STAR), lambda xi: tg.stiffness_scalar(G_STAR, R, xi),
                            1.0, 5.0, 0.1, gt=1e-3, energy=e)
    assert vz == pytest.approx(1.0, rel=1e-3)
    assert vx == pytest.approx(5.0 - 2 * 0.1 * 1.0, rel=1e-4)
    assert rw == pytest.approx(5 * 0.1 * 1.0, rel=1e-3)
    # the books close; the sphere's lost tangential energy is the slip's loss (the spring
    # holds a force of μ F_n only: its energy and stiffness work are small, measured 2.2e-3
    # of the loss: the unloading contact's rescaled force, grown back by the sliding)
    _balance(e)
    lost = _tangential_ke(5.0, 0.0) - _tangential_ke(vx, rw)
    assert e["slip"] + e["damping"] == pytest.approx(lost, rel=5e-3)
    assert abs(e["stiffness"]) < 5e-3 * lost
    assert 0.0 < e["damping"] < 0.01 * e["slip"]


def test_stick_limit_of_hertz_mindlin_against_an_ode_solver():
    """Hertz normal and Mindlin tangential contact without slip or damping against scipy's
    adaptive Runge–Kutta on the continuous equations of the incremental spring,
    ``ξ'' = −F_n(ξ)/m``, ``F_s' = −k_t(ξ) u + F_s ξ'/(2 ξ)`` (the second term while the
    contact unloads, ``ξ' < 0``: the force scaled with ``k_t ∝ sqrt(ξ)``), ``u' = (7/2) F_s/m``:
    the contact point's tangential velocity after the impact agrees to 1e-3 m/s (2e-3 of its
    initial value)."""
    fn = _hertz(E_STAR)

    def rhs(t, y):
        xi, xid, f, u = y
        x = max(xi, 1e-300)
        df = -8.0 * G_STAR * math.sqrt(R * x) * u + (0.5 * f * xid / x if xid < 0 else 0.0)
        return [xid, -fn(x) / M, df, 3.5 * f / M]

    def left(t, y):  # just before the end: F_s ∝ sqrt(ξ) there, its rate singular at 0
        return y[0] - 1e-13
    left.terminal, left.direction = True, -1
    sol = solve_ivp(rhs, (0, 1.0), [1e-12, 1.0, 0.0, 0.5], rtol=1e-10, atol=1e-14,
                    events=left)
    u_ref = sol.y_events[0][0][3]
    _, _, _, u = _impact(fn, lambda xi: tg.stiffness_scalar(G_STAR, R, xi), 1.0, 0.5, 1e9)
    assert u == pytest.approx(u_ref, abs=1e-3)
    assert abs(u_ref - 0.5) > 0.01  # the spring changed the sliding velocity (0.477 m/s)


def test_history_turns_into_the_new_contact_plane_keeping_its_length():
    """A stored spring force in the plane of an old normal, the normal turned by 10°: the
    history used is in the new plane (normal part zero) and as long as before, its energy
    ``|F|²/(2 k_t)``."""
    s = Vec(*(jnp.asarray(x) for x in (1e-6, 2e-6, 0.0)))
    a = math.radians(10.0)
    n = Vec(*(jnp.asarray(x) for x in (math.sin(a), 0.0, math.cos(a))))
    zero = Vec(*(jnp.zeros(()) for _ in range(3)))
    sp = tg.spring_jax(s, n, zero, 1e-6, 1e3, 0.0, 1.0, 1e9, jnp.asarray(True))
    h = sp.history
    assert abs(float(h.dot(n))) < 1e-21
    assert float(jnp.sqrt(h.dot(h))) == pytest.approx(math.sqrt(5e-12), rel=1e-12)
    assert float(sp.energy) == pytest.approx(0.5 * 5e-12 / 1e3, rel=1e-12)


def _random_contacts(n, seed=0):
    rng = np.random.default_rng(seed)
    nrm = rng.normal(size=(n, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    s = rng.normal(scale=1e-6, size=(n, 3))
    s -= nrm * np.sum(s * nrm, 1, keepdims=True)  # last step's plane ...
    s += rng.normal(scale=2e-7, size=(n, 3))  # ... off this step's by a little
    v = rng.normal(scale=0.1, size=(n, 3))
    v -= nrm * np.sum(v * nrm, 1, keepdims=True)
    kt = rng.uniform(1e3, 1e5, n)
    gt = rng.uniform(0.0, 0.2, n)
    fn = rng.uniform(0.0, 0.3, n)
    mu = rng.uniform(0.1, 0.6, n)
    s[:5] = 0.0  # new contacts
    return nrm, s * kt[:, None], v, kt, gt, fn, mu  # the springs' forces [N]


def test_jax_form_equals_scalar_form():
    """200 contacts, sticking and sliding, new and old, some with a history off the present
    plane, the spring growing with a velocity ``u`` near the dashpot's ``v`` (the engines'
    half-step velocity): both forms give the same force, history, energy and slip flag to
    round-off; where not touching the JAX form gives zeros."""
    nrm, s, v, kt, gt, fn, mu = _random_contacts(200)
    u = v + np.random.default_rng(1).normal(scale=0.01, size=v.shape)
    u -= nrm * np.sum(u * nrm, 1, keepdims=True)
    dt = 1e-6
    rescale = np.where(np.arange(200) % 3 == 0, 0.97, 1.0)  # every third contact unloading
    touching = np.ones(200, bool)
    touching[-3:] = False
    sp = tg.spring_jax(Vec.of(jnp.asarray(s)), Vec.of(jnp.asarray(nrm)), Vec.of(jnp.asarray(v)),
                       dt, jnp.asarray(kt), jnp.asarray(gt), jnp.asarray(fn), jnp.asarray(mu),
                       jnp.asarray(touching), Vec.of(jnp.asarray(u)), jnp.asarray(rescale))
    jf, jh = np.asarray(sp.force.stack()), np.asarray(sp.history.stack())
    sliding = np.asarray(sp.sliding)
    assert 20 < sliding.sum() < 180  # both regimes
    for i in range(197):
        out = tg.spring_scalar(*s[i], *nrm[i], *v[i], *u[i], dt, kt[i], gt[i], fn[i], mu[i],
                               rescale[i] ** 2, 1.0)
        np.testing.assert_allclose(jf[i], out[:3], rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(jh[i], out[3:6], rtol=1e-12, atol=1e-22)
        for k, name in enumerate(("energy", "turned", "damping", "slip")):
            # (the slip's loss is a difference: in stick it is round-off of the energy / dt)
            tol = 1e-12 * abs(out[6]) if name != "slip" else 1e-10 * max(out[6], out[7]) / dt
            assert float(getattr(sp, name)[i]) == pytest.approx(out[6 + k], rel=1e-9,
                                                                abs=tol), name
        assert bool(sliding[i]) == out[10]
        assert np.linalg.norm(jf[i]) <= mu[i] * fn[i] * (1 + 1e-12) or not out[10]
        # the step's books: the spring's trapezoid work −(F_s + F_s')·u dt/2 (F_s the old
        # force turned, F_a = rescale F_s) is its energy change from where the step starts it
        # (``turned``) and the slip's loss
        ft = s[i] - nrm[i] * np.dot(s[i], nrm[i])
        if np.dot(ft, ft) > 0:
            ft = ft * (np.linalg.norm(s[i]) / np.linalg.norm(ft))
        fa = ft * rescale[i]
        work = -0.5 * np.dot(ft + np.asarray(out[3:6]), u[i]) * dt
        scale = max(out[6], out[7], 1e-30)
        assert work == pytest.approx(out[9] * dt + out[6] - out[7], rel=1e-8, abs=1e-10 * scale)
        off = 0.5 * np.dot(ft - fa, u[i]) * dt
        assert out[7] == pytest.approx(0.5 * np.dot(fa, fa) / kt[i] + off, rel=1e-9,
                                       abs=1e-12 * scale)
        if out[10]:  # slipped: a loss ≥ 0, the spring cut with the force, along itself
            assert out[9] >= 0.0, "slip < 0"
            g = fa - kt[i] * u[i] * dt
            assert np.linalg.norm(np.cross(out[3:6], g)) <= 1e-9 * np.dot(g, g)
        else:  # stuck: no loss (the discrete spring is conservative)
            assert abs(out[9]) * dt <= 1e-9 * scale
    for x in (jf, jh, sp.energy, sp.damping, sp.slip):
        assert not np.asarray(x)[-3:].any()
    for i in range(197, 200):  # contacts that ended: the old force's work over the step
        ft = s[i] - nrm[i] * np.dot(s[i], nrm[i])
        if np.dot(ft, ft) > 0:
            ft = ft * (np.linalg.norm(s[i]) / np.linalg.norm(ft))
        assert float(sp.turned[i]) == pytest.approx(0.5 * dt * np.dot(ft, u[i]), rel=1e-9)


def test_gradients_are_finite_at_a_new_contact():
    """``jax.grad`` of the force through a contact with no history yet (zero lengths) and
    through a sliding one: finite."""
    def fx(vx, s0):
        z = jnp.zeros(())
        sp = tg.spring_jax(Vec(s0, z, z), Vec(z, z, z + 1.0), Vec(vx, z, z), 1e-6, 1e4, 0.1,
                           1.0, 0.3, jnp.asarray(True))
        return sp.force.x + sp.energy
    for vx, s0 in ((0.0, 0.0), (1.0, 0.0), (0.0, 1e-3)):
        g = jax.grad(fx, argnums=(0, 1))(jnp.asarray(vx), jnp.asarray(s0))
        assert all(np.isfinite(float(x)) for x in g)


def test_stiffness_forms_agree():
    """Mindlin's ``k_t = 8 G* sqrt(R* ξ)``: the JAX form equals the scalar form, and both are
    zero where ``ξ ≤ 0``."""
    xi = np.array([-1e-6, 0.0, 1e-9, 1e-6, 3e-5])
    want = [tg.stiffness_scalar(G_STAR, R, float(x)) for x in xi]
    np.testing.assert_allclose(np.asarray(tg.stiffness(G_STAR, R, jnp.asarray(xi))), want,
                               rtol=1e-14)
    assert want[0] == want[1] == 0.0
    assert want[3] == pytest.approx(8 * G_STAR * math.sqrt(R * 1e-6), rel=1e-14)
