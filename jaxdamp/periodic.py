"""Exact steady-state gradients of S3 (the smooth single-particle damper) by implicit
differentiation of its periodic orbit.

The steady state of the driven S3 system (``docs/physics.md`` §1, S3; smooth model of
:mod:`jaxdamp.impact`) is, when the motion is periodic, a *fixed point of the stroboscopic map*.
Differentiating a long transient run (what :class:`jaxdamp.optimize.S3Problem` does) gives the
derivative of a truncated, start-dependent quantity whose tangent dynamics may grow without
bound; the derivative of the *steady-state* objective (``docs/physics.md`` §7, "Objectives of
the optimiser") follows instead exactly from the implicit-function theorem at the orbit —
no transient, no horizon.

**The stroboscopic map.** With the drive period ``T = 2π/Ω`` split into ``N`` equal steps
(``N = ceil(T / dt_max)``, ``dt_max`` the smooth model's step limit of
:func:`jaxdamp.impact.contact_constants`, so ``dt = T/N`` is just below it, as
:func:`jaxdamp.impact.smooth_schedule` shrinks ``dt`` to fit the record interval),
``P(x; θ)`` is ``N`` velocity-Verlet steps of :func:`jaxdamp.impact.smooth_step` from the
phase-0 state ``x``. Because the step evaluates its velocity-dependent forces at the predicted
velocities ``v + a dt``, the accelerations carried from one step to the next are part of the
state of the discrete dynamics, so ``x`` has :data:`STATE_SIZE` = 6 components
(:data:`STATE_FIELDS`)::

    x = (z, z', y, y', z'', y'')          at t ≡ 0 (mod T)

(box and particle positions [m], velocities [m/s] and the accelerations of the last step
[m/s²]). The contact forces of the state enter only the contact-loss bookkeeping, and only
through ``F_floor - F_lid = m (y'' + g)``; the work accumulators restart at 0. Of the 6 Floquet
multipliers, 4 belong to the physical (continuous) dynamics and 2 to the predicted-velocity
scheme (parasitic, |λ| ≈ 0). ``θ`` is any scalar field of :class:`~jaxdamp.impact.SmoothParams`
(default the gap); for ``omega`` the step follows as ``dt = 2π/(Ω N)``, so that ``P`` stays one
period. ``P^k`` is ``k N`` steps (time runs on, the drive is ``T``-periodic).

**The periodic orbit** ``x* = P^k(x*)``: Newton's method on ``G(x) = P^k(x) - x`` with the
``6 × 6`` Jacobian ``∂P^k/∂x`` by ``jax.jacfwd`` (forward mode through the ``k N`` steps),
started from the state after a transient of ``transient`` seconds (default 3 s) from the
particle at rest on the floor, with a backtracking line search on the scaled residual
``r(x) = max_i |G_i(x)| / s_i`` (``s`` = :func:`state_scale`: ``L, LΩ, L, LΩ, LΩ², LΩ²`` with
``L = gap + U``). Converged when ``r ≤ tol`` (default :data:`TOL` = 1e-10). Since S3 also has
subharmonic responses, ``k = 1, 2, ..., k_max`` are tried in turn until a stable orbit is found.

**Floquet multipliers** ``λ_i``: the eigenvalues of ``∂P^k/∂x`` at ``x*``. The orbit is stable
iff ``max |λ_i| ≤ 1 - margin`` (default :data:`STABILITY_MARGIN` = 1e-3); their product equals
``det ∂P^k/∂x``.

**The objective** averaged over the orbit (``k`` periods, ``n = k N`` steps at ``t_j = j dt``):

* ``dissipation``: impact (contact) loss per drive period [J],
  ``J = W_impact(kT) / k`` (the ``impact`` work channel of :func:`~jaxdamp.impact.smooth_step`);
* ``amplitude``: first-harmonic amplitude of ``z`` at the drive frequency [m],
  ``J = sqrt(a² + b²)``, ``a = (2/n) Σ_j z_j cos Ωt_j``, ``b = (2/n) Σ_j z_j sin Ωt_j``
  (the least-squares ``cos``/``sin``/constant fit of :mod:`jaxdamp.optimize`, which is exactly
  this for uniform samples over whole periods).

**Implicit derivative.** ``x*(θ)`` solves ``P^k(x*; θ) = x*``, so with ``A = ∂P^k/∂x``::

    dx*/dθ = (I - A)^{-1} ∂P^k/∂θ
    dJ/dθ  = ∂J/∂x · dx*/dθ + ∂J/∂θ

where ``J(x, θ)`` is the objective of one orbit (``k`` periods) run from ``x``. All of
``A, ∂P^k/∂θ, ∂J/∂x, ∂J/∂θ`` come from one ``jax.jacfwd`` of ``(x, θ) ↦ (P^k(x; θ), J(x; θ))``
(7 tangents through ``k N`` steps). ``I - A`` is invertible at a stable orbit (all ``|λ| < 1``).

**Not a stable orbit.** :func:`orbit` returns an :class:`Orbit` with ``converged = False`` (no
Newton convergence for any ``k ≤ k_max``) or ``stable = False`` (converged, but a multiplier
on or outside the unit circle: the long-run motion does not settle on it) and a ``reason``;
:func:`objective_and_gradient` then returns ``(nan, nan, orbit)``. It never raises for these
cases; :class:`NoStableOrbit` is raised only by :meth:`Orbit.require`.

Example::

    >>> from jaxdamp import presets, periodic
    >>> cfg = presets.get("sanchez2012-impact")
    >>> orb = periodic.orbit(cfg, gap=0.0835, frequency=15.16)
    >>> orb.stable, orb.k, bool(abs(orb.floquet).max() < 1)          # doctest: +SKIP
    (True, 1, True)
    >>> J, dJ, orb = periodic.objective_and_gradient(cfg, "dissipation", gap=0.0835)
    >>> J, dJ = periodic.objective_and_gradient(cfg, "amplitude", gap=0.15)[:2]  # irregular
    >>> import math; math.isnan(J)                                      # doctest: +SKIP
    True

In an optimisation loop pass ``start=previous_orbit`` to skip the transient (Newton from the
previous orbit's state).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import jax
import jax.numpy as jnp
import numpy as np

from . import impact
from .config import Config, ConfigError

#: Components of the phase-0 state ``x`` of the stroboscopic map.
STATE_FIELDS = ("z", "vz", "y", "vy", "az", "ay")
STATE_SIZE = len(STATE_FIELDS)
#: Newton convergence: scaled residual ``max_i |P^k(x)_i - x_i| / s_i``.
TOL = 1e-10
#: Stable iff ``max |λ| ≤ 1 - STABILITY_MARGIN``.
STABILITY_MARGIN = 1e-3
#: Objectives averaged over the orbit.
KINDS = ("dissipation", "amplitude")


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
    ``params`` the :class:`~jaxdamp.impact.SmoothParams` (step ``dt = T/N``), ``n_steps`` ``N``
    per period; ``start`` the Newton start state and ``start_distance`` its scaled distance
    ``max_i |x*_i - start_i| / s_i`` from the orbit (small when the transient has settled on
    it: the orbit is the attractor the run reaches); ``attempts`` ``[(k, converged, residual,
    max|λ|)]`` of every ``k`` tried."""

    state: np.ndarray
    k: int
    floquet: np.ndarray
    stable: bool
    converged: bool
    residual: float
    iterations: int
    reason: str
    params: impact.SmoothParams
    n_steps: int
    start: np.ndarray
    start_distance: float = math.nan
    total_iterations: int = 0
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


