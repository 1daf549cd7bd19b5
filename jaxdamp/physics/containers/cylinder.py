"""The upright cylinder: a prism of circular section, radius ``R_c`` (``[container]`` with
``shape = "cylinder"``, ``radius``, ``Lz``).

In the box frame its axis stands at ``(R_c, R_c)``, so the section's bounding square is
``[0, 2 R_c]²`` (the frame of the box's corner, where lattices, figures and exports start). Its
one side wall is concave seen from the grains: at a grain centre ``(x, y)`` at distance ``ρ``
from the axis the wall is ``R_c − ρ`` away and its inward normal is ``−(x − R_c, y − R_c)/ρ``.

**Contact curvature.** The wall is curved in one direction only (``−1/R_c`` around the axis, 0
along it), so a sphere touching it makes an elliptical Hertz contact. Its effective radius is
taken from the mean relative curvature, ``1/R* = 1/R − 1/(2 R_c)``: the wall enters with the
contact curvature ``κ = 1/(2 R_c)`` (:data:`CONTACT_CURVATURE` of the section's ``1/R_c``) in
``R* = R / (1 − R κ)`` (:func:`jaxdamp.physics.containers.effective_radius`). This is LAMMPS'
convention (``fix wall/gran ... zcylinder`` gives the wall the radius ``−2 R_c``), and it lies
within 1 % of the equivalent radius ``√(R' R'')`` of the elliptical contact (Johnson, *Contact
Mechanics*, §4.2; ``R' = 1/(1/R − 1/R_c)``, ``R'' = R``) for ``R_c ≥ 5 R``. A concave wall is
stiffer than a plane. ``Params.section`` is ``(R_c,)``.

Example::

    >>> from jaxdamp.cases import presets
    >>> from jaxdamp.config import Container
    >>> import dataclasses
    >>> cfg = dataclasses.replace(presets.get("sanchez2012-optimal"), box=None,
    ...     container=Container("cylinder", 0.12, (("radius", 0.025),)))
    >>> from jaxdamp.physics.containers import container
    >>> round(container(cfg).base_area(cfg) * 1e4, 4)  # π R_c² [cm²]
    19.635
"""

from __future__ import annotations

import functools
import math

import jax.numpy as jnp
import numpy as np

from jaxdamp.physics.contact import safe_norm, scalar_form
from jaxdamp.physics.containers._scalar import add_wall_scalar, held

#: The container's own dimensions (keys of its ``[container]`` table beside ``shape``, ``Lz``).
FIELDS = ("radius",)
#: The side wall's contact curvature per unit of its section's curvature ``1/R_c``: the mean
#: of its two principal curvatures (module docstring).
CONTACT_CURVATURE = 0.5


def _radius(config) -> float:
    return float(config.container.dimension("radius"))


def section(config) -> np.ndarray:
    """``Params.section`` of the cylinder: ``(R_c,)`` [m]."""
    return np.array([_radius(config)], dtype=np.float64)


def sides_jax(bx, by, section):
    """Distance ``(N,)`` from grain centres ``(bx, by)`` (box frame) to the side wall, its
    inward normal ``(N, 1)`` each, and its contact curvature ``1/(2 R_c)``."""
    Rc = section[0]
    rho = jnp.stack([bx - Rc, by - Rc], axis=-1)
    d = safe_norm(rho)
    off = d > 0
    inv = 1.0 / jnp.where(off, d, 1.0)
    nx = jnp.where(off, -rho[:, 0] * inv, 1.0)
    ny = jnp.where(off, -rho[:, 1] * inv, 0.0)
    return (Rc - d,), (nx[:, None], ny[:, None]), (CONTACT_CURVATURE / Rc,)


