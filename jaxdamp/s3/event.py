"""S3, event-driven: exact up to round-off (numba), see :mod:`jaxdamp.s3.impact`."""

from __future__ import annotations

import math

import numba
import numpy as np

from jaxdamp.analysis.response import analysis_start
from jaxdamp.config import Config
from jaxdamp.physics.excitation import harmonic_base_scalar
from jaxdamp.s3.common import (
    ImpactRun,
    _add_energy,
    _check,
    collide,
    n_records,
    sample_interval,
    summarize,
)

_collide = numba.njit(cache=True)(collide)

_T0, _X0, _XD0, _Y0, _W0, _AL, _W2, _W0SQ, _ZR, _ZI, _ZC, _OM, _GAP, _G = range(14)

_FREE, _FLOOR, _LID = 0, 1, 2

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
            u, ud = harmonic_base_scalar(s, U, Om)
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
            rec[ri, 5] = harmonic_base_scalar(t, U, Om)[0]
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
        u, ud = harmonic_base_scalar(t, U, Om)
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
