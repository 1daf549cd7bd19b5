"""The tangential spring with history wired into the JAX engine (``tangential_law = "mindlin"``,
issue 39): oblique impacts on a wall and between two spheres against the single-contact
reference (:func:`jaxdamp.physics.tangential.oblique_impact`), history kept across every
neighbour-list rebuild, a grain held by static friction (sticks below the Coulomb limit with
only the springs' elastic displacement, slides above it), the energy balance, bit-identical
continuation from a checkpoint, and the configuration's refusals."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers import config, gas, run_steps, start, trajectory

from jaxdamp.config import ConfigError, Material, Primary
from jaxdamp.engine import driver, fused
from jaxdamp.engine.choice import choose
from jaxdamp.physics import tangential
from jaxdamp.physics.contact import shear_compliance
from jaxdamp.physics.model import CH, LOSSES
from jaxdamp.validation import validate

#: Thesis steel, elastic (no normal damping: the reference has none), μ = 0.3.
STEEL = Material(E=2.03e11, nu=0.28, density=7850.0, mu=0.3, gamma_n=0.0, gamma_s=0.0)
R = 2.5e-3


def _mindlin(cfg, **numerics):
    cfg = dataclasses.replace(cfg, tangential_law="mindlin")
    if numerics:
        cfg = cfg.replace(numerics=dataclasses.replace(cfg.numerics, **numerics))
    return cfg


def _constants(mat, r_eff):
    """``E*``, ``G*`` of a like pair (and of the grain against a wall of its own material)
    and the Hertz ``k_n`` at ``R* = r_eff``."""
    e_star = 1.0 / (2.0 * (1.0 - mat.nu**2) / mat.E)
    g_star = 1.0 / (2.0 * shear_compliance(mat.E, mat.nu))
    return e_star, g_star, (4.0 / 3.0) * e_star * math.sqrt(r_eff)


def _reference(m, r_eff, vn, vt, mat=STEEL):
    _, g_star, kn = _constants(mat, r_eff)
    return tangential.oblique_impact(lambda xi: kn * xi**1.5,
                                     lambda xi: 8.0 * g_star * math.sqrt(r_eff * xi),
                                     m, r_eff, vn, vt, mat.mu)


def _contact_time(m_eff, r_eff, vn, mat=STEEL):
    e_star = _constants(mat, r_eff)[0]
    return 2.87 * (m_eff**2 / (r_eff * e_star**2 * vn)) ** 0.2


# Ψ = v_t / (μ v_n): sticking through most of the contact (0.5), the transition (3), sliding
# throughout (10)
PSI = (0.5, 3.0, 10.0)
#: The engines with the spring: the JAX engine and the native kernel (its first use compiles
#: the kernel's spring form, about three minutes on 2 cores cold: long).
ENGINES = ("jax", pytest.param("native", marks=pytest.mark.long))
#: Both engines long: tests of half a minute on the JAX engine too.
LONG_ENGINES = (pytest.param("jax", marks=pytest.mark.long), ENGINES[1])


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("psi", PSI)
def test_wall_impact_matches_the_single_contact_reference(psi, engine):
    """A sphere hits the floor obliquely (no gravity, 200 steps per contact): its rebound
    velocity and spin match the reference integration of the same contact law (20 000 steps
    per contact) to 2e-3 of the impact's tangential speed (the spin ``R ω`` to 2.5 times that:
    ``R Δω = (5/2) Δv_t``) — the engine's normal law, the spring's history in the floor's slot
    and its torque. (The engine converges to the reference at first order in ``dt``: at
    Ψ = 0.5 ``v_t`` is off by 4.1e-3, 9.8e-4, 2.4e-4 of itself at 50, 200, 800 steps per
    contact.)"""
    vn = 0.5
    vt = psi * STEEL.mu * vn
    m = STEEL.density * 4.0 / 3.0 * math.pi * R**3
    t_c = _contact_time(m, R, vn)
    dt = t_c / 200
    cfg = _mindlin(config(n=1, radius=R, material=STEEL), dt=dt)
    model, pb, st, nbrs = start(cfg, [[0.025, 0.025, R + 0.2 * vn * dt]], [[vt, 0.0, -vn]])
    st, _, _ = run_steps(model, pb, st, nbrs, 1, int(2 * t_c / dt), engine)
    v, w = np.asarray(st.v[0, 0]), np.asarray(st.w[0, 0])
    ref = _reference(m, R, vn, vt)
    assert v[2] == pytest.approx(ref.vn, rel=1e-4)
    assert abs(v[0] - ref.vt) < 2e-3 * vt
    # the floor's torque spins it about +y; R Δω = (5/2) Δv_t for a solid sphere
    assert abs(R * w[1] - ref.spin) < 2.5 * 2e-3 * vt
    assert float(st.e_spring[0]) == 0.0 and not np.asarray(st.spring_wall).any()  # left


def _pair_impact(skin, engine="jax"):
    """Two like spheres' oblique impact (Ψ = 0.5) with ``numerics.skin = skin``: the final
    velocities and angular velocities ``(2, 3)``, the reference and ``v_t``."""
    vn, psi = 0.5, 0.5
    vt = psi * STEEL.mu * vn
    m = STEEL.density * 4.0 / 3.0 * math.pi * R**3
    t_c = _contact_time(0.5 * m, 0.5 * R, vn)
    dt = t_c / 200
    cfg = _mindlin(config(n=2, radius=R, material=STEEL), dt=dt, skin=skin)
    gap = 0.2 * vn * dt
    r = [[0.025, 0.025, 0.02], [0.025, 0.025, 0.02 + 2 * R + gap]]
    v = [[0.5 * vt, 0.0, 0.5 * vn], [-0.5 * vt, 0.0, -0.5 * vn]]
    model, pb, st, nbrs = start(cfg, r, v)
    st, _, _ = run_steps(model, pb, st, nbrs, 1, int(2 * t_c / dt), engine)
    return np.asarray(st.v[0]), np.asarray(st.w[0]), _reference(0.5 * m, 0.5 * R, vn, vt), vt


@pytest.mark.parametrize("engine", ENGINES)
def test_sphere_pair_impact_matches_the_reference_and_keeps_history_over_rebuilds(engine):
    """Two like spheres collide obliquely: their relative motion is the reference's for one
    sphere of ``m/2``, ``R/2`` on a wall of the same material (an exact mapping, with each
    sphere's ``I``). With ``numerics.skin = 1e-3`` the neighbour list is rebuilt at nearly
    every step of the contact (the grains move ~1e-5 m during it, the rebuild distance is
    1.25e-6 m): the history goes with the pair, and the outcome equals the one with rare
    rebuilds (skin 0.5) to round-off.

    Tolerance 4e-3 of ``v_t`` (the wall's 2e-3 and the geometry): unlike the wall's, the pair's
    normal turns during the contact, the centres sliding past each other by ``v_t t_c``
    (~3e-4 rad of the line of centres), which tilts the normal impulse; the reference keeps
    its normal. Measured: 5.3e-3, 2.2e-3, 1.4e-3 of ``v_t`` at 50, 200, 800 steps per
    contact (converging to that ~1e-3, not to zero)."""
    out = {}
    for skin in (0.5, 1e-3):
        v, w, ref, vt = _pair_impact(skin, engine)
        rel = v[0] - v[1]
        assert -rel[2] == pytest.approx(ref.vn, rel=1e-4)  # separating
        assert abs(rel[0] - ref.vt) < 4e-3 * vt
        # the contact point's tangential velocity u = v_t − (R ω_0 + R ω_1) × n, n = −z
        u = rel[0] + R * (w[0, 1] + w[1, 1])
        assert abs(u - ref.u) < 3.5 * 4e-3 * vt  # u changes by (7/2) of Δ(v_t)
        assert np.abs(v[0] + v[1]).max() < 1e-15  # momentum: the pair's forces are opposite
        out[skin] = v, w
    (va, wa), (vb, wb) = out.values()
    np.testing.assert_allclose(va, vb, rtol=0, atol=1e-13)
    np.testing.assert_allclose(R * wa, R * wb, rtol=0, atol=1e-13)


def _squeezed(fraction, law="mindlin", engine="jax"):
    """A grain squeezed between floor and lid (overlap 1 µm each, no gravity) in a box driven
    along x at 50 Hz (``A cos ωt``) with peak acceleration ``fraction`` times the friction
    limit ``2 μ F_n / m``, over two periods. Returns the times [s], the grain's displacement in
    the box [m] and, had it stuck throughout, the same from the undamped oscillator
    ``x'' + (2 k_t / m) x = A ω² cos ωt`` (its two springs in parallel, starting at rest)
    [m]."""
    mat = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=0.0, gamma_s=0.0)
    delta = 1e-6
    _, g_star, kn = _constants(mat, R)
    m = mat.density * 4.0 / 3.0 * math.pi * R**3
    a_cap = 2.0 * mat.mu * kn * delta**1.5 / m
    omega = 2 * math.pi * 50.0
    amp = fraction * a_cap / omega**2
    cfg = config(n=1, radius=R, material=mat, box=(0.02, 0.02, 2 * (R - delta)),
                 amplitude=amp, frequency=50.0, duration=0.04)
    # (a grain squeezed by the lid does not pass validation, which wants it to fit: built as is)
    cfg = dataclasses.replace(cfg, direction=(1.0, 0.0, 0.0), tangential_law=law)
    model, pb, st, nbrs = start(cfg, [[0.01, 0.01, R - delta]], [[0.0, 0.0, 0.0]])
    steps = int(0.04 / float(pb.dt[0]))
    _, traj = trajectory(model, pb, st, nbrs, steps, steps // 400, engine=engine)
    t = np.array([s["t"] for s in traj])
    # in the box: the box's corner starts at +A (the drive's z(0)) and moves by A (cos ωt − 1)
    x = np.array([s["r"][0, 0] for s in traj]) - 0.01 - amp * (np.cos(omega * t) - 1.0)
    wn = math.sqrt(2.0 * 8.0 * g_star * math.sqrt(R * delta) / m)
    stuck = amp * omega**2 / (wn**2 - omega**2) * (np.cos(omega * t) - np.cos(wn * t))
    return t, x, stuck


@pytest.mark.parametrize("engine", LONG_ENGINES)
def test_a_squeezed_grain_sticks_below_the_friction_limit_and_slides_above(engine):
    """Static friction, the spring's reason to be. At a quarter of the friction limit the grain
    sticks: its displacement in the box follows the analytic stuck oscillator (the box starts
    with its full acceleration, so the undamped springs ring about the quasi-static
    displacement; the force stays below half the limit) to 3 % of its peak over two periods
    (measured 2.1 %: the phase of the ~120 ringing cycles; the peaks agree to 4e-4), hence
    without creep. At twice the limit it slides, by far more than any elastic displacement
    (measured 1 500 times the stuck oscillator's peak). (The viscous law, with
    ``gamma_s = 0`` here, has no tangential force at rest at all.)"""
    t, x, stuck = _squeezed(0.25, engine=engine)
    peak = np.abs(stuck).max()
    assert np.abs(x - stuck).max() < 0.03 * peak
    assert abs(np.abs(x).max() - peak) < 0.01 * peak
    t, x, stuck = _squeezed(2.0, engine=engine)
    assert np.abs(x).max() > 100 * np.abs(stuck).max()


def _gas_run(law, steps=10000, material=None, engine="jax"):
    """27 grains with friction (μ = 0.3, elastic normal law unless ``material``) in a free
    2 cm box (a primary of K = C = U = 0): the records of ``steps`` steps, and ``E(0)``."""
    mat = material or Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=0.0,
                               gamma_s=2e3)
    cfg = config(n=27, radius=2e-3, material=mat, box=(0.02, 0.02, 0.02), system="primary",
                 primary=Primary(M=0.05, K=0.0, C=0.0, U=0.0), v_impact=1.0,
                 dt_per_collision=100)
    cfg = dataclasses.replace(cfg, tangential_law=law)
    model, pb, st, nbrs = start(cfg, *gas(27))
    st, nbrs, rec = run_steps(model, pb, st, nbrs, 200, steps // 200, engine)
    return st, rec, float(st.e_start[0])


@pytest.mark.parametrize("engine", LONG_ENGINES)
def test_energy_balance_closes_in_a_frictional_gas(engine):
    """27 grains colliding with friction in a free box, elastic normal law: the tangential
    springs dissipate by slip (and store, and give back), their stiffness work is booked in
    ``spring_stiffness``: ``E(t) − E(0) + losses = 0`` to 2e-5 of ``E(0)`` over 1e4 steps
    — no worse than the viscous law's balance on the same gas (within a factor 2; measured
    1.08e-5 and 1.36e-5). The slip
    channels are parts of the friction channels, and the springs' energy a part of the
    elastic energy."""
    out = {}
    for law in ("viscous", "mindlin"):
        st, rec, e0 = _gas_run(law, engine=engine)
        err = np.abs(rec["balance_residual"]).max() / e0
        work = rec["work"][-1]
        out[law] = err, work
        print(law, f"balance {err:.3g} of E(0); pp_friction {work[CH['pp_friction']]:.4g} J, "
                   f"pp_slip {work[CH['pp_slip']]:.4g}, pw_slip {work[CH['pw_slip']]:.4g}, "
                   f"spring_stiffness {work[CH['spring_stiffness']]:.4g}; E(0) {e0:.4g} J")
        assert CH["spring_stiffness"] in LOSSES
    err_v, work_v = out["viscous"]
    err_m, work_m = out["mindlin"]
    assert err_m < 2e-5 and err_m < max(2 * err_v, 1e-6)
    assert work_v[CH["pp_slip"]] == 0 and work_v[CH["spring_stiffness"]] == 0
    assert 0 < work_m[CH["pp_slip"]] <= work_m[CH["pp_friction"]] * (1 + 1e-12)
    assert 0 < work_m[CH["pw_slip"]] <= work_m[CH["pw_friction"]] * (1 + 1e-12)
    assert work_m[CH["spring_stiffness"]] != 0


def _packed_bed(vessel="box", mu=0.3, law="mindlin"):
    """27 damped frictional grains with springs, packed into the lower corner of a 2 cm box
    under gravity (springs held after 2 000 steps), or (``vessel = "cylinder"``) at the axis
    of a cylinder of radius 12 mm, thrown outwards: ``start``'s model, params, state,
    lists (another friction coefficient ``mu``, another tangential ``law`` where given)."""
    cfg = dataclasses.replace(config(n=27, radius=2e-3, material=Material(
        E=2e9, nu=0.3, density=7850.0, mu=mu, restitution=0.7), box=(0.02, 0.02, 0.02),
        gravity=9.8, dt_per_collision=50), tangential_law=law)
    r, v, w = gas(27, side=0.0125)
    if vessel == "cylinder":
        from jaxdamp.config import Container

        rc = 0.012
        cfg = dataclasses.replace(cfg, box=None, container=Container(
            "cylinder", 0.02, (("radius", rc),)))
        r = np.asarray(r) + [rc - 0.00625, rc - 0.00625, 0.0]
        v = np.asarray(v) + 0.5 * (r - [rc, rc, 0.0]) / 0.00625 * [1.0, 1.0, 0.0]
    return start(cfg, r, v, w)


@pytest.mark.parametrize("engine", LONG_ENGINES)
def test_resumes_bit_identically_from_a_checkpoint(engine):
    """With springs in the state: 2 000 steps after 2 000 equal 2 000 after a checkpoint of
    the same state (host arrays) and a restore, in every field (springs, partners, work); 27
    grains packed into the lower corner of the box, so that springs are held at the
    checkpoint."""
    model, pb, st, nbrs = _packed_bed()
    half, nb_half, _ = run_steps(model, pb, st, nbrs, 1, 2000, engine)
    one, _, _ = run_steps(model, pb, half, nb_half, 1, 2000, engine)  # (one compiled chunk)
    b = driver.Batch(model, pb, half, nb_half, engine, 1.5)
    back = driver.restore(model, pb, driver.checkpoint(b), engine=engine)
    two, _, _ = run_steps(model, pb, back.states, back.nbrs, 1, 2000, engine)
    assert np.asarray(half.spring_pair).any()  # grain–grain springs held at the checkpoint
    for f in dataclasses.fields(one):
        np.testing.assert_array_equal(np.asarray(getattr(one, f.name)),
                                      np.asarray(getattr(two, f.name)), err_msg=f.name)


def test_configuration_refuses_what_the_spring_cannot_do():
    """``tangential_law`` names a law; the spring needs the Hertz law; it runs on every engine,
    but ``auto`` does not pick the fused device step for it (that step's speed was measured
    under the viscous law only); the messages name the parameters and the limits."""
    base = config(n=2, radius=R, material=STEEL)
    with pytest.raises(ConfigError, match="tangential_law = 'coulomb'"):
        validate(dataclasses.replace(base, tangential_law="coulomb"))
    lin = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, linear_stiffness=1e5)
    with pytest.raises(ConfigError, match="needs contact_law = 'hertz'"):
        validate(dataclasses.replace(config(n=2, radius=R, material=lin, contact_law="linear"),
                                     tangential_law="mindlin"))
    if fused.available()[0]:
        assert validate(_mindlin(base, engine="fused")).numerics.engine == "fused"
    assert validate(_mindlin(base, engine="native")).numerics.engine == "native"
    assert validate(_mindlin(base, engine="auto")).tangential_law == "mindlin"
    assert choose("native", tangential="mindlin").engine == "native"
    for law in ("mindlin", "viscous"):
        assert choose("auto", "float64", 1, backend="cpu", device_kind="cpu", have_native=True,
                      tangential=law).engine == "native"
    assert choose("auto", "float64", 16384, backend="gpu", device_kind="NVIDIA H200",
                  have_native=True, have_fused=True, tangential="mindlin").engine != "fused"


def test_a_run_says_which_settings_the_spring_does_not_use():
    """Under the spring the materials' ``gamma_s`` changes nothing: a run says so, naming each
    (``validation.unused_note``, printed before the run by ``run`` and ``sweep``); nothing is
    said under the viscous law, nor where every ``gamma_s`` is 0."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.validation import unused_note

    base = apply_overrides(presets.get("sanchez2012-optimal"),
                           ["grains.0.material.gamma_s=2.5", "box.wall=steel",
                            "box.wall.gamma_s=0.5"])
    note = unused_note(apply_overrides(base, ["tangential_law='mindlin'"]))
    assert note is not None
    assert "grains.0.material.gamma_s = 2.5" in note and "box.wall.gamma_s = 0.5" in note
    assert "not used" in note and "tangential_law = 'mindlin'" in note
    assert unused_note(base) is None
    quiet = apply_overrides(base, ["grains.0.material.gamma_s=0", "box.wall.gamma_s=0",
                                   "tangential_law='mindlin'"])
    assert unused_note(quiet) is None


@pytest.mark.long  # ~25 s each on 2 cores (the engine auto picks: the native kernel)
@pytest.mark.parametrize("system", ["primary", "driven"])
def test_energy_balance_closes_in_a_damper_run_end_to_end(system):
    """The whole run (settling, driving, records, summary) with the spring: input work =
    Δ(mechanical energy) + all losses to better than 1e-3, as with the viscous law
    (tests/test_energy.py; measured on the JAX engine 7.3e-5 (S1) and 2.9e-4 (S2), the
    viscous law 5.2e-5 and 2.5e-4 on the same beds); friction dissipates by slip."""
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.studies.runner import run

    over = ["grains.0.count=40", "box.Lz=0.06", "numerics.duration=0.2", "numerics.chunk=0.1",
            "numerics.settle_time=0.3", "tangential_law='mindlin'"]
    if system == "driven":
        over += ["system='driven'", "drive.amplitude=0.004", "frequency=20"]
    res = run(apply_overrides(presets.get("sanchez2012-optimal"), over), progress=False,
              echo=None)
    s = res.summary
    assert s["granular_loss_per_cycle"] > 0 and s["pp_friction_per_cycle"] > 0
    assert s["balance_error"] < 1e-3


@pytest.mark.parametrize("engine", LONG_ENGINES)
def test_springs_follow_their_pairs_into_reallocated_lists(engine):
    """Lists re-allocated larger (``driver.grow``, as after an overflow: another capacity,
    other slots) take the springs over by pair identity: the next 2 000 steps equal those on
    the old lists to round-off (the pair sums run over other slot orders), with springs held."""
    model, pb, st, nbrs = _packed_bed()
    st, nbrs, _ = run_steps(model, pb, st, nbrs, 1, 2000, engine)
    assert np.asarray(st.spring_pair).any()
    b = driver.Batch(model, pb, st, nbrs, engine, 1.5)
    big = driver.grow(b)
    assert nb_capacity(big.nbrs) > nb_capacity(nbrs)
    same, _, _ = run_steps(model, pb, st, nbrs, 1, 2000, engine)
    grown, _, _ = run_steps(model, pb, st, big.nbrs, 1, 2000, engine)
    scale = np.abs(np.asarray(same.v)).max()
    np.testing.assert_allclose(np.asarray(grown.v), np.asarray(same.v), rtol=0,
                               atol=1e-9 * scale)
    assert float(grown.e_spring[0]) == pytest.approx(float(same.e_spring[0]), rel=1e-6)


def nb_capacity(nbrs):
    return int(nbrs.idx.shape[-1])


@pytest.mark.long  # the native kernel's spring form (compiled once, cached)
@pytest.mark.parametrize("vessel", ["box", "cylinder"])
def test_native_springs_match_the_jax_engine(vessel):
    """The native kernel's spring is the JAX engine's: the packed bed over 2 000 steps (pair
    and wall springs loading, slipping, ending, lists rebuilt), velocities to 1e-9 of their
    largest, positions to 1e-12 m, the springs' energy to 1e-7 of itself, every work channel
    to 1e-9 of the largest, and the same springs held (measured in the box 1.4e-11, 1.9e-14 m,
    2.4e-10; the two engines sum their pairs in other orders); in a cylinder (radius 12 mm,
    the bed at its axis, thrown at the curved wall) as well."""
    model, pb, st, nbrs = _packed_bed(vessel)
    a, _, _ = run_steps(model, pb, st, nbrs, 4, 500, "native")
    b, _, _ = run_steps(model, pb, st, nbrs, 4, 500, "jax")
    assert float(a.work[0][CH["pw_side"]]) > 0  # the side walls touched (the curved one too)
    scale = np.abs(np.asarray(b.v)).max()
    np.testing.assert_allclose(np.asarray(a.v), np.asarray(b.v), rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(np.asarray(a.r), np.asarray(b.r), rtol=0, atol=1e-12)
    assert float(a.e_spring[0]) == pytest.approx(float(b.e_spring[0]), rel=1e-7)
    work_a, work_b = np.asarray(a.work[0]), np.asarray(b.work[0])
    np.testing.assert_allclose(work_a, work_b, rtol=0, atol=1e-9 * np.abs(work_b).max())
    assert work_a[CH["pp_slip"]] > 0 and work_a[CH["pw_slip"]] > 0
    assert work_a[CH["spring_stiffness"]] != 0
    held = lambda s: np.count_nonzero(np.abs(np.asarray(s.spring_pair)).sum(-1))  # noqa: E731
    assert held(a) == held(b) > 0


#: The fused device step's spring, run in numba-cuda's CUDA simulator on the CPU (the tests'
#: mode, tests/conftest.py), where the cuda extra is installed.
NO_FUSED = pytest.mark.skipif(not fused.available()[0], reason="numba-cuda not installed")


@pytest.mark.long  # ~10 s in the CUDA simulator (after the native kernel's spring form)
@NO_FUSED
def test_fused_springs_match_the_native_kernel():
    """The fused device step's spring (full lists: each grain keeps its own copy of a pair's
    spring; exactly the opposite of its partner's, the contact being odd) is the native
    kernel's: the packed bed with springs held, 200 steps and a list rebuild, velocities to
    1e-9 of their largest, positions to 1e-12 m, the springs' energy to 1e-7 of itself, every
    work channel to 1e-9 of the largest, the same springs held (measured 3.6e-15, 2.6e-18 m,
    2e-14, 7e-17: the pair sums run in other orders)."""
    model, pb, st, nbrs = _packed_bed()
    st, nbrs, _ = run_steps(model, pb, st, nbrs, 1, 2000, "native")
    a, _, ra = run_steps(model, pb, st, nbrs, 2, 100, "native")
    b, _, rb = run_steps(model, pb, st, nbrs, 2, 100, "fused")
    scale = np.abs(np.asarray(a.v)).max()
    np.testing.assert_allclose(np.asarray(b.v), np.asarray(a.v), rtol=0, atol=1e-9 * scale)
    np.testing.assert_allclose(np.asarray(b.r), np.asarray(a.r), rtol=0, atol=1e-12)
    assert float(a.e_spring[0]) > 0
    assert float(b.e_spring[0]) == pytest.approx(float(a.e_spring[0]), rel=1e-7)
    work_a, work_b = np.asarray(a.work[0]), np.asarray(b.work[0])
    np.testing.assert_allclose(work_b, work_a, rtol=0, atol=1e-9 * np.abs(work_a).max())
    assert work_b[CH["pp_slip"]] > 0 and work_b[CH["pw_slip"]] > 0
    held = lambda s: {(i, int(s.spring_partner[0][i, k])) for i, k in zip(  # noqa: E731
        *np.nonzero(np.abs(np.asarray(s.spring_pair[0])).sum(-1)), strict=True)}
    assert held(a) == held(b) != set()
    np.testing.assert_allclose(np.asarray(rb["balance_residual"]),
                               np.asarray(ra["balance_residual"]), rtol=0, atol=1e-12)


@pytest.mark.long
@pytest.mark.parametrize("engine", ["native", pytest.param("fused", marks=NO_FUSED)])
def test_springs_without_room_redo_the_chunk_with_larger_lists(engine):
    """Lists of one neighbour per grain cannot hold the packed bed's springs: the native kernel
    and the fused step lose none silently: the chunk is flagged, redone with larger lists,
    and equals, bit for bit, the chunk run on roomy lists."""
    from helpers import advance

    # a cube of 8 grains pressed together in a box that holds them (5 µm overlaps between
    # grains, 2.5 µm with the walls), jostling: 3 grain springs each (and 3 wall springs)
    cfg = dataclasses.replace(config(n=8, radius=2e-3, material=Material(
        E=2e9, nu=0.3, density=7850.0, mu=0.3, restitution=0.7), box=(0.00799,) * 3,
        dt_per_collision=50), tangential_law="mindlin")
    grid = np.stack(np.meshgrid(*[np.arange(2)] * 3, indexing="ij"), -1).reshape(-1, 3)
    rng = np.random.default_rng(3)
    model, pb, st, nbrs = start(cfg, 1.9975e-3 + grid * 3.995e-3,
                                rng.normal(0.0, 0.01, (8, 3)))
    st, nbrs, _ = run_steps(model, pb, st, nbrs, 1, 200, "native")
    assert int((np.abs(np.asarray(st.spring_pair)).sum(-1) > 0).sum(-1).max()) > 1
    roomy, _ = advance(model, st, nbrs, pb, 1, 500, engine)
    grown = []
    tight = dataclasses.replace(nbrs, idx=nbrs.idx[..., :1])
    redone, _ = advance(model, st, tight, pb, 1, 500, engine,
                        on_realloc=lambda old, new: grown.append((old, new)))
    assert grown and grown[0][0] == 1
    for f in dataclasses.fields(roomy.states):
        x, y = np.asarray(getattr(roomy.states, f.name)), np.asarray(getattr(redone.states,
                                                                            f.name))
        if f.name in ("spring_pair", "spring_partner"):  # rows as long as each list
            continue
        np.testing.assert_array_equal(x, y, err_msg=f.name)

    def springs(s):  # {(grain, partner): force} of the springs held
        part, force = np.asarray(s.spring_partner[0]), np.asarray(s.spring_pair[0])
        return {(i, int(part[i, k])): tuple(force[i, k]) for i, k in zip(
            *np.nonzero(np.abs(force).sum(-1)), strict=True)}

    assert springs(roomy.states) == springs(redone.states) != {}


@pytest.mark.long  # the native kernel's spring form (compiled once, cached)
def test_without_friction_the_laws_are_the_same_dynamics():
    """With μ = 0 (the paper's reference damper is frictionless) neither law has a tangential
    force: the spring is cut to μ F_n = 0 at every step. The packed bed of 27 grains with μ = 0
    runs the same 2 000 steps under both laws to round-off, by the criterion of the native
    kernel against the JAX engine (velocities to 1e-9 of their largest, positions to 1e-12 m:
    the two compiled forms order their arithmetic differently, and the packed bed amplifies
    it; measured 3.3e-16 m / 4e-15 m and 1.6e-11 with the kernel's functions compiled in two
    contexts, ``benchmarks/RESULTS.md``, "Bits that depend on the cache"), and every spring
    stays empty: the paper's E_d is the same under both laws at any amplitude (issue 39's
    question answered by construction)."""
    out = {}
    for law in ("mindlin", "viscous"):
        model, pb, st, nbrs = _packed_bed(mu=0.0, law=law)
        out[law], _, _ = run_steps(model, pb, st, nbrs, 4, 500, "native")
    spring, viscous = out["mindlin"], out["viscous"]
    for f, atol in (("r", 1e-12), ("v", 1e-9 * np.abs(np.asarray(viscous.v)).max()),
                    ("w", 1e-9 * np.abs(np.asarray(viscous.w)).max())):
        np.testing.assert_allclose(np.asarray(getattr(spring, f)),
                                   np.asarray(getattr(viscous, f)), rtol=0, atol=atol,
                                   err_msg=f)
    assert np.abs(np.asarray(viscous.w)).max() > 0  # (spun by nothing but the start)
    assert not np.asarray(spring.spring_pair).any() and not np.asarray(spring.spring_wall).any()
