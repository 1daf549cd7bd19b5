"""S3: the single-particle impact damper (SPEC §1 S3; thesis §2.1.3, §5.3.2).

The whole bed is replaced by one point mass ``m`` that moves vertically between the floor
(``y = z``) and the lid (``y = z + gap``) of the box, which is the primary ``M`` on the spring
``K`` and damper ``C`` of S1, driven through the base ``u = U cos Ωt``. ``z = 0`` is the static
equilibrium of the empty box, so gravity ``g`` acts on the particle only. SI units throughout.

Two models of the same system:

* **Event-driven** (:func:`simulate_event`), exact up to round-off. Collisions are instants
  (:func:`collide`, restitution ``e``, momentum conserved). Between events every motion is in
  closed form: the particle flies on a parabola, the primary obeys
  ``M_ef z'' = -C(z' - u') - K(z - u) + F0`` (free: ``M_ef = M, F0 = 0``; particle resting on
  the floor or pressed against the lid: ``M_ef = M + m, F0 = -m g``), i.e. homogeneous
  (under-, critically or over-damped) + particular harmonic + constant. Events (impacts, lift
  off) are roots of smooth gap / contact-force functions, bracketed by sampling every
  ``min(1/f, 2π sqrt(M/K)) / 64`` (with a check of every local minimum between samples, so
  grazing contacts are not skipped) and refined by Brent's method to ~1e-14 s. The particle
  leaves the floor when ``z'' < -g`` and the lid when ``z'' > -g``. For ``e > 0`` the
  geometric series of ever smaller bounces (inelastic collapse, "chattering") is cut: when the
  relative speed after an impact is below ``impactor.stick_speed`` and the contact force
  would be compressive, the particle sticks (a perfectly inelastic impact; its small extra
  loss ``½ m/(1+m/M) v_rel²`` is booked as impact loss so the energy balance still closes).
  Work integrals use 8-point Gauss–Legendre on sub-intervals ≤ 1/64 of the fastest period,
  which is exact to round-off for these analytic integrands. Compiled with numba.

* **Smooth** (:func:`smooth_run`), for ``jax.grad``: the particle is a point mass with
  penalty contacts (linear spring-dashpot, force clipped ≥ 0, onset smoothed over a length
  ``smooth_width`` by a softplus/sigmoid so that the trajectory is a smooth function of the
  parameters), integrated by velocity Verlet with a fixed step in a jitted ``lax.scan`` and
  batched with ``vmap``. The dashpot's damping ratio ``ζ`` is calibrated
  (:func:`contact_damping_ratio`) so that a free binary collision of the clipped law has
  restitution ``e`` (clamped to ``≥ SMOOTH_E_MIN``: a clipped linear dashpot cannot reach
  ``e = 0``); the stiffness follows from the contact duration ``impactor.contact_time``.
  Defaults, from measurements on the thesis case (``sanchez2012-impact``, e = 0):
  ``contact_time = 3e-4 s`` (1e-3 s is too soft: with the strongly over-damped dashpot the
  particle creeps out of the wall for ~18 contact times and the response at 16.6 Hz became
  irregular, +24 %), 20 steps per contact (dt ≈ 1.5e-5 s; balance error ~1e-6), and
  ``smooth_width = 3e-5 m``: the onset must span a few steps at typical impact speeds
  (w ≳ v dt), else the tangent dynamics explode (1e-6 m: d z/d gap grew ×10 per 0.1 s;
  1e-5 m still diverged; 3e-5 m bounded) although the forward run is fine. Measured
  agreement with the event-driven model: amplitude within 1 % around resonance
  (14.5–16.6 Hz), within 3.5 % over 5–25 Hz except in irregular (non-periodic) responses,
  where the windowed amplitude itself fluctuates by ±5 % (6 % at 20.8 Hz).

Every run starts with the particle resting on the floor and the box at rest at the static
equilibrium ``z = -m g/K``.

Both return the summary of the DEM sweeps (:func:`summarize`): ``amplitude`` (half
peak-to-peak of ``z`` over the analysis window), ``amplitude_ratio``, ``phase``,
``granular_loss_per_cycle`` (= impact loss per drive period), ``input_per_cycle``,
``primary_damping_per_cycle``, ``balance_error``, ``window_start``, ``window_cycles`` plus
``impacts_per_cycle``. Work channels (:data:`CHANNELS`): ``input`` (base through spring and
damper), ``primary_damping`` (loss in C), ``impact`` (dissipated at impacts / in the contact).
Energy ``E = ½ M z'² + ½ m y'² + ½ K (z - u)² + m g y (+ ½ k s² of the penalty springs)``; the
balance ``W_input = E - E(0) + W_primary_damping + W_impact``.

Note on the collision law: SPEC §1 and thesis eq. 2.1.26 print ``v_p+ = ((1 - e) v_z- + ...)``;
momentum conservation (and the thesis' own code, appendix B) need ``(1 + e) v_z-``, used here.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass

import jax
import jax.numpy as jnp
import numba
import numpy as np

from jaxdamp.analysis.response import analysis_start, first_harmonic
from jaxdamp.config import Config, ConfigError
from jaxdamp.physics.excitation import base_motion, base_motion_scalar
from jaxdamp.physics.model import pytree_dataclass

#: Work channels of S3 records, columns of ``work``.
CHANNELS = ("input", "primary_damping", "impact")
#: Smallest restitution the smooth contact is calibrated to (``e`` below it uses this value).
SMOOTH_E_MIN = 0.005

RECORD_UNITS = {
    "t": "s",
    "z_box": "m",
    "v_box": "m/s",
    "z_particle": "m",
    "v_particle": "m/s",
    "u": "m",
    "work": "J",
    "energy": "J",
    "balance_residual": "J",
}

SUMMARY_UNITS = {
    "amplitude": "m",
    "amplitude_ratio": "1",
    "phase": "rad",
    "granular_loss_per_cycle": "J",
    "input_per_cycle": "J",
    "primary_damping_per_cycle": "J",
    "impact_per_cycle": "J",
    "impacts_per_cycle": "1",
    "balance_error": "1",
    "window_start": "s",
    "window_cycles": "1",
}


# ---------------------------------------------------------------------------------------------
# the collision law


def collide(v_p, v_z, m, M, e):
    """Velocities just after an impact of particle and box (thesis eqs. 2.1.25–26, SPEC §1 S3).

    Momentum ``m v_p + M v_z`` is conserved and the relative velocity reverses with factor
    ``e``: ``v_p+ - v_z+ = -e (v_p- - v_z-)``. Works on floats and (numpy / JAX) arrays.

    Args:
      v_p, v_z: particle and box velocities before the impact [m/s].
      m, M: particle and primary masses [kg]; e: restitution [-].
    Returns:
      ``(v_p+, v_z+)`` [m/s].
    """
    r = m / M
    v_z_new = ((1.0 - e * r) * v_z + r * (1.0 + e) * v_p) / (1.0 + r)
    v_p_new = ((1.0 + e) * v_z + (r - e) * v_p) / (1.0 + r)
    return v_p_new, v_z_new


def impact_loss(v_p, v_z, m, M, e):
    """Kinetic energy dissipated by one impact [J] (thesis eq. 5.3.1):
    ``ΔT = ½ (1 - e²) m/(1 + m/M) (v_p- - v_z-)²``."""
    return 0.5 * (1.0 - e * e) * m / (1.0 + m / M) * (v_p - v_z) ** 2


_collide = numba.njit(cache=True)(collide)

# ---------------------------------------------------------------------------------------------
# event-driven model: closed-form segments (numba)

# ctx layout: the current segment and the constants of its mode.
_T0, _X0, _XD0, _Y0, _W0, _AL, _W2, _W0SQ, _ZR, _ZI, _ZC, _OM, _GAP, _G = range(14)
_FREE, _FLOOR, _LID = 0, 1, 2
# event-function kinds
_K_FLOOR_GAP, _K_LID_GAP, _K_FLOOR_PUSH, _K_LID_PUSH, _K_ZD = 0, 1, 2, 3, 4

_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)


@numba.njit(cache=True)
def _mode_coef(M_ef, K, C, U, Om, F0, out):
    """Constants of ``M_ef z'' + C z' + K z = C u' + K u + F0``: decay ``α = C/2M_ef``,
    ``ω_d² = K/M_ef - α²`` (signed), ``ω0² = K/M_ef``, the complex amplitude
    ``Z = U (K + iCΩ)/(K - M_ef Ω² + iCΩ)`` of the harmonic particular solution
    ``Re(Z e^{iΩt})`` and the static offset ``F0/K``."""
    al = C / (2.0 * M_ef)
    w0sq = K / M_ef
    dr, di = K - M_ef * Om * Om, C * Om
    nr, ni = K * U, C * Om * U
    den = dr * dr + di * di
    out[0] = al
    out[1] = w0sq - al * al
    out[2] = w0sq
    out[3] = (nr * dr + ni * di) / den
    out[4] = (ni * dr - nr * di) / den
    out[5] = F0 / K


@numba.njit(cache=True)
def _box(ctx, t):
    """Box ``z, z', z'', z'''`` at absolute time ``t`` in the current segment (closed form)."""
    tau = t - ctx[_T0]
    al, w2, w0sq = ctx[_AL], ctx[_W2], ctx[_W0SQ]
    x0, xd0 = ctx[_X0], ctx[_XD0]
    q = xd0 + al * x0
    p = al * xd0 + w0sq * x0
    tiny = 1e-12 * w0sq
    if w2 > tiny:  # under-damped
        wd = math.sqrt(w2)
        ex = math.exp(-al * tau)
        cc = ex * math.cos(wd * tau)
        ss = ex * math.sin(wd * tau) / wd
    elif w2 < -tiny:  # over-damped: e^{-αt} cosh(βt), e^{-αt} sinh(βt)/β without overflow
        b = math.sqrt(-w2)
        if b * tau > 1.0:
            ep = math.exp((b - al) * tau)
            em = math.exp(-(al + b) * tau)
            cc = 0.5 * (ep + em)
            ss = 0.5 * (ep - em) / b
        else:
            ex = math.exp(-al * tau)
            cc = ex * math.cosh(b * tau)
            ss = ex * math.sinh(b * tau) / b
    else:  # critically damped
        ex = math.exp(-al * tau)
        cc = ex
        ss = ex * tau
    x = x0 * cc + q * ss
    xd = xd0 * cc - p * ss
    xdd = -2.0 * al * xd - w0sq * x
    xddd = -2.0 * al * xdd - w0sq * xd
    Om = ctx[_OM]
    c, s = math.cos(Om * t), math.sin(Om * t)
    zr, zi = ctx[_ZR], ctx[_ZI]
    zp = zr * c - zi * s
    zpd = -Om * (zr * s + zi * c)
    return (x + zp + ctx[_ZC], xd + zpd, xdd - Om * Om * zp, xddd - Om * Om * zpd)


@numba.njit(cache=True)
def _start_segment(ctx, coef, t0, z0, zd0, y0, w0):
    """Make ``ctx`` the segment starting at ``t0`` from box ``(z0, zd0)``, particle ``(y0, w0)``
    under the mode constants ``coef``."""
    ctx[_T0] = t0
    ctx[_AL], ctx[_W2], ctx[_W0SQ] = coef[0], coef[1], coef[2]
    ctx[_ZR], ctx[_ZI], ctx[_ZC] = coef[3], coef[4], coef[5]
    Om = ctx[_OM]
    c, s = math.cos(Om * t0), math.sin(Om * t0)
    ctx[_X0] = z0 - (coef[3] * c - coef[4] * s) - coef[5]
    ctx[_XD0] = zd0 + Om * (coef[3] * s + coef[4] * c)
    ctx[_Y0] = y0
    ctx[_W0] = w0


@numba.njit(cache=True)
def _fn(kind, ctx, t):
    """Event function of ``kind`` and its time derivative at ``t``. Gaps are ≥ 0 while the
    particle is inside; ``*_PUSH`` (the contact force per unit mass, ``±(z'' + g)``) is ≥ 0 while
    the contact holds."""
    z, zd, zdd, zddd = _box(ctx, t)
    g = ctx[_G]
    tau = t - ctx[_T0]
    y = ctx[_Y0] + ctx[_W0] * tau - 0.5 * g * tau * tau  # the particle's parabola
    yd = ctx[_W0] - g * tau
    if kind == _K_FLOOR_GAP:
        return y - z, yd - zd
    if kind == _K_LID_GAP:
        return z + ctx[_GAP] - y, zd - yd
    if kind == _K_FLOOR_PUSH:
        return zdd + g, zddd
    if kind == _K_LID_PUSH:
        return -(zdd + g), -zddd
    return zd, zdd


@numba.njit(cache=True)
def _brent(kind, deriv, ctx, a, b, fa, fb):
    """Root of the event function (``deriv``: of its derivative) in ``[a, b]`` with
    ``fa * fb ≤ 0``; Brent's method to ~4 ulp of ``t`` (~1e-15 s)."""
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    c, fc = a, fa
    d = e = b - a
    for _ in range(200):
        if fb * fc > 0.0:
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 4.0 * 2.2e-16 * abs(b) + 1e-15
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:
                p = 2.0 * m * s
                q = 1.0 - s
            else:
                q = fa / fc
                r = fb / fc
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * q - abs(tol * q), abs(e * q)):
                e = d
                d = p / q
            else:
                d = m
                e = m
        else:
            d = m
            e = m
        a, fa = b, fb
        if abs(d) > tol:
            b += d
        else:
            b += tol if m > 0 else -tol
        v, dv = _fn(kind, ctx, b)
        fb = dv if deriv else v
    return b


