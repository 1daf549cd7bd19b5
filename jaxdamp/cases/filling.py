"""Filling a cavity as a designer states it: a grain count, a mass ratio or a fill fraction.

A species of ``[[grains]]`` gives exactly one of

* ``count``: the number of grains (of one cell, :attr:`jaxdamp.config.Config.cells`);
* ``mass_ratio`` ``μ = m_grains / M``: the species' mass over the primary's mass ``M``
  (``[primary] M``), so ``N = round(μ M / m̄)`` with ``m̄ = ρ v̄`` the mean grain mass; a
  damper of ``k`` cells (``Config.cells``) splits it, ``N = round(μ M / (k m̄))`` per cell;
* ``fill_fraction`` ``f``: the volume of the species' bed at random packing over the cavity's
  volume (one cell's), ``f = N v̄ / (φ V)``, so ``N = round(f φ V / v̄)``;

where ``v̄ = (4/3) π R³ (1 + s²)`` is the mean volume of a grain whose radius is uniform in
``R [1 − s, 1 + s]`` (``radius_spread = s``), ``V`` the cavity's volume (base area × ``Lz``) and
``φ`` the random packing fraction of :func:`random_packing_fraction`. :func:`resolve` turns the
statements into counts (:func:`jaxdamp.validation.validate` calls it, so a validated
configuration always holds counts; the statement stays beside the count it gave).

**Random packing near walls.** A poured bed of equal spheres is looser near the walls, the more
so the narrower the cavity. :func:`random_packing_fraction` is Dixon's correlation for the
mean voidage ``ε`` of randomly packed spheres of diameter ``d`` in a tube of diameter ``D``
(A. G. Dixon, *Can. J. Chem. Eng.* 66:705, 1988), ``φ = 1 − ε`` with, for ``x = d/D``,

    ε = 0.4 + 0.05 x + 0.412 x²              x ≤ 0.5
    ε = 0.528 + 2.464 (x − 0.5)              0.5 < x ≤ 0.536
    ε = 1 − 0.667 x³ (2x − 1)^(−1/2)         x > 0.536

(``φ → 0.60`` in a wide cavity: poured random packing; ``φ = 0.574`` at ``D/d = 5``, 0.591 at
10, 0.597 at 20; Benyahia & O'Neill, *Part. Sci. Technol.* 23:169, 2005, agree within 0.01
over ``D/d = 5–20``). A section other than a circle enters with its hydraulic diameter
``D = 4 A / P`` (area over perimeter; the box's ``2 Lx Ly / (Lx + Ly)``), the usual extension
of tube correlations to other ducts: a stated approximation, not a measured one.

The same relation is the limit of a fill stated by mass or fraction: the species' beds together
must fit the cavity at random packing (``Σ f ≤ 1``); a larger mass ratio or fill fraction is an
error that names the largest one that fits, before any compute. (A fill given by ``count`` is
held to the densest packing of spheres instead, :mod:`jaxdamp.validation`: a count is a number
of grains, not a designer's fill.)

Example::

    >>> from jaxdamp.cases import presets
    >>> from jaxdamp.config import apply_overrides
    >>> from jaxdamp.validation import validate
    >>> thesis = presets.get("sanchez2012-optimal")     # 250 grains of 3 mm, M = 2.37 kg
    >>> validate(apply_overrides(thesis, {"grains.0.mass_ratio": 0.0958})).grains[0].count
    250
    >>> round(fill_fraction(thesis, thesis.grains[0], 250), 3)   # of its 0.1225 m box
    0.294
"""

from __future__ import annotations

import dataclasses
import math

from jaxdamp.config import FILL_KEYS, Config, ConfigError, Species


def random_packing_fraction(d_over_D: float) -> float:
    """Mean solid fraction ``φ = 1 − ε`` of randomly packed equal spheres of diameter ``d`` in a
    cavity of (hydraulic) diameter ``D`` (Dixon 1988, module docstring); ``d_over_D`` in
    ``[0, 1)``."""
    x = float(d_over_D)
    if x <= 0.5:
        eps = 0.4 + 0.05 * x + 0.412 * x * x
    elif x <= 0.536:
        eps = 0.528 + 2.464 * (x - 0.5)
    else:
        eps = 1.0 - 0.667 * x**3 / math.sqrt(2.0 * x - 1.0)
    return 1.0 - eps


def mean_grain_volume(species: Species) -> float:
    """``(4/3) π R³ (1 + s²)`` [m³]: the mean volume of grains of radius uniform in
    ``R [1 − s, 1 + s]``."""
    return 4.0 / 3.0 * math.pi * species.radius**3 * (1.0 + species.radius_spread**2)


def cavity(config: Config) -> tuple[float, float, str]:
    """``(V, D_h, words)``: the cavity's volume [m³], its section's hydraulic diameter ``4A/P``
    [m] and a description for messages."""
    from jaxdamp.physics.containers import container

    vessel = container(config)
    area = vessel.base_area(config)
    return (area * vessel.height(config), 4.0 * area / vessel.perimeter(config),
            f"{vessel.describe(config)}, {vessel.lid_key} = {vessel.height(config)} m")


def packing_fraction(config: Config, species: Species) -> float:
    """The random packing fraction of ``species``' grains in the cavity of ``config``
    (:func:`random_packing_fraction` at the largest grain diameter over the hydraulic
    diameter)."""
    _, D, _ = cavity(config)
    d = 2.0 * species.radius * (1.0 + species.radius_spread)
    return random_packing_fraction(min(d / D, 0.999))


