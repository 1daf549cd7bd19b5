"""S3, smooth: penalty contacts integrated by velocity Verlet in JAX (differentiable,
``vmap``-batched), see :mod:`jaxdamp.s3.impact`."""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.analysis.response import analysis_start
from jaxdamp.config import Config
from jaxdamp.physics.excitation import harmonic_base
from jaxdamp.physics.model import pytree_dataclass
from jaxdamp.s3.common import ImpactRun, _check, n_records, summarize

#: Smallest restitution the smooth contact is calibrated to (``e`` below it uses this value).
SMOOTH_E_MIN = 0.005

def _binary_collision(zeta: float):
    """Restitution and duration ``ω t`` of a collision under the clipped linear law
    ``μ δ'' = -max(0, k δ + c δ')``, ``c = 2 ζ sqrt(k μ)``, ``ω = sqrt(k/μ)`` (closed form:
    the contact ends when the force reaches zero, ``δ + (2ζ/ω) δ' = 0``)."""
    from scipy.optimize import brentq

    def motion(t):  # δ(0) = 0, δ'(0) = 1, ω = 1
        if zeta < 1:
            wd = math.sqrt(1 - zeta**2)
            x = math.exp(-zeta * t) * math.sin(wd * t) / wd
            v = math.exp(-zeta * t) * (math.cos(wd * t) - zeta * math.sin(wd * t) / wd)
        elif zeta == 1:
            x, v = t * math.exp(-t), (1 - t) * math.exp(-t)
        else:
            b = math.sqrt(zeta**2 - 1)
            ep, em = math.exp((b - zeta) * t), math.exp(-(b + zeta) * t)
            ch, sh = 0.5 * (ep + em), 0.5 * (ep - em) / b  # e^{-ζt} cosh bt, e^{-ζt} sinh(bt)/b
            x = sh
            v = ch - zeta * sh
        return x, v

    def force(t):
        x, v = motion(t)
        return x + 2 * zeta * v

    if zeta == 0:
        return 1.0, math.pi
    grid = np.linspace(1e-9, 4 * math.pi, 4001)
    vals = np.array([force(t) for t in grid])
    k = int(np.argmax(vals < 0))
    t_end = brentq(force, grid[k - 1], grid[k], xtol=1e-15)
    return -motion(t_end)[1], t_end

@functools.lru_cache(maxsize=256)
def contact_damping_ratio(e: float) -> tuple[float, float]:
    """Damping ratio ``ζ`` of the clipped linear spring-dashpot whose free collision has
    restitution ``max(e, SMOOTH_E_MIN)``, and the collision's duration in units of ``1/ω``."""
    from scipy.optimize import brentq

    e = max(float(e), SMOOTH_E_MIN)
    if e >= 1.0:
        return 0.0, math.pi
    zeta = brentq(lambda z: _binary_collision(z)[0] - e, 0.0, 60.0, xtol=1e-13)
    return zeta, _binary_collision(zeta)[1]

@pytree_dataclass
class SmoothParams:
    """Parameters of one smooth S3 system (all scalars; batch by stacking).

    ``M, K, C, U`` primary [kg, N/m, N s/m, m]; ``omega`` drive [rad/s]; ``m`` particle [kg];
    ``gap`` [m]; ``g`` [m/s²]; ``k``, ``c`` contact stiffness [N/m] and damping [N s/m];
    ``width`` onset smoothing length [m]; ``dt`` step [s]; ``t_window`` analysis start [s]."""

    M: jnp.ndarray
    K: jnp.ndarray
    C: jnp.ndarray
    U: jnp.ndarray
    omega: jnp.ndarray
    m: jnp.ndarray
    gap: jnp.ndarray
    g: jnp.ndarray
    k: jnp.ndarray
    c: jnp.ndarray
    width: jnp.ndarray
    dt: jnp.ndarray
    t_window: jnp.ndarray

@pytree_dataclass
class SmoothState:
    """``i`` step count; box ``z, vz, az`` and particle ``y, vy, ay`` [m, m/s, m/s²]; contact
    forces ``f_floor``, ``f_lid`` [N]; ``power`` ``(2,)`` of the primary channels [W];
    cumulative ``work`` ``(3,)`` of :data:`CHANNELS` [J]; ``z_max``, ``z_min`` over the
    analysis window [m]."""

    i: jnp.ndarray
    z: jnp.ndarray
    vz: jnp.ndarray
    az: jnp.ndarray
    y: jnp.ndarray
    vy: jnp.ndarray
    ay: jnp.ndarray
    f_floor: jnp.ndarray
    f_lid: jnp.ndarray
    power: jnp.ndarray
    work: jnp.ndarray
    z_max: jnp.ndarray
    z_min: jnp.ndarray