@numba.njit(cache=True)
def _first_event(ctx, k0, k1, t_max, h):
    """First time in ``(t0, t_max]`` where event function ``k0`` (or ``k1``; -1: none) turns
    negative, and which one. Both are ≥ 0 at ``t0`` (the particle just left a wall or a contact
    just began). Sampled every ``h``; between samples a local minimum (derivative − → +) is
    located and tested, so grazing crossings are found too. Returns ``(t, kind)``, or
    ``(inf, -1)`` when nothing happens before ``t_max``."""
    t0 = ctx[_T0]
    n_k = 1 if k1 < 0 else 2
    prev_v = np.zeros(2)
    prev_d = np.zeros(2)
    for j in range(n_k):
        kind = k0 if j == 0 else k1
        v, d = _fn(kind, ctx, t0)
        prev_v[j] = max(v, 0.0)
        prev_d[j] = d
    t_prev = t0
    i = 0
    while t_prev < t_max:
        i += 1
        t = min(t0 + i * h, t_max)
        best, which = math.inf, -1
        for j in range(n_k):
            kind = k0 if j == 0 else k1
            v, d = _fn(kind, ctx, t)
            root = math.inf
            if v < 0.0:
                lo, flo = t_prev, prev_v[j]
                if i == 1:
                    # the function is 0 at t0 itself: probe geometrically toward t0 for a
                    # positive point so that the bracket excludes the root at t0
                    hi, fhi = t, v
                    lo = t0 + 0.5 * (t - t0)
                    flo, _ = _fn(kind, ctx, lo)
                    n = 0
                    while flo <= 0.0 and n < 60:
                        hi, fhi = lo, flo
                        lo = t0 + 0.5 * (lo - t0)
                        flo, _ = _fn(kind, ctx, lo)
                        n += 1
                    if flo <= 0.0:
                        root = t0  # re-contact at once
                    else:
                        root = _brent(kind, False, ctx, lo, hi, flo, fhi)
                else:
                    root = _brent(kind, False, ctx, lo, t, flo, v)
            elif prev_d[j] < 0.0 and d > 0.0 and i > 1:
                tm = _brent(kind, True, ctx, t_prev, t, prev_d[j], d)
                vm, _ = _fn(kind, ctx, tm)
                if vm < 0.0:
                    root = _brent(kind, False, ctx, t_prev, tm, prev_v[j], vm)
            if root < best:
                best, which = root, kind
            prev_v[j] = v
            prev_d[j] = d
        if which >= 0:
            return best, which
        t_prev = t
    return math.inf, -1