def period_steps(config: Config, frequency: float | None = None) -> int:
    """``N``: steps per drive period, ``ceil(T / dt_max)`` (``dt = T/N ≤ dt_max``)."""
    f = float(config.frequency if frequency is None else frequency)
    dt_max = impact.contact_constants(config)[2]
    return max(1, int(math.ceil(1.0 / (f * dt_max) - 1e-9)))


def orbit_params(config: Config, frequency: float | None = None,
                 gap: float | None = None) -> tuple[impact.SmoothParams, int]:
    """``(SmoothParams, N)`` of ``config`` at ``frequency`` [Hz] and ``gap`` [m] (defaults:
    the config's), with ``dt = T/N``; ``t_window = 0`` (unused)."""
    f = float(config.frequency if frequency is None else frequency)
    n = period_steps(config, f)
    p = impact.smooth_params(config, 1.0 / (f * n), 0.0)
    p = dataclasses.replace(p, omega=jnp.asarray(2 * math.pi * f), t_window=jnp.asarray(0.0))
    if gap is not None:
        p = dataclasses.replace(p, gap=jnp.asarray(float(gap)))
    return p, n


def state_scale(p: impact.SmoothParams):
    """Scales ``s`` of the state components: ``L, LΩ, L, LΩ, LΩ², LΩ²``, ``L = gap + U``."""
    L = p.gap + jnp.abs(p.U)
    w = p.omega
    return jnp.stack([L, L * w, L, L * w, L * w * w, L * w * w])


