"""Multi-degree-of-freedom primary structures (S1 with ``Config.structure``; issue 16).

A linear structure of ``n`` degrees of freedom ``x`` (displacements along the excitation axis
``e``) carries the damper's box on one of them, ``x_a`` (``structure.attach``). With the base
moving by ``u(t)`` (:mod:`jaxdamp.physics.excitation`) through the influence vector ``r``
(default all ones: the whole structure stands on the moving base) and a harmonic force
``F0 cos Ωt`` on one degree of freedom ``x_m`` (``structure.force``, ``force_dof``)::

    M x'' + C (x' - r u') + K (x - r u) = e_a F_gz + b cos Ωt,      b = F0 e_m

``F_gz`` is the grains' force on the box (as for the 1-DOF primary, docs/physics.md §1, which is
the case ``n = 1``, ``M, K, C`` scalars, ``r = 1``, ``F0 = 0``). The structure is given either
by its matrices ``M, K, C`` (symmetric; ``M`` positive definite, ``K`` and ``C`` positive
semi-definite) or by modal data: natural frequencies ``f_k`` [Hz], damping ratios ``ζ_k``, mode
shapes ``Φ`` (rows: degrees of freedom, columns: modes; square and invertible) and modal masses
``m_k`` (``None``: the shapes are mass-normalised, ``m_k = 1``). Modal data become matrices by

    M = Φ^-T diag(m_k) Φ^-1,   K = Φ^-T diag(m_k ω_k²) Φ^-1,   C = Φ^-T diag(2 ζ_k ω_k m_k) Φ^-1

(classical damping; :func:`matrices`). Inside the engines the degrees of freedom are reordered
so that the box's comes first: ``x = (z, y)`` with ``z`` the box (``State.z``) and ``y`` the
others (``State.y``, ``(n - 1,)``), and ``Params`` holds the reordered ``M``, ``M⁻¹``, ``K``,
``C``, ``r``, ``b`` (:func:`internal`). A damper of several cells may put each cell on a
degree of freedom of its own (``structure.attach`` a list, one per cell: :func:`attachments`);
"the box" is then cell 0's, and the grains' forces of each cell act on its own degree of
freedom (``f`` in :func:`acceleration`, :func:`cell_dofs`). Energy of the structure
``½ x'ᵀ M x' + ½ (x - r u)ᵀ K (x - r u)``; the base's power
``-u' rᵀ [K (x - r u) + C (x' - r u')]`` plus the force's ``cos Ωt bᵀ x'``; the loss in ``C``:
``(x' - r u')ᵀ C (x' - r u')``.

Each function in its JAX form and, for the native kernel, its numba scalar form.

Example (a 2-DOF chain, the damper on the top mass)::

    import numpy as np
    from jaxdamp.cases import presets
    from jaxdamp.config import apply_overrides
    from jaxdamp.physics.structure import matrices
    cfg = apply_overrides(presets.get("sanchez2012-optimal"), {
        "structure.M": [[2.0, 0.0], [0.0, 2.37]],
        "structure.K": [[43000.0, -21500.0], [-21500.0, 21500.0]],
        "structure.C": [[15.2, -7.6], [-7.6, 7.6]], "structure.attach": 1})
    M, K, C, r, b = matrices(cfg)
    assert np.allclose(r, 1.0) and M.shape == (2, 2)
"""

from __future__ import annotations

import math

import numpy as np

from jaxdamp.physics.contact import scalar_form