@numba.njit(cache=True)
def _integrate(ctx, mode, ta, tb, hq, K, C, U, gap, t_w, rec_dt, n_rec, rec, ri, work,
               ext, gl_x, gl_w):
    """Advance the work integrals over ``[ta, tb]`` of the current segment, write every record
    time in ``(ta, tb]`` into ``rec`` (from index ``ri``) and update the extremes of ``z`` in the
    analysis window ``t ≥ t_w``. Returns the next record index."""
    Om = ctx[_OM]
    t = ta
    while t < tb:
        nxt = min(tb, t + hq)
        if ri <= n_rec:
            tr = ri * rec_dt
            if tr < nxt:
                nxt = tr
        if t < t_w < nxt:
            nxt = t_w
        half, mid = 0.5 * (nxt - t), 0.5 * (nxt + t)
        w_in = 0.0
        w_c = 0.0
        for q in range(gl_x.shape[0]):
            s = mid + half * gl_x[q]
            z, zd, _, _ = _box(ctx, s)
            u, ud = base_motion_scalar(s, U, Om)
            f = K * (z - u) + C * (zd - ud)
            w_in += gl_w[q] * (-f * ud)
            w_c += gl_w[q] * C * (zd - ud) ** 2
        work[0] += half * w_in
        work[1] += half * w_c
        if t >= t_w:  # extremes of z: at the ends, and where z' = 0 inside
            za, zda, _, _ = _box(ctx, t)
            zb, zdb, _, _ = _box(ctx, nxt)
            ext[0] = max(ext[0], za, zb)
            ext[1] = min(ext[1], za, zb)
            if zda * zdb < 0.0:
                tm = _brent(_K_ZD, False, ctx, t, nxt, zda, zdb)
                zm, _, _, _ = _box(ctx, tm)
                ext[0] = max(ext[0], zm)
                ext[1] = min(ext[1], zm)
        t = nxt
        if ri <= n_rec and t == ri * rec_dt:
            z, zd, _, _ = _box(ctx, t)
            if mode == _FREE:
                tau = t - ctx[_T0]
                y = ctx[_Y0] + ctx[_W0] * tau - 0.5 * ctx[_G] * tau * tau
                yd = ctx[_W0] - ctx[_G] * tau
            else:
                y = z + (gap if mode == _LID else 0.0)
                yd = zd
            rec[ri, 0] = t
            rec[ri, 1] = z
            rec[ri, 2] = zd
            rec[ri, 3] = y
            rec[ri, 4] = yd
            rec[ri, 5] = base_motion_scalar(t, U, Om)[0]
            rec[ri, 6] = work[0]
            rec[ri, 7] = work[1]
            rec[ri, 8] = work[2]
            ri += 1
    return ri


