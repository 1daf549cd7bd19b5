"""Named reference cases of the two source studies (docs/physics.md §5).

``jaxdamp presets`` lists them. Deviations from the sources are stated in each preset's
``notes`` (stored in every output file with the rest of the configuration).
"""

from __future__ import annotations

import dataclasses
import math

from jaxdamp.cases import mixtures
from jaxdamp.config import (
    Box,
    Config,
    ConfigError,
    Container,
    Drive,
    Impactor,
    Material,
    Numerics,
    Primary,
    RandomBase,
    Species,
    Structure,
)
from jaxdamp.materials import THESIS_DENSITY, THESIS_E, THESIS_GAMMA_S, THESIS_NU

#: Steel of the thesis (table 3.1 / §3.2): E = 2.03e11 Pa, ν = 0.28, ρ = 8030, μ = 0.3.
SANCHEZ_STEEL = Material(
    E=THESIS_E, nu=THESIS_NU, density=THESIS_DENSITY, mu=0.3, gamma_n=3660.0,
    gamma_s=THESIS_GAMMA_S)


def sanchez2012_optimal() -> Config:
    return Config(
        name="sanchez2012-optimal",
        system="primary",
        frequency=15.16,
        grains=(Species(count=250, radius=0.003, material=SANCHEZ_STEEL, name="steel"),),
        box=Box(Lx=0.03675, Ly=0.03675, Lz=0.1225),
        primary=Primary(M=2.37, K=21500.0, C=7.6, U=0.0045),
        numerics=Numerics(
            stiffness_scale=0.01, duration=5.0, chunk=0.05, record_dt=2.5e-4, v_impact=1.0
        ),
        notes=(
            "Thesis §3.2 optimal damper (Lz = 0.1225 m, f0 = 15.16 Hz). Modulus reduced 100× "
            "(numerics.stiffness_scale = 0.01: E = 2.03e9 Pa) with gamma_n, gamma_s scaled by "
            "0.01^0.6, which keeps the restitution and tangential impulse of every binary "
            "collision and lengthens collisions 6.3×; the thesis used E = 2.03e11, "
            "dt = 8.75e-8 s, 13.12 s per frequency. Set numerics.stiffness_scale = 1 for the "
            "thesis modulus. Duration 5 s (thesis 13.12 s)."
        ),
    )


def sanchez2012_cylinder() -> Config:
    """The thesis damper as designers build it: its grains in a drilled cylinder of the box's
    base area, filled by the thesis' mass ratio (``mass_ratio``: :mod:`jaxdamp.cases.filling`)."""
    base = sanchez2012_optimal()
    radius = round(math.sqrt(base.box.Lx * base.box.Ly / math.pi), 6)
    return dataclasses.replace(
        base, name="sanchez2012-cylinder", box=None,
        container=Container("cylinder", base.box.Lz, (("radius", radius),)),
        grains=(dataclasses.replace(base.grains[0], count=None, mass_ratio=0.0958),),
        notes=(f"The thesis' optimal damper in a cylinder of radius {radius} m (the box's base "
               f"area), Lz = {base.box.Lz} m, filled to the thesis' mass ratio μ = 0.0958 "
               "(250 grains of 3 mm steel on M = 2.37 kg; D/d = 6.9). Beyond the thesis: "
               "its numerics and modulus are those of sanchez2012-optimal."),
    )


def sanchez2012_cells() -> Config:
    """The thesis' optimal damper split into four box cells on the same primary
    (``Config.cells``): the same grains in all, each cell the thesis' box section and the
    thesis' free height above its bed."""
    base = sanchez2012_optimal()
    cells = 4
    per_cell = round(base.grains[0].count / cells)  # 62.5 -> 62 (half to even): 248 grains
    h_bed = 0.1225 - 0.0835  # the thesis' bed under its optimal gap (sanchez2012-impact)
    Lz = round(0.0835 + h_bed * per_cell / base.grains[0].count, 4)
    return dataclasses.replace(
        base, name="sanchez2012-cells", cells=cells,
        grains=(dataclasses.replace(base.grains[0], count=per_cell),),
        box=Box(Lx=base.box.Lx, Ly=base.box.Ly, Lz=Lz),
        notes=(f"The thesis' optimal damper split into {cells} box cells on the same primary "
               f"(cells = {cells}): {per_cell} grains of 3 mm steel in each ({cells * per_cell} "
               f"in all: 250/{cells} = 62.5 rounds to {per_cell}, 0.8 % less grain mass than "
               "the thesis' 250, μ = 0.0950 instead of 0.0958), each cell the thesis' box "
               f"section {base.box.Lx} × {base.box.Ly} m and its free height 0.0835 m above "
               f"the bed (the thesis' bed of 0.039 m scaled to {per_cell} grains, 0.0097 m: "
               f"Lz = {Lz} m). Beyond the thesis: its numerics and modulus are those of "
               "sanchez2012-optimal."),
    )


