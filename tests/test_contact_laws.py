"""One definition of the physics for both engines: the JAX forms and the numba scalar forms of
every registered contact law, of the excitation and of the integrator's pieces agree to
round-off on random inputs covering every branch; the contact tables are built once."""

import dataclasses
import math

import jax.numpy as jnp
import numpy as np
import pytest
from helpers import ENGINES, config, run_steps, start

from jaxdamp.config import (
    Box,
    Config,
    ConfigError,
    Drive,
    Material,
    Primary,
    Species,
    apply_overrides,
)
from jaxdamp.physics import contact, excitation, integrate, mounts
from jaxdamp.physics import restitution as rst
from jaxdamp.physics.contact import LAWS, Vec
from jaxdamp.physics.model import build, contact_tables
from jaxdamp.validation import validate

pytest.importorskip("numba")

RTOL = 1e-12
LAW_NAMES = tuple(LAWS)


def _close(a, b, scale, what):
    """``a == b`` to ``RTOL`` relative to each value, or to ``RTOL * scale`` absolutely (values
    formed by a cancellation, e.g. the normal loss of a nearly elastic contact)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    np.testing.assert_allclose(a, b, rtol=RTOL, atol=RTOL * scale, err_msg=what)


def _random_rows(law, rng, n):
    """Random but physical table rows of ``law`` (``γ_s``, ``μ`` first)."""
    rows = np.empty((n, len(law.columns)))
    for c, name in enumerate(law.columns):
        lo, hi = {"gamma_s": (0.0, 300.0), "mu": (0.0, 0.8), "E_star": (1e8, 1e11),
                  "gamma_n": (0.0, 100.0), "A": (0.0, 1e-5), "k": (1e3, 1e7),
                  "zeta": (0.0, 0.9), "G_star": (1e8, 1e11)}[name]
        rows[:, c] = rng.uniform(lo, hi, n)
    return rows


def _contacts(rng, n):
    """``n`` touching contacts in four groups: generic; zero slip (axis-aligned normal, normal
    velocity and spin only); fast separation (normal force clipped to zero); strong tangential
    damping with little friction (Coulomb cap) — and their opposite by the rows' spread."""
    xi = rng.uniform(1e-7, 1e-4, n)
    nrm = rng.normal(size=(n, 3))
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    v = rng.normal(0, 1.0, (n, 3))
    spin = rng.normal(0, 0.3, (n, 3))
    q = n // 4
    nrm[q:2 * q] = [0.0, 0.0, 1.0]  # zero slip: v ∥ n and spin ∥ n give v_s = 0 exactly
    v[q:2 * q, :2] = 0.0
    spin[q:2 * q, :2] = 0.0
    v[2 * q:3 * q] = 50.0 * nrm[2 * q:3 * q]  # separating fast: F_n clipped to 0
    return xi, nrm, v, spin


@pytest.mark.parametrize("name", LAW_NAMES)
def test_pair_constants_jax_equal_scalar(name):
    law = LAWS[name]
    rng = np.random.default_rng(1)
    rows = _random_rows(law, rng, 200)
    r_eff, m_eff = rng.uniform(1e-4, 1e-2, 200), rng.uniform(1e-6, 1e-1, 200)
    k_j, g_j = law.pair_jax(jnp.asarray(rows), jnp.asarray(r_eff), jnp.asarray(m_eff))
    got = np.array([law.pair_scalar(rows[i], r_eff[i], m_eff[i]) for i in range(200)])
    via = np.array([contact.pair_scalar(law.id, rows[i], r_eff[i], m_eff[i]) for i in range(200)])
    _close(got[:, 0], k_j, 0.0, "k")
    _close(got[:, 1], g_j, 0.0, "g")
    np.testing.assert_array_equal(via, got)  # the kernel's dispatch picks this law