@numba.njit(cache=True)
def _event_core(M, K, C, U, Om, m, e, gap, g, v_stick, h, rec_dt, n_rec, t_w, gl_x, gl_w,
                rec, imp, max_events):
    """The event-driven run from the particle resting on the floor at the static equilibrium
    (``z = -m g/K``, at rest) to ``n_rec * rec_dt``. Fills ``rec`` ``(n_rec + 1, 9)`` and up to
    ``len(imp)`` impacts ``(t, loss, wall, v_rel)``. Returns ``(n_impacts, z_max, z_min,
    n_events, status)``; status 0 ok, 1 too many events."""
    coef_free = np.zeros(6)
    coef_stuck = np.zeros(6)
    _mode_coef(M, K, C, U, Om, 0.0, coef_free)
    _mode_coef(M + m, K, C, U, Om, -m * g, coef_stuck)
    mu = m / (1.0 + m / M)
    ctx = np.zeros(14)
    ctx[_OM], ctx[_GAP], ctx[_G] = Om, gap, g
    work = np.zeros(3)
    ext = np.array([-math.inf, math.inf])
    t_end = n_rec * rec_dt
    hq = h
    z0 = -m * g / K
    _start_segment(ctx, coef_stuck, 0.0, z0, 0.0, z0, 0.0)
    mode = _FLOOR
    rec[0, :] = 0.0
    rec[0, 1] = z0
    rec[0, 3] = z0
    rec[0, 5] = U
    ri = 1
    n_imp = 0
    n_ev = 0
    t = 0.0
    status = 0
    while t < t_end:
        if mode == _FREE:
            t_ev, kind = _first_event(ctx, _K_FLOOR_GAP, _K_LID_GAP, t_end, h)
        elif mode == _FLOOR:
            t_ev, kind = _first_event(ctx, _K_FLOOR_PUSH, -1, t_end, h)
        else:
            t_ev, kind = _first_event(ctx, _K_LID_PUSH, -1, t_end, h)
        tb = min(t_ev, t_end)
        ri = _integrate(ctx, mode, t, tb, hq, K, C, U, gap, t_w, rec_dt, n_rec, rec, ri, work,
                        ext, gl_x, gl_w)
        if t_ev >= t_end:
            break
        n_ev += 1
        if n_ev > max_events:
            status = 1
            break
        t = t_ev
        z, zd, _, _ = _box(ctx, t)
        u, ud = base_motion_scalar(t, U, Om)
        if mode != _FREE:  # lift-off: the particle keeps the box's velocity and flies
            y = z + (gap if mode == _LID else 0.0)
            _start_segment(ctx, coef_free, t, z, zd, y, zd)
            mode = _FREE
            continue
        tau = t - ctx[_T0]
        vp = ctx[_W0] - g * tau
        lid = kind == _K_LID_GAP
        y = z + (gap if lid else 0.0)
        vp_new, vz_new = _collide(vp, zd, m, M, e)
        loss = 0.5 * (1.0 - e * e) * mu * (vp - zd) ** 2
        v_rel = vp_new - vz_new
        new_mode = _FREE
        if abs(v_rel) <= v_stick:
            # chattering cut-off: stick if the contact would be compressive
            V = (M * vz_new + m * vp_new) / (M + m)
            push = (-C * (V - ud) - K * (z - u) - m * g) / (M + m) + g
            if (push > 0.0 and not lid) or (push < 0.0 and lid):
                loss += 0.5 * mu * v_rel * v_rel
                vp_new = vz_new = V
                new_mode = _LID if lid else _FLOOR
        work[2] += loss
        if n_imp < imp.shape[0]:
            imp[n_imp, 0] = t
            imp[n_imp, 1] = loss
            imp[n_imp, 2] = 1.0 if lid else 0.0
            imp[n_imp, 3] = vp - zd
        n_imp += 1
        mode = new_mode
        _start_segment(ctx, coef_free if mode == _FREE else coef_stuck, t, z, vz_new, y, vp_new)
    return n_imp, ext[0], ext[1], n_ev, status