def _with(p: impact.SmoothParams, name: str, value, n):
    """``p`` with field ``name`` set to ``value`` and ``dt = 2π/(Ω n)``."""
    if name == "dt":
        raise ValueError("the step dt is fixed by the period (dt = T/N); differentiate omega")
    if name not in impact.SmoothParams.__dataclass_fields__:
        raise ValueError(f"{name!r} is not a field of SmoothParams")
    p = dataclasses.replace(p, **{name: value})
    return dataclasses.replace(p, dt=2 * jnp.pi / (p.omega * n))


def _to_state(x, p: impact.SmoothParams) -> impact.SmoothState:
    z, vz, y, vy, az, ay = (x[i] for i in range(STATE_SIZE))
    zero = jnp.zeros_like(z)
    return impact.SmoothState(
        i=jnp.zeros((), jnp.int64), z=z, vz=vz, az=az, y=y, vy=vy, ay=ay,
        f_floor=p.m * (ay + p.g), f_lid=zero, power=impact._primary_power(z, vz, zero, p),
        work=jnp.zeros(3, x.dtype), z_max=zero, z_min=zero)


def _from_state(st: impact.SmoothState):
    return jnp.stack([st.z, st.vz, st.y, st.vy, st.az, st.ay])


def _orbit_run(x, p: impact.SmoothParams, steps):
    """``steps`` steps from the phase-0 state ``x``: ``(x_end, impact work, Σ z cos Ωt,
    Σ z sin Ωt)`` (sums over the steps' end states). ``steps`` may be traced."""
    st0 = _to_state(x, p)

    def body(_, carry):
        st, c, s = carry
        st = impact.smooth_step(st, p)
        ph = p.omega * st.i * p.dt
        return st, c + st.z * jnp.cos(ph), s + st.z * jnp.sin(ph)

    zero = jnp.zeros_like(p.gap)
    st, c, s = jax.lax.fori_loop(0, steps, body, (st0, zero, zero))
    return _from_state(st), st.work[2], c, s


def _objective(kind, work, c, s, steps, k):
    if kind == "dissipation":
        return work / k
    if kind == "amplitude":
        return 2.0 / steps * jnp.sqrt(c * c + s * s)
    raise ValueError(f"objective {kind!r}: expected one of {KINDS}")


def stroboscopic_map(x, p: impact.SmoothParams, n: int, k: int = 1, param: str = "gap",
                     theta=None):
    """``P^k(x; θ)``: ``k n`` smooth steps from the phase-0 state ``x`` ``(6,)``; ``θ`` (if
    given) replaces field ``param`` of ``p``. Pure, jittable, forward-differentiable."""
    if theta is not None:
        p = _with(p, param, theta, n)
    return _orbit_run(x, p, k * n)[0]



@jax.jit
def _transient(p: impact.SmoothParams, steps):
    """The phase-0 state after ``steps`` (a multiple of ``N``) steps from
    :func:`jaxdamp.impact.smooth_initial` (the particle at rest on the floor)."""
    st = jax.lax.fori_loop(0, steps, lambda _, s: impact.smooth_step(s, p),
                           impact.smooth_initial(p))
    return _from_state(st)


@jax.jit
def _residual_and_jacobian(x, p: impact.SmoothParams, steps):
    """``G(x) = P^k(x) - x`` and ``∂P^k/∂x`` (jacfwd, 6 tangents)."""
    def f(x):
        y = _orbit_run(x, p, steps)[0]
        return y, y - x

    A, G = jax.jacfwd(f, has_aux=True)(x)
    return G, A


@jax.jit
def _residual(x, p: impact.SmoothParams, steps):
    return _orbit_run(x, p, steps)[0] - x


@functools.partial(jax.jit, static_argnames=("kind", "param"))
def _map_and_objective_jacobian(x, theta, p: impact.SmoothParams, n, k, kind: str,
                                param: str):
    """Values and the ``7 × 7`` Jacobian of ``(x, θ) ↦ (P^k(x; θ), J(x; θ))`` (one jacfwd)."""
    def f(xt):
        q = _with(p, param, xt[STATE_SIZE], n)
        y, work, c, s = _orbit_run(xt[:STATE_SIZE], q, k * n)
        out = jnp.concatenate([y, _objective(kind, work, c, s, k * n, k)[None]])
        return out, out

    jac, val = jax.jacfwd(f, has_aux=True)(jnp.concatenate([x, theta[None]]))
    return val, jac


def _scaled(G, scale) -> float:
    r = np.max(np.abs(np.asarray(G)) / scale)
    return float(r) if np.isfinite(r) else math.inf