def contact_constants(config: Config) -> tuple[float, float, float]:
    """``(k, c, dt_max)`` of the smooth contact: ``ζ`` from the restitution, ``ω`` from the
    contact duration, ``k = μ ω²``, ``c = 2 ζ μ ω`` with the reduced mass ``μ = mM/(m+M)``;
    ``dt_max = min(contact_time / steps_per_contact, μ/c)`` (the dashpot's explicit stability
    limit is ``2 μ/c``)."""
    im, M = config.impactor, config.primary.M
    zeta, tau = contact_damping_ratio(im.restitution)
    mu = im.mass * M / (im.mass + M)
    w = tau / im.contact_time
    k = mu * w * w
    c = 2.0 * zeta * mu * w
    dt = im.contact_time / im.steps_per_contact
    if c > 0:
        dt = min(dt, mu / c)
    return k, c, dt

def smooth_params(config: Config, dt: float, duration: float) -> SmoothParams:
    """The :class:`SmoothParams` of ``config`` with step ``dt`` over a run of ``duration``."""
    _check(config)
    p, im = config.primary, config.impactor
    k, c, _ = contact_constants(config)
    f = jnp.asarray
    return SmoothParams(M=f(p.M), K=f(p.K), C=f(p.C), U=f(p.U), omega=f(config.omega),
                        m=f(im.mass), gap=f(im.gap), g=f(config.gravity), k=f(k), c=f(c),
                        width=f(im.smooth_width), dt=f(dt),
                        t_window=f(analysis_start(config, duration)))

def _contact(d, dd, p: SmoothParams):
    """Penalty force [N] (≥ 0, pushing the bodies apart) at penetration ``d`` [m] and
    penetration rate ``dd`` [m/s], and its elastic energy [J].

    ``s = w softplus(d/w)`` is a smooth positive part of ``d`` and ``σ = sigmoid(d/w)`` its
    derivative; the elastic force ``k s σ`` derives from ``½ k s²``; the dashpot ``c dd`` is
    added and the total smoothly clipped at zero (width ``k w``) so the contact never pulls,
    and switched on by ``σ`` so that the force is a smooth function of the state (the
    trajectory then depends smoothly on the parameters, and gradients are well behaved)."""
    w = p.width
    s = w * jax.nn.softplus(d / w)
    sig = jax.nn.sigmoid(d / w)
    raw = p.k * s * sig + p.c * dd
    wf = p.k * w
    force = sig * wf * jax.nn.softplus(raw / wf)
    return force, 0.5 * p.k * s * s

def _forces(z, vz, y, vy, t, p: SmoothParams):
    """Accelerations of box and particle [m/s²] and the floor and lid contact forces [N]."""
    u, ud = harmonic_base(t, p.U, p.omega)
    f_floor, _ = _contact(z - y, vz - vy, p)
    f_lid, _ = _contact(y - z - p.gap, vy - vz, p)
    spring = p.K * (z - u) + p.C * (vz - ud)
    az = (-spring - f_floor + f_lid) / p.M
    ay = (f_floor - f_lid) / p.m - p.g
    return az, ay, f_floor, f_lid

def _primary_power(z, vz, t, p: SmoothParams):
    """Power input by the base through spring and damper, and the power lost in C [W]."""
    u, ud = harmonic_base(t, p.U, p.omega)
    spring = p.K * (z - u) + p.C * (vz - ud)
    return jnp.stack([-spring * ud, p.C * (vz - ud) ** 2])

def _elastic(z, y, p: SmoothParams):
    return _contact(z - y, 0.0, p)[1] + _contact(y - z - p.gap, 0.0, p)[1]

def smooth_initial(p: SmoothParams) -> SmoothState:
    """The particle resting on the floor, the box at the static equilibrium ``-m g/K``."""
    z = -p.m * p.g / p.K
    zero = jnp.zeros_like(z)
    az, ay, ff, fl = _forces(z, zero, z, zero, zero, p)
    return SmoothState(i=jnp.zeros((), jnp.int64), z=z, vz=zero, az=az, y=z, vy=zero, ay=ay,
                       f_floor=ff, f_lid=fl, power=_primary_power(z, zero, zero, p),
                       work=jnp.zeros(3), z_max=jnp.full_like(z, -jnp.inf),
                       z_min=jnp.full_like(z, jnp.inf))

def smooth_step(st: SmoothState, p: SmoothParams) -> SmoothState:
    """One velocity-Verlet step; velocity-dependent forces use the predicted velocities
    ``v + a dt`` (as the DEM step). Primary channels by the trapezoid rule. The contact loss
    of the step is what the scheme itself removes: the work of the step's contact impulse
    ``½(F0 + F1) dt`` on the mean relative velocity, minus the change of the elastic energy
    (a trapezoid rule on the dashpot power is off by ~10 % when the stiff dashpot changes the
    relative velocity within a few steps)."""
    dt = p.dt
    t1 = (st.i + 1) * dt
    z1 = st.z + st.vz * dt + 0.5 * st.az * dt * dt
    y1 = st.y + st.vy * dt + 0.5 * st.ay * dt * dt
    az1, ay1, ff1, fl1 = _forces(z1, st.vz + st.az * dt, y1, st.vy + st.ay * dt, t1, p)
    vz1 = st.vz + 0.5 * (st.az + az1) * dt
    vy1 = st.vy + 0.5 * (st.ay + ay1) * dt
    power1 = _primary_power(z1, vz1, t1, p)
    dv = 0.5 * ((st.vz - st.vy) + (vz1 - vy1))  # mean penetration rate of the floor contact
    impulse = 0.5 * dt * ((st.f_floor + ff1) - (st.f_lid + fl1))
    loss = impulse * dv - (_elastic(z1, y1, p) - _elastic(st.z, st.y, p))
    inside = t1 >= p.t_window
    return SmoothState(
        i=st.i + 1, z=z1, vz=vz1, az=az1, y=y1, vy=vy1, ay=ay1, f_floor=ff1, f_lid=fl1,
        power=power1,
        work=st.work + jnp.concatenate([0.5 * dt * (st.power + power1), loss[None]]),
        z_max=jnp.where(inside, jnp.maximum(st.z_max, z1), st.z_max),
        z_min=jnp.where(inside, jnp.minimum(st.z_min, z1), st.z_min),
    )

