"""Exact steady-state gradients of S3 (the smooth single-particle damper) by implicit
differentiation of its periodic orbit.

The steady state of the driven S3 system (``docs/physics.md`` §1, S3; the smooth model of
:mod:`jaxdamp.s3.impact`) is, when the motion is periodic, a *fixed point of the stroboscopic map*.
Differentiating a long transient run with ``jax.grad`` gives the derivative of a truncated,
start-dependent quantity whose tangent dynamics grow without bound where the motion is
irregular; the derivative of the *steady-state* objective (``docs/physics.md`` §7, objectives
of the optimiser, equivalent damping) follows instead exactly from the implicit-function
theorem at the orbit — no transient, no horizon — and where there is no stable orbit, this
module says so instead of returning a number.

**The stroboscopic map.** The drive period ``T = 2π/Ω`` is split into ``N`` equal steps,
``N = ceil(refine · T / dt_max)`` (:func:`period_steps`; ``dt_max`` the smooth model's step
limit of :func:`jaxdamp.s3.smooth.contact_constants`, so with ``refine = 1`` ``dt = T/N`` is just
below it, as :func:`jaxdamp.s3.smooth.smooth_schedule` shrinks ``dt`` to fit the record interval).
``P(x; θ)`` is ``N`` velocity-Verlet steps of :func:`jaxdamp.s3.smooth.smooth_step` from the
phase-0 state ``x`` (:func:`stroboscopic_map`). Because the step evaluates its
velocity-dependent forces at the predicted velocities ``v + a dt``, the accelerations carried
from one step to the next are part of the state of the discrete dynamics, so ``x`` has
:data:`STATE_SIZE` = 6 components (:data:`STATE_FIELDS`)::

    x = (z, z', y, y', z'', y'')          at t ≡ 0 (mod T)

(box and particle positions [m], velocities [m/s] and the accelerations of the last step
[m/s²]). The contact forces of :class:`~jaxdamp.s3.smooth.SmoothState` enter only the contact-loss
bookkeeping, and only through ``F_floor - F_lid = m (y'' + g)``; the work accumulators restart
at 0 and ``z_max, z_min`` are not used. Of the 6 Floquet multipliers, 4 belong to the physical
dynamics and 2 to the predicted-velocity scheme (parasitic, |λ| < 1e-6; with ``e = 0`` the
particle modes collapse as well, so ``det ∂P/∂x ≈ 0``). ``θ`` is any scalar field of
:class:`~jaxdamp.s3.smooth.SmoothParams` except ``dt`` (default the gap); for ``omega`` the step
follows as ``dt = 2π/(Ω N)``, so that ``P`` stays one period. ``P^k`` is ``k N`` steps (time
runs on; the drive is ``T``-periodic).

**The periodic orbit** ``x* = P^k(x*)`` (:func:`orbit`): Newton's method (:func:`newton`) on
``G(x) = P^k(x) - x`` with the ``6 × 6`` Jacobian ``∂P^k/∂x`` by ``jax.jacfwd`` (forward mode
through the ``k N`` steps), started from the state after a transient of ``transient`` seconds
(default 3 s) from the particle at rest on the floor, with a backtracking line search on the
scaled residual ``r(x) = max_i |G_i(x)| / s_i`` (``s`` = :func:`state_scale`:
``L, LΩ, L, LΩ, LΩ², LΩ²`` with ``L = gap + U``). Converged when ``r ≤ tol`` (default
:data:`TOL` = 1e-10; reached in 1–4 iterations from a settled transient, with ``r`` ~1e-13).
S3 also has subharmonic responses (e.g. period 2 at 10 Hz, period 3 at 22 Hz on
``sanchez2012-impact``), so ``k = 1, 2, ..., k_max`` are tried in turn until a stable orbit is
found.

**Floquet multipliers** ``λ_i``: the eigenvalues of ``∂P^k/∂x`` at ``x*``
(:func:`floquet_multipliers`). The orbit is stable iff ``max |λ_i| ≤ 1 - margin`` (default
:data:`STABILITY_MARGIN` = 1e-3).

**The objectives** averaged over the orbit (``k`` periods, ``n = k N`` steps at ``t_j = j dt``;
:func:`orbit_averages`):

* ``amplitude`` ``Z`` [m]: first-harmonic amplitude of ``z`` at the drive frequency,
  ``Z = sqrt(a² + b²)``, ``a = (2/n) Σ_j z_j cos Ωt_j``, ``b = (2/n) Σ_j z_j sin Ωt_j`` (the
  least-squares ``cos``/``sin``/constant fit of the optimiser, which is exactly this for
  uniform samples over whole periods);
* ``dissipation`` ``E`` [J]: impact (contact) loss per drive period, ``W_impact(kT) / k`` (the
  ``impact`` work channel of :func:`~jaxdamp.s3.smooth.smooth_step`);
* ``damping`` ``C_eq = E / (π Ω Z²)`` [N s/m], the equivalent viscous damping (§7);
* ``band`` (:func:`objective_and_gradient`): the smooth maximum of ``Z`` over several
  frequencies (:func:`jaxdamp.design.objectives.smooth_max`), one orbit per frequency.

**Implicit derivative.** ``x*(θ)`` solves ``P^k(x*; θ) = x*``, so with ``A = ∂P^k/∂x``::

    dx*/dθ = (I - A)^{-1} ∂P^k/∂θ
    dJ/dθ  = ∂J/∂x · dx*/dθ + ∂J/∂θ

where ``J(x, θ)`` is the objective of one orbit (``k`` periods) run from ``x``. All of
``A, ∂P^k/∂θ, ∂J/∂x, ∂J/∂θ`` come from one ``jax.jacfwd`` of
``(x, θ) ↦ (P^k(x; θ), Z, E, C_eq)`` (7 tangents through ``k N`` steps). ``I - A`` is
invertible at a stable orbit (all ``|λ| < 1``). Measured (``tests/test_periodic.py``): equal
to Richardson-extrapolated central differences of re-solved orbits to ~1e-8 and to central
differences of 30 s long-time averages to ~1e-6.

**The step and the derivative.** The derivative is exact *for the discrete model*. With the
smooth model's default 20 steps per contact (``refine = 1``) the discrete ``J(gap)`` carries a
ripple from the step grid: on ``sanchez2012-impact`` at 15.16 Hz around gap 0.0835 m the gap
derivative oscillates with a period of ~0.16 mm in the gap, by ±25 % (amplitude) and ±7 %
(dissipation) about the converged value, while ``J`` itself changes by < 1e-4. Measured
``dZ/dgap`` [m/m] and ``dE/dgap`` [J/m] for ``refine`` = 1, 2, 3, 4::

    gap 0.0400   dZ -0.11244 -0.11272 -0.11272 -0.11272   dE 93.588 93.589 93.589 93.589
    gap 0.0835   dZ  0.01992  0.02610  0.02610  0.02610   dE 15.634 16.609 16.609 16.609
    gap 0.0950   dZ  0.07340  0.06191  0.06186  0.06185   dE  6.098  4.179  4.173  4.172

``refine = 2`` (40 steps per contact) is converged to ~2e-3; use it where the derivative's
accuracy matters (cost ×2). The default stays the smooth model's step.

**Not a stable orbit.** :func:`orbit` returns an :class:`Orbit` with ``converged = False`` (no
Newton convergence for any ``k ≤ k_max``) or ``stable = False`` (converged, but a multiplier
on or outside the unit circle: the long-run motion does not settle on it) and a ``reason``
(``"not a stable periodic orbit: k=1: ...; k=2: ..."``); :func:`objective_and_gradient` then
returns ``(nan, nan, orbit)``. Neither raises in these cases; :meth:`Orbit.require` raises
:class:`NoStableOrbit`. (A stable orbit that coexists with an irregular attractor would be
found if Newton converges to it; ``Orbit.start_distance`` shows how far the transient's end
state was from the orbit.)

Example (optax style: the gradient drives a projected step)::

    import optax
    from jaxdamp.cases import presets
    from jaxdamp.s3 import periodic

    cfg = presets.get("sanchez2012-impact")
    orb = periodic.orbit(cfg, gap=0.0835)          # k = 1, max |λ| = 0.69, 1 Newton step
    print(orb.stable, orb.k, abs(orb.floquet))
    J, dJ, orb = periodic.objective_and_gradient(cfg, "dissipation", gap=0.0835)
    # 7.1028 J per period, dE/dgap = 15.63 J/m

    gap, opt = 0.0835, optax.adam(1e-3)
    state = opt.init(gap)
    for _ in range(10):                             # maximise the dissipation
        J, dJ, orb = periodic.objective_and_gradient(cfg, "dissipation", gap=gap, start=orb)
        if not orb.stable:                          # irregular motion: no number, a reason
            raise periodic.NoStableOrbit(orb.reason)
        step, state = opt.update(-dJ, state)
        gap = float(optax.apply_updates(gap, step))

    periodic.objective_and_gradient(cfg, "amplitude", gap=0.15)[:2]   # (nan, nan): irregular

``start=previous_orbit`` skips the transient (Newton from the previous orbit's state).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.config import Config, ConfigError
from jaxdamp.s3 import smooth

#: Components of the phase-0 state ``x`` of the stroboscopic map.
STATE_FIELDS = ("z", "vz", "y", "vy", "az", "ay")
STATE_SIZE = len(STATE_FIELDS)
#: Newton convergence: scaled residual ``max_i |P^k(x)_i - x_i| / s_i``.
TOL = 1e-10
#: Stable iff ``max |λ| ≤ 1 - STABILITY_MARGIN``.
STABILITY_MARGIN = 1e-3
#: Objectives averaged over the orbit (one frequency), see :func:`orbit_averages`.
KINDS = ("amplitude", "dissipation", "damping")


class NoStableOrbit(RuntimeError):
    """Raised by :meth:`Orbit.require` when no stable periodic orbit was found."""


@dataclass
class Orbit:
    """A periodic orbit of the smooth S3 model (or the report of its absence).

    ``state`` ``(6,)`` the phase-0 state ``x*`` (:data:`STATE_FIELDS`); ``k`` the period
    multiple (``x* = P^k(x*)``); ``floquet`` ``(6,)`` complex multipliers, largest modulus
    first; ``stable``, ``converged``; ``residual`` the scaled residual ``r(x*)``;
    ``iterations`` Newton iterations of the accepted ``k`` (summed over all ``k`` tried in
    ``total_iterations``); ``reason`` why it was not accepted ("" if stable);
    ``params`` the :class:`~jaxdamp.s3.smooth.SmoothParams` (step ``dt = T/N``), ``n_steps`` ``N``
    per period; ``start`` the Newton start state and ``start_distance`` its scaled distance
    ``max_i |x*_i - start_i| / s_i`` from the orbit (small when the transient has settled on
    it: the orbit is the attractor the run reaches); ``sim_seconds`` the simulated
    system-seconds spent (transient + every evaluation of ``P^k``, tangents counted once);
    ``attempts`` ``[(k, converged, residual, max|λ|)]`` of every ``k`` tried."""

    state: np.ndarray
    k: int
    floquet: np.ndarray
    stable: bool
    converged: bool
    residual: float
    iterations: int
    reason: str
    params: smooth.SmoothParams
    n_steps: int
    start: np.ndarray
    start_distance: float = math.nan
    total_iterations: int = 0
    sim_seconds: float = 0.0
    attempts: list = field(default_factory=list)

    @property
    def spectral_radius(self) -> float:
        return float(np.max(np.abs(self.floquet))) if self.floquet.size else math.nan

    def require(self) -> "Orbit":
        """``self`` if stable, else raise :class:`NoStableOrbit` with the reason."""
        if not self.stable:
            raise NoStableOrbit(self.reason)
        return self


# ---------------------------------------------------------------------------------------------
# the map


def period_steps(config: Config, frequency: float | None = None, refine: int = 1) -> int:
    """``N``: steps per drive period, ``ceil(refine T / dt_max)`` (``dt = T/N ≤ dt_max/refine``,
    ``dt_max`` of :func:`jaxdamp.s3.smooth.contact_constants`)."""
    f = float(config.frequency if frequency is None else frequency)
    dt_max = smooth.contact_constants(config)[2] / int(refine)
    return max(1, int(math.ceil(1.0 / (f * dt_max) - 1e-9)))


def orbit_params(config: Config, frequency: float | None = None, gap: float | None = None,
                 n_steps: int | None = None,
                 refine: int = 1) -> tuple[smooth.SmoothParams, int]:
    """``(SmoothParams, N)`` of ``config`` at ``frequency`` [Hz] and ``gap`` [m] (defaults:
    the config's), with ``dt = T/N`` (``N = n_steps``, default :func:`period_steps` with
    ``refine``); ``t_window = 0`` (unused)."""
    f = float(config.frequency if frequency is None else frequency)
    n = period_steps(config, f, refine) if n_steps is None else int(n_steps)
    p = smooth.smooth_params(config, 1.0 / (f * n), 0.0)
    p = dataclasses.replace(p, omega=jnp.asarray(2 * math.pi * f), t_window=jnp.asarray(0.0))
    p = dataclasses.replace(p, dt=2 * jnp.pi / (p.omega * n))  # as _with: the same rounding
    if gap is not None:
        p = dataclasses.replace(p, gap=jnp.asarray(float(gap)))
    return p, n


def state_scale(p: smooth.SmoothParams):
    """Scales ``s`` of the state components: ``L, LΩ, L, LΩ, LΩ², LΩ²``, ``L = gap + U``."""
    L = p.gap + jnp.abs(p.U)
    w = p.omega
    return jnp.stack([L, L * w, L, L * w, L * w * w, L * w * w])


def _with(p: smooth.SmoothParams, name: str, value, n):
    """``p`` with field ``name`` set to ``value`` and ``dt = 2π/(Ω n)``."""
    if name == "dt":
        raise ValueError("the step dt is fixed by the period (dt = T/N); differentiate omega")
    if name not in smooth.SmoothParams.__dataclass_fields__:
        raise ValueError(f"{name!r} is not a field of SmoothParams")
    p = dataclasses.replace(p, **{name: value})
    return dataclasses.replace(p, dt=2 * jnp.pi / (p.omega * n))


def _to_state(x, p: smooth.SmoothParams) -> smooth.SmoothState:
    z, vz, y, vy, az, ay = (x[i] for i in range(STATE_SIZE))
    zero = jnp.zeros_like(z)
    return smooth.SmoothState(
        i=jnp.zeros((), jnp.int64), z=z, vz=vz, az=az, y=y, vy=vy, ay=ay,
        f_floor=p.m * (ay + p.g), f_lid=zero, power=smooth._primary_power(z, vz, zero, p),
        work=jnp.zeros(3, x.dtype), z_max=zero, z_min=zero)


def _from_state(st: smooth.SmoothState):
    return jnp.stack([st.z, st.vz, st.y, st.vy, st.az, st.ay])


def _orbit_run(x, p: smooth.SmoothParams, steps):
    """``steps`` steps from the phase-0 state ``x``: ``(x_end, impact work, Σ z cos Ωt,
    Σ z sin Ωt)`` (sums over the steps' end states). ``steps`` may be traced."""
    st0 = _to_state(x, p)

    def body(_, carry):
        st, c, s = carry
        st = smooth.smooth_step(st, p)
        ph = p.omega * st.i * p.dt
        return st, c + st.z * jnp.cos(ph), s + st.z * jnp.sin(ph)

    zero = jnp.zeros_like(p.gap)
    st, c, s = jax.lax.fori_loop(0, steps, body, (st0, zero, zero))
    return _from_state(st), st.work[2], c, s


def _averages(x_end, work, c, s, steps, k, p: smooth.SmoothParams):
    """``(Z, E, C_eq)`` of an orbit run: first-harmonic amplitude [m], impact loss per period
    [J], equivalent viscous damping ``E / (π Ω Z²)`` [N s/m]."""
    Z = 2.0 / steps * jnp.sqrt(c * c + s * s)
    E = work / k
    return jnp.stack([Z, E, E / (jnp.pi * p.omega * Z * Z)])


def stroboscopic_map(x, p: smooth.SmoothParams, n: int, k: int = 1, param: str = "gap",
                     theta=None):
    """``P^k(x; θ)``: ``k n`` smooth steps from the phase-0 state ``x`` ``(6,)``; ``θ`` (if
    given) replaces field ``param`` of ``p``. Pure, jittable, forward-differentiable."""
    if theta is not None:
        p = _with(p, param, theta, n)
    return _orbit_run(x, p, k * n)[0]



@jax.jit
def _transient(p: smooth.SmoothParams, steps):
    """The phase-0 state after ``steps`` (a multiple of ``N``) steps from
    :func:`jaxdamp.s3.smooth.smooth_initial` (the particle at rest on the floor)."""
    st = jax.lax.fori_loop(0, steps, lambda _, s: smooth.smooth_step(s, p),
                           smooth.smooth_initial(p))
    return _from_state(st)


@jax.jit
def _residual_and_jacobian(x, p: smooth.SmoothParams, steps):
    """``G(x) = P^k(x) - x`` and ``∂P^k/∂x`` (jacfwd, 6 tangents)."""
    def f(x):
        y = _orbit_run(x, p, steps)[0]
        return y, y - x

    A, G = jax.jacfwd(f, has_aux=True)(x)
    return G, A


@jax.jit
def _residual(x, p: smooth.SmoothParams, steps):
    return _orbit_run(x, p, steps)[0] - x


@functools.partial(jax.jit, static_argnames=("param",))
def _map_and_averages_jacobian(x, theta, p: smooth.SmoothParams, n, k, param: str):
    """Values ``(P^k, Z, E, C_eq)`` ``(9,)`` and their ``9 × 7`` Jacobian w.r.t. ``(x, θ)``
    (one jacfwd, 7 tangents through ``k n`` steps)."""
    def f(xt):
        q = _with(p, param, xt[STATE_SIZE], n)
        y, work, c, s = _orbit_run(xt[:STATE_SIZE], q, k * n)
        out = jnp.concatenate([y, _averages(y, work, c, s, k * n, k, q)])
        return out, out

    jac, val = jax.jacfwd(f, has_aux=True)(jnp.concatenate([x, theta[None]]))
    return val, jac


def _scaled(G, scale) -> float:
    r = np.max(np.abs(np.asarray(G)) / scale)
    return float(r) if np.isfinite(r) else math.inf


def newton(x0, p: smooth.SmoothParams, n: int, k: int = 1, tol: float = TOL,
           max_iter: int = 30, min_step: float = 1.0 / 64) -> dict:
    """Newton's method on ``G(x) = P^k(x) - x`` from ``x0`` with backtracking (``α = 1, ½,
    ...,`` ``min_step``; accept when ``r`` decreases by the factor ``1 - 1e-4 α``).

    Returns a dict: ``x``, ``converged``, ``residual`` (``r(x)``), ``iterations``, ``A``
    (``∂P^k/∂x`` at ``x``), ``reason`` ("" or why it stopped) and ``maps`` (evaluations of
    ``P^k``, with or without tangents)."""
    scale = np.asarray(state_scale(p))
    steps = jnp.asarray(k * n)
    x = jnp.asarray(x0, dtype=jnp.float64)
    G, A = _residual_and_jacobian(x, p, steps)
    maps = 1
    r = _scaled(G, scale)
    eye = jnp.eye(STATE_SIZE)

    def out(converged, it, reason):
        return {"x": np.asarray(x), "converged": converged, "residual": r, "iterations": it,
                "A": np.asarray(A), "reason": reason, "maps": maps}

    for it in range(max_iter + 1):
        if r <= tol:
            return out(True, it, "")
        if not math.isfinite(r):
            return out(False, it, "non-finite state")
        if it == max_iter:
            break
        dx = jnp.linalg.solve(A - eye, -G)
        alpha, accepted = 1.0, False
        while alpha >= min_step:
            xt = x + alpha * dx
            if alpha == 1.0:
                Gt, At = _residual_and_jacobian(xt, p, steps)
            else:
                Gt, At = _residual(xt, p, steps), None
            maps += 1
            rt = _scaled(Gt, scale)
            if rt < (1.0 - 1e-4 * alpha) * r:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            return out(False, it + 1, f"line search failed (residual {r:.3g})")
        x, G, r = xt, Gt, rt
        if At is None:
            A = _residual_and_jacobian(x, p, steps)[1]
            maps += 1
        else:
            A = At
    return out(False, max_iter, f"no convergence in {max_iter} iterations (residual {r:.3g})")


def floquet_multipliers(A) -> np.ndarray:
    """Eigenvalues of the monodromy matrix ``A = ∂P^k/∂x``, largest modulus first."""
    lam = np.linalg.eigvals(np.asarray(A))
    return lam[np.argsort(-np.abs(lam))]


def _start_state(p, n, start, transient):
    """``(x0, periods of transient run)``."""
    if start is None:
        periods = max(1, int(round(transient * float(p.omega) / (2 * math.pi))))
        return np.asarray(_transient(p, jnp.asarray(periods * n))), periods
    if isinstance(start, Orbit):
        return np.asarray(start.state), 0
    x = np.asarray(start, float)
    if x.shape != (STATE_SIZE,):
        raise ValueError(f"start: expected a state of shape ({STATE_SIZE},), got {x.shape}")
    return x, 0


def orbit(config: Config, gap: float | None = None, frequency: float | None = None,
          k_max: int = 4, *, start=None, transient: float = 3.0, tol: float = TOL,
          margin: float = STABILITY_MARGIN, max_iter: int = 30,
          n_steps: int | None = None, refine: int = 1) -> Orbit:
    """The stable periodic orbit of the smooth S3 model of ``config`` at ``gap`` [m] and
    ``frequency`` [Hz] (defaults: the config's), or the report that there is none.

    Newton (:func:`newton`) on ``P^k(x) = x`` for ``k = 1, ..., k_max`` in turn (``start`` an
    :class:`Orbit`: its ``k`` first), from the state after ``transient`` seconds (rounded to
    whole periods) of the smooth model, or from ``start`` (an :class:`Orbit` or a state
    ``(6,)``). The first ``k`` whose orbit converges and is stable (``max |λ| ≤ 1 - margin``)
    is returned; an orbit of ``P^k`` that is one of ``P^d``, ``d | k``, is reported with
    ``k = d``. If none is, the returned :class:`Orbit` has ``stable = False`` and the reason
    (the last converged-but-unstable orbit if any, else the last attempt). ``n_steps``: steps
    per period ``N`` (default :func:`period_steps` with ``refine``: ``dt ≤ dt_max/refine``; see
    the module docstring on the step and the derivative)."""
    if config.system != "impact" or config.impactor is None:
        raise ConfigError("periodic.orbit needs an S3 configuration (system = 'impact')")
    p, n = orbit_params(config, frequency, gap, n_steps, refine)
    x0, periods = _start_state(p, n, start, transient)
    period = 2 * math.pi / float(p.omega)
    ks = list(range(1, k_max + 1))
    if isinstance(start, Orbit) and start.k in ks:
        ks.remove(start.k)
        ks.insert(0, start.k)
    scale = np.asarray(state_scale(p))
    attempts, reasons, fallback, total, maps = [], [], None, 0, float(periods)
    for k in ks:
        res = newton(x0, p, n, k, tol=tol, max_iter=max_iter)
        total += res["iterations"]
        maps += k * res["maps"]
        label = f"k={k}"
        if res["converged"] and k > 1:
            for d in range(1, k):
                if k % d:
                    continue
                maps += d
                if _scaled(_residual(jnp.asarray(res["x"]), p, jnp.asarray(d * n)),
                           scale) < 1e-6:
                    sub = newton(res["x"], p, n, d, tol=tol, max_iter=max_iter)
                    total += sub["iterations"]
                    maps += d * sub["maps"]
                    sub["iterations"] += res["iterations"]
                    res = sub
                    label = f"k={k} (an orbit of period {d})"
                    k = d
                    break
        ok, x, r = res["converged"], res["x"], res["residual"]
        lam = floquet_multipliers(res["A"])
        rho = float(np.max(np.abs(lam)))
        attempts.append((k, ok, r, rho))
        stable = ok and rho <= 1.0 - margin
        why = res["reason"]
        if ok and not stable:
            why = f"unstable periodic orbit (max |λ| = {rho:.4g})"
        orb = Orbit(state=x, k=k, floquet=lam, stable=stable, converged=ok, residual=r,
                    iterations=res["iterations"], reason="", params=p, n_steps=n, start=x0,
                    start_distance=_scaled(x - x0, scale), total_iterations=total,
                    sim_seconds=maps * period, attempts=attempts)
        if stable:
            return orb
        reasons.append(f"{label}: {why}")
        if ok or fallback is None or not fallback.converged:
            fallback = orb
    fallback.reason = "not a stable periodic orbit: " + "; ".join(reasons)
    fallback.total_iterations = total
    fallback.sim_seconds = maps * period
    return fallback


def orbit_averages(orb: Orbit, param: str = "gap") -> dict:
    """The objectives averaged over a stable orbit and their implicit derivatives w.r.t. the
    field ``param`` of :class:`~jaxdamp.s3.smooth.SmoothParams` (module docstring):
    ``{"amplitude": (Z, dZ/dθ), "dissipation": (E, dE/dθ), "damping": (C_eq, dC_eq/dθ),
    "dx": dx*/dθ (6,)}``; ``Z`` [m] the first-harmonic amplitude of ``z``, ``E`` [J] the impact
    loss per drive period, ``C_eq = E / (π Ω Z²)`` [N s/m] (``docs/physics.md`` §7). All NaN
    if ``orb`` is not stable."""
    if not orb.stable:
        nan = (math.nan, math.nan)
        return {"amplitude": nan, "dissipation": nan, "damping": nan,
                "dx": np.full(STATE_SIZE, np.nan)}
    if param == "dt" or param not in smooth.SmoothParams.__dataclass_fields__:
        _with(orb.params, param, 0.0, orb.n_steps)  # raises ValueError with the reason
    theta = jnp.asarray(getattr(orb.params, param), dtype=jnp.float64)
    val, jac = _map_and_averages_jacobian(jnp.asarray(orb.state), theta, orb.params,
                                          jnp.asarray(orb.n_steps), jnp.asarray(orb.k), param)
    val, jac = np.asarray(val), np.asarray(jac)
    m = STATE_SIZE
    A, b = jac[:m, :m], jac[:m, m]
    dx = np.linalg.solve(np.eye(m) - A, b)
    d = jac[m:, :m] @ dx + jac[m:, m]
    out = {kind: (float(val[m + i]), float(d[i])) for i, kind in enumerate(KINDS)}
    out["dx"] = dx
    return out


def implicit_derivative(orb: Orbit, kind: str, param: str = "gap"):
    """``(J, dJ/dθ, dx*/dθ)`` of one objective ``kind`` (:data:`KINDS`) of
    :func:`orbit_averages`; ``(nan, nan, nan)`` if ``orb`` is not stable."""
    if kind not in KINDS:
        raise ValueError(f"objective {kind!r}: expected one of {KINDS}")
    av = orbit_averages(orb, param)
    return av[kind][0], av[kind][1], av["dx"]


class Orbits(list):
    """The orbits of a multi-frequency objective (one per frequency), with the summary
    attributes of an :class:`Orbit`: ``stable`` (all are), ``reason`` (of the first that is
    not, prefixed with its frequency), ``sim_seconds`` (summed)."""

    def __init__(self, orbits, frequencies):
        super().__init__(orbits)
        self.frequencies = tuple(frequencies)

    @property
    def stable(self) -> bool:
        return all(o.stable for o in self)

    @property
    def converged(self) -> bool:
        return all(o.converged for o in self)

    @property
    def reason(self) -> str:
        for f, o in zip(self.frequencies, self):
            if not o.stable:
                return f"at {f:g} Hz: {o.reason}"
        return ""

    @property
    def sim_seconds(self) -> float:
        return float(sum(o.sim_seconds for o in self))


def objective_and_gradient(config: Config, objective, frequency=None, gap: float | None = None,
                           *, param: str = "gap", k_max: int = 4, start=None,
                           transient: float = 3.0, p: float | None = None, **options):
    """``(J, dJ/dθ, orbit)``: a steady-state objective over the periodic orbit(s) and its
    exact derivative w.r.t. ``param`` (default the gap [m]) at ``gap`` (default the config's).

    ``objective``:

    * a name in :data:`KINDS` — ``"amplitude"`` (first-harmonic amplitude ``Z`` of ``z`` [m]),
      ``"dissipation"`` (impact loss per drive period ``E`` [J]), ``"damping"``
      (``C_eq = E/(π Ω Z²)`` [N s/m]) at ``frequency`` [Hz] (default the config's);
      ``orbit`` is an :class:`Orbit`;
    * ``"band"`` — the band objective of :class:`jaxdamp.design.objectives.Objective` (the
      smooth maximum of ``Z``, exponent ``p``) at the frequencies ``frequency`` (a sequence;
      default 9 points over ``f0 ± 10 %``), one orbit per frequency; ``orbit`` is an
      :class:`Orbits`;
    * an objective object with ``kind``, ``frequencies(config)`` and
      ``combine(Z, E, frequencies)`` (:class:`jaxdamp.design.objectives.Objective`): the
      orbits at its frequencies (or ``frequency``), the per-frequency ``Z, E`` and their
      derivatives pushed through ``combine`` by ``jax.jvp``; ``orbit`` an :class:`Orbit` for one
      frequency, else :class:`Orbits`.

    ``J = dJ = nan`` when there is no stable periodic orbit (at any of the frequencies); the
    orbit's ``reason`` says why. ``start``: an :class:`Orbit` (or, for several frequencies, a
    sequence of them) to start Newton from instead of a transient. ``options``: of
    :func:`orbit` (``tol``, ``margin``, ``max_iter``, ``n_steps``, ``refine``). The orbits'
    ``sim_seconds`` include the ``k`` periods of the derivative run."""
    combine = None
    if isinstance(objective, str) and objective == "band":
        from jaxdamp.design.objectives import Objective

        freqs = None if frequency is None else tuple(float(f) for f in np.atleast_1d(frequency))
        objective = Objective("band", band=freqs, **({} if p is None else {"p": p}))
        frequency = None
    if isinstance(objective, str):
        if objective not in KINDS:
            raise ValueError(f"objective {objective!r}: expected one of {KINDS + ('band',)} "
                             "or an Objective")
        freqs = (float(config.frequency if frequency is None else frequency),)
        single = True
    else:
        freqs = (tuple(objective.frequencies(config)) if frequency is None
                 else tuple(float(f) for f in np.atleast_1d(frequency)))
        single = len(freqs) == 1
        combine = lambda Z, E: objective.combine(Z, E, freqs)  # noqa: E731
    starts = list(start) if isinstance(start, (list, tuple)) else [start] * len(freqs)
    if len(starts) != len(freqs):
        raise ValueError(f"start: {len(starts)} orbits for {len(freqs)} frequencies")
    orbs, Z, E = [], [], []
    for f, s in zip(freqs, starts):
        o = orbit(config, gap, f, k_max, start=s, transient=transient, **options)
        av = orbit_averages(o, param)
        if o.stable:
            o.sim_seconds += o.k * 2 * math.pi / float(o.params.omega)
        orbs.append(o)
        Z.append(av["amplitude"])
        E.append(av["dissipation"])
        if combine is None:
            J, dJ = av[objective]
    result = orbs[0] if single else Orbits(orbs, freqs)
    if not all(o.stable for o in orbs):
        return math.nan, math.nan, result
    if combine is not None:
        Zv, dZ = (jnp.asarray(v) for v in zip(*Z))
        Ev, dE = (jnp.asarray(v) for v in zip(*E))
        J, dJ = jax.jvp(combine, (Zv, Ev), (dZ, dE))
        J, dJ = float(J), float(dJ)
    return J, dJ, result
