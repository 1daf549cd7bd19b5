"""Containers: the cavity that holds the grains, registered by name (:data:`CONTAINERS`).

Every container is a prism along the box's own z axis: a flat **floor** at height 0, a flat
**lid** at ``Lz`` (``Params.Lz``, the design variable of the thesis), and **side walls** given
by its section. What differs between containers is the section, and a container module holds
everything about it side by side:

* the JAX contact form ``sides_jax(bx, by, section)``: the distances ``(N, W)`` from the grain
  centres ``(bx, by)`` (box frame) to its ``W ≤ MAX_SIDES`` side walls, their inward normals
  ``(nx, ny)`` (constants ``(W,)`` for planes, ``(N, W)`` for curved walls) and their
  contact curvatures ``κ`` (0 for a plane; a concave wall's effective contact radius is
  ``R* = R_i / (1 − R_i κ)``, :func:`effective_radius`; a wall curved in one direction only,
  as the cylinder's, enters with half its curvature: the mean of its principal curvatures);
* its scalar form for the compiled kernel, ``side_contacts_scalar``: the contacts of one
  grain with its side walls, added to the grain's sums (each wall by
  :func:`jaxdamp.physics.containers._scalar.add_wall_scalar`; the walls unrolled, so that a
  grain touching none costs a few compares), dispatched by :func:`side_contacts_scalar`, and
  ``side_reach_scalar``, whether a grain touches a side or holds a spring with one (asked
  first, by :func:`side_reach_scalar`);
* its host-side geometry: ``section(config)`` (the numbers of ``Params.section``),
  ``extent`` and ``inside`` (pouring the lattice, :mod:`jaxdamp.engine.packing`),
  ``fit_error``, ``base_area`` and ``perimeter`` (the fit checks of :mod:`jaxdamp.validation`,
  the design space's bed height, the random packing of a fill, :mod:`jaxdamp.cases.filling`),
  ``describe`` (messages), ``outline`` (figures and export), and the configuration keys of
  its lid height and of its base (the settled-bed cache and the design variable ``base``).

The wall groups every engine reports apart are the floor, the lid and the sides
(:data:`jaxdamp.physics.model.WALL_GROUPS`: ``State.n_floor``, ``n_lid``, ``n_side`` and the
work channels ``pw_floor``, ``pw_lid``, ``pw_side`` of :data:`jaxdamp.physics.model.CHANNELS`;
``State.f_floor_lid`` is the force on floor and lid). Adding a container is a module here and
its entry in :data:`CONTAINERS` and in the scalar dispatch below.
"""

from __future__ import annotations

import functools
from typing import Callable, NamedTuple

from jaxdamp.physics.contact import scalar_form
from jaxdamp.physics.containers import box, cylinder


class Container(NamedTuple):
    """A container's forms (module docstring); ``id``: its number in the scalar dispatch;
    ``curved``: whether a side wall is curved (the JAX form then forms its effective radius
    per contact); ``fields``: its own dimensions, keys of its ``[container]`` table;
    ``curvature(config)``: the largest contact curvature of its walls [1/m] (0: all planes), which
    shortens the stiffest wall contact and so the time step."""

    name: str
    id: int
    curved: bool
    fields: tuple[str, ...]
    curvature: Callable
    section: Callable
    sides_jax: Callable
    extent: Callable
    inside: Callable
    base_area: Callable
    perimeter: Callable
    fit_error: Callable
    describe: Callable
    outline: Callable
    lid_key: str
    base_keys: tuple[str, ...]

    def height(self, config) -> float:
        """The inner height, floor to lid [m] (``Params.Lz``; at :attr:`lid_key`)."""
        from jaxdamp.config import get_path

        return float(get_path(config, self.lid_key))

    def wall(self, config):
        """The wall :class:`~jaxdamp.config.Material` its table gives, or ``None``."""
        return (config.container if self.name != "box" else config.box).wall


BOX = Container("box", 0, False, box.FIELDS, box.curvature, box.section, box.sides_jax, box.extent,
                box.inside, box.base_area, box.perimeter, box.fit_error, box.describe,
                box.outline, "box.Lz", ("box.Lx", "box.Ly"))