def smooth_energy(st: SmoothState, p: SmoothParams):
    """Mechanical energy [J] including the penalty springs."""
    u, _ = harmonic_base(st.i * p.dt, p.U, p.omega)
    return (0.5 * p.M * st.vz**2 + 0.5 * p.m * st.vy**2 + 0.5 * p.K * (st.z - u) ** 2
            + p.m * p.g * st.y + _elastic(st.z, st.y, p))

def _sample(st: SmoothState, p: SmoothParams) -> dict:
    t = st.i * p.dt
    return {"t": t, "z_box": st.z, "v_box": st.vz, "z_particle": st.y, "v_particle": st.vy,
            "u": harmonic_base(t, p.U, p.omega)[0], "work": st.work,
            "energy": smooth_energy(st, p)}

@functools.partial(jax.jit, static_argnames=("n_rec", "record_every", "records"))
def smooth_run(p: SmoothParams, n_rec: int, record_every: int, records: bool = True):
    """``n_rec * record_every`` steps of the smooth model from :func:`smooth_initial`.

    Differentiable (reverse mode through the scan) and batchable with ``jax.vmap`` over any
    leaf of ``p``. Returns ``(final state, samples)``: a dict of arrays ``(n_rec + 1,)``
    (``work`` ``(n_rec + 1, 3)``), ``None`` with ``records=False``."""
    st0 = smooth_initial(p)

    def inner(st, _):
        return smooth_step(st, p), None

    def outer(st, _):
        st, _ = jax.lax.scan(inner, st, None, length=record_every)
        return st, (_sample(st, p) if records else None)

    final, rec = jax.lax.scan(outer, st0, None, length=n_rec)
    if records:
        first = _sample(st0, p)
        rec = {k: jnp.concatenate([first[k][None], v]) for k, v in rec.items()}
    return final, rec

def smooth_schedule(configs) -> tuple[float, int, int]:
    """Common ``(dt, record_every, n_rec)`` of smooth runs: the smallest step any config needs,
    shrunk so that ``record_dt`` is a whole number of steps."""
    rec_dt = configs[0].numerics.record_dt
    dt = min(contact_constants(c)[2] for c in configs)
    record_every = max(1, int(math.ceil(rec_dt / dt - 1e-9)))
    return rec_dt / record_every, record_every, n_records(configs[0])

def smooth_window_loss(p: SmoothParams, n_rec: int, record_every: int):
    """Impact loss per drive period [J] over the analysis window of a smooth run: a scalar
    objective for ``jax.grad`` (e.g. w.r.t. ``p.gap``). Accumulated inside the scan."""
    st0 = smooth_initial(p)

    def step(carry, _):
        st, w0 = carry
        st1 = smooth_step(st, p)
        w0 = jnp.where(st.i * p.dt < p.t_window, st1.work[2], w0)
        return (st1, w0), None

    n = n_rec * record_every
    (final, w0), _ = jax.lax.scan(step, (st0, jnp.zeros(())), None, length=n)
    t_end = n * p.dt
    t0 = jnp.ceil(p.t_window / p.dt - 1e-9) * p.dt
    cycles = (t_end - t0) * p.omega / (2 * jnp.pi)
    return (final.work[2] - w0) / cycles

def simulate_smooth(configs: list[Config]) -> list[ImpactRun]:
    """The smooth S3 model of every config in one ``vmap``-ed batch (common step)."""
    for c in configs:
        _check(c)
    dt, record_every, n_rec = smooth_schedule(configs)
    duration = n_rec * record_every * dt
    ps = [smooth_params(c, dt, duration) for c in configs]
    pb = jax.tree_util.tree_map(lambda *xs: jnp.stack(xs), *ps)
    final, rec = jax.vmap(lambda p: smooth_run(p, n_rec, record_every))(pb)
    rec = {k: np.asarray(v) for k, v in rec.items()}
    out = []
    for i, c in enumerate(configs):
        r = {k: v[i] for k, v in rec.items()}
        w = r["work"]
        r["balance_residual"] = r["energy"] - r["energy"][0] + w[:, 1] + w[:, 2] - w[:, 0]
        s, units = summarize(c, r, float(final.z_max[i]), float(final.z_min[i]),
                             float(ps[i].t_window), None)
        out.append(ImpactRun(records=r, impacts={}, summary=s, units=units))
    return out