@functools.partial(scalar_form, inline=False)  # called: ``hw`` passed, not assigned
def side_reach_scalar(x, y, section, Ri, hw, i):
    """Whether a grain of radius ``Ri`` at ``(x, y)`` (box frame) touches the side wall,
    ``ρ² > (R_c − R)²``, or held a spring with it (``hw``: the walls' springs or ``None``)."""
    Rc = section[0]
    dx = x - Rc
    dy = y - Rc
    return dx * dx + dy * dy > (Rc - Ri) * (Rc - Ri) or held(hw, i, 2)


@scalar_form
def side_contacts_scalar(law, x, y, section, Ri, wk, i, vx, vy, vz, sx, sy, sz, ex, ey, ez,
                         acc, sp, hw):
    """Scalar form of the side wall's contact of grain ``i`` at ``(x, y)`` (box frame), added
    to ``acc`` (:func:`jaxdamp.physics.containers._scalar.add_wall_scalar`; ``sp``: the
    tangential springs or ``None``): touching where ``ρ² > (R_c − R)²`` (no square root
    otherwise), or visited where the grain :func:`~jaxdamp.physics.containers._scalar.held`
    a spring with the wall (wall 2), with the grain's constants ``wk[i]`` formed at the
    concave radius (the kernel forms them once per call from :func:`curvature_scalar`)."""
    Rc = section[0]
    dx = x - Rc
    dy = y - Rc
    rho2 = dx * dx + dy * dy
    if side_reach_scalar(x, y, section, Ri, hw, i):
        d = math.sqrt(rho2)
        acc, _, _ = add_wall_scalar(law, Ri - (Rc - d), -dx / d, -dy / d, 0.0, vx, vy, vz, sx,
                                    sy, sz, Ri, wk[i, 0], wk[i, 1], wk[i, 2], wk[i, 3], ex, ey,
                                    ez, acc, sp, i, 2)
    return acc


@scalar_form
def curvature_scalar(section):
    """The side wall's contact curvature ``1/(2 R_c)`` [1/m] from ``Params.section``."""
    return CONTACT_CURVATURE / section[0]


def curvature(config) -> float:
    """The side wall's contact curvature ``1/(2 R_c)`` [1/m]."""
    return CONTACT_CURVATURE / _radius(config)


def extent(config) -> tuple[float, float, float, float]:
    """The section's bounding square ``(0, 2 R_c, 0, 2 R_c)`` [m]."""
    Rc = _radius(config)
    return 0.0, 2.0 * Rc, 0.0, 2.0 * Rc


def inside(x, y, margin: float, config) -> np.ndarray:
    """Whether points ``(x, y)`` lie at least ``margin`` inside the wall."""
    Rc = _radius(config)
    return np.hypot(x - Rc, y - Rc) <= Rc - margin


def base_area(config) -> float:
    """``π R_c²`` [m²]."""
    return math.pi * _radius(config) ** 2


def perimeter(config) -> float:
    """``2 π R_c`` [m]."""
    return 2.0 * math.pi * _radius(config)


def fit_error(config, diameter: float, name: str) -> str | None:
    """Why a grain of ``diameter`` [m] does not fit across the section, or ``None``."""
    Rc = _radius(config)
    if diameter >= 2.0 * Rc:
        return f"{name} does not fit container.radius = {Rc} m"
    return None


def describe(config) -> str:
    """The section in words."""
    return f"cylinder of radius {_radius(config)} m"


def outline(config, z0: float = 0.0) -> list[np.ndarray]:
    """Floor and lid circles and four vertical lines as 3-D polylines [m] (floor at ``z0``)."""
    Rc, Lz = _radius(config), float(config.container.Lz)
    a = np.linspace(0.0, 2.0 * math.pi, 73)
    ring = np.column_stack([Rc + Rc * np.cos(a), Rc + Rc * np.sin(a)])
    lines = [np.column_stack([ring, np.full(len(a), z0 + h)]) for h in (0.0, Lz)]
    for q in (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi):
        x, y = Rc + Rc * math.cos(q), Rc + Rc * math.sin(q)
        lines.append(np.array([[x, y, z0], [x, y, z0 + Lz]]))
    return lines