def matrices(config) -> tuple[np.ndarray, ...]:
    """``(M, K, C, r, b)`` of ``config.structure`` in the user's order of degrees of freedom
    (module docstring); the 1-DOF primary's ``([[M]], [[K]], [[C]], [1], [0])`` without one."""
    s = getattr(config, "structure", None)
    if s is None:
        p = config.primary
        return (np.array([[p.M]]), np.array([[p.K]]), np.array([[p.C]]), np.ones(1),
                np.zeros(1))
    if s.M is not None:
        M, K = np.asarray(s.M, float), np.asarray(s.K, float)
        C = np.asarray(s.C, float) if s.C is not None else np.zeros_like(M)
    else:
        phi = np.asarray(s.shapes, float)
        w = 2.0 * math.pi * np.asarray(s.frequencies, float)
        z = np.asarray(s.damping, float) if s.damping is not None else np.zeros(len(w))
        m = (np.asarray(s.modal_masses, float) if s.modal_masses is not None
             else np.ones(len(w)))
        inv = np.linalg.inv(phi)
        M = inv.T @ np.diag(m) @ inv
        K = inv.T @ np.diag(m * w**2) @ inv
        C = inv.T @ np.diag(2.0 * z * w * m) @ inv
        M, K, C = (0.5 * (A + A.T) for A in (M, K, C))
    n = len(M)
    r = np.asarray(s.influence, float) if s.influence is not None else np.ones(n)
    b = np.zeros(n)
    b[s.force_dof] = s.force
    return M, K, C, r, b


def attachments(config) -> tuple[int, ...]:
    """The degree of freedom (user numbering) that carries each cell of the damper
    (``Config.cells``): ``structure.attach`` for every cell, or its entries where it is a
    list (one per cell); all 0 without a structure."""
    cells = getattr(config, "cells", 1)
    s = getattr(config, "structure", None)
    if s is None:
        return (0,) * cells
    if isinstance(s.attach, (tuple, list)):
        return tuple(int(a) for a in s.attach)
    return (int(s.attach),) * cells


def order(config) -> np.ndarray:
    """The engines' order of the degrees of freedom: the box's (cell 0's,
    :func:`attachments`) first, then the others in the user's order."""
    s = getattr(config, "structure", None)
    if s is None:
        return np.zeros(1, np.int64)
    n = len(matrices(config)[0])
    box = attachments(config)[0]
    return np.array([box] + [i for i in range(n) if i != box], np.int64)


def cell_dofs(config) -> np.ndarray:
    """Where each cell's degree of freedom sits in the engines' order (:func:`order`),
    ``(cells,)`` int64: 0 (the box, ``State.z``) for cell 0 and for every cell on its degree of
    freedom, ``p > 0`` for ``State.y[p - 1]``."""
    o = order(config)
    return np.array([int(np.flatnonzero(o == a)[0]) for a in attachments(config)], np.int64)


def position(config, dof: int | None) -> int:
    """Where the user's degree of freedom ``dof`` (0-based; ``None``: the box's) sits in the
    engines' order (:func:`order`): 0 is the box's (``State.z``, record ``z_box``), ``p > 0``
    is ``State.y[p - 1]`` (record ``y_dofs[:, p - 1]``). Refuses a ``dof`` out of range."""
    o = order(config)
    if dof is None:
        return 0
    if not (isinstance(dof, (int, np.integer)) and 0 <= dof < len(o)):
        from jaxdamp.config import ConfigError

        raise ConfigError(f"dof = {dof!r}: the structure has {len(o)} degree(s) of freedom, "
                          f"numbered 0 to {len(o) - 1}")
    return int(np.flatnonzero(o == dof)[0])


def displacement(records, k: int, config, dof: int | None):
    """The displacement series [m] of degree of freedom ``dof`` (user numbering; ``None``: the
    box's) of system ``k`` in ``records`` (``z_box``, ``y_dofs``)."""
    p = position(config, dof)
    if p == 0:
        return np.asarray(records["z_box"][k])
    return np.asarray(records["y_dofs"][k])[:, p - 1]


def internal(config) -> dict:
    """``Params`` fields of the structure in the engines' order (:func:`order`):
    ``s_M``, ``s_Minv``, ``s_K``, ``s_C`` ``(n, n)``, ``s_r``, ``s_b`` ``(n,)``."""
    M, K, C, r, b = matrices(config)
    o = order(config)
    sel = np.ix_(o, o)
    return dict(s_M=M[sel], s_Minv=np.linalg.inv(M[sel]), s_K=K[sel], s_C=C[sel], s_r=r[o],
                s_b=b[o])


