"""What drives the system: the base motion of S1 and the prescribed box motion of S2 (docs/physics.md §1).

The base of S1 moves by the sum of three parts, each zero unless configured::

    u(t) = U cos Ωt                                   harmonic (``primary.U``, ``frequency``)
         + Σ_k [c_k cos ω_k t + s_k sin ω_k t]        random: a random-phase multisine
                                                      (``Config.random``, :func:`random_lines`)
         + p(t)                                       shock: a half-sine acceleration pulse
                                                      (``Config.shock``, :func:`shock_pulse`)

**Random base motion** (``Config.random``) is band-limited with a given one-sided base
*acceleration* spectral density ``S_a(f)`` [(m/s²)²/Hz]. It is synthesised as a random-phase
multisine on the lines ``f_k = k Δf`` (``Δf = random.resolution``) inside the spectrum's band:
acceleration amplitude ``A_k = sqrt(2 scale S_a(f_k) Δf)``, phases ``φ_k`` uniform from the seed,
so ``u''(t) = Σ A_k cos(ω_k t + φ_k)`` has the prescribed density at every line, RMS
``sqrt(scale ∫ S_a df)`` and period ``1/Δf``; by the central limit theorem its values are
Gaussian for many lines (Pintelon & Schoukens, *System Identification*, ch. 2). In the base
displacement each line is ``-A_k/ω_k² cos(ω_k t + φ_k)``, stored as ``(ω_k, c_k, s_k)``.

**Shock** (``Config.shock``): a half-sine base acceleration pulse (the shock-test standard),
``u'' = A sin(π τ / T)`` for ``0 ≤ τ = t - t_0 ≤ T``, zero otherwise, from rest: the base
ends the pulse at the velocity ``2 A T / π`` and keeps it (like a shock table's carriage), so
the structure's relative motion ``z - u`` is the response.

Each motion in its JAX form (of :class:`~jaxdamp.physics.model.Params`) and, next to it, its
numba scalar form for the native kernel (:mod:`jaxdamp.engine.native`); ``Ω = 2πf`` [rad/s].

Example::

    import numpy as np
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.physics.excitation import random_lines
    cfg = apply_overrides(presets.get("sanchez2012-optimal"),
                          {"random.psd": [[5.0, 1.0], [30.0, 1.0]], "random.resolution": 0.5})
    lines = random_lines(cfg)                      # (51, 3): ω_k, c_k, s_k
    A = np.hypot(lines[:, 1], lines[:, 2]) * lines[:, 0] ** 2
    assert np.allclose(A, np.sqrt(2 * 1.0 * 0.5))  # acceleration amplitude per line
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

from jaxdamp.physics.contact import scalar_form


def psd_at(psd, f) -> np.ndarray:
    """The one-sided density of the breakpoints ``psd`` ``[[f_1, S_1], …]`` (``f`` increasing)
    at the frequencies ``f`` [Hz]: linear between breakpoints, zero outside ``[f_1, f_n]``."""
    table = np.asarray(psd, dtype=np.float64).reshape(-1, 2)
    f = np.asarray(f, dtype=np.float64)
    inside = (f >= table[0, 0]) & (f <= table[-1, 0])
    return np.where(inside, np.interp(f, table[:, 0], table[:, 1]), 0.0)


def random_seed(config) -> int:
    """The seed of the random base motion's phases: ``random.seed``, or the bed's seed
    (``numerics.seed``) when it is ``None`` — then every independently poured bed of a
    replicated study also meets its own realisation of the excitation."""
    rnd = config.random
    return int(config.numerics.seed if rnd.seed is None else rnd.seed)


def random_lines(config) -> np.ndarray:
    """The lines of the random base motion, ``(L, 3)`` rows ``(ω_k [rad/s], c_k [m], s_k [m])``
    with ``u_random(t) = Σ c_k cos ω_k t + s_k sin ω_k t`` (module docstring). One zero line
    ``(0, 0, 0)`` when ``config.random`` is ``None`` or the band holds no line, so that every
    configuration has at least one (fixed-shape ``Params``)."""
    rnd = getattr(config, "random", None)
    if rnd is None or config.system != "primary":
        return np.zeros((1, 3))
    df = float(rnd.resolution)
    table = np.asarray(rnd.psd, dtype=np.float64).reshape(-1, 2)
    k = np.arange(max(1, math.ceil(table[0, 0] / df - 1e-9)),
                  math.floor(table[-1, 0] / df + 1e-9) + 1)
    f = k * df
    amp = np.sqrt(2.0 * rnd.scale * psd_at(table, f) * df)  # acceleration amplitudes [m/s²]
    keep = amp > 0
    if not keep.any():
        return np.zeros((1, 3))
    phase = np.random.default_rng(random_seed(config)).uniform(0.0, 2.0 * math.pi, len(f))
    w, amp, phase = 2.0 * math.pi * f[keep], amp[keep], phase[keep]
    disp = -amp / w**2  # u_k = -A_k/ω_k² cos(ω_k t + φ_k) = c cos ω_k t + s sin ω_k t
    return np.stack([w, disp * np.cos(phase), -disp * np.sin(phase)], axis=1)


def random_start(config) -> tuple[np.ndarray, np.ndarray]:
    """The empty structure's steady response to the random lines at ``t = 0``: displacements
    [m] and velocities [m/s] ``(n,)`` of its degrees of freedom (user order; ``n = 1`` for the
    1-DOF primary), ``Σ_k Re[X_k (c_k - i s_k)]`` with ``X_k = (K - ω_k² M + iω_k C)⁻¹ (K +
    iω_k C) r`` (:func:`jaxdamp.physics.structure.matrices`). The structure starts there, so
    that a random test of the empty box has no start-up transient and a damper's is small;
    zeros without random lines."""
    from jaxdamp.physics.structure import matrices

    if config.system != "primary":
        return np.zeros(1), np.zeros(1)
    M, K, C, r, _ = matrices(config)
    if getattr(config, "random", None) is None:
        return np.zeros(len(M)), np.zeros(len(M))
    x = np.zeros(len(M), complex)
    xd = np.zeros(len(M), complex)
    for w, c, s in random_lines(config):
        X = np.linalg.solve(K - w * w * M + 1j * w * C, (K + 1j * w * C) @ r) * (c - 1j * s)
        x += X
        xd += 1j * w * X
    return x.real, xd.real


def shock_pulse(t, a, t0, T):
    """Displacement [m], velocity [m/s] of the half-sine base acceleration pulse of peak ``a``
    [m/s²], start ``t0`` and duration ``T`` [s] (zero before; constant velocity after).
    Elementwise (JAX); ``T = 0`` means no pulse."""
    Ts = jnp.where(T > 0, T, 1.0)
    tau = jnp.clip(t - t0, 0.0, Ts)  # time spent in the pulse
    k = math.pi / Ts
    v = a / k * (1.0 - jnp.cos(k * tau))
    x = a / k * (tau - jnp.sin(k * tau) / k)
    after = jnp.maximum(t - t0 - Ts, 0.0)
    on = T > 0
    return jnp.where(on, x + v * after, 0.0), jnp.where(on, v, 0.0)


def harmonic_base(t, U, omega):
    """The harmonic base motion ``u = U cos Ωt`` [m], ``u' = -U Ω sin Ωt`` [m/s] (JAX; also
    the S3 models' base)."""
    ph = omega * t
    return U * jnp.cos(ph), -U * omega * jnp.sin(ph)