@dataclass
class ImpactRun:
    """One S3 run. ``records``: sampled series ``(T,)`` (``work`` ``(T, 3)``, columns
    :data:`CHANNELS`); ``impacts``: ``{"t", "loss", "wall" (0 floor, 1 lid), "v_rel"}`` arrays
    ``(I,)`` (event-driven only); ``summary`` and ``units``: :func:`summarize`."""

    records: dict
    impacts: dict
    summary: dict
    units: dict


def _check(config: Config) -> None:
    if config.system != "impact" or config.impactor is None or config.primary is None:
        raise ConfigError("the impact model needs system = 'impact' with [primary] and [impactor]")


def sample_interval(config: Config) -> float:
    """Bracketing interval [s] of the event search: 1/64 of the shorter of the drive period and
    the primary's undamped period (free), which resolves every sign change of the gap and force
    functions, whose fastest components oscillate at those periods."""
    p = config.primary
    return min(1.0 / config.frequency, 2 * math.pi * math.sqrt(p.M / p.K)) / 64.0


def n_records(config: Config) -> int:
    """Samples after t = 0: the run covers ``n_records * record_dt`` ≈ ``duration``."""
    return max(1, int(round(config.numerics.duration / config.numerics.record_dt)))


def simulate_event(config: Config, max_events: int = 10_000_000) -> ImpactRun:
    """The event-driven S3 run of ``config`` (see the module docstring); numba, one core."""
    _check(config)
    p, im, num = config.primary, config.impactor, config.numerics
    n_rec = n_records(config)
    duration = n_rec * num.record_dt
    t_w = analysis_start(config, duration)
    cap = max(1024, int(8 * config.frequency * duration))
    while True:
        rec = np.full((n_rec + 1, 9), np.nan)
        imp = np.zeros((cap, 4))
        n_imp, zmax, zmin, n_ev, status = _event_core(
            p.M, p.K, p.C, p.U, config.omega, im.mass, im.restitution, im.gap, config.gravity,
            im.stick_speed, sample_interval(config), num.record_dt, n_rec, t_w, _GL_X, _GL_W,
            rec, imp, max_events)
        if n_imp <= cap:
            break
        cap = int(n_imp * 1.2) + 16
    if status != 0:
        raise FloatingPointError(f"impact model: more than {max_events} events "
                                 f"(f = {config.frequency} Hz); raise impactor.stick_speed")
    records = {"t": rec[:, 0], "z_box": rec[:, 1], "v_box": rec[:, 2], "z_particle": rec[:, 3],
               "v_particle": rec[:, 4], "u": rec[:, 5], "work": rec[:, 6:9].copy()}
    _add_energy(config, records, contact_energy=None)
    impacts = {"t": imp[:n_imp, 0].copy(), "loss": imp[:n_imp, 1].copy(),
               "wall": imp[:n_imp, 2].astype(np.int8), "v_rel": imp[:n_imp, 3].copy()}
    summary, units = summarize(config, records, zmax, zmin, t_w, impacts["t"])
    return ImpactRun(records=records, impacts=impacts, summary=summary, units=units)


