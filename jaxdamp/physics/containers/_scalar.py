"""The scalar contact of one grain with one wall, added to the grain's sums: the piece every
container's scalar form (``side_contacts_scalar``) repeats for each of its side walls, as the
native kernel does for the floor and the lid."""

from __future__ import annotations

from jaxdamp.physics.contact import contact_scalar, scalar_form


@scalar_form
def add_wall_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx, sy, sz, Ri, k, g, gamma_s, mu, ex,
                    ey, ez, acc):
    """Add the contact of a grain (radius ``Ri``, velocity ``v`` relative to the walls, spin
    ``s = R ω``) with a wall of inward normal ``n`` at overlap ``xi > 0`` (constants ``k, g,
    γ_s, μ``) to ``acc = (fx, fy, fz, tx, ty, tz, elastic energy, normal loss, friction loss,
    box_z, contacts)``: force and torque on the grain, ``box_z`` less the force along ``e``,
    one more wall contact. Returns the new sums, the wall force's ``z`` component (the floor's
    and lid's own sum) and the contact's loss (normal + friction power: the wall groups' own
    sums, :data:`jaxdamp.physics.model.WALL_GROUPS`)."""
    fx, fy, fz, tx, ty, tz, e_el, pw_n, pw_f, box_z, nc = acc
    gx, gy, gz, ax, ay, az, e, ln, lf = contact_scalar(law, xi, nx, ny, nz, vx, vy, vz, sx, sy,
                                                       sz, k, g, gamma_s, mu)
    return (fx + gx, fy + gy, fz + gz, tx - Ri * (ny * az - nz * ay),
            ty - Ri * (nz * ax - nx * az), tz - Ri * (nx * ay - ny * ax), e_el + e, pw_n + ln,
            pw_f + lf, box_z - (ex * gx + ey * gy + ez * gz), nc + 1.0), gz, ln + lf