def sanchez2012_random() -> Config:
    """The thesis damper under band-limited random base motion (``jaxdamp random``)."""
    return dataclasses.replace(
        sanchez2012_optimal(), name="sanchez2012-random",
        primary=Primary(M=2.37, K=21500.0, C=7.6, U=0.0),
        random=RandomBase(psd=((5.0, 2.0), (30.0, 2.0)), resolution=0.25),
        numerics=Numerics(stiffness_scale=0.01, duration=12.0, chunk=0.05, record_dt=2.5e-4,
                          v_impact=1.0),
        notes=("The thesis damper (sanchez2012-optimal) under random base motion instead of "
               "the harmonic one: flat base acceleration density 2 (m/s²)²/Hz over 5–30 Hz "
               "(a_rms ≈ 7.1 m/s²), a random-phase multisine with lines every 0.25 Hz (period "
               "4 s), the phases from the bed's seed. 12 s: a start-up period and two to "
               "average (jaxdamp random; scale the level with --scale)."),
    )


def sanchez2012_chain() -> Config:
    """The thesis damper on the upper mass of a two-mode chain (multi-DOF structure)."""
    return dataclasses.replace(
        sanchez2012_optimal(), name="sanchez2012-chain",
        structure=Structure(M=((2.37, 0.0), (0.0, 2.37)),
                            K=((43000.0, -21500.0), (-21500.0, 21500.0)),
                            C=((15.2, -7.6), (-7.6, 7.6)), attach=1),
        notes=("The thesis damper (sanchez2012-optimal) on the upper mass of a 2-DOF chain: "
               "two 2.37 kg masses, springs 21500 N/m and dampers 7.6 N s/m base–lower and "
               "lower–upper (modes at 9.37 and 24.53 Hz; mode 1's antinode is the upper mass, "
               "DOF 1; set structure.attach = 0 for mode 2's). The base moves by U = 4.5 mm "
               "at the frequency given; primary.M, K, C are not used "
               "(experiments/two_mode_structure.py)."),
    )


def sanchez2012_sec31(n: int) -> Config:
    sets = {250: (6.05e-3, 6.55e-3), 500: (4.80e-3, 5.20e-3), 1000: (3.80e-3, 4.12e-3)}
    lo, hi = sets[n]
    radius = 0.5 * (lo + hi)
    spread = (hi - lo) / (hi + lo)
    M, K, zeta = 25.0, 2.62e5, 0.058
    steel = Material(E=2.06e8, nu=0.33, density=7900.0, mu=0.3, gamma_n=19.99, gamma_s=59.76)
    return Config(
        name=f"sanchez2012-sec31-n{n}",
        system="primary",
        frequency=16.29,
        grains=(Species(count=n, radius=radius, radius_spread=spread, material=steel, name="steel"),),
        box=Box(Lx=0.09, Ly=0.09, Lz=0.11),
        primary=Primary(M=M, K=K, C=2.0 * zeta * math.sqrt(K * M), U=0.005),
        numerics=Numerics(dt=1e-6, duration=8.0, chunk=0.05, v_impact=1.0),
        notes=(
            "Thesis §3.1 (reduced modulus E = 2.06e8 as in the thesis). The stated 0.02 × 0.02 m "
            "base cannot hold the stated ~0.05 m bed; 0.09 × 0.09 m reproduces it (a choice, "
            f"docs/physics.md §5). Radii uniform in [{lo}, {hi}] m."
        ),
    )


def sanchez2012_impact() -> Config:
    m_p = 250 * SANCHEZ_STEEL.density * 4.0 / 3.0 * math.pi * 0.003**3
    return Config(
        name="sanchez2012-impact",
        system="impact",
        frequency=15.16,
        grains=(),
        box=Box(Lx=0.03675, Ly=0.03675, Lz=0.1225),
        primary=Primary(M=2.37, K=21500.0, C=7.6, U=0.0045),
        impactor=Impactor(mass=m_p, restitution=0.0, gap=0.0835),
        numerics=Numerics(duration=13.12, record_dt=2.5e-4, analysis_window=0.1),
        notes=(
            "Thesis §5.3.2 single-particle impact damper (S3) standing for the optimal damper. "
            "Model of thesis §2.1.3; primary of §3.2 (M = 2.37 kg, K = 21500 N/m, C = 7.6 N s/m, U = 0.0045 m), "
            f"one particle of the bed's mass m_p = 250 steel grains of R = 3 mm, ρ = 8030 "
            f"({m_p:.5g} kg; thesis code 0.22704 kg), e = 0, gap = Lz − h_bed = 0.0835 m for "
            "Lz = 0.1225 m (the box is recorded but not used). Event-driven (exact); set "
            "impactor.method = 'smooth' for the differentiable penalty model. 13.12 s per "
            "frequency as the thesis' DEM runs (its impact code ran 30 s at dt = 5e-6 s)."
        ),
    )


