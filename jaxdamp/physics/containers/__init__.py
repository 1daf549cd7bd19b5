"""Containers: the cavity that holds the grains, registered by name (:data:`CONTAINERS`).

Every container is a prism along the box's own z axis: a flat **floor** at height 0, a flat
**lid** at ``Lz`` (``Params.Lz``, the design variable of the thesis), and **side walls** given
by its section. What differs between containers is the section, and a container module holds
everything about it side by side:

* the JAX contact form ``sides_jax(bx, by, section)``: the distances ``(N, W)`` from the grain
  centres ``(bx, by)`` (box frame) to its ``W ≤ MAX_SIDES`` side walls, their inward normals
  ``(nx, ny)`` (constants ``(W,)`` for planes, ``(N, W)`` for curved walls) and their
  curvatures (``1/R_wall``, 0 for a plane; a concave wall's effective contact radius is
  ``R* = R_i / (1 − R_i κ)``, :func:`effective_radius`);
* the scalar forms for the compiled kernel, ``sides_scalar(x, y, section)`` (the distances, a
  tuple of ``MAX_SIDES``, ``inf`` for absent walls) and ``normal_scalar(k, x, y, section)``
  (``(nx, ny, κ)`` of wall ``k``), dispatched by :func:`sides_scalar` / :func:`normal_scalar`;
* its host-side geometry: ``section(config)`` (the numbers of ``Params.section``),
  ``extent`` and ``inside`` (pouring the lattice, :mod:`jaxdamp.engine.packing`),
  ``fit_error`` and ``base_area`` (the fit checks of :mod:`jaxdamp.validation`, the design
  space's bed height), ``describe`` (messages), ``outline`` (figures and export), and the
  configuration keys of its lid height and of its base (the settled-bed cache and the design
  variable ``base``).

The wall groups every engine reports are the floor and the lid (``State.f_floor_lid``,
``n_floor``, ``n_lid``) and the sides (the rest); the work channels are
:data:`jaxdamp.physics.model.CHANNELS`. Adding a container is a module here and its entry in
:data:`CONTAINERS` and in the two scalar dispatches below.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

from jaxdamp.physics.contact import scalar_form
from jaxdamp.physics.containers import box, cylinder

#: Side walls a container may have (the compiled kernel's fixed loop over them).
MAX_SIDES = 4


class Container(NamedTuple):
    """A container's forms (module docstring); ``id``: its number in the scalar dispatch;
    ``curved``: whether a side wall is curved (its effective radius is then formed per
    contact); ``fields``: its own dimensions, keys of its ``[container]`` table;
    ``curvature(config)``: the largest curvature of its walls [1/m] (0: all planes), which
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
                box.inside, box.base_area, box.fit_error, box.describe, box.outline, "box.Lz",
                ("box.Lx", "box.Ly"))
CYLINDER = Container("cylinder", 1, True, cylinder.FIELDS, cylinder.curvature,
                     cylinder.section,
                     cylinder.sides_jax, cylinder.extent, cylinder.inside, cylinder.base_area,
                     cylinder.fit_error, cylinder.describe, cylinder.outline, "container.Lz",
                     ("container.radius",))

#: The containers by name.
CONTAINERS: dict[str, Container] = {c.name: c for c in (BOX, CYLINDER)}
_CYLINDER = CYLINDER.id


def container(config) -> Container:
    """The container of ``config``: the box of its ``[box]`` table, or the one its
    ``[container]`` table names (``shape``)."""
    if getattr(config, "container", None) is not None:
        return CONTAINERS[config.container.shape]
    return BOX


@scalar_form
def sides_scalar(shape, x, y, section):
    """The distances from ``(x, y)`` to the side walls of container number ``shape``, a tuple
    of :data:`MAX_SIDES` (``section``: ``Params.section``)."""
    if shape == _CYLINDER:
        return cylinder.sides_scalar(x, y, section)
    return box.sides_scalar(x, y, section)


@scalar_form
def normal_scalar(shape, k, x, y, section):
    """``(nx, ny, κ)``: inward normal and curvature of side wall ``k`` of container ``shape``."""
    if shape == _CYLINDER:
        return cylinder.normal_scalar(k, x, y, section)
    return box.normal_scalar(k, x, y, section)


def effective_radius(radius, curvature):
    """``R* = R / (1 − R κ)`` of a grain of radius ``R`` against a wall of curvature ``κ``
    (``κ = 0``: a plane, ``R* = R`` exactly; ``κ > 0``: concave, seen from inside)."""
    return radius / (1.0 - radius * curvature)