def static_offset(config, box_force: float) -> np.ndarray:
    """Static displacements ``K⁻¹ f`` [m] (user order) under a constant force ``F`` [N] on the
    damper (e.g. the bed's weight along the axis), shared equally by its cells (identical
    beds) on their degrees of freedom (:func:`attachments`); zeros where ``K`` is singular (a
    free structure has no static equilibrium)."""
    M, K, C, r, b = matrices(config)
    f = np.zeros(len(K))
    cells = attachments(config)
    for a in cells:
        f[a] += box_force / len(cells)
    try:
        return np.linalg.solve(K, f)
    except np.linalg.LinAlgError:
        return np.zeros(len(K))


# -- JAX forms (one system; x = (z, y), the box first) -------------------------------------


def acceleration(x, xd, u, ud, f, cos_t, p):
    """``x'' = M⁻¹ [-C (x' - r u') - K (x - r u) + f + b cos Ωt]`` [m/s²], ``(n,)``, with
    ``f`` ``(n,)`` [N] the grains' forces on each degree of freedom along the axis (the
    cells' on theirs; ``e_0 F_gz`` for one)."""
    rhs = -p.s_C @ (xd - p.s_r * ud) - p.s_K @ (x - p.s_r * u) + p.s_b * cos_t + f
    return p.s_Minv @ rhs


def energy(x, xd, u, p):
    """``½ x'ᵀ M x' + ½ (x - r u)ᵀ K (x - r u)`` [J]."""
    d = x - p.s_r * u
    return 0.5 * xd @ (p.s_M @ xd) + 0.5 * d @ (p.s_K @ d)


def powers(x, xd, u, ud, cos_t, p):
    """Power into the structure from the base and the force, and the loss in ``C`` [W]."""
    d, dd = x - p.s_r * u, xd - p.s_r * ud
    p_in = -ud * (p.s_r @ (p.s_K @ d + p.s_C @ dd)) + cos_t * (p.s_b @ xd)
    return p_in, dd @ (p.s_C @ dd)


# -- numba scalar forms (the native kernel); x, xd: (n,) arrays, out: (n,) ----------------


@scalar_form
def acceleration_scalar(out, x, xd, u, ud, f, cos_t, Minv, K, C, r, b, tmp):
    """Scalar form of :func:`acceleration`, written into ``out`` (``tmp``: scratch ``(n,)``)."""
    n = x.shape[0]
    for i in range(n):
        s = b[i] * cos_t + f[i]
        for j in range(n):
            s -= C[i, j] * (xd[j] - r[j] * ud) + K[i, j] * (x[j] - r[j] * u)
        tmp[i] = s
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += Minv[i, j] * tmp[j]
        out[i] = s


@scalar_form
def energy_scalar(x, xd, u, M, K, r):
    """Scalar form of :func:`energy`."""
    n = x.shape[0]
    e = 0.0
    for i in range(n):
        for j in range(n):
            e += 0.5 * xd[i] * M[i, j] * xd[j] + 0.5 * (x[i] - r[i] * u) * K[i, j] * (
                x[j] - r[j] * u)
    return e


@scalar_form
def powers_scalar(x, xd, u, ud, cos_t, K, C, r, b):
    """Scalar form of :func:`powers`: ``(p_in, p_loss)``."""
    n = x.shape[0]
    p_in = 0.0
    p_c = 0.0
    for i in range(n):
        f = 0.0
        for j in range(n):
            f += K[i, j] * (x[j] - r[j] * u) + C[i, j] * (xd[j] - r[j] * ud)
            p_c += (xd[i] - r[i] * ud) * C[i, j] * (xd[j] - r[j] * ud)
        p_in += -ud * r[i] * f + cos_t * b[i] * xd[i]
    return p_in, p_c