def newton(x0, p: impact.SmoothParams, n: int, k: int = 1, tol: float = TOL,
           max_iter: int = 30, min_step: float = 1.0 / 64):
    """Newton's method on ``G(x) = P^k(x) - x`` from ``x0`` with backtracking (``α = 1, ½,
    ...,`` ``min_step``; accept when ``r`` decreases by the factor ``1 - 1e-4 α``).

    Returns ``(x, converged, r, iterations, A, reason)``: ``A = ∂P^k/∂x`` at the returned
    ``x``, ``r`` its scaled residual, ``reason`` "" or why it stopped."""
    scale = np.asarray(state_scale(p))
    steps = jnp.asarray(k * n)
    x = jnp.asarray(x0, dtype=jnp.float64)
    G, A = _residual_and_jacobian(x, p, steps)
    r = _scaled(G, scale)
    eye = jnp.eye(STATE_SIZE)
    for it in range(max_iter + 1):
        if r <= tol:
            return np.asarray(x), True, r, it, np.asarray(A), ""
        if not math.isfinite(r):
            return np.asarray(x), False, r, it, np.asarray(A), "non-finite state"
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
            rt = _scaled(Gt, scale)
            if rt < (1.0 - 1e-4 * alpha) * r:
                accepted = True
                break
            alpha *= 0.5
        if not accepted:
            return (np.asarray(x), False, r, it + 1, np.asarray(A),
                    f"line search failed (residual {r:.3g})")
        x, G, r = xt, Gt, rt
        A = At if At is not None else _residual_and_jacobian(x, p, steps)[1]
    return (np.asarray(x), False, r, max_iter, np.asarray(A),
            f"no convergence in {max_iter} iterations (residual {r:.3g})")


def floquet_multipliers(A) -> np.ndarray:
    """Eigenvalues of the monodromy matrix ``A = ∂P^k/∂x``, largest modulus first."""
    lam = np.linalg.eigvals(np.asarray(A))
    return lam[np.argsort(-np.abs(lam))]


def _start_state(p, n, start, transient):
    if start is None:
        periods = max(1, int(round(transient * float(p.omega) / (2 * math.pi))))
        return np.asarray(_transient(p, jnp.asarray(periods * n)))
    if isinstance(start, Orbit):
        return np.asarray(start.state)
    x = np.asarray(start, float)
    if x.shape != (STATE_SIZE,):
        raise ValueError(f"start: expected a state of shape ({STATE_SIZE},), got {x.shape}")
    return x


def orbit(config: Config, gap: float | None = None, frequency: float | None = None,
          k_max: int = 4, *, start=None, transient: float = 3.0, tol: float = TOL,
          margin: float = STABILITY_MARGIN, max_iter: int = 30) -> Orbit:
    """The stable periodic orbit of the smooth S3 model of ``config`` at ``gap`` [m] and
    ``frequency`` [Hz] (defaults: the config's), or the report that there is none.

    Newton (:func:`newton`) on ``P^k(x) = x`` for ``k = 1, ..., k_max`` in turn (``start`` an
    :class:`Orbit`: its ``k`` first), from the state after ``transient`` seconds (rounded to
    whole periods) of the smooth model, or from ``start`` (an :class:`Orbit` or a state
    ``(6,)``). The first ``k`` whose orbit converges and is stable (``max |λ| ≤ 1 - margin``)
    is returned; an orbit of ``P^k`` that is one of ``P^d``, ``d | k``, is reported with
    ``k = d``. If none is, the returned :class:`Orbit` has ``stable = False`` and the reason
    (the last converged-but-unstable orbit if any, else the last attempt)."""
    if config.system != "impact" or config.impactor is None:
        raise ConfigError("periodic.orbit needs an S3 configuration (system = 'impact')")
    p, n = orbit_params(config, frequency, gap)
    x0 = _start_state(p, n, start, transient)
    ks = list(range(1, k_max + 1))
    if isinstance(start, Orbit) and start.k in ks:
        ks.remove(start.k)
        ks.insert(0, start.k)
    scale = np.asarray(state_scale(p))
    attempts, reasons, fallback, total = [], [], None, 0
    for k in ks:
        x, ok, r, its, A, why = newton(x0, p, n, k, tol=tol, max_iter=max_iter)
        total += its
        label = f"k={k}"
        if ok and k > 1:
            for d in range(1, k):
                if k % d == 0 and _scaled(_residual(jnp.asarray(x), p, jnp.asarray(d * n)),
                                           scale) < 1e-6:
                    x, ok, r, its2, A, why = newton(x, p, n, d, tol=tol, max_iter=max_iter)
                    total += its2
                    its += its2
                    label = f"k={k} (an orbit of period {d})"
                    k = d
                    break
        lam = floquet_multipliers(A)
        rho = float(np.max(np.abs(lam)))
        attempts.append((k, ok, r, rho))
        stable = ok and rho <= 1.0 - margin
        if ok and not stable:
            why = f"unstable periodic orbit (max |λ| = {rho:.4g})"
        res = Orbit(state=x, k=k, floquet=lam, stable=stable, converged=ok, residual=r,
                    iterations=its, reason="", params=p, n_steps=n, start=x0,
                    start_distance=_scaled(x - x0, scale), total_iterations=total,
                    attempts=attempts)
        if stable:
            return res
        reasons.append(f"{label}: {why}")
        if ok or fallback is None or not fallback.converged:
            fallback = res
    fallback.reason = "not a stable periodic orbit: " + "; ".join(reasons)
    fallback.stable = False
    fallback.total_iterations = total
    return fallback