CYLINDER = Container("cylinder", 1, True, cylinder.FIELDS, cylinder.curvature,
                     cylinder.section,
                     cylinder.sides_jax, cylinder.extent, cylinder.inside, cylinder.base_area,
                     cylinder.perimeter, cylinder.fit_error, cylinder.describe,
                     cylinder.outline, "container.Lz", ("container.radius",))

CONTAINERS: dict[str, Container] = {c.name: c for c in (BOX, CYLINDER)}
_CYLINDER = CYLINDER.id


def container(config) -> Container:
    """The container of ``config``: the box of its ``[box]`` table, or the one its
    ``[container]`` table names (``shape``)."""
    if getattr(config, "container", None) is not None:
        return CONTAINERS[config.container.shape]
    return BOX


@scalar_form
def side_contacts_scalar(shape, law, x, y, section, Ri, wk, i, vx, vy, vz, sx, sy, sz, ex, ey,
                         ez, acc, sp, hw):
    """The contacts of grain ``i`` (centre ``(x, y)`` in the box frame, radius ``Ri``, its
    side-wall constants ``wk[i] = (k, g, γ_s, μ)`` formed at the sides' curvature
    (:func:`side_curvature_scalar`), velocity ``v`` relative to the walls, spin ``R ω``) with
    the side walls of container number ``shape`` (``section``: ``Params.section`` as the tuple
    of :func:`section_scalar`), added to
    ``acc = (fx, fy, fz, tx, ty, tz, elastic energy, normal loss, friction loss, box_z,
    contacts)``; ``sp``: the tangential springs, or ``None`` for the viscous law
    (:func:`jaxdamp.physics.containers._scalar.add_wall_scalar`) and ``hw`` their walls' part
    (:func:`~jaxdamp.physics.containers._scalar.rows_of`)."""
    if shape == _CYLINDER:
        return cylinder.side_contacts_scalar(law, x, y, section, Ri, wk, i, vx, vy, vz, sx, sy,
                                             sz, ex, ey, ez, acc, sp, hw)
    return box.side_contacts_scalar(law, x, y, section, Ri, wk, i, vx, vy, vz, sx, sy, sz, ex,
                                    ey, ez, acc, sp, hw)


@functools.partial(scalar_form, inline=False)  # called: ``hw`` passed, not assigned
def side_reach_scalar(shape, x, y, section, Ri, hw, i):
    """Whether grain ``i`` (radius ``Ri``, centre ``(x, y)`` in the box frame) touches a side
    wall of container number ``shape`` or held a spring with one (``hw``: the walls' springs
    or ``None``, :func:`jaxdamp.physics.containers._scalar.rows_of`): the grains
    :func:`side_contacts_scalar` must visit. The kernel asks first, so that a grain far from
    the sides never hands the springs' tuple to the contacts (each of its arrays' reference
    counts touched per grain: the spring step's largest cost, ``benchmarks/RESULTS.md``)."""
    if shape == _CYLINDER:
        return cylinder.side_reach_scalar(x, y, section, Ri, hw, i)
    return box.side_reach_scalar(x, y, section, Ri, hw, i)


#: How many section numbers (``Params.section``) the compiled kernel holds in registers: the
#: most any registered container has (checked by ``tests/test_containers.py``).
MAX_SECTION = 2


@scalar_form
def section_scalar(section):
    """The section numbers ``Params.section`` as a tuple of :data:`MAX_SECTION` floats (zeros
    after a container's own), which the kernel forms once per call and passes to
    :func:`side_contacts_scalar`. Read from the parameter array inside the grain loop instead,
    the numbers were loaded again for every grain (the loop's stores to the force arrays
    might alias them): that alone made the native step 15–19 % slower
    (``benchmarks/RESULTS.md``, 2026-12-05)."""
    return (section[0], section[1] if section.shape[0] > 1 else 0.0)


@scalar_form
def side_curvature_scalar(shape, section):
    """The curvature [1/m] of the side walls of container number ``shape`` (0: planes), at
    which the kernel forms each grain's side-wall constants once per call."""
    if shape == _CYLINDER:
        return cylinder.curvature_scalar(section)
    return 0.0


def effective_radius(radius, curvature):
    """``R* = R / (1 − R κ)`` of a grain of radius ``R`` against a wall of curvature ``κ``
    (``κ = 0``: a plane, ``R* = R`` exactly; ``κ > 0``: concave, seen from inside)."""
    return radius / (1.0 - radius * curvature)