def _add_energy(config: Config, records: dict, contact_energy) -> None:
    """Mechanical energy and the balance residual ``E - E(0) + losses - input`` per sample."""
    p, m, g = config.primary, config.impactor.mass, config.gravity
    z, vz, y, vy, u = (records[k] for k in ("z_box", "v_box", "z_particle", "v_particle", "u"))
    energy = 0.5 * p.M * vz**2 + 0.5 * m * vy**2 + 0.5 * p.K * (z - u) ** 2 + m * g * y
    if contact_energy is not None:
        energy = energy + contact_energy
    w = records["work"]
    records["energy"] = energy
    records["balance_residual"] = energy - energy[0] + w[:, 1] + w[:, 2] - w[:, 0]


def summarize(config: Config, records: dict, z_max: float, z_min: float, t_window: float,
              impact_times=None) -> tuple[dict, dict]:
    """Steady-state scalars over the analysis window (as the DEM's
    :func:`jaxdamp.analysis.response.steady_state_summary`) and their units.

    ``z_max``, ``z_min``: extremes of ``z`` over ``t ≥ t_window`` (exact for the event-driven
    model, every step for the smooth one). Energies per drive period ``1/f``; ``balance_error``
    is the largest ``|residual|`` over the run over ``|input| + losses`` at its end;
    ``impacts_per_cycle`` counts impacts in the window (event-driven; NaN otherwise)."""
    t = records["t"]
    i0 = min(int(np.searchsorted(t, t_window - 1e-12)), len(t) - 1)
    w = records["work"]
    span = t[-1] - t[i0]
    cycles = span * config.frequency if span > 0 else np.nan
    s = {}
    s["amplitude"] = float(0.5 * (z_max - z_min))
    s["amplitude_ratio"] = s["amplitude"] / config.primary.U if config.primary.U > 0 else np.nan
    _, s["phase"] = first_harmonic(t[i0:], records["z_box"][i0:], config.frequency)
    per = (w[-1] - w[i0]) / cycles
    s["granular_loss_per_cycle"] = float(per[2])
    s["input_per_cycle"] = float(per[0])
    s["primary_damping_per_cycle"] = float(per[1])
    s["impact_per_cycle"] = float(per[2])
    if impact_times is None:
        s["impacts_per_cycle"] = np.nan
    else:
        n = np.count_nonzero((impact_times > t[i0]) & (impact_times <= t[-1]))
        s["impacts_per_cycle"] = float(n / cycles)
    scale = abs(w[-1, 0]) + w[-1, 1] + w[-1, 2]
    resid = float(np.max(np.abs(records["balance_residual"])))
    s["balance_error"] = resid / scale if scale > 0 else resid
    s["window_start"] = float(t[i0])
    s["window_cycles"] = float(cycles)
    return s, dict(SUMMARY_UNITS)


