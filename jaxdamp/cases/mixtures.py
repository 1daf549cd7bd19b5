"""Binary mixtures of the 2023 paper (docs/physics.md §5; Varela-Rosales et al., table 1).

Every class is built from a monodisperse reference (``N_ref`` grains of radius ``R_ref``, mass
``M_ref``) and a size ratio ``σ ∈ (0, 1]``:

========  ================================  ==================================  =============
class     large grains                      small grains                        conserved
========  ================================  ==================================  =============
``a``     ``n`` of ``R_ref``                ``n`` of ``σ R_ref``                mass
``b``     ``N_ref/2`` of ``R_ref``          ``N_ref/2`` of ``σ R_ref``          number
``c``     ``N_ref/2`` of ``σ̂ R_ref``        ``N_ref/2`` of ``σ R_ref``          number, mass
========  ================================  ==================================  =============

with ``n = N_ref / (1 + σ³)`` (half of the paper's ``N_tot = 2 N_ref / (1 + σ³)``) and
``σ̂³ = 2 - σ³``. Class c conserves number and mass exactly. Class a conserves mass only up to
rounding ``n`` to a whole grain: the relative mass error is at most ``(1 + σ³) / (2 N_ref)``
(0.19 % at σ = 0.5 for N_ref = 300) and is stated in the configuration's notes.

All grains share the reference's material; the dissipative constant ``A`` of each species is
calibrated on its own like-pair collision (ε at ``v_ref``), unlike pairs take the
configuration's mixing rule (the paper: arithmetic mean), and the walls keep the reference's
calibration radius, so the wall constant is the same in every mixture.
"""

from __future__ import annotations

import dataclasses
import math

from jaxdamp.config import Config, ConfigError, Species

CLASSES = ("a", "b", "c")

#: Family names as used by ``jaxdamp efficiency --preset`` (the reference is σ-independent).
FAMILIES = {"varela2023-reference": None, "varela2023-a": "a", "varela2023-b": "b",
            "varela2023-c": "c"}


def counts_and_radii(klass: str, sigma: float, n_ref: int, r_ref: float):
    """``((n_large, R_large), (n_small, R_small))`` of a class (see the module table)."""
    if klass not in CLASSES:
        raise ConfigError(f"mixture class {klass!r} is unknown; expected one of {CLASSES}")
    if not (isinstance(sigma, (int, float)) and 0.0 < sigma <= 1.0):
        raise ConfigError(f"sigma = {sigma!r}: the size ratio R_small/R_large must be in (0, 1]")
    if klass == "a":
        n = int(round(n_ref / (1.0 + sigma**3)))
        return (n, r_ref), (n, sigma * r_ref)
    if n_ref % 2:
        raise ConfigError(f"class {klass} splits the reference's {n_ref} grains in two halves: "
                          "the reference count must be even")
    half = n_ref // 2
    if klass == "b":
        return (half, r_ref), (half, sigma * r_ref)
    sigma_hat = (2.0 - sigma**3) ** (1.0 / 3.0)
    return (half, sigma_hat * r_ref), (half, sigma * r_ref)


def binary(reference: Config, klass: str, sigma: float) -> Config:
    """The class-``klass`` mixture of size ratio ``sigma`` built from a one-species reference.

    The result keeps everything else of ``reference`` (box, drive, numerics, mixing rule);
    species are named ``"large"`` and ``"small"``, large first. Raises :class:`ConfigError`
    for an unknown class, ``sigma`` outside ``(0, 1]`` or a multi-species reference.
    """
    if len(reference.grains) != 1:
        raise ConfigError(f"a binary mixture is built from a one-species reference; "
                          f"{reference.name!r} has {len(reference.grains)} species")
    ref = reference.grains[0]
    if ref.radius_spread:
        raise ConfigError("the reference of a binary mixture must be monodisperse "
                          f"(grains.0.radius_spread = {ref.radius_spread})")
    (n_l, r_l), (n_s, r_s) = counts_and_radii(klass, sigma, ref.count, ref.radius)
    mass = lambda n, r: n * r**3  # noqa: E731  (same density: proportional to the mass)
    err = (mass(n_l, r_l) + mass(n_s, r_s)) / mass(ref.count, ref.radius) - 1.0
    wall = reference.box.wall or ref.material
    if wall.calibration_radius is None:
        wall = dataclasses.replace(wall, calibration_radius=ref.radius)
    base = reference.name.removesuffix("-reference")
    return dataclasses.replace(
        reference,
        name=f"{base}-{klass}",
        grains=(Species(count=n_l, radius=r_l, material=ref.material, name="large"),
                Species(count=n_s, radius=r_s, material=ref.material, name="small")),
        box=dataclasses.replace(reference.box, wall=wall),
        notes=(f"Class {klass} binary mixture (σ = {sigma:g}) of {reference.name}: {n_l} grains "
               f"of R = {r_l:.6g} m and {n_s} of R = {r_s:.6g} m; granulate mass / reference "
               f"mass - 1 = {err:.2e}; number {n_l + n_s} (reference {ref.count}). "
               + reference.notes),
    )


def sigma_hat(sigma: float) -> float:
    """Large-to-reference radius ratio of class c, ``(2 - σ³)^{1/3}``."""
    return (2.0 - sigma**3) ** (1.0 / 3.0)


def granulate_mass(config: Config) -> float:
    """Mass of the granulate [kg] (nominal radii)."""
    return sum(sp.count * sp.material.density * 4.0 / 3.0 * math.pi * sp.radius**3
               for sp in config.grains)