VARELA_STEEL = Material(E=2e9, nu=0.3, density=7850.0, mu=0.0, restitution=0.75, v_ref=1.0)


def varela2023_reference() -> Config:
    return Config(
        name="varela2023-reference",
        system="driven",
        frequency=70.0,
        grains=(Species(count=300, radius=2.5e-3, material=VARELA_STEEL, name="reference"),),
        box=Box(Lx=0.08, Ly=0.08, Lz=0.08,
                wall=dataclasses.replace(VARELA_STEEL, calibration_radius=2.5e-3)),
        drive=Drive(amplitude=0.03),
        numerics=Numerics(duration=60 / 70.0, chunk=1 / 280.0, record_dt=1 / 70.0 / 100,
                          analysis_window=50 / 60, settle_time=0.15),
        notes=(
            "2023 paper reference system (S2): 300 frictionless steel grains, R = 2.5 mm, "
            "ε = 0.75 at 1 m/s, cube 8 cm driven at 70 Hz; the walls' dissipative constant "
            "calibrated on the same grain–grain collision. Default A_d = 3 cm; the paper scans "
            "2–4 cm. dt from the Hertz collision time at the walls' relative speed 2 A_d ω "
            "(26 m/s at 3 cm). 60 periods, the last 50 analysed (the paper: 50 periods). The grains "
            "settle for at most 0.15 s before the drive starts: the 10 transient periods at "
            "up to 800 g erase the start (a full settle costs more than the measurement)."
        ),
    )


def varela2023_class(klass: str, sigma: float = 0.5) -> Config:
    """A class a/b/c mixture of the 2023 paper (:mod:`jaxdamp.cases.mixtures`), σ = 0.5 by default."""
    return mixtures.binary(varela2023_reference(), klass, sigma)


PRESETS = {
    "sanchez2012-optimal": sanchez2012_optimal,
    "sanchez2012-cylinder": sanchez2012_cylinder,
    "sanchez2012-cells": sanchez2012_cells,
    "sanchez2012-random": sanchez2012_random,
    "sanchez2012-chain": sanchez2012_chain,
    "sanchez2012-sec31": lambda: sanchez2012_sec31(250),
    "sanchez2012-sec31-n250": lambda: sanchez2012_sec31(250),
    "sanchez2012-sec31-n500": lambda: sanchez2012_sec31(500),
    "sanchez2012-sec31-n1000": lambda: sanchez2012_sec31(1000),
    "sanchez2012-impact": sanchez2012_impact,
    "varela2023-reference": varela2023_reference,
    "varela2023-a": lambda: varela2023_class("a"),
    "varela2023-b": lambda: varela2023_class("b"),
    "varela2023-c": lambda: varela2023_class("c"),
}


def get(name: str) -> Config:
    """The preset called ``name``; :class:`ConfigError` lists the known names otherwise."""
    try:
        return PRESETS[name]()
    except KeyError:
        raise ConfigError(f"preset {name!r} is unknown; known presets: {', '.join(PRESETS)}") from None


def describe() -> list[tuple[str, str]]:
    """``(name, first sentence of notes)`` for every preset."""
    out = []
    for name, make in PRESETS.items():
        notes = make().notes
        out.append((name, notes.split(". ")[0]))
    return out


def family(name: str, sigma: float | None = None, reference: Config | None = None) -> Config:
    """The configuration of a paper family: ``varela2023-reference`` (σ ignored) or
    ``varela2023-a|b|c`` at ``sigma`` (default 0.5)."""
    if name not in mixtures.FAMILIES:
        raise ConfigError(f"preset {name!r} is not a binary-mixture family; known: "
                          f"{', '.join(mixtures.FAMILIES)}")
    reference = reference or get("varela2023-reference")
    klass = mixtures.FAMILIES[name]
    if klass is None:
        return reference
    return mixtures.binary(reference, klass, 0.5 if sigma is None else sigma)