def fill_fraction(config: Config, species: Species, count: int) -> float:
    """The fill fraction of ``count`` grains of ``species``: their bed's volume at random
    packing over the cavity's volume."""
    V, _, _ = cavity(config)
    return count * mean_grain_volume(species) / (packing_fraction(config, species) * V)


def mass_ratio(config: Config) -> float:
    """The whole damper's grain mass (every species, every cell) over the primary's mass ``M``
    [-] of a configuration with counts (validated): the inverse of a fill stated by
    ``mass_ratio``, for any statement."""
    if config.primary is None:
        raise ConfigError(f"mass ratio: system = {config.system!r} has no primary mass M")
    mass = sum(sp.count * sp.material.density * mean_grain_volume(sp) for sp in config.grains)
    return config.cells * mass / config.primary.M


def cavity_volume(config: Config) -> float:
    """The damper's cavity volume [m³]: every cell's (base area × ``Lz`` × ``cells``)."""
    return cavity(config)[0] * config.cells


def _given(sp: Species) -> list[str]:
    return [k for k in FILL_KEYS if getattr(sp, k) is not None]


def _count(config: Config, i: int, sp: Species) -> int:
    """The count ``sp`` (species ``i``) states, checked; ``sp.count`` for a count."""
    name = f"grains.{i}"
    if sp.mass_ratio is not None:
        mu = sp.mass_ratio
        if not (isinstance(mu, (int, float)) and not isinstance(mu, bool) and mu > 0
                and math.isfinite(mu)):
            raise ConfigError(f"{name}.mass_ratio = {mu!r}: must be a number > 0 "
                              "(the species' mass over the primary's mass M)")
        if config.primary is None:
            raise ConfigError(f"{name}.mass_ratio: a mass ratio is the grains' mass over the "
                              f"primary's mass M ([primary] M), and system = {config.system!r} "
                              "has no primary; give count or fill_fraction")
        n = round(mu * config.primary.M
                  / (config.cells * sp.material.density * mean_grain_volume(sp)))
        what = f"{name}.mass_ratio = {mu:g}"
    elif sp.fill_fraction is not None:
        f = sp.fill_fraction
        if not (isinstance(f, (int, float)) and not isinstance(f, bool) and 0 < f <= 1):
            raise ConfigError(f"{name}.fill_fraction = {f!r}: must be in (0, 1] (the bed's "
                              "volume at random packing over the cavity's volume)")
        V, _, _ = cavity(config)
        n = round(f * packing_fraction(config, sp) * V / mean_grain_volume(sp))
        what = f"{name}.fill_fraction = {f:g}"
    else:
        return sp.count
    if n < 1:
        raise ConfigError(f"{what} is less than one grain of radius {sp.radius} m; raise it")
    return n


def _largest(config: Config, i: int, sp: Species, room: float) -> str:
    """The largest statement of species ``i`` that fits ``room`` (a fill fraction)."""
    if sp.mass_ratio is not None:
        V, _, _ = cavity(config)
        n = room * packing_fraction(config, sp) * V / mean_grain_volume(sp)
        mu = config.cells * n * sp.material.density * mean_grain_volume(sp) / config.primary.M
        return f"grains.{i}.mass_ratio ≤ {mu:.4g}"
    return f"grains.{i}.fill_fraction ≤ {room:.4g}"


def resolve(config: Config) -> Config:
    """``config`` with every species' count from its statement (module docstring); a count
    given beside a statement must be the one it gives. Raises :class:`ConfigError` naming
    the parameter and its limit: a statement missing, two that disagree, a mass ratio without
    a primary, or fills stated by mass or fraction that do not fit the cavity at random
    packing."""
    if not any(sp.mass_ratio is not None or sp.fill_fraction is not None
               for sp in config.grains):
        for i, sp in enumerate(config.grains):
            if sp.count is None:
                raise ConfigError(f"grains.{i}: give its fill as count, mass_ratio or "
                                  "fill_fraction")
        return config
    grains, fractions = [], []
    for i, sp in enumerate(config.grains):
        given = _given(sp)
        stated = [k for k in given if k != "count"]
        if not given:
            raise ConfigError(f"grains.{i}: give its fill as count, mass_ratio or "
                              "fill_fraction")
        if len(stated) > 1:
            raise ConfigError(f"grains.{i}: give one of mass_ratio and fill_fraction, not both")
        n = _count(config, i, sp)
        if stated and sp.count is not None and sp.count != n:
            raise ConfigError(f"grains.{i}.count = {sp.count} disagrees with grains.{i}."
                              f"{stated[0]} = {getattr(sp, stated[0])}, which gives {n} grains; "
                              "give one of count, mass_ratio, fill_fraction")
        grains.append(dataclasses.replace(sp, count=n))
        fractions.append(fill_fraction(config, sp, n))
    total = sum(fractions)
    if total > 1.0:
        _, D, words = cavity(config)
        i = max((j for j, sp in enumerate(config.grains) if _given(sp) != ["count"]),
                key=lambda j: fractions[j])
        sp = config.grains[i]
        room = 1.0 - (total - fractions[i])
        limit = (_largest(config, i, sp, room) if room > 0 else
                 "none: the other species already fill it")
        raise ConfigError(
            f"grains: the fill does not fit the {words}: at random packing (φ = "
            f"{packing_fraction(config, sp):.3f} for grains of diameter "
            f"{2 * sp.radius:.4g} m in a hydraulic diameter of {D:.4g} m, Dixon 1988) the beds "
            f"would take {total:.3g} times its volume; the most that fits is {limit}")
    return dataclasses.replace(config, grains=tuple(grains))