def implicit_derivative(orb: Orbit, kind: str, param: str = "gap"):
    """``(J, dJ/dθ, dx*/dθ)`` at a stable orbit: the objective ``kind`` (:data:`KINDS`)
    averaged over the orbit and its derivative with respect to the field ``param`` of
    :class:`~jaxdamp.impact.SmoothParams` by the implicit-function theorem (module
    docstring). ``(nan, nan, nan)`` if ``orb`` is not stable."""
    if kind not in KINDS:
        raise ValueError(f"objective {kind!r}: expected one of {KINDS}")
    if not orb.stable:
        return math.nan, math.nan, np.full(STATE_SIZE, np.nan)
    theta = jnp.asarray(getattr(orb.params, param), dtype=jnp.float64)
    val, jac = _map_and_objective_jacobian(jnp.asarray(orb.state), theta, orb.params,
                                           jnp.asarray(orb.n_steps), jnp.asarray(orb.k),
                                           kind, param)
    jac = np.asarray(jac)
    A, b = jac[:STATE_SIZE, :STATE_SIZE], jac[:STATE_SIZE, STATE_SIZE]
    dx = np.linalg.solve(np.eye(STATE_SIZE) - A, b)
    dJ = float(jac[STATE_SIZE, :STATE_SIZE] @ dx + jac[STATE_SIZE, STATE_SIZE])
    return float(val[STATE_SIZE]), dJ, dx


def objective_and_gradient(config: Config, kind: str, frequency=None, gap: float | None = None,
                           *, param: str = "gap", k_max: int = 4, start=None,
                           transient: float = 3.0, p: float | None = None, **newton_options):
    """``(J, dJ/dθ, orbit)``: the steady-state objective over the periodic orbit and its exact
    derivative w.r.t. ``param`` (default the gap [m]) at ``gap`` and ``frequency``.

    ``kind``: ``"dissipation"`` (impact loss per period [J]), ``"amplitude"`` (first-harmonic
    amplitude of ``z`` [m]) or ``"band"``: the smooth maximum
    :func:`jaxdamp.optimize.smooth_max` (exponent ``p``, default ``BAND_P``) of the amplitudes at
    the frequencies ``frequency`` (a sequence; default that of
    :class:`jaxdamp.optimize.Objective`), one orbit per frequency; ``orbit`` is then the list
    of orbits and ``start`` may be such a list. ``J = dJ = nan`` when there is no stable
    periodic orbit (at any frequency of the band); the orbit's ``reason`` says why."""
    if kind == "band":
        from .optimize import BAND_P, Objective, smooth_max

        freqs = (Objective(kind="band").frequencies(config) if frequency is None
                 else tuple(float(f) for f in np.atleast_1d(frequency)))
        starts = start if isinstance(start, (list, tuple)) else [start] * len(freqs)
        orbs, vals, ders = [], [], []
        for f, s in zip(freqs, starts):
            o = orbit(config, gap, f, k_max, start=s, transient=transient, **newton_options)
            v, d, _ = implicit_derivative(o, "amplitude", param)
            orbs.append(o)
            vals.append(v)
            ders.append(d)
        if not all(o.stable for o in orbs):
            return math.nan, math.nan, orbs
        z = jnp.asarray(vals)
        pp = BAND_P if p is None else p
        J, w = jax.value_and_grad(lambda z: smooth_max(z, pp))(z)
        return float(J), float(np.dot(np.asarray(w), ders)), orbs
    if kind not in KINDS:
        raise ValueError(f"objective {kind!r}: expected one of {KINDS + ('band',)}")
    o = orbit(config, gap, frequency, k_max, start=start, transient=transient, **newton_options)
    J, dJ, _ = implicit_derivative(o, kind, param)
    return J, dJ, o
