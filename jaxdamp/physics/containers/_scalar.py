"""The scalar contact of one grain with one wall, added to the grain's sums: the piece every
container's scalar form (``side_contacts_scalar``) repeats for each of its side walls, as the
native kernel does for the floor and the lid."""

from __future__ import annotations

from jaxdamp.physics.contact import HAVE_NUMBA, contact_scalar, scalar_form
from jaxdamp.physics.tangential import mindlin_called


def rows_of(sp):
    """The walls' springs ``hw`` ``(N, 2 + W, 3)`` of the tangential springs ``sp``
    (:func:`add_wall_scalar`'s), or ``None`` without springs: taken once per grain loop, so
    that the loop's checks (:func:`held`) get the one array, not the tuple (a tuple handed to
    an inlined function has each of its arrays' reference counts touched: 25 % of the spring
    step's time in the thesis bed, ``benchmarks/RESULTS.md``)."""
    return None if sp is None else sp[0]


def held(hw, i, w):
    """Whether grain ``i`` held a tangential spring with wall ``w`` after the last step
    (``hw``: the walls' springs, :func:`rows_of`; ``None``: no springs, never): a contact
    that ended is visited once more, to release its spring."""
    return hw is not None and (hw[i, w, 0] != 0.0 or hw[i, w, 1] != 0.0 or hw[i, w, 2] != 0.0)


def held_sides(hw, i, n_walls):
    """Whether grain ``i`` held a spring with any of the side walls ``2 … n_walls + 1``."""
    if hw is None:
        return False
    for w in range(2, 2 + n_walls):
        if held(hw, i, w):
            return True
    return False


if HAVE_NUMBA:
    # Compiled for the arguments' types (``overload``), so that ``hw is None`` folds where
    # ``hw`` is a variable of the caller typed ``None`` (an ``njit`` function inlined by numba
    # is inlined before typing: its branch on ``None`` would not fold there; numba-cuda
    # cannot inline an overload), and called: the array is passed, not assigned, so no
    # reference count is touched, and LLVM inlines the call.
    from numba.core import types as _types
    from numba.extending import overload

    rows_of = scalar_form(rows_of, inline=False)

    def _none(x):
        return isinstance(x, (_types.NoneType, _types.Omitted))

    @overload(held)
    def _held(hw, i, w):
        if _none(hw):
            return lambda hw, i, w: False
        return lambda hw, i, w: hw[i, w, 0] != 0.0 or hw[i, w, 1] != 0.0 or hw[i, w, 2] != 0.0

    @overload(held_sides)
    def _held_sides(hw, i, n_walls):
        if _none(hw):
            return lambda hw, i, n_walls: False

        def impl(hw, i, n_walls):
            for w in range(2, 2 + n_walls):
                if hw[i, w, 0] != 0.0 or hw[i, w, 1] != 0.0 or hw[i, w, 2] != 0.0:
                    return True
            return False
        return impl


@scalar_form
def add_wall_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx, sy, sz, Ri, k, g, gamma_s, mu, ex,
                    ey, ez, acc, sp, i, w):
    """Add the contact of grain ``i`` (radius ``Ri``, velocity ``v`` relative to the walls,
    spin ``s = R ω``) with wall ``w`` (0 the floor, 1 the lid, then the container's sides) of
    inward normal ``n`` at overlap ``xi`` (constants ``k, g, γ_s, μ``) to ``acc = (fx, fy, fz,
    tx, ty, tz, elastic energy, normal loss, friction loss, box_z, contacts)``: force and torque
    on the grain, ``box_z`` less the force along ``e``, one more wall contact. Returns the new
    sums, the wall force's ``z`` component (the floor's and lid's own sum) and the contact's
    loss (normal + friction power: the wall groups' own sums,
    :data:`jaxdamp.physics.model.WALL_GROUPS`).

    ``sp``: ``None`` (the viscous tangential force, ``xi > 0``; the compiled code has no
    other branch), or the tangential springs (:func:`jaxdamp.physics.tangential.mindlin_scalar`,
    ``xi > 0`` or :func:`held`) ``(hw, vh, sh, wg, tot, zds, cg, dt)``: the springs ``hw (N,
    2 + W, 3)`` (read and written in place), the half-step velocities ``vh`` and spins ``sh =
    R ω`` ``(N, 3)`` with which they grow, per grain ``wg (N, 3) = (G*, R*`` of a plane, ``R*``
    of the sides``)``, the step's totals ``tot`` (added to: ``[0]`` the turned energy, ``[1]``,
    ``[2]`` the pairs' and the walls' slip losses, ``[3]`` the springs' energy), each damper
    cell's walls' mean velocity along ``e`` over the step ``zds (K,)`` (cells on several
    degrees of freedom move apart), each grain's cell ``cg (N,)`` and the time step."""
    fx, fy, fz, tx, ty, tz, e_el, pw_n, pw_f, box_z, nc = acc
    if sp is None:
        gx, gy, gz, ax, ay, az, e, ln, lf = contact_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx,
                                                           sy, sz, k, g, gamma_s, mu)
        touching = 1.0
    else:
        hw, vh, sh, wg, tot, zds, cg, dt = sp
        zc = zds[cg[i]]  # the grain's cell's walls
        (gx, gy, gz, ax, ay, az, e, ln, lf, h0, h1, h2, turned, slip, e_s) = mindlin_called(
            law, xi, nx, ny, nz, vx, vy, vz, sx, sy, sz, vh[i, 0] - ex * zc,
            vh[i, 1] - ey * zc, vh[i, 2] - ez * zc, sh[i, 0], sh[i, 1], sh[i, 2], k, g,
            wg[i, 0], wg[i, 1] if w < 2 else wg[i, 2], mu, dt, hw[i, w, 0], hw[i, w, 1],
            hw[i, w, 2])
        hw[i, w, 0], hw[i, w, 1], hw[i, w, 2] = h0, h1, h2
        tot[0] += turned
        tot[2] += slip
        tot[3] += e_s
        touching = 1.0 if xi > 0.0 else 0.0
    return (fx + gx, fy + gy, fz + gz, tx - Ri * (ny * az - nz * ay),
            ty - Ri * (nz * ax - nx * az), tz - Ri * (nx * ay - ny * ax), e_el + e, pw_n + ln,
            pw_f + lf, box_z - (ex * gx + ey * gy + ez * gz), nc + touching), gz, ln + lf
