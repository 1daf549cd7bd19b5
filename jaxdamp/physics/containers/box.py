"""The rectangular box: a prism of section ``[0, Lx] × [0, Ly]`` (``config.box``).

Its four side walls are planes, ``x = 0``, ``x = Lx``, ``y = 0``, ``y = Ly`` in that order
(their inward normals ``(1, 0)``, ``(-1, 0)``, ``(0, 1)``, ``(0, -1)``; all flat). The
section's numbers in ``Params.section`` are ``(Lx, Ly)``.

Example::

    >>> from jaxdamp.cases import presets
    >>> from jaxdamp.physics.containers import container
    >>> box = container(presets.get("sanchez2012-optimal"))
    >>> box.name, [round(float(v), 4) for v in box.section(presets.get("sanchez2012-optimal"))]
    ('box', [0.0402, 0.0402])
"""

from __future__ import annotations

import functools

import numpy as np

from jaxdamp.physics.contact import scalar_form
from jaxdamp.physics.containers._scalar import add_wall_scalar, held, held_sides

#: Inward unit normals ``(nx, ny)`` of the side walls x=0, x=Lx, y=0, y=Ly.
NORMALS = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])


def section(config) -> np.ndarray:
    """``Params.section`` of the box: ``(Lx, Ly)`` [m]."""
    return np.array([config.box.Lx, config.box.Ly], dtype=np.float64)


def sides_jax(bx, by, section):
    """Distances ``(N, 4)`` [m] from grain centres ``(bx, by)`` (box frame) to the side walls,
    their inward normals (constants ``(4,)``) and curvatures (all flat)."""
    gaps = (bx, section[0] - bx, by, section[1] - by)
    return gaps, (NORMALS[:, 0], NORMALS[:, 1]), (0.0, 0.0, 0.0, 0.0)


def curvature(config) -> float:
    """The largest curvature of the walls [1/m]: 0, all planes."""
    return 0.0


#: The box's own dimensions: none beyond its ``[box]`` table (Lx, Ly, Lz).
FIELDS = ()


@functools.partial(scalar_form, inline=False)  # called: ``hw`` passed, not assigned
def side_reach_scalar(x, y, section, Ri, hw, i):
    """Whether a grain of radius ``Ri`` at ``(x, y)`` (box frame) touches a side wall or held
    a spring with one (``hw``: the walls' springs or ``None``,
    :func:`~jaxdamp.physics.containers._scalar.rows_of`): the grains
    :func:`side_contacts_scalar` must visit."""
    return (x < Ri or section[0] - x < Ri or y < Ri or section[1] - y < Ri
            or held_sides(hw, i, 4))


@scalar_form
def side_contacts_scalar(law, x, y, section, Ri, wk, i, vx, vy, vz, sx, sy, sz, ex, ey, ez,
                         acc, sp, hw):
    """Scalar form of the side walls' contacts of one grain at ``(x, y)`` (box frame), added
    to ``acc`` (:func:`jaxdamp.physics.containers._scalar.add_wall_scalar`; ``wk[i]``: the
    grain's plane-wall constants ``(k, g, γ_s, μ)``; ``sp``: the tangential springs or
    ``None``, and a wall whose spring the grain :func:`~jaxdamp.physics.containers._scalar.held`
    is visited too). The four walls unrolled, in the order of :data:`NORMALS` (walls 2–5):
    most grains touch none, so the common path is four compares (no array view is made per
    grain: its reference count would be touched by every thread)."""
    if not side_reach_scalar(x, y, section, Ri, hw, i):
        return acc
    k, g, gs, mu = wk[i, 0], wk[i, 1], wk[i, 2], wk[i, 3]
    if x < Ri or held(hw, i, 2):
        acc, _, _ = add_wall_scalar(law, Ri - x, 1.0, 0.0, 0.0, vx, vy, vz, sx, sy, sz, Ri, k, g,
                                    gs, mu, ex, ey, ez, acc, sp, i, 2)
    if section[0] - x < Ri or held(hw, i, 3):
        acc, _, _ = add_wall_scalar(law, Ri - (section[0] - x), -1.0, 0.0, 0.0, vx, vy, vz, sx,
                                    sy, sz, Ri, k, g, gs, mu, ex, ey, ez, acc, sp, i, 3)
    if y < Ri or held(hw, i, 4):
        acc, _, _ = add_wall_scalar(law, Ri - y, 0.0, 1.0, 0.0, vx, vy, vz, sx, sy, sz, Ri, k, g,
                                    gs, mu, ex, ey, ez, acc, sp, i, 4)
    if section[1] - y < Ri or held(hw, i, 5):
        acc, _, _ = add_wall_scalar(law, Ri - (section[1] - y), 0.0, -1.0, 0.0, vx, vy, vz, sx,
                                    sy, sz, Ri, k, g, gs, mu, ex, ey, ez, acc, sp, i, 5)
    return acc


def extent(config) -> tuple[float, float, float, float]:
    """The section's bounding rectangle ``(x0, x1, y0, y1)`` [m]."""
    return 0.0, float(config.box.Lx), 0.0, float(config.box.Ly)


def inside(x, y, margin: float, config) -> np.ndarray:
    """Whether points ``(x, y)`` lie at least ``margin`` inside every side wall."""
    b = config.box
    return (x >= margin) & (x <= b.Lx - margin) & (y >= margin) & (y <= b.Ly - margin)


def base_area(config) -> float:
    """Area of the section (the floor) [m²]."""
    return float(config.box.Lx * config.box.Ly)


def perimeter(config) -> float:
    """Perimeter of the section [m] (with :func:`base_area`, its hydraulic diameter)."""
    return float(2.0 * (config.box.Lx + config.box.Ly))


def fit_error(config, diameter: float, name: str) -> str | None:
    """Why a grain of ``diameter`` [m] (``name`` and radius text) does not fit across the
    section, or ``None``."""
    for side in ("Lx", "Ly"):
        length = getattr(config.box, side)
        if diameter >= length:
            return f"{name} does not fit box.{side} = {length} m"
    return None


def describe(config) -> str:
    """The section in words: ``"0.04 × 0.04 m base"``."""
    return f"{config.box.Lx} × {config.box.Ly} m base"


def outline(config, z0: float = 0.0) -> list[np.ndarray]:
    """The cavity's edges as 3-D polylines [m] (lab frame, floor at ``z0``): the 12 edges."""
    Lx, Ly, Lz = config.box.Lx, config.box.Ly, config.box.Lz
    c = np.array([[x, y, z0 + z] for z in (0, Lz) for y in (0, Ly) for x in (0, Lx)])
    edges = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7), (0, 4), (1, 5),
             (2, 6), (3, 7)]
    return [c[[a, b]] for a, b in edges]