@pytest.mark.parametrize("name", LAW_NAMES)
def test_contact_jax_equals_scalar_on_every_branch(name):
    law = LAWS[name]
    rng = np.random.default_rng(7)
    n = 400
    xi, nrm, v, spin = _contacts(rng, n)
    rows = _random_rows(law, rng, n)
    rows[3 * (n // 4):, contact.GAMMA_S] *= 100.0  # strong viscous friction: capped by μ F_n
    r_eff, m_eff = rng.uniform(1e-3, 3e-3, n), rng.uniform(1e-4, 1e-3, n)
    k, g = (np.asarray(x) for x in law.pair_jax(jnp.asarray(rows), r_eff, m_eff))
    R_i = rng.uniform(1e-3, 3e-3, n)
    c = contact.contact_force(law, jnp.asarray(xi), Vec.of(jnp.asarray(nrm)), Vec.of(jnp.asarray(v)),
                              Vec.of(jnp.asarray(spin)), jnp.asarray(R_i), jnp.asarray(k),
                              jnp.asarray(g), jnp.asarray(rows[:, contact.GAMMA_S]),
                              jnp.asarray(rows[:, contact.MU]))
    s = np.array([contact.contact_scalar(law.id, xi[i], *nrm[i], *v[i], *spin[i], k[i], g[i],
                                         rows[i, contact.GAMMA_S], rows[i, contact.MU])
                  for i in range(n)])
    f_scale = float(np.abs(s[:, :3]).max())
    _close(s[:, :3], c.force.stack(), f_scale, "force")
    torque = -R_i[:, None] * np.cross(nrm, s[:, 3:6])
    _close(torque, c.torque.stack(), f_scale * R_i.max(), "torque")
    p_scale = f_scale * float(np.abs(v).max())
    _close(s[:, 6], c.elastic_energy, f_scale * xi.max(), "elastic energy")
    _close(s[:, 7], c.normal_loss, p_scale, "normal loss")
    _close(s[:, 8], c.friction_loss, p_scale, "friction loss")

    # every branch was taken
    fn = np.asarray(c.normal)
    assert (fn == 0).sum() >= n // 8 and (fn > 0).sum() >= n // 2, "clipped and pressing"
    ft = np.linalg.norm(s[:, 3:6], axis=1)
    vc = v - np.cross(spin, nrm)  # contact-point velocity, recomputed independently
    slide = vc - nrm * np.sum(vc * nrm, axis=1, keepdims=True)
    vs = np.linalg.norm(slide, axis=1)
    capped = (fn > 0) & np.isclose(ft, rows[:, contact.MU] * fn, rtol=1e-9) & (vs > 0)
    viscous = (fn > 0) & (ft < rows[:, contact.MU] * fn * (1 - 1e-9))
    zero_slip = vs == 0
    assert capped.sum() >= 20 and viscous.sum() >= 20 and zero_slip.sum() >= n // 8
    assert np.all(ft[zero_slip] == 0)


def test_contact_jax_is_zero_without_overlap():
    """Separated contacts (ξ ≤ 0) carry no force, energy or loss in the JAX form (the scalar
    form is only called for touching contacts)."""
    rng = np.random.default_rng(3)
    for law in LAWS.values():
        xi = -rng.uniform(0, 1e-4, 50)
        _, nrm, v, spin = _contacts(rng, 50)
        row = _random_rows(law, rng, 1)[0]
        k, g = law.pair_jax(jnp.asarray(row), 1e-3, 1e-4)
        c = contact.contact_force(law, jnp.asarray(xi), Vec.of(jnp.asarray(nrm)),
                                  Vec.of(jnp.asarray(v)), Vec.of(jnp.asarray(spin)), 1e-3, k, g,
                                  row[contact.GAMMA_S], row[contact.MU])
        for a in (c.force.stack(), c.torque.stack(), c.elastic_energy, c.normal_loss,
                  c.friction_loss):
            assert np.all(np.asarray(a) == 0)


def test_rotation_jax_equals_scalar_small_and_large_angles():
    """The kernel's rotation (series below half-angle 0.01, sin/cos above) against the JAX
    form's exact axis-angle rotation, both regimes."""
    rng = np.random.default_rng(5)
    n = 200
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w = rng.normal(size=(n, 3))
    w /= np.linalg.norm(w, axis=1, keepdims=True)
    dt = 1e-5
    half = np.concatenate([rng.uniform(1e-9, 9e-3, n // 2), rng.uniform(0.011, 1.5, n // 2)])
    w *= (2 * half / dt)[:, None]
    w[0] = 0.0  # no rotation at all
    assert (half < 0.01).sum() >= n // 2 - 1 and (half > 0.01).sum() == n // 2
    ref = np.asarray(integrate.rotate(jnp.asarray(q), jnp.asarray(w), dt))
    got = np.array([integrate.rotate_scalar(*q[i], *w[i], dt) for i in range(n)])
    np.testing.assert_allclose(got, ref, rtol=0, atol=1e-14)
    np.testing.assert_allclose(got[0], q[0], rtol=0, atol=1e-15)
    # quaternions off the unit sphere (|q|² - 1 beyond 1e-8): the kernel's renormalisation
    # leaves its series for the exact 1/sqrt and still lands on the JAX form's unit result
    for scale in (1.3, 1.0 + 1e-6, 1.0 - 1e-6):
        ref = np.asarray(integrate.rotate(jnp.asarray(scale * q), jnp.asarray(w), dt))
        got = np.array([integrate.rotate_scalar(*(scale * q[i]), *w[i], dt) for i in range(n)])
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-14)

    # the branch-free series form the kernel runs over all grains: equal to the JAX form where
    # it says its series hold, and it says so exactly where rotate_scalar takes both series
    for scale in (1.0, 1.3, 1.0 + 1e-6):
        qs = scale * q
        out = [integrate.rotate_series_scalar(*qs[i], *w[i], dt) for i in range(n)]
        ok = np.array([o[4] for o in out])
        h2 = 0.25 * dt * dt * (w * w).sum(axis=1)
        if scale == 1.0:
            np.testing.assert_array_equal(ok, h2 < integrate.ROTATE_H2)
            assert ok.sum() >= n // 2 - 1
        else:
            assert not ok.any()  # off the sphere: the exact renormalisation is needed
        ref = np.asarray(integrate.rotate(jnp.asarray(qs), jnp.asarray(w), dt))
        got = np.array([o[:4] for o in out])
        np.testing.assert_allclose(got[ok], ref[ok], rtol=0, atol=1e-14)


def test_body_force_primary_and_excitation_jax_equal_scalar():
    """Gravity with the settling drag, the primary's acceleration and powers, the base and the
    box motion: the kernel's scalar forms against the JAX forms."""
    rng = np.random.default_rng(9)
    m, drag, grav = rng.uniform(1e-4, 1e-2, 50), rng.uniform(0, 30, 50), 9.8
    vel = rng.normal(0, 1, (50, 3))
    ref = np.stack([np.asarray(x) for x in integrate.body_force(
        jnp.asarray(m), *(jnp.asarray(vel[:, k]) for k in range(3)), grav, jnp.asarray(drag))], 1)
    got = np.array([integrate.body_force_scalar(m[i], *vel[i], grav, drag[i]) for i in range(50)])
    _close(got, ref, 0.0, "body force")
    assert np.all(drag > 0) and np.all(ref[:, 2] != -m * grav)  # the drag acts

    M, K, C = 2.37, 21500.0, 7.6
    for _ in range(20):
        z, zd, u, ud, fz = rng.normal(0, 1e-3, 5)
        a_ref = mounts.primary_acceleration(jnp.asarray(z), zd, u, ud, fz, M, K, C)
        _close(mounts.primary_acceleration_scalar(z, zd, u, ud, fz, M, K, C), a_ref, 1.0, "z''")
        p_ref = mounts.primary_powers(jnp.asarray(z), zd, u, ud, K, C)
        _close(mounts.primary_powers_scalar(z, zd, u, ud, K, C), p_ref, 1e-6, "powers")

    cfg = Config(system="driven", frequency=14.5, grains=(), box=Box(0.1, 0.1, 0.1),
                 drive=Drive(0.02))
    p = dataclasses.replace(build(cfg)[1], U=jnp.asarray(0.0045), z_offset=jnp.asarray(0.013))
    # the base with random lines and a shock pulse (S1)
    s1 = apply_overrides(Config(system="primary", frequency=14.5, grains=(),
                                box=Box(0.1, 0.1, 0.1), primary=Primary(2.37, 21500.0, 7.6,
                                                                         0.0045)),
                         {"random.psd": [[5.0, 1.0], [30.0, 2.0]], "random.resolution": 0.5,
                          "shock.peak": 30.0, "shock.duration": 0.01, "shock.start": 1.0})
    q = build(s1)[1]
    lines = np.asarray(q.lines)
    assert lines.shape == (51, 3)
    for t in np.r_[rng.uniform(0, 10, 20), 1.0, 1.004, 1.01, 1.5]:
        _close(excitation.base_motion_scalar(t, float(q.U), float(q.omega), lines,
                                             float(q.shock_a), float(q.shock_t0),
                                             float(q.shock_T)),
               excitation.base_motion(jnp.asarray(t), q), 1.0, "base motion")
        _close(excitation.drive_motion_scalar(t, float(p.z_offset), float(p.amplitude),
                                              float(p.omega)),
               excitation.drive_motion(jnp.asarray(t), p), 100.0, "drive motion")


def test_structure_jax_equals_scalar():
    """The multi-DOF structure's acceleration, energy and powers: the kernel's scalar forms
    against the JAX forms, on a random symmetric 3-DOF structure with a force."""
    from jaxdamp.physics import structure

    rng = np.random.default_rng(3)
    A = rng.normal(size=(3, 3))
    M = A @ A.T + 3 * np.eye(3)
    B = rng.normal(size=(3, 3))
    K = 1e4 * (B @ B.T + np.eye(3))
    C = 1e-3 * K
    p = structure_params(M, K, C, r=rng.normal(size=3), b=rng.normal(size=3))
    for _ in range(10):
        x, xd = rng.normal(0, 1e-3, 3), rng.normal(0, 1e-2, 3)
        u, ud, c = rng.normal(0, 1e-3), rng.normal(0, 1e-2), rng.uniform(-1, 1)
        fz = rng.normal(size=3)  # the grains' forces on the three degrees of freedom
        out, tmp = np.empty(3), np.empty(3)
        structure.acceleration_scalar(out, x, xd, u, ud, fz, c, np.linalg.inv(M), K, C,
                                      p.s_r, p.s_b, tmp)
        _close(out, structure.acceleration(jnp.asarray(x), jnp.asarray(xd), u, ud, fz, c, p),
               1.0, "x''")
        _close(structure.energy_scalar(x, xd, u, M, K, p.s_r),
               structure.energy(jnp.asarray(x), jnp.asarray(xd), u, p), 1e-3, "energy")
        _close(structure.powers_scalar(x, xd, u, ud, c, K, C, p.s_r, p.s_b),
               structure.powers(jnp.asarray(x), jnp.asarray(xd), u, ud, c, p), 1e-2, "powers")


def structure_params(M, K, C, r, b):
    """The structure's ``Params`` fields as a namespace (what the JAX forms read)."""
    import types

    return types.SimpleNamespace(s_M=jnp.asarray(M), s_Minv=jnp.asarray(np.linalg.inv(M)),
                                 s_K=jnp.asarray(K), s_C=jnp.asarray(C), s_r=np.asarray(r),
                                 s_b=np.asarray(b))


STEEL = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=40.0, gamma_s=120.0)
GLASS = Material(E=5e9, nu=0.22, density=2500.0, mu=0.5, gamma_s=50.0, restitution=0.8)


def _two_species(law="hertz", mixing="harmonic", **extra):
    return Config(
        system="driven", frequency=30.0, drive=Drive(0.003), mixing=mixing, contact_law=law,
        grains=(Species(count=3, radius=2e-3, material=dataclasses.replace(STEEL, **extra)),
                Species(count=4, radius=1e-3, material=dataclasses.replace(GLASS, **extra))),
        box=Box(0.02, 0.02, 0.02, wall=dataclasses.replace(STEEL, mu=0.1, **extra)),
    )


@pytest.mark.parametrize("name", LAW_NAMES)
def test_tables_hold_the_mixed_constants_once(name):
    """``pair_table[s, t]`` is the law's mix of the two species' materials (symmetric),
    ``wall_table[s]`` the mix with the wall's; the grains are stored species after species."""
    law = LAWS[name]
    cfg = _two_species(name, **({"linear_stiffness": 1e4} if name == "linear" else {}))
    model, p = build(cfg)
    pair, wall = (np.asarray(x) for x in (p.pair_table, p.wall_table))
    assert pair.shape == (2, 2, len(law.columns)) and wall.shape == (2, len(law.columns))
    np.testing.assert_array_equal(pair, pair.transpose(1, 0, 2))
    lam = cfg.numerics.stiffness_scale
    mats = [law.material(sp.material, sp.radius, lam) for sp in cfg.grains]
    w = law.material(cfg.box.wall, cfg.grains[0].radius, lam)
    for s in range(2):
        np.testing.assert_array_equal(wall[s], law.mix(mats[s], w, "harmonic"))
        for t in range(2):
            np.testing.assert_array_equal(pair[s, t], law.mix(mats[s], mats[t], "harmonic"))
    mu = law.column("mu")
    assert pair[0, 1, mu] == pytest.approx(2 * 0.3 * 0.5 / 0.8)  # harmonic mean
    np.testing.assert_array_equal(model.species_index(), [0, 0, 0, 1, 1, 1, 1])
    np.testing.assert_array_equal(contact_tables(cfg)[0], pair)


def test_contact_law_is_validated_by_name():
    cfg = _two_species()
    assert validate(cfg) is cfg
    with pytest.raises(ConfigError, match=r"contact_law = 'hooke'.*" + ".*".join(LAW_NAMES)):
        validate(cfg.replace(contact_law="hooke"))


def test_mix_rules():
    assert contact.mix(1.0, 3.0, "arithmetic") == 2.0
    assert contact.mix(1.0, 4.0, "geometric") == 2.0
    assert contact.mix(1.0, 3.0, "harmonic") == 1.5
    assert contact.mix(0.0, 0.0, "harmonic") == 0.0
    with pytest.raises(ValueError, match="mixing rule"):
        contact.mix(1.0, 1.0, "median")
    assert math.isfinite(contact.mix(0.0, 2.0, "geometric"))


# ---------------------------------------------------------------------------------------------
# the linear spring–dashpot law

LINEAR = Material(E=2e9, nu=0.3, density=7850.0, restitution=0.75, linear_stiffness=1e5)
R_LIN = 2.5e-3
#: Tolerance of the DEM measurements against the closed forms: time discretisation at
#: dt = t_f/200 (velocity Verlet with predicted velocities; measured: ε 4e-4 high, overlap and
#: force durations within 1e-5 relative, with the contact's ends interpolated).
TOL = 1e-3


def test_linear_closed_forms_against_an_ode_solver():
    """The clipped law's restitution and durations (Schwager & Pöschel 2007) against scipy's
    integration of ``m ξ'' = -max(0, k ξ + γ ξ')``, under-, critically and overdamped; and
    ``ζ(e)`` inverts ``e(ζ)``."""
    from scipy.integrate import solve_ivp

    k, m, v = 1e5, 2.6e-4, 0.7
    for zeta in (0.0, 0.05, 0.3, 0.9, 1.0, 1.7):
        g = 2 * zeta * math.sqrt(k * m)

        def rhs(_, y):
            return [y[1], -max(0.0, k * y[0] + g * y[1]) / m if y[0] > 0 else 0.0]

        def force_end(_, y):
            return k * y[0] + g * y[1]

        def overlap_end(_, y):
            return y[0]

        force_end.terminal, force_end.direction = False, -1
        overlap_end.terminal, overlap_end.direction = True, -1
        sol = solve_ivp(rhs, (0, 1e-2), [1e-300, v], method="DOP853", rtol=1e-12, atol=1e-18,
                        events=(force_end, overlap_end), max_step=1e-6)
        t_f = sol.t_events[0][0] if zeta > 0 else sol.t_events[1][0]
        t_o, e = sol.t_events[1][0], -sol.y_events[1][0][1] / v
        ref = rst.linear_collision(k, m, zeta)
        assert ref.restitution == pytest.approx(e, rel=1e-8)
        assert ref.force_duration == pytest.approx(t_f, rel=1e-6)
        assert ref.duration == pytest.approx(t_o, rel=1e-6)
        if zeta > 0:
            assert rst.linear_damping_ratio(e) == pytest.approx(zeta, rel=1e-6)
    assert rst.linear_collision(k, m, 0.0).duration == pytest.approx(math.pi * math.sqrt(m / k))
    for e in (1.0, 0.9, 0.5, 0.1, 0.01):
        assert rst.linear_restitution(rst.linear_damping_ratio(e)) == pytest.approx(e, rel=1e-13)


def _linear_collision(v, engine, wall, e):
    """A head-on pair (or grain–floor) collision of the linear law at speed ``v``, gravity 0.
    Returns (ε, overlap duration, force duration or None, the closed-form collision)."""
    mat = dataclasses.replace(LINEAR, restitution=e)
    cfg = config(n=1 if wall else 2, radius=R_LIN, material=mat, contact_law="linear",
                 dt_per_collision=200)
    model, params = build(cfg)
    law, dt = LAWS["linear"], float(params.dt)
    row = np.asarray(params.wall_table[0] if wall else params.pair_table[0, 0])
    m = float(params.mass[0])
    ref = rst.linear_collision(row[law.column("k")], m if wall else m / 2, row[law.column("zeta")])
    gap = 20.3 * dt * v  # 20 steps of free flight
    c = 0.025
    if wall:
        r, vel = [[c, c, R_LIN + gap]], [[0, 0, -v]]
    else:
        r, vel = [[c - R_LIN - gap / 2, c, c], [c + R_LIN + gap / 2, c, c]], [[v / 2, 0, 0], [-v / 2, 0, 0]]
    model, pb, st, nbrs = start(cfg, r, vel)
    st, nbrs, rec = run_steps(model, pb, st, nbrs, 30 + int(1.2 * ref.duration / dt), 1,
                              engine=engine)
    vout = np.asarray(st.v[0])
    eps = vout[0, 2] / v if wall else (vout[1, 0] - vout[0, 0]) / v
    # overlap from the elastic energy k ξ²/2; ends of the contact by linear extrapolation of
    # ξ(t) (ξ' = v on the way in, -ε v on the way out)
    t = rec["t"]
    xi = np.sqrt(2 * rec["e_elastic"] / row[law.column("k")])
    on = np.flatnonzero(xi > 0)
    a, b = on[0], on[-1]
    assert on.size == b - a + 1 and b < len(t) - 3  # one contact, ended within the run
    t0 = t[a] - xi[a] / v
    duration = t[b] + xi[b] / (eps * v) - t0
    force = None
    if wall:  # the force on the box is the contact force: it ends where k ξ + γ ξ' = 0
        f = -rec["force_box"]
        pos = np.flatnonzero(f > 0)
        j = pos[-1]
        force = t[j] + f[j] * (t[j] - t[j - 1]) / (f[j - 1] - f[j]) - t0
    return eps, duration, force, ref


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("wall", [False, True], ids=["pair", "wall"])
def test_linear_restitution_is_the_material_input_at_every_speed(engine, wall):
    """The measured ε equals the material's restitution (0.75) at 0.1, 1 and 5 m/s, and the
    overlap (and, at the wall, the force) lasts the closed-form time, within ``TOL``: pair and
    wall, both engines. It is *not* ``exp(-πζ/sqrt(1-ζ²))`` at the same ζ (that is the law with
    an attractive tail)."""
    for v in (0.1, 1.0, 5.0):
        eps, duration, force, ref = _linear_collision(v, engine, wall, 0.75)
        print(f"v = {v}: ε = {eps:.6f}, overlap {duration:.6e} s (closed form {ref.duration:.6e}),"
              f" force {force} s (closed form {ref.force_duration:.6e})")
        assert eps == pytest.approx(0.75, abs=TOL)
        assert eps == pytest.approx(ref.restitution, abs=TOL)
        assert duration == pytest.approx(ref.duration, rel=TOL)
        if force is not None:
            assert force == pytest.approx(ref.force_duration, rel=TOL)
    zeta = rst.linear_damping_ratio(0.75)
    assert abs(eps - math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2))) > 10 * TOL


@pytest.mark.parametrize("engine", ENGINES)
def test_linear_elastic_collision_lasts_half_a_period(engine):
    """e = 1: ζ = 0, ε = 1 and the collision lasts t_c = π/ω_d = π sqrt(m*/k) (pair)."""
    eps, duration, _, ref = _linear_collision(1.0, engine, False, 1.0)
    m = 7850 * 4 / 3 * math.pi * R_LIN**3
    assert ref.duration == pytest.approx(math.pi * math.sqrt(m / 2 / 1e5), rel=1e-14)
    assert eps == pytest.approx(1.0, abs=TOL)
    assert duration == pytest.approx(ref.duration, rel=TOL)


def test_linear_time_step_uses_the_linear_collision_time():
    """dt = t_c / dt_per_collision with the linear law's force duration of the lightest like
    pair or grain–wall contact (independent of v_impact), and the check names it."""
    from jaxdamp.physics.model import collision_time_limit, grain_radii

    mat = dataclasses.replace(LINEAR, restitution=0.5)
    cfg = config(n=20, radius=R_LIN, material=mat, contact_law="linear", v_impact=3.0)
    cfg = cfg.replace(box=dataclasses.replace(cfg.box, wall=dataclasses.replace(mat, linear_stiffness=4e5)))
    m = 7850 * 4 / 3 * math.pi * R_LIN**3
    zeta = rst.linear_damping_ratio(0.5)
    expected = min(rst.linear_collision(1e5, m / 2, zeta).force_duration,
                   rst.linear_collision(2.5e5, m, zeta).force_duration)  # wall: k mixed 1e5, 4e5
    t_c = collision_time_limit(cfg, grain_radii(cfg))
    assert t_c == pytest.approx(expected, rel=1e-12)
    assert float(build(cfg)[1].dt) == pytest.approx(t_c / 50, rel=1e-12)
    assert collision_time_limit(cfg.replace(numerics=dataclasses.replace(cfg.numerics, v_impact=0.1)),
                                grain_radii(cfg)) == t_c
    with pytest.raises(ConfigError, match="linear collision time"):
        validate(cfg.replace(numerics=dataclasses.replace(cfg.numerics, dt=t_c / 40)))


def test_linear_material_inputs_are_validated():
    cfg = config(n=2, radius=R_LIN, material=LINEAR, contact_law="linear")
    assert validate(cfg) is cfg
    no_k = config(n=2, radius=R_LIN, material=dataclasses.replace(LINEAR, linear_stiffness=None),
                  contact_law="linear")
    with pytest.raises(ConfigError, match=r"grains\.0\.material\.linear_stiffness = None"):
        validate(no_k)
    hertz_damping = config(n=2, radius=R_LIN, material=dataclasses.replace(
        LINEAR, restitution=None, gamma_n=40.0), contact_law="linear")
    with pytest.raises(ConfigError, match=r"grains\.0\.material\.gamma_n = 40.0"):
        validate(hertz_damping)
    elastic = config(n=2, radius=R_LIN, material=dataclasses.replace(LINEAR, restitution=None),
                     contact_law="linear")
    p = build(validate(elastic))[1]
    assert float(p.pair_table[0, 0, LAWS["linear"].column("zeta")]) == 0.0  # e = 1
