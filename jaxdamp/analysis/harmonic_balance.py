"""The damper's map inserted into a structure by harmonic balance (issue 40, item 2): the
structure's response predicted from the isolated damper's effective fields
(:mod:`jaxdamp.studies.maps`), without simulating the coupled system.

A linear structure ``M x'' + C (x' − r u') + K (x − r u) = e_a F + b cos Ωt`` (the 1-DOF
primary is ``n = 1``, :func:`jaxdamp.physics.structure.matrices`) carries the damper on degree
of freedom ``a``. With every motion harmonic, ``x = Re(X e^{iΩt})``, ``u = U cos Ωt``, and the
grains' force replaced by its first harmonic at the damper's amplitude ``|X_a|``,
``F̂ = (m_eff Ω² − i Ω c_eff) X_a`` (the map at ``(|X_a|, f)``)::

    [K − Ω² M + i Ω C + e_a e_aᵀ (−Ω² m_eff(|X_a|, f) + i Ω c_eff(|X_a|, f))] X
        = (K + i Ω C) r U + b.

The solution is consistent where the amplitude the damper was evaluated at is the one it gets:
``g(A) = |X_a(A)| − A = 0``. :func:`solve` scans ``g`` over the map's amplitude range (log
spaced, every node of the map included) and refines each sign change (Brent): one root is the
response; several are the branches of a multi-valued response (a jump: the middle one of three
is the unstable one of a softening or hardening curve); none inside the range says whether the
response lies below or above it (the map does not reach it: no extrapolation). The map is
interpolated linearly in ``log A`` and in ``f`` between its nodes.

Uncertainty comes from the map's beds: each bed's map is balanced on its own
(:func:`predict`), and the response where every bed has one root is reported as mean ± SE over
them.

Example (a map constant in amplitude is a linear added mass and damper: the prediction is the
linear structure's response with ``M + m``, ``C + c``)::

    import numpy as np
    A, f = np.array([1e-3, 1e-1]), np.array([10.0])
    m, c = np.full((2, 1), 0.2), np.full((2, 1), 5.0)
    M, K, C = (np.array([[v]]) for v in (2.0, 2e4, 10.0))
    solve(A, m, c, 10.0, M, K, C, np.ones(1), np.zeros(1), U=1e-3, attach=0).roots
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: Points of the scan of ``g`` between the map's smallest and largest amplitude (the map's
#: nodes are added).
SCAN = 400


@dataclass(frozen=True)
class Balance:
    """The harmonic balance at one frequency: ``roots`` the consistent damper amplitudes [m]
    (ascending; several: a multi-valued response), ``where`` ``"inside"`` (at least one root),
    ``"below"`` or ``"above"`` (none: the response lies outside the map's amplitudes, on that
    side), ``"outside"`` (the frequency lies outside the map's)."""

    roots: tuple
    where: str

    @property
    def single(self) -> float:
        """The response where it is one root, else NaN."""
        return float(self.roots[0]) if len(self.roots) == 1 else math.nan


def _interp(A, table, f_map, f):
    """``table`` ``(A, F)`` at frequency ``f`` (linear between the map's frequencies): a
    function of the amplitude, linear in ``log A`` (NaN outside ``A``'s range)."""
    j = np.searchsorted(f_map, f)
    if np.isclose(f, f_map).any():
        col = table[:, int(np.argmin(np.abs(f_map - f)))]
    else:
        w = (f - f_map[j - 1]) / (f_map[j] - f_map[j - 1])
        col = (1.0 - w) * table[:, j - 1] + w * table[:, j]
    la = np.log(A)
    return lambda a: np.interp(np.log(a), la, col, left=np.nan, right=np.nan)


def solve(amplitudes, m_eff, c_eff, frequency: float, M, K, C, r, b, U: float,
          attach: int = 0, frequencies=None) -> Balance:
    """The harmonic balance at ``frequency`` [Hz] (module docstring) of the damper's map
    ``m_eff``, ``c_eff`` ``(A, F)`` [kg, N s/m] over ``amplitudes`` ``(A,)`` [m] and
    ``frequencies`` ``(F,)`` [Hz] (default: the one ``frequency``, ``F = 1``) on the structure
    ``M, K, C, r, b`` (:func:`jaxdamp.physics.structure.matrices`) with base amplitude ``U``
    [m], the damper on degree of freedom ``attach``."""
    from scipy.optimize import brentq

    A = np.asarray(amplitudes, float)
    f_map = np.atleast_1d(np.asarray(frequency if frequencies is None else frequencies, float))
    m_eff, c_eff = (np.asarray(x, float).reshape(len(A), len(f_map)) for x in (m_eff, c_eff))
    if not f_map.min() - 1e-9 <= frequency <= f_map.max() + 1e-9:
        return Balance((), "outside")
    order, cols = np.argsort(A), np.argsort(f_map)  # nodes ascending, as interpolation needs
    A, f_map = A[order], f_map[cols]
    m_eff, c_eff = m_eff[order][:, cols], c_eff[order][:, cols]
    m_of, c_of = _interp(A, m_eff, f_map, frequency), _interp(A, c_eff, f_map, frequency)
    W = 2.0 * math.pi * frequency
    M, K, C = (np.atleast_2d(np.asarray(x, float)) for x in (M, K, C))
    D0 = K - W * W * M + 1j * W * C
    rhs = (K + 1j * W * C) @ np.asarray(r, float) * U + np.asarray(b, float)

    def g(a):
        D = D0.copy()
        D[attach, attach] += -W * W * m_of(a) + 1j * W * c_of(a)
        return abs(np.linalg.solve(D, rhs)[attach]) - a

    grid = np.union1d(np.geomspace(A[0], A[-1], SCAN), A) if len(A) > 1 else A
    G = np.array([g(a) for a in grid])
    roots = []
    for k in np.flatnonzero(G == 0.0):
        roots.append(float(grid[k]))
    for k in np.flatnonzero(G[:-1] * G[1:] < 0):
        roots.append(float(brentq(g, grid[k], grid[k + 1], xtol=1e-14 * grid[k], rtol=1e-12)))
    if roots:
        return Balance(tuple(sorted(roots)), "inside")
    return Balance((), "below" if G[0] < 0 else "above")


def predict(field, config, frequencies=None) -> dict:
    """The response of ``config``'s structure (its primary, or ``structure`` with the damper
    on ``structure.attach``; base amplitude ``primary.U``) carrying the damper of the map
    ``field`` (:class:`jaxdamp.studies.maps.EffectiveField`), per bed of the map, at
    ``frequencies`` [Hz] (default: the map's).

    Returns ``{"frequency" (F,), "balances": [[Balance] * F] * R, "amplitude" (F, R)`` (the
    single root, else NaN), ``"mean"``, ``"se"`` (F,) (over the beds, where every bed has a
    single root), ``"branches"`` (F, R) (how many roots), ``"where"`` (F, R)}."""
    from jaxdamp.physics.structure import attachments, matrices

    M, K, C, r, b = matrices(config)
    a = attachments(config)[0]
    U = config.primary.U if config.primary is not None else 0.0
    fs = np.asarray(field.frequencies if frequencies is None else frequencies, float)
    bal = [[solve(field.amplitudes, field.values["m_eff"][..., k],
                  field.values["c_eff"][..., k], float(f), M, K, C, r, b, U, a,
                  field.frequencies) for f in fs] for k in range(field.replicates)]
    Z = np.array([[x.single for x in row] for row in bal]).T  # (F, R)
    ok = np.all(np.isfinite(Z), axis=1)
    from jaxdamp.analysis.uncertainty import standard_error

    mean = np.where(ok, np.nanmean(np.where(ok[:, None], Z, 0.0), axis=1), np.nan)
    se = np.where(ok, standard_error(np.where(ok[:, None], Z, 0.0), axis=1), np.nan)
    return dict(frequency=fs, balances=bal, amplitude=Z, mean=mean, se=se,
                branches=np.array([[len(x.roots) for x in row] for row in bal]).T,
                where=np.array([[x.where for x in row] for row in bal]).T)