# ---------------------------------------------------------------------------------------------
# smooth model (JAX): penalty contacts, fixed step, differentiable


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
    u, ud = base_motion(t, p)
    f_floor, _ = _contact(z - y, vz - vy, p)
    f_lid, _ = _contact(y - z - p.gap, vy - vz, p)
    spring = p.K * (z - u) + p.C * (vz - ud)
    az = (-spring - f_floor + f_lid) / p.M
    ay = (f_floor - f_lid) / p.m - p.g
    return az, ay, f_floor, f_lid


def _primary_power(z, vz, t, p: SmoothParams):
    """Power input by the base through spring and damper, and the power lost in C [W]."""
    u, ud = base_motion(t, p)
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
    u, _ = base_motion(st.i * p.dt, p)
    return (0.5 * p.M * st.vz**2 + 0.5 * p.m * st.vy**2 + 0.5 * p.K * (st.z - u) ** 2
            + p.m * p.g * st.y + _elastic(st.z, st.y, p))


def _sample(st: SmoothState, p: SmoothParams) -> dict:
    t = st.i * p.dt
    return {"t": t, "z_box": st.z, "v_box": st.vz, "z_particle": st.y, "v_particle": st.vy,
            "u": base_motion(t, p)[0], "work": st.work, "energy": smooth_energy(st, p)}


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