def base_motion(t, p):
    """Base displacement ``u`` [m] and velocity ``u'`` [m/s] of S1 at time ``t`` for the
    :class:`~jaxdamp.physics.model.Params` ``p`` (module docstring): harmonic + random lines +
    shock pulse."""
    uh, vh = harmonic_base(t, p.U, p.omega)
    wt = p.lines[..., 0] * t
    c, s = jnp.cos(wt), jnp.sin(wt)
    xs, vs = shock_pulse(t, p.shock_a, p.shock_t0, p.shock_T)
    u = uh + jnp.sum(p.lines[..., 1] * c + p.lines[..., 2] * s, axis=-1) + xs
    ud = vh + jnp.sum(p.lines[..., 0] * (p.lines[..., 2] * c - p.lines[..., 1] * s), axis=-1) + vs
    return u, ud


@scalar_form
def harmonic_base_scalar(t, U, omega):
    """Scalar form of :func:`harmonic_base`: ``(u, u')`` at time ``t`` [s] (also the
    event-driven S3 model's base)."""
    ph = omega * t
    return U * math.cos(ph), -U * omega * math.sin(ph)


@scalar_form
def base_motion_scalar(t, U, omega, lines, shock_a, shock_t0, shock_T):
    """Scalar form of :func:`base_motion`: ``(u, u')`` at time ``t`` [s]; ``lines`` ``(L, 3)``."""
    u, ud = harmonic_base_scalar(t, U, omega)
    for k in range(lines.shape[0]):
        if lines[k, 1] == 0.0 and lines[k, 2] == 0.0:
            continue  # the zero line of a run without random motion: no trig per step
        w = lines[k, 0]
        c = math.cos(w * t)
        s = math.sin(w * t)
        u += lines[k, 1] * c + lines[k, 2] * s
        ud += w * (lines[k, 2] * c - lines[k, 1] * s)
    if shock_T > 0.0:
        tau = min(max(t - shock_t0, 0.0), shock_T)
        k = math.pi / shock_T
        v = shock_a / k * (1.0 - math.cos(k * tau))
        u += shock_a / k * (tau - math.sin(k * tau) / k) + v * max(t - shock_t0 - shock_T, 0.0)
        ud += v
    return u, ud


def drive_motion(t, p):
    """Box position ``z_offset + A_d cos Ωt`` [m], velocity [m/s], acceleration [m/s²] of S2."""
    ph = p.omega * t
    c, s = jnp.cos(ph), jnp.sin(ph)
    return (
        p.z_offset + p.amplitude * c,
        -p.amplitude * p.omega * s,
        -p.amplitude * p.omega**2 * c,
    )


@scalar_form
def drive_motion_scalar(t, z_offset, amplitude, omega):
    """Scalar form of :func:`drive_motion`: ``(z, z', z'')`` at time ``t`` [s]."""
    ph = omega * t
    c = math.cos(ph)
    return z_offset + amplitude * c, -amplitude * omega * math.sin(ph), -amplitude * omega**2 * c