def simulate(config: Config) -> ImpactRun:
    """One S3 run with ``impactor.method`` (``"event"`` or ``"smooth"``)."""
    _check(config)
    if config.impactor.method == "smooth":
        return simulate_smooth([config])[0]
    return simulate_event(config)


# ---------------------------------------------------------------------------------------------
# sweeps (called by jaxdamp.studies.sweep.sweep for S3 configurations)


def sweep(config: Config, axes: dict, out: str | None = None, progress: bool = True,
          echo=print):
    """The S3 counterpart of :func:`jaxdamp.studies.sweep.sweep`: same grid, same
    :class:`~jaxdamp.studies.grid.SweepResult`, same HDF5 layout (``/summary``, ``/axes``,
    ``/records`` ``(P, T)``). ``"smooth"`` runs all points as one ``vmap`` batch; ``"event"``
    loops over them (numba; one core each)."""
    from jaxdamp.io.sweepfile import SweepFile
    from jaxdamp.studies.grid import SweepResult, grid_configs

    for key in axes:
        if key.startswith(("box.", "grains")):
            raise ConfigError(f"sweep axis {key!r}: the impact model (S3) does not use the box or "
                              "grains; sweep impactor.gap, impactor.mass, impactor.restitution, "
                              "primary.*, frequency")
    configs = grid_configs(config, axes)
    method = configs[0].impactor.method
    say = echo or (lambda *a, **k: None)
    wall0 = time.perf_counter()
    if method == "smooth":
        say(f"impact model (smooth): {len(configs)} points in one batch")
        runs = simulate_smooth(configs)
        dt = smooth_schedule(configs)[0]
    else:
        bar = None
        if progress:
            from tqdm.auto import tqdm

            bar = tqdm(total=len(configs), unit="point", desc="impact model (event-driven)")
        runs = []
        for c in configs:
            runs.append(simulate_event(c))
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
        dt = 0.0
    wall = time.perf_counter() - wall0
    shape = tuple(len(v) for v in axes.values())
    summary = {k: np.array([r.summary[k] for r in runs]).reshape(shape) for k in runs[0].summary}
    summary["wall_time"] = wall
    records = {k: np.stack([r.records[k] for r in runs]) for k in runs[0].records}
    n_rec = records["t"].shape[1] - 1
    duration = n_rec * configs[0].numerics.record_dt
    if out:
        sf = SweepFile.create(out, config, axes, configs, dt, duration, f"impact-{method}")
        sf.write_summary(summary, SUMMARY_UNITS)
        sf.write_records(records, RECORD_UNITS, channels=CHANNELS)
        if method == "event":
            ig = sf.h5.create_group("impacts")
            for i, r in enumerate(runs):
                g = ig.create_group(str(i))
                for k, v in r.impacts.items():
                    g.create_dataset(k, data=v)
        sf.finish(wall)
        sf.close()
    return SweepResult(axes=axes, configs=configs, summary=summary, records=records, path=out)
